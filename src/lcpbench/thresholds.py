"""Every threshold that both a compiled kernel and plain Python read, defined once.

The kernels (numba) and the Python around them (the judge, the drivers, the dual
walk) take these numbers from here; numba freezes them into the compiled code,
so this file is part of the kernel cache's hash (:mod:`lcpbench.numba_cache`):
an edit here recompiles every kernel. Plain numbers only: this module is at the
bottom of the layers and imports nothing of lcpbench.
"""

from __future__ import annotations

import numpy as np

EPS = float(np.finfo(np.float64).eps)

# --- the result judge --------------------------------------------------------------

#: the success rule's parts: τ = min(FORCE_TOL_CAP, FORCE_TOL_PER_RAD · tol)
FORCE_TOL_CAP = 1e-3
FORCE_TOL_PER_RAD = 100.0
#: per-node checks (sign, complementarity, contact threshold) at this share of τ
NODE_SHARE = 0.1
#: per-node force error bound: at most NODE_FACTOR·τ or NODE_GROSS (in F₀), whichever is
#: larger. Node forces converge more slowly than their sum: force shifts between
#: neighbouring contact nodes (default scene, tol 1e-3 rad: nodes 8e-4 F₀ off while F
#: is 7e-5 off; N = 2000: nodes 1.2e-2 off, F 7e-5). The success rule is on F; the
#: per-node bound rejects a wrong distribution (13 % of a node's force moved to its
#: neighbour) without rejecting a slow one.
NODE_FACTOR = 10.0
NODE_GROSS = 0.05
#: the round-off of a residual w = M z + q (a step's, :mod:`lcpbench.solvers.judge`) or
#: of a reaction recomputed from rounded gaps, R = K g + z (the result judge's), in ulps
#: of the size of the terms summed, S = max_i (|K| |g| + |z|)_i: even the exact answer,
#: rounded to doubles, leaves up to ε S. At N = 140 (cond K ~ 1e8) S ~ 4e6 in scaled
#: units, so a step asked for 1e-9 is limited by this floor (~2e-7).
FLOOR_ULPS = 256.0
#: penetration and closure of the exact geometry, in units of ℓ, at most
GEOMETRY_TOL = 1e-6
#: the joint torques' balance: the relative torque residual at most
#: max(TORQUE_PER_RAD · tol, TORQUE_FLOOR)
TORQUE_PER_RAD = 10.0
TORQUE_FLOOR = 1e-6
#: round-off of a reaction, in units of ε × the size of the terms summed for it
ROUNDOFF_ULPS = 64.0
#: the contraction estimate ρ is kept in [RHO_MIN, RHO_MAX]
RHO_MIN, RHO_MAX = 0.5, 0.99
#: step sizes max|Δα| below this (rad) are round-off, not contraction
STEP_NOISE = 1e4 * EPS
#: block principal pivoting rounds of the judge step before it gives up (plus 2 per node,
#: for the single pivots after STALL rounds without fewer infeasible nodes)
PIVOT_ROUNDS = 30
STALL = 3
#: in increments (model.judge_exact_kernel) the judge step's rounds are capped at
#: PIVOT_ROUNDS + 2 × this many, not 2 per node: each round is an O(N) face solve, and a
#: judge that cannot settle says so
LARGE_ROUNDS = 100

# --- the outer loop ----------------------------------------------------------------

#: the Newton scheme takes Gauss–Newton steps until the last step moved α by less
#: than this (rad): far from the answer the exact curvature of the energy only
#: lengthens the steps the line search then cuts (6 outer iterations instead of 4
#: on the default scene at 1e-3 with Newton from the start)
NEWTON_SWITCH = 0.05
#: skip the wall-free search when the arc crosses a wall by more than this many
#: times the mid-span sag of a straight pinned beam under the same load
#: (5 w ℓ⁴ / 384 EI): the arc will not sag off it. A heuristic that only saves
#: time: a scene it sends to the contact solve still gets the right answer.
SAG_BOUND = 10.0

# --- the line search on the exact energy (model.chain_kernel.armijo) -------------------

#: Armijo's sufficient decrease: E(t) ≤ E + ARMIJO_DECREASE · t · min(slope, 0) + noise
ARMIJO_DECREASE = 1e-4
#: the shortest step length the outer loops try (halving from 1) before "no decrease"
ARMIJO_SHORTEST = 1e-12
#: a cold solve of the height steps stops (compiled_kernel.BAIL_STALL, the answer refused:
#: the plan's escalations, the loading path, take over) once its line searches cut the
#: step length t to STALL_STEP or less STALL_RUN outer steps running.
#: benchmarks/cold_stall.py before the rule (cold, tol 1e-3 and 1e-9): of 2528 solves of
#: its corpus (1264 scenes: mixed batches of 6 seeds, the paper grid, 300 rows of 2-4
#: sections, 200 elastic and 200 channel scenes, the hard cases) 755 stopped after 3-137
#: outer steps (a face not positive definite 303, a repeated set 128, refused steps
#: 140 + 184), the rule fires on 740 of them at step 2-40 (median 9), and none of the
#: 1773 that converged took a step shorter than 1/32 (5 halvings above STALL_STEP).
#: On 18000 solves of 9000 other scenes (``--wide``) it fires on 8 of 29 solves out of
#: outer steps, 4 of 4 failed line searches, 8604 of 8819 stops and on one of 9148 that
#: converged: a row at tol 1e-3 whose max|Δα| hovered at the tolerance while the steps
#: were cut to 5e-7 (the judge refused its answer; the loading path answers it either
#: way, the same bits); the next closest, two steps of 1/128 running (3 halvings above),
#: another such row the judge refused. 1/256 fired 2 steps sooner (median 7) with 1
#: halving of margin there
STALL_STEP = 2.0 ** -10
STALL_RUN = 2
#: the SQP in the link angles halves its merit's step down to this length, then takes it
SQP_SHORTEST = 1e-10
#: the energy's round-off the decrease test allows: ENERGY_NOISE · (|E| + 1e-6 Σ|k|)
ENERGY_NOISE = 1e-12

# --- walls of any profile (the lagged-slope driver) --------------------------------

#: the driver's own criterion on the exact walls: penetration at most this × ℓ
#: (a tenth of the judge's GEOMETRY_TOL)
GEOMETRY_SLACK = 1e-7
#: the line search's penalty on penetration, in units of the largest reaction
PENALTY = 2.0
#: near the answer (max|Δα| < NEWTON_SWITCH) a step the merit cuts below this
#: length is taken in full instead: the lagged fixed point converges there
#: (the undamped scheme's local convergence), while the merit, which changes
#: with the lagged reactions and the walls under the moving nodes, can refuse
#: every short step (a stenosis crest, two contact nodes: 200 steps of 2e-6)
LOCAL_CUT = 1.0 / 64
#: passes of "clip the heights to the walls at the nodes' x" for the first iterate
START_PASSES = 5

# --- the dual active-set walk ------------------------------------------------------

#: step fractions of the dual walk closer than this are ties (released together)
TIE = 1e-6
#: the walk's relative stationarity on a face (solve_banded_qp's ``rtol``)
WALK_RTOL = 1e-9

# --- the SQP in the link angles (model/angle_kernel.py) ------------------------------

#: where the Lagrangian's Hessian is not positive on the closure's tangent, the shift σ I
#: tried first, in units of the largest diagonal entry of the springs and curvatures ...
ANGLE_SHIFT_START = 1e-8
#: ... then grown by this factor ...
ANGLE_SHIFT_GROWTH = 10.0
#: ... at most this many times
ANGLE_SHIFT_TRIES = 20

# --- the loading path (model/ramp.py, model/path_kernel.py) -------------------------

#: a step of the loading path starting with a link this close to the vertical (degrees)
#: takes its outer steps in the link angles (where they are in reach); the walk of
#: height steps in one kernel call (path_kernel.walk_heights) stops on an answer with a
#: link this close (|cos α_i| ≤ sin of it): the height step's linearisation divides by
#: a cos α_i
NEAR_VERTICAL_DEG = 10.0

# --- the frictional step's primal polish (model/friction_polish.py) ----------------------

#: a link whose |tan α| is at most this is level in the polish (its nodes at one wall to
#: round-off): T per node along a run of sticking nodes is then exactly indeterminate,
#: and the polish holds its split at the answer's instead of letting round-off decide it
#: (benchmarks/exact_friction.py's LEVEL)
POLISH_LEVEL = 1e-12
#: the polished answer's signs hold to this share of the answer's largest force (N >= 0,
#: |T| <= μN) and of a link length (gaps >= 0, slips of their direction, a held sticking
#: pair's slip zero). 1e-12 let three of the active set's answers on
#: benchmarks/friction_agreement.py's paths slide 2-3e-13 of a link the wrong way where,
#: exactly, the pair sticks; 1e-14 refused by round-off on the flat wall of
#: benchmarks/friction_speed.py (docs/friction.md, "What limits target 2")
POLISH_SIGN_RTOL = 1e-13
#: the polish's sticking nodes get this compliance, in link lengths per the largest force,
#: in the system it solves (not in the equations it meets): T per node along a nearly
#: straight run of sticking nodes (slopes of 1e-7 at N = 140) is singular in doubles, and
#: the compliance keeps it near where the answer put it; the refinement sweeps
#: (POLISH_SWEEPS, each against the equations without it) take its bias away where T is
#: determined. On the 375 steps of benchmarks/friction_agreement.py 1e-14 … 1e-13 with
#: 1 … 3 sweeps brought the 10 unconfirmed answers with an exact solution to it and
#: moved no confirmed one; 1e-10 cured 4 of them (too stiff: it held N too)
POLISH_STICK_COMPLIANCE = 1e-13
POLISH_SWEEPS = 2
#: where a sign of the answer's index set fails at the polished answer, the failing nodes
#: may be flipped and the set solved again, at most this many times (the exact oracle's
#: search, benchmarks/exact_friction.py, flips up to 6 times, then tries every state of
#: the edge nodes); an answer whose signs still fail is returned as it was. On the
#: unconfirmed last steps of benchmarks/friction_agreement.py's Lemke paths, flips of 0, 1,
#: 2, 4, 8 brought 0, 5, 9, 11, 14 of 33 onto an exact answer (dN <= 3e-11). Once 0: a
#: kept flipped answer made path 74's last state cycle with 1 flip and the polish on every
#: Lemke step (the back-ends by name polish every step; the default's: FINAL_FLIPS)
POLISH_FLIPS = 8
#: the polish gives up where the signs of more than this many rows and pairs fail at a
#: set it solves: the flips end there (the edge search still runs, from the first flip's
#: set, which the later flips do not change), and at the answer's own set nothing more
#: is tried (the answer is returned as it was, as any refusal). A polish repairs
#: round-off at a few nodes. Measured (benchmarks/friction_polish_failing.py on the 100
#: paths of benchmarks/friction_agreement.py and the three pull-outs of
#: benchmarks/friction_speed.py, 373 polishes that solved a set; and ProxSuite's 1460,
#: which polish every step): at the answer's own set at most 6 fail (the channel's four
#: refused answers: 2); the flips that ended on a kept set passed at most 14 (Lemke's
#: 59; one went 3, 4, 5, 9, 14, 1, 1, 0) and 17 (ProxSuite's), those that passed 20 went
#: on to 21-60 (the channel's 2, 4, 3, 4, 7, 41, 60, 28, 21) and none ended kept by its
#: flips. Here about twice the largest kept
POLISH_MOST_FAILING = 30
#: where the flips find no index set whose signs hold, every state of at most
#: POLISH_EDGE_NODES of the nodes whose sign fails is tried (friction_lemke.edge_polish:
#: those nearest the edge of two states first), at most POLISH_EDGE_SETS index sets, the
#: fewest changes first (the exact oracle's edge search, benchmarks/exact_friction.py,
#: in doubles, on the failing nodes only: every set it kept on the agreement's paths
#: changed only those)
POLISH_EDGE_NODES = 6
POLISH_EDGE_SETS = 64
#: where a sticking pair whose sign fails is joined to a sticking neighbour by a link
#: with |tan α| at most this (level to POLISH_LEVEL included), the edge search's picks of
#: likely states (that pair sliding against its sticking run's summed T, or sticking) are
#: tried after the first flip, before the others (friction_lemke.searched_polish): the
#: channel of benchmarks/friction_speed.py sticks across links of 1.2e-12 and 1.4e-12
#: between stretches sloped 1e-5, and the flips there went 4, 4, 4, 5, 41 before the
#: edge search kept a set with three of its pairs sliding against the answer's T; the
#: agreement's state 12.1 sticks across links of 1e-15 and 7e-15, and its exact set (three
#: pairs sliding against their runs' T) is the 106th pick of the fewest changes, the 40th
#: likely one
POLISH_LIKELY_LEVEL = 1e-9
#: the flips of the polish of the answers that end a frictional state (every polish of
#: the state's last steps: docs/friction.md, "Once per state"). A flipped answer, one whose
#: signs all hold, ends the state only where its move passes the state's convergence test,
#: and the judge then checks it; an answer whose signs still fail after these flips and
#: the edge search is returned as it was (docs/friction.md). On the 100 paths of
#: benchmarks/friction_agreement.py, 1 flip in a state's first polish only (later: none):
#: Lemke's answers confirmed exactly 342 of 375; 8 in every one: 355 of 377 before the
#: edge search (no state cycled; 2 more converged)
FINAL_FLIPS = 8

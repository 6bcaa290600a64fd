"""The five formulations of the contact step (lcpbench.model.formulations).

Independent checks: the step's energy written here from the paper's linearisation
(eq. 21: α̂ = α + Δy / (a cos α)) and minimised by SLSQP; the KKT conditions of each
formulation at the exact answer, with the reactions as multipliers; and the growth of
the condition numbers against N (docs/formulations.md: ~N⁴ for F1, F2, F4; ~N² for F3).
"""

import numpy as np
import pytest
from energy_oracle import energy_minimum
from scipy.optimize import minimize

import lcpbench
from lcpbench import ActuatorScene, CantileverScene
from lcpbench.errors import ProblemError
from lcpbench.model.compiled_driver import assemble_step
from lcpbench.model.formulations import (
    NAMES,
    Formulation,
    accepts,
    angle_qp,
    heights_from_reactions,
    kinematic_matrix,
    lifted_qp,
    link_heights,
    parse_formulation,
    reaction_lcp,
    resolve_formulation,
    wall_rows,
)
from lcpbench.model.step_solver import solve_step, step_lcp, step_qp
from lcpbench.solvers.registry import available_backends, get_backend

#: a back-end per kind of form that answers to 1e-9 (exact pivoting for the LCPs)
SOLVER = {"lcp": "lemke", "box": "active-set", "rows": "proxsuite-dense"}


def _step(scene, tol=1e-10):
    """The contact step at the scene's converged configuration."""
    res = lcpbench.solve(scene, settings="high", tol=tol)
    return assemble_step(scene.chain(), np.asarray(res.alpha))


@pytest.fixture(scope="module")
def small():
    return _step(ActuatorScene(theta=150, height=3, links=12))


@pytest.fixture(scope="module")
def paper():
    return _step(ActuatorScene(theta=150, height=3, links=140))


def _joint_map(chain, alpha):
    """The linearised joint angles φ̂(u) = φ̂₀ + J u, from eq. (21) written here: with y
    the node heights (the pinned nodes at 0) and y₀ = Σ a sin α their values at α, the
    link angles are α̂ = α + B (y − y₀), B the link differences over a cos α, the joint
    angles φ̂ = α̂_right − α̂_left (the clamp's left angle 0). Returns (φ̂₀, J) on the
    free nodes."""
    N, a = chain.links, chain.link_length
    free = chain.free_nodes
    y0 = np.concatenate([[0.0], np.cumsum(a * np.sin(alpha))])
    B = np.zeros((N, N + 1))
    for i in range(N):
        B[i, i], B[i, i + 1] = -1 / (a * np.cos(alpha[i])), 1 / (a * np.cos(alpha[i]))
    Jl = np.zeros((len(chain.joint_links), N))
    for j, (left, right) in enumerate(chain.joint_links):
        Jl[j, right] += 1.0
        if left >= 0:
            Jl[j, left] -= 1.0
    return Jl @ (alpha - B @ y0), Jl @ B[:, free]


def _energy(chain, alpha):
    """The step's energy in the free heights u, E = ½ Σ k (φ̂ − φ*)² − fᵀu with φ̂ from
    :func:`_joint_map` (eq. 21 written here). Returns E and ∇E as functions of u."""
    phi0, Jf = _joint_map(chain, alpha)  # φ̂ at u = 0 (every node at 0), and J
    k, rest, f = chain.joint_stiffness, chain.rest_joint, chain.nodal_load

    def E(u):
        d = phi0 + Jf @ u - rest
        return 0.5 * np.sum(k * d * d) - f @ u

    def dE(u):
        return Jf.T @ (k * (phi0 + Jf @ u - rest)) - f

    return E, dE


def _slsqp(step, chain, alpha, polish=False):
    """u* and R* = −∇E(u*) of the step by SLSQP in units of ℓ and EI/ℓ². ``polish``:
    then the stationarity of E solved exactly (dense, this module's own E) with the
    nodes SLSQP put on the wall held there -- SLSQP alone stops at ~1e-5 of the
    reactions on the cond ~1e8 step of N = 140."""
    E, dE = _energy(chain, alpha)
    L, F = float(chain.length), float(chain.force_scale)
    u0 = np.minimum(step.origin, step.upper) / L
    up = np.isfinite(step.upper)
    cons = {"type": "ineq", "fun": lambda x: (step.upper[up] / L - x[up]),
            "jac": lambda x: -np.eye(x.size)[up]}
    res = minimize(lambda x: E(x * L) / (F * L), u0, jac=lambda x: dE(x * L) / F,
                   constraints=[cons], method="SLSQP",
                   options={"ftol": 1e-16, "maxiter": 2000})
    u = res.x * L
    if polish:  # SLSQP's contact set, corrected until it is consistent (R >= 0, g >= 0)
        on = up & (step.upper - u <= 1e-6 * L)
        n = u.size
        g0 = dE(np.zeros(n))
        H = np.column_stack([dE(np.eye(n)[i]) - g0 for i in range(n)])
        for _ in range(50):
            off = ~on
            u = np.where(on, step.upper, 0.0)
            u[off] = np.linalg.solve(H[np.ix_(off, off)], -g0[off] - H[np.ix_(off, on)] @ u[on])
            R = -dE(u)
            new = (on & (R >= 0)) | (up & ~on & (u > step.upper))
            if np.array_equal(new, on):
                break
            on = new
    return u, -dE(u)


def _run(step, name, backend=None):
    form = parse_formulation(name)
    b = backend or ("proxsuite-dense" if form.equilibrated and form.kind == "box"
                    else SOLVER[form.kind])
    if b not in available_backends():
        pytest.skip(f"{b} not installed")
    return solve_step(step, b, "high", formulation=name)


@pytest.mark.parametrize("name", NAMES)
def test_small_scene_matches_the_energy_minimum(small, name):
    scene = ActuatorScene(theta=150, height=3, links=12)
    res = lcpbench.solve(scene, settings="high", tol=1e-10)
    u_ref, R_ref = _slsqp(small, scene.chain(), np.asarray(res.alpha))
    sol = _run(small, name)
    assert sol.status.value == "solved", sol.message
    scale = np.max(np.abs(R_ref))
    assert scale > 0  # the wall is touched: reactions to compare
    R = sol.forces_upper - sol.forces_lower  # the formulation's own multipliers, mapped
    assert np.max(np.abs(R - R_ref)) <= 1e-6 * scale
    assert np.max(np.abs(sol.u - u_ref)) <= 1e-8 * scene.length


@pytest.mark.parametrize("name, backend", [
    ("gaps", "lemke"), ("heights", "active-set"), ("heights+ruiz", "proxsuite-sparse"),
    ("lifted", "osqp"), ("lifted+ruiz", "osqp"), ("reactions", "lemke"),
    ("reactions+ruiz", "proxsuite-dense"), ("angles", "qpsolvers-daqp"),
    ("angles+ruiz", "osqp")])
def test_paper_scene_matches_the_energy_minimum_and_each_other(paper, name, backend):
    """Each form's multipliers, mapped back, against the energy minimisation. The angles
    form runs on DAQP, an active-set QP solver: its answer is the KKT point of the form,
    not where a first-order method stopped (SCS 3.3.1 stops at 1.7e-5 of the largest
    reaction there: its accuracy is a property of the build's iteration path, and this
    test is of the form)."""
    scene = ActuatorScene(theta=150, height=3, links=140)
    res = lcpbench.solve(scene, settings="high", tol=1e-10)
    u_ref, R_ref = _slsqp(paper, scene.chain(), np.asarray(res.alpha), polish=True)
    assert np.all(R_ref >= -1e-9 * np.max(np.abs(R_ref)))  # a consistent contact set
    sol = _run(paper, name, backend)
    assert sol.status.value == "solved", sol.message
    R = sol.forces_upper - sol.forces_lower  # the form's multipliers, mapped back
    scale = np.max(np.abs(R_ref))
    assert abs(np.sum(R) - np.sum(R_ref)) <= 1e-6 * abs(np.sum(R_ref))
    assert np.max(np.abs(R - R_ref)) <= 1e-5 * scale
    assert np.max(np.abs(sol.forces_net - R_ref)) <= 1e-5 * scale  # the judge's R


def _exact(step):
    sol = solve_step(step, "active-set", "high")
    assert sol.solved
    return sol.u, sol.forces_net


@pytest.mark.parametrize("scene", [ActuatorScene(theta=150, height=3, links=40),
                                   ActuatorScene(theta=120, height=4, links=30, channel=True),
                                   CantileverScene(height=2, links=30, load=1e-2)],
                         ids=["pinned", "channel", "cantilever"])
def test_kkt_of_each_form_holds_with_the_reactions_as_multipliers(scene):
    """At the exact answer (u*, R*) each form's KKT conditions hold to round-off with
    the multipliers of the walls equal to R* (over EI/ℓ²)."""
    step = _step(scene)
    u, R = _exact(step)
    L, F = float(step.length_scale), float(step.force_scale)
    tol = 1e-9
    # F2: P x + c + y = 0 with y = R/F
    qp = step_qp(step)
    r2 = qp.P @ (u / L) + qp.c + R / F
    assert np.max(np.abs(r2)) <= tol * np.max(np.abs(qp.P) @ np.abs(u / L))
    # F3: stationarity in (δũ, φ̂) with y = R/F on the bounds, y_rows = −k̃ (φ̂ − φ*)
    q3 = lifted_qp(step)
    phi0, J = _joint_map(scene.chain(), step.alpha)
    phi = phi0 + J @ u  # φ̂(u), eq. (21) written here
    x = np.r_[(u - step.origin) / L, phi]
    yr = -step.stiffness / (F * L) * (phi - step.rest_joint)
    y = np.r_[R / F, np.zeros(phi.size)]
    r3 = q3.P @ x + q3.c + y + q3.A.T @ yr
    assert np.max(np.abs(r3)) <= tol * max(1.0, np.max(np.abs(y)))
    assert np.max(np.abs(q3.A @ x - q3.row_lower)) <= tol * np.max(np.abs(phi))
    # F4: the gaps are W λ + q at λ = R/F on the wall rows
    f4 = reaction_lcp(step)
    lam = lcpbench_rows(f4, R) / F
    gaps = np.where(f4.signs > 0, step.upper[f4.nodes] - u[f4.nodes],
                    u[f4.nodes] - step.lower[f4.nodes]) / L
    assert np.max(np.abs(f4.M @ lam + f4.q - gaps)) <= tol
    assert np.max(np.abs(heights_from_reactions(step, f4, lam) - u)) <= tol * L
    # F5: Δα from the heights (eq. 21), the wall rows' multipliers R/F, the fixed
    # nodes' (the pin's closure) by least squares: the residual is round-off
    q5 = angle_qp(step)
    dalpha = step.predict_alpha(u) - step.alpha0
    iu, il = wall_rows(step)
    walls = np.union1d(iu, il)
    nfix = q5.rows - walls.size
    g = q5.P @ dalpha + q5.c + q5.A[:walls.size].T @ (R[walls] / F)
    if nfix:
        Af = q5.A[walls.size:].toarray()
        nu = np.linalg.lstsq(Af.T, -g, rcond=None)[0]
        g = g + Af.T @ nu
    assert np.max(np.abs(g)) <= tol * max(1.0, np.max(np.abs(R / F)))
    S = link_heights(step)
    assert np.max(np.abs(step.origin + S[step.free_nodes] @ dalpha - u)) <= 1e-11 * L
    # F1 (one wall): w = M z + q with z the gaps over ℓ, w the reactions over EI/ℓ²
    form, M, q, dz, dw = step_lcp(step)
    if q.size == form.n_gap:
        z = (form.heights - u[form.rows]) / L
        assert np.max(np.abs(M @ z + q - R[form.rows] / F)) <= tol * max(1.0, np.max(np.abs(q)))


def lcpbench_rows(f4, R):
    """λ on F4's rows (upper rows: R, lower rows: −R)."""
    return np.where(f4.signs > 0, np.maximum(R[f4.nodes], 0.0), np.maximum(-R[f4.nodes], 0.0))


def _kkt_cond(qp):
    P, A = qp.P.toarray(), qp.A.toarray()
    return np.linalg.cond(np.block([[P, A.T], [A, np.zeros((A.shape[0],) * 2)]]))


def _slope(ns, values):
    return np.polyfit(np.log(ns), np.log(values), 1)[0]


def test_conditioning_grows_as_derived():
    """cond(H) and cond of F1/F4 grow like N⁴, the lifted form's KKT matrix like N²,
    and F4's compliance is F1's condensed stiffness inverted (the same cond)."""
    ns = (20, 40, 80)
    h, f1, f3, f4 = [], [], [], []
    for n in ns:
        chain = ActuatorScene(theta=150, height=3, links=n).chain()
        step = assemble_step(chain, chain.rest_alpha)
        h.append(np.linalg.cond(step_qp(step).dense()))
        _, M, *_ = step_lcp(step)
        f1.append(np.linalg.cond(M))
        W = reaction_lcp(step).M
        f4.append(np.linalg.cond(W))
        assert np.allclose(W @ M, np.eye(M.shape[0]), atol=1e-8 * np.linalg.norm(W @ M))
        f3.append(_kkt_cond(lifted_qp(step)))
    assert 3.6 <= _slope(ns, h) <= 4.6
    assert 3.6 <= _slope(ns, f1) <= 4.6
    assert 3.6 <= _slope(ns, f4) <= 4.6
    assert 1.6 <= _slope(ns, f3) <= 2.6


def test_kinematic_matrix_is_the_steps_joint_map(small):
    """J of F3 is the map of the linearised joint angles, eq. (21) written here
    (:func:`_joint_map`): φ̂(u) − φ̂(u₀) = J (u − u₀), and φ̂(u₀) is the step's."""
    rng = np.random.default_rng(3)
    du = rng.standard_normal(small.size) * 1e-2
    J = kinematic_matrix(small)
    phi0, J_eq = _joint_map(ActuatorScene(theta=150, height=3, links=12).chain(), small.alpha)
    scale = np.max(np.abs(J_eq))
    assert np.allclose(J @ du, J_eq @ du, rtol=0, atol=1e-13 * scale * np.max(np.abs(du)) * 10)
    assert np.allclose(phi0 + J_eq @ small.origin, small.phi_origin, rtol=0,
                       atol=1e-13 * (1.0 + scale * np.max(np.abs(small.origin))))


def test_names_labels_and_refusals():
    assert parse_formulation("F3") == Formulation("lifted")
    assert parse_formulation("f4r") == Formulation("reactions", True)
    assert str(parse_formulation("angles+ruiz")) == "angles+ruiz"
    with pytest.raises(ProblemError, match="formulation must be one of"):
        parse_formulation("squares")
    lemke, osqp = get_backend("lemke"), get_backend("osqp")
    assert accepts(lemke, Formulation("reactions")) and not accepts(lemke, Formulation("lifted"))
    assert accepts(osqp, Formulation("lifted"))
    assert not accepts(get_backend("active-set"), Formulation("lifted"))
    with pytest.raises(ProblemError, match="lemke does not take lifted"):
        resolve_formulation(lemke, "lifted")
    assert resolve_formulation(osqp, "heights") is None  # its own form: today's path
    assert resolve_formulation(lemke, "F1") is None


def test_solve_with_a_formulation_is_judged_and_reported():
    scene = ActuatorScene(theta=150, height=3, links=40)
    ref = energy_minimum(scene)  # the direct minimisation (tests/energy_oracle.py)
    res = lcpbench.solve(scene, solver="lemke", settings="high", tol=1e-10,
                         formulation="reactions")
    assert res.converged and res.extra["formulation"] == "reactions"
    assert abs(res.total_force - ref.total_force) <= 1e-8 * abs(ref.total_force)
    with pytest.raises(ProblemError, match="formulation"):
        lcpbench.solve(scene, solver="lemke", formulation="lifted")


def test_the_default_answer_does_not_move():
    """formulation=None, "heights" and "best" on the built-in back-end run its own path.

    Route against route: the promise is that the argument changes nothing there, bit
    for bit (the answer itself is checked against the energy minimum in
    test_small_scene_matches_the_energy_minimum)."""
    scene = ActuatorScene(theta=120, height=4, links=60)
    a = lcpbench.solve(scene)
    for form in ("heights", "best"):
        b = lcpbench.solve(scene, formulation=form)
        assert np.array_equal(a.forces, b.forces) and "formulation" not in b.extra


def test_best_table_names_forms_its_back_ends_take():
    """The committed evidence behind formulation="best": every entry parses and is
    accepted by its back-end (from the registry's data)."""
    from lcpbench.model.formulations import best_formulations
    from lcpbench.solvers.registry import backends

    table = best_formulations()
    known = backends()
    for name, form in table.items():  # at high
        assert name in known
        assert accepts(known[name], parse_formulation(form))
    for name in table:
        if name in available_backends():
            got = resolve_formulation(known[name], "best")
            assert got is None or str(got) == str(parse_formulation(table[name]))
    daqp = known["qpsolvers-daqp"]  # in no table of the evidence
    assert "qpsolvers-daqp" not in best_formulations("default")
    assert resolve_formulation(daqp, "best", "default") is None  # no evidence: its own
    for name, form in best_formulations("default").items():
        assert accepts(known[name], parse_formulation(form))


def test_best_through_the_library_call():
    """lcpbench.solve(..., settings="high", tol=1e-9, formulation="best") runs the
    table's form and is judged as any solve."""
    if "osqp" not in available_backends():
        pytest.skip("osqp not installed")
    from lcpbench.model.formulations import best_formulations

    scene = ActuatorScene(theta=150, height=3, links=40)
    ref = energy_minimum(scene)  # the direct minimisation (tests/energy_oracle.py)
    res = lcpbench.solve(scene, solver="osqp", settings="high", tol=1e-9, formulation="best")
    assert res.extra["formulation"] == best_formulations()["osqp"]
    assert res.converged
    assert abs(res.total_force - ref.total_force) <= 1e-7 * abs(ref.total_force)


def test_elastic_walls_keep_their_own_forms():
    """A step with elastic walls is handed over in its own forms whatever the
    formulation asked for, and says so (an empty ``formulation``).

    Route against route: the promise is the same computation with or without the
    argument (the elastic step's answer is checked by its KKT conditions in
    test_elastic.py)."""
    if "osqp" not in available_backends():
        pytest.skip("osqp not installed")
    scene = ActuatorScene(theta=150, height=3, links=30, wall_stiffness=1.0)
    step = _step(scene)
    assert step.elastic
    a = solve_step(step, "osqp", "high")
    b = solve_step(step, "osqp", "high", formulation="lifted")
    assert b.formulation == "" and b.status == a.status
    assert np.allclose(a.u, b.u, rtol=0, atol=1e-9 * scene.length)

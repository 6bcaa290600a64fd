"""Commands that solve one problem: ``solve``, ``export``, ``lcp`` and ``validate``.

::

    lcpbench solve --theta 150 --height 3 [--links N|auto] [--channel] [--solver NAME]
                   [--wall-profile F.csv [--lower-profile F.csv] [--profile-kind K]]
                   [--accuracy A | --settings default|low|mid|high] [--tol RAD] [--raw]
                   [--json] [--plot F.png]
                   [--start cold|ramp] [--sections THETA:LENGTH,...|anchoring] [--gravity away|toward]
    lcpbench export --theta 150 --height 3 [scene options] --format dat|npz --out FILE
    lcpbench lcp FILE [--solver NAME] [--settings PROFILE] [--formulation NAME|best] [--json]
    lcpbench validate cantilever [--links N] [--json]
"""

from __future__ import annotations

import math
import os
from pathlib import PurePath

import numpy as np

from ..api import solve, solve_internal
from ..errors import ProblemError
from ..model.outer import METHODS
from ..model.result_view import pressure_rows, states_line
from ..problems.scenes import DEFAULT_LINKS
from ._common import (
    ArgumentParser,
    add_json_option,
    error_line,
    format_rows,
    has_matplotlib,
    int_arg,
    node_ranges,
    print_json,
)
from ._friction_args import (
    add_friction_options,
    refuse_auto_links,
    solve_frictional,
    wants_friction,
)
from ._scene_args import (
    DEFAULT_METHOD,
    DEFAULT_SOLVER,
    add_profile_options,
    add_scene_options,
    add_section_options,
    add_solver_options,
    add_tol_option,
    add_wall_options,
    scene_from,
)


def register(subparsers) -> None:
    """Add ``solve``, ``export``, ``lcp`` and ``validate`` to the command line.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The top-level parser's sub-commands.
    """
    s = subparsers.add_parser(
        "solve",
        help="constrained equilibrium of an actuator section against a wall",
        description="Solve one ActuatorScene (or, with --sections, a row of sections: a "
                    "SectionedScene) and report the contact force and its certificate.",
    )
    add_scene_options(s)
    add_section_options(s)
    add_profile_options(s)
    s.add_argument("--accuracy", type=float, default=None, metavar="A",
                   help="relative accuracy of the total force wanted (e.g. 1e-6): sets the "
                        "driver --tol and the back-end tolerance (docs/accuracy.md); not "
                        "with --settings")
    add_tol_option(s)
    add_solver_options(s)
    s.add_argument("--raw", action="store_true",
                   help="hand the back-end the raw step (mm, N) instead of the "
                        "nondimensionalised one")
    s.add_argument("--method", choices=METHODS, default=DEFAULT_METHOD,
                   help=f"outer iteration (default {DEFAULT_METHOD})")
    s.add_argument("--formulation", default=None, metavar="NAME|best",
                   help="the form each contact step is handed to the back-end in: gaps, "
                        "heights, lifted, reactions or angles (F1-F5), each also +ruiz "
                        "and @EPS (the tolerance handed to the back-end); best: the "
                        "back-end's measured recipe, its form and, for OSQP and SCS at "
                        "default, its EPS (docs/formulations.md); default: the back-end's "
                        "own form")
    s.add_argument("--start", choices=("cold", "ramp"), default="cold",
                   help="cold: from the free arc (default; a refused answer is ramped "
                        "anyway); ramp: follow the load from zero first, the state the "
                        "pressurised actuator reaches where there are several")
    add_json_option(s)
    add_friction_options(s)
    s.add_argument("--sensitivities", action="store_true",
                   help="the derivatives of the total force, node forces and heights and the "
                        "peak pressure with respect to theta, h, EI, w, length (and the wall "
                        "stiffness), by implicit differentiation at the converged contact set")
    s.add_argument("--plot", metavar="FILE.png",
                   help="draw the shape, walls and reactions (needs matplotlib)")
    add_wall_options(s)
    s.set_defaults(func=cmd_solve)

    e = subparsers.add_parser(
        "export", help="write the contact step at the converged configuration as an LCP file",
        description="Solve a scene, then write the contact step at its converged "
                    "configuration as an LCP (w = M z + q; z = gaps, w = reactions).")
    add_scene_options(e)
    add_tol_option(e, "convergence threshold of the solve", by_settings=False)
    e.add_argument("--format", choices=("dat", "npz"), default=None,
                   help="Siconos .dat (dense, column-major) or numpy .npz (M, q); "
                        "default: from the suffix of --out (a .dat or .npz suffix that "
                        "contradicts --format is refused)")
    e.add_argument("--out", required=True, metavar="FILE", help="where to write")
    e.add_argument("--raw", action="store_true",
                   help="physical units (mm, N) instead of the nondimensionalised step "
                        "(gaps / length, reactions / (EI/length^2))")
    e.set_defaults(func=cmd_export)

    lp = subparsers.add_parser(
        "lcp", help="solve an LCP file (.dat or .npz) with any back-end",
        description="Solve 0 <= z _|_ M z + q >= 0 from a Siconos .dat or a .npz file and "
                    "print z, w, status, iterations, time and residuals.")
    lp.add_argument("file", metavar="FILE", help="a .dat (Siconos) or .npz (M, q) file")
    from ..solvers.runner import LEMKE_DEFAULT_MAX_SIZE

    add_solver_options(lp, default=None,
                       default_help="active-set where M is symmetric positive definite, "
                                    f"lemke otherwise, up to n = {LEMKE_DEFAULT_MAX_SIZE}")
    lp.add_argument("--formulation", default=None, metavar="NAME|best",
                    help="the form the LCP is handed in: gaps (as given), gaps+ruiz (D M D), "
                         "reactions (the dual in w, M symmetric positive definite), "
                         "reactions+ruiz, each also @EPS (the tolerance handed to the "
                         "back-end); best: the back-end's best of these on the committed "
                         "evidence, else as given (docs/formulations.md)")
    add_json_option(lp)
    lp.set_defaults(func=cmd_lcp)

    v = subparsers.add_parser(
        "validate",
        help="validation against beam theory",
        description="Compare the model against a closed-form reference.",
    )
    cases = v.add_subparsers(dest="case", metavar="CASE", parser_class=ArgumentParser)
    c = cases.add_parser(
        "cantilever",
        help="clamped-free beam under a uniform load against a wall (Sec. III-G)",
    )
    c.add_argument("--links", type=int_arg, default=DEFAULT_LINKS, metavar="N",
                   help=f"number of links (default {DEFAULT_LINKS})")
    add_json_option(c)
    c.set_defaults(func=cmd_validate_cantilever)


# -- output -------------------------------------------------------------------
def contacts(forces, free_nodes) -> list[int]:
    """The 1-based numbers of the nodes that carry a force.

    Parameters
    ----------
    forces : array_like
        Reactions on the free nodes, N.
    free_nodes : array_like of int
        0-based indices of the free nodes.

    Returns
    -------
    list of int
        Nodes whose force exceeds 1e-9 of the total.
    """
    forces = np.asarray(forces, float)
    total = float(forces.sum())
    idx = np.flatnonzero(forces > 1e-9 * max(total, 1e-300))
    return (np.asarray(free_nodes)[idx] + 1).tolist()  # 1-based node numbers


def summary(result, extra=()) -> str:
    """The human summary of a solve: scene, forces, iterations, certificate.

    Parameters
    ----------
    result : ContactResult
        What :func:`lcpbench.solve` returned.
    extra : sequence of (str, str)
        More rows to append.

    Returns
    -------
    str
        Aligned key/value lines.
    """
    sc = result.scene
    cert = result.certificate
    free = sc.chain().free_nodes  # the scene as solved (links resolved)
    if hasattr(sc, "sections"):
        from ..problems.sections import sections_text

        scene = (f"sections {sections_text(sc)} (theta:length[:EI:w]), h={sc.height:g} mm, "
                 f"N={result.links}, length={sc.length:g} mm, weight "
                 f"{'toward' if sc.gravity == '+y' else 'away from'} the upper wall"
                 + (", channel" if sc.channel else "")
                 + (f", wall k={sc.wall_stiffness:g} N/mm per mm"
                    if getattr(sc, "wall_stiffness", np.inf) < np.inf else ""))
    else:
        wall = f"h={sc.height:g} mm"
        if getattr(sc, "wall_profile", None) is not None:
            wall = f"wall profile {sc.wall_profile.name}"
        scene = (f"theta={sc.theta:g} deg, {wall}, N={result.links}, "
                 f"length={sc.length:g} mm, EI={sc.EI:g} N*mm^2, w={sc.weight:g} N/mm"
                 + (", channel" if sc.channel else "")
                 + (f", wall k={sc.wall_stiffness:g} N/mm per mm"
                    if getattr(sc, "wall_stiffness", np.inf) < np.inf else ""))
    rows = [
        ("scene", scene),
        ("converged", ("yes" if result.converged else "no") + f" ({result.reason})"),
        ("total force" if result.forces_lower is None else "upper wall force",
         f"{1e3 * result.total_force:.6g} mN ({result.total_force:.6g} N)"
         + ("" if result.forces_lower is None else ", the total force (the paper's load cell)")),
        ("contact nodes" if result.forces_lower is None else "upper contacts",
         node_ranges(contacts(result.forces, free))),
    ]
    # what was tried beyond the cold start (a saddle left, the loading path followed)
    if getattr(result, "route", "") == "load path":
        rows.append(("ramped", "start='ramp': followed the load from zero"))
    rows += [(name, why) for name, why in getattr(result, "retries", ())
             if name in ("escaped", "ramped", "cold")]
    if getattr(result, "states", ()):  # the starts reached more than one stable state
        rows.append(("stable states", states_line(result)))
    if result.total_force_lower is not None:  # a channel: each wall's total, named
        lower = result.total_force_lower
        rows += [
            ("lower wall force", f"{1e3 * lower:.6g} mN ({lower:.6g} N)"),
            ("lower contacts", node_ranges(contacts(result.forces_lower, free))),
        ]
    rows += pressure_rows(result)
    rows += [
        ("iterations", f"{result.outer_iterations} outer, {result.inner_iterations} inner "
                       f"({result.solver}, {result.method}, tol {result.tol:g} rad"
                       + (f", formulation {form}" if (form := result.extra.get("formulation"))
                          else "") + ")"),
        ("time", f"{result.time_s:.3g} s"),
        ("certificate", f"min gap {cert.min_gap:.3g} mm, min force {cert.min_force:.3g} N, "
                        f"complementarity {cert.complementarity:.3g} N*mm, "
                        f"closure {cert.closure:.3g} mm"),
        ("", f"max torque residual {cert.max_torque_residual:.3g} N*mm "
             f"({cert.relative_torque_residual:.3g} relative)"),
        *_judge_rows(result),
        *extra,
    ]
    return format_rows(rows)


def _judge_rows(result) -> list[tuple[str, str]]:
    """The result judge's bound beside the rule it was held to (model/judge.py)."""
    j = result.judgement
    if j is None or not np.isfinite(j.force_error_bound):
        return []
    return [("force error", f"<= {j.force_error_bound:.2g} x F0, F0 = {1e3 * j.force_unit:.6g} "
                            f"mN (the judge's bound in its force unit; allowed "
                            f"{j.force_tol:.2g})"),
            ("", f"one more exact step gives a total force of "
                 f"{1e3 * j.judge_total_force:.6g} mN")]


# -- commands -----------------------------------------------------------------
def _not_a_directory(option: str, path: str, example: str) -> None:
    """ProblemError when the file an option names is an existing directory (matplotlib
    would write DIR.png beside it, numpy into a file of another name)."""
    if os.path.isdir(path):
        raise ProblemError(f"{option} {path}: is a directory; give the file to write, "
                           f"e.g. {os.path.join(path, example)}")


def cmd_solve(args) -> int:
    """``lcpbench solve``: 0 converged, 1 not converged, 2 bad input or plot error."""
    from ..model.sensitivity import sensitivities, unit, unsupported

    if args.plot is not None and not has_matplotlib():
        error_line("--plot needs matplotlib: pip install 'lcpbench[plot]'")
        return 2
    if args.plot is not None:
        _not_a_directory("--plot", args.plot, "shape.png")
    refuse_auto_links(args)  # (before scene_from runs the frictionless study)
    scene = scene_from(args)
    if wants_friction(args, scene):  # issue 39: a path of one state
        return solve_frictional(args, scene, DEFAULT_SOLVER)
    if args.sensitivities and (why := unsupported(scene)) is not None:
        raise ProblemError(f"--sensitivities: {why}")
    result = solve_internal(scene, solver=args.solver, tol=args.tol, accuracy=args.accuracy,
                            method=args.method, settings=args.settings, scaled=not args.raw,
                            pressure_limit=args.pressure_limit,
                            start="ramp" if args.start == "ramp" else None,
                            formulation=args.formulation)
    plot_error = None
    if args.plot is not None:
        from ..bench.plot import plot_shape

        if getattr(scene, "wall_profile", None) is not None:
            from ..bench.wall_plot import plot_profile_shape as plot_shape

        try:
            plot_shape(result, args.plot)
        except (OSError, ValueError) as exc:
            plot_error = f"--plot {args.plot}: {exc}"
    sens = sensitivities(result) if args.sensitivities and result.converged else None
    if args.json:
        out = result.to_dict()
        if args.accuracy is not None:
            out["accuracy"] = args.accuracy
        if args.sensitivities:  # null where the solve did not converge (its reason says why)
            out["sensitivities"] = None if sens is None else sens.as_json()
        print_json(out)
    else:
        extra = [("plot", args.plot)] if args.plot is not None and plot_error is None else []
        if sens is not None:
            extra.append(("dF/dp", ", ".join(
                f"{v:.4g} N per {unit(p)} ({p})" for p, v in sens.total_force.items())))
        print(summary(result, extra))
    if plot_error is not None:  # the result is printed all the same
        error_line(plot_error)
        return 2
    return 0 if result.converged else 1


def cmd_export(args) -> int:
    """``lcpbench export``: write the converged contact step as a .dat or .npz LCP."""
    from ..model.compiled_driver import assemble_step
    from ..model.step_solver import step_lcp
    from ..problems.lcpfile import write_lcp

    _not_a_directory("--out", args.out, "step.dat")
    fmt = args.format
    suffix = PurePath(args.out).suffix.lower().lstrip(".")
    if fmt is None:
        if suffix not in ("dat", "npz"):
            error_line(f"--out {args.out}: give a .dat or .npz suffix, or --format dat|npz")
            return 2
        fmt = suffix
    elif suffix in ("dat", "npz") and suffix != fmt:
        raise ProblemError(f"--out {args.out} ends in .{suffix} but --format is {fmt}: make "
                           f"them agree (or leave --format out: it follows the suffix)")
    scene = scene_from(args)
    result = solve(scene, tol=args.tol)
    if not result.converged:
        error_line(f"the scene did not converge ({result.reason}); nothing written")
        return 1
    chain = result.scene.chain()
    step = assemble_step(chain, result.alpha)
    form, M, q, _, _ = step_lcp(step, scaled=not args.raw)
    write_lcp(args.out, M, q, fmt=fmt)
    units = "mm and N" if args.raw else "gaps / length, reactions / (EI/length^2)"
    print(f"wrote {args.out}: LCP of size {q.size} (contact rows of nodes "
          f"{node_ranges(chain.free_nodes[form.rows] + 1)}; {units})")
    return 0


def cmd_lcp(args) -> int:
    """``lcpbench lcp``: solve an LCP file; 0 solved, 1 not."""
    from ..model.formulations import solve_lcp_in
    from ..problems.lcpfile import read_lcp
    from ..solvers.runner import default_lcp_solver

    prob = read_lcp(args.file)
    if args.solver is None:
        solver, why = default_lcp_solver(prob.M)
        choice = f"the default, as {why}"
    else:
        solver, choice = args.solver, "given by --solver"
    sol = solve_lcp_in(prob.M, prob.q, solver, args.settings, args.formulation)
    res = sol.extra.get("residuals", {})
    # lcp_residuals divides natural, min_w and complementarity by max(1, |q|_inf); say so
    scale = max(1.0, float(np.max(np.abs(prob.q), initial=0.0)))
    out = {
        "file": args.file, "size": int(prob.q.size), "solver": sol.extra.get("backend"),
        "solver_choice": choice, "formulation": sol.extra.get("formulation", "gaps"),
        "settings": args.settings, "status": sol.status.value, "message": sol.message,
        "iterations": sol.iterations, "solve_time_s": sol.solve_time,
        "setup_time_s": sol.setup_time, "time_source": sol.extra.get("time_source", "solver"),
        "residuals": res, "residual_scale": scale,
        "residuals_scaled": "natural, min_w and complementarity are divided by "
                            "residual_scale = max(1, |q|_inf); min_z is not",
        "z": sol.z, "w": sol.w,
    }
    if args.json:
        print_json(out)
    else:
        with np.printoptions(precision=6, threshold=20, edgeitems=5, linewidth=100):
            rows = [
                ("problem", f"{args.file} (n = {prob.q.size})"),
                ("solver", f"{out['solver']} (settings {args.settings}; {choice}; "
                           f"formulation {out['formulation']})"),
                ("status", sol.status.value + (f" ({sol.message})" if sol.message else "")),
                ("iterations", str(sol.iterations)),
                ("time", f"solve {1e6 * sol.solve_time:.1f} us, setup "
                         f"{1e6 * sol.setup_time:.1f} us ({out['time_source']})"),
                ("residuals", (", ".join(f"{k} {v:.3g}" for k, v in res.items())
                               + f" (all but min_z divided by max(1, |q|_inf) = {scale:.3g})")
                 if res else "n/a"),
                ("z", str(np.asarray(sol.z))),
                ("w", str(np.asarray(sol.w))),
            ]
        print(format_rows(rows))
    return 0 if sol.solved else 1


def cmd_validate_cantilever(args) -> int:
    """``lcpbench validate cantilever``: the model against linear beam theory."""
    from ..studies.validation import cantilever_validation

    out = cantilever_validation(args.links)
    if args.json:
        print_json(out)
    else:
        err = out["relative_error"]
        rows = [
            ("case", f"cantilever, uniform load against a wall (Sec. III-G), N={out['links']}"),
            ("model force", f"{1e3 * out['model_force']:.6g} mN"),
            ("theory force", f"{1e3 * out['theory_force']:.6g} mN (linear beam theory)"),
            ("relative error", "n/a (no contact in theory)" if not math.isfinite(err)
             else f"{100 * err:+.4g} %"),
            ("converged", ("yes" if out["converged"] else "no")
             + f" ({out['outer_iterations']} outer iterations)"),
            ("contact nodes", node_ranges(out["contact_nodes"])),
        ]
        print(format_rows(rows))
    return 0 if out["converged"] else 1

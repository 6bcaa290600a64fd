"""The result judge with its arithmetic compiled (:mod:`lcpbench.model.judge_kernel`).

:func:`judge_fast` takes the arguments of :func:`lcpbench.model.judge.judge`
and returns the same :class:`~lcpbench.model.judge.Judgement`, with the same
checks, thresholds and reasons; the numbers come from one call of the
compiled :func:`~lcpbench.model.judge_kernel.judge_answer` instead of a few
hundred numpy calls. The numpy judge is the reference (tests compare both);
an answer whose driver did not converge, or a chain the kernel does not take,
goes to the numpy judge.

Independent of the solve: the judge kernel shares no code with the solve
kernel (:mod:`lcpbench.model.compiled_kernel`) and takes its own exact step.
"""

from __future__ import annotations

import numpy as np

from ..problems.scenes import Chain
from . import large_n
from .judge import Judgement, failed_checks, judge, settle_verdict


def _kernel():
    """The judge kernel's module (numba imported, the kernel loaded, at the first call)."""
    return _KERNEL[0] if _KERNEL else _load_kernel()


_KERNEL: list = []  # the kernel module, once loaded (emptied by numba_cache.use_aot)


def _load_kernel():
    from ..numba_cache import held, kernel_module  # numba at the first judgement, not at import

    held(_KERNEL).append(kernel_module("lcpbench.model.judge_kernel", "judge_answer"))
    return _KERNEL[0]


def takes(chain: Chain) -> bool:
    """Whether the judge kernel takes this chain: consecutive joints, contiguous free
    nodes (the solve kernel's layouts, :func:`lcpbench.model.compiled.applies`)."""
    from .kernel_call import applies, profile_applies

    return applies("auto", "globalised", chain) or profile_applies("auto", "globalised", chain)


def chain_args(chain: Chain, kernel_args: tuple | None = None) -> tuple:
    """The chain's arrays in the order :func:`judge_kernel.judge_answer` takes them
    (``kernel_args``: the solve kernel's, :func:`lcpbench.model.compiled.kernel_args`,
    when the caller has them: the same arrays, so none is copied twice)."""
    if kernel_args is None:
        from .kernel_call import kernel_args as solve_args

        kernel_args = solve_args(chain)
    args = (*kernel_args[1:], float(chain.wall), bool(chain.channel))
    if chain.profiled_walls:  # (judge_walls: the walls' tables after these)
        from .kernel_call import profile_args

        return (*args, *profile_args(chain)[4:8])
    return args


def judge_fast(chain: Chain, alpha: np.ndarray, forces_upper: np.ndarray,
               forces_lower: np.ndarray, *, tol: float, driver_converged: bool,
               driver_reason: str, step_statuses: list[str], step_sizes: list[float],
               certificate, args: tuple | None = None) -> Judgement:
    """:func:`lcpbench.model.judge.judge`, its arithmetic in the judge kernel.

    ``certificate`` is used only where the numpy judge runs (a driver that did
    not converge, a chain the kernel does not take); otherwise the kernel's
    certificate is returned in ``judgement.certificate``. ``args``: the
    chain's :func:`chain_args`, when the caller has them already.
    """
    if not driver_converged or large_n.applies(chain) or (args is None and not takes(chain)):
        # large N: the numpy judge, whose exact step is in increments on the tridiagonal
        # factor (the kernel's is in heights on the Cholesky of H, whose round-off grows as N⁴)
        return judge(chain, alpha, forces_upper, forces_lower, tol=tol,
                     driver_converged=driver_converged, driver_reason=driver_reason,
                     step_statuses=step_statuses, step_sizes=step_sizes,
                     certificate=certificate)
    k = _KERNEL[0] if _KERNEL else _load_kernel()
    if args is None:
        args = chain_args(chain)
    entry = k.judge_walls if len(args) > 16 else k.judge_answer
    code, st, fu, fl, res = entry(
        _contiguous(alpha, dtype=float), *args, _contiguous(forces_upper, dtype=float),
        _contiguous(forces_lower, dtype=float), float(tol), np.array(step_sizes, dtype=float))
    return verdict_from_stats(code == k.SETTLED, dict(zip(k.STATS, st.tolist(), strict=True)),
                              fu, fl, res, tol=tol, driver_reason=driver_reason,
                              step_statuses=step_statuses)


_contiguous = np.ascontiguousarray


_CERT: list = []  # lcpbench.model.result.Certificate, once imported (result imports judge)


def _certificate():
    from .result import Certificate

    _CERT.append(Certificate)
    return Certificate


def verdict_from_stats(settled: bool, s: dict, fu: np.ndarray, fl: np.ndarray,
                       torque_residual: np.ndarray, *, tol: float, driver_reason: str,
                       step_statuses: list[str]) -> Judgement:
    """The Judgement (and its Certificate) from the kernel's numbers, with the
    reasons of :func:`lcpbench.model.judge.judge`, check by check."""
    Certificate = _CERT[0] if _CERT else _certificate()
    tau, F0 = s["tau"], s["F0"]
    verdict = Judgement(False, driver_reason, tau, F0, contact_threshold=s["eps_R"])
    if settled:
        verdict.forces_upper, verdict.forces_lower = fu, fl
    cert = Certificate(min_gap=s["min_gap"], min_force=s["min_force"],
                       complementarity=s["complementarity"], closure=s["closure"],
                       torque_residual=torque_residual,
                       max_torque_residual=s["max_torque_residual"],
                       relative_torque_residual=s["relative_torque_residual"])
    verdict.certificate = cert
    verdict.inexact_steps = sum(st != "solved" for st in step_statuses)
    unstable = s["unstable"]
    verdict.unstable_directions = int(unstable) if np.isfinite(unstable) else None
    bound = None
    if settled:
        total, node = s["total"], s["node"]
        verdict.force_error_bound, verdict.node_error_bound = total, node
        verdict.contraction, verdict.judge_contraction = s["rho"], s["judge_rho"]
        verdict.judge_total_force = s["judge_total_force"]
        verdict.judge_rounds = int(s["rounds"])
        bound = (total, node, s["node_allowed"])
    fails = failed_checks(cert, step_statuses, tol=tol, tau=tau, comp=s["comp"],
                          comp_allowed=s["comp_allowed"], pen=s["pen"],
                          closure_allowed=s["closure_allowed"], R_min=s["R_min"],
                          allowed_R=max(s["eps_R"], s["floor_R"]), bound=bound,
                          judge_total_force=verdict.judge_total_force,
                          unstable=unstable)
    return settle_verdict(verdict, fails, driver_reason)

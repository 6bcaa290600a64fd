"""A continuation line in one kernel call (:func:`lcpbench.model.batch_kernel.solve_line`).

:func:`lcpbench.solve_many` hands a line here first; :func:`run_line` takes it
when every scene is an actuator scene of one plane (the same scene but for θ and
h, so :class:`~lcpbench.studies.continuation.Solved` sees one plane), with a chain
the solve kernel takes (consecutive joints, flat walls, rigid or elastic), one wall or
a channel, below the large-N formulation and below the moderately heavy load
(those go through :func:`lcpbench.model.compiled.drive`'s SQP steps). Otherwise,
or where the solve kernel stops on a scene, it returns None and the line is
solved scene by scene (:func:`lcpbench.studies.batch_compiled.solve_line`), as
before; a scene alone in its plane on which it stops comes back as a
:class:`~lcpbench.studies.batch_result.Stopped`, which the caller goes on from as
:func:`lcpbench.solve` goes on from the same stop. The results are
:class:`~lcpbench.studies.batch_result.LineResult`, built from the kernel's arrays
when read.
"""

from __future__ import annotations

import time

import numpy as np

from ..model import large_n
from ..model.compiled import heavy
from ..model.elastic import compliance
from ..model.kernel_call import applies, kernel_args
from ..model.result import ContactResult
from ..solvers.judge import requested
from ..solvers.registry import DEFAULT, get_settings
from .batch_result import LineOutput, Stopped, results
from .continuation import POINTS

#: (name, dtype, shape after the rows) of the kernel's outputs per attempt;
#: "links", "n", "nj" and "stats" stand for the sizes
_OUTPUTS = (("o_code", np.int64, ()), ("o_kind", np.int64, ()), ("o_alpha", float, ("links",)),
            ("o_R", float, ("n",)), ("o_rup", float, ("n",)), ("o_rlo", float, ("n",)),
            ("o_u", float, ("n",)), ("o_sig", float, ("n",)), ("o_res", float, (5,)),
            ("o_off", np.int64, ()), ("o_count", np.int64, ()),
            ("j_code", np.int64, ()), ("j_stats", float, ("stats",)), ("j_fu", float, ("n",)),
            ("j_fl", float, ("n",)), ("j_tres", float, ("nj",)), ("conv", np.bool_, ()))
#: the outputs' layout, for the callers that fill a line's arrays themselves
#: (studies.batch_compiled.profile_line: the profile kernel's attempts)
LINE_OUTPUTS = _OUTPUTS
#: rows for cold retries of failed warm starts: a share of the line (more if needed)
SPARE = 8


def _kernel():
    from ..numba_cache import kernel_module  # numba at the first batch, not at import

    return kernel_module("lcpbench.model.batch_kernel", "solve_line")


def takes_line(chain) -> bool:
    """Whether the line kernel takes a line of one plane whose chains are like ``chain``."""
    return (applies(DEFAULT, "globalised", chain) and not large_n.applies(chain)
            and not heavy(chain))


def _shares(chain, c0) -> bool:
    """Whether the line kernel takes ``chain`` in a call whose shared arrays are those of
    ``c0``: it takes the chain, its walls yield as c0's do (rigid or elastic), in a
    channel or not as c0, and the solve kernel's arguments that a line's chains share
    (:func:`~lcpbench.model.kernel_call.kernel_args`' ℓ/N, joint links, nodal load, first
    free node, L and EI/L²) are equal, compared on the chain's own fields (its
    kernel_args not built for the comparison)."""
    if not takes_line(chain) or (chain.elastic_walls, chain.channel) != (c0.elastic_walls,
                                                                           c0.channel):
        return False
    return (float(chain.link_length) == float(c0.link_length)
            and int(chain.free_nodes[0]) == int(c0.free_nodes[0])
            and float(chain.length) == float(c0.length)
            and float(chain.force_scale) == float(c0.force_scale)
            and _same(chain.joint_links, c0.joint_links)
            and _same(_nodal_load(chain), _nodal_load(c0)))


def _compliances(chains: list, field: str, n: int) -> np.ndarray:
    """The compliances 1/k of one wall (``field``: its stiffness) of every chain, a row
    each: :func:`~lcpbench.model.elastic.compliances`' numbers (the solve kernel's
    arguments, :func:`~lcpbench.model.kernel_call.kernel_args`), computed on the rows
    stacked, in one pass for the line (a chain whose wall is rigid: zeros)."""
    ks = [getattr(c, field) for c in chains]
    if all(k is None for k in ks):
        return np.zeros((len(ks), n))
    return compliance(np.stack([np.full(n, np.inf) if k is None else k for k in ks]), n)


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """``np.array_equal(a, b)``, first by their bytes (a fifth of its cost; the same
    bytes of one dtype and shape are the same numbers for the kernel)."""
    return (a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()) \
        or np.array_equal(a, b)


def _nodal_load(chain) -> np.ndarray:
    """The chain's nodal load, kept with it (as kernel_args reads it)."""
    return chain.derived("_nodal_load", lambda: chain.nodal_load)


def run_line(scenes: list, *, tol: float, max_outer: int = 200, settings: str = "default",
             predictor: str = "adaptive", plane: list[int] | None = None,
             kin: np.ndarray | None = None, where: np.ndarray | None = None
             ) -> list[ContactResult | Stopped] | None:
    """The results of the line (actuator scenes of one plane, checked, in
    continuation order), or None: the kernel does not take it (the caller solves it
    scene by scene). ``plane``: each scene's plane (an index from 0), where the line
    holds several (:func:`lcpbench.studies.batch._planes`; rows of sections, each a
    plane of its own): one call for all of them, each scene predicted from its own
    plane (or its kin, below), where every chain shares the first one's layout (:func:`_shares`); None:
    one plane. A scene alone in its plane on which the solve kernel stops is a
    :class:`~lcpbench.studies.batch_result.Stopped` in the list (the caller solves it by
    itself). ``kin``, ``where``: each scene's kin (an index from 0; −1 none) and its
    coordinates (a row each), from which a scene that no answer of its plane predicts
    starts from the nearest answer of its kin (:func:`lcpbench.studies.batch._kin`;
    None: none)."""
    if not scenes:
        return []
    chains = [s.chain() for s in scenes]
    c0 = chains[0]
    if not takes_line(c0):
        return None
    args0 = kernel_args(c0)
    if plane is not None and not all(_shares(c, c0) for c in chains[1:]):
        return None
    m, n, nj = len(chains), c0.free_nodes.size, args0[2].size
    stacked = []
    for f, size in (("rest_alpha", c0.links), ("joint_stiffness", nj), ("rest_joint", nj),
                    ("link_load", c0.links), ("lower", n), ("upper", n)):
        flat = np.concatenate([getattr(c, f) for c in chains])
        if flat.size != m * size:  # chains of different sizes (not one plane)
            return None
        stacked.append(flat.astype(float, copy=False).reshape(m, size))
    ra, k, rest, load, lo, hi = stacked
    # elastic walls: each scene's compliances (the solve kernel's form); none: no columns
    cu, cl = (_compliances(chains, f, n) if c0.elastic_walls else np.zeros((m, 0))
              for f in ("upper_stiffness", "lower_stiffness"))
    wall = np.array([c.wall for c in chains], dtype=float)
    theta = np.array([getattr(s, "theta", 0.0) for s in scenes], dtype=float)  # (rows of
    # sections have none: each is a plane of its own, never predicted)
    height = np.array([s.height for s in scenes], dtype=float)
    kern = _kernel()
    st = get_settings(settings)
    request = requested(st)
    max_iter = st.max_iter if st.max_iter else 20 * n + 50
    sizes = {"links": c0.links, "n": n, "nj": nj, "stats": len(kern.STATS)}
    most = POINTS.get(predictor, 0)
    spare = max(SPARE, m // SPARE)
    while True:
        A = {name: np.empty((m + spare, *(sizes.get(d, d) for d in shape)), dtype=dt)
             for name, dt, shape in _OUTPUTS}
        A["conv"][:] = False
        for name in ("kept", "failed", "base"):
            A[name] = np.empty(m, np.int64)
        t0 = time.perf_counter()
        bad, A["records"] = kern.solve_line(
            ra, args0[1], args0[2], args0[3], k, rest, load, args0[7], args0[8], lo, hi, cu, cl,
            args0[11], args0[12], wall, bool(c0.channel), theta, height,
            np.zeros(m, np.int64) if plane is None else np.asarray(plane, np.int64),
            np.full(m, -1, np.int64) if kin is None else np.asarray(kin, np.int64),
            np.zeros((m, 0)) if where is None else np.asarray(where, float).reshape(m, -1),
            float(tol), int(max_outer),
            int(max_iter), float(request), most, predictor == "adaptive",
            *(A[name] for name, _, _ in _OUTPUTS), A["kept"], A["failed"], A["base"])
        elapsed = time.perf_counter() - t0
        if bad != -2:
            break
        spare = m  # more warm starts failed than rows were spared: again with room for all
    if bad >= 0:
        return None
    return results(LineOutput(scenes, A, float(tol), int(max_outer), settings, predictor,
                              elapsed / m, kern, bool(c0.channel)))


__all__ = ["run_line", "takes_line"]

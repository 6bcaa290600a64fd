"""The frictional outer step, compiled (issue 39, docs/friction.md).

One outer step of a state is :func:`assemble` (the step at the state: the walls at the
nodes' x from their tables of cubic pieces, the rows and pairs, the walls' frames, the
slips, the Delassus form and the LCP), the step's LCP (:mod:`lcpbench.model.
friction_lemke`), and :func:`move` (the answer mapped back, the chain moved by exact
inverse kinematics, the convergence test, the gross-slip excess). A wall is a table of
cubic pieces (:func:`lcpbench.model.wall_kernel.wall_height`; empty: flat). Each
function is ``@njit(cache=True)``; with NUMBA_DISABLE_JIT=1 they run as plain Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .chain_kernel import fit_heights
from .friction_step import delassus_form, frictional_lcp, recover, step_arrays
from .wall_kernel import wall_height

#: :func:`assemble`'s and :func:`move`'s codes
OK, NOT_DEFINITE, NO_Y_PREV, VERTICAL = 0, 1, 2, 3


@njit(cache=True)
def node_positions_at(alpha, a, x0):
    """Every node's x, y (mm): running sums of a cos α, a sin α (as np.cumsum), x + x0."""
    links = alpha.size
    x = np.zeros(links + 1)
    y = np.zeros(links + 1)
    sx = sy = 0.0
    for i in range(links):
        sx += a * np.cos(alpha[i])
        sy += a * np.sin(alpha[i])
        x[i + 1], y[i + 1] = sx, sy
    for i in range(links + 1):
        x[i] += x0
    return x, y


@njit(cache=True)
def node_walls(xf, hi_rows, lo_rows, ku, cu, kl, cl):
    """(h, l, h', l') per free node at its x ``xf``: the upper and lower walls' heights
    (±inf: no row, ``hi_rows``/``lo_rows`` the chain's) and slopes; a wall with a table
    (``ku``, ``cu``; ``kl``, ``cl``; empty: flat) read there where the node has a row."""
    n = xf.size
    up, lo = hi_rows.copy(), lo_rows.copy()
    su, sl = np.zeros(n), np.zeros(n)
    for i in range(n):
        if ku.size and np.isfinite(hi_rows[i]):
            up[i], su[i], _ = wall_height(ku, cu, xf[i])
        if kl.size and np.isfinite(lo_rows[i]):
            lo[i], sl[i], _ = wall_height(kl, cl, xf[i])
    return up, lo, su, sl


@njit(cache=True)
def wall_frames(signs, slope):
    """(n_x, n_y) per wall row: the unit normal in which its gap grows, (h', −1)/c at an
    upper wall (``signs`` −1) and (−l', 1)/c at a lower one, c = √(1 + slope²)."""
    out = np.empty((signs.size, 2))
    for r in range(signs.size):
        c = np.sqrt(1.0 + slope[r] * slope[r])
        out[r, 0] = -signs[r] * slope[r] / c
        out[r, 1] = signs[r] / c
    return out


@njit(cache=True)
def tangential_slip(x, y, x_prev, y_prev, nodes, slope):
    """s = t · (p − p_prev) at ``nodes``, t = (1, slope)/√(1 + slope²) (mm; x − x_prev
    where ``y_prev`` is empty, which needs every slope 0). ok False where it does not."""
    s = np.empty(nodes.size)
    ok = True
    for c in range(nodes.size):
        j = nodes[c]
        dx = x[j] - x_prev[j]
        if y_prev.size == 0:
            ok = ok and slope[c] == 0.0
            s[c] = dx
        else:
            s[c] = (dx + slope[c] * (y[j] - y_prev[j])) / np.sqrt(1.0 + slope[c] * slope[c])
    return s, ok


@njit(cache=True)
def assemble(alpha, x0, a, jl, jr, k, rest, fsh, n, load, pull, left_pull, right_datum,
             newton, has_tau, k_tau, rot_scale, hi_rows, lo_rows, ku, cu, kl, cl, c_up, c_lo,
             mu_up, mu_lo, x_prev, y_prev, pressed, rowed, row_band, near_band, force,
             length):
    """The frictional step at α and x0 (node 1's x), as
    :func:`lcpbench.model.friction_driver.frictional_step` documents it (``fsh``: the
    first free node + 1; ``rot_scale`` 0: both ends held in y; empty ``pressed``,
    ``rowed``, ``y_prev``: none). Returns (code, M, q, W, g_f, s_f, X, rows, signs,
    pair_nodes, pairs, mus, near, normal_xy, tangent_xy, origin, bands, f, gap, slip,
    compliance, rot, rot_k); code :data:`OK`, :data:`NOT_DEFINITE` or :data:`NO_Y_PREV`."""
    first = fsh - 1
    bands, f0, D0, origin = step_arrays(alpha, a, jl, jr, k, rest, fsh, n, load, pull,
                                        right_datum, newton)
    x, y = node_positions_at(alpha, a, x0)
    rot, rot_k = np.empty(0), 0.0
    if rot_scale > 0.0:  # a free right end: r_i = x_i − x_1 on the free heights
        rot = np.empty(n)
        rr = 0.0
        for i in range(n):
            rot[i] = x[first + i] - x[0]
            rr += rot[i] * rot[i]
        rot_k = rot_scale / rr ** 2
    if has_tau:  # τ: one more unknown, moving every node's x
        D = np.ones((D0.shape[0], D0.shape[1] + 1))
        D[:, :D0.shape[1]] = D0
        f = np.empty(n + 1)
        f[:n] = f0
        f[n] = pull + left_pull
    else:
        D, f = D0, f0
    up, lo, su, sl = node_walls(x[first:first + n], hi_rows, lo_rows, ku, cu, kl, cl)
    g_up = np.empty(n)
    g_lo = np.empty(n)
    near = np.zeros(n, np.bool_)
    rows_at = np.zeros(n, np.int64)  # 0 none, −1 upper, 1 lower
    paired = np.zeros(n, np.bool_)
    m_rows = m_pairs = 0
    for i in range(n):
        g_up[i], g_lo[i] = up[i] - y[first + i], y[first + i] - lo[i]
        closest = min(g_up[i], g_lo[i])
        near[i] = closest <= row_band * a or (rowed.size > 0 and rowed[i])
        touching = (closest <= near_band * a or (pressed.size > 0 and pressed[i])) and near[i]
        u_ok, l_ok = np.isfinite(hi_rows[i]) and near[i], np.isfinite(lo_rows[i]) and near[i]
        if u_ok and l_ok:  # a channel node: the nearer wall only
            u_ok, l_ok = g_up[i] <= g_lo[i], g_lo[i] < g_up[i]
        rows_at[i] = -1 if u_ok else 1 if l_ok else 0
        if rows_at[i] != 0:
            m_rows += 1
            if touching:
                paired[i] = True
                m_pairs += 1
    rows = np.empty(m_rows, np.int64)
    signs, mus, slope = np.empty(m_rows), np.empty(m_rows), np.empty(m_rows)
    gap0 = np.empty(m_rows)
    pairs = np.full(m_rows, -1, np.int64)
    pair_nodes = np.empty(m_pairs, np.int64)
    pslope = np.zeros(m_pairs)
    r = p = 0
    for i in range(n):
        if rows_at[i] == 0:
            continue
        upper = rows_at[i] < 0
        rows[r], signs[r] = i, -1.0 if upper else 1.0
        mus[r] = mu_up if upper else mu_lo
        slope[r] = su[i] if upper else sl[i]
        gap0[r] = g_up[i] if upper else g_lo[i]
        if paired[i]:
            pairs[r], pair_nodes[p], pslope[p] = p, first + i, slope[r]
            p += 1
        r += 1
    normal_xy = wall_frames(signs, slope)
    gap = np.empty(m_rows)
    compliance = np.empty(m_rows)
    for r in range(m_rows):
        gap[r] = gap0[r] * abs(normal_xy[r, 1])
        compliance[r] = c_up[rows[r]] if signs[r] < 0 else c_lo[rows[r]]
    tangent_xy = np.empty((m_pairs, 2))
    for c in range(m_pairs):
        pc = np.sqrt(1.0 + pslope[c] * pslope[c])
        tangent_xy[c, 0], tangent_xy[c, 1] = 1.0 / pc, pslope[c] / pc
    slip, ok = tangential_slip(x, y, x_prev, y_prev, pair_nodes, pslope)
    W, g_f, s_f, X, definite = delassus_form(bands, rot, rot_k, k_tau, f, rows, normal_xy,
                                             gap, D, pair_nodes, tangent_xy, slip, first)
    code = OK if ok and definite else NO_Y_PREV if not ok else NOT_DEFINITE
    for r in range(m_rows):  # an elastic wall's compliance 1/k on W_nn's diagonal
        W[r, r] += compliance[r]
    scale = force / length
    M, q = frictional_lcp(W * scale, g_f / length, s_f / length, mus, pairs)
    return (code, M, q, W, g_f, s_f, X, rows, signs, pair_nodes, pairs, mus, near, normal_xy,
            tangent_xy, origin, bands, f, gap, slip, compliance, rot, rot_k)


@njit(cache=True)
def gross_excess(N, T, pair, mu, normal_xy, tangent_xy, pull):
    """The excess |P| − Σ μN of a step that slides as a whole, 0.0 when it does not
    (:func:`lcpbench.model.friction_driver.solve_state`'s gross slip: every pair at its
    cone and the pull beyond what they hold; against a sloped wall P is P + Σ N n_x and
    Σ μN is Σ μN t_x)."""
    limit = np.zeros(T.size)
    load = pull
    for r in range(N.size):
        if pair[r] >= 0:
            limit[pair[r]] += mu[r] * N[r]
        load += normal_xy[r, 0] * N[r]
    capacity = 0.0
    for c in range(T.size):
        capacity += limit[c] * tangent_xy[c, 0]
    scale = max(abs(load), capacity, 1e-300)
    for c in range(T.size):
        if abs(T[c]) < limit[c] - 1e-9 * scale:
            return 0.0
    excess = abs(load) - capacity
    return excess if excess > 1e-9 * scale else 0.0


@njit(cache=True)
def move(z, X, mn, mt, force, length, has_tau, normal_node, pair, mu, normal_xy, tangent_xy,
         rowed, origin, alpha, x0, a, fsh, right_datum, x_right, max_turn, tol, stiff, solved,
         hi_rows, lo_rows, ku, cu, kl, cl, row_band, pull):
    """Where the LCP answer z moves the chain from (α, x0), and whether that ends the
    state (as :func:`lcpbench.model.friction_driver.solve_state` documents it): (code, N,
    T, τ of the step, pressed, α', x0', max|Δα|, τ taken, done, gross-slip excess). δy
    is halved while a link would turn by more than ``max_turn`` (:data:`VERTICAL` where
    no share of 2⁻³⁰ helps); done: a full step of a ``solved`` answer, max|Δα| < ``tol``,
    |τ| < tol·ℓ/``stiff``, every pressed node paired, every node within ``row_band`` · a
    of a wall ``rowed``."""
    zz = z.copy()
    zz[:mn + 2 * mt] *= force
    zz[mn + 2 * mt:] *= length
    N, T, d = recover(zz, X, mn, mt)
    ny = d.size - 1 if has_tau else d.size
    tau_step = d[ny] if has_tau else 0.0
    n = ny
    first = fsh - 1
    pressed = np.zeros(n, np.bool_)
    paired = True
    for r in range(mn):
        if N[r] > 0.0:
            pressed[normal_node[r]] = True
            paired = paired and pair[r] >= 0
    links = alpha.size
    new = np.empty(links)
    sines, cosines = np.empty(links), np.empty(links)
    u = np.empty(n)
    share, fitted = 1.0, False
    for _ in range(30):
        for i in range(n):
            u[i] = origin[i] + share * d[i]
        if fit_heights(new, u, alpha, a, fsh, links, np.empty(0), sines, cosines):
            turn = 0.0
            for i in range(links):
                turn = max(turn, abs(new[i] - alpha[i]))
            if turn <= max_turn:
                fitted = True
                break
        share *= 0.5
    excess = gross_excess(N, T, pair, mu, normal_xy, tangent_xy, pull) if has_tau else 0.0
    if not fitted:
        return (VERTICAL, N, T, tau_step, pressed, alpha.copy(), x0, np.inf, 0.0, False,
                excess)
    dalpha = 0.0
    for i in range(links):
        dalpha = max(dalpha, abs(new[i] - alpha[i]))
    tau = tau_step * share
    x0_new = x0 + tau
    if right_datum:
        span = 0.0
        for i in range(links):
            span += a * np.cos(new[i])
        x0_new = x_right - span
    x, y = node_positions_at(new, a, x0_new)
    up, lo, _, _ = node_walls(x[first:first + n], hi_rows, lo_rows, ku, cu, kl, cl)
    settled = True
    for i in range(n):
        if min(up[i] - y[first + i], y[first + i] - lo[i]) <= row_band * a and not rowed[i]:
            settled = False
    done = (dalpha < tol and abs(tau) * stiff < tol * length and paired and share == 1.0
            and settled and solved)
    return OK, N, T, tau_step, pressed, new, x0_new, dalpha, tau, done, excess

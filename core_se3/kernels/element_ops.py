"""The per-edge, per-element and per-node operations of the default element (numba), shared by
the drivers of ``kernels.element``: edge twists psi = log(g_a^-1 g_b) and their coefficients,
element forces f = Dbar (z - z0), G = dz/deta, the material blocks G^T Dbar G, the edge forces
F and their geometric blocks, the nodal residual and 1/2 adt(r) (``fem.element_default``'s
equations, on plain arrays).

Inlining.  The small per-edge and per-node operations, and the CSR scatters they call
(``kernels.csr.scatter``, ``scatter_diag``, ``lie.log_se3``), are inlined at numba's IR level
(``inline="always"``): a call into a separately cached function is not inlined by LLVM, and
its array arguments are passed as reference-counted structs (``CsrMap`` alone holds 11 arrays).
Measured on a 12x12 plate, serial, three runs each (per element): the node pass 0.42 -> 0.06
us, the edge pass 2.0 -> 1.5 us, the edges' logs 0.54 -> 0.27 us; the residual 1.15-1.38 ->
0.83-0.85 us, the whole tangent 5.3-6.5 -> 4.2-4.7 us.  The element's dense products
(``element_Ke`` and its helpers) stay calls: inlining them too added 3 s to the first-run
compile (23.7 -> 26.5 s for the main job) with no gain beyond the run-to-run noise."""
from __future__ import annotations

from math import sqrt

import numpy as np
from numba import njit

from .csr import scatter_diag
from .lie import (ad_exp_minus, coef_c, coef_dc, coef_ddc, cross3, dexp_inv_T_apply, dexp_inv_T_jacobian,
                  fill_L, hat_add, log_se3)

MAX_EDGE_ANGLE = 0.97 * np.pi       # fem.element_default: beyond this the log's cut at pi is too close
CHUNK = 32                          # elements/edges per parallel task (scratch arrays per task)

# ------------------------------------------------------------------------------------------
# The default element: passes over edges, elements, edges, nodes
# ------------------------------------------------------------------------------------------
# local edges (bottom, top, left, right) = mesh.LOCAL_EDGES; node incidences (edge k, end)
_LOCAL_EDGES = np.array([[0, 1], [3, 2], [0, 3], [1, 2]], np.int64)
_NODE_INC = np.array([[[0, 0], [2, 0]], [[0, 1], [3, 0]], [[1, 1], [3, 1]], [[1, 0], [2, 1]]], np.int64)


@njit(cache=True, inline="always")
def edge_pass1(g, En, e, R, psi, coef):
    """psi_e = log(g_a^-1 g_b), coef_e = (c, dc, ddc)(|w|^2); returns the turn angle |w|."""
    log_se3(g[En[e, 0]], g[En[e, 1]], R, psi[e])
    w0, w1, w2 = psi[e, 3], psi[e, 4], psi[e, 5]
    s = w0 * w0 + w1 * w1 + w2 * w2
    coef[e, 0] = coef_c(s)
    coef[e, 1] = coef_dc(s)
    coef[e, 2] = coef_ddc(s)
    return sqrt(s)


NSYM = 300                          # entries of a symmetric 24x24 matrix's upper triangle


@njit(cache=True)
def unpack_sym(Dp, el, D):
    """D (24,24) <- the symmetric matrix whose upper triangle, row by row, is Dp[el] (300,)
    (the element's Dbar is stored packed: 2.4 kB instead of 4.6 kB per element)."""
    k = 0
    for a in range(24):
        for b in range(a, 24):
            v = Dp[el, k]
            D[a, b] = v
            D[b, a] = v
            k += 1


@njit(cache=True)
def packed_matvec(Dp, x, out):
    """out[el] = Dbar[el] x[el] for every element, Dbar packed (m, 300), x (m, 24)."""
    for el in range(Dp.shape[0]):
        for a in range(24):
            out[el, a] = 0.0
        k = 0
        for a in range(24):
            out[el, a] += Dp[el, k] * x[el, a]
            k += 1
            for b in range(a + 1, 24):
                v = Dp[el, k]
                out[el, a] += v * x[el, b]
                out[el, b] += v * x[el, a]
                k += 1


@njit(cache=True)
def element_force(el, elem_edges, sgn, D, z0, Dz0, psi, z, f, fe):
    """z = (sgn_k psi_k / 2) (24,), f = D (z - z0) (D: element el's Dbar, unpacked), fe[el, k]
    = sgn_k f_k (conjugate to the mesh-edge twists).  Returns (energy 1/2 dz.f, |f + Dz0|^2 +
    |f|^2)."""
    for k in range(4):
        e = elem_edges[el, k]
        sk = 0.5 * sgn[el, k]
        for i in range(6):
            z[6 * k + i] = sk * psi[e, i] - z0[el, 6 * k + i]
    en = 0.0
    fs = 0.0
    for a in range(24):
        acc = 0.0
        for b in range(24):
            acc += D[a, b] * z[b]
        f[a] = acc
        en += z[a] * acc
        fz = acc + Dz0[el, a]
        fs += fz * fz + acc * acc
    for k in range(4):
        sk = sgn[el, k]
        for i in range(6):
            fe[el, k, i] = sk * f[6 * k + i]
    return 0.5 * en, fs


@njit(cache=True)
def _gt_times(G, M, out, nc):
    """out (24,24) <- G^T M for the element's G = d z / d eta (24x24, two non-zero 6x6 blocks
    per node column: G[k, la] = -L(-psi_k)/2, G[k, lb] = L(psi_k)/2, local psi_k = sgn psi),
    G stored as (4 edges, 2 ends, 6, 6); rows of M are used whole as axpys of length nc = 24.
    The lower-left 3x3 of every L block is zero and skipped.  ``nc`` is passed at run time on
    purpose: with a literal 24 LLVM unrolls the loop fully and can then no longer vectorise it
    (possible aliasing of out and M); as a run-time trip count it is vectorised with a runtime
    alias check (2x faster, measured)."""
    for A in range(4):
        k0 = _NODE_INC[A, 0, 0]
        e0 = _NODE_INC[A, 0, 1]
        k1 = _NODE_INC[A, 1, 0]
        e1 = _NODE_INC[A, 1, 1]
        for i in range(6):
            o = out[6 * A + i]
            for c in range(nc):
                o[c] = 0.0
            qmax = 3 if i < 3 else 6
            for q in range(qmax):
                gv = G[k0, e0, q, i]
                gw = G[k1, e1, q, i]
                m0 = M[6 * k0 + q]
                m1 = M[6 * k1 + q]
                for c in range(nc):
                    o[c] += gv * m0[c] + gw * m1[c]


@njit(cache=True)
def element_G(el, elem_edges, sgn, psi, coef, G):
    """G blocks of element el: for local edge k with local psi_k = sgn_k psi_e,
    G[k,0] = -1/2 L(-psi_k) (node la), G[k,1] = 1/2 L(psi_k) (node lb)."""
    for k in range(4):
        e = elem_edges[el, k]
        s = 1.0 if sgn[el, k] > 0 else -1.0
        fill_L(psi[e], coef[e, 0], coef[e, 1], -s, -0.5, G[k, 0])
        fill_L(psi[e], coef[e, 0], coef[e, 1], s, 0.5, G[k, 1])


@njit(cache=True)
def element_stress_lin(el, quads, elem_edges, sgn, Dbar, z0, psi, coef, eta, G, w, D, out):
    """out[el] = Dbar (z - z0 + G eta) (24,): the element's stresses linearised in the nodal
    increments eta (n, 6); the z increment of local edge k (nodes la, lb of _LOCAL_EDGES) is
    G[k,0] eta_la + G[k,1] eta_lb (``element_G``: = sgn_k/2 (L(psi) eta_b - L(-psi) eta_a) of
    the mesh edge a -> b).  Dbar packed (m, 300); workspace G (4,2,6,6), w (24,), D (24,24)."""
    unpack_sym(Dbar, el, D)
    element_G(el, elem_edges, sgn, psi, coef, G)
    for k in range(4):
        e = elem_edges[el, k]
        sk = 0.5 * sgn[el, k]
        na = quads[el, _LOCAL_EDGES[k, 0]]
        nb = quads[el, _LOCAL_EDGES[k, 1]]
        for i in range(6):
            acc = 0.0
            for j in range(6):
                acc += G[k, 0, i, j] * eta[na, j] + G[k, 1, i, j] * eta[nb, j]
            w[6 * k + i] = (sk * psi[e, i] - z0[el, 6 * k + i]) + acc
    for a in range(24):
        acc = 0.0
        for b in range(24):
            acc += D[a, b] * w[b]
        out[el, a] = acc


@njit(cache=True)
def element_Ke(D, G, TT, TTt, KeT):
    """KeT (24,24) <- (G^T D G)^T = G^T (G^T D)^T: two vectorisable G^T products (D: the
    element's Dbar, unpacked).  D is symmetric, so KeT equals Ke to round-off and is read
    row-wise by the scatter."""
    nc = D.shape[1]
    _gt_times(G, D, TT, nc)
    for a in range(24):
        for b in range(24):
            TTt[a, b] = TT[b, a]
    _gt_times(G, TTt, KeT, nc)


@njit(cache=True, inline="always")
def edge_F(e, edge_slots, fe, F):
    """F_e = sum of fe over the element sides of edge e (the bincount of element.py)."""
    for i in range(6):
        F[i] = 0.0
    for t in range(2):
        sl = edge_slots[e, t]
        if sl >= 0:
            el = sl // 4
            k = sl - 4 * el
            for i in range(6):
                F[i] += fe[el, k, i]


@njit(cache=True, inline="always")
def edge_residual(e, psi, coef, F, rE):
    """r_a = -1/2 L(-psi)^T F, r_b = 1/2 L(psi)^T F."""
    dexp_inv_T_apply(psi[e], coef[e, 0], coef[e, 1], -1.0, F, rE[e, 0], -0.5)
    dexp_inv_T_apply(psi[e], coef[e, 0], coef[e, 1], 1.0, F, rE[e, 1], 0.5)


@njit(cache=True, inline="always")
def edge_KE(e, psi, coef, F, Lp, Lm, Ad, Jm, Y, H, p):
    """Geometric edge block H (12,12) of element.py:
    p = L(psi)^T F, Jm = d(L(psi)^T F)/d psi, M = [-Ad_{exp(-psi)}, I], N = [-L(-psi), L(psi)],
    A = M^T Jm N, H = (A + A^T)/4, H_ba += -adt(p) Ad/4, H_ab += (-adt(p) Ad/4)^T."""
    ps = psi[e]
    c, dc, ddc = coef[e, 0], coef[e, 1], coef[e, 2]
    fill_L(ps, c, dc, 1.0, 1.0, Lp)
    fill_L(ps, c, dc, -1.0, 1.0, Lm)
    dexp_inv_T_jacobian(ps, c, dc, ddc, F, Jm)
    ad_exp_minus(ps, Ad)
    dexp_inv_T_apply(ps, c, dc, 1.0, F, p, 1.0)
    # Y = M^T Jm (12, 6): top = -Ad^T Jm, bottom = Jm
    for i in range(6):
        for j in range(6):
            acc = 0.0
            for k in range(6):
                acc += Ad[k, i] * Jm[k, j]
            Y[i, j] = -acc
            Y[i + 6, j] = Jm[i, j]
    # A = Y N (12, 12): A[:, :6] = -Y Lm, A[:, 6:] = Y Lp (into H, symmetrised below)
    for i in range(12):
        for j in range(6):
            a1 = 0.0
            a2 = 0.0
            for k in range(6):
                a1 += Y[i, k] * Lm[k, j]
                a2 += Y[i, k] * Lp[k, j]
            H[i, j] = -a1
            H[i, j + 6] = a2
    for i in range(12):
        for j in range(i, 12):
            s = 0.25 * (H[i, j] + H[j, i])
            H[i, j] = s
            H[j, i] = s
    # Hba = -1/4 adt(p) Ad, adt(p) = [[0, hat(pv)], [hat(pv), hat(pw)]]
    pv0, pv1, pv2, pw0, pw1, pw2 = p[0], p[1], p[2], p[3], p[4], p[5]
    for j in range(6):
        a0, a1, a2 = Ad[0, j], Ad[1, j], Ad[2, j]
        b0, b1, b2 = Ad[3, j], Ad[4, j], Ad[5, j]
        t0, t1, t2 = cross3(pv0, pv1, pv2, b0, b1, b2)        # hat(pv) Ad[3:, j]
        u0, u1, u2 = cross3(pv0, pv1, pv2, a0, a1, a2)        # hat(pv) Ad[:3, j]
        x0, x1, x2 = cross3(pw0, pw1, pw2, b0, b1, b2)        # hat(pw) Ad[3:, j]
        h = (t0, t1, t2, u0 + x0, u1 + x1, u2 + x2)
        for i in range(6):
            H[6 + i, j] -= 0.25 * h[i]
            H[j, 6 + i] -= 0.25 * h[i]


@njit(cache=True, inline="always")
def node_residual(nd, node_ptr, node_inc, rE, r):
    for i in range(6):
        r[nd, i] = 0.0
    for t in range(node_ptr[nd], node_ptr[nd + 1]):
        q = node_inc[t]
        e = q // 2
        side = q - 2 * e
        for i in range(6):
            r[nd, i] += rE[e, side, i]


@njit(cache=True, inline="always")
def node_Kn(nd, r, data, cmap, K6):
    """Kn = 1/2 adt(r) = 1/2 [[0, hat(r_v)], [hat(r_v), hat(r_w)]] on node nd's diagonal block."""
    for i in range(6):
        for j in range(6):
            K6[i, j] = 0.0
    hat_add(K6, 0, 3, r[nd, 0], r[nd, 1], r[nd, 2], 0.5)
    hat_add(K6, 3, 0, r[nd, 0], r[nd, 1], r[nd, 2], 0.5)
    hat_add(K6, 3, 3, r[nd, 3], r[nd, 4], r[nd, 5], 0.5)
    scatter_diag(data, cmap, nd, K6, 1.0)


@njit(cache=True)
def check_angles(ang):
    """(flag, edge): flag 1 if max angle > MAX_EDGE_ANGLE (edge = first argmax)."""
    if ang.size == 0:
        return 0, -1
    k = 0
    for e in range(1, ang.size):
        if ang[e] > ang[k]:
            k = e
    if ang[k] > MAX_EDGE_ANGLE:
        return 1, k
    return 0, -1

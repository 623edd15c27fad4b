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
compile (23.7 -> 26.5 s for the main job) with no gain beyond the run-to-run noise
(``element_dbar.element_D``, the per-element choice of Dbar's form, is inlined).

The material block.  With the element energy Pi_e = 1/2 (z - z0)^T Dbar (z - z0), z = (sgn_k
psi_k / 2) over the element's 4 edges, and d psi = L(psi) eta_b - L(-psi) eta_a (L = dexp_inv
= [[A, B], [0, A]]; ``fem.element_default``'s module docstring), the element's forces are f =
Dbar (z - z0) and its material block Ke = G^T Dbar G, G = dz/deta (24x24, two 6x6 blocks per
edge row: ``element_G``).  The kernels order the 24 components of z as z' = (v of the 4 edges,
w of the 4 edges) (``ZP``).  Every law of ``fem.material`` acts with membrane and shear on the
translational parts v and with bending and drilling on the rotational parts w, so its Dbar has
exactly zero v-w blocks: Dbar' = diag(Dvv, Dww), stored per element as the two 12x12 blocks
(``split_form``, read without unpacking; ``ElementKernels.split``).  A law that couples v and w
(a user's ``ResultantLaw``) takes the general path: the whole Dbar, unpacked per element
(``unpack_perm``).  Products per element (multiply-adds):

    ========================== ======== ======================== ====================
    per element                before   split Dbar (every law    general path (a law
                                        of ``fem.material``)     coupling v and w)
    ========================== ======== ======================== ====================
    unpack Dbar (stores)       576      0                        576
    f = Dbar dz                576      288                      576
    TT = G^T P^T Dbar'         5184     2592                     5184
    Ke = G^T P^T TT^T          5184     5184                     5184
    ========================== ======== ======================== ====================

The time went down mostly by the form of the G^T products (``_gt_times``: each output row
written once, its 6 or 12 terms in registers, instead of 6 or 12 axpys into it) and of the
forces (axpys of Dbar's rows instead of dot products: ``element_force``); the split form adds
the saved unpacking and halves.  Measured (``benchmarks/kernel_passes.py``, one thread, a
12x12 | 100x100 plate, min [range] of 6 alternating runs, us per element): the element pass
(forces + material blocks, scattered) 2.95-4.17 | 3.54-3.82 -> 1.90-2.10 | 2.71-3.34 (general
path 2.04-3.20 | 2.79-3.67); the whole tangent 4.73-7.31 | 5.75-7.15 -> 3.69-3.85 | 4.87-5.04
(general 3.81-4.42 | 4.91-5.54); the residual 0.92-1.27 | 0.88-1.02 -> 0.50-0.53 | 0.46-0.50
(general 0.79-1.04 | 0.81-1.10).  Tried and not kept: a product over the non-zero entries of
Dbar's union pattern (64 of 576 on meshes whose frames follow the edges, 160 on general quads):
a list of (row, column) pairs cost 7 ns per pair (0.49 us for 64 pairs, more than the whole
G^T P^T Dbar' above); only the upper node blocks of the symmetric Ke (rows of 24, 18, 12, 6
columns: no faster); one pass per node for all its six rows (register spills: slower);
storing the first product transposed (strided stores: slower than the transpose)."""
from __future__ import annotations

from math import sqrt

import numpy as np
from numba import njit

from .csr import scatter_diag
from .element_dbar import ZP, unpack_sym
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
def edge_pass1(g, En, e, R, psi, coef, Rk, gb):
    """psi_e = log(g_a^-1 g_b), coef_e = (c, dc, ddc)(|w|^2); returns the turn angle |w|.  Rk
    (E, 3, 3) non-empty: log(g_a^-1 g_b Rk[e]) across a cross field's cuts (``match_G``; gb
    (4, 4) scratch)."""
    if Rk.shape[0] == 0:
        log_se3(g[En[e, 0]], g[En[e, 1]], R, psi[e])
    else:
        b = g[En[e, 1]]
        for i in range(4):
            for j in range(3):
                gb[i, j] = b[i, 0] * Rk[e, 0, j] + b[i, 1] * Rk[e, 1, j] + b[i, 2] * Rk[e, 2, j]
            gb[i, 3] = b[i, 3]
        log_se3(g[En[e, 0]], gb, R, psi[e])
    w0, w1, w2 = psi[e, 3], psi[e, 4], psi[e, 5]
    s = w0 * w0 + w1 * w1 + w2 * w2
    coef[e, 0] = coef_c(s)
    coef[e, 1] = coef_dc(s)
    coef[e, 2] = coef_ddc(s)
    return sqrt(s)


@njit(cache=True)
def element_force(el, elem_edges, sgn, Dr, z0, Dz0, psi, z, f, fe):
    """Element forces f = dPi_e/dz = Dbar (z - z0), z = (sgn_k psi_k / 2) over the 4 edges
    (``fem.element_default``: Pi_e = 1/2 (z - z0)^T Dbar (z - z0)); returns (energy 1/2 dz.f,
    |f + Dz0|^2 + |f|^2).  Dr: element el's Dbar in the order z' (``element_D``), (24, 24), or
    the split form (24, 12) whose v rows act on dz'[:12] and w rows on dz'[12:] (288 products
    instead of 576), or (24, 16) with the v rows' coupling to the edges' w_3 (96 more); z, f
    (24,): workspace (dz, f in the order z'); fe (m, 4, 6): written,
    fe[el, k] = sgn_k f_k (conjugate to the mesh-edge twists)."""
    for k in range(4):
        e = elem_edges[el, k]
        sk = 0.5 * sgn[el, k]
        for i in range(6):
            z[ZP[6 * k + i]] = sk * psi[e, i] - z0[el, 6 * k + i]
    # f = sum_r dz_r Dbar[r] (Dbar symmetric): axpys of Dbar's rows, vectorised (a dot product
    # per row is a chain of dependent additions: about 1.8 times as long, measured)
    W = Dr.shape[1]
    H = 24 if W == 24 else 12                      # the whole row, or its own half (split forms)
    for r in range(24):
        f[r] = 0.0
    for r in range(24):
        o = 0 if r < 12 or H == 24 else 12
        zr = z[r]
        d = Dr[r]
        fo = f[o:o + H]
        for c in range(H):
            fo[c] += zr * d[c]
    if W == 16:                                    # the v rows' coupling with the edges' w_3
        for r in range(12):
            d = Dr[r]
            for k in range(4):
                f[r] += d[12 + k] * z[14 + 3 * k]
                f[14 + 3 * k] += d[12 + k] * z[r]
    en = 0.0
    for r in range(24):
        en += z[r] * f[r]
    fs = 0.0
    for k in range(4):
        sk = sgn[el, k]
        for i in range(6):
            fa = f[ZP[6 * k + i]]
            fz = fa + Dz0[el, 6 * k + i]
            fs += fz * fz + fa * fa
            fe[el, k, i] = sk * fa
    return 0.5 * en, fs


@njit(cache=True)
def _gt_times(G, M, out, nc):
    """out (24,24) <- G^T P^T M: the product of G^T, G = d z / d eta (``element_G``), with a
    matrix M whose rows are in the order z' (``ZP``; P z = z').

    G (24x24) has two non-zero 6x6 blocks per node column, G[k, la] = -L(-psi_k)/2, G[k, lb] =
    L(psi_k)/2 (local psi_k = sgn psi), stored as (4 edges, 2 ends, 6, 6).  Row 6A + i of the
    product (node A, component i) combines the rows of A's two edges k0, k1 (``_NODE_INC``):

        out[6A+i] = sum_q G[k0,e0,q,i] M[ZP[6k0+q]] + G[k1,e1,q,i] M[ZP[6k1+q]],

    q < 3 for i < 3 (the lower-left 3x3 of every L block is zero and skipped), q < 6 for
    i >= 3: 6 or 12 terms, written as one expression per column so that each output row is
    stored once and its terms stay in registers (an axpy per term, loading and storing the row
    up to 12 times, took 2.5 times as long, measured).  ``nc`` (= 24) is passed at run time on
    purpose: with a literal 24 LLVM unrolls the loop fully and can then no longer vectorise it
    (possible aliasing of out and M); as a run-time trip count it is vectorised with a runtime
    alias check (2x faster, measured)."""
    for A in range(4):
        k0 = _NODE_INC[A, 0, 0]
        e0 = _NODE_INC[A, 0, 1]
        k1 = _NODE_INC[A, 1, 0]
        e1 = _NODE_INC[A, 1, 1]
        P = G[k0, e0]
        Q = G[k1, e1]
        m0, m1, m2 = M[3 * k0], M[3 * k0 + 1], M[3 * k0 + 2]                  # rows ZP[6k0 + q], q < 3
        m3, m4, m5 = M[12 + 3 * k0], M[13 + 3 * k0], M[14 + 3 * k0]           # q >= 3
        n0, n1, n2 = M[3 * k1], M[3 * k1 + 1], M[3 * k1 + 2]
        n3, n4, n5 = M[12 + 3 * k1], M[13 + 3 * k1], M[14 + 3 * k1]
        for i in range(3):
            a0, a1, a2 = P[0, i], P[1, i], P[2, i]
            b0, b1, b2 = Q[0, i], Q[1, i], Q[2, i]
            o = out[6 * A + i]
            for c in range(nc):
                o[c] = a0 * m0[c] + a1 * m1[c] + a2 * m2[c] + b0 * n0[c] + b1 * n1[c] + b2 * n2[c]
        for i in range(3, 6):
            a0, a1, a2, a3, a4, a5 = P[0, i], P[1, i], P[2, i], P[3, i], P[4, i], P[5, i]
            b0, b1, b2, b3, b4, b5 = Q[0, i], Q[1, i], Q[2, i], Q[3, i], Q[4, i], Q[5, i]
            o = out[6 * A + i]
            for c in range(nc):
                o[c] = (a0 * m0[c] + a1 * m1[c] + a2 * m2[c] + a3 * m3[c] + a4 * m4[c] + a5 * m5[c]
                        + b0 * n0[c] + b1 * n1[c] + b2 * n2[c] + b3 * n3[c] + b4 * n4[c] + b5 * n5[c])


@njit(cache=True)
def _gt_times_split(G, Ds, out, h):
    """out (24,24) <- G^T P^T D' for D' = diag(Dvv, Dww) given as Ds (24, h = 12) (``split_form``):
    ``_gt_times`` with M = D', whose v rows vanish on the w columns and w rows on the v columns:

        out[6A+i, :h] = sum_{q<3} G[k0,e0,q,i] Dvv[3k0+q] + G[k1,e1,q,i] Dvv[3k1+q]   (all i),
        out[6A+i, h:] = sum_{q<3} G[k0,e0,3+q,i] Dww[3k0+q] + G[k1,e1,3+q,i] Dww[3k1+q]
                        (i >= 3; 0 for i < 3, where the L blocks' lower-left 3x3 is zero),

    6 terms over 12 columns per half (2592 products instead of 5184)."""
    for A in range(4):
        k0 = _NODE_INC[A, 0, 0]
        e0 = _NODE_INC[A, 0, 1]
        k1 = _NODE_INC[A, 1, 0]
        e1 = _NODE_INC[A, 1, 1]
        P = G[k0, e0]
        Q = G[k1, e1]
        m0, m1, m2 = Ds[3 * k0], Ds[3 * k0 + 1], Ds[3 * k0 + 2]               # Dvv rows of edge k0
        m3, m4, m5 = Ds[12 + 3 * k0], Ds[13 + 3 * k0], Ds[14 + 3 * k0]        # Dww rows of edge k0
        n0, n1, n2 = Ds[3 * k1], Ds[3 * k1 + 1], Ds[3 * k1 + 2]
        n3, n4, n5 = Ds[12 + 3 * k1], Ds[13 + 3 * k1], Ds[14 + 3 * k1]
        for i in range(6):
            a0, a1, a2 = P[0, i], P[1, i], P[2, i]
            b0, b1, b2 = Q[0, i], Q[1, i], Q[2, i]
            o = out[6 * A + i]
            for c in range(h):
                o[c] = a0 * m0[c] + a1 * m1[c] + a2 * m2[c] + b0 * n0[c] + b1 * n1[c] + b2 * n2[c]
            ow = out[6 * A + i, h:]
            if i < 3:
                for c in range(h):
                    ow[c] = 0.0
            else:
                a3, a4, a5 = P[3, i], P[4, i], P[5, i]
                b3, b4, b5 = Q[3, i], Q[4, i], Q[5, i]
                for c in range(h):
                    ow[c] = a3 * m3[c] + a4 * m4[c] + a5 * m5[c] + b3 * n3[c] + b4 * n4[c] + b5 * n5[c]


@njit(cache=True)
def _gt_times_drill(G, Ds, out):
    """out (24,24) += G^T P^T Dc' for the coupling part Dc' of the split form with drilling
    coupling (``split_form``, Ds (24, 16)): the v rows r of the edges (z' 3k + q) have Dc[r, k']
    in the w_3 columns 14 + 3k', the w_3 rows (z' 14 + 3k) have Dc[:, k] in the v columns:

        out[6A+i, 14+3k'] += sum_{q<3} G[k0,e0,q,i] Dc[3k0+q, k'] + G[k1,e1,q,i] Dc[3k1+q, k'],
        out[6A+i, c < 12] += G[k0,e0,5,i] Dc[c, k0] + G[k1,e1,5,i] Dc[c, k1]    (i >= 3)."""
    for A in range(4):
        k0 = _NODE_INC[A, 0, 0]
        e0 = _NODE_INC[A, 0, 1]
        k1 = _NODE_INC[A, 1, 0]
        e1 = _NODE_INC[A, 1, 1]
        P = G[k0, e0]
        Q = G[k1, e1]
        for i in range(6):
            o = out[6 * A + i]
            a0, a1, a2 = P[0, i], P[1, i], P[2, i]
            b0, b1, b2 = Q[0, i], Q[1, i], Q[2, i]
            for k in range(4):
                o[14 + 3 * k] += (a0 * Ds[3 * k0, 12 + k] + a1 * Ds[3 * k0 + 1, 12 + k] + a2 * Ds[3 * k0 + 2, 12 + k]
                                  + b0 * Ds[3 * k1, 12 + k] + b1 * Ds[3 * k1 + 1, 12 + k]
                                  + b2 * Ds[3 * k1 + 2, 12 + k])
            if i >= 3:
                a5, b5 = P[5, i], Q[5, i]
                for c in range(12):
                    o[c] += a5 * Ds[c, 12 + k0] + b5 * Ds[c, 12 + k1]


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
def element_stress_lin(el, quads, elem_edges, sgn, Rk, Dbar, z0, psi, coef, eta, G, w, D, out):
    """out[el] = Dbar (z - z0 + G eta) (24,): the element's stresses linearised in the nodal
    increments eta (n, 6); the z increment of local edge k (nodes la, lb of _LOCAL_EDGES) is
    G[k,0] eta_la + G[k,1] eta_lb (``element_G``: = sgn_k/2 (L(psi) eta_b - L(-psi) eta_a) of
    the mesh edge a -> b; across a cut: ``match_G``).  Dbar packed (m, 300); workspace G (4,2,6,6),
    w (24,), D (24,24)."""
    unpack_sym(Dbar, el, D)
    element_G(el, elem_edges, sgn, psi, coef, G)
    match_G(G, el, elem_edges, sgn, Rk)
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
def element_Ke(Dr, G, TT, TTt, KeT):
    """KeT (24,24) <- the material block G^T Dbar G of the element (``fem.element_default``:
    the part of the Hessian of Pi_e = 1/2 (z - z0)^T Dbar (z - z0) in the nodal increments eta
    that comes from dz = G eta, G = dz/deta; the part from z's curvature is the edges'), as
    G^T (G^T P^T D')^T with D' = P Dbar P^T in the order z' (``ZP``):

        TT = G^T P^T D' (= G^T Dbar P^T),  TTt = TT^T (= P Dbar G),  KeT = G^T P^T TTt,

    two vectorised G^T products (``_gt_times``).  Dr is ``element_D``'s: the whole D' (24, 24),
    or the split form (24, 12) of a law without v-w coupling, whose first product
    (``_gt_times_split``) takes half the work.  KeT equals Ke to round-off (Dbar is symmetric)
    and is read row-wise by the scatter."""
    nc = TT.shape[1]
    if Dr.shape[1] == nc:
        _gt_times(G, Dr, TT, nc)
    else:
        w = Dr.shape[1]
        # the half width 12 as a run-time value (a literal would be unrolled and not vectorised,
        # as ``_gt_times``' nc)
        _gt_times_split(G, Dr, TT, w if w == 12 else w - 4)
        if w == 16:
            _gt_times_drill(G, Dr, TT)
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


@njit(cache=True)
def rotate_blocks(K, nodes, Rq, S):
    """K (6k, 6k) <- T K T^T in place, T = blockdiag(R, R) of the rotations Rq (n, 3, 3) of the
    k ``nodes``: blocks of the element's frames (turned about the normals, ``mesh.gauge``) in the
    user's (``fem.element_default``, "Frames"); Rq empty (0, 3, 3): no gauge, nothing done.
    S (3, 3): scratch.  The 3x3 block (I, J) belongs to node I // 2, part I % 2 (v or w)."""
    if Rq.shape[0] == 0:
        return
    nb = 2 * nodes.size
    for I in range(nb):
        A = Rq[nodes[I // 2]]
        for J in range(nb):
            B = Rq[nodes[J // 2]]
            i0, j0 = 3 * I, 3 * J
            for i in range(3):                     # S = K_IJ B^T
                for j in range(3):
                    S[i, j] = K[i0 + i, j0] * B[j, 0] + K[i0 + i, j0 + 1] * B[j, 1] + K[i0 + i, j0 + 2] * B[j, 2]
            for i in range(3):                     # K_IJ = A S
                for j in range(3):
                    K[i0 + i, j0 + j] = A[i, 0] * S[0, j] + A[i, 1] * S[1, j] + A[i, 2] * S[2, j]


@njit(cache=True, inline="always")
def _times_turn_T(M, r0, r1, c0, R):
    """M[r0:r1, c0:c0+3] <- M[r0:r1, c0:c0+3] R^T (in place)."""
    for i in range(r0, r1):
        a0, a1, a2 = M[i, c0], M[i, c0 + 1], M[i, c0 + 2]
        for j in range(3):
            M[i, c0 + j] = a0 * R[j, 0] + a1 * R[j, 1] + a2 * R[j, 2]


@njit(cache=True, inline="always")
def _turn_times(M, r0, c0, c1, R):
    """M[r0:r0+3, c0:c1] <- R M[r0:r0+3, c0:c1] (in place)."""
    for j in range(c0, c1):
        a0, a1, a2 = M[r0, j], M[r0 + 1, j], M[r0 + 2, j]
        for i in range(3):
            M[r0 + i, j] = R[i, 0] * a0 + R[i, 1] * a1 + R[i, 2] * a2


@njit(cache=True)
def match_G(G, el, elem_edges, sgn, Rk):
    """G[k, end] (6, 6) <- G[k, end] blockdiag(R^T, R^T) at the end of each side k of element el
    that is its mesh edge's node b, R = Rk[edge]: the edge twist log(g_a^-1 g_b R) across a cross
    field's cut (``fem.element_default``, "Cuts"); Rk empty (0, 3, 3): nothing done."""
    if Rk.shape[0] == 0:
        return
    for k in range(4):
        e = elem_edges[el, k]
        M = G[k, 1] if sgn[el, k] > 0 else G[k, 0]
        _times_turn_T(M, 0, 6, 0, Rk[e])
        _times_turn_T(M, 0, 6, 3, Rk[e])


@njit(cache=True)
def match_edge(e, Rk, rE, H):
    """Node b's force rE[e, 1] <- blockdiag(R, R) rE[e, 1] and, with H (12, 12), b's rows and
    columns of the edge block turned likewise (R = Rk[e]: ``match_G``); Rk empty: nothing done."""
    if Rk.shape[0] == 0:
        return
    R = Rk[e]
    r = rE[e, 1]
    for o in range(0, 6, 3):
        a0, a1, a2 = r[o], r[o + 1], r[o + 2]
        for i in range(3):
            r[o + i] = R[i, 0] * a0 + R[i, 1] * a1 + R[i, 2] * a2
    if H is not None:
        _turn_times(H, 6, 0, 12, R)
        _turn_times(H, 9, 0, 12, R)
        _times_turn_T(H, 0, 12, 6, R)
        _times_turn_T(H, 0, 12, 9, R)


@njit(cache=True)
def rotate_G(G, nodes, Rq):
    """G[k, e] (6, 6) <- G[k, e] blockdiag(R^T, R^T), R = Rq[nodes[_LOCAL_EDGES[k, e]]]: the
    element's dz/deta~ (increments of its frames, eta~ = Ad_{Q^-1} eta) as dz/deta of the user's
    frames, so that G^T Dbar G is the user's material block (``rotate_blocks`` on it would cost
    four times as much: 64 3x3 block products against 8 6x6 x 3x3); Rq empty: nothing done."""
    if Rq.shape[0] == 0:
        return
    for k in range(4):
        for e in range(2):
            R = Rq[nodes[_LOCAL_EDGES[k, e]]]
            B = G[k, e]
            for i in range(6):
                for c in (0, 3):
                    x, y, z = B[i, c], B[i, c + 1], B[i, c + 2]
                    for j in range(3):
                        B[i, c + j] = x * R[j, 0] + y * R[j, 1] + z * R[j, 2]


@njit(cache=True)
def rotate_wrench(r, nd, Rq):
    """r[nd] (6,) <- (R r_v, R r_w), R = Rq[nd]: a nodal force of the element's frames in the
    user's (Rq empty: nothing done)."""
    if Rq.shape[0] == 0:
        return
    R = Rq[nd]
    for k in (0, 3):
        x, y, z = r[nd, k], r[nd, k + 1], r[nd, k + 2]
        for i in range(3):
            r[nd, k + i] = R[i, 0] * x + R[i, 1] * y + R[i, 2] * z


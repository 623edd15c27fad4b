"""Compiled loads (numba): each adds its generalised nodal forces into ``f`` (n, 6) and, with
``tangent``, its blocks -df/deta into the CSR ``data`` through the pattern's map, as the
NumPy loads of ``core_se3.model`` do (same equations: model/loads.py, model/magnetics.py,
model/supports.py).  The load-factor scale s = scale(lam) is evaluated in Python.

Nodal loads run serially (repeated nodes add up, as np.add.at; they cost < 5 % of the element at
10^4 nodes); the follower pressure, the only load with element blocks, also has a parallel
driver over the mesh colouring (race-free).
"""
from __future__ import annotations

from math import sqrt

import numpy as np
from numba import njit, prange

from .csr import scatter, scatter_diag
from .element_ops import CHUNK
from .lie import coef_c, coef_dc, cross3, ddw_add, hat_add, log_so3, outer_add

MAX_TOTAL_ROTATION = 0.95 * np.pi   # model.supports.RotationComponentSpring's limit

__all__ = ["nodal_load", "surface_load_dead", "surface_load_follower", "surface_load_follower_par",
           "magnetic_load", "dipole_field", "lab_spring", "lab_tilt_spring", "rotation_component_spring",
           "MAX_TOTAL_ROTATION"]

# ------------------------------------------------------------------------------------------
# Loads: generalised forces f (added into f_out (n,6)) and -df/deta (added into data)
# ------------------------------------------------------------------------------------------
# Every load kernel takes the load factor's scale s = scale(lam) (evaluated in Python) and adds
# its force into ``f`` (n, 6) and, if ``tangent``, its blocks into the CSR ``data`` through the
# same map as the element.  Nodal loads run serially (repeated nodes add up, as np.add.at; they
# cost < 5% of the element at 10^4 nodes, and a serial kernel compiles in a fraction of the
# time of a parallel one); the follower pressure, the only load with element blocks and
# ~1/10 of the element's work, also has a parallel driver over the mesh colouring (race-free).

@njit(cache=True)
def _zero6(K6):
    for i in range(6):
        for j in range(6):
            K6[i, j] = 0.0


@njit(cache=True)
def _RtX(g, nd, x0, x1, x2):
    """R^T x for node nd's rotation."""
    return (g[nd, 0, 0] * x0 + g[nd, 1, 0] * x1 + g[nd, 2, 0] * x2,
            g[nd, 0, 1] * x0 + g[nd, 1, 1] * x1 + g[nd, 2, 1] * x2,
            g[nd, 0, 2] * x0 + g[nd, 1, 2] * x1 + g[nd, 2, 2] * x2)


@njit(cache=True)
def _add_dead(f, nd, F0, F1, F2, M0, M1, M2, data, cmap, K6, tangent):
    """f_nd += (F, M) (body-frame components of a dead lab wrench) and, with the tangent, the
    load stiffness -df/deta = [[0, -hat(F)], [0, -hat(M)]] on the node's diagonal block."""
    f[nd, 0] += F0
    f[nd, 1] += F1
    f[nd, 2] += F2
    f[nd, 3] += M0
    f[nd, 4] += M1
    f[nd, 5] += M2
    if tangent:
        _zero6(K6)
        hat_add(K6, 0, 3, F0, F1, F2, -1.0)
        hat_add(K6, 3, 3, M0, M1, M2, -1.0)
        scatter_diag(data, cmap, nd, K6, 1.0)


@njit(cache=True)
def nodal_load(g, nodes, weights, force, moment, s, follower, f, data, cmap, tangent):
    """NodalLoad.  Dead (lab F, M): f_i += w_i s (R_i^T F, R_i^T M), block
    -df/deta = [[0, -hat(R^T F)], [0, -hat(R^T M)]] (weighted); follower: f_i += w_i s (F, M),
    no stiffness.  nodes (k,), weights (k,), force (3,), moment (3,)."""
    K6 = np.empty((6, 6))
    for t in range(nodes.size):
        nd = nodes[t]
        w = weights[t] * s
        if follower:
            for i in range(3):
                f[nd, i] += w * force[i]
                f[nd, 3 + i] += w * moment[i]
            continue
        F0, F1, F2 = _RtX(g, nd, force[0], force[1], force[2])
        M0, M1, M2 = _RtX(g, nd, moment[0], moment[1], moment[2])
        F0, F1, F2, M0, M1, M2 = w * F0, w * F1, w * F2, w * M0, w * M1, w * M2
        _add_dead(f, nd, F0, F1, F2, M0, M1, M2, data, cmap, K6, tangent)


@njit(cache=True)
def surface_load_dead(g, quads, elements, cptr, order, node_w, q, s, f, data, cmap, tangent):
    """SurfaceLoad, dead: lab force s node_w[e, a] q at corner a of element e (node_w =
    int N_a dA, reference area), f_a += R_a^T F, block [:3, 3:] = -hat(R_a^T F).
    elements (k,): the loaded elements, node_w (k,4); cptr, order: positions into elements
    grouped by colour (Pattern.group_elements)."""
    K6 = np.empty((6, 6))
    for col in range(len(cptr) - 1):
        lo, hi = cptr[col], cptr[col + 1]
        for t in range(lo, hi):
            pos = order[t]
            el = elements[pos]
            for a in range(4):
                nd = quads[el, a]
                w = s * node_w[pos, a]
                F0, F1, F2 = _RtX(g, nd, w * q[0], w * q[1], w * q[2])
                _add_dead(f, nd, F0, F1, F2, 0.0, 0.0, 0.0, data, cmap, K6, tangent)


# bilinear shape functions at the 2x2 Gauss points (loads.shape_functions, GAUSS_2x2 order)
_GP = 1.0 / np.sqrt(3.0)
_GPTS = np.array([[-_GP, -_GP], [_GP, -_GP], [_GP, _GP], [-_GP, _GP]])
_XS = np.array([-1.0, 1.0, 1.0, -1.0])
_YS = np.array([-1.0, -1.0, 1.0, 1.0])
_NQ = 0.25 * (1 + _GPTS[:, :1] * _XS) * (1 + _GPTS[:, 1:] * _YS)                      # (q, 4)
_DNQ = np.stack([0.25 * _XS * (1 + _GPTS[:, 1:] * _YS), 0.25 * _YS * (1 + _GPTS[:, :1] * _XS)], 1)  # (q,2,4)


@njit(cache=True)
def _follower_element(g, quads, el, p, f, data, cmap, tangent, a, nrm, dF, K6, T, C, turned, U):
    """One element of the follower pressure (see surface_load_follower); C (4, 3, 3) its
    corners' constant body-frame turns where ``turned`` (a curved element), U (3, 6) a workspace."""
    for qq in range(4):
        for k in range(2):
            for c in range(3):
                acc = 0.0
                x0 = g[quads[el, 0], c, 3]        # relative to the first corner (exact differences)
                for j in range(4):
                    acc += _DNQ[qq, k, j] * (g[quads[el, j], c, 3] - x0)
                a[qq, k, c] = acc
        n0, n1, n2 = cross3(a[qq, 0, 0], a[qq, 0, 1], a[qq, 0, 2], a[qq, 1, 0], a[qq, 1, 1], a[qq, 1, 2])
        nrm[qq, 0], nrm[qq, 1], nrm[qq, 2] = n0, n1, n2
    for i in range(4):
        ni = quads[el, i]
        F0 = F1 = F2 = 0.0
        for qq in range(4):
            F0 += _NQ[qq, i] * nrm[qq, 0]
            F1 += _NQ[qq, i] * nrm[qq, 1]
            F2 += _NQ[qq, i] * nrm[qq, 2]
        B0, B1, B2 = _RtX(g, ni, p * F0, p * F1, p * F2)
        if turned:
            f[ni, 0] += C[i, 0, 0] * B0 + C[i, 0, 1] * B1 + C[i, 0, 2] * B2
            f[ni, 1] += C[i, 1, 0] * B0 + C[i, 1, 1] * B1 + C[i, 1, 2] * B2
            f[ni, 2] += C[i, 2, 0] * B0 + C[i, 2, 1] * B1 + C[i, 2, 2] * B2
            if not tangent:
                continue
        else:
            f[ni, 0] += B0
            f[ni, 1] += B1
            f[ni, 2] += B2
            if not tangent:
                continue
        for j in range(4):
            nj = quads[el, j]
            dF[:, :] = 0.0
            for qq in range(4):
                cx = -p * _NQ[qq, i] * _DNQ[qq, 0, j]
                cy = p * _NQ[qq, i] * _DNQ[qq, 1, j]
                hat_add(dF, 0, 0, a[qq, 1, 0], a[qq, 1, 1], a[qq, 1, 2], cx)
                hat_add(dF, 0, 0, a[qq, 0, 0], a[qq, 0, 1], a[qq, 0, 2], cy)
            # T = dF R_j, K6[:3,:3] = -R_i^T T
            for r in range(3):
                for c in range(3):
                    T[r, c] = dF[r, 0] * g[nj, 0, c] + dF[r, 1] * g[nj, 1, c] + dF[r, 2] * g[nj, 2, c]
            _zero6(K6)
            for r in range(3):
                for c in range(3):
                    K6[r, c] = -(g[ni, 0, r] * T[0, c] + g[ni, 1, r] * T[1, c] + g[ni, 2, r] * T[2, c])
            if i == j:
                hat_add(K6, 0, 3, B0, B1, B2, -1.0)
            if turned:                               # the force rows turned: C_i K6[:3, :]
                for r in range(3):
                    for c in range(6):
                        U[r, c] = C[i, r, 0] * K6[0, c] + C[i, r, 1] * K6[1, c] + C[i, r, 2] * K6[2, c]
                K6[:3, :] = U
            scatter(data, cmap, cmap.elem_blk[el, i, j], ni, nj, K6, 0, 0, False, 1.0)


@njit(cache=True)
def surface_load_follower(g, quads, elements, cptr, order, p, turns, turned, f, data, cmap, tangent):
    """SurfaceLoad, follower pressure p (already scaled) per current area along a_1 x a_2:
    with a_k = sum_j dN_j/dxi_k phi_j at the Gauss points, F_i = p sum_q N_i a_1 x a_2 (lab),
    f_i += R_i^T F_i;  -df/deta:  block (i,i)[:3,3:] = -hat(R_i^T F_i) and
    block (i,j)[:3,:3] = -R_i^T dF_ij R_j,  dF_ij = p sum_q N_i (-dN_j/dx hat(a_2) + dN_j/dy hat(a_1)).
    Where ``turned``, the force of corner i of the t-th loaded element and its block rows are turned
    by the constant turns[t, i] (3, 3) (SurfaceLoad.turns: curved elements' area and normal).
    Serial; ``surface_load_follower_par`` runs the colours in parallel (same arguments)."""
    a = np.empty((4, 2, 3))
    nrm = np.empty((4, 3))
    dF = np.empty((3, 3))
    K6 = np.empty((6, 6))
    T = np.empty((3, 3))
    U = np.empty((3, 6))
    for t in range(elements.size):
        _follower_element(g, quads, elements[t], p, f, data, cmap, tangent, a, nrm, dF, K6, T,
                          turns[t if turned else 0], turned, U)


@njit(cache=True, parallel=True)
def surface_load_follower_par(g, quads, elements, cptr, order, p, turns, turned, f, data, cmap, tangent):
    """``surface_load_follower`` in parallel within each colour (chunks of CHUNK elements)."""
    for col in range(len(cptr) - 1):
        lo, hi = cptr[col], cptr[col + 1]
        nch = (hi - lo + CHUNK - 1) // CHUNK
        for ch in prange(nch):
            a = np.empty((4, 2, 3))
            nrm = np.empty((4, 3))
            dF = np.empty((3, 3))
            K6 = np.empty((6, 6))
            T = np.empty((3, 3))
            U = np.empty((3, 6))
            for t in range(lo + ch * CHUNK, min(hi, lo + (ch + 1) * CHUNK)):
                pos = order[t]
                _follower_element(g, quads, elements[pos], p, f, data, cmap, tangent, a, nrm, dF, K6, T,
                                  turns[pos if turned else 0], turned, U)


@njit(cache=True)
def magnetic_load(g, nodes, mu, B, Gr, H, uniform, f, data, cmap, tangent):
    """MagneticLoad on the magnetised nodes (a node listed twice, by two loads of
    ``model.magnetics.compiled_magnets``, receives both): mu (k,3) body dipoles, lab field
    B (k,3), gradient Gr (k,3,3) and Hessian H (k,3,3,3) at the nodes (ignored if uniform).
    With a = R^T B, A = R^T G R:  f_w = mu x a,  f_v = A mu;  -df/deta:
      [3:,3:] = -hat(mu) hat(a),  [3:,:3] = -hat(mu) A,  [:3,3:] = -(hat(A mu) - A hat(mu)),
      [:3,:3] = -R^T Hm R,  Hm_al = sum_b H_abl (R mu)_b   (magnetics.py, seed E50/E80)."""
    K6 = np.empty((6, 6))
    A = np.empty((3, 3))
    Mh = np.empty((3, 3))
    for t in range(nodes.size):
        nd = nodes[t]
        K6[:, :] = 0.0
        Mh[:, :] = 0.0
        m0, m1, m2 = mu[t, 0], mu[t, 1], mu[t, 2]
        a0, a1, a2 = _RtX(g, nd, B[t, 0], B[t, 1], B[t, 2])
        c0, c1, c2 = cross3(m0, m1, m2, a0, a1, a2)
        f[nd, 3] += c0
        f[nd, 4] += c1
        f[nd, 5] += c2
        hat_add(Mh, 0, 0, m0, m1, m2, 1.0)
        if tangent:
            # -hat(mu) hat(a) = -(a mu^T - (mu.a) I)
            ma = m0 * a0 + m1 * a1 + m2 * a2
            outer_add(K6, 3, 3, a0, a1, a2, m0, m1, m2, -1.0)
            K6[3, 3] += ma
            K6[4, 4] += ma
            K6[5, 5] += ma
        if not uniform:
            for i in range(3):
                for j in range(3):
                    acc = 0.0
                    for k in range(3):
                        for l in range(3):
                            acc += g[nd, k, i] * Gr[t, k, l] * g[nd, l, j]
                    A[i, j] = acc
            F0 = A[0, 0] * m0 + A[0, 1] * m1 + A[0, 2] * m2
            F1 = A[1, 0] * m0 + A[1, 1] * m1 + A[1, 2] * m2
            F2 = A[2, 0] * m0 + A[2, 1] * m1 + A[2, 2] * m2
            f[nd, 0] += F0
            f[nd, 1] += F1
            f[nd, 2] += F2
            if tangent:
                for i in range(3):
                    for j in range(3):
                        hA = 0.0
                        Ah = 0.0
                        for k in range(3):
                            hA += Mh[i, k] * A[k, j]
                            Ah += A[i, k] * Mh[k, j]
                        K6[3 + i, j] = -hA
                        K6[i, 3 + j] = Ah
                hat_add(K6, 0, 3, F0, F1, F2, -1.0)
                # R mu (lab), Hm = H . (R mu), K[:3,:3] = -R^T Hm R
                r0 = g[nd, 0, 0] * m0 + g[nd, 0, 1] * m1 + g[nd, 0, 2] * m2
                r1 = g[nd, 1, 0] * m0 + g[nd, 1, 1] * m1 + g[nd, 1, 2] * m2
                r2 = g[nd, 2, 0] * m0 + g[nd, 2, 1] * m1 + g[nd, 2, 2] * m2
                for i in range(3):
                    for j in range(3):
                        A[i, j] = H[t, i, 0, j] * r0 + H[t, i, 1, j] * r1 + H[t, i, 2, j] * r2
                for i in range(3):
                    for j in range(3):
                        acc = 0.0
                        for k in range(3):
                            for l in range(3):
                                acc += g[nd, k, i] * A[k, l] * g[nd, l, j]
                        K6[i, j] = -acc
        if tangent:
            scatter_diag(data, cmap, nd, K6, 1.0)


@njit(cache=True)
def dipole_field(x, m, x0, k, s, B, Gr, H):
    """Point dipole (fields.DipoleField) at lab points x (p,3): with r = x - x0, rm = r.m,
      B_i = s k (3 r_i rm / r^5 - m_i / r^3),
      G_il = s k [3 (d_il rm + r_i m_l + m_i r_l) / r^5 - 15 r_i r_l rm / r^7],
      H_ilj = dG_il/dx_j = s k [3 (d_il m_j + d_ij m_l + m_i d_lj) / r^5
              - 15 ((d_il rm + r_i m_l + m_i r_l) r_j + d_ij r_l rm + r_i d_lj rm + r_i r_l m_j) / r^7
              + 105 r_i r_l r_j rm / r^9]   (analytic; fields.py takes it by complex step).
    Returns 1 if a point is on the dipole (singular), else 0."""
    bad = 0
    r = np.empty(3)
    for p in range(x.shape[0]):
        for i in range(3):
            r[i] = x[p, i] - x0[i]
        r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2]
        if r2 == 0.0:
            bad = 1
            continue
        rm = r[0] * m[0] + r[1] * m[1] + r[2] * m[2]
        i5 = s * k / r2 ** 2.5
        i7 = s * k / r2 ** 3.5
        i9 = s * k / r2 ** 4.5
        for i in range(3):
            B[p, i] = 3.0 * r[i] * rm * i5 - m[i] * s * k / r2 ** 1.5
            for l in range(3):
                dil = 1.0 if i == l else 0.0
                Gr[p, i, l] = 3.0 * (dil * rm + r[i] * m[l] + m[i] * r[l]) * i5 - 15.0 * r[i] * r[l] * rm * i7
                for j in range(3):
                    dij = 1.0 if i == j else 0.0
                    dlj = 1.0 if l == j else 0.0
                    H[p, i, l, j] = (3.0 * (dil * m[j] + dij * m[l] + m[i] * dlj) * i5
                                     - 15.0 * ((dil * rm + r[i] * m[l] + m[i] * r[l]) * r[j]
                                               + dij * r[l] * rm + r[i] * dlj * rm + r[i] * r[l] * m[j]) * i7
                                     + 105.0 * r[i] * r[l] * r[j] * rm * i9)
    return bad


@njit(cache=True)
def lab_spring(g, nodes, P, X0, k, f, data, cmap, tangent):
    """LabSpring: F = -k P (phi - X0) (lab), f_v += R^T F;
    -df/deta = [[k R^T P R, -hat(R^T F)], [0, 0]].  P (q,3,3), X0 (q,3)."""
    K6 = np.empty((6, 6))
    for t in range(nodes.size):
        nd = nodes[t]
        d0 = g[nd, 0, 3] - X0[t, 0]
        d1 = g[nd, 1, 3] - X0[t, 1]
        d2 = g[nd, 2, 3] - X0[t, 2]
        L0 = -k * (P[t, 0, 0] * d0 + P[t, 0, 1] * d1 + P[t, 0, 2] * d2)
        L1 = -k * (P[t, 1, 0] * d0 + P[t, 1, 1] * d1 + P[t, 1, 2] * d2)
        L2 = -k * (P[t, 2, 0] * d0 + P[t, 2, 1] * d1 + P[t, 2, 2] * d2)
        F0, F1, F2 = _RtX(g, nd, L0, L1, L2)
        f[nd, 0] += F0
        f[nd, 1] += F1
        f[nd, 2] += F2
        if tangent:
            _zero6(K6)
            for i in range(3):
                for j in range(3):
                    acc = 0.0
                    for a in range(3):
                        for b in range(3):
                            acc += g[nd, a, i] * P[t, a, b] * g[nd, b, j]
                    K6[i, j] = k * acc
            hat_add(K6, 0, 3, F0, F1, F2, -1.0)
            scatter_diag(data, cmap, nd, K6, 1.0)


@njit(cache=True)
def lab_tilt_spring(g, nodes, tdir, k, f, data, cmap, tangent):
    """LabTiltSpring: a = R^T t, c = a_3, b = e3 x a, m = -k c b;
    -dm/domega = k (b b^T + c (a e3^T - c I)).  tdir (q,3)."""
    K6 = np.empty((6, 6))
    for t in range(nodes.size):
        nd = nodes[t]
        a0, a1, a2 = _RtX(g, nd, tdir[t, 0], tdir[t, 1], tdir[t, 2])
        c = a2
        b0, b1, b2 = -a1, a0, 0.0
        f[nd, 3] += -k * c * b0
        f[nd, 4] += -k * c * b1
        f[nd, 5] += -k * c * b2
        if tangent:
            _zero6(K6)
            outer_add(K6, 3, 3, b0, b1, b2, b0, b1, b2, k)
            outer_add(K6, 3, 3, a0, a1, a2, 0.0, 0.0, 1.0, k * c)
            K6[3, 3] -= k * c * c
            K6[4, 4] -= k * c * c
            K6[5, 5] -= k * c * c
            scatter_diag(data, cmap, nd, K6, 1.0)


@njit(cache=True)
def rotation_component_spring(g, nodes, R0, b, k, f, data, cmap, tangent):
    """RotationComponentSpring: phi = log(R0^T R), c = b.phi, gv = J_r^-T(phi) b
    = b - phi x b/2 + c(t) phi x (phi x b);  m = -k c gv,
    -dm/deta = k [gv gv^T + c D J_r^-1(phi)],  D = d gv/d phi
    = hat(b)/2 + (phi x phi x b)(dc phi)^T + c(t) [(phi.b) I + phi b^T - 2 b phi^T].
    Returns (flag, t): flag 1 if |phi| > MAX_TOTAL_ROTATION at nodes[t] (nothing added then)."""
    Rl = np.empty((3, 3))
    phi = np.empty(3)
    D = np.zeros((3, 3))
    Ji = np.empty((3, 3))
    K6 = np.empty((6, 6))
    # check first (the reference raises before adding anything)
    worst, wt = -1.0, -1
    for t in range(nodes.size):
        nd = nodes[t]
        for i in range(3):
            for j in range(3):
                Rl[i, j] = R0[t, 0, i] * g[nd, 0, j] + R0[t, 1, i] * g[nd, 1, j] + R0[t, 2, i] * g[nd, 2, j]
        log_so3(Rl, phi)
        tn = sqrt(phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2])
        if tn > worst:
            worst, wt = tn, t
    if worst > MAX_TOTAL_ROTATION:
        return 1, wt
    for t in range(nodes.size):
        nd = nodes[t]
        for i in range(3):
            for j in range(3):
                Rl[i, j] = R0[t, 0, i] * g[nd, 0, j] + R0[t, 1, i] * g[nd, 1, j] + R0[t, 2, i] * g[nd, 2, j]
        log_so3(Rl, phi)
        p0, p1, p2 = phi[0], phi[1], phi[2]
        s = p0 * p0 + p1 * p1 + p2 * p2
        cc = coef_c(s)
        dc = coef_dc(s)
        b0, b1, b2 = b[t, 0], b[t, 1], b[t, 2]
        cval = b0 * p0 + b1 * p1 + b2 * p2
        x0, x1, x2 = cross3(p0, p1, p2, b0, b1, b2)
        y0, y1, y2 = cross3(p0, p1, p2, x0, x1, x2)
        g0, g1, g2 = b0 - 0.5 * x0 + cc * y0, b1 - 0.5 * x1 + cc * y1, b2 - 0.5 * x2 + cc * y2
        f[nd, 3] += -k * cval * g0
        f[nd, 4] += -k * cval * g1
        f[nd, 5] += -k * cval * g2
        if tangent:
            # J_r^-1(phi) = I + hat(phi)/2 + c hat(phi)^2
            for i in range(3):
                pi_ = p0 if i == 0 else p1 if i == 1 else p2
                for j in range(3):
                    pj = p0 if j == 0 else p1 if j == 1 else p2
                    Ji[i, j] = (1.0 if i == j else 0.0) + cc * (pi_ * pj - (s if i == j else 0.0))
                    D[i, j] = 0.0
            hat_add(Ji, 0, 0, p0, p1, p2, 0.5)
            hat_add(D, 0, 0, b0, b1, b2, 0.5)
            outer_add(D, 0, 0, y0, y1, y2, p0, p1, p2, dc)
            ddw_add(D, 0, 0, p0, p1, p2, b0, b1, b2, cc)
            _zero6(K6)
            for i in range(3):
                gi = g0 if i == 0 else g1 if i == 1 else g2
                for j in range(3):
                    gj = g0 if j == 0 else g1 if j == 1 else g2
                    acc = 0.0
                    for l in range(3):
                        acc += D[i, l] * Ji[l, j]
                    K6[3 + i, 3 + j] = k * (gi * gj + cval * acc)
            scatter_diag(data, cmap, nd, K6, 1.0)
    return 0, -1

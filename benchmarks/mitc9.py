"""A linear curved MITC9 shell (Bucalem and Bathe 1993), a benchmark prototype for
``peer_sweeps.py``: what a genuine 9-node MITC element does on issue 30's sweeps.

OpenSees' "ShellMITC9" is a flat 9-node element (one plane per element through its corners, all
nodes projected onto it) with full 3x3 integration of untied strains (its source, and the
clamped plate in ``peer_sweeps.py``); it says nothing about the curved MITC9.  This is the
degenerated-continuum element of Bucalem, M.L. and Bathe, K.J. (1993) "Higher-order MITC
general shell elements", IJNME 36, 3729-3754, as we read it, linear:

* geometry x(r, s, t) = sum_i N_i (X_i + t h/2 V3_i) with the 9 Lagrange functions N_i and the
  exact nodal normals V3_i = d3 of core_se3's frames (d1, d2, d3 = V1, V2, V3);
* five dofs per node: the translations (in the nodal frame d1, d2, d3, so that core_se3's
  supports apply as they are) and the rotations alpha, beta about V1, V2; displacement
  u = sum_i N_i (u_i + t h/2 (-alpha_i V2_i + beta_i V1_i));
* covariant strains e_rr, e_ss, e_rs, e_rt, e_st (e_tt = 0, plane stress) tied (MITC9): e_rr and
  e_rt at (+-a, {-b, 0, b}), interpolated linearly in r and quadratically in s; e_ss and e_st at
  ({-b, 0, b}, +-a), the other way round; e_rs at (+-a, +-a), bilinear; a = 1/sqrt 3,
  b = sqrt(3/5);
* the strains in a local orthonormal frame at each integration point (e3 along g_r x g_s),
  isotropic plane stress, transverse shear G with the factor 5/6; 3x3 Gauss points in the
  surface, 2 through the thickness.

Not product code: one NumPy pass over the elements per integration point; checked by the patch
tests and the standard cases that ``peer_sweeps.py`` runs.
"""
from __future__ import annotations

import types

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

A_ = 1.0 / np.sqrt(3.0)
B_ = np.sqrt(3.0 / 5.0)
_IJ = [(0, 0), (2, 0), (2, 2), (0, 2), (1, 0), (2, 1), (1, 2), (0, 1), (1, 1)]   # (r, s) index of nodes


def _lag(x):
    return np.array([x * (x - 1) / 2, 1 - x * x, x * (x + 1) / 2]), np.array([x - 0.5, -2 * x, x + 0.5])


def shape(r, s):
    """N (9,), dN/dr, dN/ds (9,) in the corners-mid-sides-centre order (``peer_sweeps.quad9``)."""
    (lr, dlr), (ls, dls) = _lag(r), _lag(s)
    N = np.array([lr[a] * ls[b] for a, b in _IJ])
    return N, np.array([dlr[a] * ls[b] for a, b in _IJ]), np.array([lr[a] * dls[b] for a, b in _IJ])


def covariant_B(Xe, V, h, r, s, t):
    """Covariant strain operators at (r, s, t) for all elements: B (E, 5, 45) of (e_rr, e_ss,
    e_rs, e_rt, e_st) on the dofs (u lab x3, alpha, beta) per node, and the base vectors
    G (E, 3, 3) (columns g_r, g_s, g_t).  Xe (E, 9, 3), V (E, 9, 3, 3) nodal frames (columns
    V1, V2, V3)."""
    N, Nr, Ns = shape(r, s)
    V1, V2, V3 = V[..., 0], V[..., 1], V[..., 2]
    g_r = np.einsum("i,eij->ej", Nr, Xe + t * h / 2 * V3)
    g_s = np.einsum("i,eij->ej", Ns, Xe + t * h / 2 * V3)
    g_t = h / 2 * np.einsum("i,eij->ej", N, V3)
    E = len(Xe)
    # du/dq = sum_i [dN_i/dq u_i + d(t N_i)/dq h/2 (-alpha V2 + beta V1)], q = r, s, t
    def du(dN, dtN):
        D = np.zeros((E, 3, 9, 5))
        D[:, :, :, :3] = dN[None, None, :, None] * np.eye(3)[None, :, None, :]
        D[:, :, :, 3] = -(h / 2) * dtN[None, None, :] * V2.transpose(0, 2, 1)
        D[:, :, :, 4] = (h / 2) * dtN[None, None, :] * V1.transpose(0, 2, 1)
        return D.reshape(E, 3, 45)
    Dr, Ds, Dt = du(Nr, t * Nr), du(Ns, t * Ns), du(np.zeros(9), N)
    dot = lambda g, D: np.einsum("ej,ejk->ek", g, D)
    B = np.stack([dot(g_r, Dr), dot(g_s, Ds), (dot(g_r, Ds) + dot(g_s, Dr)) / 2,
                  (dot(g_r, Dt) + dot(g_t, Dr)) / 2, (dot(g_s, Dt) + dot(g_t, Ds)) / 2], 1)
    return B, np.stack([g_r, g_s, g_t], -1)


def tied_B(Xe, V, h, r, s, t):
    """The MITC9 assumed covariant strains at (r, s, t): B (E, 5, 45), and G there."""
    B, G = covariant_B(Xe, V, h, r, s, t)
    lin = lambda x: np.array([(1 - x / A_) / 2, (1 + x / A_) / 2])                 # through -a, a
    quad = lambda x: np.array([x * (x - B_) / (2 * B_ * B_), 1 - x * x / (B_ * B_), x * (x + B_) / (2 * B_ * B_)])
    out = np.zeros_like(B)
    for (i, j) in ((0, 3), (1, 4)):                                               # (e_rr, e_rt), (e_ss, e_st)
        for ka, pa in enumerate((-A_, A_)):
            for kb, pb in enumerate((-B_, 0.0, B_)):
                rr, ss = (pa, pb) if i == 0 else (pb, pa)
                w = lin(r)[ka] * quad(s)[kb] if i == 0 else lin(s)[ka] * quad(r)[kb]
                Bk = covariant_B(Xe, V, h, rr, ss, t)[0]
                out[:, [i, j]] += w * Bk[:, [i, j]]
    for ka, pa in enumerate((-A_, A_)):
        for kb, pb in enumerate((-A_, A_)):
            out[:, 2] += lin(r)[ka] * lin(s)[kb] * covariant_B(Xe, V, h, pa, pb, t)[0][:, 2]
    return out, G


def _local(G):
    """(E, 5, 5): covariant (e_rr, e_ss, e_rs, e_rt, e_st) -> local (e11, e22, g12, g13, g23)."""
    e3 = np.cross(G[..., 0], G[..., 1])
    e3 /= np.linalg.norm(e3, axis=-1, keepdims=True)
    e1 = G[..., 0] / np.linalg.norm(G[..., 0], axis=-1, keepdims=True)
    e2 = np.cross(e3, e1)
    C = np.einsum("eik,eak->eia", np.linalg.inv(G), np.stack([e1, e2, e3], 1))   # g^i . e_a (rows of G^-1: g^i)
    pairs = [(0, 0), (1, 1), (0, 1), (0, 2), (1, 2)]                           # (a, b) of the outputs
    comps = [(0, 0), (1, 1), (0, 1), (0, 2), (1, 2)]                           # (i, j) of the inputs
    T = np.zeros((len(G), 5, 5))
    for o, (a, b) in enumerate(pairs):
        f = 1.0 if a == b else 2.0                                              # engineering shears
        for k, (i, j) in enumerate(comps):
            m = C[:, i, a] * C[:, j, b] + (C[:, j, a] * C[:, i, b] if i != j else 0.0)
            T[:, o, k] = f * m
    return T


def element_stiffness(Xe, V, E, nu, h, k_shear=5.0 / 6.0, tied=True):
    """(nE, 45, 45) stiffness of the MITC9 elements (dofs per node: u lab x3, alpha, beta);
    ``tied`` False: the displacement-based 9-node element (no tying), for comparison."""
    D = np.zeros((5, 5))
    D[:2, :2] = E / (1 - nu * nu) * np.array([[1, nu], [nu, 1]])
    D[2, 2] = E / (2 * (1 + nu))
    D[3, 3] = D[4, 4] = k_shear * E / (2 * (1 + nu))
    g, w = np.polynomial.legendre.leggauss(3)
    gt, wt = np.polynomial.legendre.leggauss(2)
    K = np.zeros((len(Xe), 45, 45))
    for r, wr in zip(g, w):
        for s, ws in zip(g, w):
            for t, wtt in zip(gt, wt):
                B, G = (tied_B if tied else covariant_B)(Xe, V, h, r, s, t)
                Bl = np.einsum("eij,ejk->eik", _local(G), B)
                K += (wr * ws * wtt * np.linalg.det(G))[:, None, None] * np.einsum("eji,jk,ekl->eil", Bl, D, Bl)
    return K


def stiffness(X, R0, elems, E, nu, h, tied=True):
    """The global stiffness (5n x 5n, sparse) on the nodal-frame dofs (u in (d1, d2, d3), alpha,
    beta per node) of the 9-node elements ``elems`` on nodes X with frames R0 (n, 3, 3)."""
    elems = np.asarray(elems)
    Ke = element_stiffness(X[elems], R0[elems], E, nu, h, tied=tied)
    T = np.zeros((len(elems), 9, 5, 9, 5))                 # element dofs <- nodal-frame dofs
    for i in range(9):
        T[:, i, :3, i, :3] = R0[elems[:, i]]
    T[:, :, 3, :, 3] = T[:, :, 4, :, 4] = np.eye(9)
    T = T.reshape(len(elems), 45, 45)
    Ke = np.einsum("eji,ejk,ekl->eil", T, Ke, T)
    dof = (elems[:, :, None] * 5 + np.arange(5)).reshape(len(elems), 45)
    n = len(X)
    return sp.coo_matrix((Ke.ravel(), (np.repeat(dof, 45, 1).ravel(), np.tile(dof, (1, 45)).ravel())),
                         shape=(5 * n, 5 * n)).tocsc()


def solve_dofs(K, fixed, values, f):
    """x (n, 5) of K x = f with the dofs ``fixed`` (n, 5) held at ``values``."""
    free = ~fixed.ravel()
    x = np.where(fixed, values, 0.0).ravel()
    x[free] = spl.spsolve(K[free][:, free], (f.ravel() - K @ x)[free])
    return x.reshape(fixed.shape)


def solve(p, elems, force_lab=None, tied=True):
    """The linear MITC9 solution of core_se3's problem p on the 9-node elements ``elems``
    (supports: p's constraint mask in the nodal frames, the drilling dof dropped; loads: p's
    nodal forces and moments about d1, d2, or ``force_lab`` (n, 3) in their place): a
    Result-like object (steps[0].g, final.g) for the catalogue's measure functions."""
    g0 = p.mesh.g0
    R0 = g0[:, :3, :3]
    mat = p.material
    K = stiffness(p.mesh.X, R0, elems, mat.E, mat.nu, mat.h, tied)
    f_body = p.external(g0, 1.0, tangent=False)[0]
    f = np.zeros((len(g0), 5))
    f[:, :3] = f_body[:, :3] if force_lab is None else np.einsum("nji,nj->ni", R0, force_lab)
    f[:, 3:] = f_body[:, 3:5]
    x = solve_dofs(K, p.constraint_mask()[:, :5], np.zeros_like(f), f)
    g = g0.copy()
    g[:, :3, 3] += np.einsum("nij,nj->ni", R0, x[:, :3])
    return types.SimpleNamespace(steps=[types.SimpleNamespace(g=g0)], final=types.SimpleNamespace(g=g))

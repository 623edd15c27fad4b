"""Enhanced assumed membrane strains of the default element (Simo and Rifai 1990), condensed per
element: the in-plane bending of coarse and distorted quads (issue 30).

Why.  The tying of the default element (``element_default``) takes the membrane strain
e_ab = c_a . A_b from the edge twists: e_11 (from the bottom and top edges) varies along y only,
e_22 (left and right) along x only.  In-plane bending along x needs e_22 = -nu e_11 ~ y, which
the tying cannot hold (Poisson locking), and on a distorted quad the drilling rotations carry
the shear only in part: Cook's tapered panel at 2x2 gave 0.765 of its converged deflection
(Kratos' thick quad, whose membrane is enhanced, 0.787).

The enhancement.  At each 2x2 Gauss point q the membrane strain gets the enhanced field of
Simo and Rifai's Q1/E4, four modes in the natural coordinates (x, y) of the element centre,

    e~(x, y) = (j_c / j_q) Q_q M(x, y) Q_q^T,   M = [[x a1, x a3 + y a4], [x a3 + y a4, y a2]],
    Q_ab = A_a(q) . A^b(0)   (A_a(q) the tied tangents at q, A^b(0) the centre's dual basis),

i.e. the Cartesian tensor (j_c / j_q) M_cd A^c(0) A^d(0) in covariant components at q, carried
by c_a += e~_ab A^b(q).  Sum_q j0_q (j_c / j_q) M(x_q, y_q) = 0: the modes do no work against a
constant stress on a flat element, so the patch tests and every constant-strain state are kept
(their alpha is zero).  The modes vanish at the centre (the cell resultants, taken there, are
unchanged) and act on the membrane only (A^b(q) is tangent at q: no transverse shear, no
bending).  The mode amplitudes alpha (4 per element) are condensed exactly:

    Pi_e = min_alpha 1/2 sum_q j0_q (P_q dz + Gamma_q alpha)^T D_q (P_q dz + Gamma_q alpha)
         = 1/2 dz^T (Dbar - L^T H^-1 L) dz,   H = sum_q j0 Gamma^T D Gamma,  L = sum_q j0 Gamma^T D P_q,

so the element stays a quadratic form in the edge twists (dz = z - z0) with a constant Dbar:
objectivity, the consistent tangent, both backends and the kernels' split form (Gamma has
translational rows only; L's columns are those of the tying's membrane rows) are unchanged.
Measured (``benchmarks/results/obstacle_course.md``, linear): Cook 2x2 / 4x4 / 8x8 0.765 /
0.919 / 0.973 -> 0.834 / 0.947 / 0.983; the twisted beam's out-of-plane load 0.9745 -> 0.9774;
the pinched cylinder 8x8 0.803 -> 0.805; the roof (nu = 0) unchanged; the roof and hemisphere
thickness sweeps within 0.01 of before.

Reference: Simo, J.C. and Rifai, M.S. (1990) "A class of mixed assumed strain methods and the
method of incompatible modes", IJNME 29, 1595-1638 (the Q1/E4 modes and the j_c / j_q map).
"""
from __future__ import annotations

import numpy as np

from .material import strain_operators
from .quadrature import GAUSS_2x2

__all__ = ["enhanced_modes", "membrane_enhancement", "condensed_stiffness"]


def enhanced_modes(points=GAUSS_2x2):
    """M (q, 4, 2, 2): Simo and Rifai's four membrane modes at natural points (x, y): e_11 ~ x,
    e_22 ~ y, e_12 = e_21 ~ x, ~ y.

    Example
    -------
    >>> M = enhanced_modes()
    >>> M.shape, float(M.sum(0).max())                   # zero sum over the 2x2 Gauss points
    ((4, 4, 2, 2), 0.0)
    """
    pts = np.asarray(points, float)
    x, y = pts[:, 0], pts[:, 1]
    M = np.zeros((len(pts), 4, 2, 2))
    M[:, 0, 0, 0] = x
    M[:, 1, 1, 1] = y
    M[:, 2, 0, 1] = M[:, 2, 1, 0] = x
    M[:, 3, 0, 1] = M[:, 3, 1, 0] = y
    return M


def membrane_enhancement(z0, zeta0, j0):
    """Gamma (k, q, 12, 4): the enhanced strain twists of the four modes at the 2x2 Gauss points
    (translational rows only; module docstring).

    Parameters
    ----------
    z0 : (k, 24) array
        Reference edge twists (z_b, z_t, z_l, z_r); the centre's tangents are the means of
        opposite edges'.
    zeta0 : (k, q, 12) array
        Reference strain twists at the Gauss points (A_1 = zeta0[..., 0:3], A_2 = zeta0[..., 6:9]).
    j0 : (k, q) array
        Area elements there.

    Example
    -------
    On a unit square (A_1 = (1/2, 0, 0): natural coordinates span 2) the enhanced stretch of the
    first mode is e_11 = x a_1, carried by c_1 = x A^1 = (2 x, 0, 0):

    >>> import numpy as np
    >>> from core_se3.fem.element_default import tying_matrices
    >>> z0 = np.zeros((1, 24)); z0[:, [0, 6, 13, 19]] = 0.5
    >>> zeta0 = np.einsum("qij,mj->mqi", tying_matrices(), z0)
    >>> G = membrane_enhancement(z0, zeta0, np.full((1, 4), 0.25))
    >>> G[0, :, 0, 0].round(6).tolist()                  # 2 x at the 2x2 Gauss points
    [-1.154701, 1.154701, 1.154701, -1.154701]
    """
    A = np.stack([zeta0[..., 0:3], zeta0[..., 6:9]], -2)                     # (k, q, 2, 3)
    _, Ainv, _ = strain_operators(A[..., 0, :], A[..., 1, :])
    Acon = np.einsum("mqab,mqbi->mqai", Ainv, A)                             # A^a(q)
    A0 = 0.5 * np.stack([z0[:, 0:3] + z0[:, 6:9], z0[:, 12:15] + z0[:, 18:21]], 1)
    _, A0inv, jc = strain_operators(A0[:, 0], A0[:, 1])
    Q = np.einsum("mqai,mbc,mci->mqab", A, A0inv, A0)                        # A_a(q) . A^b(0)
    e = np.einsum("mqac,qkcd,mqbd->mqkab", Q, enhanced_modes(), Q) * (jc[:, None] / j0)[..., None, None, None]
    c = np.einsum("mqkab,mqbi->mqaik", e, Acon)                              # c_a = e_ab A^b
    Gam = np.zeros(j0.shape + (12, 4))
    Gam[:, :, 0:3] = c[:, :, 0]
    Gam[:, :, 6:9] = c[:, :, 1]
    return Gam


def condensed_stiffness(Dbar, Pm, Gam, Dj):
    """Dbar - L^T H^-1 L (k, 24, 24): the element stiffness with the enhanced modes Gam (k, q, 12,
    4) condensed (module docstring), from the tying matrices Pm (k, q, 12, 24) and the law's
    matrices times the area elements Dj = D j0 (k, q, 12, 12); symmetric to round-off (made
    exactly symmetric).

    Example
    -------
    A mode that a single strain component carries alone removes that component's energy.

    >>> import numpy as np
    >>> P = np.zeros((1, 1, 12, 24)); P[0, 0, 0, 0] = 1.0
    >>> Gam = np.zeros((1, 1, 12, 1)); Gam[0, 0, 0, 0] = 1.0
    >>> Dj = np.eye(12)[None, None]
    >>> float(condensed_stiffness(np.einsum("mqia,mqij,mqjb->mab", P, Dj, P), P, Gam, Dj)[0, 0, 0])
    0.0
    """
    DG = Dj @ Gam                                                           # (k, q, 12, 4)
    H = (np.swapaxes(Gam, -1, -2) @ DG).sum(1)
    L = (np.swapaxes(DG, -1, -2) @ Pm).sum(1)                               # (k, 4, 24)
    out = Dbar - np.swapaxes(L, 1, 2) @ np.linalg.solve(H, L)
    return 0.5 * (out + np.swapaxes(out, 1, 2))

"""The drilling rotations' share of the membrane strain of the default element, made blind to
constant membrane stress on any quad (the membrane and drilling patch tests, issue 30).

Why a constant membrane stress loads the drilling rotations.  The translational part of an
edge twist is, linearised about a flat reference (frames of the plane), z_v = (du - theta_m x
dX)/2 with theta_m = (theta_a + theta_b)/2 the edge's mean rotation: the edge's stretch and
turn relative to the mean rotation of its end frames (the Allman-type term that makes in-plane
bending exact on rectangles).  The tying zeta_1 = ((1 - y) z_b + (1 + y) z_t)/2 then carries
the drilling rotations into the membrane strain e_ab = c_a . A_b as

    c_1 += -((1 - y) theta_m,b n x dX_b + (1 + y) theta_m,t n x dX_t)/4     (zeta_2 alike).

Under a constant symmetric membrane stress N the work of a nodal drilling rotation is the
element integral of N : sym(A^a (x) c_a).  On a parallelogram (dX_b = dX_t, dX_l = dX_r) the
symmetric part of this strain integrates to zero over the element for every set of nodal
rotations (the part that turns the shear strain has zero mean), so the rotations are work-free;
on a general quad it does not: with d = dX_b - dX_t = dX_l - dX_r the work at node a is of
order N d |dX|, and a free interior drilling rotation takes it up (2.5 times the strain on
MacNeal and Harder's patch).  Holding the rotations passes the test: the translational part is
the conforming bilinear field.

The correction.  At every Gauss point the drilling rotations' symmetric membrane strain minus
its element mean is kept:

    c_a(q) <- c_a(q) - Ebar A_a(q),   Ebar = sum_q j0_q sym(A^a (x) c_a^theta)(q) / sum_q j0_q,

with c_a^theta the drilling part at the reference (the map of the nodal drilling rotations
through the reference dz/deta and the tying), written on the drilling components d_k of the edge
twists (the third rotational component, in the start node's frame) through the pseudo-inverse
of d = D theta (D the edge incidences; a uniform rotation has no symmetric strain).  The
correction is linear in the edge twists, so the element stays a quadratic form in z:

    zeta(q) = (P_q + dP_q) z,    Dbar = sum_q j0 (P_q + dP_q)^T D_q (P_q + dP_q),

and everything else (objectivity, the tangent, the kernels) is unchanged.  On parallelograms
dP = 0 (set exactly below a round-off bound), so rectangles and cylinder panels keep their
stiffness to the bit.  A state without drilling components of the edge twists (a roll-up, a
uniform stretch) sees no correction, so constant-strain states stay exact.  Linear only: at a
finite membrane strain eps the drilling rotations of a distorted patch still see a residual of
order eps times the uncorrected one (the deformed edge vectors enter the base term).
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..mesh import LOCAL_EDGES
from .material import strain_operators

__all__ = ["reference_G", "drilling_correction", "tying_correction", "ROUND_OFF"]

ROUND_OFF = 1e-12     # size of Ek (strain per radian) below which it is round-off (a parallelogram)


def reference_G(mesh, psi0, elements=slice(None)):
    """G0 (k, 24, 24): dz/deta of the elements ``elements`` (a slice) at the reference edge
    twists psi0 (E, 6) (the element's G = dz/deta, ``element_default``: rows the 24 edge-twist
    components, columns the four nodes' 6 dofs); psi0 (k, 4, 6) per element side instead (each
    oriented as its mesh edge): those of the element's own gauge across a cross field's cuts
    (``element_default``, "Cuts")."""
    ids = mesh.elem_edges[elements]
    pos = (mesh.elem_edge_sign[elements] > 0)[..., None, None]
    if psi0.ndim == 3:
        Lp, Lm = (L.reshape(ids.shape + (6, 6)) for L in lie.dexp_inv(psi0.reshape(-1, 6), both=True))
    else:
        Lp, Lm = lie.dexp_inv(psi0[np.unique(ids)], both=True)
        inv = np.searchsorted(np.unique(ids), ids)
        Lp, Lm = Lp[inv], Lm[inv]
    Lloc_p = np.where(pos, Lp, Lm)
    Lloc_m = np.where(pos, Lm, Lp)
    G = np.zeros((len(pos), 4, 6, 4, 6))
    for k, (la, lb) in enumerate(LOCAL_EDGES):
        G[:, k, :, la, :] = -0.5 * Lloc_m[:, k]
        G[:, k, :, lb, :] = 0.5 * Lloc_p[:, k]
    return G.reshape(len(pos), 24, 24)


def drilling_correction(P, z0, G0):
    """Ek (m, 3, 3, 4): the element-mean symmetric membrane strain Ebar per unit drilling
    component d_k of each local edge (module docstring), for elements with reference edge twists
    z0 (m, 24) and reference dz/deta G0 (m, 24, 24), at the points of the tying matrices P
    (q, 12, 24) (the Gauss points); zero for the elements where it is round-off (parallelograms).
    :func:`tying_correction` turns it into the correction dP of the tying matrices at any point.

    Example
    -------
    A rectangle needs none; a trapezoid does:

    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.fem.element_default import edge_twists, tying_matrices
    >>> def Ek_of(m):
    ...     psi = edge_twists(m.g0, m.edge_nodes)
    ...     z0 = (m.elem_edge_sign[..., None] * (0.5 * psi)[m.elem_edges]).reshape(-1, 24)
    ...     return drilling_correction(tying_matrices(), z0, reference_G(m, psi))
    >>> m = mesh.rectangle(2.0, 1.0, 1, 1)
    >>> float(np.abs(Ek_of(m)).max())
    0.0
    >>> m.g0[3, 0, 3] += 0.3                                  # the top left node moved along x
    >>> bool(np.abs(Ek_of(m)).max() > 0.01)
    True
    """
    m = len(z0)
    A, Acon, n, j0 = _bases(P, z0)
    Gd = G0[:, :, 5::6]                                              # nodal drilling columns (m, 24, 4)
    eps = np.einsum("qij,mjt->mqit", P, Gd)                          # (m, q, 12, 4)
    c = np.stack([eps[:, :, 0:3], eps[:, :, 6:9]], 2)                # c_a of each rotation (m, q, 2, 3, 4)
    c = c - np.einsum("mqait,mqi->mqat", c, n)[:, :, :, None, :] * n[:, :, None, :, None]   # in-plane
    E = np.einsum("mqai,mqajt->mqijt", Acon, c)
    E = 0.5 * (E + np.swapaxes(E, 2, 3))                             # sym(A^a (x) c_a)
    Ebar = np.einsum("mq,mqijt->mijt", j0, E) / j0.sum(1)[:, None, None, None]
    D = Gd[:, 5::6, :]                                               # d_k of the rotations (m, 4, 4)
    Ek = np.einsum("mijt,mtk->mijk", Ebar, np.linalg.pinv(D))
    Ek[np.abs(Ek).reshape(m, -1).max(1) <= ROUND_OFF] = 0.0         # strain per radian: round-off
    return Ek


def tying_correction(P, z0, Ek):
    """dP (m, q, 12, 24): the correction of the tying matrices P (q, 12, 24) at their points,
    c_a <- c_a - Ebar A_a with Ebar = sum_k Ek[..., k] d_k (:func:`drilling_correction`)."""
    A = _bases(P, z0)[0]
    corr = -np.einsum("mijk,mqaj->mqaik", Ek, A)                     # (m, q, 2, 3, 4 edges)
    dP = np.zeros((len(z0), P.shape[0], 12, 24))
    dP[:, :, 0:3, 5::6] = corr[:, :, 0]
    dP[:, :, 6:9, 5::6] = corr[:, :, 1]
    return dP


def _bases(P, z0):
    """(A (m, q, 2, 3) the reference tangents, A^a, the unit normal n, the area element j0)."""
    zeta0 = np.einsum("qij,mj->mqi", P, z0)
    A = np.stack([zeta0[..., 0:3], zeta0[..., 6:9]], -2)
    _, Ainv, j0 = strain_operators(A[..., 0, :], A[..., 1, :])
    n = np.cross(A[..., 0, :], A[..., 1, :]) / j0[..., None]
    return A, np.einsum("mqab,mqbi->mqai", Ainv, A), n, j0

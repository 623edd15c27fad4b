"""The in-plane shear of curved elements of the default element taken toward its element mean:
the membrane of thin curved coarse meshes without locking (issue 30, item 2).

Why the tied in-plane shear locks curved elements.  The tying of the default element
(``element_default``) carries the in-plane shear of each edge twist into the Gauss points:
e_12 = c_1 . A_2 varies along y between the bottom and top edges, e_21 = c_2 . A_1 along x
between the left and right edges.  Linearised, an edge's in-plane shear is p = (du . t_perp -
theta_m . n_mid |dX|)/2 -- its turn relative to the mean rotation of its end frames about the
edge's mid normal.  The element mean of the shear (the drilling rotations cancel in the symmetric
part) is the displacement field's shear; the two linear variations, d_y = p_t - p_b and d_x =
p_r - p_l, are differences of edge turns across the element: gradients of the drilling rotation
and, on a curved element (the mid normals of opposite edges differ by the element's turn),
bending rotations times the element's curvature.  Penalised at membrane order (E h) they tie
the bending rotations of a curved element to its in-plane shear, and the inextensional
deformations of a bending-dominated shell lock: the pinched hemisphere (R/h 1e4, 4x4) gave 0.63 of
its converged deflection, 0.017 at R/h 1e5 (``benchmarks/results/obstacle_course.md``).

The correction.  At every Gauss point q the two shear components e_12, e_21 -- taken in the
covariant basis of the element centre, projected onto the tangent plane at q -- are moved toward
their area-weighted element mean:

    e^c_ab(q) = T e(q) T^T,   T_ac = At_a . A^c(q),   At_a = A_a(0) - (A_a(0) . n_q) n_q,
    ebar_ab = sum_q j0_q e^c_ab(q) / sum_q j0_q          (ab = 12, 21),
    e(q) <- e(q) + (1 - beta) S Delta S^T,   Delta_ab = ebar_ab - e^c_ab(q),   S = T^-1,

so the tied normal strains e_11, e_22, the transverse shear, bending and drilling curvatures are
unchanged, and of the shear's linear variation (symmetric and skew) the element keeps the part
beta (:func:`shear_retention`): beta = (1 + 12 chi^2)^(-1/2), chi = phi L / h (phi the edges'
turn out of the element's plane, L its size), so the membrane-order coupling of the bending
rotations is never stiffer than the bending energy (no locking at any R/h), a flat element keeps
the tying unchanged (beta = 1: Cook's membrane and the flat patch tests to the bit), and the
drilling gradients that the variation alone holds keep a stiffness of bending order,
E h beta^2 ~ D / (phi L)^2, whatever the law's drilling modulus.  The full mean (beta = 0)
would leave them to the drilling curvature of the law (D (1 - nu), zero at ``drilling = 0``):
4 zero-energy modes more on a 3x3 cylinder patch at drilling = 0 (11 against 7), as a one-point
shear's hourglass; the kept part closes them (7, the count of the tying), and the hemisphere's
4x4 mesh gives 0.980 / 0.979 at R/h 1e4 / 1e5 (before 0.626 / 0.017).  Only the skew part's
variation locks: averaging the symmetric part alone leaves the hemisphere at 0.626.

A constant membrane strain has constant e^c (the Cartesian tensor is the same at every point),
so constant-strain states and the patch tests are kept; the correction is linear in the edge
twists and beta depends on the reference geometry and the law only (Dbar stays a quadratic form:
objectivity, the tangent, both backends unchanged) and acts on the same columns as the tying
(the v components, and the drilling components w_3 of distorted quads), so the kernels keep
their split form.
"""
from __future__ import annotations

import numpy as np

from .material import strain_operators

__all__ = ["shear_tying", "shear_retention", "shear_mean", "shear_correction"]


def shear_retention(z0, zeta0, Dmat, j0):
    """beta (k,): the factor each element keeps on the tied shear's linear variation,

        beta = (1 + 12 chi^2)^(-1/2),   chi = phi L / h,   h^2 = 12 k_b / k_m,

    phi the largest turn of the element's reference edges out of its plane (2 |z0 rotation|
    without its component on the centre normal: a frame field turning about the normal, as on
    an annulus, is flat) [rad], L = sqrt(area),
    h the thickness the law's stiffness implies (k_m, k_b: the traces of its tangential membrane
    and bending blocks at the Gauss points, C and D = C h^2 / 12 times the same metric factor
    for ``Material``; no attribute of the law is read).  The variation ties the bending rotations
    theta of a curved element to its in-plane shear at membrane order, E h (phi theta)^2 per unit
    area, against the bending energy E h^3 / 12 (theta / L)^2: their ratio is 12 chi^2.  Kept
    with the factor beta (the energy with beta^2), the coupling stays below the bending energy at
    every thickness (no locking); a flat element (phi = 0) keeps the whole tying (beta = 1: its
    in-plane bending, Cook's membrane, unchanged); and the drilling gradients the variation holds
    keep a stiffness E h beta^2 ~ D / (phi L)^2, of bending order whatever the law's drilling
    modulus (no zero-energy mode at ``drilling = 0``).

    Parameters
    ----------
    z0 : (k, 24) array
        Reference edge twists.
    zeta0 : (k, q, 12) array
        Reference strain twists at the Gauss points (A_1 = zeta0[..., 0:3], A_2 = zeta0[..., 6:9]).
    Dmat, j0 : (k, q, 12, 12), (k, q) arrays
        The law's resultant matrices and area elements there (``Material.resultant_matrix``).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Material
    >>> from core_se3.fem.element_default import tying_matrices
    >>> z0 = np.zeros((2, 24)); z0[:, [0, 6, 13, 19]] = 0.5        # unit squares
    >>> z0[1, 4] = 0.05                                             # one edge turning 0.1 rad
    >>> zeta0 = np.einsum("qij,mj->mqi", tying_matrices(), z0)
    >>> D, j0 = Material(1.0, 0.3, 0.01).resultant_matrix(zeta0[..., 0:3], zeta0[..., 6:9])
    >>> shear_retention(z0, zeta0, D, j0).round(4).tolist()         # chi = 0.1 * 1 / 0.01 = 10
    [1.0, 0.0289]
    """
    phi, coupling = curved_element_measures(z0, zeta0, Dmat, j0)
    return 1.0 / np.sqrt(1.0 + coupling)


def curved_element_measures(z0, zeta0, Dmat, j0):
    """(phi, 12 chi^2), each (k,): the largest out-of-plane turn of an element's reference edges
    [rad] and the coupling ratio 12 chi^2, chi = phi L / h (L = sqrt(area), h^2 = 12 k_b / k_m
    the thickness the law implies), as :func:`shear_retention` defines them (its parameters)."""
    n = np.cross(zeta0[..., 0:3], zeta0[..., 6:9])
    n /= np.linalg.norm(n, axis=-1)[..., None]
    nc = n.sum(axis=1)
    nc /= np.linalg.norm(nc, axis=-1)[..., None]                   # the normal at the centre
    rot = z0.reshape(len(z0), 4, 6)[..., 3:]
    rot = rot - np.einsum("mei,mi->me", rot, nc)[..., None] * nc[:, None]   # no drilling turn
    phi = 2.0 * np.linalg.norm(rot, axis=-1).max(axis=1)
    Pt = np.eye(3) - n[..., :, None] * n[..., None, :]                # tangential projector
    tr = lambda i: np.einsum("mqij,mqji->m", Pt, Dmat[..., i:i + 3, i:i + 3])   # (m,) over q
    km = tr(0) + tr(6)
    kb = tr(3) + tr(9)
    return phi, phi ** 2 * j0.sum(axis=1) * km / kb


def shear_tying(Pm, P, z0, beta, gauss=None):
    """The tying matrices Pm (m, q, 12, 24) at the points of P (q, 12, 24) with the shear
    correction: Pm + (1 - beta) dP (module docstring), worked out on the elements with beta < 1
    only (a flat mesh costs nothing).  ``gauss`` = (Pm_g, P_g): the tying at the Gauss points,
    where the element means are taken (default: Pm and P themselves).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.fem.element_default import tying_matrices
    >>> P = tying_matrices()
    >>> Pm = np.broadcast_to(P, (1,) + P.shape)
    >>> shear_tying(Pm, P, np.zeros((1, 24)), np.ones(1)) is Pm      # beta = 1: untouched
    True
    """
    k = np.nonzero(beta < 1.0)[0]
    if not len(k):
        return Pm
    Pmg, Pg = (Pm, P) if gauss is None else gauss
    if len(k) == len(beta):                    # all curved: no gather, one new array
        dP = shear_correction(Pm, P, z0, shear_mean(Pmg, Pg, z0))
        dP *= (1.0 - beta)[:, None, None, None]
        return dP.__iadd__(Pm)
    out = np.array(Pm)
    out[k] += (1.0 - beta[k])[:, None, None, None] * shear_correction(Pm[k], P, z0[k], shear_mean(Pmg[k], Pg, z0[k]))
    return out


def _geometry(P, z0):
    """At the points of P: A (m, q, 2, 3) the tied reference tangents, Acon their duals A^a, T
    (m, q, 2, 2) = At_a . A^c(q) and S = T^-1 (module docstring), the area element j0 (m, q)."""
    zeta0 = np.einsum("qij,mj->mqi", P, z0)
    A = np.stack([zeta0[..., 0:3], zeta0[..., 6:9]], -2)
    _, Ainv, j0 = strain_operators(A[..., 0, :], A[..., 1, :])
    n = np.cross(A[..., 0, :], A[..., 1, :]) / j0[..., None]
    Acon = np.einsum("mqab,mqbi->mqai", Ainv, A)
    # the centre's tangents: the means of opposite edges' reference twists (z_b, z_t, z_l, z_r)
    A0 = 0.5 * np.stack([z0[:, 0:3] + z0[:, 6:9], z0[:, 12:15] + z0[:, 18:21]], 1)     # (m, 2, 3)
    At = A0[:, None] - np.einsum("mai,mqi->mqa", A0, n)[..., None] * n[:, :, None]
    T = np.einsum("mqai,mqci->mqac", At, Acon)
    S = np.empty_like(T)                       # the 2x2 inverse in closed form
    S[..., 0, 0], S[..., 1, 1] = T[..., 1, 1], T[..., 0, 0]
    S[..., 0, 1], S[..., 1, 0] = -T[..., 0, 1], -T[..., 1, 0]
    S /= (T[..., 0, 0] * T[..., 1, 1] - T[..., 0, 1] * T[..., 1, 0])[..., None, None]
    return A, Acon, T, S, j0


def _centre_shear(Pm, A, T):
    """e^c_ab(q) = T e(q) T^T as rows on the edge twists (m, q, 2, 2, 24), e_ab = c_a . A_b."""
    c = np.stack([Pm[..., 0:3, :], Pm[..., 6:9, :]], 2)               # (m, q, 2, 3, 24)
    e = np.einsum("mqaiz,mqbi->mqabz", c, A)
    return np.einsum("mqac,mqcdz,mqbd->mqabz", T, e, T)


def shear_mean(Pm, P, z0):
    """ebar (m, 2, 24): the area-weighted element means of the centre-basis shear components
    e^c_12, e^c_21 as rows on the edge twists, from the tying matrices Pm (m, q, 12, 24) (with
    their corrections) at the Gauss points of P (q, 12, 24) and the reference twists z0 (m, 24).

    Example
    -------
    On a rectangle the mean is the shear at the centre: the means of the opposite edges' turns.

    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.fem.element_default import edge_twists, tying_matrices
    >>> m = mesh.rectangle(2.0, 1.0, 1, 1)
    >>> psi = edge_twists(m.g0, m.edge_nodes)
    >>> z0 = (m.elem_edge_sign[..., None] * (0.5 * psi)[m.elem_edges]).reshape(-1, 24)
    >>> P = tying_matrices()
    >>> eb = shear_mean(np.broadcast_to(P, (1,) + P.shape), P, z0)
    >>> np.round(eb[0, 0, [1, 7]], 12).tolist()        # e_12 = c_1 . A_2: v_y of bottom and top
    [0.25, 0.25]
    """
    A, _, T, _, j0 = _geometry(P, z0)
    ec = _centre_shear(Pm, A, T)
    w = j0 / j0.sum(1, keepdims=True)
    return np.stack([np.einsum("mq,mqz->mz", w, ec[:, :, 0, 1]), np.einsum("mq,mqz->mz", w, ec[:, :, 1, 0])], 1)


def shear_correction(Pm, P, z0, ebar):
    """dP (m, q, 12, 24): the correction of the tying matrices Pm (m, q, 12, 24) at the points
    of P (q, 12, 24) that sets the centre-basis shear components to their element means ebar
    (:func:`shear_mean`) (module docstring)."""
    A, Acon, T, S, _ = _geometry(P, z0)
    ec = _centre_shear(Pm, A, T)
    D = np.zeros_like(ec)
    D[:, :, 0, 1] = ebar[:, None, 0] - ec[:, :, 0, 1]
    D[:, :, 1, 0] = ebar[:, None, 1] - ec[:, :, 1, 0]
    de = np.einsum("mqac,mqcdz,mqbd->mqabz", S, D, S)                 # change of e_ab(q)
    dc = np.einsum("mqabz,mqbi->mqaiz", de, Acon)                     # c_a += sum_b de_ab A^b
    dP = np.zeros(Pm.shape[:2] + (12, 24))
    dP[:, :, 0:3] = dc[:, :, 0]
    dP[:, :, 6:9] = dc[:, :, 1]
    return dP

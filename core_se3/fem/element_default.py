"""The default 4-node SE(3) shell element: exact edge twists + assumed natural strains.

Kinematics.  Along each element edge a -> b the frames are joined by the SE(3) geodesic
(helicoidal interpolation, Sonneville et al. 2014); its left-trivialised strain is constant
along the edge and equal to the edge twist (in natural coordinates, edge length 2)

    z_ab = log(g_a^-1 g_b) / 2.

The strain twists zeta_1, zeta_2 of seed eq. (zeta) are *assumed* inside the element as in
MITC4 tying, from the edges on which they are exact:

    zeta_1(x, y) = ((1 - y) z_bottom + (1 + y) z_top) / 2,
    zeta_2(x, y) = ((1 - x) z_left   + (1 + x) z_right) / 2.

Consequences, each asserted by a test: the strains depend on the current relative frames
only (objective and path independent: no incremental strain update as in the seed's
Algorithm 1); constant commuting strain fields (pure bending, roll-up, uniform stretch) are
reproduced exactly on any element whose edges turn by less than pi; every strain component of
every edge is penalised, so a free element has exactly the six rigid-body zero modes; a strip
bent about its width axis is an assembly of Sonneville's locking-free SE(3) beams.

Energy.  With the reference edge twists z0, the element energy is the quadratic form

    Pi_e = 1/2 (z - z0)^T Dbar_e (z - z0),   z = (z_b, z_t, z_l, z_r) in R^24,

where Dbar_e = sum_gp j0 P_gp^T D(A_1, A_2) P_gp is computed once from the reference geometry
(2x2 Gauss, P_gp the tying interpolation, D the resultant law of ``material``), with four
enhanced membrane modes condensed per element (``membrane_enhanced``, Simo and Rifai 1990).  All
geometric nonlinearity sits in the edge logarithms, which are computed once per mesh edge.

Linearisation (exp-update g_i <- g_i exp(eta_i)).  For psi = log(g_a^-1 g_b), with
L = dexp_inv (``lie``):

    d psi = L(psi) eta_b - L(-psi) eta_a
    psi(eta) = psi + L Delta + 1/2 DL(psi)[L Delta] Delta + O(3),
    Delta = eta_b - Ad_{exp(-psi)} eta_a - 1/2 ad_{Ad eta_a} eta_b,

which gives the edge's geometric stiffness from F = dPi/dz (J_m = d(L(psi)^T F)/d psi is
taken by complex-step differentiation of the closed form of dexp_inv: exact to round-off).
The derivative of the left-trivialised gradient r along exp-updates is the symmetric Hessian
plus 1/2 adt(r_i) on each node's diagonal block (BCH to second order), so the tangent is
non-symmetric away from equilibrium, as the seed's E75 remarks.

Frames.  The element is built on the frames g Q, Q = Rz(alpha) a constant turn about each node's
normal (``mesh.gauge``: the least-turn gauge, ``Mesh.gauge_angles``), for a law that is in-plane
isotropic: the tying averages edge twists that are each constant in their own geodesic's frame,
so frames turning about the normal from node to node would enter the strains (the patch tests
with random nodal turns: error 0.7 x the turn).  With eta~ = Ad_{Q^-1} eta the forces and blocks
return to the user's frames by constant rotations, r = Ad_{Q^-1}^T r~, K_ab = Ad_{Q_a^-1}^T K~_ab
Ad_{Q_b^-1}; where alpha = 0 (frames that do not turn about the normal) nothing is done.

Cuts.  A closed doubly curved surface has no field of d1 without turns (a sphere: hairy ball): a
4-fold field (``mesh.cross_field``, a mesh file's default frames) jumps by quarter turns across
cuts.  For an in-plane isotropic law each mesh edge (a, b) takes b's frame turned by the quarter
turn R = Rz(k pi/2) that leaves the least turn about the normal (``mesh.gauge.edge_matching``):
psi = log(g_a^-1 g_b R), whose derivative in eta_b is L(psi) Ad_{R^-1} (a constant change of
b's variable: its forces and edge blocks turn back by R).  Each element compares its four edge
twists in one family of frames, its nodes' turned by the quarter turns that leave them least
turned from its first node's (``mesh.gauge.corner_turns``): C z, C = blockdiag(Ad_{S^-1}) a signed
permutation per side (S the turn of the side's first node; ``side_turns``), and Dbar = C^T Dbar_c
C with Dbar_c built from C z0 as any element's -- so the kernels see a Dbar like any other (its
v-w blocks stay exactly zero) and the strains, the resultants and the area take C.  Round a
cross field's singular node (a cubed sphere's valence-3 corners) the turns cannot close in one of
its elements, which compares its sides in frames turned to its first node's by their actual
angles.  Without cuts (every k = 0) nothing is done (the code paths of before, to the bit).  On
the closed cubed sphere read from a file (R 10): the element's area within 2.0 / 1.4 / 1.3 % of
its quad's on 4 / 8 / 16 per face (0.03 of it before on 17 / 56 / 90 elements) and a pressurised
sphere's radial displacement within -3.4 / +5.9 % of the membrane value on 16 per face
(-1.4 / +2.3 % on 24, -0.7 / +1.2 % on 32: O(h^2); largest at the midpoints of the cube's edges,
where two faces' grids meet at a kink, and as large with a hint's frames there; at the cube's 8
valence-3 corners -3.0 / -1.3 / -0.7 %, O(h^2) too, as the face centres; -5.7 ... 7.2 times it before).
"""
from __future__ import annotations

import warnings

import numpy as np

from .. import lie
from ..errors import ElementTooDistortedError, ElementWarning, edge_turn_error
from ..mesh import LOCAL_EDGES
from ..mesh.gauge import corner_turns, edge_matching, quarter_turns, turned_about_normal
from .element import Element, ElementEvaluation, register_element
from .frame_turns import check_frame_turns, check_node_windings
from .material import law_matrix
from .membrane_drilling import drilling_correction, reference_G, tying_correction
from .membrane_enhanced import condensed_stiffness, membrane_enhancement
from .membrane_shear import curved_element_measures, shear_retention, shear_tying
from .quadrature import GAUSS_2x2
from .resultants import element_resultants
from .warp import check_chord_normals, check_warp

_IU = np.triu_indices(24)                # the upper triangle of a 24x24 matrix, row by row


def _unpack(Dp):
    """The symmetric (k, 24, 24) matrices of their packed upper triangles Dp (k, 300)."""
    D = np.empty((len(Dp), 24, 24))
    D[:, _IU[0], _IU[1]] = Dp
    D[:, _IU[1], _IU[0]] = Dp
    return D

__all__ = ["DefaultElement", "edge_twists", "tying_matrices", "element_gauge", "side_turns", "check_vortices",
           "MAX_EDGE_ANGLE", "VORTEX_TURN"]

MAX_EDGE_ANGLE = 0.97 * np.pi   # beyond this the log's cut at pi is too close
SETUP_CHUNK = 4096              # elements per block of the reference stiffness set-up


def tying_matrices(points=GAUSS_2x2):
    """P (ngp, 12, 24): (zeta_1, zeta_2) at each point from (z_b, z_t, z_l, z_r).

    Parameters
    ----------
    points : (q, 2) array, optional
        Natural coordinates (x, y) in [-1, 1]^2; default the 2x2 Gauss points.

    Returns
    -------
    (q, 12, 24) ndarray
        zeta_1 = ((1 - y) z_b + (1 + y) z_t)/2 and zeta_2 = ((1 - x) z_l + (1 + x) z_r)/2 as
        matrices on the stacked edge twists.

    Example
    -------
    >>> import numpy as np
    >>> P = tying_matrices(np.zeros((1, 2)))           # the centre: means of opposite edges
    >>> P.shape, P[0, 0, [0, 6, 12, 18]].tolist()
    ((1, 12, 24), [0.5, 0.5, 0.0, 0.0])
    """
    P = np.zeros((len(points), 12, 24))
    I = np.eye(6)
    for q, (x, y) in enumerate(points):
        P[q, :6, 0:6] = 0.5 * (1 - y) * I
        P[q, :6, 6:12] = 0.5 * (1 + y) * I
        P[q, 6:, 12:18] = 0.5 * (1 - x) * I
        P[q, 6:, 18:24] = 0.5 * (1 + x) * I
    return P


def element_gauge(mesh, material):
    """Q (n, 4, 4): the turns Rz(alpha) about the nodal normals on which the element builds its
    frames (g Q; module docstring), or None where there are none to make: the mesh's frames do
    not turn about the normal (``Mesh.gauge_angles`` all 0), or the law is not in-plane isotropic
    (its material axis is the user's d1: ``ResultantLaw``).

    Example
    -------
    >>> from core_se3 import mesh, Material
    >>> law = Material(1.0e3, 0.3, 0.01)
    >>> element_gauge(mesh.rectangle(1.0, 1.0, 2, 2), law) is None
    True
    >>> element_gauge(mesh.annulus(1.0, 2.0, 1.0, 2, 2), law).shape
    (9, 4, 4)
    """
    if not getattr(material, "in_plane_isotropic", False):
        return None
    alpha = mesh.gauge_angles
    if not alpha.any():
        return None
    return turned_about_normal(np.broadcast_to(np.eye(4), (len(alpha), 4, 4)), alpha)


def _matching(g0, edge_nodes, material):
    """The edges' quarter turns across a cross field's cuts (``mesh.gauge.edge_matching``) for an
    in-plane isotropic law, else None: a law whose material axis is the user's d1 keeps it."""
    if not getattr(material, "in_plane_isotropic", False):
        return None
    return edge_matching(g0, edge_nodes)


def _axis_law_note(material, g0, mesh):
    """A sentence for an error on reference frames that turn by quarter turns across element
    edges (a cross field's cuts) under a law that does not say it is in-plane isotropic (its
    ``in_plane_isotropic`` attribute): the element keeps the user's d1 as its material axis and
    takes no quarter turns -- a user's isotropic law without the attribute was refused on a
    closed sphere from a file with the frames blamed only; "" otherwise."""
    if getattr(material, "in_plane_isotropic", False) or edge_matching(g0, mesh.edge_nodes) is None:
        return ""
    return (f". The law ({type(material).__name__}) does not say it is in-plane isotropic (a true "
            "in_plane_isotropic attribute, fem.ResultantLaw), so its material axis is each node's d1 as given and "
            "the element takes no quarter turns across the cuts of a cross field (a mesh file's default frames on a "
            "doubly curved shell); if the law is the same in every in-plane direction, say so "
            "(in_plane_isotropic = True) and the element matches them")


def edge_twists(g, edge_nodes, reference=False, matching=None):
    """psi_e = log(g_a^-1 g_b) for all edges (E, 6); raises if an edge turns by ~pi.

    Parameters
    ----------
    g : (n, 4, 4) array
        Nodal frames.
    edge_nodes : (E, 2) array of int
        The edges (a, b), e.g. ``mesh.edge_nodes``.
    reference : bool, optional
        ``g`` are the reference frames (the element's build): an edge turning by ~pi there is
        the user's frames (d1 reversed between nodes, a vortex of the d1 field), and the error
        says so instead of "refine the mesh or the load step".
    matching : (E,) int array or None, optional
        Quarter turns k of the edges across a cross field's cuts (``mesh.gauge.edge_matching``):
        psi_e = log(g_a^-1 g_b Rz(k pi/2)) (module docstring, "Cuts").

    Returns
    -------
    (E, 6) ndarray
        The relative twists (translation [length] in the frame of a, rotation [rad]).  An edge
        turning by more than ``MAX_EDGE_ANGLE`` raises
        :class:`~core_se3.errors.ElementTooDistortedError`.

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> m.edge_nodes.tolist(), edge_twists(m.g0, m.edge_nodes)[:, :3].tolist()
    ([[0, 1], [0, 2], [1, 3], [2, 3]], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    """
    return _checked_log(_relative_frames(g, edge_nodes, matching), edge_nodes, g if reference else None)


def _relative_frames(g, edge_nodes, matching=None):
    """h_e = g_a^-1 g_b (E, 4, 4) of every edge (a, b), its translation R_a^T (p_b - p_a) (as the
    compiled kernels: ``lie.relative``, no eps |p| round-off on a part far from the origin); with
    ``matching`` (E,) the quarter turns of the cuts, g_a^-1 g_b Rz(k pi/2) (exact: a signed
    permutation of the rotation's columns)."""
    h = lie.relative(g[edge_nodes[:, 0]], g[edge_nodes[:, 1]])
    if matching is not None:
        h[:, :3, :3] = h[:, :3, :3] @ quarter_turns(matching)
    return h


def _checked_log(h, edge_nodes, g_ref=None, mesh=None):
    """psi = log(h) (E, 6); ElementTooDistortedError where an edge turns by ~pi (``g_ref``: the
    reference frames, whose turn is the user's frames, not the mesh or the load step; ``mesh``:
    the nodes are named by its ``whole_ids``, a rank's part of a distributed run)."""
    psi = lie.log(h)
    ang = np.linalg.norm(psi[:, 3:], axis=1)
    if ang.size and ang.max() > MAX_EDGE_ANGLE:
        e = int(np.argmax(ang))
        a, b = edge_nodes[e].tolist()
        if g_ref is not None:
            raise ElementTooDistortedError(_reference_turn_message(g_ref, a, b, psi[e, 3:]))
        raise edge_turn_error(edge_nodes, e, float(ang[e]), MAX_EDGE_ANGLE, mesh)
    return psi


def _reference_turn_message(g, a, b, w):
    """The error for the reference frames of nodes a, b turning by |w| ~ pi (w in a's frame)."""
    R = g[a, :3, :3]
    axis = R @ w / np.linalg.norm(w)
    about = " (the normal d3)" if abs(axis @ R[:, 2]) > 0.99 else ""
    return (f"the reference frames of nodes {a} and {b} (an element edge) turn by {np.linalg.norm(w):.3f} rad "
            f"({np.degrees(np.linalg.norm(w)):.0f} deg, >= {MAX_EDGE_ANGLE:.3f} rad) about "
            f"({axis[0]:.3g}, {axis[1]:.3g}, {axis[2]:.3g}){about}: the nodal frames given (their d1, "
            f"e.g. d1 reversed at one node or a vortex of the d1 field) must turn little across an element; "
            "give consistent frames (d1 along the shell: Mesh(g0=...), a mesh file's d1_hint) -- neither a "
            "finer mesh nor a smaller load step changes this")


def _unclosed(mesh, matching):
    """The elements round which the edges' quarter turns ``matching`` (E,) do not close (a cross
    field's singular node at a corner), ascending."""
    ks = mesh.elem_edge_sign * matching[mesh.elem_edges]                                 # q_lb - q_la per side
    return np.flatnonzero((ks[:, 0] + ks[:, 3] - ks[:, 2] - ks[:, 1]) % 4)


def transported_d1_angles(R):
    """phi (k, 4) [rad]: the angle of each node's d1 from the first node's, both carried to the
    element's mean normal n = (sum_i d3_i) / |sum_i d3_i| by the least rotation that takes the
    node's d3 to n (about d3_i x n), R (k, 4, 3, 3) the nodal rotations of k elements.

    A turn of node i's frame by theta about its own d3 turns its carried d1 by theta about n,
    exactly (P Rot(d3, theta) = Rot(n, theta) P for P d3 = n), so the angles of two nodes differ
    by the same amount from any node's: phi measured from node j is phi - phi_j, and the
    frames turned by -phi (:func:`corner_frame_turns`) differ from another start node's by one
    common turn -- which leaves the element unchanged.  (Measured in the first node's tangent
    plane instead, the angles were not additive on a curved element, and rotating the nodes of
    the closed cubed sphere's corner elements moved the pinched sphere by 0.38 % / 6.3e-5 on
    4 / 8 per face.)  With v' = c v + w x v + w (w . v) / (1 + c), w = d3 x n, c = d3 . n.
    """
    d3, d1 = R[..., 2], R[..., 0]                                      # (k, 4, 3)
    n = d3.sum(axis=1)
    n /= np.linalg.norm(n, axis=1)[:, None]
    n = np.broadcast_to(n[:, None], d3.shape)
    w, c = np.cross(d3, n), np.einsum("kni,kni->kn", d3, n)
    v = c[..., None] * d1 + np.cross(w, d1) + w * (np.einsum("kni,kni->kn", w, d1) / (1.0 + c))[..., None]
    b1 = v[:, :1]                                                      # the first node's, carried
    return np.arctan2(np.einsum("kni,kni->kn", np.cross(b1, v), n), np.einsum("kni,kni->kn", b1, v))


def corner_frame_turns(mesh, g0, matching):
    """S (m, 4, 3, 3): the turns about the normal of every element's nodal frames g0 (n, 4, 4) in
    which it compares its sides (g0_i S_i; module docstring, "Cuts", and :func:`side_turns`):
    the quarter turns of ``mesh.gauge.corner_turns``, or in an element round which the edges'
    quarter turns ``matching`` (E,) do not close, Rz(-phi_i), phi_i the angle of node i's d1
    from the first node's, both carried to the element's mean normal
    (:func:`transported_d1_angles`: the element does not depend on which node comes first)."""
    S = quarter_turns(corner_turns(g0, mesh.quads))
    open_ = _unclosed(mesh, matching)
    if open_.size:
        phi = transported_d1_angles(g0[mesh.quads[open_], :3, :3])
        c, s = np.cos(phi), np.sin(phi)
        S[open_, :, 0, 0] = S[open_, :, 1, 1] = c
        S[open_, :, 0, 1], S[open_, :, 1, 0] = s, -s
    return S


def side_turns(mesh, g0, matching):
    """C (m, 24, 24): the element edge twists in each element's own gauge, C z (module
    docstring, "Cuts"), of the element's reference frames g0 (n, 4, 4) and the edges' quarter
    turns ``matching`` (E,): side k's (v, w) turned by T, T = S_a^T (its mesh edge (a, b) running
    as the side) or S_a^T R_k (running the other way, the twist in the frame g_b R_k, whose
    components are those in g_a's: Ad_h psi = psi), S = Rz(q pi/2) the quarter turn q of the side's
    first node in the element's frames (``mesh.gauge.corner_turns``; C a signed permutation,
    exact; either end gives the same).  In an element round which the matchings do not close (a
    singular node of a cross field at its corner) S = Rz(-phi), phi the angle of a node's d1 in
    the element's first node's frame, and the two ends of a side differ: T is the mean of the two
    ends' turns, so the element depends neither on the node numbering nor on which end comes
    first.  (Before, T was S^T of the mesh edge's first node: a renumbered pinched closed sphere
    moved by 4.3 % / 0.34 % (4 / 8 per face), two ranks gave 6.6e-6 off the serial run, and the
    elements round the cube's corners had areas 0.974 ... 1.024 of their quads', now 1.019 alike on 4 per
    face.)

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> from core_se3.mesh.gauge import edge_matching, quarter_turns
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)                  # quad [0, 1, 3, 2]
    >>> g = m.g0.copy(); g[[1, 3], :3, :3] = quarter_turns(3)   # d1 of nodes 1 and 3 along -y
    >>> C = side_turns(m, g, edge_matching(g, m.edge_nodes))
    >>> C[0, 18:21, 18:21].astype(int).tolist()             # the right side (1, 3) starts at node 1
    [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]
    """
    S = np.swapaxes(corner_frame_turns(mesh, g0, matching), -1, -2)               # (m, 4, 3, 3): S^T
    Rk = quarter_turns(matching[mesh.elem_edges])
    fw = (mesh.elem_edge_sign > 0)[..., None, None]
    T = np.where(fw, S[:, LOCAL_EDGES[:, 0]], S[:, LOCAL_EDGES[:, 0]] @ Rk)     # by the side's first node
    open_ = _unclosed(mesh, matching)
    if open_.size:                                                 # the mean of the two ends' turns
        Tb = np.where(fw, S[:, LOCAL_EDGES[:, 1]] @ Rk, S[:, LOCAL_EDGES[:, 1]])[open_]
        c, s = T[open_, :, 0, 0] + Tb[..., 0, 0], T[open_, :, 1, 0] + Tb[..., 1, 0]   # (a + b: either order alike)
        r = np.hypot(c, s)
        T[open_, :, 0, 0] = T[open_, :, 1, 1] = c / r
        T[open_, :, 1, 0], T[open_, :, 0, 1] = s / r, -s / r
    C = np.zeros((len(T), 8, 3, 8, 3))
    k = np.arange(8)
    C[:, k, :, k, :] = np.repeat(T, 2, axis=1).transpose(1, 0, 2, 3)
    return C.reshape(len(T), 24, 24)


def _congruence(C, D):
    """C^T D C (k, 24, 24) of the elements' side turns C and stiffnesses D (k, 24, 24), to the
    bit the einsum's (a sum of one product and zeros; zeros +0): D itself where C is the identity
    (every element off the cuts), by indexing where C is a signed permutation (across the cuts),
    (C^T D C)_ij = s_i s_j D_{r_i r_j} with column j's one entry s_j at row r_j, and by the einsum
    round a cross field's singular node (C of turns by other angles) -- the einsum alone took
    ~50 us per element (the closed cubed sphere, 64 per face: 1.26 s of its set-up)."""
    k = len(C)
    out = D + 0.0
    rest = np.flatnonzero(~(C.reshape(k, -1) == np.eye(24).ravel()).all(axis=1))
    Cr = C[rest]
    one = (np.count_nonzero(Cr, axis=1) == 1).all(axis=1) & (np.abs(Cr).max(axis=1) == 1.0).all(axis=1)
    r = np.argmax(np.abs(Cr[one]), axis=1)                                   # (k1, 24) rows r_j
    s = np.take_along_axis(Cr[one], r[:, None, :], axis=1)[:, 0]              # (k1, 24) signs s_j
    Dr = np.take_along_axis(np.take_along_axis(D[rest[one]], r[:, :, None], axis=1), r[:, None, :], axis=2)
    out[rest[one]] = s[:, :, None] * Dr * s[:, None, :] + 0.0
    other = rest[~one]
    out[other] = np.einsum("mki,mkl,mlj->mij", C[other], D[other], C[other], optimize=True)
    return out


def _cancelling_normals(A):
    """(k,) bool: the elements whose tied normals A_1 x A_2 (A (k, 4, 6) at the Gauss points)
    vanish somewhere (strain_operators' MeshError) or cancel (the element's mean normal,
    membrane_shear's, NaN): the cases that failed; normals that merely differ (a closed sphere's
    vortices) build a sound element."""
    n = np.cross(A[..., 0:3], A[..., 3:6])
    size = np.linalg.norm(A[..., 0:3], axis=-1) * np.linalg.norm(A[..., 3:6], axis=-1)
    j = np.linalg.norm(n, axis=-1)
    unit = n / np.maximum(j, 1e-300)[..., None]
    return (j <= 1e-10 * size).any(1) | (np.linalg.norm(unit.sum(axis=1), axis=-1) <= 1e-8)


#: the turn about the normal around an element [rad] above which its reference frames wind (a
#: vortex of d1: 2 pi); a curved element's holonomy (area x Gaussian curvature) stays far below
VORTEX_TURN = 1.5 * np.pi


def check_vortices(mesh, g, z0):
    """ElementTooDistortedError for elements whose tied tangents A_1 x A_2 (of the reference
    edge twists ``z0`` (m, 24), at the Gauss points) vanish or cancel over the element, naming a vortex of
    the user's d1 round them when the frames ``g`` wind about the normal there (their edges'
    turns adding up to a full turn, each edge less than pi: no gauge removes it).  A vortex
    alone is no error (a closed sphere's frames must have some, and its elements are sound);
    before, the degenerate ones failed far from their cause: "degenerate reference geometry ...
    zero-area or collapsed element", or NaN strains and a ConvergenceError "non-finite residual"
    at load factor 1.2e-4 (random d1 on a flat strip).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh, lie
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)                        # quad [0, 1, 3, 2]
    >>> g = m.g0.copy(); g[:, :3, :3] = lie.exp_so3(np.c_[np.zeros((4, 2)), [0.0, 1.6, 4.7, 3.1]])
    >>> z0 = 0.5 * (m.elem_edge_sign[..., None] * edge_twists(g, m.edge_nodes)[m.elem_edges]).reshape(-1, 24)
    >>> check_vortices(m, g, z0)                                      # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.ElementTooDistortedError: the reference frames wind about the normal round element(s) [0]...
    """
    P = tying_matrices()[:, [0, 1, 2, 6, 7, 8]]                          # the rows of A_1, A_2
    flipped = np.concatenate([_cancelling_normals(np.einsum("qij,mj->mqi", P, z0[s:s + SETUP_CHUNK]))
                              for s in range(0, len(z0), SETUP_CHUNK)])
    if not flipped.any():
        return
    from ..mesh.gauge import normal_turns
    omega = normal_turns(g, mesh.edge_nodes)[mesh.elem_edges] * mesh.elem_edge_sign   # (m, 4) b, t, l, r
    turn = omega[:, 0] + omega[:, 3] - omega[:, 1] - omega[:, 2]     # counter-clockwise round the quad
    bad = np.flatnonzero(flipped & (np.abs(turn) > VORTEX_TURN))
    if len(bad):
        e = int(bad[0])
        raise ElementTooDistortedError(
            f"the reference frames wind about the normal round element(s) {bad[:5].tolist()}"
            f"{' ...' if len(bad) > 5 else ''}: their d1 turn by {turn[e]:.3f} rad ({np.degrees(turn[e]):.0f} deg) "
            f"going round element {e} (nodes {mesh.quads[e].tolist()}), a vortex of the d1 field given on which "
            "the element's tangents degenerate (their normals vanish or cancel); give consistent frames (d1 varying "
            "smoothly along the shell: Mesh(g0=...), mesh.frames_from, a mesh file's d1_hint) -- neither a finer "
            "mesh nor a smaller load step changes this")


def _dexp_inv_jacobian_T(psi, F, h=1e-30):
    """J (E, 6, 6) with J[:, :, k] = d/dpsi_k (dexp_inv(psi)^T F), by complex step of the closed
    vector form (exact to round-off: no subtraction)."""
    pc = np.repeat(psi[None].astype(complex), 6, axis=0)               # (6k, E, 6)
    pc[np.arange(6), :, np.arange(6)] += 1j * h
    m = lie.dexp_inv_T_apply(pc, F[None])                              # (6k, E, 6)
    return np.ascontiguousarray(np.transpose(m.imag / h, (1, 2, 0)))


CHUNK = 2048   # elements/edges per block in the tangent: keeps temporaries cache-sized


@register_element
class DefaultElement(Element):
    """The default element (module docstring): precomputed element data for a mesh and a
    material law; evaluates energy, residual and tangent.

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The reference mesh (its frames give z0 and the reference tangents A_1, A_2).
    material : core_se3.fem.ResultantLaw
        One law or one per element.

    Attributes
    ----------
    z0 : (m, 24) ndarray
        Reference edge twists (z_b, z_t, z_l, z_r) of every element.
    Dbar : (m, 24, 24) ndarray
        The element stiffness on the edge twists, sum_gp j0 P^T D P with the enhanced membrane
        modes condensed (``membrane_enhanced``).
    j0 : (m, 4) ndarray
        Area element at the Gauss points; ``area`` (m,) their sum, the reference area.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh, Material, lie
    >>> el = DefaultElement(mesh.rectangle(1.0, 1.0, 2, 2), Material(1.0e3, 0.3, 0.01))
    >>> ev = el.evaluate(el.mesh.g0)                 # the reference state is stress free
    >>> float(np.abs(ev.r).max()), ev.element_blocks.shape
    (0.0, (4, 4, 4, 6, 6))
    >>> g = lie.exp([0.1, 0.2, 0.3, 0.3, -0.2, 0.5]) @ el.mesh.g0      # a rigid motion: objective
    >>> round(float(np.abs(el.evaluate(g, tangent=False).r).max()), 12)
    0.0
    """

    name = "default"
    mixed = True

    def __init__(self, mesh, material):
        super().__init__(mesh, material)
        # normals against the chords (fem/warp.py), first: a flipped normal's edge twist is not finite
        check_chord_normals(mesh, stacklevel=5, ids=getattr(mesh, "whole_ids", None))
        self._kernels = None
        self.gauge = element_gauge(mesh, material)
        # the quarter turns across a cross field's cuts (module docstring, "Cuts"): None without
        self.matching = _matching(self.frames(mesh.g0), mesh.edge_nodes, material)
        try:
            psi0 = edge_twists(self.frames(mesh.g0), mesh.edge_nodes, reference=True, matching=self.matching)
        except ElementTooDistortedError as exc:
            raise ElementTooDistortedError(str(exc) + _axis_law_note(material, self.frames(mesh.g0), mesh)) from None
        self.z0 = self._element_z(0.5 * psi0)                          # (m, 24)
        self._C = None if self.matching is None else side_turns(mesh, self.frames(mesh.g0), self.matching)   # (m, 24, 24)
        P = tying_matrices()
        check_vortices(mesh, self.frames(mesh.g0), self.z0 if self._C is None else np.einsum("mij,mj->mi", self._C, self.z0))
        m = len(self.z0)
        # Dbar is symmetric: its upper triangles are kept (300 of 576 entries, ``Dbar_packed``)
        self.Dbar_packed = np.empty((m, len(_IU[0])))
        self.Dz0 = np.empty((m, 24))
        self.j0 = np.empty((m, 4))
        self.drill_Ek = np.zeros((m, 3, 3, 4))     # the membrane-drilling correction (membrane_drilling)
        self.shear_beta = np.ones(m)               # the kept part of the tied shear (membrane_shear)
        self.coarse_curvature = np.zeros(m)        # phi^3 L / h (warn_if_coarse_thin_curved, Problem.check_element)
        # in chunks of elements: the resultant matrices and products of one element take ~18 kB,
        # four times its Dbar (a law without ``restricted`` gets all elements at once)
        step = SETUP_CHUNK if callable(getattr(material, "restricted", None)) else max(m, 1)
        for s in range(0, m, step):
            sl = slice(s, min(s + step, m))
            law = material.restricted(sl) if step < m else material
            z0, psi0_el = self.z0[sl], psi0
            if self._C is not None:            # the element's own gauge: its twists C z0 (Cuts)
                z0 = np.einsum("mij,mj->mi", self._C[sl], z0)
                psi0_el = np.einsum("mij,mj->mi", self._C[sl], psi0[mesh.elem_edges[sl]].reshape(-1, 24)).reshape(-1, 4, 6)
            zeta0 = np.einsum("qij,mj->mqi", P, z0)                        # (k, 4gp, 12)
            Dm, j0 = law_matrix(law, zeta0[..., 0:3], zeta0[..., 6:9], self.size[sl, None])  # (k, 4, 12, 12)
            self.j0[sl] = j0
            beta = shear_retention(z0, zeta0, Dm, j0)
            self.shear_beta[sl] = beta
            # the drilling correction sees the bending rotations times the curvature of a curved
            # element at membrane order; it is kept with the factor beta that membrane_shear keeps
            # of the same coupling in the tied shear (1 on flat elements: docs/ELEMENTS.md,
            # "Doubly curved shells")
            Ek = drilling_correction(P, z0, reference_G(mesh, psi0_el, sl)) * beta[:, None, None, None]
            self.drill_Ek[sl] = Ek
            Pm = np.broadcast_to(P, (len(z0),) + P.shape)
            if Ek.any():
                Pm = Pm + tying_correction(P, z0, Ek)                       # (k, 4gp, 12, 24)
            # the warning's index (its measures again: shear_retention stays the tests' and
            # roof_modes' hook for beta; the cost is that of a few (k, 4, 3, 3) products)
            phi, coupling = curved_element_measures(z0, zeta0, Dm, j0)
            self.coarse_curvature[sl] = phi ** 2 * np.sqrt(coupling / 12.0)   # phi^2 chi
            Pm = shear_tying(Pm, P, z0, beta)                                  # membrane_shear
            # Dbar = sum_q j0_q P_q^T D_q P_q, contracted pairwise (a 4-operand einsum is O(24^4 m)),
            # with the enhanced membrane modes condensed (membrane_enhanced)
            Dj = Dm * j0[..., None, None]
            Db = np.einsum("mqia,mqib->mab", Pm, np.einsum("mqij,mqjb->mqib", Dj, Pm))
            Db = condensed_stiffness(Db, Pm, membrane_enhancement(z0, zeta0, j0), Dj)
            if self._C is not None:            # C^T Dbar_c C on the mesh edges' twists (exact: C signed permutations)
                Db = _congruence(self._C[sl], Db)
            self.Dbar_packed[sl] = Db[:, _IU[0], _IU[1]]
            self.Dz0[sl] = np.einsum("mij,mj->mi", _unpack(self.Dbar_packed[sl]), self.z0[sl])  # Dbar z0
        self.area = self.j0.sum(axis=1)                                 # reference area per element
        ids = getattr(mesh, "whole_ids", None)                          # a rank's part: the whole mesh's ids
        check_frame_turns(mesh.X, mesh.quads, self.corner_frames(mesh.g0), self.j0, stacklevel=5, ids=ids)
        check_warp(mesh.X, mesh.quads, mesh.g0, stacklevel=5, ids=ids)      # warped quads (fem/warp.py)
        if self.matching is not None and ids is None:                   # d1 spinning about a node (Cuts; a
            check_node_windings(mesh, self.matching, stacklevel=5)      # rank's part: the run sums them)
        self._Dbar = None
        # the coarse-curvature warning needs the supports (which edges are free): the Problem
        # issues it when it solves (Problem.check_element)

    @staticmethod
    def reference_area(mesh, material):
        """j0 (m, 4): the area element at the 2x2 Gauss points of the element's reference geometry
        (its tied tangents A_1, A_2 of the reference edge twists, in the frames of
        :func:`element_gauge`), as the element's ``j0`` -- without building the element's
        stiffness (a load needs only this: ``model.loads.element_area``).

        Example
        -------
        >>> from core_se3 import mesh, Material
        >>> m = mesh.cylinder_panel(1.0, 1.0, 0.0, 1.2, 3, 1)
        >>> round(float(DefaultElement.reference_area(m, Material(1e3, 0.0, 0.01)).sum()), 12)  # 1.2 x 1
        1.2
        """
        Q = element_gauge(mesh, material)
        g0 = mesh.g0 if Q is None else mesh.g0 @ Q
        k = _matching(g0, mesh.edge_nodes, material)
        psi0 = edge_twists(g0, mesh.edge_nodes, matching=k)
        z0 = (mesh.elem_edge_sign[..., None] * (0.5 * psi0)[mesh.elem_edges]).reshape(-1, 24)
        if k is not None:                                               # the element's gauge (Cuts)
            z0 = np.einsum("mij,mj->mi", side_turns(mesh, g0, k), z0)
        zeta0 = np.einsum("qij,mj->mqi", tying_matrices(), z0)
        return np.linalg.norm(np.cross(zeta0[..., 0:3], zeta0[..., 6:9]), axis=-1)

    @property
    def Dbar(self):
        """The element stiffness Dbar (m, 24, 24) on the element edge twists (module docstring),
        unpacked from ``Dbar_packed`` at the first use and kept (the NumPy backend's; the compiled
        kernels read the packed form)."""
        if self._Dbar is None:
            self._Dbar = _unpack(self.Dbar_packed)
        return self._Dbar

    # ----------------------------------------------------------------------------------
    def frames(self, g):
        """The element's frames g Q (n, 4, 4) of the nodal frames g (module docstring, "Frames"):
        g itself where there is no gauge."""
        return g if self.gauge is None else g @ self.gauge

    def to_element_frames(self, eta):
        """Nodal increments eta (n, 6) in the element's frames: Ad_{Q^-1} eta (R_Q^T v, R_Q^T w)."""
        if self.gauge is None:
            return eta
        eta = np.asarray(eta, float).reshape(-1, 6)
        R = self.gauge[:, :3, :3]
        return np.concatenate([np.einsum("nji,nj->ni", R, eta[:, :3]), np.einsum("nji,nj->ni", R, eta[:, 3:])], 1)

    def _to_user(self, r):
        """Nodal forces r~ (n, 6) of the element's frames in the user's: Ad_{Q^-1}^T r~."""
        if self.gauge is None:
            return r
        R = self.gauge[:, :3, :3]
        return np.concatenate([np.einsum("nij,nj->ni", R, r[:, :3]), np.einsum("nij,nj->ni", R, r[:, 3:])], 1)

    def _blocks_to_user(self, Ke, KE):
        """The element and edge blocks of the element's frames in the user's: T_a K~_ab T_b^T,
        T = Ad_{Q^-1}^T = blockdiag(R_Q, R_Q) (module docstring)."""
        if self.gauge is None:
            return Ke, KE
        T = np.zeros((len(self.gauge), 6, 6))
        T[:, :3, :3] = T[:, 3:, 3:] = self.gauge[:, :3, :3]
        Te, TE = T[self.mesh.quads], T[self.mesh.edge_nodes]
        return (np.einsum("maij,mabjk,mblk->mabil", Te, Ke, Te, optimize=True),
                np.einsum("eaij,eabjk,eblk->eabil", TE, KE, TE, optimize=True))

    def corner_frames(self, g):
        """The frames each element compares its sides in, (m, 4, 4, 4) (module docstring, "Cuts"),
        or the element's frames g Q (n, 4, 4) without cuts."""
        if self._C is None:
            return self.frames(g)
        S = np.zeros((len(self._C), 4, 4, 4))
        S[:, :, :3, :3] = corner_frame_turns(self.mesh, self.frames(self.mesh.g0), self.matching)
        S[:, :, 3, 3] = 1.0
        return self.frames(g)[self.mesh.quads] @ S

    def _gauged(self, z):
        """Element edge twists z (m, 24) in the element's own gauge, C z (module docstring,
        "Cuts"); z itself without cuts."""
        return z if self._C is None else np.einsum("mij,mj->mi", self._C, z)

    def _matched_L(self, Lp):
        """L(psi) Ad_{Rz(k pi/2)^-1} (E, 6, 6): an edge twist's derivative in the increment of its
        node b across a cut (module docstring, "Cuts"); Lp itself without cuts."""
        if self.matching is None:
            return Lp
        T = np.zeros((len(Lp), 6, 6))
        T[:, :3, :3] = T[:, 3:, 3:] = quarter_turns(self.matching)
        return Lp @ np.swapaxes(T, 1, 2)

    def _matched_blocks(self, KE):
        """Edge blocks (E, 2, 2, 6, 6) of the increments (eta_a, Ad_{R_k^-1} eta_b) in those of
        (eta_a, eta_b): b's rows and columns turned back (module docstring, "Cuts")."""
        if self.matching is None:
            return KE
        T = np.zeros((len(KE), 2, 6, 6))
        T[:, 0] = np.eye(6)
        T[:, 1, :3, :3] = T[:, 1, 3:, 3:] = quarter_turns(self.matching)
        return np.einsum("eaij,eabjk,eblk->eabil", T, KE, T, optimize=True)

    def _element_z(self, zE):
        """Per-element edge twists (m, 24) from per-mesh-edge values (E, 6), with signs."""
        m = self.mesh
        return (m.elem_edge_sign[..., None] * zE[m.elem_edges]).reshape(-1, 24)

    def strains(self, g, points=GAUSS_2x2):
        """Strain twists (zeta_1, zeta_2) (m, npts, 12) at natural points of every element (the
        tying with the membrane-drilling correction, ``membrane_drilling``)."""
        z = self._element_z(0.5 * edge_twists(self.frames(g), self.mesh.edge_nodes, matching=self.matching))
        return np.einsum("mqij,mj->mqi", self.tying(points), self._gauged(z))

    def tying(self, points=GAUSS_2x2):
        """The element's tying matrices (m, npts, 12, 24) at natural points: the interpolation of
        the edge twists with the membrane-drilling (``membrane_drilling``) and in-plane shear
        (``membrane_shear``) corrections; zeta = tying(points) z."""
        P, Pg = tying_matrices(points), tying_matrices()
        z0, Ek = self._gauged(self.z0), self.drill_Ek
        Pm = np.broadcast_to(P, (len(z0),) + P.shape)
        Pmg = np.broadcast_to(Pg, (len(z0),) + Pg.shape)
        if Ek.any():
            Pm = Pm + tying_correction(P, z0, Ek)
            Pmg = Pmg + tying_correction(Pg, z0, Ek)
        return shear_tying(Pm, P, z0, self.shear_beta, gauss=(Pmg, Pg))

    def cell_fields(self, g, increments=None):
        """Stress resultants at the element centres (``resultants.element_resultants``); with
        ``increments`` (n, 6), those of the linear analysis whose state g is (its strains
        linearised about the reference: :meth:`linear_strains`)."""
        return element_resultants(self, g, increments)

    def linear_strains(self, eta, points=GAUSS_2x2):
        """The strain twists' increments (m, npts, 12) of the nodal increments eta (n, 6) about
        the reference frames, linearised: the tying of dz = z(dpsi / 2), dpsi the edge twists'
        linear increments (as :meth:`linear_stress` at the reference, where z = z0).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import Material, mesh
        >>> el = DefaultElement(mesh.rectangle(2.0, 1.0, 2, 1), Material(1.0e3, 0.3, 0.1))
        >>> X = el.mesh.X
        >>> eta = np.zeros((6, 6)); eta[:, 5] = 0.3; eta[:, 0], eta[:, 1] = -0.3 * X[:, 1], 0.3 * X[:, 0]  # 0.3 e_z x X
        >>> float(np.abs(el.linear_strains(eta)).max()) < 1e-15
        True
        """
        psi0 = edge_twists(self.frames(self.mesh.g0), self.mesh.edge_nodes, reference=True, matching=self.matching)
        Lp, Lm = lie.dexp_inv(psi0, both=True)
        dz = self._element_z(0.5 * self._edge_increments(self._matched_L(Lp), Lm, eta))
        return np.einsum("mqij,mj->mqi", self.tying(points), self._gauged(dz))

    def _edge_increments(self, Lp, Lm, eta):
        """The edge twists' linear increments L(psi) eta_b - L(-psi) eta_a (E, 6) of the nodal
        increments eta (n, 6) (of the user's frames: turned into the element's here; Lp across a
        cut: ``_matched_L``'s)."""
        En = self.mesh.edge_nodes
        eta = self.to_element_frames(np.asarray(eta, float).reshape(-1, 6))
        return np.einsum("eij,ej->ei", Lp, eta[En[:, 1]]) - np.einsum("eij,ej->ei", Lm, eta[En[:, 0]])

    def compiled(self, pattern, mode="auto"):
        """The numba kernels of this element on ``pattern`` (``kernels.ElementKernels``), built
        once per pattern: the same residual and tangent, written into the pattern's CSR data
        (``mode``: the kernels' driver, 'auto', 'serial', 'colour' or 'gather'; a distributed
        run with one thread per rank asks for 'serial', which needs no block workspace)."""
        kern = self._kernels
        if kern is None or kern.pattern is not pattern:
            from ..kernels import ElementKernels
            kern = ElementKernels.from_element(self, pattern, mode=mode, error=ElementTooDistortedError)
            self._kernels = kern
        return kern

    def energy(self, g):
        z = self._element_z(0.5 * edge_twists(self.frames(g), self.mesh.edge_nodes, matching=self.matching))
        dz = z - self.z0
        return 0.5 * np.einsum("mi,mij,mj->", dz, self.Dbar, dz)

    def _edge_forces(self, f):
        """Per-mesh-edge forces F (E, 6) conjugate to the edge twists, from element forces f (m, 24)."""
        mesh = self.mesh
        fe = mesh.elem_edge_sign[..., None] * f.reshape(-1, 4, 6)
        nE = len(mesh.edge_nodes)
        return np.stack([np.bincount(mesh.elem_edges.ravel(), weights=fe[..., k].ravel(), minlength=nE)
                         for k in range(6)], -1)

    def _nodal_forces(self, F, Lp, Lm):
        """Nodal forces of edge forces F: r_a = -1/2 L(-psi)^T F, r_b = 1/2 L(psi)^T F."""
        En = self.mesh.edge_nodes
        ra = -0.5 * np.einsum("eji,ej->ei", Lm, F)
        rb = 0.5 * np.einsum("eji,ej->ei", Lp, F)
        n = self.mesh.n_nodes
        return np.stack([np.bincount(En[:, 0], weights=ra[:, k], minlength=n)
                         + np.bincount(En[:, 1], weights=rb[:, k], minlength=n) for k in range(6)], -1)

    def linear_stress(self, ev, eta):
        """Element stresses linearised about the state of ``ev`` for the increment eta (n, 6):
        f = Dbar (z(g) - z0 + G eta) (m, 24), G = dz/deta (the stress update of the mixed
        iteration; the nonlinear update would be Dbar (z(g exp(eta)) - z0)).

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import Material, mesh
        >>> el = DefaultElement(mesh.rectangle(2.0, 1.0, 2, 1), Material(1.0e3, 0.3, 0.1))
        >>> ev = el.evaluate(el.mesh.g0, tangent=True)
        >>> eta = np.zeros((6, 6)); eta[[2, 5], 0] = 1e-3          # stretch the right column
        >>> f = el.linear_stress(ev, eta)
        >>> bool(np.allclose(f, el.evaluate(el.mesh.g0 @ lie.exp(eta), tangent=False).stress,
        ...                  rtol=0, atol=1e-3 * np.abs(f).max()))
        True
        """
        Lp, Lm, dz = ev.linearization
        return np.einsum("mij,mj->mi", self.Dbar, dz + self._element_z(0.5 * self._edge_increments(Lp, Lm, eta)))

    def evaluate(self, g, tangent=True, stress=None):
        """Internal residual r (n, 6) in body frames and, if asked, the tangent blocks: the
        material part G^T Dbar G per element, the geometric part per mesh edge and the nodal
        1/2 adt(r) (module docstring).

        stress: independent element stresses (m, 24) for the geometric part of the tangent (the
        mixed iteration of Magisano, Leonetti and Garcea 2017: the edge blocks and 1/2 adt(r)
        see the forces of these stresses); the residual stays Dbar (z(g) - z0)'s.  The
        evaluation's ``stress`` is Dbar (z(g) - z0) (m, 24)."""
        mesh = self.mesh
        En = mesh.edge_nodes
        h = _relative_frames(self.frames(g), En, self.matching)
        psi = _checked_log(h, En, mesh=mesh)
        Lp, Lm = lie.dexp_inv(psi, both=True)                          # L(psi), L(-psi)
        Lb = self._matched_L(Lp)                                       # node b's (Cuts)
        z = self._element_z(0.5 * psi)
        dz = z - self.z0
        f = np.einsum("mij,mj->mi", self.Dbar, dz)                      # dPi/dz_elem
        energy = 0.5 * np.einsum("mi,mi->", dz, f)
        sgn = mesh.elem_edge_sign
        nE = len(En)
        F = self._edge_forces(f)                                       # conjugate to mesh-edge z
        r = self._to_user(self._nodal_forces(F, Lb, Lm))
        # size of the terms that cancel in Dbar (z - z0): the residual's round-off floor
        fz = f + self.Dz0
        fscale = np.sqrt(np.einsum("mi,mi->", fz, fz) + np.einsum("mi,mi->", f, f))
        if not tangent:
            return ElementEvaluation(energy, r, fscale, stress=f)
        r_geo = r
        if stress is not None:                 # mixed iteration: geometric part from the stresses
            F = self._edge_forces(np.asarray(stress, float).reshape(-1, 24))
            r_geo = self._to_user(self._nodal_forces(F, Lb, Lm))
        # blocks of CHUNK elements/edges (a loop over ~n/2048 blocks, not over elements)
        m_el = mesh.n_elements
        pos = sgn > 0
        eid = mesh.elem_edges
        Ke = np.empty((m_el, 4, 4, 6, 6))
        G = np.zeros((min(CHUNK, m_el), 4, 6, 4, 6))                    # (edge, comp, node, comp)
        for s in range(0, m_el, CHUNK):
            e = min(s + CHUNK, m_el)
            c = e - s
            Gc = G[:c]
            Gc[:] = 0.0
            ids, pp = eid[s:e], pos[s:e, :, None, None]
            Lloc_p = np.where(pp, Lb[ids], Lm[ids])                     # L(psi_local)
            Lloc_m = np.where(pp, Lm[ids], Lb[ids])                     # L(-psi_local)
            for k, (la, lb) in enumerate(LOCAL_EDGES):
                Gc[:, k, :, la, :] = -0.5 * Lloc_m[:, k]
                Gc[:, k, :, lb, :] = 0.5 * Lloc_p[:, k]
            G2 = Gc.reshape(c, 24, 24)
            # material part G^T Dbar G, G = d z_elem / d eta_nodes
            Kc = np.swapaxes(G2, 1, 2) @ (self.Dbar[s:e] @ G2)
            Ke[s:e] = Kc.reshape(c, 4, 6, 4, 6).transpose(0, 1, 3, 2, 4)

        # geometric part per mesh edge: Hessian of F . z_E(eta)
        KE = np.empty((nE, 2, 2, 6, 6))
        I6 = np.eye(6)
        for s in range(0, nE, CHUNK):
            e = min(s + CHUNK, nE)
            c = e - s
            ps, Fs, Lps, Lms = psi[s:e], F[s:e], Lp[s:e], Lm[s:e]
            p = np.einsum("eji,ej->ei", Lps, Fs)                        # L(psi)^T F
            Jm = _dexp_inv_jacobian_T(ps, Fs)
            AdI = lie.Ad(lie.inv(h[s:e]))                                # Ad_{h^-1} = Ad_{exp(-psi)}
            M = np.concatenate([-AdI, np.broadcast_to(I6, AdI.shape)], axis=2)   # (c,6,12)
            N = np.concatenate([-Lms, Lps], axis=2)                              # (c,6,12)
            A = np.swapaxes(M, 1, 2) @ Jm @ N
            H = 0.25 * (A + np.swapaxes(A, 1, 2))
            Hba = -0.25 * lie.adt(p) @ AdI
            H[:, 6:, :6] += Hba
            H[:, :6, 6:] += np.swapaxes(Hba, 1, 2)
            KE[s:e] = H.reshape(c, 2, 6, 2, 6).transpose(0, 1, 3, 2, 4)

        # derivative of the left-trivialised gradient along exp updates (user's frames)
        Ke, KE = self._blocks_to_user(Ke, self._matched_blocks(KE))
        Kn = 0.5 * lie.adt(r_geo)
        return ElementEvaluation(energy, r, fscale, Ke, KE, Kn, stress=f, linearization=(Lb, Lm, dz))


#: phi^3 L / h above which a mesh is "coarse, thin and curved" (warn_if_coarse_thin_curved)
COARSE_THIN_CURVED = 2.0


def free_edge_layer_width(index, size):
    """The narrowest free-edge layer the flagged elements imply, or None if none is flagged.

    An element's coarse-curvature index phi^3 L / h (``index``, (m,)) is (L / l)^4 with
    l = R (h/R)^(1/4) the width of the layers in which a membrane-dominated shell bends along
    its free edges and R = L / phi, so l = L index^(-1/4) (``size`` (m,) = L = sqrt(area)); on
    the roof's elements, whose circumferential width b sets the layer, this is l (L / b)^(3/4),
    about 1.14 l (docs/ELEMENTS.md, "Graded meshes").

    Example
    -------
    >>> round(free_edge_layer_width(np.array([1.0, 16.0]), np.array([1.0, 2.0])), 12)
    1.0
    >>> free_edge_layer_width(np.array([1.0]), np.array([1.0])) is None
    True
    """
    flagged = np.asarray(index) > COARSE_THIN_CURVED
    if not flagged.any():
        return None
    return float(np.min(np.asarray(size)[flagged] * np.asarray(index)[flagged] ** -0.25))


def warn_if_coarse_thin_curved(index, size=None, stacklevel=2, note=""):
    """An ElementWarning when an element's phi^3 L / h (``index``, (m,): phi its reference edges'
    largest out-of-plane turn [rad], L = sqrt(area) (``size``, (m,), optional), h the law's
    thickness) exceeds COARSE_THIN_CURVED; ``note``: a sentence appended to its text (where a
    design met it, ``design.equilibrium.ElementCheck``).

    ``Problem.check_element`` calls it, when it solves, with the index of the elements along free
    edges only (a boundary edge with a node whose translation nothing holds; the others' index 0): there
    the four-node mesh of a membrane-dominated shell can be spuriously flexible, the edge tying
    leaving free-edge mechanisms of bending-order stiffness (docs/ELEMENTS.md, "The coarse thin
    roof").  With R = L / phi the radius the edge turn implies, the index is (L / l)^4,
    l = R (h/R)^(1/4) the width of the layers in which such a shell bends along its free edges:
    the element is wider than the layer it should carry (on the roof sweep every cell with
    b / l >= 1.16 fails and every cell with b / l <= 1.10 but one passes; the one, 2x2 at R/h 100,
    1.024, passed at 1.019 before the area loads took the element's own area element, when its
    load was 0.5 % short; benchmarks/results/roof_layer.md).  Measured on the Scordelis-Lo roof
    over its 64x64 value: 1.033 and 1.034 at phi^3 L / h = 3.5 and 2.2, 1.005 and 1.024 at 1.4 and
    1.8, 111 at 1800.  Bending-dominated shells (the pinched
    hemisphere: within 0.8 ... 1.02 up to 2.8e4) are not affected, so it is a warning to check
    convergence, not an error.  With ``size`` it also gives the layer's width
    l = L index^(-1/4) (the smallest over the flagged elements) and the remedy that keeps the
    element count: a mesh graded toward the free edges, the elements along them about 0.7 l wide,
    growing by at most 1.7 (``[mesh] grade``, mesh.generators.spacing; on the roof sweep every
    such cell is in band, the coarsest cells need a steeper growth and are erratic:
    benchmarks/results/roof_layer.md).

    Example
    -------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_if_coarse_thin_curved(np.array([0.5, 35.0]))
    >>> "phi^3 L / h = 35" in str(w[0].message)
    True
    """
    worst = float(np.max(index, initial=0.0))
    if worst > COARSE_THIN_CURVED:
        layer = "" if size is None else (
            f" Along free edges such a shell bends in a layer about l = L (phi^3 L / h)^(-1/4) = "
            f"{free_edge_layer_width(index, size):.3g} wide here; to resolve it "
            f"without many more elements, grade the mesh toward its free edges so that the elements along them "
            f"are about 0.7 l wide and their neighbours grow by at most 1.7 (`[mesh] grade = {{x1 = FRACTION}}` of "
            f"a structured generator; fewer elements than that growth needs cannot carry the layer).")
        warnings.warn(ElementWarning(
            f"coarse mesh of a thin curved shell: an element along a free edge turns by phi out of its plane "
            f"with phi^3 L / h = {worst:.3g} > {COARSE_THIN_CURVED:g} (L its size, h the thickness) on "
            f"{int(np.sum(index > COARSE_THIN_CURVED))} element(s). Where the shell is membrane dominated, "
            f"four-node meshes this coarse along a free edge (a boundary edge whose translations no support holds) "
            f"can be far off: "
            f"spuriously flexible (the Scordelis-Lo roof 2x2 at R/h 1e4: 10.9 times its deflection) or too stiff "
            f"(a pressurised hemisphere with a free equator, 4x4 at R/h 1e3: 0.68 of its largest displacement); "
            f"bending-dominated shells are not affected. Check by refining: `core-se3 check-mesh SCENARIO.toml` "
            f"(scenario.check_mesh) compares the linear answer with a refined mesh's (each halving of the "
            f"element size divides phi^3 L by 16) -- docs/ELEMENTS.md." + layer + (" " + note if note else "")),
        stacklevel=stacklevel + 1)

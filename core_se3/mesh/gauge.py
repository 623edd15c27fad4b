"""The least-turn gauge of the nodal frames: the turns about the normal that the element adds to
the user's frames so that neighbouring frames turn as little as possible about the normal.

Why.  The default element's edge twists are each constant in their own geodesic's frame, and its
tying averages the twists of opposite edges (``fem.element_default``).  Where the nodal frames turn
about the normal from node to node, those frames differ by the turn and the average is off by it:
the membrane patch test on MacNeal and Harder's patch with random nodal turns up to 0.1 rad errs by
7e-2 of the strain, exactly in proportion to the turn, and the annulus generator's radial frames
over 1 rad by 2.6e-2 on 3x3 (docs/ELEMENTS.md, "Nodal frames").  A turn about the normal is a
choice of the user (which in-plane direction d1 is), not of the shell.  So an in-plane isotropic
law's element is built on the frames g0 Rz(alpha): alpha (n,) about each node's own normal d3,
chosen so that neighbouring frames turn least, and the element's forces and tangent are carried
back to the user's frames by constant rotations (``fem.element_default``).

The angles.  omega_ab is the turn of the relative rotation R_a^T R_b about the mean normal of an
edge a -> b (``normal_turns``).  Turning the frames by alpha changes it, to first order, to
omega_ab + alpha_b - alpha_a, and the gauge is the least-squares solution

    min_alpha sum over the mesh edges (omega_ab + alpha_b - alpha_a)^2,

a graph-Laplacian system (one node of every connected part held at 0, then each part's angles
shifted to mean 0), repeated with the turned frames (Gauss-Newton, at most ``GAUGE_ITERATIONS``).  On a
flat mesh the turns commute and the first solve leaves every edge without turn (to round-off):
the patch tests pass whatever the user's frames.  On a curved surface the frames cannot be
parallel (the turn about the normal around an element is its area times the Gaussian curvature),
and the least squares would spread that holonomy (the quarter
hemisphere's largest edge turn 0.374 / 0.187 / 0.093 rad on 4x4 / 8x8 / 16x16 to 0.129 / 0.070 /
0.037), but where the turn cannot vanish its arrangement matters: spread by the least squares, the
pinched hemisphere's odd meshes lock at R/h 1e5 (3x3: 0.31 of the converged deflection, against
0.998 on the generator's meridian frames, an arrangement that follows the shell's symmetry) while
R/h 10 gains (4x4: 0.925 -> 0.939).  So a connected part on which the gauge leaves an edge turning
by more than ``PARALLEL_TOL`` (a doubly curved surface) keeps the user's frames: the gauge is
exact or absent.  Flat and developable parts (plates, annuli, cylinders and cones, whatever the
user's d1) get it; where no edge turns by more than ``GAUGE_TOL`` (rectangles, cylinder panels,
any mesh of frames alike) the angles are exactly 0 and the element is built on the user's frames
unchanged.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

__all__ = ["normal_turns", "least_turn_angles", "least_turn_gauge", "turned_about_normal", "GAUGE_TOL", "GAUGE_ITERATIONS",
           "PARALLEL_TOL", "quarter_turns", "edge_matching", "corner_turns"]

#: edges turning less than this about the normal [rad] need no gauge (patch-test error ~0.7 x turn)
GAUGE_TOL = 1e-10
#: the most Gauss-Newton passes of the least-squares angles (flat meshes: exact after the first,
#: developable ones (a cylinder with d1 at random within 0.7 rad) to 1e-14 rad after 5)
GAUGE_ITERATIONS = 8
#: the largest turn [rad] the gauge may leave on an edge of a part: above it the part is doubly
#: curved (its frames cannot be parallel) and keeps the user's frames (module docstring)
PARALLEL_TOL = 1e-8


def normal_turns(g0, edge_nodes):
    """omega (E,): the turn [rad] of each edge's relative rotation R_a^T R_b about the mean of its
    end normals (d3 of a and of b, in a's frame).

    Parameters
    ----------
    g0 : (n, 4, 4) array
        Nodal frames.
    edge_nodes : (E, 2) array of int
        The edges (a, b).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.annulus(1.0, 2.0, 1.0, 1, 2)              # radial d1: turns 0.5 rad per element
    >>> np.round(normal_turns(m.g0, m.edge_nodes), 12).tolist()
    [0.0, 0.5, 0.5, 0.0, 0.5, 0.5, 0.0]
    """
    from ..lie import log_so3
    Ra, Rb = g0[edge_nodes[:, 0], :3, :3], g0[edge_nodes[:, 1], :3, :3]
    w = log_so3(np.einsum("eji,ejk->eik", Ra, Rb))
    n = np.einsum("eji,ej->ei", Ra, Rb[:, :, 2])              # b's normal in a's frame
    n[:, 2] += 1.0
    n /= np.linalg.norm(n, axis=1)[:, None]
    return np.einsum("ei,ei->e", w, n)


def turned_about_normal(g0, alpha):
    """g0 Rz(alpha) (n, 4, 4): the frames turned about their own normals d3 by alpha (n,) [rad].

    Example
    -------
    >>> import numpy as np
    >>> g = turned_about_normal(np.eye(4)[None], np.array([np.pi / 2]))
    >>> np.round(g[0, :3, 0], 12).tolist()                   # d1 turned onto y
    [0.0, 1.0, 0.0]
    """
    c, s = np.cos(alpha), np.sin(alpha)
    Q = np.zeros((len(alpha), 4, 4))
    Q[:, 0, 0], Q[:, 0, 1], Q[:, 1, 0], Q[:, 1, 1] = c, -s, s, c
    Q[:, 2, 2] = Q[:, 3, 3] = 1.0
    return g0 @ Q


def least_turn_angles(g0, edge_nodes):
    """alpha (n,): the least-squares turns about the nodal normals that leave neighbouring frames
    turning least about the normal (module docstring); exactly 0 where no edge turns by more
    than GAUGE_TOL.

    Parameters
    ----------
    g0 : (n, 4, 4) array
        Nodal frames.
    edge_nodes : (E, 2) array of int
        The mesh edges.

    Returns
    -------
    (n,) ndarray
        Angles [rad] about each node's d3, mean 0 over each connected part of the mesh.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.annulus(1.0, 2.0, 1.0, 2, 4)
    >>> a = least_turn_angles(m.g0, m.edge_nodes)
    >>> float(np.abs(normal_turns(turned_about_normal(m.g0, a), m.edge_nodes)).max()) < 1e-14
    True
    >>> bool(least_turn_angles(mesh.rectangle(1.0, 1.0, 2, 2).g0, mesh.rectangle(1.0, 1.0, 2, 2).edge_nodes).any())
    False
    """
    return least_turn_gauge(g0, edge_nodes)[0]


def least_turn_gauge(g0, edge_nodes):
    """The gauge angles of :func:`least_turn_angles` and which nodes lie on a doubly curved part
    (one whose frames the gauge cannot make parallel: it keeps the user's frames, angles 0).

    Parameters
    ----------
    g0 : (n, 4, 4) array
        Nodal frames.
    edge_nodes : (E, 2) array of int
        The mesh edges.

    Returns
    -------
    alpha : (n,) ndarray
        :func:`least_turn_angles`.
    curved : (n,) ndarray of bool
        The nodes of the connected parts on which the gauge would leave a turn above PARALLEL_TOL.

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.hemisphere_quarter(10.0, 18.0, 2, 2)
    >>> bool(least_turn_gauge(m.g0, m.edge_nodes)[1].all())
    True
    """
    n, E = len(g0), len(edge_nodes)
    alpha = np.zeros(n)
    omega = normal_turns(g0, edge_nodes)
    if E == 0 or np.abs(omega).max() <= GAUGE_TOL:
        return alpha, np.zeros(n, bool)
    rows = np.repeat(np.arange(E), 2)
    B = sp.csr_matrix((np.tile([-1.0, 1.0], E), (rows, edge_nodes.ravel())), shape=(E, n))
    n_parts, part = connected_components(B.T @ B, directed=False)
    held = np.unique(part, return_index=True)[1]               # the first node of every part
    free = np.setdiff1d(np.arange(n), held)
    # the graph Laplacian with one node of each part held, factorised once (every part with an
    # edge has a free node); each pass solves with it
    lu = splu((B.T @ B).tocsr()[free][:, free].tocsc())
    for _ in range(GAUGE_ITERATIONS):          # until the turns stop falling (or vanish)
        step = lu.solve((B.T @ omega)[free])
        alpha[free] -= step
        omega = normal_turns(turned_about_normal(g0, alpha), edge_nodes)
        if np.abs(step).max() <= GAUGE_TOL:
            break
    alpha -= (np.bincount(part, weights=alpha, minlength=n_parts) / np.bincount(part, minlength=n_parts))[part]
    # a part whose frames cannot all be made parallel (doubly curved) keeps the user's frames
    left = np.zeros(n_parts)
    np.maximum.at(left, part[edge_nodes[:, 0]], np.abs(omega))
    curved = left[part] > PARALLEL_TOL
    alpha[curved] = 0.0
    return alpha, curved


# ------------------------------------------------------------------------------------------
# Quarter-turn matchings across the cuts of a cross field
# ------------------------------------------------------------------------------------------
#: cos and sin of k quarter turns, exactly (k = 0, 1, 2, 3)
_QC, _QS = np.array([1.0, 0.0, -1.0, 0.0]), np.array([0.0, 1.0, 0.0, -1.0])


def quarter_turns(k):
    """Rz(k pi/2) (..., 3, 3) of integers k, exact (entries 0, 1, -1).

    Example
    -------
    >>> quarter_turns(1)[:2, :2].tolist()
    [[0.0, -1.0], [1.0, 0.0]]
    """
    k = np.asarray(k) % 4
    R = np.zeros(k.shape + (3, 3))
    R[..., 0, 0] = R[..., 1, 1] = _QC[k]
    R[..., 1, 0], R[..., 0, 1] = _QS[k], -_QS[k]
    R[..., 2, 2] = 1.0
    return R


def edge_matching(g0, edge_nodes):
    """k (E,) int in {0, 1, 2, 3}: the quarter turn Rz(k pi/2), on the right of b's frame, that
    leaves the least turn about the normal between the frames of each edge (a, b), or None where
    every k is 0 (every mesh whose neighbouring d1 turn by less than 45 deg: no cut).

    A 4-fold direction field (``mesh.cross_field``, a mesh file's default frames) has no single
    d1 on a closed or branched surface (a sphere: hairy ball): its d1 jumps by quarter turns
    across cuts, and an edge across one is taken between g_a and g_b Rz(k pi/2) (the element:
    ``fem.element_default``, "Cuts").  The turn is the angle of b's d1 in a's tangent basis.

    Example
    -------
    >>> import numpy as np
    >>> g = np.stack([np.eye(4), np.eye(4)]); g[1, :3, :3] = quarter_turns(3)   # b's d1 along -y
    >>> edge_matching(g, np.array([[0, 1]])).tolist()
    [1]
    >>> edge_matching(g[[0, 0]], np.array([[0, 1]])) is None
    True
    """
    Ra, Rb = g0[edge_nodes[:, 0], :3, :3], g0[edge_nodes[:, 1], :3, :3]
    d1 = np.einsum("eji,ej->ei", Ra, Rb[:, :, 0])             # b's d1 in a's frame
    k = (-np.rint(np.arctan2(d1[:, 1], d1[:, 0]) / (0.5 * np.pi)).astype(np.int64)) % 4
    return k if k.any() else None


def corner_turns(g0, quads):
    """q (m, 4) int: the quarter turns Rz(q pi/2) of every element's nodal frames (g_i Rz(q_i pi/2))
    that leave each least turned about the normal from its element's first node's: the frames in
    which the element compares its edge twists across a cross field's cuts
    (``fem.element_default``, "Cuts").

    Where the edges' quarter-turn matchings (:func:`edge_matching`) close round an element (its
    d1 has no singular point inside) these are the matchings' turns along its edges whenever its
    frames turn by less than 45 deg from its first node's; round an element where they do not
    close (a cross field's singular node, whose quarter turn of d1 shows in one of the elements
    round it: a closed cubed sphere's valence-3 corners), each node takes the least turn.

    Example
    -------
    >>> import numpy as np
    >>> g = np.repeat(np.eye(4)[None], 4, axis=0)
    >>> g[2, :3, :3] = quarter_turns(1)                       # node 2's d1 along y
    >>> corner_turns(g, np.array([[0, 1, 2, 3]])).tolist()
    [[0, 0, 3, 0]]
    """
    R = g0[quads, :3, :3]                                     # (m, 4, 3, 3)
    d1 = np.einsum("mji,mnj->mni", R[:, 0], R[:, :, :, 0])    # each node's d1 in the first node's frame
    return (-np.rint(np.arctan2(d1[..., 1], d1[..., 0]) / (0.5 * np.pi)).astype(np.int64)) % 4

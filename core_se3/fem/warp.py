"""Warped quads: the check of a quad's warp against the curvature its nodes' normals show (issue 30,
doubly curved shells).

Why.  A quad whose four nodes are not coplanar is natural on a curved shell: on a smooth surface
the bilinear quad's twist x_xieta = (P0 - P1 + P2 - P3) / 4 has the normal component
x_xieta . n = -(x_xi . n_eta + x_eta . n_xi) / 2 (differentiate x_xi . n = 0), which the nodes'
normals d3 give (their differences along the quad's sides).  The element joins its nodes by the
helices of their frames, so it sees the shell the frames describe; a warp the normals do not
explain (a twisted or folded quad, nodes moved off a surface whose normals stayed, a file's
normals that cannot follow nodal-scale bumps) is a reference geometry the helices do not have.
Measured (linear, a hyperbolic paraboloid z = c x y, 1 x 1, h 0.01, clamped on one side, a tip
force; over its 32 x 32 with exact normals): with the exact normals the warp explained to 0.015
of the quad's size and the answer that of a coarse mesh (c = 2, 2 x 2: warp 0.18 of the size,
0.97; c = 4, 2 x 2: 0.72); with the normals left along z (the warp unexplained), at 0.06 of the
size as with the exact ones (0.94 / 0.98 on two meshes), at 0.11 0.90 / 0.94 (exact normals 0.95 /
0.98), at 0.18 0.47 / 0.72 (0.97 / 0.94), at 0.22 0.22 (0.72).  A flat plate whose interior nodes
are moved off its plane at random (normals along z; read from a file about the same) at an
unexplained warp of 0.02 / 0.07 / 0.20 of the size came out 0.96 / 0.77 / 0.45 of the flat one
(8 x 8, h 0.01, edges held, pressed; at h 0.1: 1.000 / 1.000 / 1.006, so part of it is the bumps' own stiffness).
Every catalogue case's mesh, the generators' (hemisphere, cylinders, Scordelis-Lo, the twisted
beam: warp 0.024 of the size on 12 x 2, 0.049 on 6 x 1, all explained to 3e-4), the closed
cubed sphere, the cubed cap, the whole and the moved-node quarter hemisphere from files and
Gmsh's unstructured domes have an unexplained warp of at most 0.0125 of the size (the quarter
with nodes moved by 0.3 of the spacing, 4 x 4); the twisted beam twisted by 720 deg instead of 90
on 12 x 2, warped by 0.19 of the size, 0.015 (its tip 0.947 of its 96 x 8's: a coarse mesh's).

The check (at the element's build, :func:`check_warp`): an element whose unexplained warp is
above WARN_WARP = 0.05 of its size (four times the most of the meshes above; below where the
paraboloid's answer moved) is an ElementWarning naming it with the measured value.  No error:
the answers of such meshes are not wrong everywhere (the thick bumpy plate above).
"""
from __future__ import annotations

import warnings

import numpy as np

from ..errors import ElementWarning

__all__ = ["quad_warp", "check_warp", "WARN_WARP", "chord_normal_mismatch", "check_chord_normals", "CHORD_NORMAL_FLOOR",
           "CHORD_NORMAL_TURN", "CHORD_NORMAL_CURVED", "MAX_EDGE_NORMAL_TURN", "chord_normal_bar"]

#: the unexplained warp [over the quad's size] above which the element warns
WARN_WARP = 0.05
#: the chord's component along its end normals' sum [over its length] above which an edge warns on
#: a flat or finely meshed shell (:func:`chord_normal_mismatch`) ...
CHORD_NORMAL_FLOOR = 0.02
#: ... plus this times the largest turn of the normals [rad] across the edges at its ends phi_ends
#: (a curvature that jumps inside the edge: a C1 junction of arcs of curvatures k1, -k2 gives
#: L (k1 + k2) / 4, Raasch's hook 96 x 32 0.032) ...
CHORD_NORMAL_TURN = 0.25
#: ... plus this times phi_ends^2 (a smooth surface's O((L/R)^2) term: docs/ELEMENTS.md, "Nodal
#: normals against the positions")
CHORD_NORMAL_CURVED = 0.5
#: [deg] normals turning by more than this across one edge warn (a node's normal flipped)
MAX_EDGE_NORMAL_TURN = 120.0


def quad_warp(X, quads, g):
    """The warp of each quad (normal component of its bilinear twist, over the square root of its
    area) and the part of it its nodes' normals do not explain (module docstring), (m,) each.

    Parameters
    ----------
    X : (n, 3) array
        Reference positions.
    quads : (m, 4) array of int
        The elements' nodes, in order round each quad.
    g : (n, 4, 4) array
        The frames (their d3: the normals).

    Returns
    -------
    warp, unexplained : (m,) ndarray
        Over the quad's size.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> m.X[3, 2] = 0.2                              # a corner lifted, the normals left along z
    >>> [round(float(w), 3) for w in np.concatenate(quad_warp(m.X, m.quads, m.g0))]
    [0.049, 0.049]
    """
    P = np.asarray(X, float)[quads]
    N = np.asarray(g, float)[quads][:, :, :3, 2]
    twist = (P[:, 0] - P[:, 1] + P[:, 2] - P[:, 3]) / 4.0
    n = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])
    size = np.sqrt(0.5 * np.linalg.norm(n, axis=1))
    n /= np.maximum(2.0 * size ** 2, 1e-300)[:, None]
    sides = np.array([[-1.0, 1.0, 1.0, -1.0], [-1.0, -1.0, 1.0, 1.0]]) / 4.0    # d/dxi, d/deta at the centre
    xs, xe = np.einsum("k,mki->mi", sides[0], P), np.einsum("k,mki->mi", sides[1], P)
    ns, ne = np.einsum("k,mki->mi", sides[0], N), np.einsum("k,mki->mi", sides[1], N)
    w = np.einsum("mi,mi->m", twist, n)
    explained = -0.5 * (np.einsum("mi,mi->m", xs, ne) + np.einsum("mi,mi->m", xe, ns))
    size = np.maximum(size, 1e-300)
    return np.abs(w) / size, np.abs(w - explained) / size


def check_warp(X, quads, g, stacklevel=3, ids=None):
    """ElementWarning for elements warped by more than their nodes' normals explain (module
    docstring).

    Parameters
    ----------
    X : (n, 3) array
        Reference positions.
    quads : (m, 4) array of int
        The elements' nodes.
    g : (n, 4, 4) array
        The frames the element builds on (their normals).
    stacklevel : int
        The warning's.
    ids : (elements (m,), nodes (n,)) arrays of int, optional
        The ids to name them by (a rank's part: the whole mesh's, ``Mesh.whole_ids``).

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.hemisphere_quarter(10.0, 18.0, 2, 2)
    >>> check_warp(m.X, m.quads, m.g0)                    # silent
    """
    warp, bad_warp = quad_warp(X, quads, g)
    bad = np.flatnonzero(bad_warp > WARN_WARP)
    if not len(bad):
        return
    k = int(bad[np.argmax(bad_warp[bad])])
    el, nd = ids if ids is not None else (np.arange(len(quads)), np.arange(len(X)))
    warnings.warn(ElementWarning(
        f"{len(bad)} element(s) (e.g. {el[bad[:5]].tolist()}) are warped (their nodes not in a plane) by more than "
        f"their nodes' normals d3 explain: element {int(el[k])} (nodes {nd[np.asarray(quads)[k]].tolist()}) by "
        f"{bad_warp[k]:.3f} of its size (its warp {warp[k]:.3f}), above {WARN_WARP:g} (a curved shell's quads "
        "with its normals: below 0.015); the element sees the shell its frames describe, and the answer depends "
        "on it there (a twisted plate with its normals left flat: 0.47 of the answer at 0.18) -- give the "
        "nodes' normals of the surface through them (Mesh(g0=...), mesh.frames_from; a file's are fitted to "
        "its nodes), or nodes on the surface the normals describe"), stacklevel=stacklevel)


def chord_normal_mismatch(X, edge_nodes, g):
    """The mismatch of each mesh edge's chord with its end normals (E,) each: the chord's component
    along the normals' sum mu = |c . (n_a + n_b)| / |c| (c = X_b - X_a), the normals' turn across
    the edge phi = acos(n_a . n_b) [rad], and the largest phi of the edges at its two ends.

    On a smooth surface through the nodes with its normals, along the edge's curve of arc length
    L (Darboux frame: normal curvature k_n, geodesic curvature k_g, geodesic torsion t_g, at the
    edge's middle) mu = L^2 |k_n' / 6 - k_g t_g / 3| + O(L^4): exactly 0 on spheres, circles and
    cylinders (n = (X - centre) / R makes c . (n_a + n_b) = (|X_b - C|^2 - |X_a - C|^2) / R),
    L^2 k^3 b / (3 (1 + k^2 b^2)) along a helicoid's helix at distance b (twist rate k); normals
    tilted by delta from the surface's give mu of order delta on any mesh.

    Parameters
    ----------
    X : (n, 3) array
        Reference positions.
    edge_nodes : (E, 2) array of int
        The mesh edges (``Mesh.edge_nodes``).
    g : (n, 4, 4) array
        The frames (their d3: the normals).

    Returns
    -------
    mu, phi, phi_ends : (E,) ndarray
        mu over the chord's length (dimensionless), the turns [rad].

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(2.0, 2.0, 2, 2, x0=-1.0)
    >>> bent = mesh.frames_from(m.X, np.tile([1.0, 0, 0], (9, 1)), m.X + [0, 0, 10.0])  # a sphere's normals
    >>> round(float(chord_normal_mismatch(m.X, m.edge_nodes, bent)[0].max()), 4)
    0.0995
    """
    X, g = np.asarray(X, float), np.asarray(g, float)
    a, b = np.asarray(edge_nodes)[:, 0], np.asarray(edge_nodes)[:, 1]
    c = X[b] - X[a]
    na, nb = g[a, :3, 2], g[b, :3, 2]
    mu = np.abs(np.einsum("ei,ei->e", c, na + nb)) / np.maximum(np.linalg.norm(c, axis=1), 1e-300)
    phi = np.arccos(np.clip(np.einsum("ei,ei->e", na, nb), -1.0, 1.0))
    node = np.zeros(len(X))
    np.maximum.at(node, a, phi)
    np.maximum.at(node, b, phi)
    return mu, phi, np.maximum(node[a], node[b])


def chord_normal_bar(phi_ends):
    """The chord-normal mismatch above which an edge warns: CHORD_NORMAL_FLOOR + CHORD_NORMAL_TURN
    phi_ends + CHORD_NORMAL_CURVED phi_ends^2, phi_ends [rad] the largest normal turn across the
    edges at its two nodes (:func:`chord_normal_mismatch`).

    Example
    -------
    >>> round(float(chord_normal_bar(0.2)), 4)
    0.09
    """
    return CHORD_NORMAL_FLOOR + CHORD_NORMAL_TURN * phi_ends + CHORD_NORMAL_CURVED * np.square(phi_ends)


def check_chord_normals(mesh, stacklevel=3, ids=None):
    """ElementWarning for edges whose end normals contradict their chord: mu above
    :func:`chord_normal_bar` (phi_ends) (:func:`chord_normal_mismatch`), or normals turning by more
    than MAX_EDGE_NORMAL_TURN across the edge.  The element joins its nodes by the helices of their
    frames and sees the shell the frames describe, not the one through the nodes: a flat 2 x 2
    plate (8 x 8 elements, edges pinned, pressed, h 0.005) given a sphere's normals of curvature
    0.1 / 0.3 (mu 0.17 / 0.51) came out 0.85 / 0.45 of the flat plate's deflection (h 0.001: 0.26 /
    0.08), solved and silent (docs/ELEMENTS.md, "Nodal normals against the positions").

    Parameters
    ----------
    mesh : core_se3.mesh.Mesh
        The mesh (its positions, edges, elements' edges and frames g0).
    stacklevel : int
        The warning's.
    ids : (elements (m,), nodes (n,)) arrays of int, optional
        The ids to name them by (a rank's part: the whole mesh's, ``Mesh.whole_ids``); else a mesh
        file's point ids where its reader renumbered them (``mesh.dropped_points``).

    Example
    -------
    >>> from core_se3 import mesh
    >>> check_chord_normals(mesh.hemisphere_quarter(10.0, 18.0, 2, 2))      # silent
    """
    mu, phi, ends = chord_normal_mismatch(mesh.X, mesh.edge_nodes, mesh.g0)
    bar = chord_normal_bar(ends)
    flip = phi > np.radians(MAX_EDGE_NORMAL_TURN)
    bad = np.flatnonzero((mu > bar) | flip)
    if not len(bad):
        return
    el, nd = ids if ids is not None else (np.arange(mesh.n_elements), _file_points(mesh))
    e = int(bad[np.argmax(np.where(flip[bad], np.inf, mu[bad] / bar[bad]))])
    edges = [tuple(nd[mesh.edge_nodes[k]].tolist()) for k in bad[:5]]
    near = np.flatnonzero(np.isin(mesh.elem_edges, bad).any(1))
    where = (f"{len(bad)} edge(s) (nodes {edges}{' ...' if len(bad) > 5 else ''}; elements "
             f"{el[near[:5]].tolist()}{' ...' if len(near) > 5 else ''})")
    at = f"edge {tuple(nd[mesh.edge_nodes[e]].tolist())} (element(s) {el[np.flatnonzero((mesh.elem_edges == e).any(1))].tolist()})"
    if flip[e]:
        what = (f"the nodes' normals d3 turn by more than {MAX_EDGE_NORMAL_TURN:g} deg across {where}: {at} by "
                f"{np.degrees(phi[e]):.0f} deg -- a node's normal flipped to the other side of the shell")
    else:
        what = (f"the nodes' normals d3 contradict the positions along {where}: {at}'s chord c has "
                f"|c . (n_a + n_b)| / |c| = {mu[e]:.3g}, above {bar[e]:.3g} ({CHORD_NORMAL_FLOOR:g} + "
                f"{CHORD_NORMAL_TURN:g} t + {CHORD_NORMAL_CURVED:g} t^2, t = {ends[e]:.3g} rad the normals' largest turn "
                "across an edge there; the normals of a smooth surface through the nodes give 0 on spheres and "
                "cylinders and at most 0.64 of the bar on the meshes measured)")
    warnings.warn(ElementWarning(
        f"{what}. The element joins the nodes by the helices of their frames and sees the shell the frames "
        "describe, not the one through the nodes (a flat plate given a sphere's normals of curvature 0.3, pressed: 0.45 "
        "of its deflection at L/h 400). Likely: normals given for another surface (or kept when the nodes were moved), a frame "
        "field rotated or mirrored against the positions, positions transformed without their frames (an axis "
        "scaled, other units along one axis); a fold (crease) between faces, which one normal per node rounds over "
        "the elements at it (an L angle read from a file: 0.71); a mesh file's normals at the boundary of a doubly "
        "curved part of unequal curvatures (fitted with one curvature there: an ellipsoid's cap 4 x 4 13 deg off, "
        "8 x 8 4 deg). Fix: give d3 the normal of the surface through the nodes "
        "(Mesh(g0=mesh.frames_from(X, d1, d3)) with the surface's normals; a mesh file read without frames gets "
        "normals fitted to its nodes; at a doubly curved boundary, refine there)"), stacklevel=stacklevel)


def _file_points(mesh):
    """The nodes' ids to show (n,): a mesh file's point ids where its reader dropped points that no quad
    uses and renumbered those after them (``mesh.dropped_points``), else the node ids."""
    dropped = getattr(mesh, "dropped_points", None)
    n = mesh.n_nodes
    return np.arange(n) if dropped is None else np.delete(np.arange(n + len(dropped)), dropped)

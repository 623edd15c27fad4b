"""Uniform refinement of a quad mesh on SE(3): every quad into four, the new frames on the
geodesics of the reference frames.

A new node at the middle of a mesh edge gets the midpoint of the SE(3) geodesic that joins the
frames of its two ends,

    g_m = g_a exp(log(g_a^-1 g_b) / 2),

which is the curve the default element itself takes for a reference edge (exact edge twists,
docs/ELEMENTS.md): a refined mesh is the coarse mesh's own geometry, sampled finer.  Where the
frames of neighbouring nodes differ by a rotation about a fixed axis (the generators' circles:
cylinders, arches, annuli, the hemisphere's parallels and meridians; identical frames on a
straight edge) the geodesic is that circle or line, so the new nodes lie on the surface exactly.
A quad's centre node is the geodesic midpoint of the two midpoints of its opposite edge pairs
(each pair joined by its own geodesic).  Across a cross field's cuts (a mesh file's default
frames on a closed surface, whose d1 jump by quarter turns: ``mesh.gauge.edge_matching``) the
far frame is taken turned by the quarter turn that leaves it least turned about the normal, as
the element takes it (``fem.element_default``, "Cuts"): the geodesic of frames a quarter or half
turn apart is a helix off the surface (before, refining the closed cubed sphere from a file made
quads that "are degenerate, non-convex or listed clockwise", a MeshError, so ``check-mesh``
could not run on it).  Where no edge jumps (every generator's mesh) nothing changes.

Frames that turn about the normal.  The geodesics are those of the user's frames, not of the
least-turn gauge's (``mesh.gauge``, the frames the element builds on for an in-plane isotropic
law, parallel on flat and developable parts): a turn of d1 about the normal from node to node
is read as a curved edge.  That is what reproduces the annulus generator's circles from its
radial d1 (the gauge's frames would put its new nodes on the chords: 2 x 3 refined twice,
0.028 off the circle); but a plate 2 x 1 (4 x 2) whose d1 is turned at random by up to 0.5 rad gets new nodes
0.048 off its grid (spacing 0.5) and off its free edge, and a refined tip deflection 10 % off
(0.3347 against 0.3043), a cylinder panel (d1 within 0.7 rad) new nodes 0.002 off its radius.
No rule from one edge tells the two apart; give d1 that follows the mesh lines (or is parallel)
before refining or running ``check-mesh``.

The old nodes keep their ids (the new ones follow: edge midpoints, then centres); element e's
children are 4e ... 4e + 3, so after k refinements the descendants of element e are the ids
4^k e ... 4^k (e + 1) - 1.  Named node sets that are lines (consecutive nodes joined by mesh
edges) get the midpoints between their nodes, in order (a closed loop its closing edge's too);
other named sets the new nodes they enclose (the midpoint of every element edge with both ends
in the set, the centre of every element with its four corners in it: several lines, a patch),
isolated nodes stay points; regions list the children of their elements.  ``carry_held`` gives
the same enclosed nodes for any selection of ids (what a support of them holds).
"""
from __future__ import annotations

import numpy as np

from .. import lie
from ..errors import MeshError
from .core import Mesh
from .gauge import edge_matching, quarter_turns

__all__ = ["refine", "refine_levels", "carry_nodes", "carry_held", "geodesic_midpoints", "descendants"]


def geodesic_midpoints(ga, gb):
    """Midpoints g_a exp(log(g_a^-1 g_b) / 2) of the SE(3) geodesics from ga to gb (..., 4, 4).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import lie
    >>> ga = np.eye(4)
    >>> gb = lie.exp([0.0, -np.pi / 2, 0.0, 0.0, 0.0, np.pi / 2])   # quarter turn about z through (1, 0, 0)
    >>> geodesic_midpoints(ga, gb)[:3, 3].round(12).tolist()          # on the unit circle about (1, 0, 0)
    [0.292893218813, -0.707106781187, 0.0]
    """
    ga, gb = np.asarray(ga, float), np.asarray(gb, float)
    rel = lie.log(lie.relative(ga, gb))
    return ga @ lie.exp(0.5 * rel)


def _matched(ga, gb):
    """gb (k, 4, 4) turned about its normals by the quarter turns that leave each least turned from
    ga (``mesh.gauge.edge_matching``: a cross field's cuts); gb itself where none is."""
    k = edge_matching(np.concatenate([ga, gb]), np.stack([np.arange(len(ga)), len(ga) + np.arange(len(ga))], 1))
    if k is None:
        return gb
    out = gb.copy()
    out[:, :3, :3] = gb[:, :3, :3] @ quarter_turns(k)
    return out


def descendants(elements, levels):
    """Element ids, after ``levels`` uniform refinements, of the descendants of ``elements``.

    Example
    -------
    >>> descendants([0, 2], 1).tolist()
    [0, 1, 2, 3, 8, 9, 10, 11]
    """
    e = np.asarray(elements, np.int64).ravel()
    k = 4 ** int(levels)
    return (k * e[:, None] + np.arange(k)).ravel()


def refine(mesh, levels=1):
    """The mesh refined ``levels`` times: every quad into four (module docstring).

    Parameters
    ----------
    mesh : Mesh
        The mesh (its named node sets and regions are carried over).
    levels : int
        Number of refinements (0: the mesh itself); each multiplies the elements by four.

    Returns
    -------
    Mesh
        The refined mesh (``shape`` None: its node numbering is not a structured grid's).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = refine(mesh.cylinder_panel(2.0, 1.0, 0.0, np.pi / 2, 2, 1))
    >>> m.n_elements, m.n_nodes, bool(np.allclose(np.hypot(m.X[:, 0], m.X[:, 2]), 2.0))   # on the cylinder
    (8, 15, True)
    >>> m.node_set("x0").tolist()                  # the line x0 with its new midpoint
    [0, 7, 3]
    """
    return refine_levels(mesh, levels)[-1]


def refine_levels(mesh, levels):
    """[mesh, refine(mesh, 1), ..., refine(mesh, levels)] (the meshes of every level).

    Example
    -------
    >>> from core_se3 import mesh
    >>> [m.n_elements for m in refine_levels(mesh.rectangle(2.0, 1.0, 2, 1), 2)]
    [2, 8, 32]
    """
    if isinstance(levels, bool) or int(levels) != levels or levels < 0:
        raise MeshError(f"refine needs a whole number of levels >= 0, got {levels!r}")
    meshes = [mesh]
    for _ in range(int(levels)):
        meshes.append(_refine_once(meshes[-1]))
    return meshes


def carry_nodes(meshes, ids):
    """Node ids of the unrefined mesh ``meshes[0]`` on the last of ``refine_levels``' meshes: a
    line (consecutive nodes joined by mesh edges) gets the new nodes between its nodes, as the
    named node sets do; other selections (points) keep their ids.

    Example
    -------
    >>> from core_se3 import mesh
    >>> ms = refine_levels(mesh.rectangle(2.0, 1.0, 2, 1), 1)
    >>> carry_nodes(ms, [2, 5]).tolist(), carry_nodes(ms, [0, 5]).tolist()     # a line, two points
    ([2, 10, 5], [0, 5])
    """
    ids = np.asarray(ids, np.int64)
    for m in meshes[:-1]:
        ids = _refined_line(m, ids, enclose=False)
    return ids


def carry_held(meshes, ids):
    """Node ids of the unrefined mesh ``meshes[0]`` on the last of ``refine_levels``' meshes as a
    support holds them: with every new node on an element edge both of whose ends are held,
    whatever the order of ``ids`` (a line listed out of order, several lines in one set, a closed
    loop such as a hole's edge).  A support that held both ends of an edge and not the node
    between them would be weaker on the refined mesh.  (Element centres are not added: ids that
    happen to be an element's corners may be points; a named patch carries its centres.)

    Example
    -------
    >>> from core_se3 import mesh
    >>> ms = refine_levels(mesh.rectangle(2.0, 1.0, 2, 1), 1)
    >>> carry_held(ms, [5, 2]).tolist(), carry_held(ms, [0, 2, 3, 5]).tolist()   # a line; two lines
    ([2, 5, 10], [0, 2, 3, 5, 7, 10])
    >>> carry_held(ms, [0, 1, 3, 4]).tolist()                   # an element's corners: its edges
    [0, 1, 3, 4, 6, 7, 9, 11]
    """
    held = np.unique(np.asarray(ids, np.int64))
    for m in meshes[:-1]:
        held = np.unique(_held_once(m, held, centres=False))
    return held


def _held_once(mesh, ids, centres=True):
    """``ids`` followed by the new nodes of one refinement of ``mesh`` that they enclose: the
    midpoint of every element edge with both ends in ``ids`` (node n + edge), then, with
    ``centres``, the centre of every element with its four corners in ``ids`` (n + |E| + element)."""
    inset = np.zeros(mesh.n_nodes, bool)
    inset[ids] = True
    edges = np.flatnonzero(inset[mesh.edge_nodes].all(1))
    centres = np.flatnonzero(inset[mesh.quads].all(1)) if centres else np.zeros(0, np.int64)
    n = mesh.n_nodes
    return np.concatenate([ids, n + edges, n + len(mesh.edge_nodes) + centres]).astype(np.int64)


def _refine_once(mesh):
    n, m = mesh.n_nodes, mesh.n_elements
    g0, E = mesh.g0, mesh.edge_nodes
    def middle(ga, gb):                    # across a cut: gb turned by its quarter turn (module docstring)
        return geodesic_midpoints(ga, _matched(ga, gb))
    g_mid = middle(g0[E[:, 0]], g0[E[:, 1]])                           # nodes n ... n + |E| - 1
    mid = n + mesh.elem_edges              # (m, 4) midpoint ids of the local edges bottom, top, left, right
    g_all = np.concatenate([g0, g_mid])
    across = middle(g_all[mid[:, 0]], g_all[mid[:, 1]])                # bottom to top
    along = middle(g_all[mid[:, 2]], g_all[mid[:, 3]])                 # left to right
    g_c = middle(across, along)
    c = n + len(E) + np.arange(m)
    q = mesh.quads
    b, t, l, r = mid.T
    quads = np.stack([np.stack([q[:, 0], b, c, l], 1), np.stack([b, q[:, 1], r, c], 1),
                      np.stack([c, r, q[:, 2], t], 1), np.stack([l, c, t, q[:, 3]], 1)], 1).reshape(-1, 4)
    edges = {name: _refined_line(mesh, np.asarray(ids, np.int64)) for name, ids in mesh.edges.items()}
    regions = {name: descendants(ids, 1) for name, ids in mesh.regions.items()}
    return Mesh(np.concatenate([g_all, g_c]), quads, edges, shape=None, regions=regions)


def _refined_line(mesh, ids, enclose=True):
    """A node set with the edge midpoints between consecutive nodes if it is a line (every
    consecutive pair a mesh edge; a closed loop, whose last node is joined to its first, also
    the closing edge's midpoint, last), else, with ``enclose`` (a named set), with the new nodes
    it encloses (``_held_once``: several lines, a patch; points stay points) and without it (a
    user's ids, which may be points that happen to be neighbours) unchanged."""
    if len(ids) < 2:
        return ids
    n = mesh.n_nodes
    E = mesh.edge_nodes
    codes = E[:, 0] * n + E[:, 1]

    def edge_of(a, b):                                                 # edge index, or -1
        want = np.minimum(a, b) * n + np.maximum(a, b)
        pos = np.minimum(np.searchsorted(codes, want), len(codes) - 1)  # edge_nodes is sorted (np.unique)
        return np.where(codes[pos] == want, pos, -1)
    pos = edge_of(ids[:-1], ids[1:])
    if np.any(pos < 0):
        return _held_once(mesh, ids) if enclose else ids
    out = np.empty(2 * len(ids) - 1, np.int64)
    out[0::2], out[1::2] = ids, n + pos
    closing = edge_of(ids[-1:], ids[:1])[0] if len(ids) >= 4 else -1   # quad meshes have no 3-cycles
    return np.append(out, n + closing) if closing >= 0 else out


"""Nodal d1 along a quad mesh's own edges: the default frames of doubly curved parts read from files.

Why.  On a doubly curved part the element keeps the user's nodal frames (``mesh.gauge``: they
cannot be made parallel), and there frames that turn from node to node relative to the mesh's
edges lock thin shells: an edge's geodesic is fixed by its two end frames, so turned frames make
other curves of the edges (docs/ELEMENTS.md, "Nodal frames").  A constant hint projected on the
tangent planes (``from_meshio``'s rule for a given ``d1_hint``) does that: the whole thin
hemisphere (R/h 1e4) gave 0.30 / 0.47 / 0.93 of its meridian frames' deflection on 4x4 / 8x8 /
16x16 per quarter.  On a lat-long mesh the meridian frames are the frames along the edges, and
they do not lock (nor do the parallels: the same answer).

The field.  At each node a 4-fold symmetric direction (a "cross"), as the complex number
z = exp(4 i theta) of an angle theta in the node's tangent plane: the node's own z is the mean of
exp(4 i theta) over the two edges leaving it in each adjacent quad (a corner of two orthogonal
edges gives both the same number; at a boundary node, over its boundary edges alone, and kept);
then ``CROSS_PASSES`` passes of z <- own + CROSS_SMOOTHING x the mean of the neighbours' unit z
at the interior nodes, each carried over its edge by keeping its angle to the edge (the chord
a -> b at a, b -> a at b), which smooths the field where nodes are moved at random (the quarter
hemisphere at R/h 1e4, interior nodes moved by 0.1 / 0.3 of the spacing, 16x16: 0.934 / 0.731 of
the generator's deflection unsmoothed, 0.961 / 0.809 smoothed, 0.963 / 0.803 on the meridians
with the same normals; ``benchmarks/curved_frames.py``).  d1 lies at a quarter of z's argument.
On a lat-long mesh of a surface of revolution the chords on either side of a node along a
parallel are mirror images about its meridian plane, so the field is the meridians' to
round-off.  Of the four directions of a node's cross, the one taken is that closest to its
parent's along a minimum spanning tree of the mesh edges weighted by the crosses' mismatch, so
that neighbours agree where the field is smooth (around an irregular node, whose cross turns by
a quarter turn around it, some edge must see the jump); each part starts at its first node with
the direction closest to the chord to its first neighbour, so that the frames turn with the mesh.
Where two such quarter-turn cuts meet, neighbours can end half a turn apart (a closed cubed
sphere, 16 x 16 per face: 180 deg): the element takes every edge between its end frames turned
by the quarter turn that leaves them least turned about the normal (``mesh.gauge.edge_matching``,
``fem.element_default``, "Cuts"), so any quarter turns are kept as they are.  (The nodes of
such edges once took the quarter turn, or else the angle, that made the cube of their edges'
turns least: at most 134.8 deg left, but an arbitrary angle on some nodes, whose elements' area
came out 0.46 of their quads' on the 16 x 16 sphere.)  An irregular interior node at an edge
turning by more than ``SETTLE_TURN`` about the normal, modulo quarter turns (a singular node of
the field: the cube's valence-3 corners, whose three edges the field cannot follow), takes the
angle that makes the cube of its edges' turns least, modulo quarter turns (the elements round
them on the closed cubed sphere: area within 2.6 % of their quads').
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

__all__ = ["edge_aligned_d1", "CROSS_PASSES", "CROSS_SMOOTHING", "SETTLE_TURN"]

#: smoothing passes of the cross field (each a Jacobi step; the weight below makes 30 converge to
#: about 1e-3)
CROSS_PASSES = 30
#: weight of the neighbours' mean against the node's own edges in a smoothing pass
CROSS_SMOOTHING = 4.0


def _unit_chords(X, a, b, r, s):
    """exp(i theta) (E,) of the chords a -> b in a's tangent basis (r, s)."""
    v = X[b] - X[a]
    z = np.einsum("ni,ni->n", v, r[a]) + 1j * np.einsum("ni,ni->n", v, s[a])
    return z / np.maximum(np.abs(z), 1e-300)


def _node_sum(n, idx, values):
    """Sum (n,) complex of ``values`` at the nodes ``idx``."""
    return np.bincount(idx, values.real, n) + 1j * np.bincount(idx, values.imag, n)


def _cross_field(X, quads, edges, r, s):
    """z (n,) complex: exp(4 i theta) of each node's cross in its basis (r, s) (module docstring)."""
    n = len(X)
    own = np.zeros(n, complex)
    for k in range(4):
        a = quads[:, k]
        for b in (quads[:, (k + 1) % 4], quads[:, (k + 3) % 4]):
            own += _node_sum(n, a, _unit_chords(X, a, b, r, s) ** 4)
    own /= 2.0 * np.bincount(quads.ravel(), minlength=n)
    # boundary nodes: their boundary edges alone, kept
    cyc = np.sort(np.stack([quads, np.roll(quads, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    key, count = np.unique(cyc[:, 0] * n + cyc[:, 1], return_counts=True)
    bd = np.stack([key[count == 1] // n, key[count == 1] % n], 1)
    on = np.zeros(n, bool)
    on[bd.ravel()] = True
    if len(bd):
        a, b = np.r_[bd[:, 0], bd[:, 1]], np.r_[bd[:, 1], bd[:, 0]]
        own[on] = (_node_sum(n, a, _unit_chords(X, a, b, r, s) ** 4) / np.maximum(np.bincount(a, minlength=n), 1))[on]
    a, b = np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]]
    carry = (_unit_chords(X, a, b, r, s) / _unit_chords(X, b, a, r, s)) ** 4     # b's basis -> a's
    weight = np.where(on, 0.0, CROSS_SMOOTHING) / np.maximum(np.bincount(a, minlength=n), 1)
    z = own
    for _ in range(CROSS_PASSES):
        z = own + weight * _node_sum(n, a, carry * (z / np.maximum(np.abs(z), 1e-300))[b])
    return z


def _quarter_turns(edges, d1, d2, root_choice):
    """k (n,) in 0 ... 3: the quarter turns of d1 (n, 3) (d2 = d3 x d1) that make neighbours along a
    minimum spanning tree of the crosses' mismatch agree best; ``root_choice`` (n,) the turn at
    the node that starts its part."""
    n = len(d1)
    a, b = edges[:, 0], edges[:, 1]
    best = np.maximum(np.abs(np.einsum("ei,ei->e", d1[a], d1[b])), np.abs(np.einsum("ei,ei->e", d1[a], d2[b])))
    G = sp.csr_matrix((2.0 - best, (a, b)), shape=(n, n))       # > 0: every edge stays an edge
    T = minimum_spanning_tree(G + G.T)
    T = (T + T.T).tocsr()
    _, part = connected_components(T, directed=False)
    roots = np.unique(part, return_index=True)[1]
    pred = np.full(n, -1)
    for root in roots:                                        # one pass per connected part
        _, p = breadth_first_order(T, root, directed=False)
        mine = part == part[root]
        pred[mine] = p[mine]
    pred[roots] = -1
    child = np.flatnonzero(pred >= 0)
    par = pred[child]
    # the child's turn k whose d1_c(k) = cos(k pi/2) d1_c + sin(k pi/2) d2_c is closest to the parent's d1
    c1, c2 = np.einsum("ei,ei->e", d1[par], d1[child]), np.einsum("ei,ei->e", d1[par], d2[child])
    total = np.zeros(n, np.int64)
    total[child] = np.argmax(np.stack([c1, c2, -c1, -c2], 1), axis=1)
    total[roots] = root_choice[roots]
    up = pred.copy()
    while (up >= 0).any():                                    # sums up to the root (pointer jumping)
        has = np.flatnonzero(up >= 0)
        total[has], up[has] = total[has] + total[up[has]], up[up[has]]
    return total % 4


def edge_aligned_d1(X, quads, d3, edges=None):
    """Unit d1 (n, 3) in each node's tangent plane along the mesh's own edges (module docstring).

    Parameters
    ----------
    X : (n, 3) array
        Node positions.
    quads : (m, 4) array of int
        The quads (every node in one at least).
    d3 : (n, 3) array
        Unit normals.
    edges : (E, 2) array of int, optional
        The mesh's edges (default: from the quads).

    Returns
    -------
    (n, 3) ndarray

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import mesh
    >>> m = mesh.hemisphere_quarter(10.0, 18.0, 4, 4)          # meridian d1
    >>> d1 = edge_aligned_d1(m.X, m.quads, m.g0[:, :3, 2])
    >>> inner = np.abs(np.einsum("ni,ni->n", d1, m.g0[:, :3, 0]))[m.shape[0] + 1:-m.shape[0] - 1]
    >>> bool(np.all((inner > 1 - 1e-12) | (inner < 1e-12)))     # off the sides: meridians or parallels
    True
    """
    X, quads, d3 = np.asarray(X, float), np.asarray(quads, np.int64), np.asarray(d3, float)
    if edges is None:
        e = np.stack([quads, np.roll(quads, -1, axis=1)], -1).reshape(-1, 2)
        edges = np.unique(np.sort(e, axis=1), axis=0)
    n = len(X)
    first = np.full(n, -1)                       # a neighbour of every node: its basis' first axis
    first[edges[::-1, 0]], first[edges[::-1, 1]] = edges[::-1, 1], edges[::-1, 0]
    r = X[first] - X
    r -= np.einsum("ni,ni->n", r, d3)[:, None] * d3
    r /= np.linalg.norm(r, axis=1, keepdims=True)
    s = np.cross(d3, r)
    phi = np.angle(_cross_field(X, quads, edges, r, s)) / 4.0
    d1 = np.cos(phi)[:, None] * r + np.sin(phi)[:, None] * s
    d2 = np.cross(d3, d1)
    # at a part's first node: the quarter turn closest to the chord to its neighbour (r)
    k = _quarter_turns(edges, d1, d2, np.argmax(np.stack([np.cos(phi), -np.sin(phi), -np.cos(phi), np.sin(phi)], 1),
                                                axis=1))
    # where two quarter-turn cuts meet, neighbours can be half a turn apart: the element matches
    # every edge's frames by the quarter turn that leaves them least turned (``mesh.gauge.edge_matching``)
    D = np.cos(k * np.pi / 2)[:, None] * d1 + np.sin(k * np.pi / 2)[:, None] * d2
    return _settled(quads, edges, D, d3)


#: an irregular interior node (not 4 quads round it) at an edge turning by more than this [deg]
#: about the normal, modulo quarter turns, takes the angle that makes the cube of its edges' turns
#: least (a singular node of the field: a closed cubed sphere's corners)
SETTLE_TURN = 30.0


def _quarter_rests(D, d3, v, nb, turns=None):
    """|turn| [rad] about v's normal, modulo quarter turns, from v's d1 (turned by ``turns`` (c,):
    (c, k)) to the d1 of its neighbours nb (k,): the angle of each in v's tangent basis."""
    d2 = np.cross(d3[v], D[v])
    ang = np.arctan2(D[nb] @ d2, D[nb] @ D[v])
    t = np.zeros(1) if turns is None else turns
    return np.abs(np.angle(np.exp(4j * (ang[None, :] - t[:, None])))) / 4.0


def _settled(quads, edges, D, d3):
    """D (n, 3) with the irregular interior nodes at an edge turning by more than SETTLE_TURN about
    the normal, modulo quarter turns, moved to the angle (in 1 deg steps) that makes the cube of
    their edges' turns least, node by node (a few nodes: a loop over them), a few sweeps."""
    n = len(D)
    adj = sp.csr_matrix((np.ones(2 * len(edges)), (np.r_[edges[:, 0], edges[:, 1]], np.r_[edges[:, 1], edges[:, 0]])),
                        shape=(n, n))
    cyc = np.sort(np.stack([quads, np.roll(quads, -1, axis=1)], -1).reshape(-1, 2), axis=1)
    key, count = np.unique(cyc[:, 0] * n + cyc[:, 1], return_counts=True)
    boundary = np.zeros(n, bool)
    boundary[key[count == 1] // n] = True
    boundary[key[count == 1] % n] = True
    irregular = np.flatnonzero((np.bincount(quads.ravel(), minlength=n) != 4) & ~boundary)
    turns = np.radians(np.arange(90.0))
    for _ in range(5):
        moved = False
        for v in irregular:
            nb = adj.indices[adj.indptr[v]:adj.indptr[v + 1]]
            if _quarter_rests(D, d3, v, nb).max() <= np.radians(SETTLE_TURN):
                continue
            cost = (_quarter_rests(D, d3, v, nb, turns) ** 3).sum(axis=1)
            j = int(np.argmin(cost))
            if cost[j] < cost[0] - 1e-12:
                D[v], moved = np.cos(turns[j]) * D[v] + np.sin(turns[j]) * np.cross(d3[v], D[v]), True
        if not moved:
            break
    return D

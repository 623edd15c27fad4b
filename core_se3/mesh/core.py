"""The quadrilateral shell mesh: nodal reference frames g0 = (R0, phi0) in SE(3), quads, and named
node sets (edges) and element regions.

A node carries a reference frame whose third axis is the surface normal; quads are listed
counter-clockwise about that normal (natural coordinates (-1,-1), (1,-1), (1,1), (-1,1)).  Named
node sets (``edges``) are ordered along the line they follow; named element sets (``regions``)
come from Gmsh physical surfaces or from the generators.
"""
from __future__ import annotations

import warnings
from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from ..errors import MeshError, MeshWarning, did_you_mean

__all__ = ["Mesh", "frames_from", "LOCAL_EDGES", "chain_order", "bow_tie_error", "missing_nodes_error",
           "degenerate_quad_error"]

# local edges of a quad in its own orientation: bottom, top (direction xi1), left, right (xi2)
LOCAL_EDGES = np.array([[0, 1], [3, 2], [0, 3], [1, 2]])


def frames_from(X, d1, d3):
    """SE(3) frames (n, 4, 4) with position X, first axis d1 and third axis d3 (orthonormalised).

    d3 is normalised, d1 is made orthogonal to it (Gram-Schmidt) and normalised, d2 = d3 x d1.

    Parameters
    ----------
    X : (n, 3) array
        Positions [length].
    d1 : (n, 3) array
        Approximate first directors (any length, not parallel to d3).
    d3 : (n, 3) array
        Third directors, the surface normals (any non-zero length).

    Returns
    -------
    (n, 4, 4) ndarray
        Frames [[d1, d2, d3, X], [0, 0, 0, 1]] (directors as columns).

    Example
    -------
    >>> import numpy as np
    >>> g = frames_from(np.zeros((1, 3)), np.array([[1.0, 1, 0]]), np.array([[0, 0, 2.0]]))
    >>> np.allclose(g[0, :3, 1], [-2 ** -0.5, 2 ** -0.5, 0])
    True
    """
    d3 = d3 / np.linalg.norm(d3, axis=-1, keepdims=True)
    d1 = d1 - np.einsum("...i,...i->...", d1, d3)[..., None] * d3
    d1 = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
    d2 = np.cross(d3, d1)
    g = np.zeros(X.shape[:-1] + (4, 4))
    g[..., :3, 0], g[..., :3, 1], g[..., :3, 2] = d1, d2, d3
    g[..., :3, 3] = X
    g[..., 3, 3] = 1.0
    return g


def _whole(a, what):
    """``a`` as an int64 array, else a MeshError: ids that are not whole numbers (a quad of 0.7
    was read as node 0, a region's 0.5 as element 0)."""
    raw = np.asarray(a)
    ids = raw.astype(np.int64) if raw.size else np.zeros(raw.shape, np.int64)
    if raw.dtype == bool or (raw.size and not np.array_equal(ids, raw)):
        raise MeshError(f"{what} must be whole numbers (ids), got {raw.ravel()[:6].tolist()}")
    return ids


def _set_ids(ids, count, what, kind):
    """A named set's ids (k,) checked: whole numbers, existing, each once (a region listing an
    element twice doubled its pressure or gravity, a node set listing a node twice its nodal
    load, silently: the ids given directly were refused so, the named ones were not)."""
    ids = _whole(ids, what)
    if ids.ndim != 1 or len(ids) == 0 or ids.min() < 0 or ids.max() >= count:
        raise MeshError(f"{what} must list existing {kind} ids (0 .. {count - 1}), got "
                        f"{np.asarray(ids).ravel()[:6].tolist()}")
    uniq, counts = np.unique(ids, return_counts=True)
    if counts.max() > 1:
        raise MeshError(f"{what} lists {kind} {int(uniq[np.argmax(counts)])} {int(counts.max())} times: a load on it "
                        f"would act {int(counts.max())} times; list every {kind} once")
    return ids


#: the largest span [length] of a mesh: beyond it the squares of its lengths (edge lengths
#: |e| = sqrt(e.e), areas) overflow double precision (1.8e308, at lengths of 1.3e154), and a
#: mesh of L = 1e300 was refused as 'degenerate quads' (its edges' lengths inf)
MAX_SPAN = 1e150

#: the sine of a quad's corner angle at or below which the quad is degenerate (round-off)
DEGENERATE_SINE = 1e-10


def _corner_turns(P):
    """Turns (m, 4) of the corners k + 1 of quads with corners P (m, 4, 3) about the quad's
    plane (the sign of (e_k x e_k+1) . n, n the largest of those cross products), 0 where the
    corner's sine is round-off."""
    e = np.roll(P, -1, axis=1) - P                                   # edges k -> k + 1
    turn = np.cross(e, np.roll(e, -1, axis=1))                       # at corner k + 1
    size = np.linalg.norm(turn, axis=-1)
    ref = turn[np.arange(len(P)), np.argmax(size, axis=1)]
    s = np.einsum("mki,mi->mk", turn, ref)
    lens = np.linalg.norm(e, axis=-1)
    tol = DEGENERATE_SINE * lens * np.roll(lens, -1, axis=1) * np.linalg.norm(ref, axis=-1)[:, None]
    return np.where(np.abs(s) > tol, np.sign(s), 0.0)


def bow_tie_error(quads, P, what="quad"):
    """The message of the first self-intersecting (bow-tie) quad among ``quads`` (m, 4) node
    ids with corners P (m, 4, 3), or "": its corners turn two one way, two the other (a convex
    quad's all alike, a non-convex one's three to one), so that two of its edges cross -- not
    flipped normals nor a clockwise quad, which is what the orientation checks would say.

    Example
    -------
    >>> P = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]])
    >>> print(bow_tie_error(np.array([[4, 5, 6, 7]]), P))
    quad 0 is self-intersecting (a bow-tie): its node order [4, 5, 6, 7] crosses its edges (5, 6) and (7, 4); list its nodes around its boundary, [4, 5, 7, 6] (reversed if its neighbours run the other way)
    """
    t = _corner_turns(P)
    bad = np.flatnonzero(((t > 0).sum(1) == 2) & ((t < 0).sum(1) == 2))
    if not len(bad):
        return ""
    i = int(bad[0])
    a, b, c, d = (int(v) for v in quads[i])
    fixes = [((a, b, d, c), [0, 1, 3, 2], f"({b}, {c}) and ({d}, {a})"),
             ((a, c, b, d), [0, 2, 1, 3], f"({a}, {b}) and ({c}, {d})")]
    order, cross = next(((o, x) for o, k, x in fixes if abs(_corner_turns(P[i:i + 1, k]).sum()) == 4),
                        (fixes[0][0], fixes[0][2]))
    more = f" ({len(bad)} such {what}s: {bad[:5].tolist()}{' ...' if len(bad) > 5 else ''})" if len(bad) > 1 else ""
    return (f"{what} {i} is self-intersecting (a bow-tie): its node order {[a, b, c, d]} crosses its edges "
            f"{cross}{more}; list its nodes around its boundary, {list(order)} (reversed if its neighbours "
            "run the other way)")


def missing_nodes_error(quads, n, what="quad"):
    """The message for ``quads`` (m, k) node ids some of which are not among the n nodes, or "":
    the first such element, its ids, the range found -- and, where no element uses id 0 and the
    largest id is n (ids numbered from 1, as Gmsh, Abaqus and Fortran number them), that fix.

    Example
    -------
    >>> print(missing_nodes_error(np.array([[1, 2, 4, 3], [2, 5, 6, 4]]), 6))
    quad 1 refers to node 6, which does not exist (ids 1 ... 6 for 6 nodes, numbered from 0): the ids look numbered from 1 (no quad uses 0, the largest is the number of nodes) -- subtract 1 from them (quads - 1)
    """
    q = np.asarray(quads)
    off = (q < 0) | (q >= n)
    if not off.any():
        return ""
    i = int(np.flatnonzero(off.any(1))[0])
    lo, hi = int(q.min()), int(q.max())
    msg = (f"{what} {i} refers to node {int(q[i][off[i]][0])}, which does not exist (ids {lo} ... {hi} for {n} "
           f"nodes, numbered from 0)")
    if lo >= 1 and hi == n:
        return msg + (f": the ids look numbered from 1 (no {what} uses 0, the largest is the number of nodes) -- "
                      "subtract 1 from them (quads - 1)")
    return msg + ": the connectivity and the nodes do not belong together"


# positions are stored absolutely, to eps |X|: a mesh farther from the origin than this many of
# its shortest edges keeps its displacements to eps |X| only (a cantilever 10 x 1 on 8 x 2
# elements, shortest edge 0.5, tip deflection 1.3e-3, placed at 1e8 / 1e10 / 1e12: 4e-6 / 4.7e-4 /
# 3.4 % off, measured: tests/test_lie_numerics.py's far part)
FAR_FROM_ORIGIN = 1e10


def _round_off_note(X_all, X_bad):
    """The reason a quad is degenerate when it is the positions' round-off: eps |X| is more than
    1e-3 of its longest edge (a strip placed 1e17 from the origin has edges along x of 0)."""
    far, eps = float(np.abs(X_all).max()), np.finfo(float).eps
    edges = np.linalg.norm(X_bad - np.roll(X_bad, 1, axis=1), axis=-1)
    edge = float(edges.min())
    if not np.isfinite(far) or eps * far <= 1e-3 * float(edges.max()):
        return ""
    return (f": the mesh lies {far:.3g} from the origin, where positions are stored to eps |X| = "
            f"{np.finfo(float).eps * far:.2g}, and this quad's shortest edge is {edge:.2g}; translate the mesh "
            "toward the origin (core_se3 keeps positions absolutely)")


def degenerate_quad_error(quads, P, nrm=None, what="quad"):
    """The message for the quads among ``quads`` (m, 4) node ids with corners P (m, 4, 3) that are
    not convex with positive area about the normals ``nrm`` (m, 3) (default: each quad's largest
    corner cross product, which a file's quads' normals follow), or "": which quads, and for the
    first the cause (two nodes at one point, listed clockwise, a straight or a re-entrant corner),
    its node(s) and the fix; a corner whose sine is round-off is degenerate too (an annulus of two
    elements round a full turn: its quads' corners on one line, sine 2.4e-16).

    Example
    -------
    >>> P = np.array([[[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0.0]]])
    >>> print(degenerate_quad_error(np.array([[3, 4, 5, 6]]), P).split("; ")[1])
    quad 0: its corner at node 4 is straight (180 deg: three of its nodes on one line, zero area there): move node 4 off the line
    """
    e1, e2 = np.roll(P, -1, axis=1) - P, np.roll(P, 1, axis=1) - P          # (m, 4, 3) at each corner
    turn = np.cross(e1, e2)
    if nrm is None:
        nrm = turn[np.arange(len(P)), np.argmax(np.linalg.norm(turn, axis=-1), axis=1)]
    nrm = nrm / np.maximum(np.linalg.norm(nrm, axis=1), 1e-300)[:, None]
    c = np.einsum("mki,mi->mk", turn, nrm)
    l1, l2 = np.linalg.norm(e1, axis=2), np.linalg.norm(e2, axis=2)
    flat = c <= DEGENERATE_SINE * l1 * l2
    if not np.any(flat):
        return ""
    bad = np.flatnonzero(flat.any(1))
    k, i = int(np.argmax(flat[bad[0]])), int(bad[0])
    X_all = P.reshape(-1, 3)
    return (f"{what}s {bad[:5].tolist()} are degenerate, non-convex or listed clockwise about their normal "
            f"(corner {k}){_round_off_note(X_all, P[bad[:5]])}"
            + _bad_corner_note(np.asarray(quads)[i], i, c[i], l1[i], l2[i], len(bad), what))


def _bad_corner_note(q, i, c, l1, l2, count, what="quad"):
    """What is wrong with quad i (nodes q) whose corners' sines times edge lengths c (4,) about its
    nodes' mean normal are not all positive (edge lengths l1, l2 (4,) at each corner), and the fix:
    two nodes at one point, listed clockwise, a straight or a re-entrant corner."""
    tol = DEGENERATE_SINE * l1 * l2
    scale = max(float(l1.max()), 1e-300)
    k = int(np.argmin(c / np.maximum(l1 * l2, 1e-300)))
    node = int(q[k])
    more = f" (of {count} such {what}s)" if count > 1 else ""
    if l1.min() <= 1e-12 * scale:
        j = int(np.argmin(l1))
        why = (f"its nodes {int(q[j])} and {int(q[(j + 1) % 4])} are at one point (an edge of length "
               f"{float(l1[j]):.2g}): merge them, or move one")
    elif np.all(c < -tol):
        why = (f"its nodes {[int(v) for v in q]} run clockwise about their normals d3 (every corner turns the other "
               f"way): list them the other way round, {[int(v) for v in q[::-1]]}, or turn its nodes' d3 over")
    elif np.all(np.abs(c) <= tol):
        why = "its four nodes lie on one line (zero area): move them apart or remove the quad"
    elif abs(c[k]) <= tol[k]:
        why = (f"its corner at node {node} is straight (180 deg: three of its nodes on one line, zero area "
               f"there): move node {node} off the line")
    else:
        why = (f"its corner at node {node} is re-entrant (non-convex: it turns the other way about the normal): "
               f"move node {node} so that the quad is convex, or split it")
    return f"; {what} {i}{more}: {why}"


def chain_order(segments):
    """Order the nodes of line segments [(a, b), ...] along the line they form (sorted ids if
    they do not form one line).

    A closed loop starts at the first node of the first segment.

    Parameters
    ----------
    segments : sequence of (int, int)
        Node-id pairs of the line cells (any order, either direction).

    Returns
    -------
    (k,) ndarray of int
        The node ids in their order along the line, starting at one of its ends.

    Example
    -------
    >>> chain_order([(2, 3), (1, 2), (3, 7)]).tolist()
    [1, 2, 3, 7]
    """
    adj = defaultdict(list)
    for a, b in segments:
        adj[a].append(b)
        adj[b].append(a)
    ends = [v for v, nb in adj.items() if len(nb) == 1]
    start = ends[0] if ends else segments[0][0]
    order, prev, cur = [start], None, start
    while True:
        nxt = [v for v in adj[cur] if v != prev and v not in order[-2:]]
        if not nxt or nxt[0] == start:
            break
        prev, cur = cur, nxt[0]
        order.append(cur)
    if len(order) != len(adj):
        return np.array(sorted(adj))
    return np.array(order)


@dataclass
class Mesh:
    """Nodes with reference frames ``g0`` (n, 4, 4), quads (m, 4), named node sets ``edges``
    (name -> node ids, ordered along the edge) and named element sets ``regions`` (name ->
    element ids).

    Derived once: the unique undirected element edges ``edge_nodes`` (E, 2), and per quad the
    ids of its four local edges (bottom, top, left, right) with orientation signs
    ``elem_edges``, ``elem_edge_sign`` (m, 4).

    Construction checks the input and raises :class:`~core_se3.errors.MeshError` for frames
    that are not proper rigid motions, collapsed, clockwise or non-convex quads (about the mean
    nodal normal), an edge shared by more than two quads, or regions listing missing elements.

    Parameters
    ----------
    g0 : (n, 4, 4) array
        Reference frames: d1, d2, d3 (= the normal) as rotation columns, position [length].
    quads : (m, 4) array of int
        Node ids of each quad, counter-clockwise about the normal.
    edges : dict, optional
        Named node sets: name -> node ids (ordered along the line for loads and probes).
    shape : (int, int), optional
        (nx, ny) of a structured mesh, None otherwise.
    regions : dict, optional
        Named element sets: name -> element ids.

    Attributes
    ----------
    X : (n, 3) ndarray
        Reference positions (property).
    n_nodes, n_elements : int
        Node and quad counts (properties).
    length_scale : float
        Bounding-box diagonal (1 for a mesh without extent), the scale of the convergence norms.
    edge_nodes : (E, 2) ndarray
        Unique element edges (lower node id first).
    elem_edges, elem_edge_sign : (m, 4) ndarray
        Mesh-edge id of each local edge (bottom, top, left, right) and +1/-1 for its direction.

    Example
    -------
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(2.0, 1.0, 2, 1)
    >>> m.n_nodes, m.n_elements, m.node_set("x1").tolist()
    (6, 2, [2, 5])
    >>> len(m.edge_nodes), bool(m.elem_edges[0, 3] == m.elem_edges[1, 2])   # 7 edges, x = 1 shared
    (7, True)
    """
    g0: np.ndarray
    quads: np.ndarray
    edges: dict = field(default_factory=dict)
    shape: tuple | None = None      # (nx, ny) for structured meshes
    regions: dict = field(default_factory=dict)

    def __post_init__(self):
        self.g0 = np.asarray(self.g0, float)
        self.quads = _whole(self.quads, "quads")
        n = self.g0.shape[0]
        if self.g0.shape != (n, 4, 4) or not np.all(np.isfinite(self.g0)):
            raise MeshError("g0 must be a finite (n, 4, 4) array of SE(3) frames")
        R = self.g0[:, :3, :3]
        if np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() > 1e-8 or np.any(np.linalg.det(R) < 0):
            raise MeshError("reference rotations are not proper orthonormal matrices")
        if np.any(self.g0[:, 3] != [0.0, 0.0, 0.0, 1.0]):
            k = int(np.flatnonzero(np.any(self.g0[:, 3] != [0.0, 0.0, 0.0, 1.0], axis=1))[0])
            raise MeshError(f"the frames' last rows must be [0, 0, 0, 1] (homogeneous 4x4 frames), node {k}'s is "
                            f"{self.g0[k, 3].tolist()}: the position is the last column, g0[:, :3, 3]")
        if self.quads.ndim != 2 or self.quads.shape[1] != 4 or len(self.quads) == 0:
            raise MeshError("quads must be an (m, 4) integer array with m >= 1")
        if self.quads.min() < 0 or self.quads.max() >= n:
            raise MeshError(missing_nodes_error(self.quads, n))
        s = np.sort(self.quads, axis=1)
        if np.any(s[:, 1:] == s[:, :-1]):
            bad = np.nonzero(np.any(s[:, 1:] == s[:, :-1], axis=1))[0][:5]
            raise MeshError(f"quads {bad.tolist()} repeat a node (collapsed element)")
        for name, ids in self.regions.items():
            self.regions[name] = _set_ids(ids, len(self.quads), f"region {name!r}", "element")
        for name, ids in self.edges.items():
            if np.size(ids):                   # (an empty set is refused where it is used)
                _set_ids(ids, n, f"node set {name!r}", "node")
        self._build_edges()
        self._gauge_angles = None
        self._check_geometry()
        self._check_origin()

    @property
    def X(self):
        """Reference positions (n, 3)."""
        return self.g0[:, :3, 3]

    @property
    def gauge_angles(self):
        """The least-turn gauge (n,) [rad]: the turns about the nodal normals on which the default
        element builds its frames (``mesh.gauge``), computed at the first use; 0 where the frames
        turn nowhere about the normal.  A sub-mesh of a partition is given its whole mesh's
        angles (``parallel.local.subdomain``), so that every rank's element is the serial one."""
        if self._gauge_angles is None:
            from .gauge import least_turn_angles
            self._gauge_angles = least_turn_angles(self.g0, self.edge_nodes)
        return self._gauge_angles

    @gauge_angles.setter
    def gauge_angles(self, alpha):
        alpha = np.asarray(alpha, float)
        if alpha.shape != (self.n_nodes,) or not np.isfinite(alpha).all():
            raise MeshError(f"gauge_angles must be {self.n_nodes} finite angles, got shape {alpha.shape}")
        self._gauge_angles = alpha

    @property
    def n_nodes(self):
        return self.g0.shape[0]

    @property
    def n_elements(self):
        return self.quads.shape[0]

    @property
    def length_scale(self):
        """The bounding-box diagonal of the reference mesh (1 if the mesh has no extent)."""
        X = self.X
        return float(np.linalg.norm(X.max(0) - X.min(0))) or 1.0

    def _build_edges(self):
        loc = self.quads[:, LOCAL_EDGES]                       # (m, 4, 2) directed local edges
        a, b = loc[..., 0].ravel(), loc[..., 1].ravel()
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        key = lo * self.n_nodes + hi
        uniq, inv = np.unique(key, return_inverse=True)
        self.edge_nodes = np.stack([uniq // self.n_nodes, uniq % self.n_nodes], 1)
        self.elem_edges = inv.reshape(-1, 4)
        self.elem_edge_sign = np.where(a == lo, 1, -1).reshape(-1, 4)
        counts = np.bincount(inv, minlength=len(uniq))
        if counts.max() > 2:
            raise MeshError("an edge is shared by more than two quads (non-manifold mesh)")

    def _check_origin(self):
        """MeshWarning when the mesh lies more than FAR_FROM_ORIGIN of its shortest edge from the
        origin: its displacements then carry the positions' round-off eps |X|."""
        X = self.X
        far = float(np.linalg.norm(X, axis=1).max())
        edge = float(np.linalg.norm(X[self.edge_nodes[:, 1]] - X[self.edge_nodes[:, 0]], axis=1).min())
        if far > FAR_FROM_ORIGIN * edge:
            eps = np.finfo(float).eps
            warnings.warn(MeshWarning(
                f"the mesh lies {far:.3g} from the origin, {far / edge:.2g} times its shortest edge ({edge:.3g}): "
                f"positions are stored to eps |X| = {eps * far:.2g} ({eps * far / edge:.1g} of that edge), and "
                "displacements to no better (a cantilever of shortest edge 0.5 and tip deflection 1.3e-3, "
                "placed at 1e10: 5e-4 off; at 1e12: 3 %). Translate the mesh toward the origin"), stacklevel=4)

    def _check_geometry(self):
        # every quad must be convex with positive area about the mean of its nodal normals; a
        # corner whose sine is round-off (an annulus of two elements round a full turn: its
        # quads' corners on one line, sine 2.4e-16) is degenerate too
        span = float(np.max(self.X.max(0) - self.X.min(0)))     # (no square: it cannot overflow first)
        if not span <= MAX_SPAN:
            raise MeshError(f"the mesh spans {span:.3g} [length], beyond {MAX_SPAN:g}: its lengths' squares (edge "
                            "lengths, areas) overflow double precision (1.8e308), so its quads cannot be measured; "
                            "a span that large is likely a unit or exponent mistake: give the mesh in a unit where "
                            "it spans about 1 to 1e6")
        X = self.X[self.quads]                                   # (m,4,3)
        why = bow_tie_error(self.quads, X)
        if why:
            raise MeshError(why)
        why = degenerate_quad_error(self.quads, X, self.g0[self.quads][:, :, :3, 2].sum(1))
        if why:
            raise MeshError(why)

    def node_set(self, name_or_pred):
        """Node ids of a named node set, of the elements of a named region, or of the nodes
        whose reference position satisfies a predicate ``pred(X) -> bool mask``."""
        if callable(name_or_pred):
            mask = np.asarray(name_or_pred(self.X))
            if mask.shape != (self.n_nodes,) or mask.dtype != bool:
                raise MeshError(f"a node predicate must return one boolean per node, shape ({self.n_nodes},), got "
                                f"{mask.dtype} of shape {mask.shape} (compare a coordinate: lambda X: "
                                "np.isclose(X[:, 0], 1.0), not lambda X: X == 1.0 or X[:, 0] - 1.0)")
            return np.nonzero(mask)[0]
        if name_or_pred in self.edges:
            return np.asarray(self.edges[name_or_pred])
        if name_or_pred in self.regions:
            return np.unique(self.quads[self.regions[name_or_pred]])
        names = sorted(self.edges) + sorted(self.regions)
        raise MeshError(f"unknown node set {name_or_pred!r}{did_you_mean(name_or_pred, names)}; "
                        f"node sets: {sorted(self.edges)}, regions: {sorted(self.regions)}")

    def node_at(self, x, tol=None):
        """The id of the node at the point x: the nearest node, which must lie within ``tol``
        (default a quarter of the shortest mesh edge at that node, so that a point typed with a
        few digits finds its node and a point between nodes is refused); MeshError otherwise.

        Example
        -------
        >>> from core_se3 import mesh
        >>> m = mesh.rectangle(2.0, 1.0, 2, 1)
        >>> m.node_at((2.0, 0.5, 0.0)), m.node_at((1.0001, -0.5, 0.0))
        (5, 1)
        >>> m.node_at((0.5, -0.5, 0.0))                     # between nodes 0 and 1
        Traceback (most recent call last):
        ...
        core_se3.errors.MeshError: no node at [0.5, -0.5, 0.0]: the nearest is node 0 at [0.0, -0.5, 0.0], at distance 0.5 > 0.25 (give that point, or a larger tol)
        """
        try:
            p = np.asarray(x, float)
        except (TypeError, ValueError):          # ('abc': a bare ValueError of NumPy before)
            p = np.full(1, np.nan)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise MeshError(f"a point must be three finite coordinates [x, y, z], got {x!r}")
        d = np.linalg.norm(self.X - p, axis=1)
        k = int(np.argmin(d))
        if tol is None:
            at = self.edge_nodes[(self.edge_nodes == k).any(1)]
            tol = 0.25 * float(np.linalg.norm(self.X[at[:, 0]] - self.X[at[:, 1]], axis=1).min())
        if d[k] > tol:
            raise MeshError(f"no node at {p.tolist()}: the nearest is node {k} at {self.X[k].round(6).tolist()}, at "
                            f"distance {d[k]:.4g} > {tol:.4g} (give that point, or a larger tol)")
        return k

    def boundary_edges(self):
        """The mesh's boundary: (edge ids (k,), the element of each (k,)), the edges that belong
        to one element only (rows of ``edge_nodes``).

        Example
        -------
        >>> from core_se3 import mesh
        >>> e, el = mesh.rectangle(2.0, 1.0, 2, 1).boundary_edges()
        >>> len(e), sorted(set(el.tolist()))
        (6, [0, 1])
        """
        counts = np.bincount(self.elem_edges.ravel(), minlength=len(self.edge_nodes))
        el, local = np.nonzero(counts[self.elem_edges] == 1)
        return self.elem_edges[el, local], el

    def elements(self, region=None):
        """Element ids of a named region (a name), of a list of ids, of a boolean mask over the
        elements, or of all elements (None).

        Ids must be whole numbers, each given once (a repeated element would carry its load
        twice); a mask must have one entry per element.  MeshError otherwise.

        Example
        -------
        >>> from core_se3 import mesh
        >>> m = mesh.rectangle(4.0, 1.0, 4, 1)
        >>> m.elements([3, 1]).tolist(), m.elements(m.X[m.quads].mean(1)[:, 0] > 2.0).tolist()
        ([3, 1], [2, 3])
        >>> m.elements([1, 1])
        Traceback (most recent call last):
        ...
        core_se3.errors.MeshError: element selection lists element 1 more than once: its load would act twice; give every element once
        """
        if region is None:
            return np.arange(self.n_elements)
        if isinstance(region, str):
            if region not in self.regions:
                raise MeshError(f"unknown region {region!r}{did_you_mean(region, self.regions)}; "
                                f"regions: {sorted(self.regions) or 'none'}")
            return self.regions[region]
        raw = np.asarray(region)
        if raw.dtype == bool:
            if raw.shape != (self.n_elements,):
                raise MeshError(f"a boolean element selection needs one entry per element ({self.n_elements}), "
                                f"got shape {raw.shape}")
            raw = np.nonzero(raw)[0]
        try:
            ids = raw.astype(np.int64).ravel()
            whole = ids.size == raw.size and np.array_equal(ids, raw.ravel())
        except (TypeError, ValueError):
            whole = False
        if not whole:
            raise MeshError(f"element ids must be whole numbers, got {np.asarray(region).ravel()[:5].tolist()}")
        if ids.size == 0 or ids.min() < 0 or ids.max() >= self.n_elements:
            raise MeshError("element selection is empty or refers to elements that do not exist")
        uniq, count = np.unique(ids, return_counts=True)
        if np.any(count > 1):
            raise MeshError(f"element selection lists element {int(uniq[count > 1][0])} more than once: its load "
                            "would act twice; give every element once")
        return ids

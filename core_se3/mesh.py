"""Quadrilateral shell meshes with nodal reference frames g0 = (R0, phi0) in SE(3).

A mesh is a set of nodes, each carrying a reference frame whose third axis is the surface
normal, and quads listed counter-clockwise about that normal (natural coordinates
(-1,-1), (1,-1), (1,1), (-1,1)).  Named node sets (edges) are ordered along the edge.
Structured generators: ``rectangle`` (flat strip/plate), ``cylinder_arch`` (cylindrical
panel bent in the x-z plane), ``annulus`` (sector or slit annulus).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import se3
from .errors import MeshError

__all__ = ["Mesh", "rectangle", "cylinder_arch", "cylinder_panel", "annulus", "from_meshio",
           "frames_from"]

# local edges of a quad in its own orientation: bottom, top (direction xi1), left, right (xi2)
LOCAL_EDGES = np.array([[0, 1], [3, 2], [0, 3], [1, 2]])


def frames_from(X, d1, d3):
    """SE(3) frames (n,4,4) with position X, first axis d1 and third axis d3 (orthonormalised)."""
    d3 = d3 / np.linalg.norm(d3, axis=-1, keepdims=True)
    d1 = d1 - np.einsum("...i,...i->...", d1, d3)[..., None] * d3
    d1 = d1 / np.linalg.norm(d1, axis=-1, keepdims=True)
    d2 = np.cross(d3, d1)
    g = np.zeros(X.shape[:-1] + (4, 4))
    g[..., :3, 0], g[..., :3, 1], g[..., :3, 2] = d1, d2, d3
    g[..., :3, 3] = X
    g[..., 3, 3] = 1.0
    return g


@dataclass
class Mesh:
    """Nodes with reference frames ``g0`` (n,4,4), quads (m,4), named node sets ``edges``.

    Derived once: the unique undirected element edges ``edge_nodes`` (E,2), and per quad the
    ids of its four local edges (bottom, top, left, right) with orientation signs.
    """
    g0: np.ndarray
    quads: np.ndarray
    edges: dict = field(default_factory=dict)
    shape: tuple | None = None      # (nx, ny) for structured meshes

    def __post_init__(self):
        self.g0 = np.asarray(self.g0, float)
        self.quads = np.asarray(self.quads, dtype=np.int64)
        n = self.g0.shape[0]
        if self.g0.shape != (n, 4, 4) or not np.all(np.isfinite(self.g0)):
            raise MeshError("g0 must be a finite (n, 4, 4) array of SE(3) frames")
        R = self.g0[:, :3, :3]
        if np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() > 1e-8 or np.any(np.linalg.det(R) < 0):
            raise MeshError("reference rotations are not proper orthonormal matrices")
        if self.quads.ndim != 2 or self.quads.shape[1] != 4 or len(self.quads) == 0:
            raise MeshError("quads must be an (m, 4) integer array with m >= 1")
        if self.quads.min() < 0 or self.quads.max() >= n:
            raise MeshError("quad connectivity refers to nodes that do not exist")
        s = np.sort(self.quads, axis=1)
        if np.any(s[:, 1:] == s[:, :-1]):
            bad = np.nonzero(np.any(s[:, 1:] == s[:, :-1], axis=1))[0][:5]
            raise MeshError(f"quads {bad.tolist()} repeat a node (collapsed element)")
        self._build_edges()
        self._check_geometry()

    @property
    def X(self):
        return self.g0[:, :3, 3]

    @property
    def n_nodes(self):
        return self.g0.shape[0]

    @property
    def n_elements(self):
        return self.quads.shape[0]

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

    def _check_geometry(self):
        # every quad must be convex with positive area about the mean of its nodal normals
        X = self.X[self.quads]                                   # (m,4,3)
        nrm = self.g0[self.quads][:, :, :3, 2].sum(1)
        for k in range(4):
            e1 = X[:, (k + 1) % 4] - X[:, k]
            e2 = X[:, (k + 3) % 4] - X[:, k]
            c = np.einsum("mi,mi->m", np.cross(e1, e2), nrm)
            if np.any(c <= 0):
                bad = np.nonzero(c <= 0)[0][:5]
                raise MeshError(f"quads {bad.tolist()} are degenerate, non-convex or listed clockwise "
                                f"about their normal (corner {k})")

    def node_set(self, name_or_pred):
        """Node ids of a named edge, or of the nodes whose position satisfies a predicate."""
        if callable(name_or_pred):
            return np.nonzero(name_or_pred(self.X))[0]
        try:
            return np.asarray(self.edges[name_or_pred])
        except KeyError:
            raise MeshError(f"unknown node set {name_or_pred!r}; available: {sorted(self.edges)}") from None


def _structured(nx, ny):
    if nx < 1 or ny < 1:
        raise MeshError(f"mesh needs at least 1x1 elements, got {nx}x{ny}")
    ids = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)   # ids[j, i]
    quads = np.stack([ids[:-1, :-1], ids[:-1, 1:], ids[1:, 1:], ids[1:, :-1]], -1).reshape(-1, 4)
    edges = {"x0": ids[:, 0], "x1": ids[:, -1], "y0": ids[0, :], "y1": ids[-1, :]}
    return ids, quads, edges


def rectangle(L, width, nx, ny, x0=0.0):
    """Flat strip [x0, x0+L] x [-width/2, width/2] in the x-y plane, frames = identity."""
    if not (L > 0 and width > 0):
        raise MeshError(f"rectangle needs L > 0 and width > 0, got {L}, {width}")
    ids, quads, edges = _structured(nx, ny)
    x = x0 + np.linspace(0.0, L, nx + 1)
    y = np.linspace(-width / 2, width / 2, ny + 1)
    XX, YY = np.meshgrid(x, y)
    X = np.stack([XX.ravel(), YY.ravel(), np.zeros(XX.size)], -1)
    n = X.shape[0]
    g0 = frames_from(X, np.tile([1.0, 0, 0], (n, 1)), np.tile([0, 0, 1.0], (n, 1)))
    return Mesh(g0, quads, edges, shape=(nx, ny))


def cylinder_arch(R, angle, width, nx, ny):
    """Cylindrical panel of radius R bent in the x-z plane over ``angle`` [rad].

    The arc starts at the origin with tangent +x; the centre of curvature is (0, 0, R); the
    width runs along y.  Frames: d1 = tangent, d2 = +y, d3 = d1 x d2 (toward the centre).
    """
    if not (R > 0 and angle > 0 and width > 0):
        raise MeshError("cylinder_arch needs R, angle, width > 0")
    ids, quads, edges = _structured(nx, ny)
    s = np.linspace(0.0, angle, nx + 1)
    y = np.linspace(-width / 2, width / 2, ny + 1)
    SS, YY = np.meshgrid(s, y)
    S, Y = SS.ravel(), YY.ravel()
    X = np.stack([R * np.sin(S), Y, R * (1 - np.cos(S))], -1)
    d1 = np.stack([np.cos(S), 0 * S, np.sin(S)], -1)
    d3 = np.stack([-np.sin(S), 0 * S, np.cos(S)], -1)
    return Mesh(frames_from(X, d1, d3), quads, edges, shape=(nx, ny))


def cylinder_panel(R, length, theta0, theta1, nt, nl):
    """Cylindrical panel phi0 = (R sin t, s, R cos t), t in [theta0, theta1], s in [0, length].

    The axis is the global y axis.  xi1 = t (edges 'x0' at theta0, 'x1' at theta1), xi2 = s
    (edges 'y0' at s = 0, 'y1' at s = length).  Frames: d1 circumferential, d2 = +y,
    d3 = d1 x d2 = the outward normal (sin t, 0, cos t).  With theta in [-pi/2, pi/2] this is
    the semi-cylinder of Sze et al. 2004, s3.7.
    """
    if not (R > 0 and length > 0 and theta1 > theta0):
        raise MeshError("cylinder_panel needs R > 0, length > 0 and theta1 > theta0")
    ids, quads, edges = _structured(nt, nl)
    t = np.linspace(theta0, theta1, nt + 1)
    s = np.linspace(0.0, length, nl + 1)
    TT, SS = np.meshgrid(t, s)
    T, S = TT.ravel(), SS.ravel()
    X = np.stack([R * np.sin(T), S, R * np.cos(T)], -1)
    d1 = np.stack([np.cos(T), 0 * T, -np.sin(T)], -1)
    d3 = np.stack([np.sin(T), 0 * T, np.cos(T)], -1)
    return Mesh(frames_from(X, d1, d3), quads, edges, shape=(nt, nl))


def _chain(segments):
    """Order the nodes of a set of line segments along the line (or return them sorted)."""
    from collections import defaultdict
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


def from_meshio(source, d1_hint=(1.0, 0.0, 0.0), edges=None):
    """Mesh from any quad surface mesh meshio reads (file name or ``meshio.Mesh``).

    Nodal frames: d3 = area-weighted mean of the adjacent quads' normals (quads must be
    consistently oriented: the normal is the right-hand side of the node order); d1 = the
    projection of ``d1_hint`` on the tangent plane (the global y axis where that degenerates).
    Named node sets: every ``cell_sets`` entry made of line cells (e.g. Gmsh physical curves),
    ordered along the line, plus ``edges`` = {name: predicate(X) -> bool mask}.
    """
    import contextlib
    import io as _io
    import meshio
    said = _io.StringIO()
    try:
        # meshio raises many kinds, and reports some unreadable files by printing and calling
        # sys.exit: both become a MeshError naming the file and the cause
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            m = source if isinstance(source, meshio.Mesh) else meshio.read(source)
    except (Exception, SystemExit) as exc:
        why = " ".join(said.getvalue().split())
        if not isinstance(exc, SystemExit):
            why = f"{type(exc).__name__}: {exc}" + (f" ({why})" if why else "")
        raise MeshError(f"cannot read mesh {source!r}: {why or 'meshio could not read it'}") from None
    X = np.asarray(m.points, float)
    if X.ndim != 2 or X.shape[1] not in (2, 3):
        raise MeshError("mesh points must be 2-D or 3-D")
    if X.shape[1] == 2:
        X = np.c_[X, np.zeros(len(X))]
    quads = [c.data for c in m.cells if c.type == "quad"]
    other = sorted({c.type for c in m.cells} - {"quad", "line", "vertex"})
    if other:
        raise MeshError(f"only quadrilateral shells are supported; the mesh also has {other} cells")
    if not quads:
        raise MeshError("the mesh has no quad cells")
    quads = np.concatenate(quads).astype(np.int64)
    used = np.unique(quads)
    if len(used) < len(X):          # drop points no quad uses (e.g. Gmsh geometry points)
        remap = -np.ones(len(X), np.int64)
        remap[used] = np.arange(len(used))
        quads = remap[quads]
    else:
        remap = np.arange(len(X))
    X = X[used]
    # orientation consistency: each interior edge must be traversed in opposite directions
    cyc = np.stack([quads, np.roll(quads, -1, axis=1)], -1).reshape(-1, 2)
    key = cyc[:, 0] * len(X) + cyc[:, 1]
    u, cnt = np.unique(key, return_counts=True)
    if np.any(cnt > 1):
        bad = u[cnt > 1][0]
        raise MeshError(f"quad normals flip across the edge ({bad // len(X)}, {bad % len(X)}): orient "
                        "all quads consistently (same node order about the surface normal)")
    P = X[quads]
    nq = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])       # 2 x area-weighted normal
    nn = np.zeros_like(X)
    for k in range(4):
        np.add.at(nn, quads[:, k], nq)
    norm = np.linalg.norm(nn, axis=1)
    if np.any(norm <= 0):
        raise MeshError("degenerate quads: a node has no well-defined normal")
    d3 = nn / norm[:, None]
    hint = np.broadcast_to(np.asarray(d1_hint, float), X.shape)
    t = hint - np.einsum("ni,ni->n", hint, d3)[:, None] * d3
    weak = np.linalg.norm(t, axis=1) < 1e-6
    if weak.any():
        alt = np.array([0.0, 1.0, 0.0]) - d3[weak, 1:2] * d3[weak]
        t[weak] = alt
    named = {}
    for name, blocks in (m.cell_sets or {}).items():
        segs = []
        for cb, ids in zip(m.cells, blocks):
            if cb.type == "line" and ids is not None and len(ids):
                segs.extend(remap[cb.data[np.asarray(ids)]].tolist())
        if segs:
            named[name] = _chain(segs)
    mesh = Mesh(frames_from(X, t, d3), quads, named)
    for name, pred in (edges or {}).items():
        mesh.edges[name] = np.nonzero(pred(mesh.X))[0]
    return mesh


def annulus(r_in, r_out, angle, nr, nt):
    """Annular sector in the x-y plane, radius r_in..r_out, polar angle 0..angle (2 pi: slit).

    Parameter xi1 runs along the radius, xi2 around; edges 'x0' (inner), 'x1' (outer),
    'y0' (angle 0), 'y1' (angle ``angle``).  Frames: d1 radial, d3 = +z.
    """
    if not (0 < r_in < r_out and 0 < angle <= 2 * np.pi):
        raise MeshError("annulus needs 0 < r_in < r_out and 0 < angle <= 2 pi")
    ids, quads, edges = _structured(nr, nt)
    r = np.linspace(r_in, r_out, nr + 1)
    t = np.linspace(0.0, angle, nt + 1)
    RR, TT = np.meshgrid(r, t)
    Rr, T = RR.ravel(), TT.ravel()
    X = np.stack([Rr * np.cos(T), Rr * np.sin(T), 0 * T], -1)
    d1 = np.stack([np.cos(T), np.sin(T), 0 * T], -1)
    d3 = np.tile([0, 0, 1.0], (X.shape[0], 1))
    return Mesh(frames_from(X, d1, d3), quads, edges, shape=(nr, nt))

"""Meshes from files: any quad surface mesh meshio reads (Gmsh .msh, .vtu, ...), with Gmsh's named
physical groups as named node sets (curves, points) and element regions (surfaces).

There is one reader, :func:`from_meshio`; scenario files and the Python API both use it.
"""
from __future__ import annotations

import contextlib
import io as _io
import os
import warnings

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import MeshError, MeshWarning
from .core import Mesh, bow_tie_error, chain_order, degenerate_quad_error, frames_from, missing_nodes_error
from .subdivide import split_to_quads

__all__ = ["from_meshio", "read_meshio"]

_DIMS = {"vertex": 0, "line": 1, "triangle": 2, "quad": 2}


def read_meshio(source):
    """A ``meshio.Mesh`` from a file name (or the object itself), with Gmsh physical groups as
    ``cell_sets``; every failure is a MeshError naming the file and the cause.

    meshio reports some unreadable files by printing and calling sys.exit: that output is
    captured and becomes the message.

    Parameters
    ----------
    source : str, path-like or meshio.Mesh
        A file meshio reads (Gmsh ``.msh`` 2.2 or 4, ``.vtu``, ...), or a mesh already read.

    Returns
    -------
    meshio.Mesh
        The mesh (the same object when one is given), its ``cell_sets`` filled from Gmsh 2.2
        physical tags when the reader left them empty.

    Example
    -------
    >>> import meshio, numpy as np
    >>> raw = meshio.Mesh(np.zeros((4, 3)), [("quad", np.array([[0, 1, 2, 3]]))])
    >>> read_meshio(raw) is raw
    True
    >>> read_meshio("no-such-file.msh")
    Traceback (most recent call last):
    ...
    core_se3.errors.MeshError: cannot read mesh 'no-such-file.msh': ReadError: File no-such-file.msh not found.
    """
    import meshio
    if isinstance(source, meshio.Mesh):
        _physical_sets(source)
        return source
    said = _io.StringIO()
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            raw = meshio.read(source)
        _physical_sets(raw)
    except (Exception, SystemExit) as exc:
        why = " ".join(said.getvalue().split())
        if not isinstance(exc, SystemExit):
            why = f"{type(exc).__name__}: {exc}" + (f" ({why})" if why else "")
        raise MeshError(f"cannot read mesh {source!r}: {why or 'meshio could not read it'}") from None
    _warn_shared_names(source, raw)
    return raw


def _gmsh_physical_names(path):
    """[(dim, tag, name)] of a Gmsh file's $PhysicalNames section (text in ASCII and binary
    files, near the start), [] where there is none or it cannot be parsed."""
    with open(path, "rb") as fh:
        head = fh.read(1 << 22)
    a = head.find(b"$PhysicalNames")
    b = head.find(b"$EndPhysicalNames", a)
    if a < 0 or b < 0:
        return []
    out = []
    try:
        for line in head[a:b].decode("utf-8", "replace").splitlines()[2:]:
            dim, tag, name = line.split(maxsplit=2)
            out.append((int(dim), int(tag), name.strip().strip('"')))
    except ValueError:
        return []
    return out


def _warn_shared_names(source, raw):
    """A MeshWarning for a name that a Gmsh file gives to several physical groups (a curve and a
    point, or two surfaces): meshio keeps one group per name, the others come named by their
    numbers, so ``edge = "NAME"`` found one of them (a region's name used for a point group of
    the same name selected every node of the region)."""
    if not isinstance(source, (str, bytes)) and not hasattr(source, "__fspath__"):
        return
    if not str(os.fspath(source)).lower().endswith(".msh"):
        return
    groups = {}
    for dim, tag, name in _gmsh_physical_names(source):
        groups.setdefault(name, []).append((dim, tag))
    kinds = ("point", "curve", "surface", "volume")
    for name, tags in groups.items():
        if len(tags) < 2:
            continue
        kept = tuple(int(x) for x in np.asarray((raw.field_data or {}).get(name, [-1, -1])).ravel()[:2][::-1])
        others = [f"the {kinds[d] if 0 <= d < 4 else 'group'} {t} as {str(t)!r}" for d, t in tags if (d, t) != kept]
        warnings.warn(MeshWarning(
            f"mesh file: {len(tags)} physical groups are named {name!r} ("
            + ", ".join(f"{kinds[d] if 0 <= d < 4 else 'group'} {t}" for d, t in tags)
            + f"): a name selects one group, so {name!r} is the "
            + (f"{kinds[kept[0]]} {kept[1]}" if 0 <= kept[0] < 4 else "first") + " and the others come by number ("
            + ", ".join(others) + "); give each physical group its own name"), stacklevel=3)


def _physical_sets(raw):
    """Cell sets from Gmsh physical tags (``gmsh:physical`` cell data; names from field_data
    name -> [tag, dim]): the named groups when the reader left ``cell_sets`` without them (Gmsh
    2.2 files), and a group without a name (a physical tag alone) as the set named by its number,
    e.g. "1" (it was dropped: a scenario's edge = "1" found no named edge)."""
    phys = (raw.cell_data or {}).get("gmsh:physical")
    if phys is None:
        return
    names = {}
    for name, fd in (raw.field_data or {}).items():
        fd = np.asarray(fd).ravel()
        if len(fd) >= 2:
            names[int(fd[1]), int(fd[0])] = str(name)
    have = any(not str(k).startswith("gmsh:") for k in (raw.cell_sets or {}))
    sets = {}
    for i, (cb, p) in enumerate(zip(raw.cells, phys)):
        dim, p = _DIMS.get(cb.type), np.asarray(p).ravel()
        for tag in (np.unique(p[p > 0]) if dim is not None else []):
            name = names.get((dim, int(tag)))
            if name is None or not have:
                per = sets.setdefault(name or str(int(tag)), [np.zeros(0, np.int64)] * len(raw.cells))
                per[i] = np.nonzero(p == tag)[0]
    if sets:
        raw.cell_sets = {**(raw.cell_sets or {}), **{k: v for k, v in sets.items() if k not in (raw.cell_sets or {})}}


def _named_sets(raw):
    """name -> per-block index arrays of the file's named cell sets (Gmsh physical groups),
    leaving out meshio's own ``gmsh:*`` sets (``gmsh:bounding_entities`` holds entity tags,
    not cell indices: taking it for a group crashed MSH 4.1 files)."""
    out = {}
    for name, blocks in (raw.cell_sets or {}).items():
        if str(name).startswith("gmsh:"):
            continue
        blocks = list(blocks) + [None] * (len(raw.cells) - len(blocks))
        out[str(name)] = [None if b is None else np.asarray(b, np.int64).ravel() for b in blocks]
    return out


def _physical_dims(raw):
    """The dimensions of the file's physical groups (Gmsh ``field_data`` name -> [tag, dim])."""
    dims = set()
    for fd in (raw.field_data or {}).values():
        fd = np.asarray(fd).ravel()
        if len(fd) >= 2:
            dims.add(int(fd[1]))
    return dims


def from_meshio(source, d1_hint=None, edges=None, triangles="error"):
    """Mesh from any quad surface mesh meshio reads (file name or ``meshio.Mesh``): Gmsh MSH 4.1
    and 2.2, ASCII and binary, VTU, ...

    Nodal frames: d3 = area-weighted mean of the adjacent quads' normals (quads must be
    consistently oriented: the normal is the right-hand side of the node order), on doubly curved
    parts the normal of a quadric fitted to each node's ring (the mean is off by half an element's
    angle at a boundary and by the distortion inside, which thin domes feel), at the boundary of
    a curved developable part (a tube) the neighbours' normals reflected across the chords
    (``_boundary_normals``: exact on a circle).  Without a
    ``d1_hint``, d1 = the projection of +x on flat and developable parts (where the element makes
    the frames parallel whatever d1 is: ``mesh.gauge``), and on doubly curved parts (domes,
    spheres, bellows, whose frames it keeps as given) d1 along the mesh's own edges
    (:func:`~core_se3.mesh.cross_field.edge_aligned_d1`: a lat-long mesh gets its meridian or
    parallel frames; the projection of a constant hint locked the thin whole hemisphere, R/h 1e4:
    0.30 / 0.47 / 0.93 of the meridian frames' deflection on 4x4 / 8x8 / 16x16 per quarter).
    With a ``d1_hint``, d1 = its projection on the tangent plane everywhere (the global y axis
    where that degenerates, x where y does too); on a doubly curved part d1 turning by more than
    D1_TURN_MAX = 30 deg within a quad (a hint nearly normal to the shell there) is then a
    MeshWarning: the answer depends on it.
    Named groups (Gmsh physical groups, meshio cell sets; a physical group without a name is
    named by its number, e.g. "1", as is every group but one of a name that a Gmsh file gives to
    several groups, with a MeshWarning; point sets such as Abaqus' ``*NSET`` are node sets of
    their points; an element repeated in a Gmsh file (MSH 2.2: once per group) is read once):
    a group of line cells (a physical
    curve) becomes a node set in ``edges``, ordered along the line; a group of vertex cells (a
    physical point) a node set of those nodes; a group of quads (a physical surface) a region.
    ``edges`` = {name: predicate(X) -> bool mask} adds node sets.

    Element ids are the quads counted from 0 in the order read, not the file's element numbers
    (meshio keeps no Gmsh tags): ``mesh.element_numbering`` says why they differ (a Gmsh file,
    other cells, split triangles), else None.
    Points that no quad uses (e.g. Gmsh geometry points) are dropped (``mesh.dropped_points``:
    their ids when that renumbers the points after them, else None); line and vertex cells are
    allowed; a group of lines off the quads is a MeshError.  Triangles (a quad-dominant mesh) are a MeshError naming the fixes, unless
    ``triangles="split"``: then every cell is split conformingly into quads (each quad into 4,
    each triangle into 3, lines into 2; :func:`~core_se3.mesh.subdivide.split_to_quads`) and the
    groups follow their cells.  Quads oriented oppositely across a cut (distinct nodes at one
    point) or between separate parts (opposite mean normals) are a MeshWarning, as are distinct
    nodes at one point.  Any other cell type, quads whose orientation flips across an
    edge, and a file without quads (Gmsh saves only the elements of physical groups: a file
    with physical curves but no physical surface has none) are MeshErrors.

    Parameters
    ----------
    source : str, path-like or meshio.Mesh
        The file (or mesh); see :func:`read_meshio`.
    d1_hint : (3,) or (n, 3) array_like, optional
        Lab direction of the first director, projected on each node's tangent plane (per node:
        e.g. a dome's meridians).  Default None: +x on flat and developable parts, along the
        mesh's edges on doubly curved ones.
    edges : dict, optional
        Extra node sets: name -> predicate of the reference positions X (n, 3) returning a
        boolean mask.
    triangles : {"error", "split"}, optional
        What to do with triangles (default: a MeshError).

    Returns
    -------
    Mesh
        Unstructured (``shape`` None), in the file's length unit.

    Example
    -------
    >>> import os, core_se3
    >>> path = os.path.join(os.path.dirname(core_se3.__file__), "..", "examples", "gripper.msh")
    >>> m = from_meshio(path)
    >>> sorted(m.regions)[:2], "tip_px" in m.edges
    (['finger_mx', 'finger_my'], True)

    A lat-long dome written without frames comes back with d1 along its meridians (or parallels):

    >>> import meshio, numpy as np
    >>> lat, lon = np.meshgrid(np.linspace(0.0, 1.2, 5), np.linspace(0.0, 2 * np.pi, 17)[:-1], indexing="ij")
    >>> X = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], -1).reshape(-1, 3)
    >>> i = np.arange(80).reshape(5, 16)
    >>> q = np.stack([i[:-1], np.roll(i, -1, 1)[:-1], np.roll(i, -1, 1)[1:], i[1:]], -1).reshape(-1, 4)
    >>> dome = from_meshio(meshio.Mesh(X, [("quad", q)]))
    >>> lon_dir = np.stack([-np.sin(lon), np.cos(lon), 0 * lon], -1).reshape(-1, 3)     # the parallels
    >>> bool(np.all(np.minimum(*[abs(1 - abs(np.sum(dome.g0[:, :3, k] * lon_dir, 1))) for k in (0, 1)]) < 1e-12))
    True
    """
    if triangles not in ("error", "split"):
        raise MeshError(f"triangles must be 'error' or 'split', got {triangles!r}")
    raw = read_meshio(source)
    X, blocks, sets, qb = _cell_blocks(raw, triangles)
    quads, remap = _oriented_quads(X, blocks, qb)
    X = X[remap >= 0]
    t, d3 = _nodal_directors(X, quads, DEFAULT_HINT if d1_hint is None else d1_hint)
    named, regions = _named_groups(sets, blocks, qb, remap)
    for name, nodes in _point_sets(raw, remap).items():
        named.setdefault(name, nodes)           # a group of lines of the same name keeps its order
    try:
        mesh = Mesh(frames_from(X, t, d3), quads, named, regions=regions)
    except MeshError:                         # a degenerate quad: named by the file's point ids
        why = degenerate_quad_error(np.flatnonzero(remap >= 0)[quads], X[quads], d3[quads].sum(1), "quad cell")
        if not why:
            raise
        raise MeshError(f"mesh file: {why} (point ids of the file)") from None
    _curved_part_frames(mesh, d1_hint)
    for name, pred in (edges or {}).items():
        mesh.edges[name] = np.nonzero(pred(mesh.X))[0]
    # the file's points that no quad uses, when dropping them renumbered the nodes after them
    # (node ids then differ from the file's point ids: scenario.geometry says so where ids are used)
    dropped = np.flatnonzero(remap < 0)
    mesh.dropped_points = dropped if len(dropped) and dropped[0] < len(remap) - len(dropped) else None
    mesh.element_numbering = _element_numbering(raw, blocks, qb)
    _warn_orientation(X, quads, _warn_coincident(X))
    if d1_hint is not None:                # the default's d1 follows the edges (jumps at irregular nodes)
        _warn_turning_d1(mesh)
    return mesh


#: the lab direction whose projection is d1 on flat and developable parts when no d1_hint is given
DEFAULT_HINT = (1.0, 0.0, 0.0)


def _curved_part_frames(mesh, d1_hint):
    """The frames of the doubly curved parts (those whose frames the least-turn gauge cannot make
    parallel, ``mesh.gauge``), in place: d3 the normal of a quadric fitted to each node's ring
    (``_fitted_normals``), and without a d1_hint d1 along the mesh's own edges
    (:func:`~core_se3.mesh.cross_field.edge_aligned_d1`) instead of DEFAULT_HINT's projection.
    Flat and developable parts keep theirs (the gauge decides there, and their angles are kept:
    the same element to the bit).  A projected constant hint locked the thin whole hemisphere
    (R/h 1e4: 0.30 / 0.47 / 0.93 of its meridian frames' deflection on 4x4 / 8x8 / 16x16 per
    quarter); the edges' own directions are its meridians (docs/ELEMENTS.md, "Nodal frames")."""
    from .cross_field import edge_aligned_d1
    from .gauge import least_turn_gauge
    alpha, curved = least_turn_gauge(mesh.g0, mesh.edge_nodes)
    moved = _boundary_normals(mesh, ~curved)
    if moved.any():                            # a curved developable part's edge: its normals and gauge again
        d1 = _projected_hint(DEFAULT_HINT if d1_hint is None else d1_hint, mesh.g0[:, :3, 2])
        mesh.g0[moved] = frames_from(mesh.X[moved], d1[moved], mesh.g0[moved, :3, 2])
        alpha, curved = least_turn_gauge(mesh.g0, mesh.edge_nodes)
    mesh.gauge_angles = alpha                  # the element's gauge (it would compute the same)
    if not curved.any():
        return
    d3 = mesh.g0[:, :3, 2].copy()
    boundary = np.zeros(mesh.n_nodes, bool)
    boundary[mesh.edge_nodes[mesh.boundary_edges()[0]].ravel()] = True
    d3[curved] = _fitted_normals(mesh.X, mesh.quads, d3, boundary)[curved]
    if d1_hint is None:
        d1 = edge_aligned_d1(mesh.X, mesh.quads, d3, edges=mesh.edge_nodes)
    else:
        d1 = _projected_hint(d1_hint, d3)
    mesh.g0[curved] = frames_from(mesh.X[curved], d1[curved], d3[curved])


def _boundary_normals(mesh, part):
    """At the boundary nodes of ``part`` (n,) bool (the flat and developable parts) the quads' mean
    normal, off by half an element's angle on a curved edge (a half tube of 15 deg elements: 7.5
    deg, its chords' mismatch |c . (n_a + n_b)| / |c| 0.13, ``fem.warp.check_chord_normals``; the
    answer 1.2 % off), replaced in ``mesh.g0``'s d3 (in place) by the mean of its neighbours'
    normals reflected across the planes normal to the chords, n_b - 2 (n_b . c) c / |c|^2 (exact on
    a circle, hence a cylinder): first from interior neighbours, then a corner from the boundary
    nodes so set.  Changes below 1e-9 rad are not made (a flat part keeps its frames to the bit).
    Returns the nodes changed (n,) bool."""
    n, E = mesh.n_nodes, mesh.edge_nodes
    d3 = mesh.g0[:, :3, 2]
    todo = np.zeros(n, bool)
    todo[E[mesh.boundary_edges()[0]].ravel()] = True
    known, todo = ~todo, todo & part
    a, b = np.concatenate([E[:, 0], E[:, 1]]), np.concatenate([E[:, 1], E[:, 0]])
    c = mesh.X[b] - mesh.X[a]
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    new = d3.copy()
    for _ in range(2):                         # the edges' nodes, then the corners
        use = todo[a] & known[b]
        r = new[b] - 2.0 * np.einsum("ei,ei->e", new[b], c)[:, None] * c
        s = np.stack([np.bincount(a[use], r[use, i], n) for i in range(3)], 1)
        got = todo & (np.bincount(a[use], minlength=n) > 0)
        new[got] = s[got] / np.linalg.norm(s[got], axis=1, keepdims=True)
        known, todo = known | got, todo & ~got
    moved = np.linalg.norm(np.cross(new, d3), axis=1) > 1e-9
    mesh.g0[moved, :3, 2] = new[moved]         # (the caller makes the frames orthonormal again)
    return moved


#: the largest turn [deg] of a fitted normal from the quads' mean normal (else the mean is kept)
FIT_TURN_MAX = 30.0


#: a boundary node's two-ring quadric with anisotropy below this fraction of its mean curvature
#: is a sphere's: the one-curvature fit is kept there
UMBILIC = 0.1


def _fitted_normals(X, quads, d3, boundary):
    """Unit normals (n, 3): at each node the normal at the node of the quadric z = d x + e y +
    a x^2 + b x y + c y^2 fitted (least squares) in the frame of its quads' mean normal d3 to the
    nodes of its quads (8 or more inside; an irregular interior node with fewer, z = d x + e y +
    k (x^2 + y^2)) or, at a ``boundary`` (n,) bool node, to those of its two rings (its quads'
    nodes and theirs: 14 at an edge node of a structured mesh, 8 at a corner).  Where there are
    too few points, or the fit turns from d3 by more than FIT_TURN_MAX, d3.  The mean of the
    quads' normals is off by half an element's angle at a boundary and by the mesh's distortion
    inside: the thin whole hemisphere from a file (R/h 1e4, 4x4) gave 0.978 of its exact normals'
    deflection, a quarter with interior nodes moved by 0.3 of the spacing (16x16) 0.64 ... 0.81;
    with the fitted normals 1.001 and 1.00 ... 1.01 (benchmarks/results/curved_frames.md).  At a
    boundary one ring is one-sided: its full quadric extrapolates (10 deg off on a cubed cap's
    edge), one curvature misses unequal ones (an ellipsoid's cap, tests/test_element.py: 12.9 /
    4.3 / 3.0 deg on 4x4 / 8x8 / 16x16, 0.53 / 0.16 / 0.05 inside); the two rings' quadric 1.3 /
    0.48 / 0.16.  It is taken at a boundary node unless it is umbilic (anisotropy |(a - c, b)| <=
    UMBILIC |a + c|: a sphere, where one curvature is exact) or agrees worse with the node's chords,
    sum (c . (n_a + n_b))^2 / |c|^2 (``fem.warp.chord_normal_mismatch``'s measure; on coarse wide
    rings the quadric misfits: an ellipsoidal dome's equator on 4x4 per quarter, 8.8 deg, its
    answer 0.06 of the exact normals'; now 0.993) (docs/ELEMENTS.md, "A mesh file's own normals")."""
    n = len(X)
    pairs = np.concatenate([np.stack([quads[:, i], quads[:, j]], 1) for i in range(4) for j in range(4) if i != j])
    key = np.unique(pairs[:, 0] * n + pairs[:, 1])
    a, b = key // n, key % n
    count = np.bincount(a, minlength=n)
    v = _quadric_normals(X, a, b, d3, count >= 8)[0]
    at = np.flatnonzero(boundary[a])           # (a, b) at a boundary node a, then b's ring (b, c)
    k = count[b[at]]
    first = np.searchsorted(a, b[at])          # b's ring: its pairs from here on
    aa, cc = np.repeat(a[at], k), b[np.repeat(first - np.cumsum(k) + k, k) + np.arange(k.sum())]
    two = np.unique(np.concatenate([key[at], (aa * n + cc)[aa != cc]]))
    w, (p, q, r) = _quadric_normals(X, two // n, two % n, d3, np.ones(n, bool))
    use = boundary & (np.hypot(p - r, q) > UMBILIC * np.abs(p + r))     # else one curvature fits
    c = X[b] - X[a]
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    u = np.where(use[:, None], w, v)
    mu2 = [np.bincount(a, np.einsum("pi,pi->p", c, s[a] + s[b]) ** 2, n) for s in (u, v)]
    use &= mu2[0] <= mu2[1]                    # the one agreeing better with its chords
    v[use] = w[use]
    return v


def _quadric_normals(X, a, b, d3, full):
    """The normals of ``_fitted_normals`` fitted at each node a to its points b (pairs (a, b),
    each once; lengths in units of their rms): the full quadric where ``full`` (n,) bool and 5
    points or more, else one curvature k (x^2 + y^2) with 3 or more; none (d3) with fewer."""
    n = len(X)
    t1 = np.cross(d3, np.where(np.abs(d3[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]]))
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(d3, t1)
    V = X[b] - X[a]
    count = np.bincount(a, minlength=n)
    L = np.sqrt(np.bincount(a, np.einsum("pi,pi->p", V, V), n) / np.maximum(count, 1))
    x, y, z = (np.einsum("pi,pi->p", V, t[a]) / L[a] for t in (t1, t2, d3))
    slopes = []
    for A in (np.stack([x, y, x * x, x * y, y * y], 1), np.stack([x, y, x * x + y * y], 1)):
        k = A.shape[1]
        AtA, Atz = np.zeros((n, k, k)), np.zeros((n, k))
        for i in range(k):                     # per entry: memory of the pairs, not 25 times it
            Atz[:, i] = np.bincount(a, A[:, i] * z, n)
            for j in range(i, k):
                AtA[:, i, j] = AtA[:, j, i] = np.bincount(a, A[:, i] * A[:, j], n)
        AtA[count < k] = np.eye(k)
        slopes.append(np.linalg.solve(AtA + 1e-12 * np.eye(k), Atz[..., None])[..., 0])
    full = full & (count >= 5)
    c = np.where(full[:, None], slopes[0][:, :2], slopes[1][:, :2])
    v = d3 - c[:, :1] * t1 - c[:, 1:2] * t2
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    keep = (count < 3) | (np.einsum("ni,ni->n", v, d3) < np.cos(np.radians(FIT_TURN_MAX)))
    v[keep] = d3[keep]
    return v, slopes[0][:, 2:].T


#: the element's d1 turning by more than this within a quad [deg] (on a doubly curved part, which
#: keeps the user's frames: ``mesh.gauge``) warns
D1_TURN_MAX = 30.0


def _warn_turning_d1(mesh):
    """A MeshWarning where the element's d1 turns by more than D1_TURN_MAX degrees about the
    normal within one quad, for a given d1_hint (the default's d1 follows the edges, and turns by a
    quarter turn across a few quads about irregular nodes on purpose: ``mesh.cross_field``).  The
    nodal d1 is d1_hint projected on each node's tangent plane, which
    turns fast where the hint is nearly normal to the shell (a tube about z with the default hint
    +x flips d1 by 180 deg along the line where d3 = +x).  The element builds its frames in the
    least-turn gauge (``mesh.gauge``), which undoes any such turn on flat and developable parts
    (on a half cylinder, tests/test_mesh_file_frames.py, a hint 3 deg off the normal, d1 turning by
    79 deg, had moved the tip by 4.6 % of its travel and a flip by 180 deg stopped the solve; both
    now give the answer of a good hint to 6e-12).  A doubly curved part keeps the user's frames, so
    there the hint still matters (a spherical cap whose d1 flips within a quad cannot be solved:
    ElementTooDistortedError), and this warning says so."""
    from .gauge import turned_about_normal
    P = mesh.X[mesh.quads]
    nq = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])
    nq /= np.linalg.norm(nq, axis=1, keepdims=True)
    d1 = turned_about_normal(mesh.g0, mesh.gauge_angles)[mesh.quads][:, :, :3, 0]
    t = d1 - np.einsum("eki,ei->ek", d1, nq)[..., None] * nq[:, None]
    t /= np.maximum(np.linalg.norm(t, axis=2, keepdims=True), 1e-300)
    turn = np.degrees(np.arccos(np.clip(np.einsum("eki,eli->ekl", t, t).min(axis=(1, 2)), -1.0, 1.0)))
    bad = np.flatnonzero(turn > D1_TURN_MAX)
    if len(bad):
        k = bad[np.argmax(turn[bad])]
        warnings.warn(MeshWarning(
            f"mesh file: the first director d1 (d1_hint projected on the tangent plane) turns by {turn[k]:.0f} deg "
            f"within quad {k} (nodes {mesh.quads[k].tolist()}; {len(bad)} quad(s) above {D1_TURN_MAX:g} deg): d1_hint "
            f"is nearly normal to the shell there, and on a doubly curved shell (whose frames the element cannot make "
            f"parallel) its answer depends on d1 turning within the quads, for any material (a flip by 180 deg cannot be "
            f"solved). Give a d1_hint that lies along the shell everywhere (e.g. a dome's meridians or parallels), or one "
            f"hint per node"), stacklevel=3)


def _element_numbering(raw, blocks, qb):
    """Why the mesh's element ids (its quads counted from 0 in the order read) are not the ids the
    file shows, or None when they are (a file of quads only that is no Gmsh file: VTU cell ids).
    meshio keeps no element tags, so ids cannot be mapped back: Gmsh numbers every element
    (points, lines, quads) from 1."""
    gmsh = any(str(k).startswith("gmsh:") for k in (raw.cell_data or {}))
    other = sum(len(c) for i, (t, c) in enumerate(blocks) if i not in qb)
    split = sum(len(blocks[i][1]) for i in qb) != sum(len(c.data) for c in raw.cells if c.type == "quad")
    if not (gmsh or other or split):
        return None
    why = ("the file is a Gmsh mesh, whose element tags count every element (points, lines, quads) from 1" if gmsh
           else "its cells were split into quads (triangles = \"split\")" if split
           else f"the file has {other} cells that are not quads, not counted")
    return f"element ids count the mesh's quads from 0 in the order read, not the file's element numbers: {why}"


#: nodes closer than this fraction of the mesh's extent are one point (Gmsh's Geometry.Tolerance)
COINCIDENT = 1e-8


def _warn_coincident(X):
    """A MeshWarning if distinct nodes of X (n, 3) lie at one point: the quads on either side
    do not share them, so the shell is cut there (surfaces meshed separately, or two meshes put
    together without merging their nodes); each side of the cut is a free edge and the answer
    that of two shells (two strips clamped at their far ends and joined that way: two
    cantilevers).  A slit may be meant (Sze et al.'s slit ring), so it is a warning."""
    from scipy.spatial import cKDTree
    r = COINCIDENT * max(float(np.ptp(X, axis=0).max(initial=0.0)), 1e-300)
    pairs = cKDTree(X).query_pairs(r, output_type="ndarray")
    if len(pairs):
        shown = ", ".join(f"{a}-{b}" for a, b in pairs[:4].tolist()) + (", ..." if len(pairs) > 4 else "")
        warnings.warn(MeshWarning(
            f"mesh file: {len(pairs)} pair(s) of distinct nodes lie at one point (nodes {shown}, within {r:.2g}): "
            f"the elements on either side do not share them, so the shell is cut there and each side is a free "
            f"edge (surfaces meshed without a shared curve, or meshes put together without merging their nodes). "
            f"If the cut is not meant, merge the nodes (Gmsh: Coherence, or Geometry.Tolerance; meshio: "
            f"remove the duplicates) and read the mesh again; a slit that is meant may stay."), stacklevel=3)
    return pairs


#: parts whose area-weighted mean unit normals have a dot product below this face opposite ways
OPPOSITE = -0.5


def _warn_orientation(X, quads, pairs):
    """MeshWarnings for quads oriented oppositely where the edge check cannot see it (the normal
    d3 is the right-hand side of each quad's node order, and a follower pressure, a follower
    force along d3 and a magnet's ``Br_frame`` act along it): across a cut (nodes at one point,
    ``pairs``: taken as one node, an edge then traversed twice the same way), and between
    separate parts (mean unit normals, each part at least half flat, with a dot product below
    OPPOSITE).  Two parts may face each other on purpose (two jaws), so these are warnings."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    n = len(X)
    one = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)) if len(pairs) else None
    rep = connected_components(one, directed=False)[1] if one is not None else np.arange(n)
    cyc = np.stack([rep[quads], np.roll(rep[quads], -1, axis=1)], -1).reshape(-1, 2)
    cyc = cyc[cyc[:, 0] != cyc[:, 1]]
    u, first, cnt = np.unique(cyc[:, 0] * n + cyc[:, 1], return_index=True, return_counts=True)
    if np.any(cnt > 1):
        a, b = cyc[first[np.argmax(cnt > 1)]]
        at = ", ".join(f"{k}-{'-'.join(map(str, np.flatnonzero(rep == rep[k])[1:]))}" for k in
                       (np.flatnonzero(rep == a)[0], np.flatnonzero(rep == b)[0]))
        warnings.warn(MeshWarning(
            f"mesh file: the quads on either side of the cut at nodes {at} (distinct nodes at one point) are "
            f"oriented oppositely: their normals d3 (the right-hand side of the node order) point opposite ways, "
            f"so a follower pressure, a follower force along d3 or a magnet's Br_frame acts opposite ways on the two "
            f"sides; orient all quads consistently (Gmsh: gmsh.model.mesh.reverse on one surface) and merge the "
            f"nodes"), stacklevel=3)
    _warn_opposite_parts(X, quads, rep, cyc)


def _warn_opposite_parts(X, quads, rep, cyc):
    """The MeshWarning of _warn_orientation for separate parts facing opposite ways (cyc: the
    quads' edges between merged nodes ``rep``)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    n = len(X)
    k, part = connected_components(coo_matrix((np.ones(len(cyc)), (cyc[:, 0], cyc[:, 1])), shape=(n, n)),
                                   directed=False)
    if k < 2:
        return
    P = X[quads]
    nq = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])        # 2 x area-weighted normal
    of = part[rep[quads[:, 0]]]
    total, area = np.zeros((n, 3)), np.zeros(n)
    np.add.at(total, of, nq)
    np.add.at(area, of, np.linalg.norm(nq, axis=1))
    parts = np.unique(of)
    mean = total[parts] / np.maximum(area[parts], 1e-300)[:, None]
    flat = np.linalg.norm(mean, axis=1) > 0.5
    unit = mean / np.maximum(np.linalg.norm(mean, axis=1), 1e-300)[:, None]
    dots = np.where(np.outer(flat, flat), unit @ unit.T, 1.0)
    if dots.min() >= OPPOSITE:
        return
    i, j = np.unravel_index(np.argmin(dots), dots.shape)
    show = [f"the part of quad {int(np.flatnonzero(of == parts[m])[0])} ({int(np.sum(of == parts[m]))} quads, mean "
            f"normal {np.round(unit[m], 3).tolist()})" for m in (i, j)]
    warnings.warn(MeshWarning(
        f"mesh file: the mesh has {k} separate parts, and {show[0]} faces opposite to {show[1]}: the normal d3 "
        f"is the right-hand side of each quad's node order, so a follower pressure, a follower force along d3 or "
        f"a magnet's Br_frame acts opposite ways on the two. If they should face the same way, reverse one part's "
        f"node order (Gmsh: gmsh.model.mesh.reverse on its surface); parts that face each other on purpose may "
        f"stay"), stacklevel=3)


def _cell_blocks(m, triangles):
    """Points (n, 3), cell blocks [(type, cells)], named sets and the indices of the quad blocks
    of a meshio mesh (triangles split into quads with ``triangles="split"``); other cells, or no
    quad at all, a MeshError naming the fix."""
    X = np.asarray(m.points, float)
    if X.ndim != 2 or X.shape[1] not in (2, 3):
        raise MeshError("mesh points must be 2-D or 3-D")
    if X.shape[1] == 2:
        X = np.c_[X, np.zeros(len(X))]
    blocks = [(c.type, np.asarray(c.data, np.int64)) for c in m.cells]
    bad = [(t, c) for t, c in blocks if c.size and (c.min() < 0 or c.max() >= len(X))]
    if bad:
        ids = np.concatenate([c.ravel() for _, c in blocks if c.size])
        why = missing_nodes_error(bad[0][1], len(X), f"{bad[0][0]} cell").split(": ", 1)[0]
        fix = ("the file's point ids look numbered from 1 (no cell uses point 0, the largest id is the number of "
               "points): a writer of this file took them from 1 -- write it with ids from 0 (meshio.Mesh(points, "
               "cells) with cells - 1)" if ids.min() >= 1 and ids.max() == len(X) else
               "the file is inconsistent; write it again")
        raise MeshError(f"the mesh's {sorted({t for t, _ in bad})} cells refer to points that do not exist (it has "
                        f"{len(X)} points; {why}): {fix}")
    sets = _named_sets(m)
    blocks = _merge_repeated(m, blocks, sets)
    types = {t for t, _ in blocks}
    other = sorted(types - {"quad", "line", "vertex"})
    if other == ["triangle"] and triangles == "split" and "quad" in types | {"triangle"}:
        X, blocks, kids = split_to_quads(X, blocks)
        sets = {name: [None if ids is None or not len(ids) else np.sort(k[ids].ravel())
                       for ids, k in zip(per, kids)] for name, per in sets.items()}
        other = []
    if other:
        hint = (": a quad-dominant mesh (quads and triangles) becomes all quads with triangles = "
                "\"split\" ([mesh] triangles, or mesh.from_meshio(..., triangles=\"split\")), or in "
                "Gmsh with Mesh.RecombineAll = 1 and Mesh.SubdivisionAlgorithm = 1"
                if other == ["triangle"] else
                ": second-order elements; mesh with first-order ones (Gmsh: Mesh.ElementOrder = 1)"
                if set(other) <= {"quad8", "quad9", "line3", "triangle6", "vertex"} else "")
        raise MeshError(f"only quadrilateral shells are supported; the mesh also has {other} cells{hint}")
    qb = [i for i, (t, c) in enumerate(blocks) if t == "quad" and len(c)]
    if not qb:
        hint = ""
        if types & {"line", "vertex"} and 2 not in _physical_dims(m) and _physical_dims(m):
            hint = ("; the file has physical groups of curves or points but none of surfaces, and "
                    "Gmsh then saves only the elements of physical groups: add a physical surface "
                    "(e.g. gmsh.model.addPhysicalGroup(2, [...], name=\"shell\")) or set "
                    "Mesh.SaveAll = 1 before writing")
        raise MeshError("the mesh has no quad cells" + hint)
    return X, blocks, sets, qb


def _merge_repeated(raw, blocks, sets):
    """The cell blocks with each repeated cell (the same nodes in the same order) once, ``sets``
    updated in place to the kept cells.  Gmsh MSH 2.2 writes an element once per physical group
    it is in (a surface in the groups "shell" and "magnet" gave every quad twice, and the reader
    said the normals flip); a repeated quad in another file is a MeshError (its stiffness and
    loads would count twice)."""
    gmsh = "gmsh:physical" in (raw.cell_data or {})
    out = []
    for i, (typ, cells) in enumerate(blocks):
        if len(cells) < 2 or cells.ndim != 2:
            out.append((typ, cells))
            continue
        _, first, inv = np.unique(cells, axis=0, return_index=True, return_inverse=True)
        if len(first) == len(cells):
            out.append((typ, cells))
            continue
        if typ == "quad" and not gmsh:
            twice = np.flatnonzero(np.bincount(inv.ravel()) > 1)[0]
            a, b = np.flatnonzero(inv.ravel() == twice)[:2]
            raise MeshError(f"quad cells {a} and {b} of a block list the same nodes {cells[a].tolist()}: an element "
                            f"given twice would count its stiffness and loads twice; remove the repeated cells")
        rank = np.empty(len(first), np.int64)
        rank[np.argsort(first)] = np.arange(len(first))     # the kept cells in the order first read
        new = rank[inv.ravel()]
        out.append((typ, cells[np.sort(first)]))
        for per in sets.values():
            if i < len(per) and per[i] is not None:
                per[i] = np.unique(new[per[i]])
    return out


def _oriented_quads(X, blocks, qb):
    """The quads renumbered over the points they use, and remap (point -> node, -1 for a point no
    quad uses); quads whose orientation flips across an edge are a MeshError."""
    quads = np.concatenate([blocks[i][1] for i in qb]).astype(np.int64)
    why = bow_tie_error(quads, X[quads], "quad cell") if np.isfinite(X[quads]).all() else ""
    if why:                         # before the orientation checks, which would call it a flip
        raise MeshError(f"mesh file: {why} (point ids of the file)")
    used = np.unique(quads)
    remap = -np.ones(len(X), np.int64)
    remap[used] = np.arange(len(used))
    quads = remap[quads]
    n = len(used)
    inf = used[~np.isfinite(X[used]).all(axis=1)]
    if len(inf):
        raise MeshError(f"mesh points {inf[:5].tolist()}{' ...' if len(inf) > 5 else ''} ({len(inf)} of the quads' "
                        f"{n}) have coordinates that are not finite (nan or inf): the file is damaged or was "
                        f"written from a failed computation; write it again")
    # orientation consistency: each interior edge must be traversed in opposite directions
    cyc = np.stack([quads, np.roll(quads, -1, axis=1)], -1).reshape(-1, 2)
    key = cyc[:, 0] * n + cyc[:, 1]
    u, cnt = np.unique(key, return_counts=True)
    if np.any(cnt > 1):
        raise MeshError(_flip_message(quads, used, key, u[cnt > 1][0]))
    return quads, remap


def _flip_message(quads, used, key, bad):
    """The MeshError message for quads (m, 4) (node ids; ``used`` their file point ids) two of which
    run along one edge the same way (``key`` the directed edges a n + b of every quad's cycle,
    ``bad`` a repeated one): the edge and the two cells in the file's ids, and the quads listed the
    other way round from the rest of their connected part (the fewer of its two orientations),
    which to reverse -- or that the surface is not
    orientable (a Moebius strip).  (Before: the edge in the reader's own node numbers, no cell.)"""
    n = len(used)
    a, b = int(bad // n), int(bad % n)
    cells = np.flatnonzero((key.reshape(-1, 4) == bad).any(1))[:2].tolist()
    head = (f"quad cells {cells[0]} and {cells[1]} run along their shared edge ({int(used[a])}, {int(used[b])}) the "
            f"same way (point ids of the file; cells counted over the file's quads in the order read): their "
            f"normals flip there")
    # the orientations spread over the quads' shared edges: two quads that run along an edge the
    # same way have opposite orientations.  The double cover (quad, side): (i, 0) joined to (j, 0)
    # where they agree, to (j, 1) where they do not; a part is orientable iff (i, 0) and (i, 1) lie
    # in different components, and then s_i (which of the two) is the quad's orientation
    und = np.sort(np.stack([quads, np.roll(quads, -1, axis=1)], -1), axis=-1).reshape(-1, 2)
    e_id = np.unique(und[:, 0] * n + und[:, 1], return_inverse=True)[1].ravel()
    order = np.argsort(e_id, kind="stable")
    pair = e_id[order][1:] == e_id[order][:-1]
    first, second = order[:-1][pair], order[1:][pair]                  # the directed edges of two quads
    flip = (key[first] == key[second]).astype(np.int64)
    qi, qj, m = first // 4, second // 4, len(quads)
    rows = np.concatenate([qi, qi + m])
    cols = np.concatenate([qj + m * flip, qj + m * (1 - flip)])
    H = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(2 * m, 2 * m))
    lab = connected_components(H, directed=False)[1]
    l0, l1 = lab[:m], lab[m:]
    if np.any(l0 == l1):
        return head + ("; no order of the quads makes the normals agree everywhere (a non-orientable surface, a "
                       "Moebius strip): a shell needs one side -- cut it into orientable parts")
    part, s = np.minimum(l0, l1), (l0 > l1).astype(np.int64)
    ones, size = np.bincount(part, weights=s, minlength=2 * m), np.bincount(part, minlength=2 * m)
    s ^= (2 * ones > size)[part].astype(np.int64)                      # the fewer of each part's two
    flipped = np.flatnonzero(s)
    return head + (f"; {len(flipped)} of the {m} quads (cells {flipped[:10].tolist()}{' ...' if len(flipped) > 10 else ''})"
                   f" are listed the other way round from the rest of their part: reverse their node order "
                   f"(cells[i] = cells[i][::-1]), or orient the surface in the mesher")


def _nodal_directors(X, quads, d1_hint):
    """d1 direction t (unnormalised, in the tangent plane) and d3 (unit) at each node: d3 the
    area-weighted mean of the adjacent quads' normals, t the projection of d1_hint (the global
    y axis where that degenerates, x where y does too: a hint of y on a plate normal to y)."""
    P = X[quads]
    nq = np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])       # 2 x area-weighted normal
    nn = np.zeros_like(X)
    for k in range(4):
        np.add.at(nn, quads[:, k], nq)
    norm = np.linalg.norm(nn, axis=1)
    if np.any(norm <= 0):
        nodes = np.flatnonzero(norm <= 0)
        around = np.flatnonzero(np.isin(quads, nodes).any(axis=1))
        raise MeshError(f"degenerate quads: node(s) {nodes[:5].tolist()} have no normal (the quads at them, "
                        f"{around[:5].tolist()}{' ...' if len(around) > 5 else ''}, have zero area or their normals "
                        f"cancel): remove collapsed quads or merge the nodes that coincide")
    d3 = nn / norm[:, None]
    return _projected_hint(d1_hint, d3), d3


def _projected_hint(d1_hint, d3):
    """d1_hint (3,) or (n, 3) projected on the planes normal to d3 (n, 3) (unnormalised; the global
    y axis where that degenerates, x where y does too: a hint of y on a plate normal to y)."""
    hint = np.broadcast_to(np.asarray(d1_hint, float), d3.shape)
    t = hint - np.einsum("ni,ni->n", hint, d3)[:, None] * d3
    for axis in (1, 0):
        weak = np.linalg.norm(t, axis=1) < 1e-6
        if weak.any():
            t[weak] = np.eye(3)[axis] - d3[weak, axis:axis + 1] * d3[weak]
    return t


def _on_shell(name, segs, remap):
    """MeshError if a group of lines has nodes that no quad uses (remapped to -1: a support or
    load on the group would act on the mesh's last node instead)."""
    off = np.unique(np.flatnonzero(np.asarray(segs).ravel() < 0) // 2)
    if len(off):
        raise MeshError(
            f"the group {name!r} has {len(off)} of its {len(segs)} line cell(s) off the shell (their nodes "
            f"belong to no quad): the curve is not on the meshed surface -- in Gmsh, a surface that is in no "
            f"physical surface is not saved (add it to one, or set Mesh.SaveAll = 1), or remove the curve "
            f"from the group")


def _point_sets(raw, remap):
    """Node sets of the file's point sets (Abaqus ``*NSET``, ...; they were dropped): name -> the
    sorted ids of its points that quads use (points no quad uses are dropped, as for a group of
    vertex cells); ids outside the file's points are a MeshError."""
    out = {}
    for name, ids in (raw.point_sets or {}).items():
        ids = np.asarray(ids, np.int64).ravel()
        if ids.size and (ids.min() < 0 or ids.max() >= len(raw.points)):
            raise MeshError(f"the point set {str(name)!r} refers to points that do not exist (the file has "
                            f"{len(raw.points)} points): the file is inconsistent; write it again")
        nodes = remap[ids]
        if (nodes >= 0).any():
            out[str(name)] = np.unique(nodes[nodes >= 0])
    return out


def _named_groups(sets, blocks, qb, remap):
    """Node sets (a group of lines: ordered along the line; of vertices: those nodes) and regions
    (a group of quads: its elements) of the named sets."""
    named, regions, offsets, off = {}, {}, {}, 0
    for i in qb:
        offsets[i], off = off, off + len(blocks[i][1])
    for name, per in sets.items():
        segs, points, elems = [], [], []
        for i, ((typ, cells), ids) in enumerate(zip(blocks, per)):
            if ids is None or not len(ids):
                continue
            if typ == "line":
                segs.extend(remap[cells[ids]].tolist())
            elif typ == "vertex":
                points.extend(remap[cells[ids]].ravel().tolist())
            elif typ == "quad":
                elems.extend((offsets[i] + ids).tolist())
        if segs:
            _on_shell(name, segs, remap)
            named[name] = chain_order(segs)
        elif points:
            pts = [p for p in dict.fromkeys(points) if p >= 0]     # points no quad uses are dropped
            if pts:
                named[name] = np.asarray(pts, np.int64)
        if elems:
            regions[name] = np.unique(elems)
    return named, regions

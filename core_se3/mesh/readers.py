"""Meshes from files: any quad surface mesh meshio reads (Gmsh .msh, .vtu, ...), with Gmsh's named
physical groups as named node sets (curves, points) and element regions (surfaces).

There is one reader, :func:`from_meshio`; scenario files and the Python API both use it.
"""
from __future__ import annotations

import contextlib
import io as _io

import numpy as np

from ..errors import MeshError
from .core import Mesh, chain_order, frames_from

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
    return raw


def _physical_sets(raw):
    """Named cell sets from Gmsh physical tags (``gmsh:physical`` cell data and field_data
    name -> [tag, dim]) when the reader left ``cell_sets`` empty (Gmsh 2.2 files)."""
    phys = (raw.cell_data or {}).get("gmsh:physical")
    if raw.cell_sets or phys is None or not raw.field_data:
        return
    sets = {}
    for name, fd in raw.field_data.items():
        fd = np.asarray(fd).ravel()
        if len(fd) < 2:
            continue
        tag, dim = int(fd[0]), int(fd[1])
        blocks = [np.nonzero(np.asarray(p) == tag)[0] if _DIMS.get(cb.type) == dim else
                  np.zeros(0, np.int64) for cb, p in zip(raw.cells, phys)]
        if any(len(b) for b in blocks):
            sets[str(name)] = blocks
    raw.cell_sets = sets


def _file_regions(raw):
    """Element sets of quad cells named in the file (e.g. Gmsh physical surfaces), as ids into
    the concatenated quad blocks (the element order of :func:`from_meshio`)."""
    out, offset = {}, 0
    offsets = []
    for cb in raw.cells:
        offsets.append(offset if cb.type == "quad" else None)
        if cb.type == "quad":
            offset += len(cb.data)
    for name, blocks in (raw.cell_sets or {}).items():
        ids = []
        for off, blk in zip(offsets, blocks):
            if off is not None and blk is not None and len(blk):
                ids.extend((off + np.asarray(blk, np.int64)).tolist())
        if ids:
            out[str(name)] = np.unique(ids)
    return out


def from_meshio(source, d1_hint=(1.0, 0.0, 0.0), edges=None):
    """Mesh from any quad surface mesh meshio reads (file name or ``meshio.Mesh``).

    Nodal frames: d3 = area-weighted mean of the adjacent quads' normals (quads must be
    consistently oriented: the normal is the right-hand side of the node order); d1 = the
    projection of ``d1_hint`` on the tangent plane (the global y axis where that degenerates).
    Named node sets: every named set of line cells (e.g. Gmsh physical curves), ordered along
    the line, plus ``edges`` = {name: predicate(X) -> bool mask}.  Named regions: every named
    set of quad cells (Gmsh physical surfaces).

    Points that no quad uses (e.g. Gmsh geometry points) are dropped; line and vertex cells are
    allowed, any other cell type (triangles) is a MeshError, as are quads whose orientation flips
    across an edge.

    Parameters
    ----------
    source : str, path-like or meshio.Mesh
        The file (or mesh); see :func:`read_meshio`.
    d1_hint : (3,) or (n, 3) array_like, optional
        Lab direction of the first director (default +x).
    edges : dict, optional
        Extra node sets: name -> predicate of the reference positions X (n, 3) returning a
        boolean mask.

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
    """
    m = read_meshio(source)
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
            named[name] = chain_order(segs)
    mesh = Mesh(frames_from(X, t, d3), quads, named, regions=_file_regions(m))
    for name, pred in (edges or {}).items():
        mesh.edges[name] = np.nonzero(pred(mesh.X))[0]
    return mesh

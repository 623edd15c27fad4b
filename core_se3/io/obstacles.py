"""Rigid obstacles (``model.obstacles``) for output: their surfaces as quad meshes, drawn in the
shell pictures (``plots.plot_shell(surfaces=...)``) and written as VTU files for ParaView (one
file per output step holding every obstacle at that load factor, with the cell field
``obstacle``: its index)."""
from __future__ import annotations

import os

import numpy as np

from ..results.atomic import atomic_path

__all__ = ["obstacle_surfaces", "write_obstacles"]


def obstacle_surfaces(obstacles, points, lam=1.0, pad=0.25):
    """[(name, points (p, 3), quads (q, 4))] of the obstacles that can draw themselves, at load
    factor lam; unbounded ones (a plane, an infinite cylinder) are cut to the box of ``points``
    (the shell's positions (n, 3)) grown by ``pad`` times its diagonal.

    Example
    -------
    >>> from core_se3.model import make_obstacle
    >>> ball = make_obstacle("sphere", centre=(0.0, 0.0, 2.0), radius=1.0, name="ball")
    >>> [(name, p.shape[1], q.shape[1]) for name, p, q in obstacle_surfaces([ball], [[0.0, 0.0, 0.0]])]
    [('ball', 3, 4)]
    """
    pts = np.atleast_2d(np.asarray(points, float))
    lo, hi = pts.min(0), pts.max(0)
    grow = pad * max(float(np.linalg.norm(hi - lo)), 1e-12)
    bounds = np.array([lo - grow, hi + grow])
    out = []
    for ob in obstacles:
        surf = ob.surface(lam, bounds)
        if surf is not None:
            out.append((ob.name, surf[0], surf[1]))
    return out


def write_obstacles(path, obstacles, points, lam=1.0):
    """Write the obstacles' surfaces at lam as one ``.vtu`` of quads (cell field ``obstacle``:
    the index of each quad's obstacle); returns the path, or None when none can draw itself.

    Example
    -------
    >>> import os, tempfile, meshio
    >>> from core_se3.model import make_obstacle
    >>> floor = make_obstacle("half_space", point=(0, 0, -1.0), normal=(0, 0, 1.0))
    >>> p = write_obstacles(os.path.join(tempfile.mkdtemp(), "obstacles.vtu"), [floor], [[0, 0, 0], [1, 1, 0]])
    >>> meshio.read(p).cells_dict["quad"].shape
    (64, 4)
    """
    import meshio
    surfs = obstacle_surfaces(obstacles, points, lam)
    if not surfs:
        return None
    P, C, idx, off = [], [], [], 0
    for k, (_, p, q) in enumerate(surfs):
        P.append(p)
        C.append(q + off)
        idx.append(np.full(len(q), k, np.int64))
        off += len(p)
    mesh = meshio.Mesh(np.concatenate(P), [("quad", np.concatenate(C))],
                       cell_data={"obstacle": [np.concatenate(idx).astype(float)]})
    path = os.fspath(path)
    with atomic_path(path) as tmp:        # a failed or interrupted write keeps the earlier file whole
        meshio.write(tmp, mesh, file_format="vtu")
    return path

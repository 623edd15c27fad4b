"""Output: VTK/ParaView files (via meshio) and PNG plots (via matplotlib, Agg, imported lazily).

Conventions: a shell state is a set of nodal frames ``g`` of shape ``(n, 4, 4)`` in SE(3), with
rotation ``R = g[:, :3, :3]`` (columns = directors d1, d2, d3; d3 is the shell normal) and position
``phi = g[:, :3, 3]``. All lengths are in the model's length unit (whatever the mesh uses, e.g. mm or
m), angles in radians; nothing is rescaled on output.

VTU files are written on the *reference* configuration (points = ``X``) with a ``displacement``
point field, so ParaView's *Warp By Vector* on ``displacement`` (scale 1) shows the deformed shape.
"""
from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from typing import Mapping, Sequence

import numpy as np

__all__ = [
    "frame_fields",
    "rotation_angle",
    "write_vtu",
    "write_pvd",
    "write_series",
    "plot_load_deflection",
    "plot_shell",
    "plot_sequence",
]

_CELL_TYPES = {3: "triangle", 4: "quad"}


# ----------------------------------------------------------------------------- helpers
def _as_frames(g, n: int | None = None, name: str = "g") -> np.ndarray:
    g = np.asarray(g, dtype=float)
    if g.ndim != 3 or g.shape[1:] != (4, 4):
        raise ValueError(f"{name} must have shape (n, 4, 4), got {g.shape}")
    if n is not None and g.shape[0] != n:
        raise ValueError(f"{name} has {g.shape[0]} frames but the mesh has {n} nodes")
    return g


def _as_points(X) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] not in (2, 3):
        raise ValueError(f"X must have shape (n, 3), got {X.shape}")
    if X.shape[1] == 2:
        X = np.column_stack([X, np.zeros(len(X))])
    return X


def _as_cells(quads, n: int) -> np.ndarray:
    c = np.asarray(quads)
    if c.ndim != 2 or c.shape[1] not in _CELL_TYPES:
        raise ValueError(f"quads must have shape (m, 4) (or (m, 3) for triangles), got {c.shape}")
    if not np.issubdtype(c.dtype, np.integer):
        if not np.all(np.equal(np.mod(c, 1), 0)):
            raise ValueError("quads must hold integer node ids")
    c = c.astype(np.int64)
    if c.size and (c.min() < 0 or c.max() >= n):
        raise ValueError(f"quads reference node ids outside [0, {n})")
    return c


def _ensure_parent(path) -> str:
    path = os.fspath(path)
    parent = os.path.dirname(os.path.abspath(path))
    os.makedirs(parent, exist_ok=True)
    return path


def rotation_angle(R: np.ndarray) -> np.ndarray:
    """Rotation angle in [0, pi] (rad) of each matrix in ``R`` (shape (n, 3, 3)); robust near 0 and pi."""
    R = np.asarray(R, dtype=float)
    tr = np.trace(R, axis1=-2, axis2=-1)
    w = np.stack(
        [R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], axis=-1
    )
    return np.arctan2(0.5 * np.linalg.norm(w, axis=-1), 0.5 * (tr - 1.0))


def frame_fields(g0, g) -> dict[str, np.ndarray]:
    """Point fields derived from reference/current frames ``g0``, ``g`` (n, 4, 4):
    ``displacement`` (phi - phi0, length unit), ``d1``/``d2``/``d3`` (current directors, unit
    vectors) and ``rotation_angle`` (angle of R R0^T, rad, in [0, pi])."""
    g0 = _as_frames(g0, name="g0")
    g = _as_frames(g, len(g0), name="g")
    R0, R = g0[:, :3, :3], g[:, :3, :3]
    return {
        "displacement": g[:, :3, 3] - g0[:, :3, 3],
        "d1": np.ascontiguousarray(R[:, :, 0]),
        "d2": np.ascontiguousarray(R[:, :, 1]),
        "d3": np.ascontiguousarray(R[:, :, 2]),
        "rotation_angle": rotation_angle(R @ np.swapaxes(R0, 1, 2)),
    }


# ----------------------------------------------------------------------------- VTK / ParaView
def write_vtu(path, X, quads, g0, g, point_data: Mapping[str, np.ndarray] | None = None,
              cell_data: Mapping[str, np.ndarray] | None = None) -> str:
    """Write one state as a VTK unstructured grid (``.vtu``) of quads on the reference mesh.

    X: (n, 3) reference node positions; quads: (m, 4) node ids; g0, g: (n, 4, 4) reference and
    current frames. Point fields: ``displacement``, ``d1``, ``d2``, ``d3``, ``rotation_angle`` (see
    :func:`frame_fields`) plus any ``point_data`` (name -> (n,) or (n, k) array); ``cell_data``:
    name -> (m,) or (m, k) array per quad (e.g. stress resultants). Returns the path.
    """
    import meshio

    X = _as_points(X)
    n = len(X)
    cells = _as_cells(quads, n)
    fields = frame_fields(_as_frames(g0, n, "g0"), _as_frames(g, n, "g"))
    for name, arr in (point_data or {}).items():
        a = np.asarray(arr)
        if a.shape[0] != n:
            raise ValueError(f"point_data[{name!r}] has {a.shape[0]} rows, expected {n}")
        fields[name] = a.astype(float) if a.dtype.kind in "biuf" else a
    cfields = {}
    for name, arr in (cell_data or {}).items():
        a = np.asarray(arr, dtype=float)
        if a.shape[0] != len(cells):
            raise ValueError(f"cell_data[{name!r}] has {a.shape[0]} rows, expected {len(cells)}")
        cfields[name] = [a]
    path = _ensure_parent(path)
    mesh = meshio.Mesh(points=X, cells=[(_CELL_TYPES[cells.shape[1]], cells)], point_data=fields,
                       cell_data=cfields or None)
    meshio.write(path, mesh, file_format="vtu")
    return path


def write_pvd(path, entries: Sequence[tuple[float, str]]) -> str:
    """Write a ParaView collection (``.pvd``) listing ``entries`` = [(time, vtu file name relative
    to the .pvd's directory), ...]. ``time`` is the pseudo-time/load factor (any unit). Returns path."""
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for t, fname in entries:
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=os.fspath(fname))
    ET.indent(root)
    path = _ensure_parent(path)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
    return path


def write_series(
    directory,
    X,
    quads,
    g0,
    frames_per_step: Sequence[np.ndarray],
    times: Sequence[float],
    prefix: str = "step",
    point_data_per_step: Sequence[Mapping[str, np.ndarray]] | None = None,
) -> list[str]:
    """Write a load/time series: ``{prefix}_0000.vtu``, ``{prefix}_0001.vtu``, ... and ``series.pvd``
    in ``directory`` (created if needed). ``frames_per_step[k]`` is the (n, 4, 4) state at
    ``times[k]``. Returns the written paths: the .vtu files in order, then the .pvd last."""
    if len(frames_per_step) != len(times):
        raise ValueError(f"{len(frames_per_step)} states but {len(times)} times")
    if point_data_per_step is not None and len(point_data_per_step) != len(times):
        raise ValueError("point_data_per_step must have one mapping per step")
    directory = os.fspath(directory)
    os.makedirs(directory, exist_ok=True)
    paths, entries = [], []
    for k, (g, t) in enumerate(zip(frames_per_step, times)):
        fname = f"{prefix}_{k:04d}.vtu"
        pdata = point_data_per_step[k] if point_data_per_step is not None else None
        paths.append(write_vtu(os.path.join(directory, fname), X, quads, g0, g, pdata))
        entries.append((float(t), fname))
    paths.append(write_pvd(os.path.join(directory, "series.pvd"), entries))
    return paths


# ----------------------------------------------------------------------------- plots
def _new_figure(figsize=(6.4, 4.8)):
    """A matplotlib Figure on an Agg canvas (no pyplot, no global backend switch)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=120)
    FigureCanvasAgg(fig)
    return fig


def plot_load_deflection(
    path,
    loads,
    displacements: Mapping[str, np.ndarray],
    labels: Mapping[str, str] | Sequence[str] | None = None,
    reference: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    xlabel: str = "displacement [length unit]",
    ylabel: str = "load [load unit]",
    title: str | None = None,
) -> str:
    """Load-deflection curves as a PNG: displacement on x, load on y (as in Sze et al. 2004).

    loads: (k,) load levels; displacements: name -> (k,) computed values, drawn as lines;
    labels: legend text per curve (dict name -> label, or a list in the order of ``displacements``;
    default: the names); reference: name -> (loads, values), drawn as open markers, in the colour of
    the computed curve of the same name if there is one. Returns the path.
    """
    loads = np.asarray(loads, dtype=float)
    names = list(displacements)
    if labels is None:
        lab = {k: k for k in names}
    elif isinstance(labels, Mapping):
        lab = {k: labels.get(k, k) for k in names}
    else:
        labels = list(labels)
        if len(labels) != len(names):
            raise ValueError(f"{len(labels)} labels for {len(names)} curves")
        lab = dict(zip(names, labels))

    fig = _new_figure()
    ax = fig.add_subplot(1, 1, 1)
    colors = {}
    for i, name in enumerate(names):
        d = np.asarray(displacements[name], dtype=float)
        if d.shape != loads.shape:
            raise ValueError(f"displacements[{name!r}] has shape {d.shape}, loads {loads.shape}")
        (line,) = ax.plot(d, loads, "-", lw=1.6, label=lab[name], color=f"C{i % 10}")
        colors[name] = line.get_color()
    j = len(names)
    for name, (rl, rv) in (reference or {}).items():
        color = colors.get(name)
        if color is None:
            color, j = f"C{j % 10}", j + 1
        ax.plot(np.asarray(rv, float), np.asarray(rl, float), "o", mfc="none", ms=5, color=color,
                label=f"{name} (reference)")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    ax.grid(True, alpha=0.3)
    if names or reference:
        ax.legend(fontsize="small")
    fig.tight_layout()
    path = _ensure_parent(path)
    fig.savefig(path)
    return path


def plot_shell(path, X, quads, g, title: str | None = None, color_by_rotation: bool = True,
               elev: float | None = None, azim: float | None = None, roll: float = 0.0) -> str:
    """3-D view of the deformed shell (faces = ``quads`` on the current positions ``g[:, :3, 3]``)
    with equal axis scaling, saved as PNG. ``X`` (reference positions, (n, 3)) is drawn as a faint
    wireframe for comparison. Faces are coloured by their mean nodal rotation angle (rad) if
    ``color_by_rotation``. Returns the path."""
    import mpl_toolkits.mplot3d  # noqa: F401  (registers the 3d projection)
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    X = _as_points(X)
    n = len(X)
    cells = _as_cells(quads, n)
    g = _as_frames(g, n)
    phi = g[:, :3, 3]
    polys = phi[cells]  # (m, 4, 3)

    fig = _new_figure((7.0, 6.0))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    faces = Poly3DCollection(polys, edgecolor="k", linewidths=0.3, alpha=0.9)
    if color_by_rotation:
        import matplotlib.cm as cm
        from matplotlib.colors import Normalize

        ang = rotation_angle(g[:, :3, :3])[cells].mean(axis=1)
        norm = Normalize(vmin=0.0, vmax=max(float(ang.max()), 1e-12))
        faces.set_facecolor(cm.viridis(norm(ang)))
        sm = cm.ScalarMappable(norm=norm, cmap="viridis")
        sm.set_array(ang)
        fig.colorbar(sm, ax=ax, shrink=0.6, label="rotation angle [rad]")
    else:
        faces.set_facecolor("tab:blue")
    ax.add_collection3d(faces)
    # reference mesh outline (closed polygons as segments)
    ref = X[cells]
    segs = np.stack([ref, np.roll(ref, -1, axis=1)], axis=2).reshape(-1, 2, 3)
    ax.add_collection3d(Line3DCollection(segs, colors="0.6", linewidths=0.3, linestyles=":"))

    pts = np.vstack([phi, X])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * max(float((hi - lo).max()), 1e-12)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    try:
        ax.set_box_aspect((1, 1, 1))
    except AttributeError:  # matplotlib < 3.3
        pass
    if elev is not None or azim is not None or roll:
        _view(ax, elev, azim, roll)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    if title:
        ax.set_title(title)
    path = _ensure_parent(path)
    fig.savefig(path)
    return path


def _view(ax, elev, azim, roll=0.0):
    """Camera elevation, azimuth and (matplotlib >= 3.6) roll, in degrees."""
    try:
        ax.view_init(elev=elev, azim=azim, roll=roll)
    except TypeError:          # matplotlib < 3.6: no roll
        ax.view_init(elev=elev, azim=azim)


def plot_sequence(path, X, quads, positions: Sequence[np.ndarray], labels: Sequence[str] | None = None,
                  title: str | None = None, cmap: str = "viridis", elev: float = 20.0,
                  azim: float = -60.0, roll: float = 0.0) -> str:
    """Several deformed shapes of one shell in one 3-D view (e.g. the states of a load path):
    ``positions[k]`` (n, 3) are the current node positions of state k, drawn as faces coloured
    by k (``cmap``), with a legend of ``labels``; ``X`` (reference) as a dotted outline, equal
    axis scaling; camera ``elev``, ``azim``, ``roll`` [deg]. Returns the path."""
    import matplotlib
    import mpl_toolkits.mplot3d  # noqa: F401
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    X = _as_points(X)
    cells = _as_cells(quads, len(X))
    positions = [_as_points(p) for p in positions]
    if not positions:
        raise ValueError("plot_sequence needs at least one state")
    fig = _new_figure((7.0, 6.0))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    colors = matplotlib.colormaps[cmap](np.linspace(0.0, 0.9, len(positions)))
    handles = []
    for k, phi in enumerate(positions):
        if phi.shape != X.shape:
            raise ValueError(f"positions[{k}] has shape {phi.shape}, expected {X.shape}")
        faces = Poly3DCollection(phi[cells], facecolor=colors[k], edgecolor="k", linewidths=0.15, alpha=0.75)
        ax.add_collection3d(faces)
        if labels is not None:
            handles.append(Patch(facecolor=colors[k], label=labels[k]))
    ref = X[cells]
    segs = np.stack([ref, np.roll(ref, -1, axis=1)], axis=2).reshape(-1, 2, 3)
    ax.add_collection3d(Line3DCollection(segs, colors="0.6", linewidths=0.3, linestyles=":"))
    pts = np.vstack(positions + [X])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * max(float((hi - lo).max()), 1e-12)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    _view(ax, elev, azim, roll)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    if handles:
        ax.legend(handles=handles, fontsize="x-small", loc="upper left", ncol=2, framealpha=0.6)
    if title:
        ax.set_title(title)
    path = _ensure_parent(path)
    fig.savefig(path)
    return path

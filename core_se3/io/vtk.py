"""VTK/ParaView output (via meshio): one state as a ``.vtu``, a series with its ``.pvd``.

Conventions: a shell state is a set of nodal frames ``g`` of shape ``(n, 4, 4)`` in SE(3), with
rotation ``R = g[:, :3, :3]`` (columns = directors d1, d2, d3; d3 is the shell normal) and position
``phi = g[:, :3, 3]``. All lengths are in the model's length unit (whatever the mesh uses, e.g. mm or
m), angles in radians; nothing is rescaled on output.

VTU files are written on the *reference* configuration (points = ``X``) with a ``displacement``
point field, so ParaView's *Warp By Vector* on ``displacement`` (scale 1) shows the deformed shape.
"""
from __future__ import annotations

import os
from typing import Mapping, Sequence

import numpy as np

from ..errors import OptionError
from ..lie import rotation_angle
from ..results.atomic import atomic_path

__all__ = ["frame_fields", "write_vtu", "write_pvd", "write_series", "as_frames", "as_points",
           "as_cells", "read_field_data", "pvd_times"]

_CELL_TYPES = {3: "triangle", 4: "quad"}


# ----------------------------------------------------------------------------- helpers
def as_frames(g, n: int | None = None, name: str = "g") -> np.ndarray:
    g = np.asarray(g, dtype=float)
    if g.ndim != 3 or g.shape[1:] != (4, 4):
        raise ValueError(f"{name} must have shape (n, 4, 4), got {g.shape}")
    if n is not None and g.shape[0] != n:
        raise ValueError(f"{name} has {g.shape[0]} frames but the mesh has {n} nodes")
    return g


def as_points(X) -> np.ndarray:
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[1] not in (2, 3):
        raise ValueError(f"X must have shape (n, 3), got {X.shape}")
    if X.shape[1] == 2:
        X = np.column_stack([X, np.zeros(len(X))])
    return X


def as_cells(quads, n: int) -> np.ndarray:
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


def frame_fields(g0, g) -> dict[str, np.ndarray]:
    """Point fields derived from reference/current frames ``g0``, ``g`` (n, 4, 4):
    ``displacement`` (phi - phi0, length unit), ``d1``/``d2``/``d3`` (current directors, unit
    vectors) and ``rotation_angle`` (angle of R R0^T, rad, in [0, pi]).

    Parameters
    ----------
    g0, g : (n, 4, 4) array_like
        Reference and current frames (ValueError for other shapes or node counts).

    Returns
    -------
    dict
        name -> (n, 3) arrays, and ``rotation_angle`` (n,).

    Example
    -------
    >>> import numpy as np
    >>> g = np.broadcast_to(np.eye(4), (2, 4, 4))
    >>> sorted(frame_fields(g, g))
    ['d1', 'd2', 'd3', 'displacement', 'rotation_angle']
    """
    g0 = as_frames(g0, name="g0")
    g = as_frames(g, len(g0), name="g")
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
              cell_data: Mapping[str, np.ndarray] | None = None,
              field_data: Mapping[str, float] | None = None) -> str:
    """Write one state as a VTK unstructured grid (``.vtu``) of quads on the reference mesh.

    X: (n, 3) reference node positions; quads: (m, 4) node ids; g0, g: (n, 4, 4) reference and
    current frames. Point fields: ``displacement``, ``d1``, ``d2``, ``d3``, ``rotation_angle`` (see
    :func:`frame_fields`) plus any ``point_data`` (name -> (n,) or (n, k) array); ``cell_data``:
    name -> (m,) or (m, k) array per quad (e.g. stress resultants); ``field_data``: name -> number,
    global values of the state (the load factor, the physical loads), written as the VTK
    ``FieldData`` that ParaView shows per time step. Returns the path.

    Parameters
    ----------
    path : str or path-like
        The ``.vtu`` file (its directory is created), written atomically (``results.atomic``).
    X, quads, g0, g, point_data, cell_data
        As above (ValueError for inconsistent shapes).

    Returns
    -------
    str
        The path.

    Example
    -------
    >>> import os, tempfile, meshio
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> g = m.g0.copy(); g[:, 2, 3] += 0.5                      # lifted by 0.5
    >>> p = write_vtu(os.path.join(tempfile.mkdtemp(), "s.vtu"), m.X, m.quads, m.g0, g, cell_data={"id": [0, 1]})
    >>> v = meshio.read(p)
    >>> v.point_data["displacement"][:, 2].tolist(), list(v.cell_data)
    ([0.5, 0.5, 0.5, 0.5, 0.5, 0.5], ['id'])
    """
    import meshio

    X = as_points(X)
    n = len(X)
    cells = as_cells(quads, n)
    fields = frame_fields(as_frames(g0, n, "g0"), as_frames(g, n, "g"))
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
    path = os.fspath(path)
    mesh = meshio.Mesh(points=X, cells=[(_CELL_TYPES[cells.shape[1]], cells)], point_data=fields,
                       cell_data=cfields or None)
    with atomic_path(path) as tmp:        # a failed or interrupted write keeps the earlier file whole
        meshio.write(tmp, mesh, file_format="vtu")
        if field_data:
            _add_field_data(tmp, field_data)
    return path


def _add_field_data(path, values):
    """Insert a VTK <FieldData> block (one Float64 tuple per name) into a written .vtu file."""
    from xml.sax.saxutils import quoteattr
    arrays = "".join(f'<DataArray type="Float64" Name={quoteattr(str(k))} NumberOfTuples="1" '
                     f'format="ascii">{float(v)!r}</DataArray>\n' for k, v in values.items())
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    text = text.replace("<UnstructuredGrid>", f"<UnstructuredGrid>\n<FieldData>\n{arrays}</FieldData>", 1)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


def read_field_data(path) -> dict:
    """The ``FieldData`` values of a .vtu file written by :func:`write_vtu` (name -> float).

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 1, 1)
    >>> p = write_vtu(os.path.join(tempfile.mkdtemp(), "s.vtu"), m.X, m.quads, m.g0, m.g0,
    ...               field_data={"load_factor": 0.5, "fields.coil.B [T]": 0.03})
    >>> read_field_data(p)
    {'load_factor': 0.5, 'fields.coil.B [T]': 0.03}
    """
    import xml.etree.ElementTree as ET     # at the first use: 4 ms of every start otherwise
    out = {}
    root = ET.parse(os.fspath(path)).getroot()
    for fd in root.iter("FieldData"):
        for arr in fd.iter("DataArray"):
            out[arr.get("Name")] = float(arr.text.split()[0])
    return out


def pvd_times(times, steps=None) -> list[float]:
    """The times of a ``.pvd`` collection: ``times`` when they increase strictly, else ``steps``
    (default the positions 0, 1, 2, ...).

    ParaView sorts a collection by its times and shows one data set per time, so load factors that
    do not increase (an arc-length path past a limit point, load factors towards negative values,
    a repeated value) would play the states out of order or hide some; the load factor stays in
    each file's ``FieldData`` (``load_factor``).

    Example
    -------
    >>> pvd_times([0.0, 0.5, 1.0]), pvd_times([0.0, -0.5, -1.0]), pvd_times([0.0, 0.7, 0.6], [0, 2, 4])
    ([0.0, 0.5, 1.0], [0.0, 1.0, 2.0], [0.0, 2.0, 4.0])
    """
    t = np.asarray(times, float).ravel()
    if np.all(np.diff(t) > 0):
        return t.tolist()
    return np.asarray(np.arange(len(t)) if steps is None else steps, float).ravel().tolist()


def write_pvd(path, entries: Sequence[tuple[float, str]]) -> str:
    """Write a ParaView collection (``.pvd``) listing ``entries`` = [(time, vtu file name relative
    to the .pvd's directory), ...]. ``time`` is the pseudo-time/load factor (any unit); times that
    do not increase strictly are replaced by the entries' positions (:func:`pvd_times`: ParaView
    would sort them). Returns path.

    Parameters
    ----------
    path : str or path-like
        The ``.pvd`` file.
    entries : sequence of (float, str)
        (time, file) pairs, in order.

    Returns
    -------
    str
        The path.

    Example
    -------
    >>> import os, tempfile
    >>> p = write_pvd(os.path.join(tempfile.mkdtemp(), "series.pvd"), [(0.0, "step_0000.vtu"), (0.5, "step_0001.vtu")])
    >>> [ln.strip() for ln in open(p) if "DataSet" in ln]
    ['<DataSet timestep="0.0" group="" part="0" file="step_0000.vtu" />', '<DataSet timestep="0.5" group="" part="0" file="step_0001.vtu" />']
    """
    import xml.etree.ElementTree as ET     # at the first use: 4 ms of every start otherwise
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    entries = list(entries)
    for t, (_, fname) in zip(pvd_times([t for t, _ in entries]), entries):
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=os.fspath(fname))
    ET.indent(root)
    path = os.fspath(path)
    with atomic_path(path) as tmp:
        ET.ElementTree(root).write(tmp, encoding="utf-8", xml_declaration=True)
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
    ``times[k]``. Returns the written paths: the .vtu files in order, then the .pvd last.

    The directory holds one series of ``prefix``: the files ``{prefix}_NNNN.vtu`` of an earlier,
    longer series written there are deleted (ParaView groups ``step_*.vtu`` as one series, so a
    run of 10 steps after one of 20 showed the old steps 10-19 as part of the new run); files of
    other names are left alone.

    Parameters
    ----------
    directory : str or path-like
        Output directory.
    X, quads, g0
        The reference mesh as for :func:`write_vtu`.
    frames_per_step : sequence of (n, 4, 4) arrays
        One state per step; ``times``: their load factors (same length).
    prefix : str, optional
        File-name prefix.
    point_data_per_step : sequence of dict, optional
        Extra point fields per step.

    Returns
    -------
    list of str

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> [os.path.basename(p) for p in write_series(tempfile.mkdtemp(), m.X, m.quads, m.g0, [m.g0, m.g0], [0.0, 1.0])]
    ['step_0000.vtu', 'step_0001.vtu', 'series.pvd']
    """
    if len(frames_per_step) != len(times):
        raise ValueError(f"{len(frames_per_step)} states but {len(times)} times")
    if point_data_per_step is not None and len(point_data_per_step) != len(times):
        raise ValueError("point_data_per_step must have one mapping per step")
    directory = os.fspath(directory)
    if os.path.exists(directory) and not os.path.isdir(directory):
        raise OptionError(f"write_series: directory {directory!r} is a file, not a directory: nothing was written; "
                          "give the path of a directory (the series' .vtu files and series.pvd go in it)")
    os.makedirs(directory, exist_ok=True)
    paths, entries = [], []
    for k, (g, t) in enumerate(zip(frames_per_step, times)):
        fname = f"{prefix}_{k:04d}.vtu"
        pdata = point_data_per_step[k] if point_data_per_step is not None else None
        paths.append(write_vtu(os.path.join(directory, fname), X, quads, g0, g, pdata))
        entries.append((float(t), fname))
    paths.append(write_pvd(os.path.join(directory, "series.pvd"), entries))
    _delete_stale_steps(directory, prefix, len(entries))
    return paths


def _delete_stale_steps(directory, prefix, count):
    """Delete ``{prefix}_NNNN.vtu`` (the names :func:`write_series` gives) numbered ``count`` or
    more in ``directory``: the steps of an earlier, longer series."""
    import re
    pattern = re.compile(re.escape(prefix) + r"_(\d{4,})\.vtu")
    for name in os.listdir(directory):
        m = pattern.fullmatch(name)
        if m and int(m.group(1)) >= count and name == f"{prefix}_{int(m.group(1)):04d}.vtu":
            os.unlink(os.path.join(directory, name))



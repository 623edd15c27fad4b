"""The files of a sweep (``scenario.sweep``): ``sweep.csv`` (one row per finished run, rewritten
atomically after each), ``sweep.png``, ``sweep.json`` (status, message, provenance) and the
checkpoint ``sweep.npz`` (the finished rows, their final frames and the 'auto' backend's count,
so that a resumed sweep repeats the uninterrupted one bit for bit).

Example
-------
>>> import csv, os, tempfile
>>> p = write_csv(os.path.join(tempfile.mkdtemp(), "sweep.csv"), ["material.E"],
...               [{"material.E": 1.0, "status": "complete", "tip.uz": 0.5}])
>>> list(csv.DictReader(open(p)))[0]["tip.uz"]
'0.5'
"""
from __future__ import annotations

import csv
import hashlib
import json

import numpy as np

from ..backend import restore_rent
from ..errors import CheckpointError
from ..io import atomic_path, write_json_atomic

__all__ = ["SWEEP_FILES", "SweepCheckpoint", "write_csv", "write_plot", "write_status", "columns", "column_units"]

SWEEP_FILES = ("sweep.csv", "sweep.png", "sweep.json", "sweep.npz")
FORMAT = "core-se3-sweep-checkpoint"


class SweepCheckpoint:
    """The finished rows of a sweep and their final frames (None for a failed run), saved in
    ``sweep.npz`` after every run with what each session ran with (``resume.session_record``:
    ``sessions``, each with its ``first_row``); :meth:`load` restores them for a resume
    (CheckpointError for a checkpoint of another scenario or grid, a damaged one, or one of
    another package version; a warning naming another difference: ``resume.check_session``)."""

    def __init__(self, rd, scn, grid, warm):
        from .resume import session_record
        self.rd = rd
        self.rows, self.finals, self.rent = [], [], None
        self.sessions = [dict(session_record(scn, 1), first_row=0)]
        self.n = scn.mesh.n_nodes
        # the load factors too: a run's fingerprint leaves them out (--resume may extend a run to a
        # higher lam_end), but a sweep's rows are the final states at them
        self.fingerprint = hashlib.sha256(json.dumps(dict(scenario=scn.fingerprint, grid=grid, warm=bool(warm),
                                                          load_factors=[float(x) for x in scn.load_factors()]),
                                                     sort_keys=True, default=str).encode()).hexdigest()

    def add(self, row, g, rent):
        """One finished run: its row, final frames (or None) and the backend count after it."""
        self.rows.append(row)
        self.finals.append(g)
        self.rent = rent
        arrays = {f"g_{i}": g for i, g in enumerate(self.finals) if g is not None}
        with atomic_path(self.rd.file("sweep.npz")) as tmp:
            with open(tmp, "wb") as fh:
                np.savez(fh, format=np.array(FORMAT), fingerprint=np.array(self.fingerprint),
                         rows=np.array(json.dumps(self.rows)), rent=np.array(json.dumps(rent)),
                         sessions=np.array(json.dumps(self.sessions)), **arrays)

    def load(self):
        """The rows done so far (none without a checkpoint: the sweep starts at its first point)."""
        import os
        path = os.path.join(self.rd.path, "sweep.npz")
        if not os.path.exists(path):
            return self
        try:
            with np.load(path, allow_pickle=False) as z:
                if str(z["format"]) != FORMAT:
                    raise ValueError(f"not a {FORMAT} file")
                fp, rows, rent = str(z["fingerprint"]), json.loads(str(z["rows"])), json.loads(str(z["rent"]))
                finals = [np.array(z[f"g_{i}"]) if f"g_{i}" in z.files else None for i in range(len(rows))]
                sessions = json.loads(str(z["sessions"])) if "sessions" in z.files else None
        except Exception as exc:
            raise CheckpointError(f"cannot read the sweep checkpoint {path}: {type(exc).__name__}; start over with "
                                  "--force, or use another --out") from None
        if fp != self.fingerprint:
            raise CheckpointError(f"{path} belongs to another sweep (the scenario, its load steps, the swept values "
                                  "or --cold changed): start over with --force, or use another --out")
        if not isinstance(rows, list) or any(g is not None and g.shape != (self.n, 4, 4) for g in finals):
            raise CheckpointError(f"{path} is inconsistent (its rows or frames do not fit the scenario): start over "
                                  "with --force, or use another --out")
        from .resume import check_session
        check_session(path, sessions, self.sessions[-1])
        self.sessions = list(sessions or []) + [dict(self.sessions[-1], first_row=len(rows))]
        self.rows, self.finals, self.rent = rows, finals, rent
        restore_rent(rent)
        return self


def columns(rows):
    """The CSV columns: every key of every row, in order of appearance."""
    cols = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    return cols


def _cell(v):
    """A CSV cell: a vector as ``x;y;z``; floats as their shortest exact decimal (0.1, not the
    0.10000000000000001 of %.17g: both read back to the same float)."""
    if isinstance(v, (list, tuple, np.ndarray)):
        return ";".join(_cell(x) for x in v)
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    return str(v)


def write_csv(path, keys, rows):
    """``sweep.csv``: the rows (swept values first), written atomically."""
    cols = columns([{k: None for k in keys}] + list(rows))
    with atomic_path(path) as tmp:
        with open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            for r in rows:
                w.writerow([_cell(r.get(c, "")) for c in cols])
    return path


_DIMENSIONS = (("length", ("ux", "uy", "uz", "penetration", "gap_error", "largest_slip")),
               ("force", ("Fx", "Fy", "Fz", "tangential_force", "normal_force")), ("moment", ("Mx", "My", "Mz")))


def column_units(cols, units):
    """column -> unit of the ``sweep.csv`` columns a sweep computes, in the scenario's unit system
    (``units``; its dimension names where none is given): probe displacements and contact lengths
    in the length unit, reactions and contact forces in the force unit, their moments in the
    moment unit, rotations in rad; the swept values are as the scenario gives them (absent).

    Example
    -------
    >>> column_units(["E", "tip.uz", "tip.rotation", "supports[0].My", "steps"], "N-mm-MPa")
    {'tip.uz': 'mm', 'tip.rotation': 'rad', 'supports[0].My': 'N mm', 'steps': '1'}
    """
    from .units import UNIT_SYSTEMS
    u = UNIT_SYSTEMS.get(units) or UNIT_SYSTEMS["consistent"]
    out = {}
    for c in cols:
        tail = c.rsplit(".", 1)[-1]
        dim = next((d for d, tails in _DIMENSIONS if tail in tails and "." in c), None)
        if dim is not None:
            out[c] = u[dim]
        elif tail in ("rotation", "rotation_vector") and "." in c:
            out[c] = "rad"
        elif c in ("steps", "iterations") or tail in ("nodes_in_contact", "faces_in_contact", "sticking", "slipping"):
            out[c] = "1"
    return out


def write_status(path, result, scn, state, message=None):
    """``sweep.json``: status, message, the swept keys, the number of rows, the unit system and
    the units of the CSV's computed columns (:func:`column_units`), provenance."""
    from ..results.provenance import provenance
    from .outputs import unit_system_record
    units = scn.spec["units"]
    doc = dict(schema="core-se3-sweep", version=1, scenario=scn.file, name=scn.name, status=result.status,
               error=message, keys=result.keys, rows=len(result.rows),
               failed=sum(r.get("status") != "complete" for r in result.rows),
               unit_system=unit_system_record(units),
               column_units=column_units(columns([{k: None for k in result.keys}] + list(result.rows)), units),
               provenance=provenance(scn.problem))
    if len(state.sessions) > 1:         # a resumed sweep: what each session ran with, from which row
        doc["provenance"]["sessions"] = state.sessions
    return write_json_atomic(path, doc)


def write_plot(path, result, title):
    """Every probe displacement component against the first swept value (names or switches:
    one tick per run)."""
    from ..io.plots import new_figure, save_figure
    fig = new_figure()
    ax = fig.add_subplot(1, 1, 1)
    key = result.keys[0]
    xs = [r[key] for r in result.rows]
    numeric = all(isinstance(v, (int, float, list, tuple)) and not isinstance(v, bool) for v in xs)
    x = np.array([np.linalg.norm(v) if isinstance(v, (list, tuple)) else v for v in xs], float) if numeric \
        else np.arange(len(xs), dtype=float)
    if not numeric:
        ax.set_xticks(x)
        ax.set_xticklabels([str(v) for v in xs], rotation=30)
    cols = [c for c in columns(result.rows) if c.endswith((".ux", ".uy", ".uz"))]
    ys = {c: np.array([r.get(c, np.nan) for r in result.rows], float) for c in cols}
    big = max([np.nanmax(np.abs(y)) for y in ys.values() if np.isfinite(y).any()] + [0.0])
    for i, (c, y) in enumerate(ys.items()):
        if np.isfinite(y).any() and np.nanmax(np.abs(y)) > 1e-9 * big:
            ax.plot(x, y, "o-", ms=4, label=c, color=f"C{i % 10}")
    ax.set_xlabel(key + (" (|vector|)" if numeric and isinstance(xs[0], (list, tuple)) else ""))
    ax.set_ylabel("final probe displacement")
    ax.set_title(f"{title}: sweep of {', '.join(result.keys)}")
    ax.grid(True, alpha=0.3)
    if ys:
        ax.legend(fontsize="small")
    fig.tight_layout()
    save_figure(fig, path)
    return path

"""Magnetisation patterns of [[magnets]] beyond a uniform vector: ``direction = "radial"`` or
``"tangential"`` about a ``centre`` and an ``axis`` (a magnitude ``Br`` [T] in the plane normal to
the axis, plus ``Br_axial`` along it), and per-element or per-node tables from a CSV file
(``Br_file``, header ``element,Brx,Bry,Brz`` or ``node,Brx,Bry,Brz``).

Radial: B^r = Br e_r + Br_axial a, with e_r the unit vector from the axis to the element
centroid; tangential: e_t = a x e_r.  A table gives every element of the magnet's selection
(``element``) or every node of it (``node``, interpolated bilinearly) exactly once.
"""
from __future__ import annotations

import csv
import hashlib
import os

import numpy as np

from ..io.files import read_input_file

from .validate import join

__all__ = ["DIRECTIONS", "pattern_section", "pattern_br"]

DIRECTIONS = ("radial", "tangential")
PATTERN_KEYS = ("direction", "centre", "axis", "Br_axial", "Br_file")


def pattern_section(v, t, key, mesh, elems, base_dir):
    """Validated pattern keys of a [[magnets]] table (a dict to merge into its spec), or {}."""
    out = {}
    if "direction" in t:
        out["direction"] = v.string(t, "direction", key, choices=DIRECTIONS)
        br = t.get("Br")
        if isinstance(br, bool) or not isinstance(br, (int, float)):
            v.fail(join(key, "Br"), f'with direction = "{out["direction"]}" Br is the magnitude [T] (a number), '
                                    f"got {br!r}")
        out["Br"] = v.number(t, "Br", key)
        out["Br_axial"] = v.number(t, "Br_axial", key, default=0.0)
        out["centre"] = v.vector(t, "centre", key, default=[0.0, 0.0, 0.0])
        out["axis"] = v.vector(t, "axis", key, default=[0.0, 0.0, 1.0], nonzero=True)
        sel = np.arange(mesh.n_elements) if elems is None else np.asarray(elems)
        _, dist = _radial(mesh, sel, out["centre"], out["axis"])
        bad = np.nonzero(dist < 1e-9 * mesh.length_scale)[0]
        if len(bad):
            v.fail(join(key, "centre"), f"element {int(sel[bad[0]])} has its centroid on the axis through the "
                                        f"centre {out['centre']}: its {out['direction']} direction is undefined; "
                                        "move the centre or leave that element out of the magnet's region")
        out["Br_max"] = float(np.hypot(out["Br"], out["Br_axial"]))
    elif "Br_axial" in t or "centre" in t or "axis" in t:
        k = next(k for k in ("Br_axial", "centre", "axis") if k in t)
        v.fail(join(key, k), f"{k!r} belongs to a radial or tangential magnetisation: add direction = "
                             '"radial" or "tangential"')
    if "Br_file" in t:
        fname = v.string(t, "Br_file", key)
        path = fname if os.path.isabs(fname) else os.path.join(base_dir, fname)
        kind, ids, vals, digest = _read_table(v, join(key, "Br_file"), fname, path)
        sel = np.arange(mesh.n_elements) if elems is None else np.asarray(elems)
        want = sel if kind == "element" else np.unique(mesh.quads[sel])
        n = mesh.n_elements if kind == "element" else mesh.n_nodes
        out_of = ids[(ids < 0) | (ids >= n)]
        if len(out_of):
            v.fail(join(key, "Br_file"), f"{fname}: {kind} ids {out_of[:5].tolist()} do not exist (valid: 0 .. {n - 1})")
        uniq, cnt = np.unique(ids, return_counts=True)
        if np.any(cnt > 1):
            v.fail(join(key, "Br_file"), f"{fname}: {kind} {int(uniq[cnt > 1][0])} is listed {int(cnt.max())} times")
        missing = np.setdiff1d(want, ids)
        if len(missing):
            v.fail(join(key, "Br_file"), f"{fname}: the table misses {len(missing)} of the magnet's {len(want)} "
                                         f"{kind}s (first: {missing[:5].tolist()}); give every {kind} of its "
                                         "region once")
        if kind == "node":
            from .geometry import renumbered_warning
            renumbered_warning(v, join(key, "Br_file"), mesh, ids)
        out["Br_table"] = dict(file=fname, kind=kind, sha256=digest, path=path)
        out["Br_max"] = float(np.linalg.norm(vals, axis=1).max())
    return out


MAX_TABLE_BYTES = 256 * 2 ** 20      # a table of 10^6 elements has about 60 MB


def _read_table(v, key, fname, path):
    """The table's kind, ids, values and digest; errors never show the file's contents (a
    scenario may name any file)."""
    if not os.path.exists(path):
        v.fail(key, f"magnetisation table {fname!r} does not exist (looked for {path})")
    try:
        data = read_input_file(path, MAX_TABLE_BYTES, "a magnetisation table")
    except (ValueError, OSError) as exc:
        v.fail(key, str(exc))
    text = data.decode("utf-8-sig", "replace")     # without the byte order mark of a spreadsheet's UTF-8 CSV
    rows = [r for r in csv.reader(text.splitlines()) if r and not r[0].startswith("#")]
    head = [c.strip() for c in rows[0]] if rows else []
    if head not in (["element", "Brx", "Bry", "Brz"], ["node", "Brx", "Bry", "Brz"]):
        v.fail(key, f"{fname}: expected the header element,Brx,Bry,Brz or node,Brx,Bry,Brz as its first row "
                    f"(a CSV table; its first row has {len(head)} field{'s' if len(head) != 1 else ''})")
    try:
        table = np.array([[float(c) for c in r] for r in rows[1:]], float).reshape(-1, 4)
    except ValueError:
        line = next(i for i, r in enumerate(rows[1:], 2) if not _numeric(r))
        v.fail(key, f"{fname}: row {line} is not four numbers (id, Brx, Bry, Brz)")
    if not np.all(np.isfinite(table)) or np.any(table[:, 0] != np.round(table[:, 0])):
        v.fail(key, f"{fname}: ids must be integers and Br values finite numbers")
    return head[0], table[:, 0].astype(np.int64), table[:, 1:], hashlib.sha256(data).hexdigest()


def _numeric(r):
    try:
        [float(c) for c in r]
        return len(r) == 4
    except ValueError:
        return False


def _radial(mesh, sel, centre, axis):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    r = mesh.X[mesh.quads[sel]].mean(1) - np.asarray(centre, float)
    r -= np.outer(r @ a, a)
    d = np.linalg.norm(r, axis=1)
    return r / np.where(d > 0, d, 1.0)[:, None], d


def pattern_br(m, mesh, elems):
    """Br of a validated pattern: (k, 3) per element of the selection or (n_nodes, 3) per node."""
    sel = np.arange(mesh.n_elements) if elems is None else np.asarray(elems)
    if "direction" in m:
        a = np.asarray(m["axis"], float) / np.linalg.norm(m["axis"])
        er, _ = _radial(mesh, sel, m["centre"], m["axis"])
        e = er if m["direction"] == "radial" else np.cross(a, er)
        return m["Br"] * e + m["Br_axial"] * a
    tab = m["Br_table"]
    with open(tab["path"]) as fh:
        rows = [r for r in csv.reader(fh) if r and not r[0].startswith("#")][1:]
    table = np.array([[float(c) for c in r] for r in rows], float).reshape(-1, 4)
    ids = table[:, 0].astype(np.int64)
    if tab["kind"] == "element":
        full = np.zeros((mesh.n_elements, 3))
        full[ids] = table[:, 1:]
        return full[sel]
    full = np.zeros((mesh.n_nodes, 3))
    full[ids] = table[:, 1:]
    return full

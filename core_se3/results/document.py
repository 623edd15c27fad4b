"""The result document (JSON schema ``core-se3-result`` version 1): its one writer and reader.

    {"schema": "core-se3-result", "version": 1, "case", "model", "variant",
     "params": {key: {"value", "unit"}}, "mesh": {"nx", "ny", "n_nodes", "n_elements", "n_dofs"},
     "steps": [{"load_factor", "load": {"name", "value", "unit"},
                "probes": {name: {"u": [ux, uy, uz], "rotation_angle", "rotation_vector",
                                  "rotation": 3x3}},
                "iterations", "residual", "residual_force", "residual_moment" (the norms of the
                force and moment parts of the residual on the free dofs, in force and force x
                length; null where not recorded), "residual_floor", "residual_history",
                "max_correction" (the step's largest Newton correction |eta|_s / ell; null where not
                counted: linear analysis, arc length, the start),
                "reactions": {"force", "moment"}, "applied": {"force", "moment"} (lab totals of the
                support reactions -- held dofs and penalty springs -- and of the applied loads;
                moments about the origin), "balance_error",
                "attempts", "linear_solves", "backend" ('numpy'/'numba': what evaluated the step),
                "contact": {name: {"force", "moment", "penetration",
                ...}} (with obstacles only),
                "checks": {"path_check", "contraction", "travel", "path_rejections", "det_sign",
                           "snap_probes", "landed_elsewhere" (with contact)}
                (load stepping: what was checked before the state was accepted)}],
     "totals": {"attempts", "linear_solves", "iterations"},
     "timings": {"setup", "assembly", "solve", "other", "total"},
     "reference": {"entry", "block", "error", "error_at"} or null}

``rotation_angle`` is |w| of the rotation vector of R R0^T unwrapped continuously along the
path (so a roll-up reports 6 pi, not its value modulo 2 pi).  Catalogue runs, scenario runs
(``results.json``, with status fields) and fenicsx_ref all write this schema through
:func:`result_document` and :func:`step_record`.
"""
from __future__ import annotations

import json
import os

import numpy as np

from ..errors import ResultFileError
from .atomic import atomic_path

__all__ = ["SCHEMA", "VERSION", "NON_FINITE", "read_json", "write_json", "json_text", "probe_record", "step_record",
           "format_residual", "ROUNDOFF_NOTE", "contact_record", "mesh_record", "timing_record", "step_totals",
           "result_document"]

SCHEMA = "core-se3-result"
VERSION = 1


def probe_record(p, axis=None):
    """JSON form of a recorded probe state (``results.ProbeState``: the same keys;
    ``rotation_about_axis`` = rotation_vector . axis when an axis is given).

    Parameters
    ----------
    p : dict
        dict(u (3,), rotation (3, 3), rotation_vector (3,)) as in ``StepResult.probes`` (the
        older names R and w are read too).
    axis : (3,) array, optional
        Lab axis for ``rotation_about_axis`` [rad].

    Returns
    -------
    dict
        u, rotation_angle (|w|), [rotation_about_axis], rotation_vector, rotation: plain lists
        and floats.

    Example
    -------
    >>> import numpy as np
    >>> r = probe_record(dict(u=np.zeros(3), rotation=np.eye(3), rotation_vector=np.array([0.0, 0.0, 2 * np.pi])),
    ...                  axis=np.array([0, 0, 1.0]))
    >>> list(r), r["rotation_angle"]                  # a full turn: the unwrapped angle is 2 pi
    (['u', 'rotation_angle', 'rotation_about_axis', 'rotation_vector', 'rotation'], 6.283185307179586)
    """
    w = np.asarray(p["rotation_vector"] if "rotation_vector" in p else p["w"])
    R = np.asarray(p["rotation"] if "rotation" in p else p["R"])
    out = dict(u=np.asarray(p["u"]).tolist(), rotation_angle=float(np.linalg.norm(w)))
    if axis is not None:
        out["rotation_about_axis"] = float(w @ axis)
    out.update(rotation_vector=w.tolist(), rotation=R.tolist())
    return out


def step_record(st, load, axis=None, **extra):
    """JSON form of a StepResult: load factor, the reported load (dict name, value, unit, ...),
    probes, Newton iterations and residuals, the lab totals of the support reactions (held dofs
    and penalty springs) and of the applied loads (``reactions``, ``applied``: force, and moment
    about the origin), balance error, then ``extra`` keys.

    Parameters
    ----------
    st : StepResult
        The step.
    load : dict
        The reported load, e.g. dict(name="P", value=1.0, unit="N").
    axis : (3,) array, optional
        As for :func:`probe_record`.
    **extra
        Further keys of the record.

    Returns
    -------
    dict

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0)); p.add_probe("tip")
    >>> rec = step_record(p.solve(steps=1).final, dict(name="P", value=1.0, unit="N"), error=None)
    >>> list(rec), rec["load_factor"], rec["residual"] < 1e-10
    (['load_factor', 'load', 'probes', 'iterations', 'residual', 'residual_force', 'residual_moment', 'residual_floor', 'residual_history', 'max_correction', 'reactions', 'applied', 'balance_error', 'attempts', 'linear_solves', 'backend', 'support_reactions', 'checks', 'error'], 1.0, True)
    >>> [[round(f, 9) + 0.0 for f in rec[k]["force"]] for k in ("reactions", "applied")]   # held by the clamp
    [[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]]
    """
    rec = dict(load_factor=float(st.load_factor), load=load,
               probes={name: probe_record(p, axis) for name, p in st.probes.items()},
               iterations=int(st.iterations),
               residual=float(st.residual_history[-1]) if st.residual_history else 0.0,
               residual_force=_number(getattr(st, "residual_force", None)),
               residual_moment=_number(getattr(st, "residual_moment", None)),
               residual_floor=float(getattr(st, "residual_floor", 0.0)),
               residual_history=[float(x) for x in st.residual_history],
               max_correction=None if getattr(st, "max_correction", None) is None else float(st.max_correction),
               reactions=dict(force=np.asarray(st.reaction_force, float).tolist(),
                              moment=np.asarray(st.reaction_moment, float).tolist()),
               applied=dict(force=np.asarray(st.applied_force, float).tolist(),
                            moment=np.asarray(st.applied_moment, float).tolist()),
               balance_error=float(st.balance_error), attempts=int(st.attempts),
               linear_solves=None if st.linear_solves is None else int(st.linear_solves),
               backend=str(getattr(st, "backend", "")) or None)
    if getattr(st, "support_reactions", None):
        rec["support_reactions"] = {name: {k: np.asarray(v, float).tolist() for k, v in r.items()}
                                    for name, r in st.support_reactions.items()}
    if st.contact:
        rec["contact"] = {name: contact_record(c) for name, c in st.contact.items()}
    if getattr(st, "checks", None):
        rec["checks"] = dict(st.checks)
    rec.update(extra)
    return rec


def _number(x):
    """A float, or None for None (a record without the value)."""
    return None if x is None else float(x)


ROUNDOFF_NOTE = ("* the loads vanish at this state (internal and external forces are round-off): the "
                 "relative residual is of order 1 and below its round-off floor -- converged")


def format_backends(steps):
    """One line naming the backend of each run of steps (``backend`` of the step records; the
    'auto' backend moves from NumPy to numba once, ``core_se3.backend``); '' when not recorded.

    Example
    -------
    >>> format_backends([{"backend": None}] + [{"backend": "numpy"}] * 3 + [{"backend": "numba"}] * 2)
    'backend: numpy for steps 1-3, numba for steps 4-5'
    """
    runs = []
    for k, rec in enumerate(steps):
        b = rec.get("backend")
        if not b:
            continue
        if runs and runs[-1][0] == b and runs[-1][2] == k - 1:
            runs[-1][2] = k
        else:
            runs.append([b, k, k])
    if not runs:
        return ""
    if len(runs) == 1:
        return f"backend: {runs[0][0]}"
    return "backend: " + ", ".join(f"{b} for step{'s' if a != z else ''} {a}{'-' + str(z) if a != z else ''}"
                                   for b, a, z in runs)


def format_residual(rec, width=9):
    """The relative residual of a step record for a table: ``1.2e-11``, or ``1.0e+00*`` where
    the state converged at the residual's round-off floor with a relative residual above 1e-6
    -- a state where the loads vanish, so that the relative residual compares round-off with
    round-off (:data:`ROUNDOFF_NOTE` explains the mark).

    Parameters
    ----------
    rec : dict
        A step record (:func:`step_record`; ``residual_floor`` may be missing in old documents).
    width : int, optional
        Field width, the mark included.

    Returns
    -------
    str

    Example
    -------
    >>> format_residual({"residual": 3e-12, "residual_floor": 1e-10})
    '  3.0e-12'
    >>> format_residual({"residual": 0.9997, "residual_floor": 310.0})
    ' 1.0e+00*'
    """
    r = float(rec.get("residual", 0.0))
    mark = "*" if r > 1e-6 and r <= float(rec.get("residual_floor", 0.0)) else ""
    return f"{r:.1e}{mark}".rjust(width)


def contact_record(c):
    """JSON form of one entry of ``StepResult.contact``: the total lab force on the shell
    [force] and its moment about the origin, and the scalars of the load's report (penetration
    [length], gap_error, nodes_in_contact); the multipliers are left out.

    Example
    -------
    >>> import numpy as np
    >>> contact_record(dict(force=np.array([0.0, 0.0, 2.0]), moment=np.zeros(3), multipliers=np.ones(4),
    ...                     penetration=1e-9, nodes_in_contact=3))
    {'force': [0.0, 0.0, 2.0], 'moment': [0.0, 0.0, 0.0], 'penetration': 1e-09, 'nodes_in_contact': 3}
    """
    out = dict(force=np.asarray(c["force"], float).tolist(), moment=np.asarray(c["moment"], float).tolist())
    for k, v in c.items():
        if k not in ("force", "moment", "multipliers") and np.isscalar(v):
            out[k] = v.item() if hasattr(v, "item") else v
    return out


def mesh_record(mesh):
    """nx, ny (the structured shape, None for unstructured meshes), node, element, dof counts.

    Parameters: mesh (core_se3.mesh.Mesh).  Returns: dict(nx, ny, n_nodes, n_elements, n_dofs).

    Example
    -------
    >>> from core_se3 import mesh
    >>> mesh_record(mesh.rectangle(1.0, 1.0, 2, 1))
    {'nx': 2, 'ny': 1, 'n_nodes': 6, 'n_elements': 2, 'n_dofs': 36}
    """
    nx, ny = mesh.shape or (None, None)
    return dict(nx=nx, ny=ny, n_nodes=mesh.n_nodes, n_elements=mesh.n_elements, n_dofs=6 * mesh.n_nodes)


def timing_record(timings):
    """The timings with their ``total`` (the sum of the phases).

    Parameters: timings (dict phase -> seconds; a ``total`` given is recomputed).  Returns: dict.

    Example
    -------
    >>> timing_record({"setup": 0.5, "solve": 1.0, "total": 9.0})
    {'setup': 0.5, 'solve': 1.0, 'total': 1.5}
    """
    t = {k: float(v) for k, v in timings.items() if k != "total"}
    t["total"] = sum(t.values())
    return t


def result_document(case, model, variant, params, mesh, steps, timings, reference=None, **extra):
    """The schema's top level: ``params`` {key: {value, unit}}, ``mesh`` a Mesh (or its record),
    ``steps`` step records, ``timings`` a dict of phases; ``extra`` keys follow the standard ones.

    Parameters
    ----------
    case, model, variant : str
        Case (or scenario) name, model ('core_se3', 'fenicsx_ref') and variant (element).
    params : dict
        key -> dict(value, unit).
    mesh : core_se3.mesh.Mesh or dict
        The mesh (or its :func:`mesh_record`).
    steps : list of dict
        Step records (:func:`step_record`).
    timings : dict
        Seconds per phase (the total is added).
    reference : dict, optional
        dict(entry, block, error, ...) of the reference comparison.
    **extra
        Further top-level keys (``control`` goes right after ``variant``).

    Returns
    -------
    dict
        The JSON-able document of schema ``core-se3-result`` version 1.

    Example
    -------
    >>> from core_se3 import mesh
    >>> d = result_document("demo", "core_se3", "default", {}, mesh.rectangle(1, 1, 2, 1), [], {"solve": 1.0})
    >>> d["schema"], d["mesh"]["nx"], d["timings"]["total"]
    ('core-se3-result', 2, 1.0)
    """
    doc = dict(schema=SCHEMA, version=VERSION, case=case, model=model, variant=variant)
    doc.update({k: extra.pop(k) for k in list(extra) if k in ("control",)})
    doc.update(params=params, mesh=mesh if isinstance(mesh, dict) else mesh_record(mesh), steps=steps,
               totals=step_totals(steps), timings=timing_record(timings), reference=reference)
    doc.update(extra)
    return doc


def step_totals(steps):
    """Sums over step records of ``attempts``, ``linear_solves`` and ``iterations`` (the cost
    of the path; a sum is None when a step did not count it).

    Example
    -------
    >>> step_totals([dict(attempts=1, linear_solves=4, iterations=4),
    ...              dict(attempts=3, linear_solves=20, iterations=5)])
    {'attempts': 4, 'linear_solves': 24, 'iterations': 9}
    """
    out = {}
    for key in ("attempts", "linear_solves", "iterations"):
        vals = [s.get(key) for s in steps]
        out[key] = None if any(v is None for v in vals) else int(sum(vals))
    return out


NON_FINITE = "non_finite"
"""The key of a document's non-finite numbers (:func:`json_text`): JSON pointer -> 'NaN',
'Infinity' or '-Infinity'."""


def json_text(doc):
    """``doc`` as strict JSON (indent 1): a NaN or infinite number -- which ``json.dumps`` wrote
    as ``NaN``/``Infinity``, text that strict readers (JavaScript's JSON.parse, jq, Go, Rust's
    serde) refuse -- is written as ``null`` and named, by its JSON pointer (RFC 6901), under the
    top-level key ``non_finite`` of a dict document; :func:`read_json` puts the numbers back.

    Example
    -------
    >>> json.loads(json_text({"u": [0.5, float("nan")], "e": float("-inf")}))
    {'u': [0.5, None], 'e': None, 'non_finite': {'/u/1': 'NaN', '/e': '-Infinity'}}
    """
    try:
        return json.dumps(doc, indent=1, allow_nan=False)
    except ValueError as exc:             # (the walk only where a number is not finite)
        if "Out of range float" not in str(exc):
            raise                         # (a circular reference)
        found = {}
        clean = _finite(doc, "", found)
        if not isinstance(clean, dict):
            raise ValueError(f"a document with non-finite numbers ({', '.join(found)}) must be a JSON object, "
                             "to name them under 'non_finite'") from None
        clean[NON_FINITE] = {**clean.get(NON_FINITE, {}), **found}
        return json.dumps(clean, indent=1, allow_nan=False)


def _finite(x, ptr, found):
    """``x`` with its non-finite floats as None, each recorded in ``found`` by its pointer."""
    if isinstance(x, float) and not np.isfinite(x):
        found[ptr] = "NaN" if x != x else ("Infinity" if x > 0 else "-Infinity")
        return None
    if isinstance(x, dict):
        return {k: _finite(v, f"{ptr}/{str(k).replace('~', '~0').replace('/', '~1')}", found) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v, f"{ptr}/{i}", found) for i, v in enumerate(x)]
    return x


def _restore(doc):
    """Put back the numbers a document names under ``non_finite`` (:func:`json_text`)."""
    for ptr, text in (doc.pop(NON_FINITE, None) or {}).items():
        *path, last = [p.replace("~1", "/").replace("~0", "~") for p in ptr.split("/")[1:]]
        node = doc
        for p in path:
            node = node[int(p)] if isinstance(node, list) else node[p]
        node[int(last) if isinstance(node, list) else last] = float(text.replace("Infinity", "inf"))
    return doc


def write_json(path, doc):
    """Write a document as strict JSON (indent 1; a NaN or infinite number as null, named under
    ``non_finite``: :func:`json_text`).

    Parameters: path (str or path-like), doc (a JSON-able dict).  Atomic (``results.atomic``):
    the text goes to a temporary file beside ``path`` and is moved into place with os.replace, so
    a write that fails or is interrupted half way keeps the previous file whole (before, an
    ``open(path, "w")`` emptied it first).  Returns the path.

    Example
    -------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "r.json")
    >>> _ = write_json(path, result_document("demo", "core_se3", "default", {}, {"nx": None}, [], {}))
    >>> read_json(path)["case"]
    'demo'
    """
    text = json_text(doc)              # (an unserialisable doc fails here, before any file is touched)
    with atomic_path(path) as tmp:
        with open(tmp, "w") as fh:
            fh.write(text)
    return os.fspath(path)


def read_json(path):
    """Read a document, checking its schema and version.

    Parameters: path (str or path-like).  Returns: the document (dict).  Raises
    :class:`~core_se3.errors.ResultFileError` (a ``ValueError``) naming the file for text that is
    not JSON, a top level that is not an object (a list, a number, a string) and an object of
    another schema or version.  The numbers named under ``non_finite`` (:func:`json_text`) are
    put back (NaN, inf), and the key goes.

    Example
    -------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "other.json"
    >>> _ = path.write_text('{"schema": "something-else"}')
    >>> read_json(path)                   # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.ResultFileError: ...other.json: not a core-se3-result document (its schema is 'something-else')
    """
    with open(path) as fh:
        try:
            doc = json.load(fh)
        except json.JSONDecodeError as exc:
            raise ResultFileError(f"not JSON ({exc}); expected a {SCHEMA} document", str(path)) from None
    if not isinstance(doc, dict):
        raise ResultFileError(f"the top level is {_json_kind(doc)}; expected a JSON object (a {SCHEMA} "
                              f"document, as written by write_json)", str(path))
    if doc.get("schema") != SCHEMA:
        raise ResultFileError(f"not a {SCHEMA} document (its schema is {doc.get('schema')!r})", str(path))
    if doc.get("version") != VERSION:
        raise ResultFileError(f"schema version {doc.get('version')!r} (this code reads {VERSION})", str(path))
    try:
        return _restore(doc)
    except (KeyError, IndexError, ValueError, TypeError, AttributeError) as exc:
        raise ResultFileError(f"its '{NON_FINITE}' names a number that is not there ({type(exc).__name__}: {exc})",
                              str(path)) from None


def _json_kind(value):
    """The JSON name of a decoded value's type, with its article (``an array (a list)``, ...)."""
    kinds = ((bool, "a boolean"), (list, "an array (a list)"), (str, "a string"), ((int, float), "a number"))
    return next((name for cls, name in kinds if isinstance(value, cls)), "null")

"""The result document (JSON schema ``core-se3-result`` version 1): its one writer and reader.

    {"schema": "core-se3-result", "version": 1, "case", "model", "variant",
     "params": {key: {"value", "unit"}}, "mesh": {"nx", "ny", "n_nodes", "n_elements", "n_dofs"},
     "steps": [{"load_factor", "load": {"name", "value", "unit"},
                "probes": {name: {"u": [ux, uy, uz], "rotation_angle", "rotation_vector",
                                  "rotation": 3x3}},
                "iterations", "residual", "residual_history", "balance_error"}],
     "timings": {"setup", "assembly", "solve", "other", "total"},
     "reference": {"entry", "block", "error", "error_at"} or null}

``rotation_angle`` is |w| of the rotation vector of R R0^T unwrapped continuously along the
path (so a roll-up reports 6 pi, not its value modulo 2 pi).  Catalogue runs, scenario runs
(``results.json``, with status fields) and fenicsx_ref all write this schema through
:func:`result_document` and :func:`step_record`.
"""
from __future__ import annotations

import json

import numpy as np

__all__ = ["SCHEMA", "VERSION", "read_json", "write_json", "probe_record", "step_record",
           "mesh_record", "timing_record", "result_document"]

SCHEMA = "core-se3-result"
VERSION = 1


def probe_record(p, axis=None):
    """JSON form of a recorded probe state dict(u, R, w) (``rotation_about_axis`` = w . axis
    when an axis is given)."""
    out = dict(u=np.asarray(p["u"]).tolist(), rotation_angle=float(np.linalg.norm(p["w"])))
    if axis is not None:
        out["rotation_about_axis"] = float(np.asarray(p["w"]) @ axis)
    out.update(rotation_vector=np.asarray(p["w"]).tolist(), rotation=np.asarray(p["R"]).tolist())
    return out


def step_record(st, load, axis=None, **extra):
    """JSON form of a StepResult: load factor, the reported load (dict name, value, unit, ...),
    probes, Newton iterations and residuals, balance error, then ``extra`` keys."""
    rec = dict(load_factor=float(st.load_factor), load=load,
               probes={name: probe_record(p, axis) for name, p in st.probes.items()},
               iterations=int(st.iterations),
               residual=float(st.residual_history[-1]) if st.residual_history else 0.0,
               residual_history=[float(x) for x in st.residual_history],
               balance_error=float(st.balance_error))
    rec.update(extra)
    return rec


def mesh_record(mesh):
    """nx, ny (the structured shape, None for unstructured meshes), node, element, dof counts."""
    nx, ny = mesh.shape or (None, None)
    return dict(nx=nx, ny=ny, n_nodes=mesh.n_nodes, n_elements=mesh.n_elements, n_dofs=6 * mesh.n_nodes)


def timing_record(timings):
    """The timings with their ``total`` (the sum of the phases)."""
    t = {k: float(v) for k, v in timings.items() if k != "total"}
    t["total"] = sum(t.values())
    return t


def result_document(case, model, variant, params, mesh, steps, timings, reference=None, **extra):
    """The schema's top level: ``params`` {key: {value, unit}}, ``mesh`` a Mesh (or its record),
    ``steps`` step records, ``timings`` a dict of phases; ``extra`` keys follow the standard ones.

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
               timings=timing_record(timings), reference=reference)
    doc.update(extra)
    return doc


def write_json(path, doc):
    """Write a document (indent 1)."""
    with open(path, "w") as fh:
        json.dump(doc, fh, indent=1)


def read_json(path):
    """Read a document, checking its schema and version."""
    with open(path) as fh:
        doc = json.load(fh)
    if doc.get("schema") != SCHEMA:
        raise ValueError(f"{path}: not a {SCHEMA} document")
    if doc.get("version") != VERSION:
        raise ValueError(f"{path}: schema version {doc.get('version')} (this code reads {VERSION})")
    return doc

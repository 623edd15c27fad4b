"""Shared plumbing of the studies: output paths, JSON records, reference paths, plots."""
from __future__ import annotations

import json
import os
import time

import numpy as np

__all__ = ["OUT", "stem", "save", "load", "planar", "reference_path", "progress"]

OUT = os.environ.get("COMPARISON_OUT", os.path.join(os.path.dirname(__file__), "..", "reports"))


def _path(*parts):
    p = os.path.normpath(os.path.join(OUT, *parts))
    os.makedirs(os.path.dirname(p), exist_ok=True)
    return p


def stem(study, quick=False):
    """File stem of a study's data and figure: a ``--quick`` (development) run writes
    ``<study>-quick``, never over the full study that reports/REPORT.md is rendered from."""
    return f"{study}-quick" if quick else study


def save(study, data, quick=False):
    """reports/data/<study>.json (``<study>-quick.json`` for a quick run)"""
    with open(_path("data", f"{stem(study, quick)}.json"), "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1, default=float)


def load(study, quick=False):
    with open(_path("data", f"{stem(study, quick)}.json"), encoding="utf-8") as f:
        return json.load(f)


def figure_path(name):
    return _path("figures", name)


_T0 = time.perf_counter()


def progress(msg):
    print(f"[{time.perf_counter() - _T0:7.1f} s] {msg}", flush=True)


def planar(case, u):
    """Probe displacements (n, 3) -> the reference plane (u, v) of the case (catalogue.planar)."""
    from core_se3.catalogue import planar as _planar
    return _planar(case, np.asarray(u, float).reshape(-1, 3))


def reference_path(name, overrides, lams, block=None, entry=None):
    """Reference (u, v) of case ``name`` at the load factors ``lams`` (n, 2), in case units, or
    None when the case has no displacement reference.  ``block``/``entry`` override the case's
    (e.g. 'tip_reissner_instance')."""
    from core_se3 import catalogue
    from core_se3.catalogue.references import elastica_entry
    from .metrics import interp_reference
    case = catalogue.get_case(name)
    p = catalogue.case_params(case, overrides)
    r = catalogue.reference_for(case, p, check=entry is None)   # a study's own entry is its choice
    if r is None:
        return None
    e = elastica_entry(entry or r[0])
    blk = e[block or r[1]]
    Lr = case.reference.length(p)  # every block of an entry shares its units (u/L or physical)
    loads = [case.reference.load_to_ref(p, case.load_value(p, lam)) for lam in lams]
    vals = np.column_stack([Lr * np.asarray(blk["u"], float), Lr * np.asarray(blk["v"], float)])
    return interp_reference(loads, np.asarray(e["load"], float), vals)

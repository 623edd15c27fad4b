"""Access to the packaged reference solutions (``core_se3/data``).

``elastica.json``: planar elastica solutions keyed by case name (e.g.
``"1_cantilever_tip_force_kirchhoff"``); ``literature.json``: ``{"_meta": ..., "benchmarks": [...]}``
with Sze, Liu & Lo (2004) and other tables, each benchmark identified by its ``"id"``.
See ``data/SOURCE.md`` and ``data/REFERENCES.md`` for provenance and conventions. Cite the file and
key of every entry a test uses.
"""
from __future__ import annotations

import ast
import copy
import json
from functools import lru_cache
from importlib import resources
from typing import Any

__all__ = [
    "load_elastica",
    "load_literature",
    "elastica_names",
    "elastica_entry",
    "literature_ids",
    "literature_entry",
    "contact_lift_elastica",
]

def _read_json(name: str) -> Any:
    # core_se3/data has no __init__.py: address it from the core_se3 package.
    ref = resources.files("core_se3").joinpath("data").joinpath(name)
    return json.loads(ref.read_text(encoding="utf-8"))


@lru_cache(maxsize=None)
def _elastica_raw() -> dict:
    return _read_json("elastica.json")


@lru_cache(maxsize=None)
def _literature_raw() -> dict:
    return _read_json("literature.json")


def load_elastica() -> dict:
    """The whole ``elastica.json`` as a dict (cached; a deep copy, safe to modify)."""
    return copy.deepcopy(_elastica_raw())


def load_literature() -> dict:
    """The whole ``literature.json`` as a dict (cached; a deep copy, safe to modify)."""
    return copy.deepcopy(_literature_raw())


def _parse_literals(value: Any) -> Any:
    """Recursively turn strings holding Python/JSON literals (``"{'EI': 1.0}"``, ``"[0, 0.5]"``,
    ``"1e-3"``) into real objects; other strings (descriptions, units) are left alone."""
    if isinstance(value, dict):
        return {k: _parse_literals(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_parse_literals(v) for v in value]
    if isinstance(value, str):
        s = value.strip()
        if s[:1] in "[{(" and s[-1:] in "]})":
            try:
                return _parse_literals(ast.literal_eval(s))
            except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
                return value
        if s in ("None", "True", "False"):
            return ast.literal_eval(s)
        if s and s[0] in "+-.0123456789":  # bare numbers stored as text, e.g. "1.0", "-3e-4"
            try:
                num = ast.literal_eval(s)
            except (ValueError, SyntaxError, TypeError):
                return value
            if isinstance(num, (int, float)) and not isinstance(num, bool):
                return num
        return value
    return value


def elastica_names() -> list[str]:
    """Names of the elastica cases (all keys except ``_meta``).

    Returns: list of str, in file order.

    Example
    -------
    >>> "1_cantilever_tip_force_kirchhoff" in elastica_names()
    True
    """
    return [k for k in _elastica_raw() if not k.startswith("_")]


def elastica_entry(name: str) -> dict:
    """One elastica case as a dict, with literal-valued strings parsed into dicts/lists/numbers.

    Raises ``KeyError`` listing the available names if ``name`` is unknown.

    Parameters: name (str).  Returns: dict (a copy: safe to modify).

    Example
    -------
    >>> e = elastica_entry("1_cantilever_tip_force_kirchhoff")
    >>> sorted(k for k in e if k in ("load", "tip"))
    ['load', 'tip']
    """
    data = _elastica_raw()
    if name not in data or name.startswith("_"):
        raise KeyError(
            f"no elastica reference {name!r} in elastica.json; available: " + ", ".join(elastica_names())
        )
    return _parse_literals(copy.deepcopy(data[name]))


def literature_ids() -> list[str]:
    """Ids of the benchmarks in ``literature.json``.

    Returns: list of str, in file order.

    Example
    -------
    >>> literature_ids()[0]
    'sze3.1_cantilever_end_shear'
    """
    return [b["id"] for b in _literature_raw()["benchmarks"]]


def literature_entry(benchmark_id: str) -> dict:
    """One ``literature.json`` benchmark (by its ``id``), literal-valued strings parsed.

    Raises ``KeyError`` listing the available ids if ``benchmark_id`` is unknown.

    Parameters: benchmark_id (str).  Returns: dict (a copy) with ``title``, ``columns``, the
    table columns (``P_over_Pmax``, ...), sources and parameters.

    Example
    -------
    >>> e = literature_entry("sze3.1_cantilever_end_shear")
    >>> e["columns"][0], e["P_over_Pmax"][0], e["P_over_Pmax"][-1]
    ('P_over_Pmax', 0.0, 1.0)
    """
    for b in _literature_raw()["benchmarks"]:
        if b.get("id") == benchmark_id:
            return _parse_literals(copy.deepcopy(b))
    raise KeyError(
        f"no literature benchmark {benchmark_id!r} in literature.json; available: " + ", ".join(literature_ids())
    )


@lru_cache(maxsize=None)
def _lift_raw() -> dict:
    return _read_json("contact_lift_elastica.json")


def contact_lift_elastica() -> dict:
    """``contact_lift_elastica.json``: the large-deflection reference of ``contact-lift`` (the
    elastica of a heavy strip lifted off a rigid plane, free detachment point), rows for
    q_l L^3 / EI = 20 at delta / L = 0.0025 ... 0.3, computed in this project by
    ``benchmarks/contact_lift_elastica.py`` (shooting and collocation, agreeing to < 1e-12).

    Returns: dict (a copy) with ``params``, ``scaling``, ``rows`` (delta_over_L, l_over_L,
    lift_force_over_qlL, tip_angle_rad, ...), ``methods`` and ``source``.

    Example
    -------
    >>> d = contact_lift_elastica()
    >>> d["params"]["Q"], [round(r["l_over_L"], 6) for r in d["rows"] if r["delta_over_L"] == 0.2]
    (20.0, [0.717426])
    """
    return copy.deepcopy(_lift_raw())

"""TOML writing of scenario documents (the reader is the standard tomllib)."""
from __future__ import annotations

import json
import math

import numpy as np

__all__ = ["dumps"]


def dumps(doc):
    """TOML text of a scenario given as nested dicts/lists (tables, arrays of tables, values).

    Parameters
    ----------
    doc : dict
        Tables (dicts), arrays of tables (lists of dicts) and values (bool, int, float, str,
        lists, NumPy scalars); anything else is a TypeError.

    Returns
    -------
    str
        TOML that ``tomllib.loads`` reads back to ``doc`` (floats written with repr).

    Example
    -------
    >>> print(dumps({"name": "demo", "mesh": {"generator": "rectangle", "nx": 4}}))
    name = "demo"
    <BLANKLINE>
    [mesh]
    generator = "rectangle"
    nx = 4
    <BLANKLINE>
    """
    lines = []
    _dump_table(doc, [], lines)
    return "\n".join(lines).strip() + "\n"


def _dump_key(k):
    k = str(k)
    return k if k and all(c.isascii() and (c.isalnum() or c in "-_") for c in k) else _dump_string(k)


def _dump_string(s):
    """A TOML basic string: UTF-8 as it is (a ``\\uXXXX`` escape of a character beyond U+FFFF
    would be half a surrogate pair, which TOML refuses), control characters escaped (DEL too)."""
    return json.dumps(s, ensure_ascii=False).replace("\x7f", "\\u007f")


def _dump_value(x):
    if isinstance(x, bool):
        return "true" if x else "false"
    if isinstance(x, int):
        return str(x)
    if isinstance(x, float):
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return repr(float(x))                  # float(): NumPy 2 scalars repr as np.float64(...)
    if isinstance(x, str):
        return _dump_string(x)
    if isinstance(x, (list, tuple)):
        return "[" + ", ".join(_dump_value(y) for y in x) + "]"
    if isinstance(x, dict):
        return "{" + ", ".join(f"{_dump_key(k)} = {_dump_value(y)}" for k, y in x.items()) + "}"
    if isinstance(x, np.generic):
        return _dump_value(x.item())
    raise TypeError(f"cannot write {type(x).__name__} to TOML")


def _dump_table(d, path, lines):
    def is_aot(x):
        return isinstance(x, list) and x and all(isinstance(y, dict) for y in x)
    for k, x in d.items():
        if not isinstance(x, dict) and not is_aot(x):
            lines.append(f"{_dump_key(k)} = {_dump_value(x)}")
    for k, x in d.items():
        if isinstance(x, dict):
            p = path + [_dump_key(k)]
            lines.append("")
            lines.append(f"[{'.'.join(p)}]")
            _dump_table(x, p, lines)
        elif is_aot(x):
            for y in x:
                p = path + [_dump_key(k)]
                lines.append("")
                lines.append(f"[[{'.'.join(p)}]]")
                _dump_table(y, p, lines)

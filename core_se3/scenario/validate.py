"""Typed access to a parsed scenario document: every failure is a ScenarioError naming the file,
the dotted key (``loads[2].force``) and what was expected.

:class:`Validator` checks one value at a time (number, integer, boolean, string, vector, 3x3
matrix, load-factor scale, tables); :meth:`Validator.params` checks the keys a registered load
or field kind declares (``core_se3.model.Param``), so that a new kind needs no validator code.
"""
from __future__ import annotations

import math
from collections import namedtuple

from ..errors import ScenarioError, ScenarioWarning, did_you_mean
from ..registry import REQUIRED
from ..model.base import ScaleTable

__all__ = ["Validator", "Bounds", "join", "tname", "show", "make_scale", "user_key", "elsewhere"]

_REQ = REQUIRED


def elsewhere(k):
    """'; it is a key of [solver]' when ``k`` is a key of another table of the scenario (the top
    level, [mesh], [material], [solver], [output], [design]), else '': a key written in the wrong
    table, as often after a [table] header that TOML makes it part of.

    Example
    -------
    >>> elsewhere("steps"), elsewhere("nosuch")
    ('; it is a key of [solver]', '')
    >>> elsewhere("units")[:55]
    '; it is a top-level key: put it before the first [table'
    """
    from ..fem.material_kinds import MATERIALS
    from .schema import ARCLENGTH, DESIGN, OUTPUT, SCENARIO, SOLVER
    if k in SCENARIO.keys() and k not in ("name", "description"):
        return ("; it is a top-level key: put it before the first [table] header (TOML makes a key after a "
                "header part of that table)")
    homes = [("[mesh]", ("generator", "file", "d1_hint", "triangles", "refine", "grade")),
             ("[material]", tuple(x for law in MATERIALS.values() for x in law.keys()) + ("law",)),
             ("[solver]", SOLVER.keys() + ARCLENGTH.keys()), ("[output]", OUTPUT.keys()), ("[design]", DESIGN.keys())]
    found = [name for name, keys in homes if k in keys]
    return f"; it is a key of {' and '.join(found)}" if found else ""


def make_scale(spec):
    """Load-factor scaling s(lam) from a validated spec ("linear", "constant" or a table
    [[lam, s], ...], linear in between and constant outside).

    Parameters
    ----------
    spec : str or sequence of (float, float)
        "linear" (s = lam), "constant" (s = 1) or the table (lam strictly increasing).

    Returns
    -------
    callable
        lam -> s (a table: a :class:`~core_se3.model.ScaleTable`, whose points load stepping lands on).

    Example
    -------
    >>> make_scale([[0.0, 0.0], [0.5, 1.0]])(0.25), make_scale("constant")(7.0)
    (0.5, 1.0)
    """
    if spec == "linear":
        return lambda lam: lam
    if spec == "constant":
        return lambda lam: 1.0
    return ScaleTable(spec)        # its points are where load stepping lands a try


_TYPE_NAMES = ((bool, "a boolean"), (int, "an integer"), (float, "a number"), (str, "a string"),
               (list, "an array"), (dict, "a table"))

Bounds = namedtuple("Bounds", "lo lo_open hi hi_open", defaults=(None, False, None, False))
Bounds.__doc__ = """The bounds of a number (``Validator.number``): lo, hi (None: unbounded) and whether
each is open (excluded): ``Bounds(lo=0.0, lo_open=True)`` is "> 0".

Example
-------
>>> Validator({}).number({"t": 0.0}, "t", "mesh", bounds=Bounds(lo=0.0, lo_open=True))
Traceback (most recent call last):
...
core_se3.errors.ScenarioError: [mesh.t]: expected a number > 0, got 0
"""


def tname(v):
    """'a boolean', 'an integer', ... : the TOML type of a value, for messages."""
    for t, name in _TYPE_NAMES:
        if isinstance(v, t):
            return name
    return type(v).__name__


def show(v):
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


class Validator:
    """Typed access to a parsed TOML document; every failure is a ScenarioError(file, key)."""

    def __init__(self, file, strict=False):
        self.file = file
        self.strict = strict
        self.warnings = []

    def fail(self, key, msg):
        raise ScenarioError(msg, self.file, key)

    @staticmethod
    def shown(x):
        """A value as messages show it: its TOML type and (shortened) repr."""
        return f"{tname(x)} {show(x)}"

    def warn(self, key, msg):
        """An implausible value: a ScenarioWarning kept in ``warnings`` (with ``strict`` a
        ScenarioError)."""
        if self.strict:
            self.fail(key, msg + " (an error with --strict)")
        self.warnings.append(ScenarioWarning(msg, self.file, key))

    def choice_fail(self, key, value, choices):
        """Fail for a value that is not one of ``choices`` (with the closest one)."""
        self.fail(key, f"unknown value {value!r}{did_you_mean(value, choices)} (expected one of "
                       f"{', '.join(map(repr, choices))})")

    def table(self, d, key, allowed, required=()):
        if not isinstance(d, dict):
            self.fail(key, f"expected a table, got {tname(d)} {show(d)}")
        for k in d:
            if k not in allowed:
                self.fail(join(key, k), f"unknown key {k!r}{elsewhere(k) or did_you_mean(k, allowed)} (allowed "
                                        f"here: {', '.join(allowed)})")
        for k in required:
            if k not in d:
                self.fail(join(key, k), "missing required key")
        return d

    def _lookup(self, d, k, key, default, what):
        """(path, present): the dotted path of d[k]; a missing required key fails naming ``what``."""
        path = join(key, k)
        if k not in d and default is _REQ:
            self.fail(path, f"missing required key ({what})")
        return path, k in d

    def number(self, d, k, key, default=_REQ, bounds=None, infinite=False):
        """A finite number (``infinite``: +-inf too, for a bound whose default is none) in the
        ``bounds`` (:data:`Bounds`, or anything with their fields, e.g. a Param; default none)."""
        lo, lo_open, hi, hi_open = (None, False, None, False) if bounds is None else \
            (bounds.lo, bounds.lo_open, bounds.hi, bounds.hi_open)
        path, present = self._lookup(d, k, key, default, "a number")
        if not present:
            return default
        v = d[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(path, f"expected a number, got {tname(v)} {show(v)}")
        v = float(v)
        if not math.isfinite(v) and not (infinite and math.isinf(v)):
            self.fail(path, f"expected a finite number, got {v}")
        if lo is not None and (v <= lo if lo_open else v < lo):
            self.fail(path, f"expected a number {'>' if lo_open else '>='} {lo:g}, got {v:g}")
        if hi is not None and (v >= hi if hi_open else v > hi):
            self.fail(path, f"expected a number {'<' if hi_open else '<='} {hi:g}, got {v:g}")
        return v

    def integer(self, d, k, key, default=_REQ, lo=None, hi=None):
        path, present = self._lookup(d, k, key, default, "an integer")
        if not present:
            return default
        v = d[k]
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(path, f"expected an integer, got {tname(v)} {show(v)}")
        if lo is not None and v < lo:
            self.fail(path, f"expected an integer >= {lo}, got {v}")
        if hi is not None and v > hi:
            self.fail(path, f"expected an integer <= {hi}, got {v}")
        return v

    def boolean(self, d, k, key, default=_REQ):
        path, present = self._lookup(d, k, key, default, "true or false")
        if not present:
            return default
        if not isinstance(d[k], bool):
            self.fail(path, f"expected true or false, got {tname(d[k])} {show(d[k])}")
        return d[k]

    def string(self, d, k, key, default=_REQ, choices=None):
        path, present = self._lookup(d, k, key, default, "a string" if not choices else
                                     f"one of {', '.join(map(repr, choices))}")
        if not present:
            return default
        v = d[k]
        if not isinstance(v, str):
            self.fail(path, f"expected a string, got {tname(v)} {show(v)}")
        if choices is not None and v not in choices:
            self.fail(path, f"unknown value {v!r}{did_you_mean(v, choices)} (expected one of "
                            f"{', '.join(map(repr, choices))})")
        return v

    def vector(self, d, k, key, n=3, default=_REQ, nonzero=False):
        path, present = self._lookup(d, k, key, default, f"an array of {n} numbers")
        if not present:
            return default
        v = d[k]
        if (not isinstance(v, list) or len(v) != n
                or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)):
            self.fail(path, f"expected an array of {n} numbers, got {tname(v)} {show(v)}")
        v = [float(x) for x in v]
        if not all(math.isfinite(x) for x in v):
            self.fail(path, f"expected finite numbers, got {v}")
        if nonzero and not any(v):
            self.fail(path, "expected a non-zero vector")
        return v

    def matrix3(self, d, k, key):
        path = join(key, k)
        v = d.get(k, _REQ)
        if v is _REQ:
            self.fail(path, "missing required key (a 3x3 array of numbers)")
        if not isinstance(v, list) or len(v) != 3:
            self.fail(path, f"expected a 3x3 array of numbers, got {tname(v)} {show(v)}")
        return [self.vector({"row": r}, "row", f"{path}[{i}]") for i, r in enumerate(v)]

    def scale(self, d, key, default="linear"):
        path = join(key, "scale")
        if "scale" not in d:
            return default
        v = d["scale"]
        if isinstance(v, str):
            return self.string(d, "scale", key, choices=("linear", "constant"))
        if not isinstance(v, list) or len(v) < 2:
            self.fail(path, 'expected "linear", "constant" or a table [[lam, s], ...] of at least two '
                            f"points, got {tname(v)} {show(v)}")
        rows = [self.vector({"p": r}, "p", f"{path}[{i}]", n=2) for i, r in enumerate(v)]
        lam = [r[0] for r in rows]
        if any(b <= a for a, b in zip(lam, lam[1:])):
            self.fail(path, f"the load factors of a scale table must increase strictly, got {lam}")
        return rows

    def array_of_tables(self, doc, k):
        v = doc.get(k, [])
        if isinstance(v, dict):
            self.fail(k, f"expected an array of tables ([[{k}]]), got a single table ([{k}])")
        if not isinstance(v, list) or any(not isinstance(x, dict) for x in v):
            self.fail(k, f"expected an array of tables ([[{k}]]), got {tname(v)} {show(v)}")
        return v

    def names_table(self, doc, k):
        v = doc.get(k, {})
        if not isinstance(v, dict):
            self.fail(k, f"expected a table of named entries ([{k}.NAME]), got {tname(v)} {show(v)}")
        for name, t in v.items():
            if not isinstance(t, dict):
                self.fail(join(k, name), f"expected a table, got {tname(t)} {show(t)}")
        return v

    def section(self, d, key, kind, first=(), extra=(), required=()):
        """The values of table ``d`` declared by ``kind`` (a ``registry.Kind``): unknown keys
        refused (``first``, ``extra``: keys the section itself reads before and after the kind's,
        e.g. ``type`` and the selection), ``required`` present, every declared key checked
        (:meth:`params`), then the kind's check across keys."""
        self.table(d, key, tuple(first) + kind.keys() + tuple(extra), required=required)
        out = self.params(d, key, kind.params)
        self.kind_check(kind, out, d, key)
        return out

    def kind_check(self, kind, values, d, key):
        """Run ``kind.check(values, given)``; its (key, message) becomes a ScenarioError."""
        check = getattr(kind, "check", None)
        if check is not None:
            bad = check(values, set(d))
            if bad is not None:
                self.fail(join(key, bad[0]) if bad[0] else key, bad[1])

    def params(self, d, key, params):
        """Values of the declared keys ``params`` (``registry.Param``) of table d, defaults
        filled in (``table`` params validated recursively; None stays None)."""
        out = {}
        for p in params:
            out[p.name] = self.param(d, key, p)
        return out

    def param(self, d, key, p):
        """The value of one declared key (``registry.Param``) of table d (its default when absent)."""
        if p.parse is not None:
            if p.name not in d:
                if p.required:
                    self.fail(join(key, p.name), f"missing required key ({p.doc or 'see the docs'})")
                return p.default
            return p.parse(self, d, key)
        if p.kind == "vector":
            val = self.vector(d, p.name, key, n=p.n, default=p.default, nonzero=p.nonzero)
            return list(val) if isinstance(val, (tuple, list)) else val
        if p.kind == "number":           # a bound whose default is infinite may be given as inf
            return self.number(d, p.name, key, default=p.default, bounds=p,
                               infinite=isinstance(p.default, float) and math.isinf(p.default))
        if p.kind == "integer":
            return self.integer(d, p.name, key, default=p.default, lo=p.lo, hi=p.hi)
        if p.kind == "bool":
            return self.boolean(d, p.name, key, default=p.default)
        if p.kind == "string":
            return self.string(d, p.name, key, default=p.default, choices=p.choices)
        if p.kind == "matrix3":
            if p.name not in d and not p.required:
                return p.default
            return self.matrix3(d, p.name, key)
        if p.kind == "list":
            return self.items(d, key, p)
        if p.kind == "any":
            if p.name not in d:
                if p.required:
                    self.fail(join(key, p.name), "missing required key")
                return p.default
            return d[p.name]
        if p.name not in d:                                   # a table
            if p.required:
                self.fail(join(key, p.name), "missing required key (a table)")
            return p.default
        k2 = join(key, p.name)
        self.table(d[p.name], k2, tuple(q.name for q in p.fields),
                   required=tuple(q.name for q in p.fields if q.required))
        return self.params(d[p.name], k2, p.fields)

    def items(self, d, key, p):
        """An array of strings (from ``p.choices``) or integers (in [p.lo, p.hi]): at least
        ``p.min_items``; ``p.unique`` 'error' refuses a repeat, 'sort' gives the sorted set."""
        path, present = self._lookup(d, p.name, key, p.default, "an array")
        if not present:
            return list(p.default) if isinstance(p.default, (list, tuple)) else p.default
        x = d[p.name]
        what = p.doc or ("names" if p.item == "string" else "integers")
        ok = isinstance(x, list) and len(x) >= p.min_items
        if ok and p.item == "string":
            ok = all(isinstance(a, str) and (p.choices is None or a in p.choices) for a in x)
        elif ok:
            ok = all(not isinstance(a, bool) and isinstance(a, int) and (p.lo is None or a >= p.lo)
                     and (p.hi is None or a <= p.hi) for a in x)
        if ok and p.unique == "error" and len(set(x)) != len(x):
            again = sorted({a for a in x if x.count(a) > 1})
            self.fail(path, f"lists {show(again)} more than once ({show(x)}): each of the {what} once; was "
                            "another meant?")
        if not ok:
            self.fail(path, f"expected {'a non-empty' if p.min_items else 'an'} array of {what}, got {show(x)}")
        return sorted(set(x)) if p.unique == "sort" else list(x)


def user_key(key, kind, exc):
    """The dotted key to name for a ValueError that a kind's own build raised (a user's
    constructor refusing a value): ``exc.param`` when it has one, else the one declared key whose
    name the message mentions, else the entry's key.

    Example
    -------
    >>> from core_se3.registry import Param, Section
    >>> k = Section("torus", (Param("R", "number"), Param("r", "number")))
    >>> user_key("obstacles[0]", k, ValueError("the tube radius r = 2 must be below R = 1")), user_key("x", k, ValueError("bad"))
    ('obstacles[0]', 'x')
    >>> user_key("obstacles[0]", k, ValueError("r must be > 0, got -1"))
    'obstacles[0].r'
    """
    import re
    param = getattr(exc, "param", None)
    if param:
        return join(key, param)
    named = [k for k in kind.keys() if re.search(rf"(?<![\w.]){re.escape(k)}(?![\w(])", str(exc))]
    return join(key, named[0]) if len(named) == 1 else key


def join(key, k):
    """The dotted key ``key.k`` (``k`` alone at the top level)."""
    if not key:
        return str(k)
    return f"{key}.{k}"

"""The one vocabulary of extension points: :class:`Param` (one key a scenario file may give),
:class:`Kind` (a named set of Params with a build function and a check across keys: a load kind,
a mesh generator, a material law, a support, a scenario section, ...) and :class:`Registry` (the
kinds of one extension point by name: it refuses a second entry of the same name and answers an
unknown name with the closest one).

Every scenario section is declared by a Kind and every extension point is a Registry of Kinds
of one class, so that one description gives the validation of scenario files
(``scenario.validate.Validator.section``), the tables of docs/SCENARIOS.md (:meth:`Kind.table`,
:meth:`Registry.table`), the ``core-se3 kinds`` listing and ``--help`` text, the TOML writer
(:meth:`Kind.entry`) and the contract tests every registered kind passes
(tests/test_kind_contracts.py).  :func:`register` adds a kind to the registry of its class;
each extension point also keeps its own ``register_*`` function of the same shape (a kind in,
the same kind out).

Example
-------
>>> reg = Registry("load kind")
>>> reg.register("gravity", object) is object
True
>>> reg.lookup("gravty")
Traceback (most recent call last):
...
core_se3.errors.OptionError: unknown load kind 'gravty'; did you mean 'gravity'?; registered: gravity
>>> Param("E", "number", lo=0.0, lo_open=True, doc="Young's modulus").describe()
'a number > 0'
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import OptionError, did_you_mean

__all__ = ["Registry", "Param", "Kind", "Section", "REQUIRED", "register", "PARAM_KINDS", "registries"]


class _Required:
    """The default of a required key (a singleton: ``Param.required`` is True)."""

    def __repr__(self):
        return "REQUIRED"


REQUIRED = _Required()

# the value types a Param may declare (docs/EXTENDING.md, "The vocabulary")
PARAM_KINDS = ("number", "integer", "bool", "string", "vector", "matrix3", "table", "list", "any")
_FRAMES = (None, "vector", "rotation", "tensor")


@dataclass(frozen=True)
class Param:
    """One key of a kind or a section in a scenario file.

    kind: 'number', 'integer', 'bool', 'string' (with ``choices``), 'vector' (``n`` numbers,
    ``nonzero``), 'matrix3' (3x3 numbers), 'table' (a sub-table with ``fields``, themselves
    Params), 'list' (an array of ``item`` = 'string' or 'integer' values, at least
    ``min_items``; ``unique``: 'error' refuses a repeat, 'sort' keeps the sorted distinct values)
    or 'any' (checked by the kind's own check); ``default`` REQUIRED for a required key (None:
    optional, no value); ``lo``/``hi`` bounds of numbers and integers (exclusive with
    ``lo_open``/``hi_open``); ``doc``: one line for the docs (for a list also the message's
    description of its items); ``frame``: how the value changes under a rigid rotation Q of the
    whole scene, for the contract tests: 'vector' (Q v: directions and points about the
    origin; the default of vectors), 'rotation' (a rotation vector: log(Q exp(v))), 'tensor'
    (Q G Q^T: the default of 3x3 matrices) or None (unchanged); ``parse``: for a value of a
    structure of its own (kind 'any'), ``parse(validator, table, key) -> value`` reads and checks
    ``table[name]`` when the key is given (``scenario.validate.Validator``: its ``fail`` names the
    key).

    The scenario validator checks every declared key from these fields, so a new kind needs no
    validator code.

    Attributes
    ----------
    name : str
        The key.
    kind : str
        One of :data:`PARAM_KINDS`.
    default : object
        The default value, or ``REQUIRED``; ``required`` (property) is True for the latter.
    nonzero, lo, lo_open, doc, fields, hi, hi_open, choices, n, item, min_items, unique, frame, parse
        As above.

    Example
    -------
    >>> p = Param("nu", "number", lo=-1.0, lo_open=True, hi=0.5, hi_open=True, doc="Poisson's ratio")
    >>> p.required, p.describe()
    (True, 'a number in (-1, 0.5)')
    >>> Param("x", "vektor")
    Traceback (most recent call last):
    ...
    TypeError: Param 'x': unknown kind 'vektor'; did you mean 'vector'? (one of number, integer, bool, string, vector, matrix3, table, list, any)
    """
    name: str
    kind: str
    default: object = REQUIRED
    nonzero: bool = False
    lo: float | None = None
    lo_open: bool = False
    doc: str = ""
    fields: tuple = ()
    hi: float | None = None
    hi_open: bool = False
    choices: tuple | None = None
    n: int = 3
    item: str | None = None
    min_items: int = 0
    unique: str | None = None
    frame: str | None = "auto"
    parse: object = None

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise TypeError(f"a Param needs a non-empty name, got {self.name!r}")
        if self.kind not in PARAM_KINDS:
            raise TypeError(f"Param {self.name!r}: unknown kind {self.kind!r}{did_you_mean(self.kind, PARAM_KINDS)} "
                            f"(one of {', '.join(PARAM_KINDS)})")
        if self.kind == "table" and any(not isinstance(f, Param) for f in self.fields):
            raise TypeError(f"Param {self.name!r}: the fields of a table are Params")
        if self.kind == "list" and self.item not in ("string", "integer"):
            raise TypeError(f"Param {self.name!r}: a list needs item = 'string' or 'integer'")
        if self.unique not in (None, "error", "sort"):
            raise TypeError(f"Param {self.name!r}: unique must be None, 'error' or 'sort'")
        if self.frame == "auto":
            object.__setattr__(self, "frame", {"vector": "vector", "matrix3": "tensor"}.get(self.kind))
        if self.parse is not None and not callable(self.parse):
            raise TypeError(f"Param {self.name!r}: parse must be callable")
        if self.frame not in _FRAMES:
            raise TypeError(f"Param {self.name!r}: frame must be one of {_FRAMES}")

    @property
    def required(self):
        return self.default is REQUIRED

    def describe(self):
        """The value type in words ('a number > 0', 'an array of 3 numbers', ...), for the docs
        and --help."""
        if self.kind in ("number", "integer"):
            return ("a number" if self.kind == "number" else "an integer") + _bounds(self)
        if self.kind == "bool":
            return "true or false"
        if self.kind == "string":
            return "one of " + ", ".join(f'"{c}"' for c in self.choices) if self.choices else "a string"
        if self.kind == "vector":
            return f"an array of {self.n} numbers" + (", not all zero" if self.nonzero else "")
        if self.kind == "matrix3":
            return "a 3x3 array of numbers"
        if self.kind == "table":
            return "a table" + (": " + ", ".join(p.name for p in self.fields) if self.fields else "")
        if self.kind == "list":
            what = "names" if self.item == "string" else "integers"
            return f"an array of {what}" + (f" from {', '.join(map(repr, self.choices))}" if self.choices else "")
        return "(see the text)"

    def default_text(self):
        """The default as the docs show it: 'required', 'none' or the TOML value."""
        if self.required:
            return "required"
        if self.default is None:
            return "none"
        return _toml_text(self.default)


def _bounds(p):
    lo = None if p.lo is None else f"{p.lo:g}"
    hi = None if p.hi is None or p.hi == math.inf else f"{p.hi:g}"
    if lo is not None and hi is not None:
        return f" in {'(' if p.lo_open else '['}{lo}, {hi}{')' if p.hi_open else ']'}"
    if lo is not None:
        return f" {'>' if p.lo_open else '>='} {lo}"
    if hi is not None:
        return f" {'<' if p.hi_open else '<='} {hi}"
    return ""


def _toml_text(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_text(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    return str(v)


@dataclass(frozen=True)
class Kind:
    """Base class of every kind of every extension point (and of :class:`Section`).

    A subclass is a frozen dataclass that declares ``params`` (tuple of :class:`Param`: the keys
    besides the selector key ``type``), ``build`` (what makes the object; its signature is the
    extension point's), ``check`` ((values, given) -> (key, message) or None: a check across
    keys, ``given`` the keys the user wrote; optional) and ``doc`` (one line).  The field order
    is each subclass's own (``LoadKind(name, target, params, build, ...)``), so this base holds
    only ``name`` and what every kind does with its Params.

    Example
    -------
    >>> k = Section("probe", (Param("name", "string"), Param("edge", "string", None)), doc="a recorded point")
    >>> k.keys(), k.entry({"name": "tip", "edge": None})
    (('name', 'edge'), {'name': 'tip'})
    >>> print(k.table())
    | key | value | default | |
    |---|---|---|---|
    | `name` | a string | required | |
    | `edge` | a string | none | |
    """
    name: str

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise TypeError(f"a {type(self).__name__} needs a non-empty name, got {self.name!r}")
        params = getattr(self, "params", ())
        if isinstance(params, list):              # a list of Params is taken as the tuple
            params = tuple(params)
            object.__setattr__(self, "params", params)
        if not isinstance(params, tuple) or any(not isinstance(p, Param) for p in params):
            raise TypeError(f"{type(self).__name__} {self.name!r}: params must be a tuple of Param")
        names = [p.name for p in params]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise TypeError(f"{type(self).__name__} {self.name!r}: key {twice[0]!r} is declared twice")

    def keys(self):
        """The declared keys, in order."""
        return tuple(p.name for p in self.params)

    def param(self, name):
        """The Param ``name`` (KeyError naming the closest key otherwise)."""
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(f"{self.name!r} has no key {name!r}{did_you_mean(name, self.keys())}")

    def required(self):
        """The keys that have no default."""
        return tuple(p.name for p in self.params if p.required)

    def entry(self, values):
        """The TOML table of validated ``values`` (the kind's keys only, None left out):
        what ``scenario.dumps`` writes for the kind, and reads back to the same values."""
        out = {}
        for p in self.params:
            v = values.get(p.name)
            if v is None:
                continue
            if p.kind == "table" and isinstance(v, dict):
                v = Section(p.name, p.fields).entry(v)
            out[p.name] = list(v) if isinstance(v, tuple) else v
        return out

    def table(self):
        """The Markdown table of the keys: key, value type, default, doc."""
        rows = ["| key | value | default | |", "|---|---|---|---|"]
        for p in self.params:
            rows.append(f"| `{p.name}` | {p.describe()} | {p.default_text()} | {p.doc} |")
        return "\n".join(rows)

    def summary(self, markdown=False):
        """One line: the keys (required ones first, then the optional with their defaults),
        with the section's own keys this kind reads (:meth:`selection`) in front."""
        q = (lambda k: f"`{k}`") if markdown else (lambda k: k)
        req = [q(p.name) for p in self.params if p.required]
        opt = [f"{q(p.name)} ({p.default_text()})" for p in self.params if not p.required]
        own = self.selection()
        return ", ".join(([" or ".join(map(q, own[0]))] if own and own[0] else []) + req + opt
                         + [q(k) for k in (own[1] if own else ())]) or "no keys"

    def selection(self):
        """(alternative keys the entry selects its place by, further section keys it takes),
        e.g. (("edge", "nodes"), ("scale",)) of an edge load; None: none."""
        return None


@dataclass(frozen=True)
class Section(Kind):
    """A scenario section (or a part of one) that is not an extension point: its keys, a check
    across them and a line of doc (``[output]``, ``[[probes]]``, ``[[magnets]]``, ...).

    Example
    -------
    >>> Section("output", (Param("vtu", "bool", True),)).summary()
    'vtu (true)'
    """
    params: tuple = ()
    check: object = None
    doc: str = ""
    build: object = None


_BY_KIND = {}                      # Kind subclass -> its Registry (register() looks it up)
_REGISTRIES = []


def registries():
    """Every registry made with a Kind class, in the order they were made (the contract tests
    and ``core-se3 kinds`` walk them).

    Example
    -------
    >>> import core_se3.model
    >>> "load kind" in [r.what for r in registries()]
    True
    """
    return list(_REGISTRIES)


class Registry(dict):
    """name -> entry, for the extension point ``what`` (used in messages); ``kind``: the Kind
    class of its entries (:meth:`add` and :func:`register` check it); ``key``: the selector key
    of scenario files ('type', 'generator', 'law'); ``reserved``: keys of the section that a
    kind may not declare (the selection, the scale, ...)."""

    def __init__(self, what, kind=None, key="type", reserved=()):
        super().__init__()
        self.what = what
        self.kind = kind
        self.key = key
        self.reserved = tuple(reserved)
        if kind is not None:
            _BY_KIND[kind] = self
            _REGISTRIES.append(self)

    def register(self, name, entry):
        """Add ``entry`` under ``name`` (which must be a new, non-empty string); returns it."""
        if not isinstance(name, str) or not name:
            raise TypeError(f"a {self.what} needs a non-empty name, got {name!r}")
        if name in self:
            raise ValueError(f"{self.what} {name!r} is registered twice")
        self[name] = entry
        return entry

    def add(self, kind):
        """Register a kind under its own name: TypeError for an entry that is not of this
        registry's Kind class or declares a reserved key, ValueError for a name already taken."""
        if self.kind is not None and not isinstance(kind, self.kind):
            raise TypeError(f"a {self.what} must be a {self.kind.__name__}, got {type(kind).__name__}")
        clash = [k for k in getattr(kind, "keys", lambda: ())() if k in self.reserved + (self.key,)]
        if clash:
            raise TypeError(f"{self.what} {kind.name!r}: key {clash[0]!r} is the section's own "
                            f"(reserved here: {', '.join((self.key,) + self.reserved)})")
        return self.register(kind.name, kind)

    def lookup(self, name):
        """The entry ``name``; an OptionError naming the closest registered name otherwise."""
        try:
            return self[name]
        except (KeyError, TypeError):
            raise OptionError(f"unknown {self.what} {name!r}{did_you_mean(name, self)}; registered: "
                              f"{', '.join(sorted(self))}") from None

    def table(self):
        """The Markdown table of the registered kinds: selector value, keys, doc."""
        rows = [f"| {self.key} | keys | |", "|---|---|---|"]
        for name, k in self.items():
            doc = getattr(k, "doc", "") + (f"; {k.edges}" if getattr(k, "edges", "") else "")
            rows.append(f"| `{name}` | {k.summary(markdown=True)} | {doc} |")
        return "\n".join(rows)


def register(kind):
    """Add ``kind`` to the registry of its class (a LoadKind to the loads, a SupportKind to the
    supports, ...); returns it.  The one call a plugin file needs for any extension point
    whose kinds are Kinds (elements keep their class decorator ``fem.register_element``).

    Example
    -------
    >>> from core_se3.model import LoadKind, load_kind
    >>> register(load_kind("gravity"))
    Traceback (most recent call last):
    ...
    ValueError: load kind 'gravity' is registered twice
    >>> register(Section("x"))                     # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    TypeError: Section 'x' is not a kind of an extension point (registered kind classes: ...)
    """
    for cls in type(kind).__mro__:
        if cls in _BY_KIND:
            return _BY_KIND[cls].add(kind)
    names = ", ".join(c.__name__ for c in _BY_KIND)
    raise TypeError(f"{type(kind).__name__} {getattr(kind, 'name', '')!r} is not a kind of an extension point "
                    f"(registered kind classes: {names})")

"""The design variables and targets of scenario files (``[[design.variables]] type = NAME``,
``[[design.targets]] type = NAME``): registries of :class:`VariableKind` and :class:`TargetKind`
whose Params are the kind's keys.

A kind's ``build`` receives a context ``ctx`` made by the scenario layer: ``ctx.problem``,
``ctx.regions`` (name -> element ids), ``ctx.fields`` (name -> the Field), ``ctx.loads`` (the
Load objects of each ``[[loads]]`` entry), ``ctx.pose(name)`` (the index of a pose, None for
None), ``ctx.add_regulariser(r)`` and ``ctx.index`` (the entry's position).  Keys named
``field``, ``regions``, ``pose``, ``load`` and ``probe`` refer to the scenario's names and are
checked against them before ``build`` (a did-you-mean naming the key).

A new design variable is a :class:`~core_se3.design.Variable` subclass plus one
``register_variable(VariableKind(...))``; a new target a :class:`~core_se3.design.Quantity`
plus ``register_target(TargetKind(...))``.

Example
-------
>>> sorted(VARIABLES), sorted(TARGETS)
(['field', 'load', 'magnetisation', 'material'], ['angle', 'orientation', 'position'])
>>> VARIABLES["material"].keys()
('prop', 'regions', 'lower', 'upper')
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import lie
from ..registry import Kind, Param, Registry
from .magnetisation import Parametrisation, RegionMagnetisation
from .material import MaterialVariable
from .objectives import AngleInDegrees, NodePosition, Orientation, ProbePosition
from .targets import Smoothness
from .variables import FieldVariable, LoadMagnitude

__all__ = ["VariableKind", "TargetKind", "VARIABLES", "TARGETS", "register_variable", "register_target",
           "REFERENCE_KEYS", "plane_value", "planes_value"]

# keys whose values name things of the scenario (checked by the scenario layer before build)
REFERENCE_KEYS = ("field", "regions", "pose", "load", "probe")


@dataclass(frozen=True)
class VariableKind(Kind):
    """A design variable of scenario files: ``build(ctx, values) -> Variable`` (module docstring);
    ``write(scn, doc, variable)`` puts the variable's value into the scenario document ``doc``
    (nested dicts), so that ``core-se3 design`` writes an optimised scenario that reproduces the
    design (the built-in kinds' writers are in ``scenario.design_runner``; a user kind without
    one is refused by ``core-se3 design``).

    Example
    -------
    >>> VARIABLES["field"].param("form").choices
    ('vector', 'polar')
    """
    name: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""
    write: Callable | None = None
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class TargetKind(Kind):
    """A design target of scenario files: ``build(ctx, values, where) -> Quantity`` (``where``:
    ``{"probe": name}`` or ``{"node": id}``); ``size``: the number of components of the quantity
    (``components`` picks among them); ``scale``: the default scale of its misfit (None: the
    mesh's length for positions, 1 otherwise), in the target's unit.

    Example
    -------
    >>> TARGETS["angle"].size, round(TARGETS["angle"].scale, 4)
    (1, 57.2958)
    """
    name: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""
    size: int = 3
    scale: float | None = None
    extra: dict = field(default_factory=dict)


VARIABLES = Registry("design variable kind", VariableKind)
TARGETS = Registry("design target kind", TargetKind,
                   reserved=("pose", "probe", "node", "components", "weight", "scale"))


def register_variable(kind: VariableKind):
    """Add a design variable kind (its name must be new); returns it.

    Example
    -------
    >>> register_variable(VARIABLES["load"])
    Traceback (most recent call last):
    ...
    ValueError: design variable kind 'load' is registered twice
    """
    return VARIABLES.add(kind)


def register_target(kind: TargetKind):
    """Add a design target kind (its name must be new); returns it."""
    return TARGETS.add(kind)


def plane_value(v, d, key, name="plane"):
    """A plane [e1, e2] of two non-zero 3-vectors (a Param's ``parse``)."""
    return _plane_at(v, d[name], f"{key}.{name}")


def planes_value(v, d, key):
    """One plane, or one per region (their number checked across keys)."""
    x = d["planes"]
    if not isinstance(x, list) or not x:
        v.fail(f"{key}.planes", "expected one plane [e1, e2] or one per region")
    return [_plane_at(v, p, f"{key}.planes[{j}]") for j, p in enumerate(x)]


def _plane_at(v, p, path):
    if not isinstance(p, list) or len(p) != 2:
        v.fail(path, f"expected two 3-vectors [e1, e2], got {v.shown(p)}")
    return [v.vector({"e": e}, "e", f"{path}[{i}]", nonzero=True) for i, e in enumerate(p)]


def _free_check(values, given):
    """``free`` parts of a vector (x, y, z) or polar (magnitude, angle) form."""
    fr = values.get("free")
    if fr is None:
        return None
    parts = ("x", "y", "z") if values["form"] == "vector" else ("magnitude", "angle")
    if not isinstance(fr, list) or not fr or any(x not in parts for x in fr):
        return "free", f"expected a non-empty array of {', '.join(map(repr, parts))}, got {_show(fr)}"
    return None


def _magnetisation_check(values, given):
    if len(values["planes"]) not in (1, len(values["regions"])):
        return "planes", f"expected one plane [e1, e2] or one per region ({len(values['regions'])})"
    return _free_check(values, given)


def _show(x):
    s = repr(x)
    return s if len(s) <= 60 else s[:57] + "..."


_FORM = Param("form", "string", "vector", choices=("vector", "polar"),
              doc="vector, or polar: magnitude and angle in a plane")
_FREE = Param("free", "any", None, doc='the free parts: "x", "y", "z" or "magnitude", "angle" (default all)')
_XZ = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]


def _field(ctx, v):
    return FieldVariable(ctx.problem, ctx.fields[v["field"]], v["form"], v["plane"], v.get("free"), v["B_max"],
                         ctx.pose(v["pose"]), name=v["field"])


def _magnetisation(ctx, v):
    planes = v["planes"][0] if len(v["planes"]) == 1 else v["planes"]
    mv = RegionMagnetisation(ctx.problem, {r: ctx.regions[r] for r in v["regions"]},
                             Parametrisation(v["form"], planes, v.get("free"), v["Br_max"]),
                             None if v["field"] is None else ctx.fields[v["field"]], name=f"magnetisation{ctx.index}")
    if v["smoothness"] > 0:
        ctx.add_regulariser(Smoothness(mv, v["smoothness"]))
    return mv


def _material(ctx, v):
    return MaterialVariable(ctx.problem, {r: ctx.regions[r] for r in v["regions"]}, v["prop"], v["lower"], v["upper"],
                            name=f"{v['prop']}{ctx.index}")


def _load(ctx, v):
    # every load the entry built (an edge load on a union of lines: one per line; gravity: one
    # per density and thickness) under one multiplier, as the file's entry is scaled
    return LoadMagnitude(ctx.problem, list(ctx.loads[v["load"]]), v["lower"], v["upper"], ctx.pose(v["pose"]),
                         name=f"load{v['load']}")


_REGIONS = Param("regions", "list", item="string", min_items=1, doc="region names")
_POSE = Param("pose", "string", None, doc="the pose it belongs to (default every pose)")
register_variable(VariableKind(
    "field", (Param("field", "string", doc="a [fields.NAME]"), _FORM,
              Param("plane", "any", _XZ, parse=plane_value, doc="[e1, e2] of the polar form"), _FREE,
              Param("B_max", "number", None, lo=0.0, lo_open=True, doc="bound of |B|"), _POSE),
    _field, _free_check, doc="the applied field (per pose)"))
register_variable(VariableKind(
    "magnetisation", (_REGIONS, _FORM,
                      Param("planes", "any", [_XZ], parse=planes_value, doc="one plane, or one per region"),
                      _FREE, Param("Br_max", "number", None, lo=0.0, lo_open=True, doc="bound of |Br|"),
                      Param("smoothness", "number", 0.0, lo=0.0, doc="regularisation of neighbouring regions"),
                      Param("field", "string", None, doc="the field of the magnets (default all)")),
    _magnetisation, _magnetisation_check, doc="B^r constant over each region"))
register_variable(VariableKind(
    "material", (Param("prop", "string", choices=("E", "h"), doc="the property"), _REGIONS,
                 Param("lower", "number", 0.0, doc="bound"), Param("upper", "number", math.inf, doc="bound")),
    _material, doc="E or h per region"))
register_variable(VariableKind(
    "load", (Param("load", "integer", lo=0, doc="an index of [[loads]]"), Param("lower", "number", -math.inf),
             Param("upper", "number", math.inf), _POSE),
    _load, doc="a multiplier of that load"))


def _position(ctx, v, where):
    if "probe" in where:
        return ProbePosition(ctx.problem, where["probe"], v["value"])
    return NodePosition(ctx.problem, [where["node"]], v["value"])


def _orientation(ctx, v, where):
    q = Orientation(ctx.problem, **where)       # the frame turned by the rotation vector from its reference
    q.target = lie.exp_so3(np.asarray(v["value"], float)) @ q.target
    return q


register_target(TargetKind("position", (Param("value", "vector", doc="[length]"),), _position,
                           doc="the position of a probe or node"))
register_target(TargetKind(
    "angle", (Param("value", "number", doc="[deg] about axis"),
              Param("axis", "vector", [0.0, -1.0, 0.0], nonzero=True, doc="lab axis")),
    lambda ctx, v, where: AngleInDegrees(ctx.problem, axis=v["axis"], target=v["value"], **where),
    doc="the rotation angle about a lab axis, in degrees", size=1, scale=AngleInDegrees.DEGREE))
register_target(TargetKind("orientation", (Param("value", "vector", doc="rotation vector from the reference [rad]"),),
                           _orientation, doc="the orientation of a probe or node"))

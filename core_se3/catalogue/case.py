"""Benchmark case definitions (data only) and the registries of cases and case families.

A case is a geometry, a material, supports, loads scaled by the load factor ``lam`` in [0, 1]
(or a signed range for ``curved-rollup``), the probe to record, and the reference entry of
``core_se3/data/elastica.json`` the probe is measured against.  ``fenicsx_ref`` reads the same
definitions, so that neither model can drift from the other.

Coordinates (all cases): the clamped edge is ``x0`` (the edge at the first parameter value),
the free end is ``x1``; the width runs along the global y axis, symmetric about y = 0.  Flat
strips lie in the x-y plane with normal +z.  Arches bend in the x-z plane: reference tangent
+x at the clamp, centre of curvature at (0, 0, R), tip at (0, 0, 2R).

Planar reference solutions (x-y plane of ``elastica.json``) map onto the shell as
``u -> ux``, ``v -> uz`` and ``theta ->`` rotation about -y (counter-clockwise in the x-z plane).

Units: every case is in one consistent unit system, stated in ``units``; the unit strings are
reported in results and never converted.

A new case is one :func:`add_case` call (in a module of its own, or a user's script); a new
family of cases with its own builder and runner is a :class:`Family` and one
:func:`register_family` call.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

from ..errors import OptionError, did_you_mean
from ..registry import Registry

__all__ = ["Case", "CaseLoad", "Reference", "Variant", "CASES", "add_case", "get_case", "list_cases",
           "beam_EI", "Family", "FAMILIES", "register_family", "family_of", "case_params",
           "resolve", "ResolvedLoad"]


def beam_EI(p):
    """Bending stiffness of the strip as a rod, E w h^3 / 12 (exact reduction for nu = 0)."""
    return p["E"] * p["width"] * p["h"] ** 3 / 12.0


@dataclass(frozen=True)
class CaseLoad:
    """One load of a case, scaled linearly by the load factor.

    kind: ``edge_force`` (total force distributed consistently along ``edge``),
    ``edge_moment`` (total moment along ``edge``), ``pressure`` (per unit reference area along
    ``direction`` if dead; along the current surface normal, per unit current area, if
    follower), ``edge_rotation`` (prescribed rigid rotation of ``edge`` about ``axis`` through
    ``point``, angle = magnitude * lam, translations along ``free`` axes left free), and the
    kinds a family builds itself (``point_force``, ``magnetic``).  ``direction`` is a lab
    vector for dead loads and body-frame components (d1, d2, d3) of the edge's own frame for
    follower loads.  ``magnitude(params)`` is the value at lam = 1.
    """
    kind: str
    edge: str | None
    direction: tuple
    magnitude: Callable[[dict], float]
    follower: bool = False
    axis: tuple | None = None
    point: tuple | None = None
    free: tuple = ()



@dataclass(frozen=True)
class Reference:
    """How a reference entry maps onto the case.

    ``entry``: key in elastica.json; ``block``: which tip block ('tip', 'tip_reissner', ...);
    ``load_to_ref(params, load)``: physical load value -> the entry's ``load`` axis;
    ``length(params)``: the entry's displacement unit in case units (1 for physical entries,
    L for the dimensionless master curves).
    """
    entry: str
    load_to_ref: Callable[[dict, float], float]
    length: Callable[[dict], float]
    block: str = "tip"
    note: str = ""


@dataclass(frozen=True)
class Variant:
    """A switch of the case by a parameter (on when params[param] >= 0.5): the load number
    ``load`` gets the fields ``changes`` (e.g. follower=True, direction=...), the reference
    the entry ``entry``."""
    param: str
    load: int = 0
    changes: dict = field(default_factory=dict)
    entry: str | None = None


@dataclass(frozen=True)
class Case:
    name: str
    description: str
    geometry: str                      # 'strip' | 'arch' | 'semicylinder' | a family's shape
    params: dict
    units: dict
    mesh: tuple                        # default (nx, ny)
    steps: int                         # default number of load steps
    loads: tuple
    load_name: str                     # the reported load quantity
    load_unit: str
    load_value: Callable[[dict, float], float]  # (params, lam) -> reported load value
    supports: tuple = (("clamp", "x0"),)
    reference: Reference | None = None
    probe: str = "tip"
    lam_range: tuple = (0.0, 1.0)
    notes: str = ""
    extra: dict = field(default_factory=dict)
    variants: tuple = ()


CASES = Registry("case")


def add_case(case):
    """Register a case (its name must be new); returns it."""
    if not isinstance(case, Case):
        raise TypeError("add_case needs a core_se3.catalogue.Case")
    return CASES.register(case.name, case)


def get_case(name: str) -> Case:
    """The case ``name``; a KeyError naming the closest case otherwise."""
    try:
        return CASES[name]
    except KeyError:
        raise KeyError(f"unknown case {name!r}{did_you_mean(name, CASES)}; available: "
                       f"{', '.join(sorted(CASES))}") from None


def list_cases():
    """[(name, description)] of every registered case."""
    return [(c.name, c.description) for c in CASES.values()]


def case_params(case, overrides=None):
    """The case's parameters with ``overrides`` (each must be a parameter of the case)."""
    p = dict(case.params)
    for k, v in (overrides or {}).items():
        if k not in p:
            raise KeyError(f"case {case.name!r} has no parameter {k!r}{did_you_mean(k, p)}; its keys: "
                           f"{', '.join(p)}")
        p[k] = float(v)
    return p


@dataclass(frozen=True)
class ResolvedLoad:
    """A case load with its variant switches applied and its magnitude at lam = 1 evaluated."""
    kind: str
    edge: str | None
    direction: tuple
    magnitude: float
    follower: bool
    axis: tuple | None
    point: tuple | None
    free: tuple


def resolve(case, p):
    """(resolved loads, reference) of a case at parameters p: the variants switched on by p
    applied (e.g. pressure-strip's follower=1, arch-follower's direction=1)."""
    loads = [ResolvedLoad(ld.kind, ld.edge, tuple(ld.direction), float(ld.magnitude(p)), bool(ld.follower),
                          ld.axis, ld.point, tuple(ld.free)) for ld in case.loads]
    ref = case.reference
    for var in case.variants:
        if p.get(var.param, 0.0) >= 0.5:
            loads[var.load] = replace(loads[var.load], **var.changes)
            if var.entry is not None and ref is not None:
                ref = replace(ref, entry=var.entry)
    return loads, ref


@dataclass
class Family:
    """How to run the cases of one family (``case.extra["family"]``) that the generic strip/arch
    runner does not cover: each hook takes the generic one's arguments.

    build(case, p, mesh, element, linear_solver) -> Problem
    run(case, p, prob, steps, **solve_kw) -> (doc, Result)             (doc: result schema)
    plot(case, p, doc, res, path) -> None                               (optional)
    report(doc) -> list of extra lines for the CLI                      (optional)
    """
    build: Callable
    run: Callable
    plot: Callable | None = None
    report: Callable | None = None


FAMILIES = Registry("case family")


def register_family(name, family):
    """Register the runner of a case family."""
    return FAMILIES.register(name, family)


def family_of(case):
    """The Family of a case, or None for the generic cases."""
    name = case.extra.get("family")
    if name is None:
        return None
    if name not in FAMILIES:
        raise OptionError(f"case {case.name!r} belongs to the unregistered family {name!r}")
    return FAMILIES[name]

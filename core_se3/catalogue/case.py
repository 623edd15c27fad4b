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
reported in results and never converted (a table in physical units carries over to the same
case in other units by similarity: ``cases_shells.similarity``).

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
    """Bending stiffness of the strip as a rod, E w h^3 / 12 (exact reduction for nu = 0).

    Parameters
    ----------
    p : dict
        Case parameters with E [force/length^2], width and h [length].

    Returns
    -------
    float
        EI [force x length^2].

    Example
    -------
    >>> round(beam_EI({"E": 1.2e6, "width": 1.0, "h": 0.1}), 9)
    100.0
    """
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

    Attributes
    ----------
    kind : str
        As above; ``edge``: the node set (None for pressure).
    direction : tuple
        Unit direction (lab or body components).
    magnitude : callable
        params -> the magnitude at lam = 1 [the case's force, moment, pressure or rad unit].
    follower : bool
        Body-fixed direction; ``axis``, ``point``, ``free``: of an ``edge_rotation``.

    Example
    -------
    >>> ld = get_case("cantilever-shear").loads[0]
    >>> ld.kind, ld.edge, ld.direction, ld.magnitude(get_case("cantilever-shear").params)
    ('edge_force', 'x1', (0.0, 0.0, 1.0), 4.0)
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
    L for the dimensionless master curves).  ``note``: a remark for reports; ``applies``: the
    check that the entry holds at the case's parameters (see the attribute).

    Example
    -------
    The cantilever's entry is the master curve in P L^2 / EI (EI = 100, L = 10) and u / L:

    >>> case = get_case("cantilever-shear")
    >>> ref = case.reference
    >>> ref.entry, ref.block, round(ref.load_to_ref(case.params, 4.0), 12), ref.length(case.params)
    ('1_cantilever_tip_force_kirchhoff', 'tip', 4.0, 10.0)
    """
    entry: str
    load_to_ref: Callable[[dict, float], float]
    length: Callable[[dict], float]
    block: str = "tip"
    note: str = ""
    #: (case parameters, the entry's ``params``) -> "" when the entry applies to these
    #: parameters, else why not (a table computed for other parameters must not be compared
    #: against: ``reference_for`` then returns None); None: it always applies
    applies: Callable[[dict, dict], str] | None = None


@dataclass(frozen=True)
class Variant:
    """A switch of the case by a parameter (on when params[param] >= 0.5): the load number
    ``load`` gets the fields ``changes`` (e.g. follower=True, direction=...), the reference
    the entry ``entry``.

    Attributes: param (str), load (int, index into ``Case.loads``), changes (dict of CaseLoad
    fields), entry (str or None: keep the case's reference entry).

    Example
    -------
    >>> get_case("pressure-strip").variants[0]
    Variant(param='follower', load=0, changes={'follower': True}, entry='5_plate_cylindrical_bending_pressure_follower')
    """
    param: str
    load: int = 0
    changes: dict = field(default_factory=dict)
    entry: str | None = None


@dataclass(frozen=True)
class Case:
    """A benchmark case of the catalogue (data only; module docstring for the conventions).

    Attributes
    ----------
    name, description : str
        The registry key (``core-se3 bench run NAME``) and one line for listings.
    geometry : str
        'strip', 'arch', 'semicylinder' or a family's shape.
    params : dict
        Default parameters (``--set key=value`` overrides them); ``units``: key -> unit string.
    mesh : (int, int)
        Default (nx, ny); ``steps``: default number of load steps.
    loads : tuple of CaseLoad
        The loads at lam = 1; ``supports``: ((kind, where), ...), default a clamp at x0.
    load_name, load_unit : str
        The reported load; ``load_value(params, lam)``: its value.
    reference : Reference or None
        The reference entry; ``probe``: the recorded probe; ``lam_range``: (start, end).
    notes, extra, variants
        Free text, family data (``extra["family"]``), Variant switches.

    Example
    -------
    >>> c = get_case("cantilever-shear")
    >>> c.geometry, c.mesh, c.steps, c.load_name, c.load_value(c.params, 0.5)
    ('strip', (16, 1), 10, 'P', 2.0)
    """
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
    """Register a case (its name must be new); returns it.

    Parameters: case (Case).  Returns: case; TypeError for anything else, ValueError for a
    name that is already registered.

    Example
    -------
    >>> add_case(get_case("rollup"))
    Traceback (most recent call last):
    ...
    ValueError: case 'rollup' is registered twice
    """
    if not isinstance(case, Case):
        raise TypeError("add_case needs a core_se3.catalogue.Case")
    return CASES.register(case.name, case)


def get_case(name: str) -> Case:
    """The case ``name``; a KeyError naming the closest case otherwise.

    Parameters: name (str).  Returns: Case.

    Example
    -------
    >>> get_case("rollup").reference.entry
    '2_pure_bending_rollup_out_of_plane'
    >>> get_case("rolup")                        # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    KeyError: "unknown case 'rolup'; did you mean 'rollup'?; available: ..."
    """
    try:
        return CASES[name]
    except KeyError:
        raise KeyError(f"unknown case {name!r}{did_you_mean(name, CASES)}; available: "
                       f"{', '.join(sorted(CASES))}") from None


def list_cases():
    """[(name, description)] of every registered case.

    Returns: list of (str, str), in registration order.

    Example
    -------
    >>> ("rollup", get_case("rollup").description) in list_cases()
    True
    """
    return [(c.name, c.description) for c in CASES.values()]


def case_params(case, overrides=None):
    """The case's parameters with ``overrides`` (each must be a parameter of the case).

    Parameters
    ----------
    case : Case
        The case.
    overrides : dict, optional
        key -> value (converted to float); an unknown key is a KeyError naming the closest.

    Returns
    -------
    dict

    Example
    -------
    >>> case_params(get_case("cantilever-shear"), {"load_max": 2})["load_max"]
    2.0
    >>> case_params(get_case("cantilever-shear"), {"Lenght": 2})
    Traceback (most recent call last):
    ...
    KeyError: "case 'cantilever-shear' has no parameter 'Lenght'; its keys: E, nu, h, L, width, load_max"
    """
    p = dict(case.params)
    for k, v in (overrides or {}).items():
        if k not in p:
            raise KeyError(f"case {case.name!r} has no parameter {k!r}{did_you_mean(k, p)}; its keys: "
                           f"{', '.join(p)}")
        p[k] = float(v)
    return p


@dataclass(frozen=True)
class ResolvedLoad:
    """A case load with its variant switches applied and its magnitude at lam = 1 evaluated.

    Attributes: those of :class:`CaseLoad`, with ``magnitude`` a float.

    Example
    -------
    >>> case = get_case("pressure-strip")
    >>> ld = resolve(case, case_params(case, {"follower": 1}))[0][0]
    >>> ld.kind, ld.follower, round(ld.magnitude, 9)
    ('pressure', True, 20.0)
    """
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
    applied (e.g. pressure-strip's follower=1, arch-follower's direction=1).

    Parameters
    ----------
    case : Case
        The case; ``p``: its parameters (:func:`case_params`).

    Returns
    -------
    (list of ResolvedLoad, Reference or None)

    Example
    -------
    >>> case = get_case("pressure-strip")
    >>> [resolve(case, case_params(case, {"follower": f}))[1].entry for f in (0, 1)]
    ['5_plate_cylindrical_bending_pressure_dead', '5_plate_cylindrical_bending_pressure_follower']
    """
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

    Example
    -------
    >>> fam = FAMILIES["sze"]
    >>> callable(fam.build), callable(fam.run), family_of(get_case("sze-hinged-roof")) is fam
    (True, True, True)
    """
    build: Callable
    run: Callable
    plot: Callable | None = None
    report: Callable | None = None


FAMILIES = Registry("case family")


def register_family(name, family):
    """Register the runner of a case family.

    Parameters: name (str, the value of ``case.extra["family"]``), family (Family).  Returns:
    family; ValueError for a name that is already registered.

    Example
    -------
    >>> register_family("sze", FAMILIES["sze"])
    Traceback (most recent call last):
    ...
    ValueError: case family 'sze' is registered twice
    """
    return FAMILIES.register(name, family)


def family_of(case):
    """The Family of a case, or None for the generic cases.

    Parameters: case (Case).  Returns: Family or None; OptionError for an unregistered family.

    Example
    -------
    >>> family_of(get_case("rollup")) is None, family_of(get_case("magnetic-plate")) is FAMILIES["magnetic"]
    (True, True)
    """
    name = case.extra.get("family")
    if name is None:
        return None
    if name not in FAMILIES:
        raise OptionError(f"case {case.name!r} belongs to the unregistered family {name!r}")
    return FAMILIES[name]

"""The material laws of scenario files (``[material] law = NAME``, default ``"isotropic"``): a
registry of :class:`MaterialKind` whose Params are the law's keys.  A new law is an object with
``resultant_matrix(A1, A2) -> (Dmat, j0)`` (``fem.ResultantLaw``) and a thickness ``h`` (the
contact offset, gravity and magnetisation read it), plus one ``register_material(MaterialKind(...))``.

Example
-------
>>> sorted(MATERIALS), material_kind("isotropic").required()
(['isotropic'], ('E', 'nu', 'h'))
>>> material_kind("isotropic").build(dict(E=1e3, nu=0.0, h=0.1, shear_factor=1.0, drilling=1.0, rho=None)).D
0.08333333333333336
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ..registry import Kind, Param, Registry
from .material import SHEAR_STABILISATION_FLOOR, STIFFNESS_RANGE, Material, stiffness_range_error

__all__ = ["MaterialKind", "MATERIALS", "register_material", "material_kind", "ISOTROPIC"]


@dataclass(frozen=True)
class MaterialKind(Kind):
    """A material law of scenario files.

    build(values) -> law: the law (``fem.ResultantLaw`` with a thickness ``h``) of the values of
    its ``params``; a region of ``[material.regions.NAME]`` gives the same keys, its defaults
    the base ones.  ``inert``: keys that do not change the stiffness (the density): regions
    that differ only in them keep any element.

    Attributes
    ----------
    name : str
        ``[material] law = name``.
    params : tuple of Param
        Its keys.
    build, check, doc, inert
        As above.

    Example
    -------
    >>> material_kind("isotropic").inert
    ('rho',)
    """
    name: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""
    inert: tuple = ()
    extra: dict = field(default_factory=dict)


MATERIALS = Registry("material law", MaterialKind, key="law", reserved=("regions",))


def register_material(kind: MaterialKind):
    """Add a material law (its name must be new); returns it.

    Example
    -------
    >>> register_material(material_kind("isotropic"))
    Traceback (most recent call last):
    ...
    ValueError: material law 'isotropic' is registered twice
    """
    return MATERIALS.add(kind)


def material_kind(name) -> MaterialKind:
    """The registered law ``name``; an OptionError naming the closest one otherwise.

    Example
    -------
    >>> material_kind("isotropc")                # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown material law 'isotropc'; did you mean 'isotropic'?; registered: ...
    """
    return MATERIALS.lookup(name)


def _stiffness_check(v):
    """(key, message) of an E and h whose stiffness double precision cannot solve, or None."""
    msg = stiffness_range_error(v["E"], v["h"])
    lo, hi = STIFFNESS_RANGE
    return None if msg is None else ("h" if lo <= v["E"] <= hi else "E", msg)


ISOTROPIC = register_material(MaterialKind("isotropic", (
    Param("E", "number", lo=0.0, lo_open=True, doc="Young's modulus, > 0"),
    Param("nu", "number", lo=-1.0, lo_open=True, hi=0.5, hi_open=True, doc="Poisson's ratio, in (-1, 0.5)"),
    Param("h", "number", lo=0.0, lo_open=True, doc="thickness, > 0"),
    Param("shear_factor", "number", 1.0, lo=0.0, lo_open=True, doc="transverse shear factor, > 0"),
    Param("drilling", "number", 1.0, lo=0.0, doc="factor on the drilling modulus D(1 - nu), >= 0"),
    Param("rho", "number", None, lo=0.0, doc="density (for gravity), >= 0"),
    Param("shear_stabilisation", "number", 0.0, lo=0.0,
          doc="alpha of Lyly-Stenberg-Vihinen's shear stabilisation, >= 0 (0: off; Kratos' thick quad: 0.1)"),
    Param("shear_stabilisation_floor", "number", SHEAR_STABILISATION_FLOOR, lo=0.0, hi=1.0,
          doc="floor c of the stabilisation's factor, in [0, 1] (0: Lyly-Stenberg-Vihinen's and Kratos' own)")),
    lambda v: Material(v["E"], v["nu"], v["h"], v["shear_factor"], v["drilling"], v["rho"],
                       shear_stabilisation=v.get("shear_stabilisation", 0.0),
                       shear_stabilisation_floor=v.get("shear_stabilisation_floor", SHEAR_STABILISATION_FLOOR)),
    lambda v, given: _stiffness_check(v),
    doc="the isotropic resultant law of the seed (fem.Material)", inert=("rho",)))

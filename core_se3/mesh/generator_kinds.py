"""The mesh generators of scenario files (``[mesh] generator = NAME``): a registry of
:class:`GeneratorKind` whose Params are the generator's keys.  A new generator is a function
returning a :class:`~core_se3.mesh.Mesh` plus one ``register_generator(GeneratorKind(...))``.

Example
-------
>>> sorted(GENERATORS)[:3], generator_kind("rectangle").keys()
(['annulus', 'annulus_sector', 'cylinder_arch'], ('L', 'width', 'nx', 'ny', 'x0', 'grade'))
>>> generator_kind("rectangle").build(L=1.0, width=1.0, nx=2, ny=1).n_elements
2
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ..registry import REQUIRED, Kind, Param, Registry
from .generators import GRADE_EDGES, annulus, cylinder_arch, cylinder_panel, hemisphere_quarter, rectangle
from .shapes import BACKENDS, annulus_sector, disk, polygon, rounded_rectangle, star

__all__ = ["GeneratorKind", "GENERATORS", "register_generator", "generator_kind"]


@dataclass(frozen=True)
class GeneratorKind(Kind):
    """A mesh generator of scenario files.

    build(**values) -> Mesh makes the mesh from the values of its ``params`` (optional keys the
    file leaves out are not passed: the function's own default applies, and the Param's default
    documents it; a ``backend`` is always passed).  ``counts``: the two
    integer keys whose product is the element count, ``extent``: the length keys whose largest
    over ``size`` estimates it (the scenario refuses more than its limit of elements; both may
    be empty); ``edges``: the named node sets and regions it makes, for the docs.

    Attributes
    ----------
    name : str
        ``[mesh] generator = name``.
    params : tuple of Param
        Its keys.
    build, check, doc, edges, counts, extent
        As above.

    Example
    -------
    >>> generator_kind("star").counts, generator_kind("star").extent
    ((), ('arm_length', 'arm_width'))
    """
    name: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""
    edges: str = ""
    counts: tuple = ()
    extent: tuple = ()
    extra: dict = field(default_factory=dict)


GENERATORS = Registry("mesh generator", GeneratorKind, key="generator")


def register_generator(kind: GeneratorKind):
    """Add a mesh generator (its name must be new); returns it.

    Example
    -------
    >>> register_generator(generator_kind("disk"))
    Traceback (most recent call last):
    ...
    ValueError: mesh generator 'disk' is registered twice
    """
    return GENERATORS.add(kind)


def generator_kind(name) -> GeneratorKind:
    """The registered generator ``name``; an OptionError naming the closest one otherwise.

    Example
    -------
    >>> generator_kind("rectangel")                # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown mesh generator 'rectangel'; did you mean 'rectangle'?; registered: ...
    """
    return GENERATORS.lookup(name)


def _pos(name, doc="", default=REQUIRED):
    return Param(name, "number", default, lo=0.0, lo_open=True, doc=doc)


def _count(name, doc=""):
    return Param(name, "integer", lo=1, hi=100_000, doc=doc)


def _real(name, doc="", default=REQUIRED):
    return Param(name, "number", default, doc=doc)


_SIZE = _pos("size", "target element size [length]")
_GRADE = Param("grade", "table", None,
               fields=tuple(Param(e, "number", None, lo=0.0, hi=1.0, lo_open=True, hi_open=True,
                                  doc=f"fraction of the side spanned by the elements along `{e}`")
                            for e in GRADE_EDGES),
               doc="elements narrower toward named edges, e.g. {x1 = 0.05}: the elements along x1 span 5 % of "
                   "the side, the others growing geometrically (resolves free-edge layers; docs/ELEMENTS.md)")
_BACKEND = Param("backend", "string", "auto", choices=BACKENDS,
                 doc="structured, gmsh (needs gmsh) or auto (Gmsh where installed)")

register_generator(GeneratorKind(
    "rectangle", (_pos("L", "length along x"), _pos("width", "along y"), _count("nx"), _count("ny"),
                  _real("x0", "start of the strip along x", 0.0), _GRADE),
    rectangle, doc="a flat L x width strip in the x-y plane", edges="`x0`, `x1` (ends), `y0`, `y1` (sides)",
    counts=("nx", "ny")))
register_generator(GeneratorKind(
    "cylinder_arch", (_pos("R", "radius"), _pos("angle", "opening [rad]"), _pos("width"), _count("nx"), _count("ny"), _GRADE),
    cylinder_arch, doc="a circular arch of radius R", edges="as rectangle, along the arc", counts=("nx", "ny")))
register_generator(GeneratorKind(
    "cylinder_panel", (_pos("R", "radius"), _pos("length"), _real("theta0", "[rad]"), _real("theta1", "[rad]"),
                       _count("nt"), _count("nl"), _GRADE),
    cylinder_panel, doc="a cylindrical panel", edges="`x0`/`x1` at theta0/theta1, `y0`/`y1` at s = 0/length",
    counts=("nt", "nl")))
register_generator(GeneratorKind(
    "annulus", (_pos("r_in"), _pos("r_out"), _pos("angle", "[rad]"), _count("nr"), _count("nt"), _GRADE),
    annulus, doc="a flat annular sector", edges="`x0` inner, `x1` outer, `y0`/`y1` the radial edges",
    counts=("nr", "nt")))
register_generator(GeneratorKind(
    "hemisphere_quarter", (_pos("R", "radius"), _pos("hole_deg", "half-angle of the polar hole, in (0, 90) [deg]"),
                           _count("nt"), _count("nf"), _GRADE),
    hemisphere_quarter, doc="a quarter hemisphere with a polar hole (d3 the outward normal)",
    edges="`x0` the hole, `x1` the equator, `y0`/`y1` on the planes y = 0 / x = 0", counts=("nt", "nf")))
# outlines of soft robots (mesh/shapes.py): element size and backend instead of counts
register_generator(GeneratorKind(
    "star", (Param("n_arms", "integer", lo=3, hi=64, doc=">= 3"), _pos("arm_length"), _pos("arm_width"),
             _pos("palm", "circumradius of the palm polygon (default: side = arm width)", None),
             _real("angle0", "0: arm 0 along +x", 0.0), _SIZE, _BACKEND),
    star, doc="a star-shaped gripper", edges="regions `palm`, `finger_0` ..., `fingers`; node sets `tip_0` ..., `tips`",
    extent=("arm_length", "arm_width")))
register_generator(GeneratorKind(
    "polygon", (Param("n_sides", "integer", lo=3, hi=64), _pos("radius", "circumradius"), _real("angle0", "", 0.0),
                _SIZE, _BACKEND),
    polygon, doc="a regular polygon", edges="region `polygon`; node sets `side_0` ..., `boundary`", extent=("radius",)))
register_generator(GeneratorKind(
    "rounded_rectangle", (_pos("length"), _pos("width"), _real("radius", "corners, 0: sharp", 0.0), _SIZE, _BACKEND),
    rounded_rectangle, doc="a rectangle with rounded corners",
    edges="region `plate`; node sets `x0`, `x1`, `y0`, `y1` (straight parts), `boundary`", extent=("length", "width")))
register_generator(GeneratorKind(
    "disk", (_pos("radius"), _SIZE, _BACKEND), disk, doc="a disk", edges="region `disk`; node set `rim`",
    extent=("radius",)))
register_generator(GeneratorKind(
    "annulus_sector", (_pos("r_in"), _pos("r_out"), _pos("angle", "< 2 pi [rad]"), _real("theta0", "", 0.0), _SIZE,
                       _BACKEND),
    annulus_sector, doc="an annular sector", edges="region `sector`; node sets `inner`, `outer`, `start`, `end`",
    extent=("r_in", "r_out", "angle")))

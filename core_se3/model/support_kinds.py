"""The support kinds of scenario files (``[[supports]] type = NAME``): a registry of
:class:`SupportKind` whose Params are the kind's keys.  Every entry selects its nodes by
``edge``, ``nodes`` or ``region``; a kind that moves its nodes with the load factor
(``moves``) also takes ``scale``.  A new support is a function that adds it to a Problem (with
``Problem.clamp``, ``fix``, ``prescribe``, ``move_edge`` or a penalty load) plus one
``register_support(SupportKind(...))``.

Example
-------
>>> sorted(SUPPORTS), support_kind("fix").keys(), support_kind("rotate").moves
(['clamp', 'fix', 'lab', 'lab_rotation', 'prescribed', 'rotate'], ('dofs',), True)
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..registry import Kind, Param, Registry

__all__ = ["SupportKind", "SUPPORTS", "register_support", "support_kind", "AXES", "support_stiffness"]

AXES = {"x": 0, "y": 1, "z": 2}


@dataclass(frozen=True)
class SupportKind(Kind):
    """A support of scenario files.

    build(problem, nodes, scale, **values) adds the support on the node ids ``nodes`` to the
    problem (``scale``: the load-factor programme of a kind that ``moves``, else None).
    ``moves``: the kind moves its nodes with the load factor (a prescribed motion: arc length
    refuses it, and the entry takes ``scale``).

    Attributes
    ----------
    name : str
        ``[[supports]] type = name``.
    params : tuple of Param
        Its keys besides the selection (and ``scale``).
    build, check, doc, moves
        As above.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> support_kind("fix").build(p, p.nodes("x0"), None, dofs=[0, 1, 2])
    >>> p.supports[0].fixed.tolist()
    [True, True, True, False, False, False]
    """
    name: str
    params: tuple
    build: Callable
    check: Callable | None = None
    doc: str = ""
    moves: bool = False
    extra: dict = field(default_factory=dict)

    def selection(self):
        return ("edge", "nodes", "region"), (("scale",) if self.moves else ())


SUPPORTS = Registry("support kind", SupportKind, reserved=("edge", "nodes", "region", "scale"))


def register_support(kind: SupportKind):
    """Add a support kind (its name must be new); returns it.

    Example
    -------
    >>> register_support(support_kind("clamp"))
    Traceback (most recent call last):
    ...
    ValueError: support kind 'clamp' is registered twice
    """
    return SUPPORTS.add(kind)


def support_kind(name) -> SupportKind:
    """The registered support kind ``name``; an OptionError naming the closest one otherwise.

    Example
    -------
    >>> support_kind("clmap")                # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: unknown support kind 'clmap'; did you mean 'clamp'?; registered: ...
    """
    return SUPPORTS.lookup(name)


def _rotate(problem, nodes, scale, axis, angle, point, free):
    point = point if point is not None else problem.mesh.X[nodes].mean(0)
    problem.rotate_edge(nodes, axis, angle, point=point, free=[AXES[a] for a in free], scale=scale)


def _prescribed(problem, nodes, scale, translate, rotate, free):
    rot = rotate or dict(axis=None, angle=0.0, point=None)
    problem.move_edge(nodes, translate, rot["axis"], rot["angle"], rot["point"], free=[AXES[a] for a in free],
                      scale=scale)


def _prescribed_check(values, given):
    if "translate" not in given and "rotate" not in given:
        return "", "a prescribed support needs 'translate' = [dx, dy, dz] and/or 'rotate' = {axis, angle, point}"
    return None


_FREE = Param("free", "list", [], item="string", choices=tuple(AXES), unique="error",
              doc='distinct lab axes "x", "y", "z"')
register_support(SupportKind("clamp", (), lambda problem, nodes, scale: problem.clamp(nodes),
                             doc="position and rotation held at their reference values"))
register_support(SupportKind(
    "fix", (Param("dofs", "list", item="integer", lo=0, hi=5, min_items=1, unique="error",
                  doc="dof numbers 0..5 (0-2 translations along d1..d3, 3-5 rotations)"),),
    lambda problem, nodes, scale, dofs: problem.fix(nodes, dofs),
    doc="body-frame dofs held: 0-2 translations along d1, d2, d3, 3-5 rotations"))
register_support(SupportKind(
    "rotate", (Param("axis", "vector", nonzero=True, doc="lab axis of the rotation"),
               Param("angle", "number", doc="[rad] at scale 1"),
               Param("point", "vector", None, doc="on the axis (default the nodes' centroid)"), _FREE),
    _rotate, doc="rigid rotation by angle * scale(lam) about `axis` through `point`; `free`: lab axes along which "
                 "the nodes may still translate", moves=True))
register_support(SupportKind(
    "prescribed", (Param("translate", "vector", [0.0, 0.0, 0.0], doc="[length] at scale 1"),
                   Param("rotate", "table", None, doc="axis, angle [rad], point (default the centroid)",
                         fields=(Param("axis", "vector", nonzero=True), Param("angle", "number"),
                                 Param("point", "vector", None))), _FREE),
    _prescribed, _prescribed_check,
    doc="rigid motion: at load factor lam, with s = scale(lam), x -> p + Q(s angle)(x - p) + s translate (lifting "
        "an end, pushing a foot; Python: `Problem.move_edge`)", moves=True))


# Lab-frame supports by penalty (model.supports.LabSpring, RotationComponentSpring): exact for
# nodes that turn about any axis, unlike ``fix``, which holds the body-frame components of each
# increment (docs/SCENARIOS.md, errors.SupportWarning).  Their stiffness is ``penalty`` times the
# element's own scale -- E h [force/length] for translations, E h^3 [force length/rad^2] for the
# rotation component -- so that one dimensionless default fits every unit system; the
# constraint's error is about the reaction over that stiffness (1e-6 of a reaction / (E h) at the
# default), well below the step table's 1e-6 of the path.
PENALTY_DEFAULT = 1e6
_PENALTY = Param("penalty", "number", PENALTY_DEFAULT, lo=0.0, lo_open=True,
                 doc="stiffness / (E h) (translations) or / (E h^3) (rotations), dimensionless")


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def support_stiffness(problem, nodes, power):
    """E h^power of the material at the supported nodes: the largest over the elements around
    them (with [material.regions] of different E or h the law has no single E: a lab support
    failed with 'E differs between regions; use per_element('E')').

    Example
    -------
    >>> from core_se3 import Problem, Material, RegionMaterial, mesh
    >>> law = RegionMaterial.from_regions(2, Material(1e3, 0.0, 0.1), {(1,): Material(2e3, 0.0, 0.1)})
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), law)
    >>> support_stiffness(p, p.nodes("x0"), 1), support_stiffness(p, p.nodes("x1"), 1)
    (100.0, 200.0)
    """
    per = getattr(problem.material, "per_element", None)
    if per is None:
        return float(problem.material.E * problem.material.h ** power)
    around = np.isin(problem.mesh.quads, nodes).any(1)
    E, h = np.asarray(per("E"), float)[around], np.asarray(per("h"), float)[around]
    return float(np.max(E * h ** power))


def _lab(problem, nodes, scale, direction, penalty):
    problem.add_lab_support(nodes, [_unit(direction)], penalty * support_stiffness(problem, nodes, 1))


def _lab_rotation(problem, nodes, scale, axis, penalty):
    problem.add_rotation_component_support(nodes, _unit(axis), penalty * support_stiffness(problem, nodes, 3))


register_support(SupportKind(
    "lab", (Param("direction", "vector", nonzero=True, doc="lab direction of the held displacement component"),
            _PENALTY), _lab, extra=dict(example=dict(direction=[0.0, 0.0, 1.0])),
    doc="the lab displacement component along `direction` held at zero by penalty springs of stiffness penalty * "
        "E h (a roller; exact however the nodes turn; Python: `Problem.add_lab_support`)"))
register_support(SupportKind(
    "lab_rotation", (Param("axis", "vector", nonzero=True, doc="lab axis of the held rotation component"),
                     _PENALTY), _lab_rotation, extra=dict(example=dict(axis=[0.0, 1.0, 0.0])),
    doc="the component along `axis` of the total rotation vector log(R R0^T) held at zero by a penalty penalty * "
        "E h^3 (a holonomic theta_y = 0, total rotation below pi; Python: `Problem.add_rotation_component_support`)"))

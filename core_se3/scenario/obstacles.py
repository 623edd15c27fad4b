"""Scenario section [[obstacles]]: rigid obstacles the shell may touch (frictionless contact,
``model.contact``).  Each entry: ``type`` (a key of ``core_se3.model.OBSTACLES``) with the kind's
parameters (read from the registry, so a new kind needs no code here), ``name``, the contact
elements ``region`` (default all), an optional rigid ``motion`` with the load factor (a table:
``translate``, ``axis``, ``angle``, ``point``, ``scale``) and the enforcement (``mode``, ``beta``,
``eps``, ``tol``, ``cap_depth``, ``side``, ``faces``) and Coulomb's ``friction`` coefficient (default 0).  Schema and examples: docs/SCENARIOS.md."""
from __future__ import annotations

from ..errors import CoreSE3Error
from ..model import OBSTACLES, ContactLaw
from ..model.contact import SIDES
from ..model.contact_output import field_key, field_key_clash
from .geometry import region_ref
from .schema import MOTION, OBSTACLE
from .validate import join, make_scale, user_key

__all__ = ["OBSTACLE_KEYS", "MOTION_KEYS", "SIDES", "obstacles_section", "add_obstacles", "obstacles_of"]

OBSTACLE_KEYS = ("type",) + OBSTACLE.keys()
MOTION_KEYS = MOTION.keys()


def obstacles_section(v, doc, regions):
    """The validated [[obstacles]] entries (a list of dicts, defaults filled in)."""
    out, names = [], set()
    for i, t in enumerate(v.array_of_tables(doc, "obstacles")):
        key = f"obstacles[{i}]"
        typ = v.string(t, "type", key, choices=tuple(OBSTACLES))
        kind = OBSTACLES[typ]
        v.table(t, key, ("type",) + OBSTACLE.keys() + kind.keys())
        o = dict(type=typ, name=v.string(t, "name", key, default=typ))
        if o["name"] in names:
            v.fail(join(key, "name"), f"obstacle names must be unique: {o['name']!r} is used twice (give 'name')")
        same = field_key_clash(sorted(names), o["name"])       # the check of Problem.add_obstacle
        if same is not None:
            v.fail(join(key, "name"), f"obstacles {same!r} and {o['name']!r} have one VTU field name, "
                                      f"contact_gap_{field_key(o['name'])} (the output sums the two): name them "
                                      "apart in letters and digits")
        names.add(o["name"])
        o["params"] = v.params(t, key, kind.params)
        v.kind_check(kind, o["params"], t, key)
        _, o["region"] = region_ref(v, t, key, regions)
        for k in ("mode", "beta", "eps", "tol", "cap_depth", "side", "friction", "faces"):
            o[k] = v.param(t, key, OBSTACLE.param(k))
        if o["faces"] not in ("auto", True, False) or isinstance(o["faces"], (int, float)) and \
                not isinstance(o["faces"], bool):
            v.fail(join(key, "faces"), f'expected true, false or "auto", got {o["faces"]!r}')
        o["motion"] = None
        if "motion" in t:
            mk = join(key, "motion")
            m = v.table(t["motion"], mk, MOTION.keys())
            if "translate" not in m and "axis" not in m:
                v.fail(mk, "a motion needs 'translate' (a vector [length] at load factor 1) and/or 'axis' "
                           "with 'angle' [rad] (and 'point')")
            o["motion"] = {p.name: v.param(m, mk, p) for p in MOTION.params if p.name != "scale"}
            o["motion"]["scale"] = v.scale(m, mk)
            if o["motion"]["axis"] is not None and "angle" not in m:
                v.fail(join(mk, "angle"), "a rotation 'axis' needs its 'angle' [rad] at load factor 1")
            if o["motion"]["axis"] is None and "angle" in m:
                v.fail(join(mk, "axis"), "an 'angle' needs its rotation 'axis' (and 'point' on it): without "
                                         "one the obstacle would not turn")
        out.append(o)
    return out


def add_obstacles(v, prob, spec, regions):
    """Add the validated obstacles to the Problem; a failure of the core's checks (e.g. an
    obstacle that already intersects the undeformed shell) is a ScenarioError keyed to it."""
    for i, o in enumerate(spec.get("obstacles", [])):
        key = f"obstacles[{i}]"
        motion = None
        if o["motion"] is not None:
            m = dict(o["motion"])
            motion = dict(translate=m["translate"], axis=m["axis"], angle=m["angle"], point=m["point"],
                          scale=make_scale(m["scale"]))
        try:
            law = ContactLaw(mode=o["mode"], beta=o["beta"], eps=o["eps"], tol=o["tol"], cap_depth=o["cap_depth"],
                             faces=o.get("faces", "auto"))
            prob.add_obstacle(o["type"], region=regions[o["region"]] if o["region"] else None, motion=motion,
                              name=o["name"], side=SIDES[o["side"]], friction=o["friction"], law=law,
                              **o["params"])
        except CoreSE3Error as exc:
            param = getattr(exc, "param", None)
            if param in ("nodes", "beta", "eps", "tol", "cap_depth", "side", "mode", "type", "friction", "faces"):
                param = None if param == "nodes" else param
            v.fail(join(key, param) if param else key, str(exc))
        except ValueError as exc:               # a user's kind refusing its values
            v.fail(user_key(key, OBSTACLES[o["type"]], exc), f"{o['type']}: {exc}")


def obstacles_of(prob):
    """The rigid obstacles of the problem's contact loads (for pictures and VTU files).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
    >>> _ = p.add_obstacle("sphere", centre=(0.5, 0.0, 0.5), radius=0.4, name="ball")
    >>> [ob.name for ob in obstacles_of(p)]
    ['ball']
    """
    return [ld.obstacle for ld in prob.loads if getattr(ld, "constraint_force", False) and hasattr(ld, "obstacle")]

"""The [design] section of scenario files (issue 15): the design variables, poses and targets of
an inverse problem on the scenario's shell, validated with errors naming the file and the key,
and built into a :class:`core_se3.design.Design`.

    [design]
    method = "least_squares"        # or "L-BFGS-B", "SLSQP", "trust-constr"
    max_iter = 50
    tolerance = 0.02                # largest misfit that counts as reaching the targets
    stop_at_tolerance = false       # stop at the first iteration within the tolerance

    [[design.poses]]                # optional (default: one pose "design")
    name = "grasp"
    fields = { coil = [0.0, 0.0, 0.0] }     # fields held at a value in this pose

    [[design.variables]]
    type = "field"                  # field | magnetisation | material | load
    field = "coil"                  # a [fields.NAME]
    form = "polar"                  # vector | polar (magnitude and angle in plane = [e1, e2])
    plane = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    free = ["magnitude", "angle"]
    B_max = 0.08
    pose = "grasp"                  # the pose it belongs to (default: every pose)

    [[design.variables]]
    type = "magnetisation"
    regions = ["seg1", "seg2"]      # B^r constant over each (what can be fabricated)
    form = "polar"
    planes = [[[1, 0, 0], [0, 0, 1]]]        # one plane, or one per region
    free = ["angle"]
    smoothness = 0.0                # regularisation of neighbouring regions

    [[design.targets]]
    pose = "grasp"
    type = "position"               # position | angle | orientation
    probe = "tip_px"                # or node = ID
    value = [18.0, 0.0, 10.0]       # position [length]; angle [deg]; orientation rotation vector [rad]
    components = [0, 2]             # optional
    weight = 1.0

The full schema, with every key, is in docs/SCENARIOS.md ("[design]").  An angle target's
value, misfit (in design.json), scale and the tolerance it is compared with are in degrees.
"""
from __future__ import annotations

import numpy as np

from ..design import (METHODS, Design, FieldVariable, LoadMagnitude, MaterialVariable, NodePosition, Orientation,
                      Pose, ProbePosition, RegionMagnetisation, RotationAngle, Smoothness, Target)
from ..design.objectives import Quantity
from .. import lie
from ..errors import CoreSE3Error, ScenarioError, did_you_mean
from .validate import join, show, tname

__all__ = ["design_section", "build_design", "DESIGN_KEYS", "AngleInDegrees"]

DESIGN_KEYS = ("method", "max_iter", "tolerance", "tol", "stop_at_tolerance", "variables", "poses", "targets")
VARIABLE_KEYS = {"field": ("field", "form", "plane", "free", "B_max", "pose"),
                 "magnetisation": ("regions", "form", "planes", "free", "Br_max", "smoothness", "field"),
                 "material": ("prop", "regions", "lower", "upper"),
                 "load": ("load", "lower", "upper", "pose")}
TARGET_KEYS = ("pose", "type", "probe", "node", "value", "components", "weight", "axis", "scale")


def _names(v, d, k, key, allowed, what):
    x = d.get(k)
    if not isinstance(x, list) or not x or any(not isinstance(a, str) for a in x):
        v.fail(join(key, k), f"expected a non-empty array of {what} names, got {tname(x)} {show(x)}")
    for a in x:
        if a not in allowed:
            v.fail(join(key, k), f"unknown {what} {a!r}{did_you_mean(a, allowed)}; defined: {sorted(allowed) or 'none'}")
    return x


def _plane(v, d, k, key, default):
    if k not in d:
        return default
    x = d[k]
    if not isinstance(x, list) or len(x) != 2:
        v.fail(join(key, k), f"expected two 3-vectors [e1, e2], got {tname(x)} {show(x)}")
    return [v.vector({"e": e}, "e", f"{join(key, k)}[{i}]", nonzero=True) for i, e in enumerate(x)]


class AngleInDegrees(Quantity):
    """A scenario's angle target: a ``RotationAngle`` with its value, misfit, target and scale
    in degrees (an angle goes in and comes out of a scenario in degrees); the scenario's default
    scale is 1 rad = 57.3 deg (the Python API's, so the objective is the same).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh, lie
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> g = lie.exp(np.array([0, 0, 0, 0, -0.5, 0])) @ p.mesh.g0            # 0.5 rad about -y
    >>> round(float(AngleInDegrees(p, node=2, target=30.0).value(p, g, 1.0)[0]), 6)   # 28.6479 - 30
    -1.35211
    """
    DEGREE = 180.0 / np.pi

    def __init__(self, problem, target=None, **kw):
        self.angle = RotationAngle(problem, target=None if target is None else np.radians(target), **kw)
        self.target, self.name, self.size = target, self.angle.name, 1

    def value(self, problem, g, lam):
        return self.DEGREE * self.angle.value(problem, g, lam)

    def jacobian(self, problem, g, lam):
        return self.DEGREE * self.angle.jacobian(problem, g, lam)

    def explicit(self, problem, g, lam, variable):
        return self.DEGREE * self.angle.explicit(problem, g, lam, variable)


def design_section(v, doc, spec, mesh, regions):
    """The validated [design] section (None when absent)."""
    if "design" not in doc:
        return None
    d, key = doc["design"], "design"
    v.table(d, key, DESIGN_KEYS, required=("variables", "targets"))
    out = dict(method=v.string(d, "method", key, default="least_squares", choices=METHODS),
               max_iter=v.integer(d, "max_iter", key, default=50, lo=1, hi=10_000),
               tolerance=v.number(d, "tolerance", key, default=None, lo=0.0),
               tol=v.number(d, "tol", key, default=1e-12, lo=0.0, lo_open=True),
               stop_at_tolerance=v.boolean(d, "stop_at_tolerance", key, default=False))
    poses = []
    for i, t in enumerate(v.array_of_tables(d, "poses") if "poses" in d else []):
        k2 = f"design.poses[{i}]"
        v.table(t, k2, ("name", "fields", "lam"), required=("name",))
        name = v.string(t, "name", k2)
        if name in [p["name"] for p in poses]:
            v.fail(join(k2, "name"), f"pose names must be unique, got {name!r} twice")
        fields = {}
        ft = t.get("fields", {})
        if not isinstance(ft, dict):
            v.fail(join(k2, "fields"), f"expected a table field name -> [Bx, By, Bz], got {tname(ft)}")
        for fname in ft:
            if fname not in spec["fields"]:
                v.fail(join(join(k2, "fields"), fname), f"unknown field {fname!r}{did_you_mean(fname, spec['fields'])}; "
                       f"defined fields: {sorted(spec['fields']) or 'none'}")
            fields[fname] = v.vector(ft, fname, join(k2, "fields"))
        poses.append(dict(name=name, fields=fields, lam=v.number(t, "lam", k2, default=1.0)))
    if not poses:
        poses = [dict(name="design", fields={}, lam=1.0)]
    pnames = [p["name"] for p in poses]
    out["poses"] = poses

    def pose_ref(t, k2, default=None):
        if "pose" not in t:
            return default
        name = v.string(t, "pose", k2)
        if name not in pnames:
            v.fail(join(k2, "pose"), f"unknown pose {name!r}{did_you_mean(name, pnames)}; poses: {', '.join(pnames)}")
        return name

    out["variables"] = []
    for i, t in enumerate(v.array_of_tables(d, "variables")):
        k2 = f"design.variables[{i}]"
        typ = v.string(t, "type", k2, choices=tuple(VARIABLE_KEYS))
        v.table(t, k2, ("type",) + VARIABLE_KEYS[typ])
        var = dict(type=typ)
        if typ in ("field", "magnetisation"):
            var["form"] = v.string(t, "form", k2, default="vector", choices=("vector", "polar"))
            if "free" in t:
                fr = t["free"]
                parts = ("x", "y", "z") if var["form"] == "vector" else ("magnitude", "angle")
                if not isinstance(fr, list) or not fr or any(x not in parts for x in fr):
                    v.fail(join(k2, "free"), f"expected a non-empty array of {', '.join(map(repr, parts))}, got {show(fr)}")
                var["free"] = fr
        if typ == "field":
            var["field"] = v.string(t, "field", k2, choices=tuple(spec["fields"]) or ("(no fields defined)",))
            var["plane"] = _plane(v, t, "plane", k2, [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
            var["B_max"] = v.number(t, "B_max", k2, default=None, lo=0.0, lo_open=True)
            var["pose"] = pose_ref(t, k2)
        elif typ == "magnetisation":
            var["regions"] = _names(v, t, "regions", k2, regions, "region")
            pl = t.get("planes", [[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]])
            if not isinstance(pl, list) or len(pl) not in (1, len(var["regions"])):
                v.fail(join(k2, "planes"), f"expected one plane [e1, e2] or one per region ({len(var['regions'])})")
            var["planes"] = [_plane(v, {"p": p}, "p", f"{k2}.planes[{j}]", None) for j, p in enumerate(pl)]
            var["Br_max"] = v.number(t, "Br_max", k2, default=None, lo=0.0, lo_open=True)
            var["smoothness"] = v.number(t, "smoothness", k2, default=0.0, lo=0.0)
            var["field"] = v.string(t, "field", k2, default=None, choices=tuple(spec["fields"]) or ("(none)",))
        elif typ == "material":
            var["prop"] = v.string(t, "prop", k2, choices=("E", "h"))
            var["regions"] = _names(v, t, "regions", k2, regions, "region")
            var["lower"] = v.number(t, "lower", k2, default=0.0)
            var["upper"] = v.number(t, "upper", k2, default=float("inf"))
        else:
            var["load"] = v.integer(t, "load", k2, lo=0)
            if var["load"] >= len(spec["loads"]):
                v.fail(join(k2, "load"), f"there is no loads[{var['load']}] (the scenario has {len(spec['loads'])} loads)")
            var["lower"] = v.number(t, "lower", k2, default=-float("inf"))
            var["upper"] = v.number(t, "upper", k2, default=float("inf"))
            var["pose"] = pose_ref(t, k2)
        out["variables"].append(var)
    if not out["variables"]:
        v.fail("design.variables", "a design needs at least one variable")
    probes = [p["name"] for p in spec["probes"]]
    out["targets"] = []
    for i, t in enumerate(v.array_of_tables(d, "targets")):
        k2 = f"design.targets[{i}]"
        v.table(t, k2, TARGET_KEYS, required=("type", "value"))
        typ = v.string(t, "type", k2, choices=("position", "angle", "orientation"))
        tg = dict(type=typ, pose=pose_ref(t, k2, pnames[0]), weight=v.number(t, "weight", k2, default=1.0, lo=0.0),
                  scale=v.number(t, "scale", k2, default=None, lo=0.0, lo_open=True))
        if ("probe" in t) == ("node" in t):
            v.fail(k2, "give exactly one of 'probe' (a [[probes]] name) or 'node' (a node id)")
        if "probe" in t:
            tg["probe"] = v.string(t, "probe", k2, choices=tuple(probes) or ("(no probes defined)",))
        else:
            tg["node"] = v.integer(t, "node", k2, lo=0, hi=mesh.n_nodes - 1)
        if typ == "angle":
            tg["value"] = v.number(t, "value", k2)
            tg["axis"] = v.vector(t, "axis", k2, default=[0.0, -1.0, 0.0], nonzero=True)
        else:
            tg["value"] = v.vector(t, "value", k2)
        if "components" in t:
            c = t["components"]
            n = 1 if typ == "angle" else 3
            if not isinstance(c, list) or not c or any(isinstance(x, bool) or not isinstance(x, int) or not 0 <= x < n
                                                        for x in c):
                v.fail(join(k2, "components"), f"expected an array of component numbers 0..{n - 1}, got {show(c)}")
            tg["components"] = c
        out["targets"].append(tg)
    if not out["targets"]:
        v.fail("design.targets", "a design needs at least one target")
    return out


def build_design(scn):
    """The Design of a scenario's validated [design] (the scenario's problem is changed: the
    magnets on design regions become the design's own magnetic loads); ScenarioError naming the
    key when the core refuses a variable or a target.

    Example
    -------
    See docs/DESIGN.md (examples/gripper-design.toml) and tests/test_design_scenario.py.

    >>> DESIGN_KEYS[0]
    'method'
    """
    from .validate import Validator
    ds, prob, v = scn.spec["design"], scn.problem, Validator(scn.file)
    fields = scn.fields
    pnames = [p["name"] for p in ds["poses"]]
    variables, reg = [], []
    for i, var in enumerate(ds["variables"]):
        key = f"design.variables[{i}]"
        try:
            if var["type"] == "field":
                variables.append(FieldVariable(prob, fields[var["field"]], var["form"], var["plane"], var.get("free"),
                                               var["B_max"], None if var["pose"] is None else pnames.index(var["pose"]),
                                               name=var["field"]))
            elif var["type"] == "magnetisation":
                regions = [scn.regions[r] for r in var["regions"]]
                planes = var["planes"][0] if len(var["planes"]) == 1 else var["planes"]
                mv = RegionMagnetisation(prob, regions, var["form"], planes, var.get("free"), var["Br_max"],
                                         None if var["field"] is None else fields[var["field"]],
                                         name=f"magnetisation{i}")
                mv.region_names = list(var["regions"])
                variables.append(mv)
                if var["smoothness"] > 0:
                    reg.append(Smoothness(mv, var["smoothness"]))
            elif var["type"] == "material":
                mv = MaterialVariable(prob, [scn.regions[r] for r in var["regions"]], var["prop"], var["lower"],
                                      var["upper"], name=f"{var['prop']}{i}")
                mv.region_names = list(var["regions"])
                variables.append(mv)
            else:
                built = scn.load_objects[var["load"]]
                if len(built) != 1:
                    v.fail(join(key, "load"), f"loads[{var['load']}] is {len(built)} loads (one per region): "
                                              "a load variable needs a single load")
                variables.append(LoadMagnitude(prob, built[0], var["lower"], var["upper"],
                                               None if var["pose"] is None else pnames.index(var["pose"]),
                                               name=f"load{var['load']}"))
        except ScenarioError:
            raise
        except CoreSE3Error as exc:
            v.fail(key, str(exc))
    field_vars = {}
    for var, spec_var in zip(variables, ds["variables"]):
        if spec_var["type"] == "field":
            field_vars.setdefault(spec_var["field"], []).append(var)
    poses = []
    for k, p in enumerate(ds["poses"]):
        settings = {}
        for fname, B in p["fields"].items():
            owners = [fv for fv in field_vars.get(fname, []) if fv.pose != k]
            aux = FieldVariable(prob, fields[fname], "vector", name=fname)
            settings[aux] = np.asarray(B, float)
            for fv in owners:              # the field of another pose's variable, held here
                full = B if fv.form == "vector" else [np.hypot(B @ fv.e1, B @ fv.e2), np.arctan2(B @ fv.e2, B @ fv.e1)]
                settings[fv] = np.asarray(full, float)[fv.free]
        poses.append(Pose(p["name"], [], settings, p["lam"]))
    for i, t in enumerate(ds["targets"]):
        key = f"design.targets[{i}]"
        where = dict(probe=t["probe"]) if "probe" in t else dict(node=t["node"])
        try:
            if t["type"] == "position":
                q = ProbePosition(prob, t["probe"], t["value"]) if "probe" in t else NodePosition(prob, [t["node"]], t["value"])
            elif t["type"] == "angle":             # degrees in, degrees out (misfit, tolerance, scale)
                q = AngleInDegrees(prob, axis=t["axis"], target=t["value"], **where)
                t = dict(t, scale=t["scale"] if t["scale"] is not None else AngleInDegrees.DEGREE)
            else:                           # the frame turned by the rotation vector from its reference
                q = Orientation(prob, **where)
                q.target = lie.exp_so3(np.asarray(t["value"], float)) @ q.target
            poses[pnames.index(t["pose"])].targets.append(
                Target(q, t["weight"], t["scale"], t.get("components"), name=f"targets[{i}]"))
        except CoreSE3Error as exc:
            v.fail(key, str(exc))
    try:
        return Design(prob, variables, poses, reg)
    except CoreSE3Error as exc:
        v.fail("design", str(exc))

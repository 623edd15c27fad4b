"""The [design] section of scenario files (issue 15): the design variables, poses and targets of
an inverse problem on the scenario's shell, validated with errors naming the file and the key,
and built into a :class:`core_se3.design.Design`.

    [design]
    method = "least_squares"        # or "L-BFGS-B", "SLSQP", "trust-constr"
    max_iter = 50
    tolerance = 0.02                # largest misfit that counts as reaching the targets
    stop_at_tolerance = false       # stop at the first iteration within the tolerance
    equilibria = "follow"           # or "ramp": each evaluation solved from the flat state

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

from ..design import Design, FieldVariable, Pose, Target
from ..design.kinds import TARGETS, VARIABLES
from ..design.objectives import AngleInDegrees
from ..errors import CoreSE3Error, ScenarioError, did_you_mean
from ..io.rundir import safe_name
from .schema import DESIGN, POSE, TARGET
from .validate import join, user_key

__all__ = ["design_section", "build_design", "DESIGN_KEYS", "AngleInDegrees"]

DESIGN_KEYS = DESIGN.keys()


def design_section(v, doc, spec, mesh, regions):
    """The validated [design] section (None when absent): its own keys (scenario.schema.DESIGN),
    poses, variables (core_se3.design.VARIABLES) and targets (core_se3.design.TARGETS)."""
    if "design" not in doc:
        return None
    d, key = doc["design"], "design"
    v.table(d, key, DESIGN.keys(), required=("variables", "targets"))
    out = {k: v.param(d, key, DESIGN.param(k)) for k in ("method", "max_iter", "tolerance", "tol", "stop_at_tolerance",
                                                          "equilibria")}
    out["poses"] = _poses(v, d, spec)
    names = dict(field=spec["fields"], regions=regions, pose=[p["name"] for p in out["poses"]],
                 load=spec["loads"], probe=[p["name"] for p in spec["probes"]])
    out["variables"] = [_variable(v, t, f"design.variables[{i}]", names)
                        for i, t in enumerate(v.array_of_tables(d, "variables"))]
    if not out["variables"]:
        v.fail("design.variables", "a design needs at least one variable")
    out["targets"] = [_target(v, t, f"design.targets[{i}]", names, mesh)
                      for i, t in enumerate(v.array_of_tables(d, "targets"))]
    if not out["targets"]:
        v.fail("design.targets", "a design needs at least one target")
    return out


def _poses(v, d, spec):
    """[[design.poses]] (default one pose "design"): unique names, fields held at a value."""
    poses = []
    for i, t in enumerate(v.array_of_tables(d, "poses") if "poses" in d else []):
        k2 = f"design.poses[{i}]"
        v.table(t, k2, POSE.keys(), required=POSE.required())
        name = v.string(t, "name", k2)
        if name in [p["name"] for p in poses]:
            v.fail(join(k2, "name"), f"pose names must be unique, got {name!r} twice")
        same = [p["name"] for p in poses if safe_name(p["name"]) == safe_name(name)]
        if same:               # the files of the one would overwrite the other's
            v.fail(join(k2, "name"), f"poses {same[0]!r} and {name!r} have one file name, {safe_name(name)!r} "
                                     f"(optimised_NAME.toml, vtu/NAME/): name them apart in letters, digits, "
                                     f"'.', '_' or '-'")
        fields = {}
        ft = t.get("fields", {})
        if not isinstance(ft, dict):
            v.fail(join(k2, "fields"), f"expected a table field name -> [Bx, By, Bz], got {v.shown(ft)}")
        for fname in ft:
            if fname not in spec["fields"]:
                v.fail(join(join(k2, "fields"), fname), f"unknown field {fname!r}{did_you_mean(fname, spec['fields'])}; "
                       f"defined fields: {sorted(spec['fields']) or 'none'}")
            fields[fname] = v.vector(ft, fname, join(k2, "fields"))
        poses.append(dict(name=name, fields=fields, lam=v.param(t, k2, POSE.param("lam"))))
    return poses or [dict(name="design", fields={}, lam=1.0)]


def _refs(v, values, key, names):
    """The keys of ``values`` that name things of the scenario (design.kinds.REFERENCE_KEYS):
    each must exist (a did-you-mean naming the key otherwise)."""
    for k, x in values.items():
        if x is None or k not in names:
            continue
        path = join(key, k)
        if k in ("field", "probe"):
            if x not in names[k]:
                v.choice_fail(path, x, tuple(names[k]) or (f"(no {k}s defined)",))
        elif k == "regions":
            for a in x:
                if a not in names[k]:
                    v.fail(path, f"unknown region {a!r}{did_you_mean(a, names[k])}; defined: {sorted(names[k]) or 'none'}")
        elif k == "pose":
            if x not in names[k]:
                v.fail(path, f"unknown pose {x!r}{did_you_mean(x, names[k])}; poses: {', '.join(names[k])}")
        elif k == "load" and x >= len(names[k]):
            v.fail(path, f"there is no loads[{x}] (the scenario has {len(names[k])} loads)")


def _variable(v, t, key, names):
    """One [[design.variables]] entry: its kind's keys, the names they refer to."""
    typ = v.string(t, "type", key, choices=tuple(VARIABLES))
    kind = VARIABLES[typ]
    values = v.section(t, key, kind, first=("type",))
    _refs(v, values, key, names)
    return dict(type=typ, **{k: x for k, x in values.items() if not (k == "free" and x is None)})


def _target(v, t, key, names, mesh):
    """One [[design.targets]] entry: its kind's keys and the common ones (scenario.schema.TARGET)."""
    if "type" not in t:
        v.fail(join(key, "type"), "missing required key")
    typ = v.string(t, "type", key, choices=tuple(TARGETS))
    kind = TARGETS[typ]
    v.table(t, key, ("type",) + kind.keys() + TARGET.keys(), required=kind.required())
    tg = dict(type=typ, pose=v.param(t, key, TARGET.param("pose")) or names["pose"][0],
              weight=v.param(t, key, TARGET.param("weight")), scale=v.param(t, key, TARGET.param("scale")))
    _refs(v, dict(pose=tg["pose"]), key, names)
    if ("probe" in t) == ("node" in t):
        v.fail(key, "give exactly one of 'probe' (a [[probes]] name) or 'node' (a node id)")
    if "probe" in t:
        tg["probe"] = v.param(t, key, TARGET.param("probe"))
        _refs(v, dict(probe=tg["probe"]), key, names)
    else:
        # a node id of the unrefined mesh, as everywhere in the file (its nodes keep their ids)
        base = getattr(mesh, "_lineage", [mesh])[0]
        tg["node"] = v.integer(t, "node", key, lo=0, hi=base.n_nodes - 1)
    tg.update(v.params(t, key, kind.params))
    v.kind_check(kind, tg, t, key)
    if "components" in t:
        c = t["components"]
        if not isinstance(c, list) or not c or any(isinstance(x, bool) or not isinstance(x, int) or not 0 <= x < kind.size
                                                    for x in c):
            v.fail(join(key, "components"), f"expected an array of component numbers 0..{kind.size - 1}, got {v.shown(c)}")
        tg["components"] = c
    return tg


class DesignContext:
    """What a design kind's ``build`` sees (design.kinds): the problem, the regions, fields and
    load objects of the scenario by name, the pose indices, the regularisers collected."""

    def __init__(self, scn, pose_names):
        self.problem, self.regions, self.fields, self.loads = scn.problem, scn.regions, scn.fields, scn.load_objects
        self.pose_names, self.regularisers, self.index = pose_names, [], 0

    def pose(self, name):
        return None if name is None else self.pose_names.index(name)

    def add_regulariser(self, r):
        self.regularisers.append(r)


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
    ds, v = scn.spec["design"], Validator(scn.file)
    ctx = DesignContext(scn, [p["name"] for p in ds["poses"]])
    variables = []
    for i, var in enumerate(ds["variables"]):
        ctx.index = i
        kind = VARIABLES[var["type"]]
        variables.append(_built(v, f"design.variables[{i}]", kind, lambda: kind.build(ctx, var)))
        variables[-1].scenario_kind = kind            # how core-se3 design writes its value back
    poses = _design_poses(ctx, ds, variables)
    for i, t in enumerate(ds["targets"]):
        kind = TARGETS[t["type"]]
        where = dict(probe=t["probe"]) if "probe" in t else dict(node=t["node"])
        q = _built(v, f"design.targets[{i}]", kind, lambda: kind.build(ctx, t, where))
        scale = t["scale"] if t["scale"] is not None else kind.scale
        poses[ctx.pose(t["pose"])].targets.append(Target(q, t["weight"], scale, t.get("components"),
                                                          name=f"targets[{i}]"))
    try:
        return Design(scn.problem, variables, poses, ctx.regularisers, equilibria=ds["equilibria"])
    except CoreSE3Error as exc:
        v.fail("design", str(exc))


def _built(v, key, kind, make):
    """``make()``, its refusal a ScenarioError naming the key."""
    try:
        return make()
    except ScenarioError:
        raise
    except CoreSE3Error as exc:
        param = getattr(exc, "param", None)
        v.fail(join(key, param) if param else key, str(exc))
    except ValueError as exc:                  # a user's kind refusing its values
        v.fail(user_key(key, kind, exc), f"{kind.name}: {exc}")


def _design_poses(ctx, ds, variables):
    """The Poses of the [design]: each holds its fields at the given values, also where another
    pose's field variable owns that field."""
    field_vars = {}
    for var, spec_var in zip(variables, ds["variables"]):
        if spec_var["type"] == "field":
            field_vars.setdefault(spec_var["field"], []).append(var)
    poses = []
    for k, p in enumerate(ds["poses"]):
        settings = {}
        for fname, B in p["fields"].items():
            owners = [fv for fv in field_vars.get(fname, []) if fv.pose != k]
            aux = FieldVariable(ctx.problem, ctx.fields[fname], "vector", name=fname)
            settings[aux] = np.asarray(B, float)
            for fv in owners:              # the field of another pose's variable, held here
                full = B if fv.form == "vector" else [np.hypot(B @ fv.e1, B @ fv.e2), np.arctan2(B @ fv.e2, B @ fv.e1)]
                settings[fv] = np.asarray(full, float)[fv.free]
        poses.append(Pose(p["name"], [], settings, p["lam"]))
    return poses

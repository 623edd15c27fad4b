"""Scenario sections on physics and control: [material] (and per-region values), [fields.NAME]
(the field registry), [[magnets]], [[supports]], [[loads]] (the load registry), [solver] (the
fields and defaults of NewtonOptions / ArcLengthOptions) and [output]."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import LoadError, did_you_mean
from ..fem import ELEMENTS
from ..fem.material_kinds import MATERIALS
from ..model import FIELDS, LOADS, SUPPORTS, edge_weights, line_shares
from .geometry import nodes_ref, region_ref
from .magnetisation import pattern_section
from .schema import ARCLENGTH, MAGNET, OUTPUT, PARALLEL_KEYS, SOLVER
from .validate import Bounds, join, tname, show

__all__ = ["material_section", "material_law_keys", "material_index", "fields_section",
           "magnets_section", "supports_section", "loads_section", "solver_section",
           "output_section", "SOLVER_DEFAULTS", "ARCLENGTH_DEFAULTS", "OUTPUT_DEFAULTS",
           "NON_PHYSICAL"]

# [solver] keys of both controls and their defaults (scenario.schema.SOLVER: NewtonOptions' own;
# arc-length runs of scenario files use Newton's tolerances and iteration limit)
SOLVER_DEFAULTS = {p.name: p.default for p in SOLVER.params
                   if p.name not in ("load_factors",) + tuple(PARALLEL_KEYS) + ("petsc",)}
# arc-length keys, with ArcLengthOptions' defaults (dlam0: lam_end / steps)
ARCLENGTH_DEFAULTS = {p.name: p.default for p in ARCLENGTH.params}
OUTPUT_DEFAULTS = {p.name: p.default for p in OUTPUT.params if p.name != "dir"}
# [solver] keys that only load control reads (arc length and linear analysis have none of them)
LOAD_CONTROL_ONLY = ("max_cutbacks", "iteration", "predictor", "path_check", "limit_check", "max_substeps",
                     "snap_check", "friction_check", "friction_halving", "friction_tol", "end_check", "inertia_check",
                     "midpoint_probe", "refine_check")
# solver keys that do not change the converged states (left out of the --resume fingerprint);
# max_steps only decides where an arc-length path stops, so a resume may raise it
NON_PHYSICAL = ("rtol", "dtol", "max_iter", "max_cutbacks", "linear_solver", "max_steps", "iteration",
                "predictor", "linear", "petsc", "partition", "path_check", "limit_check", "max_substeps",
                "critical_tol", "snap_check", "inertia_check", "end_check", "midpoint_probe", "refine_check",
                "friction_check", "friction_tol", "friction_halving")


def material_section(v, d, regions):
    """[material]: ``law`` (a key of core_se3.fem.MATERIALS, default "isotropic") with the law's
    keys, and ``[material.regions.NAME]`` tables of the same keys (defaults: the base values)
    on regions that must not overlap.  The spec names the law only when it is not the default."""
    key = "material"
    if not isinstance(d, dict):
        v.fail(key, f"expected a table, got {tname(d)} {show(d)}")
    law = v.string(d, "law", key, default="isotropic", choices=tuple(MATERIALS))
    kind = MATERIALS[law]
    out = v.section(d, key, kind, extra=("law", "regions"), required=kind.required())
    out["regions"] = {}
    reg = d.get("regions", {})
    if not isinstance(reg, dict):
        v.fail(join(key, "regions"), f"expected a table of [material.regions.NAME], got {tname(reg)}")
    region_kind = replace(kind, params=tuple(replace(p, default=out[p.name]) for p in kind.params))
    for name, t in reg.items():
        k2 = join(join(key, "regions"), name)
        if name not in regions:
            v.fail(k2, f"unknown region {name!r}{did_you_mean(name, regions)}; defined regions: "
                       f"{sorted(regions) or 'none'}")
        vals = v.section(t, k2, region_kind)
        for other in out["regions"]:
            if np.intersect1d(regions[other], regions[name]).size:
                v.fail(k2, f"material regions {other!r} and {name!r} overlap: an element would get "
                           "two materials")
        out["regions"][name] = vals
    _unused_floor(v, d, out, key)
    if law != "isotropic":
        out["law"] = law
    return out


def _unused_floor(v, d, out, key):
    """A warning at ``shear_stabilisation_floor`` where it is written but no law uses it: the
    floor only bounds the stabilisation's factor (``Material.shear_scale``), so without
    shear_stabilisation > 0 it changes nothing (a floor of 0.2 on its own left the shear modulus
    at ks G h, silently)."""
    name = "shear_stabilisation_floor"
    why = (f"{name} bounds the factor of the shear stabilisation from below and has no effect without "
           "shear_stabilisation > 0 (off here): give shear_stabilisation = alpha (Kratos' thick quad: 0.1) "
           f"to stabilise, or remove {name}")
    regions = d.get("regions", {})
    inherit = [out["regions"][r]["shear_stabilisation"] for r, t in regions.items() if name not in t]
    if name in d and out.get("shear_stabilisation") == 0 and not any(inherit):
        v.warn(join(key, name), why)
    for r, t in regions.items():
        if name in t and out["regions"][r].get("shear_stabilisation") == 0:
            v.warn(join(join(join(key, "regions"), r), name), why)


def material_law_keys(spec_material):
    """The keys of the law of a validated [material] (its kind's keys)."""
    return MATERIALS[spec_material.get("law", "isotropic")].keys()


def material_index(spec_material, regions, n_elements):
    """(list of property dicts, (m,) index into it): the material of every element.

    Parameters
    ----------
    spec_material : dict
        The validated [material] section (E, nu, h, shear_factor, drilling, rho,
        shear_stabilisation, shear_stabilisation_floor and ``regions``: name -> the same keys).
    regions : dict
        name -> element ids.
    n_elements : int
        Number of elements.

    Returns
    -------
    (list of dict, (m,) ndarray)
        The distinct property sets (the base one first) and each element's index.

    Example
    -------
    >>> base = dict(E=1.0, nu=0.3, h=0.1, shear_factor=1.0, drilling=1.0, rho=None, shear_stabilisation=0.0,
    ...             shear_stabilisation_floor=0.05)
    >>> mats, index = material_index(dict(base, regions={"tip": dict(base, E=2.0)}), {"tip": [2, 3]}, 4)
    >>> [m["E"] for m in mats], index.tolist()
    ([1.0, 2.0], [0, 0, 1, 1])
    """
    keys = material_law_keys(spec_material)
    mats = [{k: spec_material[k] for k in keys}]
    index = np.zeros(n_elements, np.int64)
    for name, vals in spec_material["regions"].items():
        vals = {k: vals[k] for k in keys}
        if vals not in mats:
            mats.append(vals)
        index[regions[name]] = mats.index(vals)
    return mats, index


def fields_section(v, doc):
    """[fields.NAME]: type (a key of core_se3.model.FIELDS), scale and the kind's parameters."""
    out = {}
    for name, t in v.names_table(doc, "fields").items():
        key = join("fields", name)
        typ = v.string(t, "type", key, choices=tuple(FIELDS))
        kind = FIELDS[typ]
        v.table(t, key, ("type",) + kind.keys() + ("scale",))
        f = dict(type=typ, scale=v.scale(t, key))
        f.update(v.params(t, key, kind.params))
        v.kind_check(kind, f, t, key)
        out[name] = f
    return out


def magnets_section(v, doc, regions, fields, mesh=None, base_dir="."):
    out = []
    for i, t in enumerate(v.array_of_tables(doc, "magnets")):
        key = f"magnets[{i}]"
        v.table(t, key, MAGNET.keys())
        if ("Br" in t) + ("Br_frame" in t) + ("Br_file" in t) != 1:
            v.fail(key, "give exactly one of 'Br' (lab vector [T]) or 'Br_frame' (components "
                        "[T] along the reference directors d1, d2, d3), or 'Br_file' (a table per element or node)")
        m = {}
        if "direction" in t or "Br_file" in t or any(k in t for k in ("Br_axial", "centre", "axis")):
            elems, m["region"] = region_ref(v, t, key, regions)
            m.update(pattern_section(v, t, key, mesh, elems, base_dir))
        elif "Br" in t:
            m["Br"] = v.vector(t, "Br", key)
        else:
            m["Br_frame"] = v.vector(t, "Br_frame", key)
        _, m["region"] = region_ref(v, t, key, regions)
        m["mu0"] = v.number(t, "mu0", key, default=None, bounds=Bounds(lo=0.0, lo_open=True))
        if not fields:
            v.fail(key, "a magnet needs an applied field: define one in [fields.NAME]")
        if "field" in t:
            m["field"] = v.string(t, "field", key, choices=tuple(fields))
        elif len(fields) == 1:
            m["field"] = next(iter(fields))
        else:
            v.fail(join(key, "field"), f"several fields are defined ({', '.join(fields)}): name one")
        _refuse_repeat(v, out, m, key, "magnets", "the magnet")
        _refuse_overlap(v, out, m, key, regions)
        out.append(m)
    if fields and not out:
        v.fail("fields", "fields are defined but no [[magnets]] use them")
    return out


def _refuse_overlap(v, out, m, key, regions):
    """An element has one remanent magnetisation: two magnets of the same field on common
    elements would add their Br silently (a copied region name, a whole-shell magnet beside a
    region's)."""
    mine = None if m["region"] is None else set(np.asarray(regions[m["region"]]).tolist())
    for j, o in enumerate(out):
        if o["field"] != m["field"]:
            continue
        other = None if o["region"] is None else set(np.asarray(regions[o["region"]]).tolist())
        common = (mine & other if other is not None else mine) if mine is not None else other
        if common is None or common:
            where = ("common elements: " + ("every element" if common is None else f"{len(common)}") +
                     ("" if mine is not None and other is not None else
                      " (a magnet without 'region' magnetises the whole shell)"))
            v.fail(key, f"magnets[{j}] and {key} have {where}, for field {m['field']!r}: an element has one "
                        "remanent magnetisation, and the two would add; give each region once (split the "
                        "regions, or sum the Br into one magnet)")


def supports_section(v, doc, mesh, regions):
    """[[supports]]: type (a key of core_se3.model.SUPPORTS), the node selection (edge, nodes or
    region), the kind's keys and, for a kind that moves its nodes, scale."""
    sup = v.array_of_tables(doc, "supports")
    # a free shell may rest on obstacles (friction holds it: the rigid-motion check of the solve
    # counts the contact nodes' restraints and names a motion left free)
    if not sup and not doc.get("obstacles"):
        v.fail("supports", "no supports: the shell could move as a rigid body; add e.g. "
                           '[[supports]] type = "clamp", edge = "x0"')
    out = []
    for i, t in enumerate(sup):
        key = f"supports[{i}]"
        typ = v.string(t, "type", key, choices=tuple(SUPPORTS))
        kind = SUPPORTS[typ]
        v.table(t, key, ("type", "edge", "nodes", "region") + kind.keys() + (("scale",) if kind.moves else ()))
        s = dict(type=typ, **nodes_ref(v, t, key, mesh, regions=regions))
        s.update(v.params(t, key, kind.params))
        v.kind_check(kind, s, t, key)
        if kind.moves:
            s["scale"] = v.scale(t, key)
        _refuse_repeat(v, out, s, key, "supports", "the support")
        out.append(s)
    return out


def _refuse_repeat(v, done, entry, key, section, what):
    """A ScenarioError when ``entry`` repeats an earlier entry of ``section`` exactly (a copy
    that would apply a load twice, or hold the same nodes twice)."""
    for j, other in enumerate(done):
        if other == entry:
            v.fail(key, f"repeats {section}[{j}] exactly: {what} would act twice; remove one (or, for a "
                        "load meant twice, double its value)")


def _line_union(v, t, key, mesh):
    """A line load's ``edge = ["x0", "x1"]``: a union of named lines, each along its own element
    edges (``model.loads.line_shares``)."""
    path = join(key, "edge")
    if "nodes" in t:
        v.fail(key, "give one of 'edge' or 'nodes', not 'edge' and 'nodes'")
    names = t["edge"]
    if not names or not all(isinstance(n, str) for n in names):
        v.fail(path, f"expected a name or an array of names of lines, got {show(names)}")
    for n in names:
        if n not in mesh.edges:
            v.fail(path, f"unknown edge {n!r}{did_you_mean(n, mesh.edges)}; the mesh has: "
                         f"{', '.join(sorted(mesh.edges)) or 'no named edges'}")
        try:
            edge_weights(mesh, mesh.edges[n])
        except LoadError as exc:
            v.fail(path, f"node set {n!r}: {exc}")
    try:
        line_shares(mesh, names)
    except LoadError as exc:
        v.fail(path, str(exc))
    return dict(edge=list(names))


def loads_section(v, doc, mesh, regions):
    """[[loads]]: type (a key of core_se3.model.LOADS), scale, the selection the kind's target
    needs (edge/nodes, or region) and the kind's parameters, checked by its own check."""
    out = []
    for i, t in enumerate(v.array_of_tables(doc, "loads")):
        key = f"loads[{i}]"
        typ = v.string(t, "type", key, choices=tuple(LOADS))
        kind = LOADS[typ]
        nodal = kind.target in ("line", "nodes")
        v.table(t, key, ("type",) + (("edge", "nodes") if nodal else ()) + kind.keys()
                + ("scale",) + (() if nodal else ("region",)))
        ld = dict(type=typ, scale=v.scale(t, key))
        if kind.target == "line" and isinstance(t.get("edge"), list):
            ld.update(_line_union(v, t, key, mesh))
        elif nodal:
            ld.update(nodes_ref(v, t, key, mesh))
            if kind.target == "line" and "edge" in ld:
                try:                      # the set's element edges carry it (one line, pieces, a loop)
                    edge_weights(mesh, mesh.edges[ld["edge"]])
                except LoadError as exc:
                    v.fail(join(key, "edge"), f"node set {ld['edge']!r}: {exc}")
        ld.update(v.params(t, key, kind.params))
        v.kind_check(kind, ld, t, key)
        if not nodal:
            _, ld["region"] = region_ref(v, t, key, regions)
        _refuse_repeat(v, out, ld, key, "loads", "the load")
        out.append(ld)
    return out


def solver_section(v, doc):
    """[solver]: control, steps or load_factors, tolerances, element, linear solver and, with
    control = "arclength", the arc-length controls (scenario.schema.SOLVER, ARCLENGTH)."""
    d = doc.get("solver", {})
    key = "solver"
    v.table(d, key, SOLVER.keys() + ARCLENGTH.keys())
    s = dict(SOLVER_DEFAULTS)
    for name in ("linear", "partition", "control", "steps", "lam_end"):
        s[name] = v.param(d, key, SOLVER.param(name))
    s["petsc"] = _petsc_options(v, d.get("petsc", {}), join(key, "petsc"))
    if s["lam_end"] == 0:
        v.fail(join(key, "lam_end"), "expected a non-zero final load factor, got 0")
    for name in ("rtol", "dtol", "max_iter", "max_cutbacks", "element", "linear_solver", "iteration", "predictor",
                 "path_check", "limit_check", "critical_tol", "max_substeps", "snap_check", "inertia_check",
                 "end_check", "midpoint_probe", "refine_check", "friction_check", "friction_tol", "friction_halving"):
        s[name] = v.param(d, key, SOLVER.param(name))
    for name in LOAD_CONTROL_ONLY if s["control"] != "load" else ():
        if name in d:           # a warning, not an error: a sweep may switch the control of the file
            v.warn(join(key, name), f'a switch of load control: control = "{s["control"]}" does not use it '
                                    f'(the run goes on without it); remove it, or use control = "load"')
    if s["control"] != "arclength":
        extra = [k for k in ARCLENGTH_DEFAULTS if k in d]
        if extra:
            v.fail(join(key, extra[0]), 'an arc-length control: only with control = "arclength"')
        if "load_factors" in d and s["control"] == "linear":
            v.fail(join(key, "load_factors"), 'a linear analysis (control = "linear") is one solve at lam_end: '
                                              "give lam_end, not load factors")
        if "steps" in d and s["control"] == "linear" and s["steps"] != 1:
            # a warning, not an error: a sweep may switch the control of a file that gives steps
            v.warn(join(key, "steps"), f'a linear analysis (control = "linear") is one solve at lam_end: '
                                       f'steps = {s["steps"]} is not used (one state, no intermediate load steps)')
        if "load_factors" in d:
            both = [k for k in ("steps", "lam_end") if k in d]
            if both:
                v.fail(join(key, both[0]), "give either load_factors or steps and lam_end, not both")
            s["load_factors"] = _load_factors(v, d["load_factors"], join(key, "load_factors"))
            s["steps"], s["lam_end"] = len(s["load_factors"]), s["load_factors"][-1]
        return s
    if "load_factors" in d:
        v.fail(join(key, "load_factors"), 'explicit load factors are for control = "load"; arc length '
                                          "chooses its own (lam_end, dlam0)")
    s.update(v.params(d, key, ARCLENGTH.params))
    if s["dlam0"] is None:
        s["dlam0"] = s["lam_end"] / s["steps"]
    if s["dlam0"] == 0 or s["dlam0"] * s["lam_end"] < 0:
        v.fail(join(key, "dlam0"), f"expected a first load-factor step of the sign of lam_end, got {s['dlam0']:g}")
    if ELEMENTS[s["element"]].stateful:
        v.fail(join(key, "element"), "arc length needs the default (path-independent) element")
    return s


def _petsc_options(v, d, path):
    """[solver.petsc]: free-form PETSc options (name without the dash = number, string or bool)."""
    if not isinstance(d, dict):
        v.fail(path, f"expected a table of PETSc options, got {tname(d)} {show(d)}")
    out = {}
    for k, x in d.items():
        if not isinstance(x, (bool, int, float, str)) or isinstance(x, float) and not math.isfinite(x):
            v.fail(join(path, k), f"expected a number, string or boolean PETSc option value, got {tname(x)} {show(x)}")
        out[str(k).lstrip("-")] = x
    return out


def solve_defaults(s):
    """Problem.solve keywords of a validated [solver] (so that scenario.problem.solve() runs
    the scenario's own settings)."""
    common = dict(rtol=s["rtol"], dtol=s["dtol"], max_iter=s["max_iter"], linear_solver=s["linear_solver"],
                  lam_end=s["lam_end"])
    if s["control"] == "arclength":
        return dict(control="arclength", method=s["method"], dlam0=s["dlam0"], psi=s["psi"],
                    max_steps=s["max_steps"], target_iter=s["target_iter"],
                    ds_max_factor=s["ds_max_factor"], stability=s["stability"],
                    critical_tol=s["critical_tol"], **common)
    if s["control"] == "linear":
        return dict(control="linear", **common)
    out = dict(control="load", max_cutbacks=s["max_cutbacks"], iteration=s["iteration"],
               predictor=s["predictor"], path_check=s["path_check"], limit_check=s["limit_check"],
               critical_tol=s["critical_tol"], max_substeps=s["max_substeps"], snap_check=s["snap_check"],
               inertia_check=s["inertia_check"], end_check=s["end_check"], midpoint_probe=s["midpoint_probe"],
               refine_check=s["refine_check"],
               friction_check=s["friction_check"], friction_tol=s["friction_tol"],
               friction_halving=s["friction_halving"], **common)
    out.update(linear=s.get("linear", "mumps"), petsc_options=dict(s.get("petsc") or {}),
               partition=s.get("partition", "auto"))
    if s.get("load_factors") is not None:
        out.pop("lam_end")
        out["load_factors"] = list(s["load_factors"])
    else:
        out["steps"] = s["steps"]
    return out


def _load_factors(v, x, path):
    """Explicit load factors of the steps: finite, non-zero, strictly monotone from 0."""
    if (not isinstance(x, list) or not x
            or any(isinstance(a, bool) or not isinstance(a, (int, float)) for a in x)):
        v.fail(path, f"expected a non-empty array of numbers, got {tname(x)} {show(x)}")
    lam = [float(a) for a in x]
    if not all(math.isfinite(a) for a in lam):
        v.fail(path, f"expected finite load factors, got {lam}")
    steps = np.diff([0.0] + lam)
    if np.any(steps == 0) or np.any(np.sign(steps) != np.sign(steps[0])):
        v.fail(path, "the load factors must move strictly in one direction from 0 (no repeats, no "
                     f"reversals: trace a path that turns back with arc length), got {lam}")
    return lam


def output_section(v, doc):
    """[output] (scenario.schema.OUTPUT); ``view`` is two or three angles [deg]."""
    d = doc.get("output", {})
    key = "output"
    o = v.section(d, key, OUTPUT)
    if o["picture_steps"] > 1 and not o["vtu"]:
        v.fail(join(key, "picture_steps"), "a picture of several steps is drawn from the VTU files: "
                                            "needs vtu = true")
    if isinstance(d.get("view"), list) and len(d["view"]) == 3:
        o["view"] = v.vector(d, "view", key, n=3)
    else:
        o["view"] = v.vector(d, "view", key, n=2, default=None)
    return o

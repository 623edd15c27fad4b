"""Scenario sections on physics and control: [material] (and per-region values), [fields.NAME]
(the field registry), [[magnets]], [[supports]], [[loads]] (the load registry), [solver] (the
fields and defaults of NewtonOptions / ArcLengthOptions) and [output]."""
from __future__ import annotations

import math

import numpy as np

from ..errors import did_you_mean
from ..fem import ELEMENTS
from ..model import FIELDS, LOADS
from ..model.base import REQUIRED
from ..solvers import ArcLengthOptions, NewtonOptions
from ..solvers.options import ITERATIONS, PREDICTORS
from .geometry import is_line, nodes_ref, region_ref
from .magnetisation import PATTERN_KEYS, pattern_section
from .validate import join, tname, show

__all__ = ["MATERIAL_KEYS", "material_section", "material_index", "fields_section",
           "magnets_section", "supports_section", "loads_section", "solver_section",
           "output_section", "SOLVER_DEFAULTS", "ARCLENGTH_DEFAULTS", "OUTPUT_DEFAULTS",
           "NON_PHYSICAL", "SUPPORT_KEYS"]

MATERIAL_KEYS = ("E", "nu", "h", "shear_factor", "drilling", "rho")
SUPPORT_KEYS = {"clamp": (), "fix": ("dofs",), "rotate": ("axis", "angle", "point", "free", "scale"),
                "prescribed": ("translate", "rotate", "free", "scale")}
MOVING_SUPPORTS = ("rotate", "prescribed")          # supports that move their nodes with the load factor
_NEWTON = NewtonOptions()
_ARC = ArcLengthOptions()
# [solver] keys of both controls; their defaults are NewtonOptions' (arc-length runs of scenario
# files use Newton's tolerances and iteration limit)
SOLVER_DEFAULTS = dict(steps=10, lam_end=1.0, rtol=_NEWTON.rtol, dtol=_NEWTON.dtol,
                       max_iter=_NEWTON.max_iter, max_cutbacks=_NEWTON.max_cutbacks,
                       element="default", linear_solver="auto", control="load",
                       iteration=_NEWTON.iteration, predictor=_NEWTON.predictor)
# arc-length keys, with ArcLengthOptions' defaults (dlam0: lam_end / steps)
ARCLENGTH_DEFAULTS = dict(method=_ARC.method, dlam0=None, max_steps=_ARC.max_steps, psi=_ARC.psi,
                          target_iter=_ARC.target_iter, ds_max_factor=_ARC.ds_max_factor,
                          stability=_ARC.stability)
OUTPUT_DEFAULTS = dict(vtu=True, vtu_every=1, plots=True, picture=True, picture_steps=1, view=None)
# solver keys that do not change the converged states (left out of the --resume fingerprint);
# max_steps only decides where an arc-length path stops, so a resume may raise it
NON_PHYSICAL = ("rtol", "dtol", "max_iter", "max_cutbacks", "linear_solver", "max_steps", "iteration",
                "predictor", "linear", "petsc", "partition")
# [solver] keys of a distributed run (mpirun; docs/PARALLEL.md): serial runs ignore them
PARALLEL_KEYS = dict(linear=("mumps", "gamg", "hypre"), partition=("auto", "ptscotch", "parmetis", "rcb"))


def material_section(v, d, regions):
    key = "material"
    v.table(d, key, MATERIAL_KEYS + ("regions",), required=("E", "nu", "h"))
    out = _material_values(v, d, key, base=None)
    out["regions"] = {}
    reg = d.get("regions", {})
    if not isinstance(reg, dict):
        v.fail(join(key, "regions"), f"expected a table of [material.regions.NAME], got {tname(reg)}")
    for name, t in reg.items():
        k2 = join(join(key, "regions"), name)
        if name not in regions:
            v.fail(k2, f"unknown region {name!r}{did_you_mean(name, regions)}; defined regions: "
                       f"{sorted(regions) or 'none'}")
        v.table(t, k2, MATERIAL_KEYS)
        vals = _material_values(v, t, k2, base=out)
        for other in out["regions"]:
            if np.intersect1d(regions[other], regions[name]).size:
                v.fail(k2, f"material regions {other!r} and {name!r} overlap: an element would get "
                           "two materials")
        out["regions"][name] = vals
    return out


def material_index(spec_material, regions, n_elements):
    """(list of property dicts, (m,) index into it): the material of every element.

    Parameters
    ----------
    spec_material : dict
        The validated [material] section (E, nu, h, shear_factor, drilling, rho and
        ``regions``: name -> the same keys).
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
    >>> base = dict(E=1.0, nu=0.3, h=0.1, shear_factor=1.0, drilling=1.0, rho=None)
    >>> mats, index = material_index(dict(base, regions={"tip": dict(base, E=2.0)}), {"tip": [2, 3]}, 4)
    >>> [m["E"] for m in mats], index.tolist()
    ([1.0, 2.0], [0, 0, 1, 1])
    """
    mats = [{k: spec_material[k] for k in MATERIAL_KEYS}]
    index = np.zeros(n_elements, np.int64)
    for name, vals in spec_material["regions"].items():
        vals = {k: vals[k] for k in MATERIAL_KEYS}
        if vals not in mats:
            mats.append(vals)
        index[regions[name]] = mats.index(vals)
    return mats, index


def _material_values(v, d, key, base):
    b = base or {}
    out = {}
    out["E"] = v.number(d, "E", key, default=b.get("E", REQUIRED), lo=0.0, lo_open=True)
    out["nu"] = v.number(d, "nu", key, default=b.get("nu", REQUIRED), lo=-1.0, lo_open=True, hi=0.5,
                         hi_open=True)
    out["h"] = v.number(d, "h", key, default=b.get("h", REQUIRED), lo=0.0, lo_open=True)
    out["shear_factor"] = v.number(d, "shear_factor", key, default=b.get("shear_factor", 1.0),
                                   lo=0.0, lo_open=True)
    out["drilling"] = v.number(d, "drilling", key, default=b.get("drilling", 1.0), lo=0.0)
    out["rho"] = v.number(d, "rho", key, default=b.get("rho", None), lo=0.0)
    return out


def fields_section(v, doc):
    """[fields.NAME]: type (a key of core_se3.model.FIELDS), scale and the kind's parameters."""
    out = {}
    for name, t in v.names_table(doc, "fields").items():
        key = join("fields", name)
        typ = v.string(t, "type", key, choices=tuple(FIELDS))
        kind = FIELDS[typ]
        v.table(t, key, ("type",) + tuple(p.name for p in kind.params) + ("scale",))
        f = dict(type=typ, scale=v.scale(t, key))
        f.update(v.params(t, key, kind.params))
        if kind.check is not None:
            bad = kind.check(f, set(t))
            if bad is not None:
                v.fail(join(key, bad[0]), bad[1])
        out[name] = f
    return out


def magnets_section(v, doc, regions, fields, mesh=None, base_dir="."):
    out = []
    for i, t in enumerate(v.array_of_tables(doc, "magnets")):
        key = f"magnets[{i}]"
        v.table(t, key, ("Br", "Br_frame", "region", "field", "mu0") + PATTERN_KEYS)
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
        m["mu0"] = v.number(t, "mu0", key, default=None, lo=0.0, lo_open=True)
        if not fields:
            v.fail(key, "a magnet needs an applied field: define one in [fields.NAME]")
        if "field" in t:
            m["field"] = v.string(t, "field", key, choices=tuple(fields))
        elif len(fields) == 1:
            m["field"] = next(iter(fields))
        else:
            v.fail(join(key, "field"), f"several fields are defined ({', '.join(fields)}): name one")
        _refuse_repeat(v, out, m, key, "magnets", "the magnet")
        out.append(m)
    if fields and not out:
        v.fail("fields", "fields are defined but no [[magnets]] use them")
    return out


def supports_section(v, doc, mesh, regions):
    sup = v.array_of_tables(doc, "supports")
    # a free shell may rest on obstacles (friction holds it: the rigid-motion check of the solve
    # counts the contact nodes' restraints and names a motion left free)
    if not sup and not doc.get("obstacles"):
        v.fail("supports", "no supports: the shell could move as a rigid body; add e.g. "
                           '[[supports]] type = "clamp", edge = "x0"')
    out = []
    for i, t in enumerate(sup):
        key = f"supports[{i}]"
        typ = v.string(t, "type", key, choices=tuple(SUPPORT_KEYS))
        v.table(t, key, ("type", "edge", "nodes", "region") + SUPPORT_KEYS[typ])
        s = dict(type=typ, **nodes_ref(v, t, key, mesh, regions=regions))
        if typ == "fix":
            d = t.get("dofs", None)
            if (not isinstance(d, list) or not d
                    or any(isinstance(x, bool) or not isinstance(x, int) or not 0 <= x <= 5 for x in d)):
                v.fail(join(key, "dofs"), "expected a non-empty array of dof numbers 0..5 (0-2 "
                                           f"translations along d1..d3, 3-5 rotations), got {show(d)}")
            s["dofs"] = sorted(set(d))
        elif typ == "rotate":
            s["axis"] = v.vector(t, "axis", key, nonzero=True)
            s["angle"] = v.number(t, "angle", key)
            s["point"] = v.vector(t, "point", key, default=None)
        elif typ == "prescribed":
            s.update(_prescribed(v, t, key))
        if typ in MOVING_SUPPORTS:
            fr = t.get("free", [])
            if not isinstance(fr, list) or any(x not in ("x", "y", "z") for x in fr) or len(set(fr)) != len(fr):
                v.fail(join(key, "free"), f'expected an array of distinct lab axes "x", "y", "z", got {show(fr)}')
            s["free"] = fr
            s["scale"] = v.scale(t, key)
        _refuse_repeat(v, out, s, key, "supports", "the support")
        out.append(s)
    return out


def _prescribed(v, t, key):
    """The motion of a ``type = "prescribed"`` support: ``translate`` [length, at scale 1] and/or
    ``rotate = {axis, angle [rad], point}`` (the nodes' centroid by default); at load factor lam
    x -> p + Q(s angle) (x - p) + s translate, s = scale(lam)."""
    if "translate" not in t and "rotate" not in t:
        v.fail(key, "a prescribed support needs 'translate' = [dx, dy, dz] and/or 'rotate' = {axis, angle, point}")
    out = dict(translate=v.vector(t, "translate", key, default=[0.0, 0.0, 0.0]), rotate=None)
    if "rotate" in t:
        k2 = join(key, "rotate")
        v.table(t["rotate"], k2, ("axis", "angle", "point"), required=("axis", "angle"))
        out["rotate"] = dict(axis=v.vector(t["rotate"], "axis", k2, nonzero=True),
                             angle=v.number(t["rotate"], "angle", k2),
                             point=v.vector(t["rotate"], "point", k2, default=None))
    return out


def _refuse_repeat(v, done, entry, key, section, what):
    """A ScenarioError when ``entry`` repeats an earlier entry of ``section`` exactly (a copy
    that would apply a load twice, or hold the same nodes twice)."""
    for j, other in enumerate(done):
        if other == entry:
            v.fail(key, f"repeats {section}[{j}] exactly: {what} would act twice; remove one (or, for a "
                        "load meant twice, double its value)")


def loads_section(v, doc, mesh, regions):
    """[[loads]]: type (a key of core_se3.model.LOADS), scale, the selection the kind's target
    needs (edge/nodes, or region) and the kind's parameters, checked by its own check."""
    out = []
    for i, t in enumerate(v.array_of_tables(doc, "loads")):
        key = f"loads[{i}]"
        typ = v.string(t, "type", key, choices=tuple(LOADS))
        kind = LOADS[typ]
        nodal = kind.target in ("line", "nodes")
        v.table(t, key, ("type",) + (("edge", "nodes") if nodal else ()) + tuple(p.name for p in kind.params)
                + ("scale",) + (() if nodal else ("region",)))
        ld = dict(type=typ, scale=v.scale(t, key))
        if nodal:
            ld.update(nodes_ref(v, t, key, mesh))
            if kind.target == "line" and "edge" in ld and not is_line(mesh, mesh.edges[ld["edge"]]):
                v.fail(join(key, "edge"), f"node set {ld['edge']!r} is not a line of element edges; "
                                          "an edge load needs one (use type = \"nodal\")")
        ld.update(v.params(t, key, kind.params))
        if kind.check is not None:
            bad = kind.check(ld, set(t))
            if bad is not None:
                v.fail(join(key, bad[0]) if bad[0] else key, bad[1])
        if not nodal:
            _, ld["region"] = region_ref(v, t, key, regions)
        _refuse_repeat(v, out, ld, key, "loads", "the load")
        out.append(ld)
    return out


def solver_section(v, doc):
    """[solver]: control, steps or load_factors, tolerances, element, linear solver and, with
    control = "arclength", the arc-length controls."""
    d = doc.get("solver", {})
    key = "solver"
    v.table(d, key, tuple(SOLVER_DEFAULTS) + ("load_factors",) + tuple(ARCLENGTH_DEFAULTS) + tuple(PARALLEL_KEYS)
            + ("petsc",))
    s = dict(SOLVER_DEFAULTS)
    s["linear"] = v.string(d, "linear", key, default="mumps", choices=PARALLEL_KEYS["linear"])
    s["partition"] = v.string(d, "partition", key, default="auto", choices=PARALLEL_KEYS["partition"])
    s["petsc"] = _petsc_options(v, d.get("petsc", {}), join(key, "petsc"))
    s["control"] = v.string(d, "control", key, default="load", choices=("load", "arclength"))
    s["steps"] = v.integer(d, "steps", key, default=SOLVER_DEFAULTS["steps"], lo=1, hi=100_000)
    s["lam_end"] = v.number(d, "lam_end", key, default=1.0)
    if s["lam_end"] == 0:
        v.fail(join(key, "lam_end"), "expected a non-zero final load factor, got 0")
    for name in ("rtol", "dtol"):
        s[name] = v.number(d, name, key, default=SOLVER_DEFAULTS[name], lo=0.0, lo_open=True, hi=1.0, hi_open=True)
    s["max_iter"] = v.integer(d, "max_iter", key, default=SOLVER_DEFAULTS["max_iter"], lo=1, hi=1000)
    s["max_cutbacks"] = v.integer(d, "max_cutbacks", key, default=SOLVER_DEFAULTS["max_cutbacks"], lo=0, hi=50)
    s["element"] = v.string(d, "element", key, default="default", choices=tuple(ELEMENTS))
    s["linear_solver"] = v.string(d, "linear_solver", key, default="auto",
                                  choices=("auto", "banded", "mumps", "superlu"))
    s["iteration"] = v.string(d, "iteration", key, default=SOLVER_DEFAULTS["iteration"], choices=ITERATIONS)
    s["predictor"] = v.string(d, "predictor", key, default=SOLVER_DEFAULTS["predictor"], choices=PREDICTORS)
    if s["control"] != "arclength":
        extra = [k for k in ARCLENGTH_DEFAULTS if k in d]
        if extra:
            v.fail(join(key, extra[0]), 'an arc-length control: only with control = "arclength"')
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
    s["method"] = v.string(d, "method", key, default=ARCLENGTH_DEFAULTS["method"], choices=("crisfield", "riks"))
    s["dlam0"] = v.number(d, "dlam0", key, default=s["lam_end"] / s["steps"])
    if s["dlam0"] == 0 or s["dlam0"] * s["lam_end"] < 0:
        v.fail(join(key, "dlam0"), f"expected a first load-factor step of the sign of lam_end, got {s['dlam0']:g}")
    s["max_steps"] = v.integer(d, "max_steps", key, default=ARCLENGTH_DEFAULTS["max_steps"], lo=1, hi=100_000)
    s["psi"] = v.number(d, "psi", key, default=ARCLENGTH_DEFAULTS["psi"], lo=0.0)
    s["target_iter"] = v.integer(d, "target_iter", key, default=ARCLENGTH_DEFAULTS["target_iter"], lo=1, hi=100)
    s["ds_max_factor"] = v.number(d, "ds_max_factor", key, default=ARCLENGTH_DEFAULTS["ds_max_factor"], lo=1.0)
    s["stability"] = v.boolean(d, "stability", key, default=ARCLENGTH_DEFAULTS["stability"])
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
                    ds_max_factor=s["ds_max_factor"], stability=s["stability"], **common)
    out = dict(control="load", max_cutbacks=s["max_cutbacks"], iteration=s["iteration"],
               predictor=s["predictor"], **common)
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
    d = doc.get("output", {})
    key = "output"
    v.table(d, key, tuple(OUTPUT_DEFAULTS) + ("dir",))
    o = {}
    o["dir"] = v.string(d, "dir", key, default=None)
    o["vtu"] = v.boolean(d, "vtu", key, default=True)
    o["vtu_every"] = v.integer(d, "vtu_every", key, default=1, lo=1)
    o["plots"] = v.boolean(d, "plots", key, default=True)
    o["picture"] = v.boolean(d, "picture", key, default=True)
    o["picture_steps"] = v.integer(d, "picture_steps", key, default=1, lo=1, hi=50)
    if o["picture_steps"] > 1 and not o["vtu"]:
        v.fail(join(key, "picture_steps"), "a picture of several steps is drawn from the VTU files: "
                                            "needs vtu = true")
    if isinstance(d.get("view"), list) and len(d["view"]) == 3:
        o["view"] = v.vector(d, "view", key, n=3)
    else:
        o["view"] = v.vector(d, "view", key, n=2, default=None)
    return o

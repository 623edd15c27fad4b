"""Runner of the Sze et al. (2004) family (cases in cases_sze.py and ``sze-semicylinder``).

Build: mesh, supports and point/line loads from ``case.extra["shape"]``.  Run: arc-length
continuation (core_se3.solvers) to the end of the published table, or load-stepped
Newton for ``extra["path"] == "load"``.  Measure (``catalogue.measures.curve_deviation``): the deviation

    dev = max_k min over the polyline |(P_k/P_max, u_k/u_max) - table curve|

(the largest distance of a computed point to the tabulated curve, each column normalised by
its largest |value|; max over the case's columns).  It serves snap-throughs and snap-backs,
where a comparison at equal load is ill-defined.
"""
from __future__ import annotations

from math import pi

import numpy as np

from .. import mesh as M
from ..errors import MeshError
from ..fem import Material
from ..model import Problem
from ..results import result_document, step_record
from ..solvers import arc_length
from .case import Family, register_family
from .measures import curve_columns, curve_deviation, table_curves
from .references import literature_entry

__all__ = ["sze_problem", "run_sze", "document", "table_scale", "table_units", "table_comparison", "stop_length_ratio"]


# ------------------------------------------------------------------ build -----------------

def _corner(m, x, y):
    X = m.X
    k = np.nonzero((np.abs(X[:, 0] - x) < 1e-9 * (1 + abs(x))) & (np.abs(X[:, 1] - y) < 1e-9 * (1 + abs(y))))[0]
    if len(k) != 1:
        raise ValueError(f"expected one node at x = {x}, y = {y}, found {len(k)}")
    return int(k[0])


def sze_problem(case, p, mesh=None, element="default", linear_solver="auto"):
    """Problem of a Sze case (see cases_sze.py for geometry, supports and loads): the builder
    of its ``shape`` (:data:`SHAPES`) on its mesh, with the probes and ``control`` (the node and
    direction of the controlled displacement)."""
    shape = case.extra["shape"]
    if shape not in SHAPES:
        raise ValueError(f"unknown Sze shape {shape!r}")
    nx, ny = mesh or case.mesh
    mat = Material(p["E"], p["nu"], p["h"], drilling=p.get("drilling", 1.0))

    def problem(m):
        return Problem(m, mat, element=element, linear_solver=linear_solver)
    return SHAPES[shape](p, nx, ny, problem)


def _probes(prob, control, direction, **probes):
    for name, node in probes.items():
        prob.add_probe(name, [node])
    prob.control = (control, direction)
    return prob


def _roof(p, nx, ny, problem):
    """The hinged cylindrical roof, a quarter with symmetry planes or (``full``) the whole."""
    R, L, th = p["R"], p["L"], p["theta"]
    if bool(p.get("full", 0.0)):
        m = M.cylinder_panel(R, L, -th, th, nx, ny)
        m.g0[:, 1, 3] -= L / 2                           # centre the roof on y = 0
        prob = problem(m)
        prob.fix("x0", (0, 1, 2))
        prob.fix("x1", (0, 1, 2))
        c = _corner(m, 0.0, 0.0)
        prob.add_nodal_load(c, force=(0.0, 0.0, -p["load_max"]))
    else:
        m = M.cylinder_panel(R, L / 2, 0.0, th, nx, ny)
        prob = problem(m)
        # crown line x = 0: u_x (= d1) and rotations about y (d2), z (d3) fixed;
        # mid-length y = 0: u_y (= d2) and rotations about d1, d3 fixed; x1 hinged
        prob.fix("x0", (0, 4, 5))
        prob.fix("y0", (1, 3, 5))
        prob.fix("x1", (0, 1, 2))
        c = _corner(m, 0.0, 0.0)
        prob.add_nodal_load(c, force=(0.0, 0.0, -p["load_max"] / 4))
    return _probes(prob, c, (0.0, 0.0, -1.0), C=c)


def _slit_annulus(p, nx, ny, problem):
    m = M.annulus(p["r_in"], p["r_out"], 2 * pi, nx, ny)
    prob = problem(m)
    prob.clamp("y1")
    prob.add_edge_force("y0", (0.0, 0.0, p["load_max"] * (p["r_out"] - p["r_in"])))
    y0 = m.node_set("y0")
    return _probes(prob, int(y0[-1]), (0.0, 0.0, 1.0), A=int(y0[0]), B=int(y0[-1]))


def _cylinder_octant(p, nx, ny, problem, shape):
    """The pulled-out or pinched cylinder: an octant with its symmetry planes."""
    R, L = p["R"], p["L"]
    m = M.cylinder_panel(R, L / 2, 0.0, pi / 2, nx, ny)
    prob = problem(m)
    # symmetry planes: x = 0 (t = 0: d1 = x) and z = 0 (t = pi/2: d1 = -z): u along d1 and
    # the rotations about d2, d3 fixed; y = L/2 (d2 = y): u_y and rotations about d1, d3
    prob.fix("x0", (0, 4, 5))
    prob.fix("x1", (0, 4, 5))
    prob.fix("y1", (1, 3, 5))
    y1, x1 = m.node_set("y1"), m.node_set("x1")
    A, B, Cn = int(y1[0]), int(y1[-1]), int(x1[0])
    sign = 1.0 if shape == "pullout" else -1.0
    prob.add_nodal_load(A, force=(0.0, 0.0, sign * p["load_max"] / 4))
    if shape == "pullout":
        return _probes(prob, A, (0.0, 0.0, 1.0), A=A, B=B, C=Cn)
    _diaphragm(prob, m, p, R * (pi / 2) / nx)
    return _probes(prob, A, (0.0, 0.0, -1.0), A=A, B=B)


def _diaphragm(prob, m, p, ell):
    """The pinched cylinder's rigid diaphragm at s = 0: lab radial and circumferential
    directions of each node held; with diaphragm_tilt = 1 also the rotation about the cylinder
    axis (the normal stays normal to the circumferential tangent: MacNeal-Harder's
    theta_axis = 0); ``ell``: the node spacing on the ring."""
    y0 = m.node_set("y0")
    g0 = m.g0[y0]
    dirs = np.stack([g0[:, :3, 0], g0[:, :3, 2]], 1)        # reference d1, d3
    k = p["k_diaphragm"] * p["E"] * p["h"]
    prob.add_lab_support(y0, dirs, k)
    if p.get("diaphragm_tilt", 0.0):
        prob.add_lab_tilt_support(y0, g0[:, :3, 0], k * ell ** 2)
    if p.get("diaphragm_theta_axis", 0.0):
        # theta_y = 0 as a total-rotation-vector component (Abaqus' UR2 = 0)
        prob.add_rotation_component_support(y0, (0.0, 1.0, 0.0), k * ell ** 2)


def _hemisphere(p, nx, ny, problem):
    m = M.hemisphere_quarter(p["R"], p["hole_deg"], nx, ny)
    prob = problem(m)
    # y = 0 (f = 0, d2 = +y) and x = 0 (f = pi/2, d2 = -x): u along d2 and the rotations
    # about d1, d3 fixed (the frame may turn about d2 only, which keeps d2 lab-fixed)
    prob.fix("y0", (1, 3, 5))
    prob.fix("y1", (1, 3, 5))
    A, B = int(m.node_set("y0")[-1]), int(m.node_set("y1")[-1])
    prob.add_lab_support([A], [[0.0, 0.0, 1.0]], p["k_pin"] * p["E"] * p["h"])
    prob.add_nodal_load(A, force=(p["load_max"] / 2, 0.0, 0.0))
    prob.add_nodal_load(B, force=(0.0, -p["load_max"] / 2, 0.0))
    return _probes(prob, A, (1.0, 0.0, 0.0), A=A, B=B)


def _semicylinder(p, nx, ny, problem):
    m = M.cylinder_panel(p["R"], p["L"], -pi / 2, pi / 2, nx, ny)
    prob = problem(m)
    prob.clamp("y0")
    # longitudinal edges t = -+pi/2 (d1 = -+z, d2 = +y): the lab u_z and the lab-y component of
    # the total rotation vector held (Abaqus' U3 = UR2 = 0, the reference's reading), by penalties
    # k_pin E h and k_rot E h^3.  Holding body dofs 0 and 4 instead (fix) holds each Newton
    # increment's components in the turning frame, which is not holonomic: the edges turn about
    # d1 and d3, the held rotation drifted by 4.9e-4 rad and the state differed by 3.3e-6 rad
    # between 1 and 160 load steps (errors.SupportWarning).
    for edge in ("x0", "x1"):
        prob.add_lab_support(edge, [[0.0, 0.0, 1.0]], p["k_pin"] * p["E"] * p["h"])
        prob.add_rotation_component_support(edge, (0.0, 1.0, 0.0), p["k_rot"] * p["E"] * p["h"] ** 3)
    y1 = m.node_set("y1")
    if len(y1) % 2 != 1:
        raise MeshError("sze-semicylinder needs an even number of elements around the half-circle "
                        f"(a node at the crown, where the load acts), got {nx} (mesh {nx}x{ny})")
    crown = int(y1[len(y1) // 2])
    prob.add_nodal_load(crown, force=(0.0, 0.0, -p["load_max"]))
    return _probes(prob, crown, (0.0, 0.0, -1.0), crown=crown)


# shape -> builder(p, nx, ny, problem: mesh -> Problem) of the Problem with its probes and control
SHAPES = {"roof": _roof, "slit-annulus": _slit_annulus, "hemisphere": _hemisphere, "semicylinder": _semicylinder,
          "pullout": lambda p, nx, ny, problem: _cylinder_octant(p, nx, ny, problem, "pullout"),
          "pinched": lambda p, nx, ny, problem: _cylinder_octant(p, nx, ny, problem, "pinched")}


# ------------------------------------------------------------------ run -------------------

def run_sze(case, p, prob, steps, **kw):
    """Trace the case's path; returns (document, Result)."""
    x = case.extra
    # monotone paths default to the case's load steps (sze-semicylinder: 40, as fenicsx_ref)
    if x.get("path", "load" if x["shape"] == "semicylinder" else "arc_length") == "load":
        res = prob.solve(steps=steps, **kw)
    else:
        node, direction = prob.control
        stop_at, lam_end = None, 1.0
        if x.get("stop") == "table_end_displacement":
            (_, _, tu), = table_curves(case)[:1]
            stop_at, lam_end = (node, direction, float(tu[-1]) * stop_length_ratio(case, p)), None
        dlam0 = kw.pop("dlam0", x.get("dlam0", 1.0 / max(steps, 1)))
        res = arc_length(prob, lam_end=lam_end, dlam0=dlam0, stop_at=stop_at,
                         ds_max=kw.pop("ds_max", None),
                         ds_max_factor=kw.pop("ds_max_factor", x.get("ds_max_factor", 8.0)),
                         target_iter=kw.pop("target_iter", x.get("target_iter", 5)),
                         psi=kw.pop("psi", x.get("psi", 0.0)), max_steps=kw.pop("max_steps", 400), **kw)
    return document(case, p, prob, res), res


def stop_length_ratio(case, p):
    """The factor on a table's end displacement where a path stops (``stop =
    "table_end_displacement"``): the roof's rise R (1 - cos theta) at the parameters p over the
    table's, so that the path ends at the same point of a roof in other units (every length times
    s: the stop times s; before, mm -> m ran to max_steps past the snap, m -> km stopped after two
    steps) or of another rise (the snap carries the crown to about twice the rise); 1 for a shape
    without R and theta.

    Example
    -------
    >>> from .case import get_case, case_params
    >>> c = get_case("sze-hinged-roof")
    >>> stop_length_ratio(c, case_params(c, None)), round(stop_length_ratio(c, case_params(c, {"R": 2.54})), 15)
    (1.0, 0.001)
    """
    t = {_TABLE_KEYS.get(k, k): v for k, v in literature_entry(case.extra["literature"]).get("parameters", {}).items()}
    if not all(k in t and k in p for k in ("R", "theta")):
        return 1.0
    rise = lambda q: q["R"] * (1.0 - np.cos(q["theta"]))
    return float(rise(p) / rise(t))


# the tables' parameter names (literature.json "parameters") -> the cases' keys; P_max is the
# table's load scale, not a parameter the run must share
_TABLE_KEYS = {"R_inner": "r_in", "R_outer": "r_out", "L_total": "L", "half_angle_rad": "theta",
               "hole_half_angle_deg": "hole_deg"}


def table_units(case, p):
    """(a, f): the length scale of the run ``p`` against its table and the scale of its load
    (``load_max``: a force, f = s a^2; the slit annulus' line force, f = s a), by similarity
    (``cases_shells.similarity``: lengths times a, E times s).  A run in other units (``--set``
    of every dimensional parameter) is the table's problem: its loads are the table's times f,
    its displacements times a.  The penalty factors (``k_pin``, ``k_rot``, ``k_diaphragm``) are
    stiffnesses over E h (E h^3), dimensionless: they carry over unchanged.

    Example
    -------
    >>> from .case import get_case, case_params
    >>> c = get_case("sze-hemisphere")
    >>> a, f = table_units(c, case_params(c, {"R": 10000.0, "h": 40.0, "E": 68.25}))
    >>> round(a, 12), round(f, 12)
    (1000.0, 1.0)
    """
    from .cases_shells import similarity
    t = {_TABLE_KEYS.get(k, k): v for k, v in literature_entry(case.extra["literature"]).get("parameters", {}).items()}
    a, s = similarity(p, t)
    return a, s * a ** (1 if case.units.get("load_max") == "force/length" else 2)


def table_scale(case, p):
    """(P_max, why) of a case's table: P_max the load its P/P_max column is normalised by (the
    published problem's, ``parameters.P_max`` of literature.json; the case's default
    ``load_max`` where the table states none, e.g. s3.8(d)) in the run's units (times the load
    scale of :func:`table_units`), ``why`` "" when the table holds at the parameters p (E, nu,
    h, R, L, ... as published, or all of them in other units), else which one differs.

    Example
    -------
    >>> from .case import get_case, case_params
    >>> c = get_case("sze-hinged-roof")
    >>> table_scale(c, case_params(c, {"load_max": 1000}))
    (3000.0, '')
    >>> table_scale(c, case_params(c, {"h": 6.35}))[1]
    'the reference entry is for h = 12.7, the run has h = 6.35'
    >>> P, why = table_scale(c, case_params(c, {"R": 2.54, "L": 0.508, "h": 0.0127, "E": 3.10275e9}))
    >>> round(P, 9), why
    (3000.0, '')
    """
    from .cases_shells import similar_params
    t = {_TABLE_KEYS.get(k, k): v for k, v in literature_entry(case.extra["literature"]).get("parameters", {}).items()}
    P_max = t.get("P_max", t.get("P_max_per_unit_length", case.params["load_max"]))
    why = similar_params(p, {k: v for k, v in t.items() if not k.startswith("P_max")})
    return float(P_max) * table_units(case, p)[1], why


def table_comparison(case, p, lams, probes):
    """The ``reference`` block of a Sze run and its per-step deviations (None: not compared).

    lams: the steps' load factors (P = lam load_max); probes: per step {probe: u (3,)}.  The
    table's axis is P / P_max with the table's own P_max (:func:`table_scale`); a run in other
    units is compared in the table's (its displacements / ``length_scale``, :func:`table_units`;
    the block's u values are the table's units); at parameters other than the table's nothing is
    compared (``note`` says why).  Points beyond the table's
    largest load on a path stopped by the load (``load_max`` above the table's) are left out
    (``n_beyond_table``); ``path_complete`` is False when the path ended before the table's end
    (the deviation then covers the computed part only).
    """
    P_max, why = table_scale(case, p)
    entry = case.extra["literature"]
    base = dict(entry=entry, file="literature.json", block=",".join(c["column"] for c in curve_columns(case)),
                P_max=P_max, n_points=len(lams))
    if why:
        return dict(base, error=None, deviation=None, note=f"not compared: {why}"), [None] * len(lams)
    a, f = table_units(case, p)
    if (a, f) != (1.0, 1.0):            # a run in other units: the table's displacements x a, loads x f
        base.update(length_scale=a, load_scale=f)
        probes = [{k: np.asarray(u, float) / a for k, u in pr.items()} for pr in probes]
    x = np.asarray(lams, float) * p["load_max"] / P_max
    curves = table_curves(case)
    by_load = case.extra.get("stop") != "table_end_displacement"
    top = max(float(tl.max()) for _, tl, _ in curves)
    keep = (x <= top * (1 + 1e-9)) if by_load else np.ones(len(x), bool)
    dev, per, info = curve_deviation(case, x[keep], [pr for pr, k in zip(probes, keep) if k])
    per_step = np.full(len(x), np.nan)
    per_step[keep] = per
    col = curve_columns(case)[0]
    u_end = col["sign"] * probes[-1][col["probe"]][col["component"]]
    u_tab = float(curves[0][2][-1])
    # by the load: a compared point at the table's largest load (a path run past it by load_max >
    # P_max whose last point inside stops short, e.g. 0.93 of 1, is partial too)
    complete = bool(x[keep].max() >= top * (1 - 1e-9)) if by_load else bool(abs(u_end) >= abs(u_tab) * (1 - 1e-6))
    out = dict(base, error=dev, deviation=dev, curves=info, path_complete=complete,
               n_beyond_table=int((~keep).sum()),
               measure="max distance of computed points to the table polyline in (P/P_max, u/u_max), "
                       "u_max per column")
    if not complete:
        out["note"] = (f"partial: the path ended at P/P_max = {x[-1]:.4g} ({col['column']} = {u_end:.4g}), the "
                       f"table goes to P/P_max = {float(curves[0][1][-1]):.4g} ({u_tab:.4g}); the deviation "
                       f"covers the computed part only (up to P/P_max = {x[keep].max():.4g})")
    return out, [None if np.isnan(d) else float(d) for d in per_step]


def document(case, p, prob, res):
    """Result document (schema core-se3-result) with the curve deviation as the error
    (:func:`table_comparison`)."""
    P_max, _ = table_scale(case, p)
    steps = []
    for st in res.steps:
        value = case.load_value(p, st.load_factor)
        load = dict(name=case.load_name, value=float(value), unit=case.load_unit,
                    reference_entry=case.extra["literature"], reference_value=float(value) / P_max)
        extra = {}
        if st.stability is not None:
            extra["stability"] = dict(det_sign=int(st.stability["det_sign"]),
                                      negative_eigenvalues=st.stability["negative_eigenvalues"])
        steps.append(step_record(st, load, **extra))
    reference, per_step = table_comparison(case, p, [st.load_factor for st in res.steps],
                                           [{k: v["u"] for k, v in st.probes.items()} for st in res.steps])
    for s, d in zip(steps, per_step):
        s["error"] = d
    reference["unverified"] = literature_entry(case.extra["literature"]).get("unverified_fields", [])
    reference["monotonic"] = bool(all(np.all(np.diff(tl) > 0) for _, tl, _ in table_curves(case)))
    t = dict(res.timings)
    t.setdefault("setup", 0.0)
    extra = {}
    if any(st.stability is not None for st in res.steps):        # a path-following result
        extra["critical_points"] = [dict(kind=c.kind, load_factor=c.lam, bracket=list(c.lam_bracket),
                                         step=c.step, negative_eigenvalues=list(c.negative_eigenvalues))
                                    for c in res.critical_points]
    from ..scenario.provenance import problem_provenance
    return result_document(case.name, "core_se3", prob.element_name,
                           {k: dict(value=v, unit=case.units.get(k, "")) for k, v in p.items()},
                           prob.mesh, steps, t, reference, provenance=problem_provenance(prob, res), **extra)


def plot(case, p, doc, res, path):
    from ..io.plots import new_figure, save_figure
    fig = new_figure()
    ax = fig.add_subplot(111)
    ref = doc["reference"]
    x = np.array([s["load"]["reference_value"] for s in doc["steps"]])          # P / P_max of the table
    for (col, tl, tu), c in zip(table_curves(case), curve_columns(case)):
        u = np.array([c["sign"] * s["probes"][c["probe"]]["u"][c["component"]] for s in doc["steps"]])
        line, = ax.plot(u, x, "o-", ms=3, label=f"core_se3 {col}")
        ax.plot(tu * ref.get("length_scale", 1.0), tl, "--", color="k" if len(curve_columns(case)) == 1 else line.get_color(), lw=1,
                label=f"Sze 2004 {col}")
    for cp in doc.get("critical_points", []):
        ax.axhline(cp["load_factor"] * p["load_max"] / ref["P_max"], color="0.8", lw=0.6)
    ax.set_xlabel("displacement")
    ax.set_ylabel(f"P / P_max  (P_max = {ref['P_max']:g})")
    dev = ref["deviation"]
    ax.set_title(f"{case.name} ({doc['mesh']['nx']}x{doc['mesh']['ny']}): "
                 + (ref["note"] if dev is None else f"deviation {100 * dev:.2f} %"
                    + ("" if ref["path_complete"] else " (partial path)")))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    save_figure(fig, path, dpi=120, bbox_inches="tight")      # atomic: a failed save keeps the earlier image


def report(doc):
    ref = doc["reference"]
    if ref["deviation"] is None:
        return [f"curve deviation: {ref['note']}"]
    lines = [f"curve deviation (max distance to the table polyline in (P/P_max, u/u_max), P_max = "
             f"{ref['P_max']:g}): {100 * ref['deviation']:.2f} % over {ref['n_points']} points"]
    if ref.get("note"):
        lines.append(f"  {ref['note']}")
    if ref.get("n_beyond_table"):
        lines.append(f"  {ref['n_beyond_table']} points beyond the table's largest load left out")
    for c in ref["curves"]:
        lines.append(f"  {c['column']}: {100 * c['deviation']:.2f} % (worst at P/P_max = "
                     f"{c['at']['P_over_Pmax']:.4g}, u = {c['at']['u']:.4g}); end computed "
                     f"({c['computed_end']['P_over_Pmax']:.4g}, {c['computed_end']['u']:.4g}), "
                     f"table ({c['table_end']['P_over_Pmax']:.4g}, {c['table_end']['u']:.4g})")
    scale = doc["params"]["load_max"]["value"] / ref["P_max"]
    for cp in doc.get("critical_points", []):
        lines.append(f"  {cp['kind']} point at P/P_max ~ {scale * cp['load_factor']:.5g} (bracket "
                     f"{scale * cp['bracket'][0]:.5g} .. {scale * cp['bracket'][1]:.5g})")
    lines += _snaps_note(doc, scale)
    if ref.get("unverified"):
        lines.append(f"  table fields marked unverified: {ref['unverified']}")
    return lines


def _snaps_note(doc, scale=1.0):
    """The report's note on limit points of a path whose reference curve has none (its load rises
    monotonically): snaps of the discrete model, each with its drop in P/P_max (``scale``: P/P_max
    per load factor).  The pinched
    cylinder's 16x16 octant has four such snaps between P/P_max 0.145 and 0.319 (drops up to 0.022),
    its 24x24 and 48x48 none (docs/PATHFOLLOWING.md)."""
    cps = [c for c in doc.get("critical_points", []) if c["kind"] == "limit"]
    if not cps or not doc["reference"].get("monotonic"):
        return []
    drops = [f"{scale * a['load_factor']:.4g} -> {scale * b['load_factor']:.4g}" for a, b in zip(cps, cps[1:])
             if b["load_factor"] < a["load_factor"] and b["step"] > a["step"]
             and a["negative_eigenvalues"][0] == b["negative_eigenvalues"][1]]
    return [f"  the reference curve has no limit point (its load rises monotonically): these are snaps of "
            f"this discrete model (P/P_max {', '.join(drops) or 'see above'}), local buckling that a finer "
            "mesh may remove (docs/PATHFOLLOWING.md, the Sze suite)"]


register_family("sze", Family(build=sze_problem, run=run_sze, plot=plot, report=report))

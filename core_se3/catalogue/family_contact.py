"""Runner of the contact catalogue cases (``cases_contact``): build, solve, measure, report, plot.

Every step of a result document carries ``contact`` (the total lab force on the shell of each
obstacle, ``results.document.step_record``) and ``measures``:

* ``contact-lift``: ``lifted_length`` (the detachment line located between the nodes from the gap
  field, ``measures.lifted_length_from_gaps``), ``lift_force`` (the vertical reaction at x0), the
  small-deflection formulas and the elastica (``data/contact_lift_elastica.json``) with the
  relative differences, the penetration and the end's tangent angle;
* ``contact-propped``: the tip reaction ``R`` (the total contact force), the formula, the nodes
  that carry force and the smallest gap off the tip;
* ``magnetic-gripper-grasp``: the force on the sphere (minus the force on the shell), the nodes
  in contact, the penetration.
"""
from __future__ import annotations

import numpy as np

from .. import mesh as M
from ..fem import Material
from ..model import Problem
from ..results import restore_multipliers
from .case import Family, get_case, register_family
from .family_magnetic import build as magnetic_build
from .generic import case_document
from .measures import lifted_length_from_gaps
from .references import contact_lift_elastica
from .spline import CubicSpline

__all__ = ["strip_EI", "lift_formula", "lift_elastica", "propped_formula", "propped_mismatch", "contact_of",
           "PROPPED_GEOMETRIC_ERROR"]


def strip_EI(p):
    """E w h^3 / (12 (1 - nu^2)) of a strip case [force length^2] (the beam's EI for nu = 0).

    Example
    -------
    >>> round(strip_EI(dict(E=1.2e6, nu=0.0, width=0.05, h=0.01)), 12)
    0.005
    """
    return p["E"] * p["width"] * p["h"] ** 3 / (12.0 * (1.0 - p["nu"] ** 2))


def lift_formula(p, delta):
    """Small-deflection lifted length l = (24 EI delta / q_l)^(1/4) [length] and lift force
    q_l l / 2 [force] (q_l = q w).

    Example
    -------
    >>> [round(v, 6) for v in lift_formula(dict(E=1.2e6, nu=0.0, width=0.05, h=0.01, q=2.0), 0.01)]
    [0.330975, 0.016549]
    """
    ql = p["q"] * p["width"]
    l = (24.0 * strip_EI(p) * delta / ql) ** 0.25
    return l, ql * l / 2.0


def lift_elastica(p, delta):
    """The elastica reference at lift delta: dict(l, F, tip_angle, interpolated) [length, force,
    rad], from the table's rows scaled by ell_q = (EI / q_l)^(1/3) (interpolated by a cubic
    spline in delta / ell_q between rows), or None outside the table.

    Example
    -------
    >>> ref = lift_elastica(dict(E=1.2e6, nu=0.0, width=0.05, h=0.01, q=2.0, L=1.0), 0.2)
    >>> round(ref["l"], 6), round(ref["F"], 7), ref["interpolated"]
    (0.717426, 0.0370879, False)
    """
    tab = contact_lift_elastica()
    Q = tab["params"]["Q"]
    ql = p["q"] * p["width"]
    ell = (strip_EI(p) / ql) ** (1.0 / 3.0)
    r = Q ** (1.0 / 3.0)                                   # L / ell_q of the table
    rows = tab["rows"]
    x = np.array([row["delta_over_L"] * r for row in rows])          # delta / ell_q
    cols = {k: np.array([row[c] * (r if c != "tip_angle_rad" else 1.0) for row in rows])
            for k, c in (("l", "l_over_L"), ("F", "lift_force_over_qlL"), ("tip_angle", "tip_angle_rad"))}
    t = delta / ell
    if not x[0] * (1 - 1e-12) <= t <= x[-1] * (1 + 1e-12):
        return None
    hit = np.nonzero(np.abs(x - t) <= 1e-9 * t)[0]
    out = {}
    for k, v in cols.items():
        val = float(v[hit[0]]) if len(hit) else float(CubicSpline(x, v)(t))
        out[k] = val * (ell if k == "l" else ql * ell if k == "F" else 1.0)
    out["interpolated"] = not len(hit)
    return out


def propped_formula(p, lam):
    """Tip reaction R = 3 EI (q_l L^4 / (8 EI) - g) / L^3 at load factor lam, 0 before contact.

    Example
    -------
    >>> round(propped_formula(dict(E=1.2e6, nu=0.0, width=0.05, h=0.01, q=0.016, g=0.01, L=1.0), 1.0), 12)
    0.00015
    """
    EI = strip_EI(p)
    w_free = lam * p["q"] * p["width"] * p["L"] ** 4 / (8.0 * EI)
    return max(0.0, 3.0 * EI * (w_free - p["g"]) / p["L"] ** 3)


def contact_of(prob, name=None):
    """The problem's contact load (named ``name``, default the first).

    Example
    -------
    >>> from core_se3.catalogue import build_problem, case_params
    >>> case = get_case("contact-propped")
    >>> contact_of(build_problem(case, case_params(case), (4, 1))).name
    'plane'
    """
    loads = [ld for ld in prob.loads if getattr(ld, "kind", "") == "contact"]
    return next(ld for ld in loads if name is None or ld.name == name)


def _strip(case, p, mesh, element, linear_solver):
    nx, ny = mesh or case.mesh
    return Problem(M.rectangle(p["L"], p["width"], nx, ny), Material(p["E"], p["nu"], p["h"]),
                   element=element, linear_solver=linear_solver)


def build(case, p, mesh, element, linear_solver):
    if case.name == "contact-lift":
        prob = _strip(case, p, mesh, element, linear_solver)
        prob.add_pressure(p["q"], direction=(0.0, 0.0, -1.0), scale=lambda lam: 1.0)
        g_edge = prob.mesh.g0[prob.mesh.node_set("x0")].copy()

        def target(lam, delta=p["delta"]):
            t = g_edge.copy()
            t[:, 2, 3] += lam * delta
            return t
        # the translations of the lifted edge follow the target; its rotation is free
        prob.prescribe("x0", target, fixed=(True, True, True, False, False, False))
        prob.add_obstacle("half_space", point=(0.0, 0.0, -p["h"] / 2), normal=(0.0, 0.0, 1.0), name="floor")
        prob.add_probe("lifted_end", "x0")
        return prob
    if case.name == "contact-propped":
        prob = _strip(case, p, mesh, element, linear_solver)
        prob.clamp("x0")
        prob.add_pressure(p["q"], direction=(0.0, 0.0, -1.0))
        prob.add_obstacle("half_space", point=(0.0, 0.0, -p["h"] / 2 - p["g"]), normal=(0.0, 0.0, 1.0),
                          name="plane")
        prob.add_probe("tip", "x1")
        return prob
    if case.name == "magnetic-gripper-grasp":
        prob = magnetic_build(get_case("magnetic-gripper"), p, mesh, element, linear_solver)
        prob.add_obstacle("sphere", centre=(0.0, 0.0, p["h"] / 2 + p["gap"] + p["radius"]), radius=p["radius"],
                          name="sphere")
        return prob
    raise KeyError(f"no contact builder for case {case.name!r}")


def _columns(mesh):
    """Reference x of the node columns of a structured strip and the node ids of each."""
    x = mesh.X[:, 0]
    xs, inv = np.unique(np.round(x / (np.ptp(x) or 1.0), 12), return_inverse=True)
    cols = [np.nonzero(inv == k)[0] for k in range(len(xs))]
    return np.array([x[c].mean() for c in cols]), cols


def _rel(a, b):
    return None if b is None or b == 0 or not np.isfinite(a) else float(a / b - 1.0)


def _lift_measures(prob, p, st, cols):
    c = contact_of(prob)
    xc, groups = cols
    lam = st.load_factor
    gap = np.zeros(prob.mesh.n_nodes)
    fz = np.zeros(prob.mesh.n_nodes)
    gap[c.nodes] = c.gaps(st.g, lam)
    fz[c.nodes] = c.nodal_forces(st.g, lam)[0][:, 2]
    cg = np.array([gap[k].mean() for k in groups])
    cf = np.array([fz[k].sum() for k in groups])
    xd, nfit = lifted_length_from_gaps(xc, cg, cf)
    delta = lam * p["delta"]
    l = float(xd - xc[0])
    F = float(st.reaction_force[2])
    out = dict(delta=delta, lifted_length=l, lift_force=F, columns_fitted=nfit,
               horizontal_reaction=float(st.reaction_force[0]), penetration=c.penetration(st.g, lam))
    R = st.g[prob.mesh.node_set("x0"), :3, :3]
    out["end_angle"] = float(np.mean(np.arctan2(-R[:, 2, 0], R[:, 0, 0])))
    if delta > 0 and p["nu"] != 0.0:
        out["not_compared"] = _NU_NOTE.format(nu=p["nu"])
    elif delta > 0:
        lf, Ff = lift_formula(p, delta)
        out.update(l_formula=lf, F_formula=Ff, l_error_formula=_rel(l, lf), F_error_formula=_rel(F, Ff))
        el = lift_elastica(p, delta)
        if el is not None:
            out.update(l_elastica=el["l"], F_elastica=el["F"], end_angle_elastica=el["tip_angle"],
                       elastica_interpolated=el["interpolated"], l_error_elastica=_rel(l, el["l"]),
                       F_error_elastica=_rel(F, el["F"]))
    return out


def _propped_measures(prob, p, st):
    c = contact_of(prob)
    lam = st.load_factor
    F, _ = c.nodal_forces(st.g, lam)
    d = c.gaps(st.g, lam)
    tip = prob.mesh.node_set("x1")
    on_tip = np.isin(c.nodes, tip)
    R, Rf = float(F[:, 2].sum()), propped_formula(p, lam)
    out = dict(R=R, R_formula=Rf, R_error=_rel(R, Rf), nodes_with_force=c.nodes[F[:, 2] > 0].tolist(),
               tip_nodes=tip.tolist(), min_gap_off_tip=float(d[~on_tip].min()), penetration=c.penetration(st.g, lam))
    why = propped_mismatch(p, lam)
    if why:
        out.update(R_formula=None, R_error=None, not_compared=why)
    return out


_NU_NOTE = ("not compared: the formulas and the elastica are for a beam (EI = E w h^3/12, the strip's "
            "exact reduction at nu = 0); at nu = {nu:g} the strip's stiffness lies between that and the plate's")


# The propped formula is small-deflection beam theory: in contact the tip is held g below its
# start, and the rotations shift R by about -0.85 (g/L)^2 3 EI g / L^3 whatever the load (40x1,
# the tip only touching, 20 steps to q_l L^4/(8 EI) = 2 g: R -2.9 % at lam = 1 and -34 % at 0.55
# for g/L = 0.2; -0.66 / -8.2 % at 0.1; -0.13 / -2.1 % at 0.05; +0.022 / -0.029 % at the default
# 0.01, its mesh's error), so relative to R = 3 EI (w - g)/L^3 (w = q_l L^4/(8 EI)) it is about
# 0.85 (g/L)^2 g/(w - g): compared while that is below PROPPED_GEOMETRIC_ERROR.
PROPPED_GEOMETRIC_ERROR = 2e-3


def propped_mismatch(p, lam):
    """"" when the propped formula (:func:`propped_formula`) holds at load factor lam, else why
    not: nu != 0 (the beam is the strip only at nu = 0), the free deflection so large that
    the strip rests on the plane beyond its tip (tip-only contact needs q_l L^4 / (72 EI) <= g,
    docs/CONTACT.md; g = 0.001 at lam = 1: R 27 % above the formula, 16 nodes touching), or the
    rotations' effect on R, about 0.85 (g/L)^2 g/(q_l L^4/(8 EI) - g), above
    PROPPED_GEOMETRIC_ERROR (small deflection: g = 0.2 L, the tip only touching, R 2.9 % below
    the formula at q_l L^4/(8 EI) = 2 g, 34 % below at 1.1 g).

    Example
    -------
    >>> from .cases_contact import PROPPED_PARAMS
    >>> propped_mismatch(PROPPED_PARAMS, 1.0), propped_mismatch(dict(PROPPED_PARAMS, g=0.001), 0.5)[:45]
    ('', 'not compared: the formula holds while only th')
    """
    if p["nu"] != 0.0:
        return _NU_NOTE.format(nu=p["nu"])
    w72 = lam * p["q"] * p["width"] * p["L"] ** 4 / (72.0 * strip_EI(p))
    if w72 > p["g"] * (1 + 1e-12):
        return (f"not compared: the formula holds while only the tip touches (q_l L^4/(72 EI) <= g); here "
                f"q_l L^4/(72 EI) = {w72:.4g} > g = {p['g']:g}")
    over = lam * p["q"] * p["width"] * p["L"] ** 4 / (8.0 * strip_EI(p)) - p["g"]      # w - g
    est = 0.85 * (p["g"] / p["L"]) ** 2 * p["g"] / over if over > 0 else 0.0
    if est > PROPPED_GEOMETRIC_ERROR:
        return (f"not compared: the formula is small-deflection beam theory; in contact the tip is held "
                f"g/L = {p['g'] / p['L']:.3g} below its start, and the rotations' effect on R, about "
                f"0.85 (g/L)^2 g/(q_l L^4/(8 EI) - g), is {est:.2%} here (compared below "
                f"{PROPPED_GEOMETRIC_ERROR:.1%})")
    return ""


def _grasp_measures(prob, p, st):
    c = contact_of(prob)
    lam = st.load_factor
    F, _ = c.nodal_forces(st.g, lam)
    on = np.linalg.norm(F, axis=1) > 0
    rep = c.report(st.g, lam)
    return dict(force_on_sphere=(-c.total(st.g, lam)[0]).tolist(), nodes_in_contact=int(on.sum()),
                faces_in_contact=int(rep.get("faces_in_contact", 0)),
                penetration=c.penetration(st.g, lam), tip_z=float(st.probes["tip"]["u"][2]) if "tip" in st.probes
                else None)


def run(case, p, prob, steps, **kw):
    kw.setdefault("predictor", "tangent")      # the lifted edge carries the strip (no kink, no fold)
    res = prob.solve(steps=steps, **kw)
    doc = case_document(case, p, prob, res)
    cols = _columns(prob.mesh) if case.name == "contact-lift" else None
    doc["steps"][0]["balance_error"] = 0.0          # the start state, not an equilibrium
    for rec, st in zip(doc["steps"], res.steps):
        restore_multipliers(prob, st)             # the contact forces of that step
        if case.name == "contact-lift":
            rec["measures"] = _lift_measures(prob, p, st, cols)
        elif case.name == "contact-propped":
            rec["measures"] = _propped_measures(prob, p, st)
        else:
            rec["measures"] = _grasp_measures(prob, p, st)
    c = contact_of(prob)
    res.obstacles = [ld.obstacle for ld in prob.loads if getattr(ld, "kind", "") == "contact"]   # for plot
    doc["contact_summary"] = dict(
        obstacle=c.name, kind=c.obstacle.kind, mode=c.mode, tolerance=c.tol, band=c.eps,
        max_penetration=max(s["measures"]["penetration"] for s in doc["steps"][1:]) if len(doc["steps"]) > 1 else 0.0,
        max_balance_error=max(s["balance_error"] for s in doc["steps"][1:]) if len(doc["steps"]) > 1 else 0.0)
    return doc, res


def case_load(s):
    """'NAME VALUE' of a step record's load."""
    return f"{s['load']['name']} {s['load']['value']:.4g}"


def report(doc):
    lines = []
    cs = doc.get("contact_summary") or {}
    if cs:
        lines.append(f"contact with {cs['obstacle']} ({cs['kind']}, {cs['mode']}): max penetration "
                     f"{cs['max_penetration']:.2e} (tolerance {cs['tolerance']:.2e}), balance {cs['max_balance_error']:.1e}")
    for s in doc["steps"][1:]:
        m = s.get("measures", {})
        if "lifted_length" in m and "l_formula" in m:
            line = (f"delta {m['delta']:.4g}: l {m['lifted_length']:.6g} (formula {m['l_formula']:.6g}, "
                    f"{100 * (m['l_error_formula'] or 0):+.3f}%), lift force {m['lift_force']:.6g} (formula "
                    f"{m['F_formula']:.6g}, {100 * (m['F_error_formula'] or 0):+.3f}%)")
            if "l_elastica" in m:
                line += (f"; elastica l {m['l_elastica']:.6g} ({100 * m['l_error_elastica']:+.3f}%), F "
                         f"{m['F_elastica']:.6g} ({100 * m['F_error_elastica']:+.3f}%)")
            lines.append(line)
        elif "not_compared" in m:
            lines.append(f"{case_load(s)}: {m['not_compared']}")
        elif "R_formula" in m:
            err = "" if m["R_error"] is None else f" ({100 * m['R_error']:+.3f}%)"
            lines.append(f"q {s['load']['value']:.4g}: tip reaction {m['R']:.6g}, formula {m['R_formula']:.6g}{err}")
        elif "force_on_sphere" in m:
            F = m["force_on_sphere"]
            lines.append(f"Ba {s['load']['value']:.4g} T: force on the sphere ({F[0]:.4g}, {F[1]:.4g}, {F[2]:.4g}), "
                         f"{m['nodes_in_contact']} nodes and {m.get('faces_in_contact', 0)} faces in contact")
    return lines


def plot(case, p, doc, res, path):
    from ..io import obstacle_surfaces, plot_load_deflection, plot_shell
    steps = doc["steps"][1:]
    x = np.array([s["load"]["value"] for s in steps])
    if case.name == "contact-lift":
        curves = {"lifted length": np.array([s["measures"]["lifted_length"] for s in steps])}
        ref = {"lifted length": (x, np.array([s["measures"].get("l_formula", np.nan) for s in steps]))}
        xl = "lifted length [length]"
    elif case.name == "contact-propped":
        curves = {"tip reaction": np.array([s["measures"]["R"] for s in steps])}
        ref = {"tip reaction": (x, np.array([np.nan if s["measures"]["R_formula"] is None else s["measures"]["R_formula"]
                                             for s in steps]))}
        xl = "tip reaction [force]"
    else:
        curves = {"force on the sphere": np.array([np.linalg.norm(s["measures"]["force_on_sphere"]) for s in steps])}
        ref, xl = None, "contact force [N]"
    plot_load_deflection(path, x, curves, reference=ref, axes=(xl, f"{case.load_name} [{case.load_unit}]"),
                         title=case.name)
    shape = path[:-4] + "_shape.png" if path.endswith(".png") else path + "_shape.png"
    m = res.mesh
    g = res.final.g
    plot_shell(shape, m.X, m.quads, g, title=f"{case.name}: final shape",
               surfaces=obstacle_surfaces(getattr(res, "obstacles", []), g[:, :3, 3], res.final.load_factor))


register_family("contact", Family(build=build, run=run, plot=plot, report=report))

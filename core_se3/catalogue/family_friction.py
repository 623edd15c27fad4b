"""Runner of the friction catalogue cases (``cases_friction``): build, solve, measure, report, plot.

Every step of a result document carries ``contact`` (with the normal and tangential totals and
the stick/slip counts of the rough obstacle) and ``measures``:

* ``friction-pushed-cantilever``: the wall's travel s, the end's lateral displacement u and the
  lateral force H against the exact min(s, s*) and min(s / f, mu P), the normal force against P;
* ``friction-gripper-hold``: the force with which the grasp holds the sphere back (``hold``), the
  bound sum_i N_i (n_z,i + mu sqrt(1 - n_z,i^2)) and mu sum_i N_i of the normal forces N_i
  (normals n_i from the sphere at the contact points, z the pull);
* the walkers: the centroid's displacement along x, the feet's, the highest point; the
  document's ``walk`` has the displacement of every cycle (the centroid between cycle ends), the
  largest motion of a node over one stored step (a snap shows as a good part of L: the
  solver's limit check is re-based where contact changes, so it does not see one) and the
  quasi-static check of the last cycle (``quasi_static``).
"""
from __future__ import annotations

import warnings

import numpy as np

from .. import mesh as M
from ..errors import AccuracyWarning
from ..fem import Material
from ..model import Problem
from ..model.fields import UniformField
from ..results import restore_multipliers
from .case import Family, get_case, register_family
from .cases_friction import RAMP, push_formula, push_wall, walker_field
from .family_contact import contact_of
from .family_magnetic import MU0_MM, build as magnetic_build
from .generic import case_document

__all__ = ["walker_problem", "walk_measures", "quasi_static_check", "quasi_static_warning", "hold_bound", "QS_FRICTION"]


def _strip(p, mesh, element, linear_solver):
    nx, ny = mesh
    return Problem(M.rectangle(p["L"], p["width"], nx, ny), Material(p["E"], p["nu"], p["h"]),
                   element=element, linear_solver=linear_solver)


def walker_problem(p, mesh=(20, 1), element="default", linear_solver="auto"):
    """The walker of ``cases_friction`` at parameters p: a free strip on a rough floor under its
    weight, its rear half magnetised along +x, its front half along -x (Br), both with mz Br
    through the thickness, in the field :func:`~core_se3.catalogue.cases_friction.walker_field`.

    Example
    -------
    >>> from core_se3.catalogue.cases_friction import WALKER_PARAMS
    >>> prob = walker_problem(WALKER_PARAMS, (8, 1))
    >>> [ld.kind for ld in prob.loads if getattr(ld, "kind", "") == "contact"], sorted(prob.probes)
    (['contact'], ['centre', 'front', 'rear'])
    """
    prob = _strip(p, mesh, element, linear_solver)
    prob.add_gravity(rho=p["rho"], g=(0.0, 0.0, -p["g"]), scale=lambda lam: 1.0)
    xc = prob.mesh.X[prob.mesh.quads].mean(1)[:, 0]
    Br = np.zeros((prob.mesh.n_elements, 3))
    Br[:, 0] = p["Br"] * np.where(xc < p["L"] / 2, 1.0, -1.0)
    Br[:, 2] = p["mz"] * p["Br"]
    path = walker_field(p)
    scale = max(p["B0"], p["Bx"], 1e-300)

    def direction(lam):
        # where the field is zero (the start) its direction is the one it takes next: the
        # direction is continuous (a jump would be split into sub-steps without end)
        for at in (lam, lam + 1e-9, 0.5 + 1e-9, 1.0):
            B = path(at)
            if np.any(B != 0.0):
                return B
        return np.array([0.0, 0.0, 1.0])
    field = UniformField((0.0, 0.0, scale), scale=lambda lam: float(np.linalg.norm(path(lam))) / scale,
                         direction=direction)
    prob.add_magnetic(Br, field, mu0=MU0_MM)
    prob.add_obstacle("half_space", point=(0.0, 0.0, -p["h"] / 2), normal=(0.0, 0.0, 1.0), name="floor",
                      friction=p["mu"])
    X = prob.mesh.X[:, 0]
    prob.add_probe("rear", "x0")
    prob.add_probe("front", "x1")
    prob.add_probe("centre", np.nonzero(np.abs(X - X[np.argmin(np.abs(X - p["L"] / 2))]) < 1e-12)[0])
    return prob


def build(case, p, mesh, element, linear_solver):
    mesh = mesh or case.mesh
    if case.name == "friction-pushed-cantilever":
        r = push_formula(p)
        prob = _strip(p, mesh, element, linear_solver)
        prob.fix("x0", (1, 2, 3, 4, 5))                 # the root slides along the axis, under P
        prob.add_edge_force("x0", (r["P"], 0.0, 0.0), scale=lambda lam: min(lam / RAMP, 1.0))
        prob.add_obstacle("half_space", point=(p["L"], 0.0, 0.0), normal=(-1.0, 0.0, 0.0), nodes="x1", side=0,
                          name="wall", friction=p["mu"],
                          motion=dict(translate=(0.0, 0.0, r["travel"]),
                                      scale=lambda lam: max(0.0, (lam - RAMP) / (1.0 - RAMP))))
        prob.add_probe("tip", "x1")
        return prob
    if case.name == "friction-gripper-hold":
        prob = magnetic_build(get_case("magnetic-gripper"), p, mesh, element, linear_solver)
        prob.loads[0].field.scale = lambda lam: min(2.0 * lam, 1.0)
        prob.add_obstacle("sphere", centre=(0.0, 0.0, p["h"] / 2 + p["gap"] + p["radius"]), radius=p["radius"],
                          name="sphere", friction=p["mu"],
                          motion=dict(translate=(0.0, 0.0, p["lift"]), scale=lambda lam: max(0.0, 2.0 * lam - 1.0)))
        return prob
    return walker_problem(p, mesh, element, linear_solver)


def load_factors(case, p, steps):
    """The stored load factors of a run with ``steps`` (the case's meaning of them)."""
    if case.name == "friction-pushed-cantilever":
        return [RAMP / 2, RAMP] + [RAMP + (1 - RAMP) * k / steps for k in range(1, steps + 1)]
    if case.name == "friction-gripper-hold":
        return [0.05 * k for k in range(1, 11)] + [0.5 + 0.5 * k / steps for k in range(1, steps + 1)]
    n = int(round(p["cycles"]))
    return [0.1 * k for k in range(1, 11)] + [1.0 + k / steps for k in range(1, steps * n + 1)]


def _push_measures(prob, p, st, r):
    lam = st.load_factor
    c = st.contact["wall"]
    s = push_wall(p, lam)
    tip = prob.mesh.node_set("x1")
    u = float(st.g[tip, 2, 3].mean())
    H, N = c["force"][2], -c["force"][0]              # on the shell: across the strip and along it
    H_ex, u_ex = min(s / r["f"], p["mu"] * r["P"]), min(s, r["s_star"])
    out = dict(s=s, u=u, u_exact=u_ex, H=H, H_exact=H_ex, N=N, N_exact=r["P"] * min(lam / RAMP, 1.0),
               regime="press" if s == 0 else "stick" if s < r["s_star"] else "slip")
    if p["nu"] != 0.0:
        out.update(u_exact=None, H_exact=None, not_compared=NU_NOTE.format(nu=p["nu"]))
    elif s > 0:
        out.update(u_error=u / u_ex - 1.0, H_error=H / H_ex - 1.0)
    return out


# the beam-column formula (EI = E w h^3/12) is the strip's exact reduction at nu = 0 only: at
# nu = 0.3 the stick-regime H was reported 0.83 % off (0.075 % at nu = 0)
NU_NOTE = ("not compared: the beam-column formula (EI = E w h^3/12) is exact for the strip at nu = 0 "
           "only; the run has nu = {nu:g}")


def hold_bound(c, g, lam, mu):
    """(hold, bound, mu sum N, sum N) of the sphere at (g, lam): the force [N] with which the
    contact holds it against a pull along +z, and the bounds of the normal forces
    (``friction-gripper-hold``)."""
    x, d, n, H, pp, dp = c.state(g, lam)
    N = c.A * pp
    nz = n[:, 2]                                   # the sphere's outward normal at the contact, along z
    bound = float(np.sum(N * (nz + mu * np.sqrt(np.maximum(0.0, 1.0 - nz ** 2)))))
    hold = float(c.total(g, lam)[0][2])            # the force on the shell: the sphere pulls it up
    return hold, bound, float(mu * N.sum()), float(N.sum())


def _hold_measures(prob, p, st):
    c = contact_of(prob, "sphere")
    hold, bound, muN, N = hold_bound(c, st.g, st.load_factor, p["mu"])
    rep = st.contact["sphere"]
    return dict(lift=p["lift"] * max(0.0, 2 * st.load_factor - 1), hold=hold, bound=bound, mu_sum_N=muN, sum_N=N,
                ratio=hold / bound if bound > 0 else None, sticking=rep.get("sticking", 0),
                slipping=rep.get("slipping", 0))


def walk_measures(prob, st, X0):
    """Per step of a walker: the centroid's x displacement, the rear and front feet's, the
    highest point [mm]."""
    u = st.g[:, :3, 3] - X0
    return dict(centroid_ux=float(u[:, 0].mean()), rear_ux=float(st.probes["rear"]["u"][0]),
                front_ux=float(st.probes["front"]["u"][0]), z_max=float(st.g[:, 2, 3].max()))


QS_FRICTION = 0.1
"""The walker's quasi-static check: the time the floor's friction mu m g needs to make the
centroid's velocity changes over a cycle may be at most this fraction of the period
(``quasi_static_check``), else an AccuracyWarning."""


def quasi_static_check(prob, p, steps_g, dlam):
    """The quasi-static assumption over one cycle of period ``period`` stored as ``steps_g``
    (frames at equal load-factor steps dlam): the largest nodal acceleration |a| (central
    differences, t = period x load factor) over g, the centroid's, the lowest bending frequency
    f1 of the free strip (free-free beam, 4.730^2 sqrt(EI / (rho A)) / (2 pi L^2)) against the
    driving frequency, and the magnetic couple c = Br B0 w h / mu0 and elastic force EI/L^2 per
    unit length over the weight rho g w h (the inertial force per unit length over the weight
    is |a| / g).  The centroid's horizontal velocity v_c changes only by the net horizontal force,
    which only the floor's friction gives (a uniform field exerts no net force), at most mu m g:
    the changes of v_c over the cycle take friction at least sum |dv_c| / (mu g), and
    ``friction_time_over_period`` = sum |dv_c| / (mu g period) must be small (below QS_FRICTION).
    The velocity jumps where a foot starts or stops slipping, so its total variation converges
    with the steps where the largest acceleration does not (10 x 1, mu 0.5: |a_c| / (mu g) 0.0042,
    0.0084, 0.0166 at 20, 40, 80 steps per cycle; the total variation 8.49e-4, 9.31e-4, 9.31e-4).
    The quasi-static stride does not vanish as mu -> 0 (the two feet's forces balance, and which
    one slips does not depend on mu's size: 0.650, 0.710, 0.743, 0.754 mm at mu 1, 0.5, 0.2, 0.1,
    20 x 1 elements): the real walker's does, once friction can no longer move its mass."""
    dt = p["period"] * dlam
    x = np.array([g[:, :3, 3] for g in steps_g])
    a = (x[2:] - 2 * x[1:-1] + x[:-2]) / dt ** 2
    EI = p["E"] * p["width"] * p["h"] ** 3 / 12.0
    rhoA = p["rho"] * p["width"] * p["h"]
    q = rhoA * p["g"]
    f1 = 4.730 ** 2 * np.sqrt(EI / rhoA) / (2 * np.pi * p["L"] ** 2)
    v_c = np.diff(x.mean(1)[:, :2], axis=0) / dt
    dv = float(np.linalg.norm(np.diff(v_c, axis=0), axis=1).sum())
    return dict(period=p["period"], largest_acceleration_over_g=float(np.linalg.norm(a, axis=2).max() / p["g"]),
                centroid_acceleration_over_g=float(np.linalg.norm(a.mean(1), axis=1).max() / p["g"]),
                friction_time_over_period=dv / (p["mu"] * p["g"] * p["period"]) if p["mu"] > 0 else np.inf,
                lowest_frequency=float(f1), drive_over_lowest_squared=float((1.0 / p["period"] / f1) ** 2),
                magnetic_couple_over_weight_L=float(p["Br"] * p["B0"] * p["width"] * p["h"] / MU0_MM / (q * p["L"])),
                elastic_over_weight=float(EI / p["L"] ** 2 / (q * p["L"])))


def quasi_static_warning(q, mu):
    """An AccuracyWarning when the quasi-static check ``q`` (:func:`quasi_static_check`) has the
    floor's friction mu m g needing more than QS_FRICTION of the period to make the centroid's
    velocity changes: the stride is then the quasi-static model's, not the walker's (its feet
    cannot move its mass so fast), with the period at which it would be QS_FRICTION (the
    velocities scale as 1 / period, the time friction needs too)."""
    r = q["friction_time_over_period"]
    if not r > QS_FRICTION:
        return
    slow = q["period"] * np.sqrt(r / QS_FRICTION)
    warnings.warn(AccuracyWarning(
        f"walker: the floor's friction mu m g (mu {mu:g}) needs {r:.3g} of the {q['period']:g} s cycle to change the "
        f"centroid's velocity as the quasi-static cycle does, above {QS_FRICTION:g}: friction cannot move the walker so "
        f"fast and the quasi-static stride is not the walker's (it does not vanish as mu -> 0, the real one does); "
        f"raise the period to at least {slow:.3g} s or mu"), stacklevel=3)


def run(case, p, prob, steps, **kw):
    res = prob.solve(load_factors=load_factors(case, p, steps), **kw)
    doc = case_document(case, p, prob, res)
    doc["steps"][0]["balance_error"] = 0.0          # the start state, not an equilibrium
    r = push_formula(p) if case.name == "friction-pushed-cantilever" else None
    X0 = prob.mesh.g0[:, :3, 3]
    for rec, st in zip(doc["steps"][1:], res.steps[1:]):
        restore_multipliers(prob, st)
        if r is not None:
            rec["measures"] = _push_measures(prob, p, st, r)
        elif case.name == "friction-gripper-hold":
            rec["measures"] = _hold_measures(prob, p, st)
        else:
            rec["measures"] = walk_measures(prob, st, X0)
    doc["steps"][0]["measures"] = {}
    res.obstacles = [ld.obstacle for ld in prob.loads if getattr(ld, "kind", "") == "contact"]
    m = [s["measures"] for s in doc["steps"][1:]]
    if r is not None:
        doc["push"] = dict(P=r["P"], kL=r["kL"], s_star=r["s_star"], H_slip=p["mu"] * r["P"],
                           **{f"largest_{q}_error_{reg}": max((abs(x[f"{q}_error"]) for x in m if x["regime"] == reg and f"{q}_error" in x),
                                                              default=None)
                              for q in ("u", "H") for reg in ("stick", "slip")})
        if p["nu"] != 0.0:
            doc["push"]["note"] = NU_NOTE.format(nu=p["nu"])
    elif case.name == "friction-gripper-hold":
        best = max(m, key=lambda x: x["hold"])
        doc["hold"] = dict(largest_hold=best["hold"], lift=best["lift"], bound=best["bound"], ratio=best["ratio"],
                           mu_sum_N=best["mu_sum_N"], ratio_mu_sum_N=best["hold"] / best["mu_sum_N"])
    else:
        lams = [st.load_factor for st in res.steps]
        ends = [i for i, lam in enumerate(lams) if lam >= 1 - 1e-12 and abs(lam - round(lam)) < 1e-9]
        xs = [doc["steps"][i]["measures"]["centroid_ux"] for i in ends]
        per = [b - a for a, b in zip(xs, xs[1:])]
        last = [st.g for st in res.steps[ends[-2]:ends[-1] + 1]] if len(ends) > 1 else []
        # the largest motion of a node over one stored step: a snap (the strip standing up on one
        # foot) moves nodes by a good part of L in one step however small the steps are
        x = np.array([st.g[:, :3, 3] for st in res.steps])
        jump = np.linalg.norm(np.diff(x, axis=0), axis=2).max(1)
        k = int(np.argmax(jump))
        doc["walk"] = dict(per_cycle=per, per_cycle_over_L=[v / p["L"] for v in per], steps_per_cycle=steps,
                           largest_step_motion_over_L=float(jump[k] / p["L"]),
                           largest_step_motion_at=float(res.steps[k + 1].load_factor),
                           quasi_static=quasi_static_check(prob, p, last, 1.0 / steps) if len(last) > 2 else None)
        if doc["walk"]["quasi_static"]:
            quasi_static_warning(doc["walk"]["quasi_static"], p["mu"])
    return doc, res


def report(doc):
    lines = []
    if "push" in doc:
        d = doc["push"]
        lines.append(f"P {d['P']:.6g} (kL {d['kL']:.4f}), slip onset s* {d['s_star']:.6g}, slip force mu P "
                     f"{d['H_slip']:.6g}")
        for s in doc["steps"][1:]:
            m = s["measures"]
            if m["regime"] != "press" and "not_compared" in m:
                lines.append(f"s {m['s']:.5g} ({m['regime']}): u {m['u']:.6g}, H {m['H']:.6g}: {m['not_compared']}")
            elif m["regime"] != "press":
                lines.append(f"s {m['s']:.5g} ({m['regime']}): u {m['u']:.6g} (exact {m['u_exact']:.6g}, "
                             f"{100 * m['u_error']:+.3f}%), H {m['H']:.6g} (exact {m['H_exact']:.6g}, "
                             f"{100 * m['H_error']:+.3f}%), N/P {m['N'] / m['N_exact']:.6f}")
    elif "hold" in doc:
        d = doc["hold"]
        lines.append(f"largest force held {d['largest_hold']:.5g} N at lift {d['lift']:.4g} mm: {d['ratio']:.4f} of the "
                     f"bound {d['bound']:.5g} N of the normal forces ({d['ratio_mu_sum_N']:.4f} of mu sum N)")
    elif "walk" in doc:
        d = doc["walk"]
        lines.append("net displacement per cycle: " + ", ".join(f"{v:+.6g}" for v in d["per_cycle"])
                     + f" mm ({d['steps_per_cycle']} steps per cycle); largest motion of a node in one step "
                     f"{d['largest_step_motion_over_L']:.3g} L (at load factor {d['largest_step_motion_at']:.4g}: "
                     "above about 0.25 L the strip snapped)")
        q = d.get("quasi_static")
        if q:
            lines.append(f"quasi-static at a {q['period']:g} s cycle: largest |a|/g {q['largest_acceleration_over_g']:.2e} "
                         f"(centroid {q['centroid_acceleration_over_g']:.2e}, friction's time / period "
                         f"{q.get('friction_time_over_period', float('nan')):.2e}), (f/f1)^2 {q['drive_over_lowest_squared']:.2e} "
                         f"(f1 {q['lowest_frequency']:.3g} Hz); magnetic couple / (weight L) "
                         f"{q['magnetic_couple_over_weight_L']:.3g}, EI/L^2 / (weight L) {q['elastic_over_weight']:.3g}")
    return lines


def plot(case, p, doc, res, path):
    from ..io import obstacle_surfaces, plot_load_deflection, plot_shell
    steps = doc["steps"][1:]
    m = [s["measures"] for s in steps]
    if "push" in doc:
        x = np.array([v["s"] for v in m])
        plot_load_deflection(path, x, {"lateral force H": np.array([v["H"] for v in m])},
                             reference={"lateral force H": (x, np.array([np.nan if v["H_exact"] is None else v["H_exact"]
                                                                          for v in m]))},
                             axes=("lateral force [force]", "wall travel s [length]"), title=case.name)
    elif "hold" in doc:
        x = np.array([v["lift"] for v in m])
        plot_load_deflection(path, x, {"force held": np.array([v["hold"] for v in m]),
                                       "bound": np.array([v["bound"] for v in m])},
                             axes=("force [N]", "lift [mm]"), title=case.name)
    else:
        x = np.array([s["load_factor"] for s in steps])
        plot_load_deflection(path, x, {"centroid": np.array([v["centroid_ux"] for v in m]),
                                       "rear foot": np.array([v["rear_ux"] for v in m]),
                                       "front foot": np.array([v["front_ux"] for v in m])},
                             axes=("displacement along x [mm]", "load factor (1 + cycles)"), title=case.name)
    shape = path[:-4] + "_shape.png" if path.endswith(".png") else path + "_shape.png"
    g = res.final.g
    plot_shell(shape, res.mesh.X, res.mesh.quads, g, title=f"{case.name}: final shape",
               surfaces=obstacle_surfaces(getattr(res, "obstacles", []), g[:, :3, 3], res.final.load_factor))


register_family("friction", Family(build=build, run=run, plot=plot, report=report))

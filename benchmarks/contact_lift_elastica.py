"""Generates core_se3/data/contact_lift_elastica.json, the large-deflection reference of the
catalogue case ``contact-lift`` (issue 16): the inextensible, shear-rigid elastica of the
lifted part of a heavy strip on a rigid frictionless plane, with a free detachment point.

Scaled variables (ell_q = (EI / q_l)^(1/3), the only length of the lifted part): arc length
s in [0, l] from the detachment point (s = 0) to the lifted end (s = l), tangent angle theta
to the plane, height y, lift force F at the end (vertical; the horizontal end force is zero
because the plane is frictionless), all lengths over ell_q and forces over q_l ell_q:

    theta' = kappa,   kappa' = -cos(theta) (F - (l - s)),   y' = sin(theta),   x' = cos(theta)
    s = 0:  theta = 0, kappa = 0 (the flat part carries no moment), y = 0, x = 0
    s = l:  kappa = 0 (rotation free), y = delta.

Unknowns (F, l); the detachment reaction is R = l - F.  Two independent methods:

* shooting: solve_ivp (DOP853, rtol 1e-13) from s = 0 for given (F, l), residuals
  (kappa(l), y(l) - delta) zeroed by scipy.optimize.root (hybr, xtol 1e-14);
* collocation: solve_bvp on t = s / l in [0, 1] with the parameters (F, l), tol 1e-10.

The small-deflection limit is l = (24 delta)^(1/4), F = l / 2 (docs/CONTACT.md).

Run:  python benchmarks/contact_lift_elastica.py      (< 1 s; rewrites the JSON, prints the rows)
tests/test_contact.py imports ``shoot`` and ``collocate`` from here and checks that the two methods
agree and that the packaged table is what this script computes.
"""
from __future__ import annotations

import json

import numpy as np
from scipy.integrate import solve_bvp, solve_ivp
from scipy.optimize import root

__all__ = ["shoot", "collocate", "table", "write_table"]


def _rhs_s(s, Y, F, l):
    th, ka, y, x = Y
    return [ka, -np.cos(th) * (F - (l - s)), np.sin(th), np.cos(th)]


def _integrate(F, l):
    sol = solve_ivp(_rhs_s, (0.0, l), [0.0, 0.0, 0.0, 0.0], args=(F, l), method="DOP853",
                    rtol=1e-13, atol=1e-15)
    return sol.y[:, -1]


def shoot(delta, guess=None):
    """(l, F, tip angle, horizontal span) of the scaled problem by shooting."""
    l0 = (24.0 * delta) ** 0.25
    x0 = np.array(guess if guess is not None else (l0 / 2, l0))

    def res(z):
        F, l = z
        th, ka, y, x = _integrate(F, l)
        return [ka, y - delta]

    r = root(res, x0, method="hybr", options=dict(xtol=1e-14))
    # hybr may stop at the round-off of the integration ("no further improvement"): accept
    # the point if its residuals are at that level
    if np.max(np.abs(res(r.x))) > 1e-11 * max(1.0, delta):
        raise RuntimeError(f"shooting failed at delta = {delta}: {r.message}")
    F, l = r.x
    th, ka, y, x = _integrate(F, l)
    return dict(l=float(l), F=float(F), tip_angle=float(th), span=float(x),
                residual=float(np.max(np.abs(res(r.x)))))


def collocate(delta, guess=None, tol=1e-10):
    """The same by scipy.integrate.solve_bvp on t = s / l."""
    l0 = (24.0 * delta) ** 0.25
    F0, L0 = guess if guess is not None else (l0 / 2, l0)
    t = np.linspace(0.0, 1.0, 41)

    def f(t, Y, p):
        F, l = p
        th, ka, y, x = Y
        return np.vstack([l * ka, -l * np.cos(th) * (F - l * (1 - t)), l * np.sin(th), l * np.cos(th)])

    def bc(Ya, Yb, p):
        return np.array([Ya[0], Ya[1], Ya[2], Ya[3], Yb[1], Yb[2] - delta])

    # small-deflection initial shape
    s = L0 * t
    A = L0 / 12.0
    y0 = np.vstack([3 * A * s ** 2 - s ** 3 / 6, 6 * A * s - s ** 2 / 2,
                    A * s ** 3 - s ** 4 / 24, s])
    sol = solve_bvp(f, bc, t, y0, p=[F0, L0], tol=tol, max_nodes=200000, bc_tol=1e-13)
    if not sol.success:
        raise RuntimeError(f"solve_bvp failed at delta = {delta}: {sol.message}")
    F, l = sol.p
    return dict(l=float(l), F=float(F), tip_angle=float(sol.y[0, -1]), span=float(sol.y[3, -1]),
                nodes=int(sol.x.size), rms_residual=float(np.max(sol.rms_residuals)))


DELTA_OVER_L = (0.0025, 0.005, 0.0075) + tuple(round(0.01 * k, 4) for k in range(1, 31))


def table(Q=20.0, delta_over_L=DELTA_OVER_L):
    """Rows for a strip of length L with Q = q_l L^3 / EI: L / ell_q = Q^(1/3)."""
    r = Q ** (1.0 / 3.0)                       # L / ell_q
    rows = []
    guess = None
    for dl in delta_over_L:
        d = dl * r                                # delta / ell_q
        a = shoot(d, guess)
        b = collocate(d, (a["F"], a["l"]))
        guess = (a["F"], a["l"])
        l_small = (24.0 * d) ** 0.25
        rows.append(dict(
            delta_over_L=dl, l_over_L=a["l"] / r, lift_force_over_qlL=a["F"] / r,
            tip_angle_rad=a["tip_angle"], span_over_L=a["span"] / r,
            detachment_reaction_over_qlL=(a["l"] - a["F"]) / r,
            l_over_L_small_deflection=l_small / r,
            l_over_L_bvp=b["l"] / r, lift_force_over_qlL_bvp=b["F"] / r, tip_angle_rad_bvp=b["tip_angle"],
            max_abs_difference_shoot_vs_bvp=float(max(abs(a["l"] - b["l"]), abs(a["F"] - b["F"]),
                                                       abs(a["tip_angle"] - b["tip_angle"])) / r),
            bvp_nodes=b["nodes"]))
    return rows


def write_table(path, Q=20.0):
    rows = table(Q)
    doc = dict(
        name="contact-lift elastica",
        description=("Heavy inextensible shear-rigid strip (elastica) on a rigid frictionless plane, "
                     "one end lifted by delta with its rotation free; lifted part with a free detachment "
                     "point (zero curvature there, concentrated reaction), the rest flat on the plane."),
        equations=("theta'' = -cos(theta) (F - q_l (l - s)) / EI on 0 <= s <= l (s from the detachment), "
                   "y' = sin(theta); theta(0) = theta'(0) = y(0) = 0, theta'(l) = 0, y(l) = delta; "
                   "unknowns F (lift force) and l (lifted arc length)"),
        methods=["shooting: scipy solve_ivp DOP853 (rtol 1e-13, atol 1e-15) + scipy.optimize.root hybr (xtol 1e-14; residuals < 1e-11 accepted)",
                 "collocation: scipy solve_bvp on t = s/l with parameters (F, l), tol 1e-10, bc_tol 1e-13"],
        scaling=("ell_q = (EI/q_l)^(1/3): l/ell_q, F/(q_l ell_q) and the tip angle depend on delta/ell_q only "
                 "(the flat part carries no moment, so the strip length L enters only through L > l). "
                 "Rows are for Q = q_l L^3/EI, i.e. L/ell_q = Q^(1/3); other Q: rescale with ell_q."),
        params=dict(Q=Q, L_over_ell_q=Q ** (1 / 3)),
        units=dict(delta_over_L="1", l_over_L="1 (arc length of the lifted part / L)",
                   lift_force_over_qlL="1 (vertical end force / (q_l L))", tip_angle_rad="rad (end tangent to the plane)",
                   span_over_L="1 (horizontal distance lifted end - detachment / L)",
                   detachment_reaction_over_qlL="1"),
        columns_primary="shooting; *_bvp = solve_bvp; max_abs_difference_shoot_vs_bvp over l/L, F/(q_l L), angle",
        source=("computed in this project by benchmarks/contact_lift_elastica.py (NumPy/SciPy: two methods, "
                "shooting and collocation, agreeing to < 1e-12); not a published table"),
        rows=rows)
    with open(path, "w") as fh:
        json.dump(doc, fh, indent=1)
    return doc


if __name__ == "__main__":
    import os
    here = os.path.dirname(os.path.abspath(__file__))
    doc = write_table(os.path.join(here, "..", "core_se3", "data", "contact_lift_elastica.json"))
    for r in doc["rows"]:
        print(f"{r['delta_over_L']:.4f}  l/L {r['l_over_L']:.10f}  F/qlL {r['lift_force_over_qlL']:.10f}  "
              f"tip {r['tip_angle_rad']:.8f}  small {r['l_over_L_small_deflection']:.6f}  "
              f"diff {r['max_abs_difference_shoot_vs_bvp']:.1e}  nodes {r['bvp_nodes']}")

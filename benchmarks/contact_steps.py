"""Contact over whole load steps (issue 29, contact items): the rising ball in 2, 20 and 40 steps
(no stored state with any part of the strip inside the ball, the same states and a continuous
contact force whatever the steps), the ball moved 1000 L in two steps, and the 200-element strip
settling on a table.  Writes benchmarks/results/contact_steps.md.

    python benchmarks/contact_steps.py
"""
from __future__ import annotations

import os
import time

import numpy as np

import core_se3 as cs
from core_se3.model.contact_sweep import face_grid

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "contact_steps.md")


def rising_ball(steps, dist=6.0):
    """The 16 x 1 cantilever (L 10, h 0.1, E 1e6) over a ball of radius 1 under x = 8 rising by
    ``dist``: (result or None, error, worst depth of the strip's surface inside the ball, time)."""
    p = cs.Problem(cs.mesh.rectangle(10.0, 1.0, 16, 1), cs.Material(1e6, 0.0, 0.1))
    p.clamp("x0")
    c = p.add_obstacle("sphere", centre=(8.0, 0.0, -1.1), radius=1.0, motion=dict(translate=(0, 0, dist)),
                       name="ball")
    t = time.perf_counter()
    try:
        res, err = p.solve(steps=steps), ""
    except cs.ConvergenceError as exc:
        res, err = exc.result, str(exc)
    dt = time.perf_counter() - t
    W = face_grid(0.05, 1.0)
    worst = 0.0
    for st in res.steps:
        x = c.contact_points(st.g)
        pts = np.concatenate([x, np.einsum("qa,mai->mqi", W, x[c._quads]).reshape(-1, 3)])
        worst = min(worst, float(c.obstacle.distance(pts, st.load_factor).min()))
    return res, err, worst, dt


def settling_strip(n=200):
    """100 x 10 x 1 mm, E 1 MPa, rho 1000 under gravity, clamped 1 mm above a table."""
    p = cs.Problem(cs.mesh.rectangle(0.1, 0.01, n, 1), cs.Material(1e6, 0.3, 1e-3))
    p.clamp("x0")
    p.add_gravity(rho=1000.0)
    c = p.add_obstacle("half_space", point=(0, 0, -0.001), normal=(0, 0, 1), name="table")
    t = time.perf_counter()
    res = p.solve(steps=10)
    return res, c, time.perf_counter() - t


def main():
    lines = ["# Contact over whole load steps (issue 29)", "",
             "`python benchmarks/contact_steps.py`; the ball under the strip's centre line, face samples on "
             "('auto').  Depth: the deepest point of the strip's contact surface (nodes and a 0.05 grid on "
             "every face) inside the ball over all stored states (0: none).", "",
             "| rising ball | status | depth | tip uz at 0.5, 1 | Fz at 0.5, 1 | largest change of Fz between stored "
             "states | time |", "|---|---|---|---|---|---|---|"]
    tips = {}
    for steps in (2, 20, 40):
        res, err, worst, dt = rising_ball(steps)
        at = {round(s.load_factor, 9): s for s in res.steps}
        tips[steps] = at
        Fz = [s.contact["ball"]["force"][2] for s in res.steps]
        pick = lambda lam, f: f"{f(at[lam]):.4f}" if lam in at else "-"
        lines.append(f"| {steps} steps | {'complete' if not err else 'stopped: ' + err[:80]} | {worst:.2e} | "
                     f"{pick(0.5, lambda s: s.g[16, 2, 3])}, {pick(1.0, lambda s: s.g[16, 2, 3])} | "
                     f"{pick(0.5, lambda s: s.contact['ball']['force'][2])}, "
                     f"{pick(1.0, lambda s: s.contact['ball']['force'][2])} | {np.abs(np.diff(Fz)).max():.4f} | "
                     f"{dt:.1f} s |")
    res, err, worst, dt = rising_ball(2, 1e4)
    lines += ["", f"Ball moved 1000 L in 2 steps: {'complete' if not err else err[:200]}; deepest stored "
                  f"surface point {worst:.2e} ({dt:.1f} s).", ""]
    res, c, dt = settling_strip()
    st = res.final
    lines += [f"200-element strip settling: load factor {st.load_factor:g}, penetration "
              f"{c.penetration(st.g, 1.0):.2e} m, balance {st.balance_error:.1e}, "
              f"{sum(s.attempts or 0 for s in res.steps)} tries, {sum(s.linear_solves or 0 for s in res.steps)} "
              f"linear solves, {dt:.1f} s."]
    with open(OUT, "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

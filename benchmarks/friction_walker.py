"""The magnetic inchworm of the friction catalogue (issue 31, item 4): net displacement per cycle
against the steps per cycle (its convergence), the mesh, the friction coefficient mu and the
field amplitude B0, the symmetric walker's (zero), and the quasi-static check of the cycle.
Each run is the catalogue case ``friction-walker`` over two cycles; the displacement per cycle
is the centroid's over the second (the first starts from the flat set-up state; from the second
on the cycle repeats: the third equals the second to 1e-15 at 40 steps per cycle).  Writes
benchmarks/results/friction_walker.{md,json,png}.

    python benchmarks/friction_walker.py
"""
from __future__ import annotations

import json
import os
import time

import numpy as np

from core_se3.catalogue import run_case
from core_se3.catalogue.cases_friction import WALKER_PARAMS
from core_se3.errors import CoreSE3Error

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")
L = WALKER_PARAMS["L"]


SNAP = 0.25          # a node moving by more than SNAP L in one stored step: the path jumped (a snap)


def walk(steps=40, mesh=(20, 1), name="friction-walker", **over):
    """(second-cycle displacement [mm] or None, first-cycle, error, quasi-static check, time [s]);
    the error names a snap (a node moving by more than SNAP L in one step: the walker stood up
    on one foot, a jump the quasi-static path cannot follow) and the displacement is then None."""
    t = time.perf_counter()
    try:
        doc, _, _ = run_case(name, mesh=mesh, steps=steps, overrides=dict(cycles=2.0, **over))
    except CoreSE3Error as exc:
        return None, None, str(exc).splitlines()[0][:160], None, time.perf_counter() - t
    w = doc["walk"]
    if w["largest_step_motion_over_L"] > SNAP:
        return None, None, (f"snaps at load factor {w['largest_step_motion_at']:.4g}: a node moves "
                            f"{w['largest_step_motion_over_L']:.2f} L in one step"), None, time.perf_counter() - t
    walk.largest = max(getattr(walk, "largest", 0.0), w["largest_step_motion_over_L"])
    per = w["per_cycle"]
    return per[1], per[0], "", w["quasi_static"], time.perf_counter() - t


def main():
    out = dict(params=WALKER_PARAMS)
    lines = ["# Friction walker: net displacement per cycle (issue 31, item 4)", "",
             "`python benchmarks/friction_walker.py`; catalogue case `friction-walker` (a 4 x 1.5 x 0.2 mm "
             "magnetic inchworm, E 70 kPa, Br 78 mT along +-x with 20 % through the thickness, on a floor with "
             "mu 0.5 under its weight; per cycle Bz 1 -> 3 -> 1 mT with Bx +-0.5 mT). Displacement per cycle: the "
             "centroid's over the second of two cycles.", ""]
    rows = []
    for n in (10, 20, 40, 80, 160):
        d, d1, err, qs, dt = walk(steps=n)
        rows.append(dict(steps=n, per_cycle=d, first_cycle=d1, error=err, time=dt))
        if n == 40:
            out["quasi_static"] = qs
    ref = rows[-1]["per_cycle"]
    lines += ["## Convergence with steps per cycle (20 x 1 elements)", "",
              "| steps per cycle | per cycle [mm] | / L | vs 160 steps | first cycle [mm] | time [s] |",
              "|---|---|---|---|---|---|"]
    for r in rows:
        d = r["per_cycle"]
        lines.append(f"| {r['steps']} | {d:.6f} | {d / L:.5f} | {100 * (d / ref - 1):+.3f} % | "
                     f"{r['first_cycle']:.6f} | {r['time']:.1f} |" if d is not None else
                     f"| {r['steps']} | fails: {r['error']} | | | | {r['time']:.1f} |")
    out["steps"] = rows
    mrows = []
    for nx in (10, 20, 40):
        d, _, err, _, dt = walk(steps=40, mesh=(nx, 1))
        mrows.append(dict(nx=nx, per_cycle=d, error=err, time=dt))
    lines += ["", "## Mesh (40 steps per cycle)", "", "| elements | per cycle [mm] | / L | time [s] |", "|---|---|---|---|"]
    lines += [f"| {r['nx']} x 1 | {r['per_cycle']:.6f} | {r['per_cycle'] / L:.5f} | {r['time']:.1f} |"
              if r["per_cycle"] is not None else f"| {r['nx']} x 1 | fails: {r['error']} | | {r['time']:.1f} |"
              for r in mrows]
    out["mesh"] = mrows
    d, d1, err, _, _ = walk(steps=40, name="friction-walker-symmetric")
    out["symmetric"] = dict(per_cycle=d, first_cycle=d1, error=err)
    lines += ["", "## Symmetric walker (mz = 0, Bx = 0; 20 x 1, 40 steps per cycle)", "",
              f"first cycle {d1:+.3e} mm, second {d:+.3e} mm: |net| / L = {max(abs(d), abs(d1)) / L:.1e} "
              "(target 1e-8)" if d is not None else f"fails: {err}"]
    sweeps = {}
    for key, values in (("mu", (0.2, 0.3, 0.5, 0.7, 1.0)), ("B0", (2e-3, 3e-3, 4e-3, 5e-3))):
        sweeps[key] = []
        for v in values:
            d, _, err, _, dt = walk(steps=40, **{key: v})
            sweeps[key].append(dict(value=v, per_cycle=d, error=err, time=dt))
    out["sweeps"] = sweeps
    for key, unit in (("mu", ""), ("B0", " [T]")):
        lines += ["", f"## Sweep of {key} (20 x 1, 40 steps per cycle; the others as in the case)", "",
                  f"| {key}{unit} | per cycle [mm] | / L |", "|---|---|---|"]
        lines += [f"| {r['value']:g} | {r['per_cycle']:.6f} | {r['per_cycle'] / L:.5f} |" if r["per_cycle"] is not None
                  else f"| {r['value']:g} | fails: {r['error']} | |" for r in sweeps[key]]
    lines += ["", f"A run is marked as snapping when a node moves by more than {SNAP} L in one stored step; "
              f"the largest such motion of the runs that walk is {walk.largest:.3f} L."]
    out["largest_step_motion_over_L"] = walk.largest
    q = out["quasi_static"]
    lines += ["", "## Quasi-static check (the 40-step cycle at a period of 1 s)", "",
              f"- largest nodal acceleration (central differences of the stored states) {q['largest_acceleration_over_g']:.2e} g, "
              f"the centroid's {q['centroid_acceleration_over_g']:.2e} g: the inertial force per unit mass is about 1 % of "
              "the weight, which is itself the smallest of the forces in play;",
              f"- magnetic couple Br B0 w h / mu0 over weight x L: {q['magnetic_couple_over_weight_L']:.3g}; bending "
              f"stiffness EI/L^2 over the weight: {q['elastic_over_weight']:.3g};",
              f"- lowest bending frequency of the free strip f1 = {q['lowest_frequency']:.3g} Hz: (f_drive / f1)^2 = "
              f"{q['drive_over_lowest_squared']:.1e}, the dynamic amplification of the elastic response.",
              "", "Quasi-static holds for cycles slower than about 0.1 s (|a| scales with 1/period^2: 1 % of g at 1 s, "
              "100 % at 0.1 s)."]
    with open(os.path.join(HERE, "friction_walker.md"), "w") as fh:
        fh.write("\n".join(lines) + "\n")
    with open(os.path.join(HERE, "friction_walker.json"), "w") as fh:
        json.dump(out, fh, indent=1)
    plot(sweeps, os.path.join(HERE, "friction_walker.png"))
    print("\n".join(lines))


def plot(sweeps, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.6))
    for a, key, scale, label in ((ax[0], "mu", 1.0, "friction coefficient mu"),
                                 (ax[1], "B0", 1e3, "field amplitude B0 [mT]")):
        r = [x for x in sweeps[key] if x["per_cycle"] is not None]
        a.plot([x["value"] * scale for x in r], [x["per_cycle"] / L for x in r], "o-")
        a.set_xlabel(label)
        a.set_ylabel("net displacement per cycle / L")
        a.grid(alpha=0.3)
    fig.suptitle("friction-walker (20 x 1, 40 steps per cycle)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()

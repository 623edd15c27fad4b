"""Hard-magnetic benchmark table: the Zhao et al. 2019 cantilevers, the antiparallel buckling case
and the plate/gripper predictions, written to benchmarks/results/magnetic.md (and .json).

    python benchmarks/magnetic.py            # about a minute on 2 cores
"""
from __future__ import annotations

import json
import os
import time

import numpy as np

from core_se3.catalogue import run_case
from core_se3.catalogue.cases_magnetic import ZHAO_BEAMS

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    from core_se3.backend import pin_for_timing
    pin_for_timing()          # time the compiled product, not 'auto''s NumPy start
    out = {}
    lines = ["# Hard-magnetic benchmarks (`python benchmarks/magnetic.py`)", "",
             "Error = max over the path (up to A Br Ba L^2/(mu0 E I) = 20) of |tip - ref| / max |tip_ref|,",
             "against `core_se3/data/elastica.json` (nu = 0; default element).", "",
             "| beam L x h [mm] | L/h | mesh | max load | 90 deg (`3_magnetic_perpendicular_field`) | "
             "135 deg (`3_magnetic_field_135deg`) | 2x mesh, 90 deg | time [s] |",
             "|---|---|---|---|---|---|---|---|"]
    for L, h, nx in ZHAO_BEAMS:
        t = time.perf_counter()
        e = {}
        for ang in (90.0, 135.0):
            doc, _, _ = run_case("magnetic-cantilever", mesh=(nx, 1), overrides=dict(L=L, h=h, nu=0.0, field_angle_deg=ang))
            e[ang] = doc["reference"]["error_up_to_load_20"]
            qmax = doc["steps"][-1]["load"]["dimensionless"]
        d2, _, _ = run_case("magnetic-cantilever", mesh=(2 * nx, 1), overrides=dict(L=L, h=h, nu=0.0))
        dt = time.perf_counter() - t
        e2 = d2["reference"]["error_up_to_load_20"]
        out[f"{L}x{h}"] = dict(nx=nx, max_load=qmax, err90=e[90.0], err135=e[135.0], err90_2x=e2, time=dt)
        lines.append(f"| {L} x {h} | {L / h:.1f} | {nx}x1 | {qmax:.1f} | {100 * e[90.0]:.3f} % | "
                     f"{100 * e[135.0]:.3f} % | {100 * e2:.3f} % | {dt:.1f} |")
    lines += ["", "nu = 0.480 (the seed's material): tip deflection v between the plate-stiffness (0) and the",
              "beam-stiffness (1) answers of `3_magnetic_zhao2019_*`, as the fraction (v - v_plate)/(v_beam - v_plate)",
              "over the 20 field values:", "",
              "| beam | mesh | inside at every field | fraction min..max |", "|---|---|---|---|"]
    for L, h, nx in ZHAO_BEAMS:
        for mesh in ((nx, 1), (2 * nx, 4)):
            doc, _, _ = run_case("magnetic-cantilever", mesh=mesh, overrides=dict(L=L, h=h))
            fr = [(r["v"] - r["v_plate"]) / (r["v_beam"] - r["v_plate"]) for r in doc["bracket"]["rows"]]
            lines.append(f"| {L} x {h} | {mesh[0]}x{mesh[1]} | {doc['bracket']['all_inside']} | "
                         f"{min(fr):.3f}..{max(fr):.3f} |")
            out[f"{L}x{h}_nu048_{mesh[0]}x{mesh[1]}"] = dict(inside=doc["bracket"]["all_inside"], fmin=min(fr), fmax=max(fr))
    t = time.perf_counter()
    doc, _, _ = run_case("magnetic-antiparallel")
    dt = time.perf_counter() - t
    c, pb = doc["critical"], doc["perfect_branch"]
    out["antiparallel"] = dict(critical=c["load"], error=c["error"],
                               post=pb["max_error_over_L_at_load_ge_1p3_critical"], time=dt)
    lines += ["", "`magnetic-antiparallel` (17.2 x 0.42 mm, 30x1, nu = 0, load to 10): critical load "
              f"{c['load']:.6f} vs pi^2/4 = {c['exact']:.6f} ({100 * c['error']:+.3f} %); perfect post-buckled "
              f"branch (tilt {doc['imperfection']['tilt_deg']} deg removed) within {100 * pb['max_error_over_L_at_load_ge_1p3_critical']:.3f} % "
              f"of L of `3_magnetic_antiparallel_field` at loads >= 1.3 x critical; {dt:.1f} s."]
    for name in ("magnetic-plate", "magnetic-gripper"):
        t = time.perf_counter()
        doc, _, _ = run_case(name)
        dt = time.perf_counter() - t
        u = np.asarray(doc["steps"][-1]["probes"]["tip"]["u"])
        out[name] = dict(tip=u.tolist(), angle=doc["steps"][-1]["probes"]["tip"]["rotation_angle"], time=dt)
        m = doc["mesh"]
        grid = f"{m['nx']}x{m['ny']}" if m.get("nx") else f"{m['n_elements']} elements"    # the gripper: no grid
        lines.append(f"\n`{name}` (prediction, {grid}): tip displacement "
                     f"{np.round(u, 3).tolist()} mm, rotation {out[name]['angle']:.3f} rad at the largest field; {dt:.1f} s.")
    os.makedirs(os.path.join(HERE, "results"), exist_ok=True)
    with open(os.path.join(HERE, "results", "magnetic.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(HERE, "results", "magnetic.json"), "w") as f:
        json.dump(out, f, indent=1)
    print("\n".join(lines))


if __name__ == "__main__":
    main()

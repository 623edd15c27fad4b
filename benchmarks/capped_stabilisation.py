#!/usr/bin/env python3
"""A capped shear stabilisation, measured on the obstacle course (issue 30; a measurement, no
product change).

``Material(..., shear_stabilisation=alpha)`` scales the transverse-shear modulus ks G h by
Lyly, Stenberg and Vihinen's s(L) = h^2 / (h^2 + alpha L^2) (L: the element's longest reference
edge).  In the thin limit s -> h^2 / (alpha L^2): the shear stiffness falls to bending order and
the thin coarse meshes get more flexible (docs/ELEMENTS.md, "Convergence to 128x128").  The
candidate here caps the factor from below,

    s_c(L) = max(h^2 / (h^2 + alpha L^2), c),     0 <= c < 1,

which keeps the shear at membrane order (c ks G h) on thin shells and still tends to 1 as
L -> 0 (consistent).  Measured first with a subclass of Material overriding ``shear_scale``
(commit 11e8e26), now ``Material``'s own ``shear_stabilisation_floor`` (c; its default 0.05 was
chosen from these results).  For each (alpha, c) it measures

1. the roof and hemisphere thickness sweeps (R/h 10 ... 1e5, 2x2 ... 16x16), each over the same
   law's own 64x64 value, and the cells that leave 0.8 ... 1.02 (2x2: only > 1.02) where the
   default (alpha 0) stays inside;
2. the 16x16 set of the issue over the published values (roof, hemisphere, cylinder 32x32,
   twisted beam 12x2 in-plane and out-of-plane with the Cosserat law; the Raasch hook 96x32 with
   the classical law);
3. the pinched cylinder and the roof, 4x4 ... 64x64 over the same law's own 128x128 value;
4. the thick hemisphere (R/h 10) 4x4 over its own 64x64 and 128x128 values, point and spread loads.

The candidates: the default (alpha 0), the uncapped alpha = 0.1 (the control: it must give
obstacle_course.md's "Shear stabilisation" numbers), and alpha = 0.1 with c from 0.5 down to
0.002.

    PYTHONPATH=. nice .venv/bin/python benchmarks/capped_stabilisation.py [--candidates 0.1:0.5 ...]

Writes ``benchmarks/results/capped_stabilisation.{md,json}`` (candidates already in the json
are kept unless rerun).  On the Debian venv (MUMPS) run one candidate per process: a process
grows by about 3.5 GB per candidate (the report's memory note).
"""
from __future__ import annotations

import argparse
import datetime
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from core_se3 import Material                                  # noqa: E402
from core_se3.errors import ElementWarning                     # noqa: E402
import obstacle_course as oc                                   # noqa: E402

sc, REF = oc.sc, oc.REF
RESULTS = ROOT / "benchmarks" / "results"
SWEEP_CASES = (("Scordelis-Lo roof", sc.scordelis_lo, 25.0), ("pinched hemisphere", sc.pinched_hemisphere, 10.0))
CONVERGENCE_MESHES = (4, 8, 16, 32, 64, 128)
CONVERGENCE_CASES = (("pinched cylinder", sc.pinched_cylinder), ("Scordelis-Lo roof", sc.scordelis_lo))
#: (alpha, c): the default, the uncapped control (obstacle_course.md's alpha = 0.1), the caps
CANDIDATES = ((0.0, 0.0), (0.1, 0.0)) + tuple((0.1, c) for c in (0.5, 0.25, 0.1, 0.05, 0.03, 0.025, 0.02, 0.01, 0.005, 0.002))
#: the 16x16 set: (case, builder, arguments, reference, classical law, obstacle_course.json's standard row)
STANDARD = (("Scordelis-Lo roof 16x16", sc.scordelis_lo, (16,), REF["scordelis-lo"], False, ("Scordelis-Lo roof", "16x16")),
            ("pinched hemisphere 16x16", sc.pinched_hemisphere, (16,), REF["pinched-hemisphere"], False,
             ("pinched hemisphere", "16x16")),
            ("pinched cylinder 32x32", sc.pinched_cylinder, (32,), REF["pinched-cylinder"], False, ("pinched cylinder", "32x32")),
            ("twisted beam 12x2, in-plane load", sc.twisted_beam, ("in-plane",), REF["twisted-beam-in-plane"], False,
             ("twisted beam, in-plane load", "12x2")),
            ("twisted beam 12x2, out-of-plane load", sc.twisted_beam, ("out-of-plane",),
             REF["twisted-beam-out-of-plane"], False, ("twisted beam, out-of-plane load", "12x2")),
            ("Raasch hook 96x32, classical law", sc.raasch_hook, (96, 32), REF["raasch-hook"], True, ("Raasch hook", "96x32")))


def label(alpha, cap):
    return "default (alpha 0)" if alpha == 0 else f"alpha {alpha:g}, c {cap:g}"


def capped(build, alpha, cap, classical=False):
    """``build`` with its own E, nu, h under the capped law (alpha 0: the case's own law):
    ``Material(..., shear_stabilisation=alpha, shear_stabilisation_floor=cap)``."""
    def run(*a, **kw):
        if alpha == 0 and not classical:
            return build(*a, **kw)
        m = build(*a, **kw)[0].material
        make = Material.classical_shell if classical else Material
        kw.pop("h", None)
        return build(*a, material=make(m.E, m.nu, m.h, shear_stabilisation=alpha, shear_stabilisation_floor=cap), **kw)
    return run


def sweeps(alpha, cap):
    """{case|R/h: {converged, ratios {n: value / own 64x64}}}."""
    out = {}
    for case, build, R in SWEEP_CASES:
        run = capped(build, alpha, cap)
        for rh in oc.SWEEP_RH:
            vals = {n: oc.measure(run, None, n, h=R / rh)["core_se3"] for n in oc.SWEEP_MESHES + (64,)}
            out[f"{case}|{rh:g}"] = dict(converged=vals[64], ratios={str(n): vals[n] / vals[64] for n in oc.SWEEP_MESHES})
            print(" ", label(alpha, cap), case, f"{rh:g}",
                  {n: round(v, 3) for n, v in out[f"{case}|{rh:g}"]["ratios"].items()}, flush=True)
    return out


def standard(alpha, cap):
    """{case: value / published}: the 16x16 set."""
    out = {}
    for case, build, args, ref, classical, _ in STANDARD:
        p, meas = capped(build, alpha, cap, classical)(*args)
        out[case] = meas(p.solve_linear()) / ref
    print(" ", label(alpha, cap), {k: round(v, 4) for k, v in out.items()}, flush=True)
    return out


def convergence(alpha, cap):
    """{case: {n: raw value}} of the pinched cylinder and the roof, n in CONVERGENCE_MESHES."""
    out = {}
    for case, build in CONVERGENCE_CASES:
        run = capped(build, alpha, cap)
        out[case] = v = {str(n): oc.measure(run, None, n)["core_se3"] for n in CONVERGENCE_MESHES}
        print(" ", label(alpha, cap), case, {n: round(x / v["128"], 4) for n, x in v.items()}, flush=True)
    return out


def uncapped_scales():
    """{case mesh: (min, max)} of h^2 / (h^2 + 0.1 L^2) over the elements of the meshes where
    the cap decides (L: the longest reference edge, as Element.size)."""
    out = {}
    for name, build, n, kw in (("pinched cylinder", sc.pinched_cylinder, (4, 8, 16, 32), {}),
                               ("Scordelis-Lo roof R/h 100", sc.scordelis_lo, (2, 4, 16), {}),
                               ("pinched hemisphere R/h 10", sc.pinched_hemisphere, (4,), dict(h=1.0)),
                               ("pinched hemisphere R/h 1e3", sc.pinched_hemisphere, (3, 6), dict(h=0.01)),
                               ("Scordelis-Lo roof R/h 1e4", sc.scordelis_lo, (8,), dict(h=2.5e-3))):
        for k in n:
            p = build(k, **kw)[0]
            X = p.mesh.X[p.mesh.quads]
            L = np.linalg.norm(X - np.roll(X, -1, axis=1), axis=2).max(axis=1)
            s = p.material.h ** 2 / (p.material.h ** 2 + 0.1 * L ** 2)
            out[f"{name} {k}x{k}"] = (float(s.min()), float(s.max()))
    return out


def out_of_band(ratio, n):
    """True if a sweep cell misses the issue's band: 0.8 ... 1.02 (2x2: only > 1.02)."""
    return ratio > 1.02 or (n != 2 and ratio < 0.8)


def new_failures(cand, default):
    """(case, R/h, n, value, default's value) of the cells out of band where the default is in
    (``new``), and of those in band where the default is out (``mended``)."""
    new, mended = [], []
    for key, s in cand["sweeps"].items():
        case, rh = key.split("|")
        for n, r in s["ratios"].items():
            d = default["sweeps"][key]["ratios"][n]
            if out_of_band(r, int(n)) != out_of_band(d, int(n)):
                (new if out_of_band(r, int(n)) else mended).append((case, rh, int(n), r, d))
    return new, mended


def thick_hemisphere(alpha, cap):
    """The hemisphere at R/h 10 (h = 1): 4x4, 64x64 and 128x128 raw values, point loads and
    loads spread over an arc h (the well-posed version: docs/ELEMENTS.md)."""
    out = {}
    for name, kw in (("point", {}), ("spread", dict(load_arc=1.0))):
        run = capped(sc.pinched_hemisphere, alpha, cap)
        out[name] = {str(n): oc.measure(run, None, n, h=1.0, **kw)["core_se3"] for n in (4, 64, 128)}
    print(" ", label(alpha, cap), "hemisphere R/h 10, 4x4 / own 128x128",
          {k: round(v["4"] / v["128"], 4) for k, v in out.items()}, flush=True)
    return out


def run_candidate(alpha, cap):
    t = time.perf_counter()
    print(label(alpha, cap), flush=True)
    d = dict(alpha=alpha, cap=cap, sweeps=sweeps(alpha, cap), standard=standard(alpha, cap),
             convergence=convergence(alpha, cap), thick_hemisphere=thick_hemisphere(alpha, cap))
    d["seconds"] = time.perf_counter() - t
    return d


# ------------------------------------------------------------------ report -----------------
NOTES = """## Reading (issue 30's targets, per candidate)

* **The hypothesis holds for the thin shells.** With any cap c >= 0.025 the thin cells (R/h >=
  1e3) move by at most 0.5 % from the default (c 0.5 ... 0.025: 0.14 / 0.04 / 0.11 / 0.23 /
  0.40 / 0.49 %) and no sweep cell leaves the band that the default keeps; uncapped alpha = 0.1
  moves them by up to 509 % (the roof 2x2 at 1e5, 110 -> 374) with 15 new cells out of band.
  The converged (64x64) values move by at most 0.17 % from the default's (c <= 0.01, the
  hemisphere at R/h 1e3; c >= 0.03: 0.14 %; uncapped: 0.27 %).
* **Sweep target (every cell 0.8 ... 1.02): not met by any candidate**, nor by the default: the
  same 11 cells of the thin coarse roof (R/h >= 1e3, 2x2 ... 8x8: the free-edge mechanism of the
  edge tying, `roof_modes.md`) are out of band for the default and every cap; the cap neither
  adds to them (c >= 0.025) nor mends one. With c <= 0.02 a 12th cell fails: the roof 2x2 at
  R/h 100 (default 1.0186; c 0.025 / 0.02 / 0.01 / 0.005 / 0.002: 1.0199 / 1.0203 / 1.0222 /
  1.0260 / 1.0279, uncapped 1.0279; its uncapped factor is 0.0040).
* **Hemisphere 4x4 at R/h 10 >= 0.95: met for c <= 0.25** (0.955 over its own 64x64, 0.953
  over its own 128x128; spread load 0.935), where the cap does not bind (the uncapped factor is
  0.40 ... 0.51 there); c 0.5 binds and gives 0.945 (default 0.925, Kratos thick 0.943 over its
  own 128x128).
* **The 16x16 set within 2 %: met by every candidate** (the twisted beam's out-of-plane load
  0.9784, the worst; the hook with the classical law 1.0020 -- alpha, not the cap, moves it: its
  factor is about 0.98). Against Kratos thick on the same meshes: the roof 16x16 is behind for
  every law (0.9923 ... 0.9937 against 0.9975 over the published value; over its own 128x128
  0.9984 against Kratos' 1.0008), the hook 1.0020 against Kratos' 1.0017 (Kratos with its own
  law), the rest ahead (hemisphere 0.988 ... 0.996 against 0.971, cylinder 32x32 1.0086
  against 1.0098, twisted beam 0.9934 / 0.9784 against 0.9883 / 0.9668).
* **The cylinder's lift is where the cap costs.** Its elements' uncapped factor is 0.0065 /
  0.025 / 0.094 / 0.29 at 4x4 / 8x8 / 16x16 / 32x32: a cap above 0.025 takes back part of the
  8x8 lift (over its own 128x128: c 0.5 0.799, 0.25 0.807, 0.1 0.831, 0.05 0.870, 0.03 0.921,
  uncapped 0.943; default 0.796, Kratos thick 0.850) and above 0.094 part of the 16x16 one.
  The cylinder 8x8 (R/h 100, factor 0.025) and the roof 2x2 at R/h 100 (factor 0.0040) are
  what a cap must tell apart; c in (0.0203 ..., 0.025] keeps both (c 0.025: roof cell 1.0199,
  cylinder 8x8 0.943), but that window is the course's meshes (it sits on the cylinder 8x8's
  own factor, 0.0254) and the roof cell's margin is 1.3e-4: a tuned fit, not a principle.
* **Material's own floor is the measured law.** After main's `shear_stabilisation_floor`
  (default c 0.05) every candidate was rerun through it: every number of the json equals the
  first run's (a Material subclass overriding `shear_scale`, commit 11e8e26) to the bit.
* **In short**: c 0.05 or 0.03 meets the hemisphere 4x4 target, keeps every sweep cell the
  default keeps (the thin cells within 0.4 %), meets the 16x16 set and beats Kratos thick on
  the cylinder 8x8 / 16x16 (0.870 or 0.921 / 0.987 against 0.850 / 0.976), at the cost of part
  of the uncapped 8x8 lift; it does not touch the roof's 11 failing thin cells, which remain the
  open part of the sweep target, nor the roof 16x16 gap to Kratos thick.
"""


MEMORY = """Memory: when these candidates ran, one process grew by about 3.5 GB per candidate
(about 100 linear solves) on the Debian venv (MUMPS) -- the PETSc matrix, KSP and MUMPS factors
outlived each MumpsSolver -- so the OOM killer stopped a first run at 24 GB; hence one process per
candidate. Fixed in a21f131 (MumpsSolver.close and __del__ free them). Measured again on
2026-12-04, the roof 64x64 `Problem.solve_linear()` 16 times with the Problem dropped and
`gc.collect()` between: RSS 304 -> 536 MB after 7 and 576 MB from the 9th on (a plateau: the
allocator's pools and the bounded cache of CSR row indices, solvers/linalg.py); NumPy-2 venv
(SuperLU) 140 -> 417 ... 447 MB, flat from the 8th."""


def _f(x, nd=3):
    return "n/a" if x is None else f"{x:.{nd}f}"


def _cells(cells):
    return "; ".join(f"{c.split()[0] if c.startswith('Scordelis') else 'hemisphere'} {rh} {n}x{n} {r:.3f} ({d:.3f})"
                     for c, rh, n, r, d in cells) or "none"


def _summary(doc):
    cands = doc["candidates"]
    default = cands.get(label(0.0, 0.0))
    L = ["## Summary", "",
         "Sweep cells: out of 0.8 ... 1.02 (2x2: > 1.02) where the default is inside (\"new\"), and the "
         "reverse (\"mended\"); each cell `case R/h mesh value (default's value)`. Hemisphere R/h 10 4x4: "
         "over the same law's 64x64 (the sweep's cell) and own 128x128 value, point load; spread load "
         "over its own 128x128. Cylinder: over the same law's own 128x128 value.", "",
         "| candidate | out-of-band cells (all) | thin cells (R/h >= 1e3): largest change from the default | new out-of-band cells | mended cells | hemisphere R/h 10 4x4 (64 / 128; spread) "
         "| cylinder 8x8 / 16x16 / 32x32 |", "|---|---:|---:|---|---|---|---|"]
    for name, d in cands.items():
        new, mended = new_failures(d, default) if default else ([], [])
        th, cy = d["thick_hemisphere"], d["convergence"]["pinched cylinder"]
        every = sum(out_of_band(r, int(n)) for s in d["sweeps"].values() for n, r in s["ratios"].items())
        thin = max(abs(r / default["sweeps"][k]["ratios"][n] - 1) for k, s in d["sweeps"].items()
                   if float(k.split("|")[1]) >= 1e3 for n, r in s["ratios"].items()) if default else None
        L.append(f"| {name} | {every} | {_f(None if thin is None else 100 * thin, 2)} % | {len(new)}: {_cells(new)} | {len(mended)}: {_cells(mended)} | "
                 f"{th['point']['4'] / th['point']['64']:.3f} / {th['point']['4'] / th['point']['128']:.3f}; "
                 f"{th['spread']['4'] / th['spread']['128']:.3f} | "
                 + " / ".join(f"{cy[n] / cy['128']:.3f}" for n in ("8", "16", "32")) + " |")
    kp, ks = _kratos_thick("pinched hemisphere R/h 10, point loads"), _kratos_thick("pinched hemisphere R/h 10, loads spread over an arc h")
    cy = _kratos_thick("pinched cylinder")
    if kp and ks and cy:
        L.append(f"| Kratos thick (obstacle_course.json's convergence run) | | | | | - / {kp['4'] / kp['128']:.3f}; "
                 f"{ks['4'] / ks['128']:.3f} | " + " / ".join(f"{cy[n] / cy['128']:.3f}" for n in ("8", "16", "32")) + " |")
    return L + [""]


def _standard_table(doc):
    cands = doc["candidates"]
    L = ["## The 16x16 set over the published values", "",
         "Targets: within 2 % (the twisted beam with the Cosserat law, the hook with the classical law, "
         "both with the candidate's shear factor).", "",
         "| case | " + " | ".join(cands) + " | Kratos thick (obstacle_course.json) |", "|---|" + "---:|" * (len(cands) + 1)]
    kratos = _kratos_standard()
    for case, *_, key in STANDARD:
        L.append(f"| {case} | " + " | ".join(f"{d['standard'][case]:.4f}" for d in cands.values())
                 + f" | {_f(kratos.get(key), 4)} |")
    for case, ref in (("pinched cylinder", "pinched-cylinder"), ("Scordelis-Lo roof", "scordelis-lo")):
        L += ["", f"## {case}: over its own 128x128 value (and over the published {REF[ref]:g})", "",
              "| candidate | " + " | ".join(f"{n}x{n}" for n in CONVERGENCE_MESHES) + " |",
              "|---|" + "---:|" * len(CONVERGENCE_MESHES)]
        rows = {name: d["convergence"][case] for name, d in cands.items()}
        kratos = _kratos_thick(case)
        if kratos:
            rows["Kratos thick (obstacle_course.json)"] = kratos
        for name, v in rows.items():
            L.append(f"| {name} | " + " | ".join(f"{v[str(n)] / v['128']:.4f} ({v[str(n)] / REF[ref]:.4f})"
                                                 for n in CONVERGENCE_MESHES) + " |")
    L += ["", "## Where the cap decides", "",
          "The uncapped factor h^2 / (h^2 + 0.1 L^2), smallest / largest over the elements (the cap c "
          "replaces it where it is below c):", ""]
    L += [f"* {k}: {a:.2e} / {b:.2e}" for k, (a, b) in doc.get("uncapped_scales", {}).items()]
    return L + [""]


def _kratos_standard():
    """{(case, mesh): value / published} of Kratos' thick quad from obstacle_course.json's
    standard cases (the hook: Kratos' own law)."""
    path = RESULTS / "obstacle_course.json"
    rows = json.loads(path.read_text()).get("standard", []) if path.exists() else []
    return {(r["case"], r["mesh"]): r["values"].get("kratos thick") for r in rows}


def _kratos_thick(case):
    """Kratos' thick quad's raw values of a convergence case from obstacle_course.json (its
    convergence run, the same meshes and nodal loads), or None."""
    path = RESULTS / "obstacle_course.json"
    rows = json.loads(path.read_text()).get("convergence", []) if path.exists() else []
    return next((r["values"] for r in rows if r["case"] == case and r["element"] == "kratos thick"), None)


def _sweep_tables(doc):
    cands = doc["candidates"]
    default = cands.get(label(0.0, 0.0))
    L = ["## Sweeps", "", "Each cell over the same law's own 64x64 value at the same thickness; `*`: out of "
         "0.8 ... 1.02 (2x2: > 1.02). Last column: the law's 64x64 value over the default's (how far the "
         "cap moves the converged value).", ""]
    for name, d in cands.items():
        L += [f"{name}:", "", "| case | R/h | " + " | ".join(f"{n}x{n}" for n in oc.SWEEP_MESHES) + " | 64x64 / default's |",
              "|---|---|" + "---:|" * (len(oc.SWEEP_MESHES) + 1)]
        for key, s in d["sweeps"].items():
            case, rh = key.split("|")
            conv = s["converged"] / default["sweeps"][key]["converged"] if default else None
            L.append(f"| {case} | {rh} | " + " | ".join(
                _f(s["ratios"][str(n)]) + ("*" if out_of_band(s["ratios"][str(n)], n) else "") for n in oc.SWEEP_MESHES)
                + f" | {_f(conv, 4)} |")
        L.append("")
    return L


def _control(doc):
    """The uncapped control against obstacle_course.json's alpha = 0.1 section, and each
    candidate's count of out-of-band sweep cells (the default's included)."""
    path = RESULTS / "obstacle_course.json"
    d = doc["candidates"].get(label(0.1, 0.0))
    if d is None or not path.exists():
        return []
    ref = json.loads(path.read_text()).get("stabilisation", {}).get("0.1")
    if not ref:
        return []
    dsw = max(abs(d["sweeps"][k]["ratios"][n] - v) for k, row in ref["sweeps"].items() for n, v in row.items())
    dst = max(abs(d["standard"][k] - v) for k, v in ref["standard"].items())
    return ["## Control", "",
            f"alpha 0.1, c 0 against `obstacle_course.json`'s alpha = 0.1 section: largest difference "
            f"{dsw:.1e} over the sweep cells, {dst:.1e} over the 16x16 set.", ""]


def write(doc):
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "capped_stabilisation.json").write_text(json.dumps(doc, indent=1))
    L = ["# A capped shear stabilisation: s_c(L) = max(h^2 / (h^2 + alpha L^2), c) (issue 30)", "",
         "The default element, linear analysis (`benchmarks/capped_stabilisation.py`); the runs that made "
         "these results (each candidate from the last run that names it; no argument: all of CANDIDATES):", ""]
    L += [f"* `{r}`" for r in doc.get("runs", [])] + ["", MEMORY, ""]
    L += _summary(doc) + _standard_table(doc) + _sweep_tables(doc) + _control(doc) + [NOTES]
    (RESULTS / "capped_stabilisation.md").write_text("\n".join(L))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--candidates", nargs="*", default=[f"{a:g}:{c:g}" for a, c in CANDIDATES],
                    help="alpha:c pairs (0:0 the default law); none: rewrite the report of the kept results")
    a = ap.parse_args()
    path = RESULTS / "capped_stabilisation.json"
    doc = json.loads(path.read_text()) if path.exists() else {"candidates": {}}
    doc["date"] = datetime.datetime.now().isoformat(timespec="seconds")
    if a.candidates:
        doc.setdefault("runs", []).append(f"{doc['date']}: python benchmarks/capped_stabilisation.py "
                                          + " ".join(sys.argv[1:]))
    warnings.simplefilter("ignore", ElementWarning)       # the coarse thin meshes are the point here
    doc["uncapped_scales"] = uncapped_scales()
    for pair in a.candidates:
        alpha, cap = (float(x) for x in pair.split(":"))
        doc["candidates"][label(alpha, cap)] = run_candidate(alpha, cap)
        write(doc)
    # the default, the uncapped laws, then the caps from the largest
    doc["candidates"] = dict(sorted(doc["candidates"].items(),
                                    key=lambda kv: (kv[1]["alpha"] > 0, kv[1]["cap"] > 0, -kv[1]["cap"], kv[1]["alpha"])))
    write(doc)


if __name__ == "__main__":
    sys.exit(main())

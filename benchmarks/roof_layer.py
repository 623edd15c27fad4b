"""The Scordelis-Lo roof's free-edge layer, and the coarse meshes that do not resolve it.

A membrane-dominated cylindrical shell carries its bending in layers along its free edges (the
generators) whose width scales like R (h/R)^(1/4) (the t^(1/4) scale of layers along the
generators of parabolic shells).  Measured here on the converged 128x128 roof at R/h 1e2 ... 1e5:
along the mid-span line (the symmetry plane y = L/2), where the circumferential curvature change
w'' of the normal deflection peaks, and within which distances of the free edge 50 % and 90 % of
w''^2 lie.  Then every roof cell of the thickness sweeps (benchmarks/results/mesh_check.json: the
deflection over the 64x64 value) beside b / l, the element's circumferential width b over
l = R (h/R)^(1/4).  For the roof's square-ish elements b / l = (phi^3 L / h)^(1/4), the default
element's coarse-curvature index (fem.element_default.warn_if_coarse_thin_curved).

Last, the failing cells again on meshes of the same element counts graded toward the free edge
(geometric circumferential spacing, the edge element 0.7 l wide): does resolving the layer, not
another element, mend them?

    python benchmarks/roof_layer.py       # -> benchmarks/results/roof_layer.md (about 1 min)
"""
from __future__ import annotations

import datetime
import json
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from core_se3.catalogue import shell_course as sc  # noqa: E402
from core_se3.fem.element_default import COARSE_THIN_CURVED  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
R, ANGLE = 25.0, np.radians(40.0)


def layer(rh, n=128):
    """(s at the peak of |w''|, s50, s90) from the free edge of the n x n roof at R/h = rh
    (``shell_course.roof_free_edge_layer``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, _ = sc.scordelis_lo(n, h=R / rh)
        return sc.roof_free_edge_layer(p.mesh, p.solve_linear().displacements())


def graded_roof(n, first, h):
    """(free-edge deflection, q) of the quarter roof on n x n elements graded toward the free edge
    (``[mesh] grade``: the circumferential widths grow geometrically from ``first`` [length] at
    the edge x1; axially uniform); uniform where ``first`` is None."""
    grade = None if first is None else {"x1": first / (R * ANGLE)}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, meas = sc.scordelis_lo(n, h=h, grade=grade)
        u = meas(p.solve_linear())
    w = np.diff(np.arctan2(*p.mesh.X[p.mesh.node_set("y0")][:, [0, 2]].T))
    return u, float(w[0] / w[1]) if grade and n > 1 else 1.0


def main():
    rows = []
    for rh in (1e2, 1e3, 1e4, 1e5):
        peak, s50, s90 = layer(rh)
        ell = R * rh ** -0.25
        rows.append(dict(rh=rh, ell=ell, peak=peak, s50=s50, s90=s90))
        print(f"R/h {rh:g}: l {ell:.3f}, peak {peak:.3f}, s50 {s50:.3f}, s90 {s90:.3f}", flush=True)
    cells = [r for r in json.loads((RESULTS / "mesh_check.json").read_text())["rows"] if r["case"] == "scordelis-lo"]
    L = ["# The Scordelis-Lo roof's free-edge layer", "",
         f"`python benchmarks/roof_layer.py` ({datetime.date.today()}); module docstring for the method.", "",
         "| R/h | l = R (h/R)^(1/4) | peak of w'' at s | 50 % of w''^2 within s | 90 % within s | peak / l |",
         "|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        L.append(f"| {r['rh']:g} | {r['ell']:.3f} | {r['peak']:.3f} | {r['s50']:.3f} | {r['s90']:.3f} | "
                 f"{r['peak'] / r['ell']:.2f} |")
    for a, b in zip(rows[1:-1], rows[2:]):
        L.append(f"\nPeak ratio R/h {a['rh']:g} -> {b['rh']:g}: {a['peak'] / b['peak']:.3f} (10^(1/4) = "
                 f"{10 ** 0.25:.3f}).")
    L += ["", "Every roof cell of the sweeps (deflection / 64x64, benchmarks/results/mesh_check.md) beside b / l "
          "(b = 25 x 40 deg / n, the element's circumferential width):", "",
          "| R/h | n | b / l | deflection / 64x64 | within 0.8 ... 1.02 (2x2: <= 1.02) |", "|---:|---:|---:|---:|---|"]
    for c in sorted(cells, key=lambda c: (c["rh"], c["n"])):
        ratio = c["n"] and R * ANGLE / c["n"] / (R * c["rh"] ** -0.25)
        L.append(f"| {c['rh']:g} | {c['n']} | {ratio:.2f} | {c['ratio']:.4g} | {'yes' if _in_band(c['ratio'], c['n']) else 'NO'} |")
    L += ["", "The failing cells on graded meshes of the same counts (the edge element 0.7 l wide; q the growth "
          "ratio of the circumferential widths; deflection over the uniform 64x64 value):", "",
          "| R/h | n | uniform | graded | q | within 0.8 ... 1.02 |", "|---:|---:|---:|---:|---:|---|"]
    graded = []
    for c in sorted(cells, key=lambda c: (c["rh"], c["n"])):
        h = R / c["rh"]
        ref = c["ratio"] / _uniform_deflection(c["n"], h)
        ell, b = R * c["rh"] ** -0.25, R * ANGLE / c["n"]
        u, q = graded_roof(c["n"], 0.7 * ell if b > THRESHOLD * ell else None, h)
        graded.append(dict(c, graded=u * ref, q=q))
        print("graded", c["rh"], c["n"], round(u * ref, 4), round(q, 3), flush=True)
    for c in graded:
        if not _in_band(c["ratio"], c["n"]) and c["n"] > 2:
            L.append(f"| {c['rh']:g} | {c['n']} | {c['ratio']:.4g} | {c['graded']:.4g} | {c['q']:.2f} | "
                     f"{'yes' if _in_band(c['graded'], c['n']) else 'NO'} |")
    L += ["", f"The whole roof sweep graded by the ElementWarning's rule: where it flags the uniform mesh (b > "
          f"{THRESHOLD:.3f} l), `[mesh] grade = {{x1 = f}}` with f = 0.7 l / (25 x 40 deg), else uniform; deflection over "
          "the uniform 64x64 value, and in brackets the growth ratio q where graded:", "",
          "| R/h | " + " | ".join(f"{n}x{n}" for n in NS) + " |", "|---|" + "---:|" * len(NS)]
    for rh in sorted({c["rh"] for c in graded}):
        row = {c["n"]: c for c in graded if c["rh"] == rh}
        L.append(f"| {rh:g} | " + " | ".join(_cell(row[n]) for n in NS) + " |")
    bad = [c for c in graded if not _in_band(c["graded"], c["n"])]
    mild = [c for c in graded if c["q"] <= Q_MILD]
    L.append(f"\n`*`: out of 0.8 ... 1.02 (2x2: above 1.02). Graded: {len(graded) - len(bad)} of {len(graded)} cells "
             f"in band (uniform: {sum(_in_band(c['ratio'], c['n']) for c in graded)}); of the cells whose growth "
             f"ratio is at most {Q_MILD} (uniform included): {sum(_in_band(c['graded'], c['n']) for c in mild)} of "
             f"{len(mild)}.")
    L += ["", "The coarsest cells that grading leaves out of band, for several widths of the free-edge element "
          "(deflection over the uniform 64x64 value, growth ratio q):", "",
          "| R/h | n | " + " | ".join(f"{f} l" for f in FIRSTS) + " |", "|---:|---:|" + "---|" * len(FIRSTS)]
    for c in bad:
        ell, ref = R * c["rh"] ** -0.25, c["ratio"] / _uniform_deflection(c["n"], R / c["rh"])
        runs = [graded_roof(c["n"], f * ell, R / c["rh"]) for f in FIRSTS]
        L.append(f"| {c['rh']:g} | {c['n']} | " + " | ".join(f"{u * ref:.3f} ({q:.2f})" for u, q in runs) + " |")
    (RESULTS / "roof_layer.md").write_text("\n".join(L) + "\n")


NS = (2, 3, 4, 6, 8, 12, 16)
# b / l above which the ElementWarning flags a roof element: its index phi^3 L / h is
# (L / b) (b / l)^4 with L = sqrt(b x 25 / n) = b sqrt(25 / (R ANGLE)) (docs/ELEMENTS.md)
THRESHOLD = (COARSE_THIN_CURVED / np.sqrt(25.0 / (R * ANGLE))) ** 0.25
Q_MILD = 1.7               # growth ratios up to which every graded cell measured is in band
FIRSTS = (0.3, 0.5, 0.7, 1.0, 1.4)


def _cell(c):
    mark = "" if _in_band(c["graded"], c["n"]) else " *"
    return f"{c['graded']:.3f}{mark}" + (f" ({c['q']:.2f})" if c["q"] != 1.0 else "")


def _in_band(r, n):
    """Issue 30's band: 0.8 ... 1.02 of the converged value (2x2: at most 1.02)."""
    return r <= 1.02 and (n == 2 or r >= 0.8)


def _uniform_deflection(n, h):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, meas = sc.scordelis_lo(n, h=h)
        return meas(p.solve_linear())


if __name__ == "__main__":
    main()

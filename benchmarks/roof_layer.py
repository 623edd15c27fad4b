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

    python benchmarks/roof_layer.py       # -> benchmarks/results/roof_layer.md (about 30 s)
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

RESULTS = ROOT / "benchmarks" / "results"
R, ANGLE = 25.0, np.radians(40.0)


def layer(rh, n=128):
    """(s at the peak of |w''|, s50, s90) from the free edge of the n x n roof at R/h = rh
    (``shell_course.roof_free_edge_layer``)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, _ = sc.scordelis_lo(n, h=R / rh)
        return sc.roof_free_edge_layer(p.mesh, p.solve_linear().displacements())


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
        ok = c["ratio"] <= 1.02 and (c["n"] == 2 or c["ratio"] >= 0.8)
        L.append(f"| {c['rh']:g} | {c['n']} | {ratio:.2f} | {c['ratio']:.4g} | {'yes' if ok else 'NO'} |")
    (RESULTS / "roof_layer.md").write_text("\n".join(L) + "\n")


if __name__ == "__main__":
    main()

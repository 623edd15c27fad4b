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

from core_se3 import Material, Problem  # noqa: E402
from core_se3.catalogue import shell_course as sc  # noqa: E402
from core_se3.mesh.generators import _patch  # noqa: E402

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
    """The quarter roof's free-edge deflection on n x n elements whose circumferential widths grow
    geometrically from ``first`` [length] at the free edge (axially uniform)."""
    f = first / R
    lo, hi = 1.0, 20.0
    for _ in range(200):                              # the ratio q with f (q^n - 1) / (q - 1) = ANGLE
        q = 0.5 * (lo + hi)
        lo, hi = (q, hi) if f * (q ** n - 1) / (q - 1) < ANGLE else (lo, q)
    theta = np.sort(ANGLE - np.concatenate([[0.0], np.cumsum(f * q ** np.arange(n))]))
    theta[0] = 0.0
    m = _patch(theta, np.linspace(0.0, 25.0, n + 1),
               lambda T, S: (np.stack([R * np.sin(T), S, R * np.cos(T)], -1),
                             np.stack([np.cos(T), 0 * T, -np.sin(T)], -1), np.stack([np.sin(T), 0 * T, np.cos(T)], -1)))
    p = Problem(m, Material(4.32e8, 0.0, h))
    p.fix("x0", (0, 4, 5))
    p.fix("y1", (1, 3, 5))
    p.fix("y0", (0, 2, 4))
    p.add_body_force((0.0, 0.0, -90.0))
    a = int(m.node_set("x1")[-1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = p.solve_linear()
    return -float(r.final.g[a, 2, 3] - m.X[a, 2]), q


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
    L += ["", "The failing cells on graded meshes of the same counts (the edge element 0.7 l wide; q the growth "
          "ratio of the circumferential widths; deflection over the uniform 64x64 value):", "",
          "| R/h | n | uniform | graded | q | within 0.8 ... 1.02 |", "|---:|---:|---:|---:|---:|---|"]
    for c in sorted(cells, key=lambda c: (c["rh"], c["n"])):
        ok = c["ratio"] <= 1.02 and (c["n"] == 2 or c["ratio"] >= 0.8)
        if ok or c["n"] == 2:
            continue
        h = R / c["rh"]
        ref = c["ratio"] / _uniform_deflection(c["n"], h)
        u, q = graded_roof(c["n"], 0.7 * R * c["rh"] ** -0.25, h)
        g = u * ref
        L.append(f"| {c['rh']:g} | {c['n']} | {c['ratio']:.4g} | {g:.4g} | {q:.2f} | {'yes' if 0.8 <= g <= 1.02 else 'NO'} |")
        print("graded", c["rh"], c["n"], round(g, 4), flush=True)
    (RESULTS / "roof_layer.md").write_text("\n".join(L) + "\n")


def _uniform_deflection(n, h):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p, meas = sc.scordelis_lo(n, h=h)
        return meas(p.solve_linear())


if __name__ == "__main__":
    main()

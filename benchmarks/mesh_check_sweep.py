"""Does the mesh check (``core-se3 check-mesh``) find the meshes that are wrong?

Every cell of issue 30's thickness sweeps -- the Scordelis-Lo roof and the pinched hemisphere,
n x n for n in 2 ... 16, R/h 10 ... 1e5 -- is run through ``scenario.check_mesh`` (one uniform
refinement, tol 5 %) and compared with its true error, the deflection over the same element's
64x64 value (as in benchmarks/obstacle_course.py's sweeps).  A cell is "wrong" when its
deflection is off the 64x64 value by more than the tolerance; the check should flag every wrong
cell and few right ones.  Also listed: whether the element's ElementWarning (phi^3 L / h > 2)
fired on the cell.

    python benchmarks/mesh_check_sweep.py      # -> benchmarks/results/mesh_check.{md,json}
"""
from __future__ import annotations

import datetime
import json
import sys
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from core_se3 import scenario  # noqa: E402
from core_se3.catalogue import shell_course as sc  # noqa: E402
from core_se3.scenario.mesh_check import DEFAULT_TOL, check_mesh  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
MESHES = (2, 3, 4, 6, 8, 12, 16)
RH = (10.0, 1e2, 1e3, 1e4, 1e5)
CASES = (("scordelis-lo", 25.0), ("pinched-hemisphere", 10.0))
CONVERGED = 64


def deflection(case, n, h):
    """The measured deflection of the case's n x n mesh (its probe A, in the load's direction)."""
    res = _scenario(case, n, h).problem.solve_linear()
    u = res.final.probes["A"]["u"]
    return -float(u[2]) if case == "scordelis-lo" else float(u[0])


def _scenario(case, n, h):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(sc.scenario_doc(case, n, h))


def run():
    rows = []
    for case, R in CASES:
        for rh in RH:
            h = R / rh
            ref = deflection(case, CONVERGED, h)
            for n in MESHES:
                chk = check_mesh(_scenario(case, n, h), tol=DEFAULT_TOL)
                ratio = deflection(case, n, h) / ref
                rows.append(dict(case=case, rh=rh, n=n, ratio=ratio, error=abs(ratio - 1.0), change=chk.change,
                                 flagged=not chk.converged, warned=any(w.startswith("level 0") for w in chk.warnings)))
                print(case, f"{rh:g}", n, f"ratio {ratio:.4g} change {chk.change:.4g}", flush=True)
    return rows


def _counts(rows, key):
    wrong = [r for r in rows if r["error"] > DEFAULT_TOL]
    right = [r for r in rows if r["error"] <= DEFAULT_TOL]
    return (sum(r[key] for r in wrong), len(wrong), sum(r[key] for r in right), len(right))


def write(rows):
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "mesh_check.json").write_text(json.dumps(dict(date=str(datetime.date.today()), tol=DEFAULT_TOL,
                                                             rows=rows), indent=1))
    L = ["# The mesh check on the thickness sweeps", "",
         f"`python benchmarks/mesh_check_sweep.py` ({datetime.date.today()}): every cell of the roof and "
         "hemisphere sweeps through `scenario.check_mesh` (one uniform refinement, tol "
         f"{DEFAULT_TOL:g}); \"error\" is |deflection / the same element's {CONVERGED}x{CONVERGED} value - 1|, "
         "\"change\" the check's largest relative change (energy, displacements, probe), \"warned\" the "
         "element's ElementWarning (phi^3 L / h > 2) on the cell.", ""]
    for key, what in (("flagged", "the check (change > tol)"), ("warned", "the ElementWarning")):
        fw, nw, fr, nr = _counts(rows, key)
        L.append(f"* {what}: flags {fw} of the {nw} cells whose error exceeds {DEFAULT_TOL:g}, and {fr} of the "
                 f"{nr} cells within it.")
    L += ["", "| case | R/h | n | deflection / 64x64 | error | check change | check | warning |",
          "|---|---:|---:|---:|---:|---:|---|---|"]
    for r in rows:
        L.append(f"| {r['case']} | {r['rh']:g} | {r['n']} | {r['ratio']:.4g} | {r['error']:.3g} | {r['change']:.3g} | "
                 f"{'NOT converged' if r['flagged'] else 'ok'} | {'warned' if r['warned'] else ''} |")
    (RESULTS / "mesh_check.md").write_text("\n".join(L) + "\n")


if __name__ == "__main__":
    write(run())

#!/usr/bin/env python3
"""Sze, Liu & Lo (2004) benchmark suite with core_se3 at the full meshes (issue 6 acceptance).

For each case (and a mesh study where cheap), runs ``core_se3.catalogue.run_case`` (arc length or
load control as the case defines), and records the curve deviation (largest distance of a
computed point to the table polyline in (P/P_max, u/u_max)), the end point against the table's,
the critical points, steps and timings.  Writes ``benchmarks/results/sze.{md,json}`` and, with
``--plots DIR``, one PNG per run (computed curve over the table).

    .venv/bin/python benchmarks/sze.py                  # everything (~10 min on 2 busy cores)
    .venv/bin/python benchmarks/sze.py --only sze-hinged-roof --plots out/sze

Runs one case at a time (the machine is shared).
"""
from __future__ import annotations

import argparse
import datetime
import json
import platform
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from core_se3 import catalogue  # noqa: E402
from core_se3.catalogue import get_case  # noqa: E402

# (case, mesh, overrides, bar or None, role)
RUNS = [
    ("sze-hinged-roof", (8, 8), {}, 0.03, "study"),
    ("sze-hinged-roof", (16, 16), {}, 0.03, "full (quarter 16x16 = roof 32x32)"),
    ("sze-hinged-roof", (24, 24), {}, 0.03, "study"),
    ("sze-hinged-roof", (32, 32), {}, 0.03, "study"),
    ("sze-hinged-roof", (32, 32), {"full": 1.0}, 0.03, "whole roof 32x32 (no symmetry)"),
    ("sze-hinged-roof-6.35", (8, 8), {}, None, "study"),
    ("sze-hinged-roof-6.35", (16, 16), {}, None, "study"),
    ("sze-hinged-roof-6.35", (32, 32), {}, None,
     "full (quarter 32x32); no bar: P_max unverified, curve on the stated scale P_max = 3000 (s3.8a's)"),
    ("sze-slit-annular", (6, 30), {}, 0.02, "study"),
    ("sze-slit-annular", (10, 80), {}, 0.02, "full (table mesh 10x80)"),
    ("sze-semicylinder", (16, 16), {}, 0.02, "study"),
    ("sze-semicylinder", (24, 24), {}, 0.02, "study"),
    ("sze-semicylinder", (40, 40), {}, 0.02, "full (table mesh 40x40)"),
    ("sze-hemisphere", (8, 8), {}, 0.03, "study"),
    ("sze-hemisphere", (16, 16), {}, 0.03, "full (quarter 16x16)"),
    ("sze-hemisphere", (32, 32), {}, 0.03, "study"),
    ("sze-pullout", (18, 12), {}, 0.03, "study"),
    ("sze-pullout", (36, 24), {}, 0.03, "full (table mesh 24x36 octant)"),
    ("sze-pinched-cylinder", (16, 16), {}, 0.03, "study"),
    ("sze-pinched-cylinder", (24, 24), {}, 0.03, "study"),
    ("sze-pinched-cylinder", (32, 32), {}, 0.03, "study"),
    ("sze-pinched-cylinder", (48, 48), {}, 0.03, "full (table mesh 48x48 octant)"),
    ("sze-pinched-cylinder", (48, 48), {"diaphragm_theta_axis": 0.0}, None,
     "study: diaphragm rotations free (the MBDyn and Elmer inputs' support)"),
    ("sze-pinched-cylinder", (32, 32), {"diaphragm_theta_axis": 0.0, "diaphragm_tilt": 1.0}, None,
     "study: diaphragm normal held normal to the ring (another finite-rotation reading)"),
]


def main(argv=None):
    from core_se3.backend import pin_for_timing
    pin_for_timing()          # time the compiled product, not 'auto''s NumPy start
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None, help="case names to run")
    ap.add_argument("--plots", default=None, help="directory for PNG plots")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results" / "sze"))
    ap.add_argument("--rewrite", action="store_true", help="only rewrite the .md from the .json")
    args = ap.parse_args(argv)
    rows = []
    if args.rewrite:
        data = json.loads(Path(args.out).with_suffix(".json").read_text())
        write_md(Path(args.out), data["meta"], data["runs"])
        return
    for name, mesh, over, bar, role in RUNS:
        if args.only and name not in args.only:
            continue
        t0 = time.perf_counter()
        doc, res, prob = catalogue.run_case(name, mesh=mesh, overrides=over)
        wall = time.perf_counter() - t0
        ref = doc["reference"]
        bar = bar if role != "study" else None          # the bars apply at the full meshes
        row = dict(case=name, mesh=f"{mesh[0]}x{mesh[1]}", overrides=over, role=role,
                   deviation=ref["deviation"], bar=bar,
                   passes=None if bar is None else bool(ref["deviation"] <= bar),
                   curves=ref["curves"], steps=len(doc["steps"]) - 1, wall_s=round(wall, 1),
                   n_dofs=doc["mesh"]["n_dofs"], critical_points=doc.get("critical_points", []),
                   unverified=ref.get("unverified", []),
                   run=datetime.datetime.utcnow().isoformat(timespec="seconds") + "Z")
        rows.append(row)
        print(f"{name:22s} {row['mesh']:>6s} {str(over):14s} deviation {100 * row['deviation']:6.2f} % "
              f"({row['steps']} steps, {wall:.1f} s)" + "".join(
                  f"  {c['kind']} {c['load_factor']:.4f}" for c in row["critical_points"]), flush=True)
        if args.plots:
            from core_se3.catalogue.family_sze import plot
            tag = _tag(dict(overrides=over)).replace(" ", "-").replace("-whole", "-full")
            plot(get_case(name), catalogue.case_params(get_case(name), over), doc, res,
                 str(Path(args.plots) / f"{name}{tag}-{row['mesh']}.png"))
    out = Path(args.out)
    if args.only and out.with_suffix(".json").exists():      # keep the other cases' rows
        old = json.loads(out.with_suffix(".json").read_text())["runs"]
        keep = [r for r in old if r["case"] not in args.only]
        order = [n for n, *_ in RUNS]
        rows = sorted(keep + rows, key=lambda r: order.index(r["case"]))
    meta = dict(date=datetime.datetime.utcnow().isoformat(timespec="seconds") + "Z",
                machine=platform.platform(), python=platform.python_version(),
                command="python benchmarks/sze.py " + " ".join(argv or sys.argv[1:]))
    out.with_suffix(".json").write_text(json.dumps(dict(meta=meta, runs=rows), indent=1))
    write_md(out, meta, rows)
    print(f"wrote {out.with_suffix('.md')} and .json")


def _tag(r):
    o = r["overrides"]
    return ((" whole" if o.get("full") else "") + (" tilt" if o.get("diaphragm_tilt") else "")
            + (" free" if o.get("diaphragm_theta_axis") == 0.0 and not o.get("diaphragm_tilt") else ""))


def write_md(out, meta, rows):
    lines = ["# Sze et al. (2004) suite with core_se3", "",
             f"{meta['date']}, `{meta['command']}`, {meta['machine']} (2 cores shared with other jobs: "
             "wall times are indicative)", "",
             "Deviation = largest distance of a computed point to the table polyline in "
             "(P/P_max, u/u_max), u_max per column, max over the case's columns. Bars (issue 6) "
             "apply at the full meshes; study rows have none. Column run: when the row was computed "
             "(`--only` reruns keep the other cases' rows; '-' = before per-row dates were recorded, "
             "i.e. an earlier full or --only run).", "",
             "| case | mesh | role | deviation | bar | steps | dofs | wall [s] | critical points (P/P_max) | run |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        crit = ", ".join(f"{c['kind']} {c['load_factor']:.4f}" for c in r["critical_points"]) or "-"
        bar = None if r["role"] == "study" else r["bar"]
        bar = "-" if bar is None else f"{100 * bar:.0f} % ({'ok' if r['deviation'] <= bar else 'FAIL'})"
        lines.append(f"| `{r['case']}` | {r['mesh']}{_tag(r)} | "
                     f"{r['role']} | {100 * r['deviation']:.2f} % | {bar} | {r['steps']} | {r['n_dofs']} | "
                     f"{r['wall_s']} | {crit} | {r.get('run', '-')} |")
    lines += ["", "End points (computed vs table, P/P_max and u):", ""]
    for r in rows:
        for c in r["curves"]:
            lines.append(f"* `{r['case']}` {r['mesh']}{_tag(r)} "
                         f"{c['column']}: computed "
                         f"({c['computed_end']['P_over_Pmax']:.4f}, {c['computed_end']['u']:.4f}), table "
                         f"({c['table_end']['P_over_Pmax']:.4f}, {c['table_end']['u']:.4f}); worst point "
                         f"{100 * c['deviation']:.2f} % at P/P_max = {c['at']['P_over_Pmax']:.4f}")
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out.with_suffix('.md')} and .json")


if __name__ == "__main__":
    main()

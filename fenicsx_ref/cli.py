"""Command line: ``python -m fenicsx_ref bench list`` / ``bench run NAME [options]``."""
from __future__ import annotations

import argparse
import json
import logging
import sys


def _parse_set(items):
    out = {}
    for it in items or []:
        if "=" not in it:
            raise SystemExit(f"--set expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        out[k.strip()] = float(v)
    return out


def _parse_mesh(s):
    try:
        nx, ny = s.lower().split("x")
        return int(nx), int(ny)
    except ValueError:
        raise SystemExit(f"--mesh expects NXxNY (e.g. 16x1), got {s!r}") from None


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m fenicsx_ref",
                                 description="fenicsx_ref: DOLFINx Naghdi shell on the core_se3 benchmark cases")
    sub = ap.add_subparsers(dest="cmd", required=True)
    bench = sub.add_parser("bench", help="benchmark cases")
    bsub = bench.add_subparsers(dest="bcmd", required=True)
    bsub.add_parser("list", help="list the cases")
    run = bsub.add_parser("run", help="run one case")
    run.add_argument("name")
    run.add_argument("--mesh", type=_parse_mesh, default=None, help="NXxNY elements (default: the case's)")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a case parameter")
    run.add_argument("--integration", choices=["full", "psri"], default="psri")
    run.add_argument("--shear-factor", type=float, default=1.0)
    run.add_argument("--steps", type=int, default=None)
    run.add_argument("--cell", choices=["quadrilateral", "triangle"], default="quadrilateral")
    run.add_argument("--json", default=None, metavar="FILE", help="write the result JSON here ('-' = stdout)")
    a = ap.parse_args(argv)

    from core_se3.cases import list_cases
    if a.bcmd == "list":
        for name, desc in list_cases():
            print(f"{name:24s} {desc}")
        return 0

    logging.getLogger().setLevel(logging.WARNING)  # silence FFCx/CFFI build chatter
    from . import run_case
    r = run_case(a.name, mesh=a.mesh, overrides=_parse_set(a.set), steps=a.steps,
                 integration=a.integration, shear_factor=a.shear_factor, cell=a.cell)
    if a.json == "-":
        json.dump(r, sys.stdout, indent=1)
        print()
    else:
        if a.json:
            with open(a.json, "w", encoding="utf-8") as f:
                json.dump(r, f, indent=1)
        m = r["mesh"]
        print(f"{r['case']} [{r['variant']}] mesh {m['nx']}x{m['ny']} ({m['n_dofs']} dofs): {r['status']}")
        print(f"{'load':>14s} {'ux':>12s} {'uy':>10s} {'uz':>12s} {'angle':>10s} {'it':>4s}")
        for s in r["steps"]:
            u = s["probes"]["tip"]["u"]
            print(f"{s['load']['value']:14.6g} {u[0]:12.6g} {u[1]:10.3g} {u[2]:12.6g} "
                  f"{s['probes']['tip']['rotation_angle']:10.6f} {s['iterations']:4d}")
        if r["reference"]:
            print(f"reference {r['reference']['entry']}: error {r['reference']['error']:.3e} "
                  f"({r['reference']['n_points']} reference loads)")
        t = r["timings"]
        print("timings [s]: " + ", ".join(f"{k} {v:.2f}" for k, v in t.items()))
    return 0 if r["status"] == "ok" else 1

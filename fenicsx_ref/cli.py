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
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise SystemExit(f"--set {k.strip()}: the value must be a number, got {v!r}") from None
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

    from core_se3.catalogue import list_cases
    if a.bcmd == "list":
        for name, desc in list_cases():
            print(f"{name:24s} {desc}")
        return 0

    from . import run_case
    from .solver import _import_dolfinx
    _import_dolfinx()
    logging.disable(logging.INFO)  # silence the FFCx/CFFI/setuptools build chatter
    from core_se3.errors import CoreSE3Error
    try:
        r = run_case(a.name, mesh=a.mesh, overrides=_parse_set(a.set), steps=a.steps,
                     integration=a.integration, shear_factor=a.shear_factor, cell=a.cell)
    except (CoreSE3Error, KeyError, NotImplementedError) as exc:  # a bad input / a case it cannot run
        print(f"error: {type(exc).__name__}: {exc.args[0] if exc.args else exc}", file=sys.stderr)
        return 2
    if a.name == "torsion":  # the small-twist torsion constant, as core_se3 reports it
        from core_se3.catalogue.references import elastica_entry
        from .solver import torsion_constant
        d = torsion_constant(mesh=a.mesh, integration=a.integration, shear_factor=a.shear_factor,
                             cell=a.cell, overrides=_parse_set(a.set))
        e = elastica_entry("5_strip_torsion_seed_strip")["params"]
        r["torsion"] = {"J": d["J"], "J_interior": d["J_interior"], "angle": d["angle"],
                        "mesh": [r["mesh"]["nx"], r["mesh"]["ny"]],
                        "reference_entry": "5_strip_torsion_seed_strip",
                        "J_mindlin_ks1": e["J_mindlin_ks=1"],
                        "J_kirchhoff_plate": e["J_kirchhoff_plate=wh^3/3"],
                        "note": "J = T L/(G angle) includes the end restraint of the rotation about "
                                "the width axis (clamp and rigid end edge), ~ +0.08/L here; "
                                "J_interior = T/(G tau_mid) is the Saint-Venant value."}
    if a.json == "-":
        json.dump(r, sys.stdout, indent=1)
        print()
    else:
        if a.json:
            with open(a.json, "w", encoding="utf-8") as f:
                json.dump(r, f, indent=1)
        m = r["mesh"]
        print(f"{r['case']} [{r['variant']}] mesh {m['nx']}x{m['ny']} ({m['n_dofs']} dofs): {r['status']}")
        probe = next(iter(r["steps"][0]["probes"])) if r["steps"] else "tip"
        print(f"probe {probe}")
        print(f"{'load':>14s} {'ux':>12s} {'uy':>10s} {'uz':>12s} {'angle':>10s} {'it':>4s}"
              + (f" {'moment':>12s}" if r["steps"] and "reactions" in r["steps"][0] else ""))
        for s in r["steps"]:
            u = s["probes"][probe]["u"]
            line = (f"{s['load']['value']:14.6g} {u[0]:12.6g} {u[1]:10.3g} {u[2]:12.6g} "
                    f"{s['probes'][probe]['rotation_angle']:10.6f} {s['iterations']:4d}")
            if "reactions" in s:
                line += f" {s['reactions'][0]['moment_about_axis']:12.6g}"
            print(line)
        trunc = r["options"].get("reference_truncated_at")
        if trunc:  # the case's load range was shortened (|theta| reaches pi beyond it)
            from core_se3.catalogue import get_case
            print(f"path ends at load factor {trunc['load_factor']:.6g} (the case's range ends at "
                  f"{get_case(a.name).lam_range[1]:g}): {trunc['reason']}")
        if r["reference"]:
            ref = r["reference"]
            if ref["error"] is None:
                print(f"reference {ref['entry']}: {ref.get('note', 'no reference load on the path')}")
            else:
                print(f"reference {ref['entry']}: error {ref['error']:.3e} ({ref['n_points']} points"
                      + (f"; {ref['measure']}" if "measure" in ref else "")
                      + ("" if r["status"] == "ok" else "; over the converged part of the path only") + ")")
        if "torsion" in r:
            t = r["torsion"]
            print(f"small-twist torsion constant J = T L/(G angle) = {t['J']:.5e}, from the interior "
                  f"twist rate {t['J_interior']:.5e} (J_mindlin_ks=1 = {t['J_mindlin_ks1']:.5e}; "
                  f"ratios {t['J'] / t['J_mindlin_ks1']:.4f}, {t['J_interior'] / t['J_mindlin_ks1']:.4f})")
        t = r["timings"]
        print("timings [s]: " + ", ".join(f"{k} {v:.2f}" for k, v in t.items()))
    return 0 if r["status"] == "ok" else 1

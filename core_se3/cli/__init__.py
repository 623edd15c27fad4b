"""Command line (the top layer): ``core-se3 bench list``, ``core-se3 bench run NAME [options]``,
``core-se3 run SCENARIO.toml [--out DIR] [--resume] [--strict]`` (scenario files, see
docs/SCENARIOS.md), ``core-se3 sweep SCENARIO.toml --set KEY=v1,v2,...`` and
``core-se3 design SCENARIO.toml [--out DIR]`` (a scenario's [design], docs/DESIGN.md),
``core-se3 check-mesh SCENARIO.toml [--levels N] [--tol T]`` (the mesh against its refinements) and
``core-se3 warmup`` (compile the numba kernels once); the scenario commands live in
``cli.scenario``.

``-v`` shows the solvers' per-step log (``logging`` at INFO on stderr)."""
from __future__ import annotations

import argparse
import logging
import os
import sys

import numpy as np

from ..backend import launched_rank, launched_ranks
from ..errors import CoreSE3Error
from ..fem import ELEMENTS
from ..results.document import ROUNDOFF_NOTE, format_backends, format_residual
from .common import error_code as _error_code, interrupted as _interrupted, output_error as _output_error, \
    progress_on as _progress_on, whole_number
from .scenario import (add_parsers, design_run, friction_cells, friction_obstacles, kinds, mesh_check,
                       scenario_run, scenario_sweep, step_table as _step_table, warmup)


def _parse_mesh(s):
    try:
        nx, ny = s.lower().split("x")
        return int(nx), int(ny)
    except ValueError:
        raise argparse.ArgumentTypeError(f"mesh must look like 16x1, got {s!r}") from None


def _parse_set(items):
    """``bench run --set KEY=VALUE ...`` as {KEY: float}; SystemExit naming the --set for a value
    that is not a finite number (before, load_max=nan was reported as the edge force's
    'got array([nan, nan, nan])') or a KEY given twice (the second silently replaced the first)."""
    out = {}
    for it in items or []:
        if "=" not in it:
            raise SystemExit(f"--set expects KEY=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        if k in out:
            raise SystemExit(f"--set {k} is given twice (the second would silently replace the first): give it once")
        try:
            out[k] = float(v)
        except ValueError:
            raise SystemExit(f"--set {k}: value {v!r} is not a number") from None
        if not np.isfinite(out[k]):
            raise SystemExit(f"--set {k}: value {v!r} is not a finite number")
    return out


def _count(step, key):
    v = step.get(key)
    return "-" if v is None else str(v)


def _print_doc(doc):
    m = doc["mesh"]
    shape = f"{m['nx']}x{m['ny']}" if m["nx"] is not None else f"{m['n_elements']} elements"
    print(f"case {doc['case']}  model {doc['model']}  element {doc['variant']}  "
          f"mesh {shape} ({m['n_dofs']} dofs)")
    print("params: " + ", ".join(f"{k}={v['value']:g} [{v['unit']}]" for k, v in doc["params"].items()))
    ref = doc["reference"]
    obstacles = list(doc["steps"][-1].get("contact", {}))    # total contact force |F| per obstacle
    print(f"{'load':>12} {'ux':>12} {'uy':>12} {'uz':>12} {'angle':>9} {'it':>3} {'try':>3} {'solves':>6} "
          f"{'residual':>9}" + "".join(f" {'|F ' + o + '|':>12}" for o in obstacles)
          + "".join(f" {'N ' + o:>12} {'T ' + o:>12} {'stick/slip':>10}" for o in friction_obstacles(doc["steps"]))
          + ("  error" if ref else ""))
    probe = next(iter(doc["steps"][0]["probes"]))          # the case's probe ('tip', 'crown', ...)
    for s in doc["steps"]:
        u = s["probes"][probe]["u"]
        line = (f"{s['load']['value']:>12.5g} {u[0]:>12.5g} {u[1]:>12.5g} {u[2]:>12.5g} "
                f"{s['probes'][probe]['rotation_angle']:>9.4f} {s['iterations']:>3d} {_count(s, 'attempts'):>3} "
                f"{_count(s, 'linear_solves'):>6} {format_residual(s)}")
        for o in obstacles:
            c = s.get("contact", {}).get(o)
            line += f" {float(np.linalg.norm(c['force'])) if c else 0.0:>12.5g}"
        line += "".join(friction_cells(s, o) for o in friction_obstacles(doc["steps"]))
        if ref and s.get("error") is not None:
            line += f"  {100 * s['error']:.3f}%"
        print(line)
    if any(format_residual(s).endswith("*") for s in doc["steps"]):
        print(ROUNDOFF_NOTE)
    if format_backends(doc["steps"]):
        print(format_backends(doc["steps"]))
    if ref and ref.get("error") is None:
        print(f"reference {ref['file']}:{ref['entry']}: {ref.get('note', 'not compared')}")
    elif ref:
        print(f"reference {ref['file']}:{ref['entry']} [{ref['block']}]: error {100 * ref['error']:.3f}% "
              f"({ref.get('measure', 'max over the path of |u - u_ref| / max |u_ref|')})")
        if ref.get("note"):                  # e.g. partial: steps beyond the table not compared
            print(f"  {ref['note']}")
    if "torsion" in doc:
        t = doc["torsion"]
        print(f"small-twist torsion constant J = {t['J']:.4e} (mesh {t['mesh'][0]}x{t['mesh'][1]}); "
              + ("" if t["J_mindlin_ks1"] is None else f"Mindlin plate ks=1: {t['J_mindlin_ks1']:.4e}, ")
              + f"thin plate w h^3/3: {t['J_kirchhoff_plate']:.4e}")
        if t["J_mindlin_ks1"] is None:
            print(f"  {t['note']}")
    tot = doc.get("totals") or {}
    if tot.get("linear_solves") is not None:
        print(f"cost: {tot['attempts']} Newton tries, {tot['iterations']} iterations of the stored tries, "
              f"{tot['linear_solves']} linear solves")
    t = doc["timings"]
    print("timings [s]: " + ", ".join(f"{k} {t[k]:.3f}" for k in ("setup", "assembly", "solve", "other", "total")))
    what = "applied loads, reactions and contact forces balance" if obstacles else \
        "reactions balance the applied loads"
    print(f"{what} to {max(s['balance_error'] for s in doc['steps']):.1e}")


def _plot_generic(case, p, doc, path, name):
    from ..catalogue import reference_for
    from ..io import plot_load_deflection
    loads = np.array([s["load"]["value"] for s in doc["steps"]])
    u = np.array([s["probes"]["tip"]["u"] for s in doc["steps"]])
    disp = {"ux": u[:, 0], "uy": u[:, 1], "uz": u[:, 2]}
    reference = None
    rr = reference_for(case, p)
    if rr is not None:
        entry, block, r = rr
        # reference load axis -> case load axis
        lmax = loads.max() if loads.max() > 0 else loads.min()
        Lc = r["load"] / case.reference.load_to_ref(p, 1.0)
        sel = (Lc >= min(0, lmax) - 1e-12) & (Lc <= max(0, lmax) + 1e-12)
        vkey = "uy" if case.extra.get("plane") == "xy" else "uz"
        reference = {"ux": (Lc[sel], r["u"][sel]), vkey: (Lc[sel], r["v"][sel])}
    shape = f"{doc['mesh']['nx']}x{doc['mesh']['ny']}"
    plot_load_deflection(path, loads, disp, reference=reference,
                         axes=("tip displacement [length]",
                               f"{doc['steps'][-1]['load']['name']} [{doc['steps'][-1]['load']['unit']}]"),
                         title=f"{name} ({doc['variant']}, {shape})")


def _case_plot(name, overrides, doc, res, path):
    """The case's PNG: its family's plot, or the load-deflection curve of its tip probe."""
    from ..catalogue import case_params, family_of, get_case
    case = get_case(name)
    p = case_params(case, overrides)
    fam = family_of(case)
    if fam is not None and fam.plot is not None:
        fam.plot(case, p, doc, res, path)
    else:
        _plot_generic(case, p, doc, path, name)


BENCH_FILES = ("step_*.vtu", "series.pvd", "obstacles.pvd")     # a bench's --vtu names (never over foreign ones)


def _plot_target_error(path):
    """Why the image ``path`` cannot be written -- an existing directory, an extension matplotlib
    has no writer for -- or None: checked before the case solves, not after (a bare ValueError
    from savefig; for a directory, 'Is a directory' naming the temporary file after the solve)."""
    if os.path.isdir(path):
        return (f"--plot {path!r} is a directory: give the path of an image file (e.g. "
                f"{os.path.join(path, 'plot.png')!r})")
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    if not ext:
        return None                            # matplotlib's default format (png)
    from matplotlib.backend_bases import FigureCanvasBase
    known = FigureCanvasBase.get_supported_filetypes()
    return None if ext in known else (f"--plot {path!r}: matplotlib writes no '.{ext}' images (it writes "
                                      f"{', '.join(sorted(known))}): give a path such as plot.png")


def _json_target_error(path):
    """Why --json may not write ``path``: an existing file that is not an earlier ``bench run``
    JSON (a scenario, a run's results.json, notes: the user's), else None."""
    from .common import existing_json
    exists, old = existing_json(path)
    if not exists:
        return None
    if isinstance(old, dict) and old.get("schema") == "core-se3-result" and "case" in old and "scenario" not in old:
        return None                            # (a run's results.json names its scenario)
    if os.path.isdir(path):
        return f"--json {path!r} is a directory: give the path of a file (e.g. {os.path.join(path, 'case.json')!r})"
    return f"--json {path!r} is a file that is not an earlier bench run's JSON: give another path (e.g. case.json)"


def bench_run(args):
    """``core-se3 bench run``; with ``--plot`` matplotlib is imported by a forked worker while the
    case solves (``io.worker.PlotProcess``; not under MPI)."""
    from ..io.lifecycle import termination_as_interrupt
    from ..io.rundir import RunDirectory
    from ..io.worker import PlotProcess
    from ..scenario.context import on_root
    bad = (_plot_target_error(args.plot) if args.plot else None) or (_json_target_error(args.json) if args.json
                                                                      else None)
    if bad is not None:
        if launched_rank() == 0:
            print(f"error: {bad}", file=sys.stderr)
        return 2
    rd = RunDirectory(args.vtu, "bench", BENCH_FILES, option="--vtu") if args.vtu else None
    try:       # a run directory's rules: never over a file it did not write; its own earlier files go
        if rd is not None:
            on_root(lambda: rd.claim(force=args.force, replace=True))
    except CoreSE3Error as exc:
        if launched_rank() == 0:
            print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        return _output_error(exc, "nothing was solved")
    try:       # (the plot worker is forked before the handlers: it keeps the default ones)
        with PlotProcess(enabled=bool(args.plot) and launched_ranks() == 1) as plots, termination_as_interrupt():
            return _bench_run(args, plots, rd)
    except KeyboardInterrupt as exc:            # Ctrl-C or SIGTERM: one line, 130 or 143 (was a traceback)
        return _interrupted(exc, "the case stopped; the outputs said 'wrote ...' above are complete (each file is "
                                 "written whole), the others are not written: run it again")
    finally:
        if rd is not None:
            rd.release()


def _bench_run(args, plots, rd):
    from ..catalogue import family_of, get_case, run_case
    from ..io import LogProgress, Progress
    try:
        case = get_case(args.name)
        ELEMENTS.lookup(args.element)
        if not args.quiet:
            print(f"case {case.name}: units " + ", ".join(f"{k} [{u}]" for k, u in case.units.items()))
        kw = dict(linear=args.linear) if args.linear and launched_ranks() > 1 else {}   # distributed runs
        bar = Progress(None, _progress_on(args) and launched_rank() == 0, delay=0.0 if args.progress else 2.0)
        with LogProgress(bar):
            doc, res, prob = run_case(args.name, mesh=args.mesh, overrides=_parse_set(args.set),
                                      steps=args.steps, element=args.element, linear_solver=args.solver, **kw)
    except (CoreSE3Error, KeyError) as exc:
        if launched_rank() == 0:         # every rank reads the same input and meets the same error
            print(f"error: {exc.args[0] if isinstance(exc, KeyError) and exc.args else exc}", file=sys.stderr)
        return 2
    if launched_rank() != 0:                 # under mpirun: rank 0 reports and writes
        return 0
    if args.plot:                     # drawn by the worker while the other outputs are written
        plots.submit(_case_plot, args.name, _parse_set(args.set), doc, res, args.plot)
    _print_doc(doc)
    fam = family_of(case)
    if fam is not None and fam.report is not None:
        for line in fam.report(doc):
            print(line)
    try:
        _write_bench_outputs(args, doc, res, prob, plots, rd)
    except OSError as exc:
        return _output_error(exc, "the solve finished and its table above is complete")
    return 0


def _write_bench_outputs(args, doc, res, prob, plots, rd):
    """The --json, --vtu (in the claimed RunDirectory ``rd``) and --plot outputs of ``bench run``
    (the plot drawn by the worker)."""
    from ..io import write_json_atomic
    if args.json:                         # written beside and moved into place: a full disk keeps the earlier one
        write_json_atomic(args.json, doc)
        print(f"wrote {args.json}")
    if args.vtu:                          # the files of core-se3 run's vtu/ (scenario.sinks.step_files)
        from ..scenario.sinks import write_path_vtu
        pvd = write_path_vtu(rd, ".", prob, res.steps)
        print(f"wrote {len(res.steps)} VTU files and {pvd}")
    if args.plot:
        plots.wait()
        print(f"wrote {args.plot}")


def _bench_parsers(sub):
    """``bench list`` and ``bench run NAME [options]``."""
    bench = sub.add_parser("bench", help="benchmark catalogue")
    bsub = bench.add_subparsers(dest="bcmd", required=True)
    bsub.add_parser("list", help="list the catalogue cases")
    run = bsub.add_parser("run", help="run a catalogue case")
    run.add_argument("name")
    run.add_argument("--mesh", type=_parse_mesh, default=None, help="NXxNY, e.g. 16x1")
    run.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a case parameter")
    run.add_argument("--steps", type=whole_number("steps"), default=None, help="load steps (>= 1; default the case's)")
    run.add_argument("--element", default="default", help=f"element: {', '.join(sorted(ELEMENTS))}")
    run.add_argument("--solver", choices=["auto", "banded", "mumps", "superlu"], default="auto")
    run.add_argument("--linear", choices=["mumps", "gamg", "hypre"], default=None,
                     help="linear solver of a distributed run (mpirun -n N, N > 1; docs/PARALLEL.md)")
    run.add_argument("--json", default=None)
    run.add_argument("--vtu", default=None, help="directory for VTU files and series.pvd (its earlier bench files "
                     "are replaced; files core-se3 did not write are refused, kept with --force)")
    run.add_argument("--force", action="store_true", help="write the VTU files beside files core-se3 did not write "
                     "(never over them)")
    run.add_argument("--plot", default=None, help="PNG load-deflection plot")
    run.add_argument("-v", "--verbose", action="store_true", help="log every Newton (sub-)step")
    both = run.add_mutually_exclusive_group()        # one or the other: both is a usage error
    both.add_argument("--progress", action="store_true", help="progress line even when not on a terminal")
    both.add_argument("-q", "--quiet", action="store_true", help="no progress line")


def parser():
    """The ``core-se3`` argument parser, every subcommand with its options (tests/test_docs_claims.py
    parses every command line of the docs with it)."""
    ap = argparse.ArgumentParser(prog="core-se3", description="Geometrically exact Cosserat shells on SE(3)")
    sub = ap.add_subparsers(dest="cmd", required=True)
    _bench_parsers(sub)
    add_parsers(sub)
    return ap


def main(argv=None):
    args = parser().parse_args(argv)
    if launched_rank() != 0 and args.cmd in ("run", "bench"):     # under mpirun: rank 0 prints
        sys.stdout = open(os.devnull, "w")
    if getattr(args, "verbose", False):
        logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
        logging.getLogger("core_se3").setLevel(logging.INFO)
    commands = {"run": scenario_run, "design": design_run, "sweep": scenario_sweep, "warmup": warmup, "kinds": kinds,
                "check-mesh": mesh_check}
    if args.cmd in commands:
        return commands[args.cmd](args)
    if args.cmd == "bench" and args.bcmd == "list":
        from ..catalogue import CASES
        for c in CASES.values():
            print(f"{c.name:<24} {c.description}")
        return 0
    if args.cmd == "bench" and args.bcmd == "run":
        return bench_run(args)
    return 1


def console_main():
    """The ``core-se3`` program: :func:`main` on ``sys.argv``, then ``gc.freeze()`` before the
    interpreter exits.  The main job ends with 130,000 objects tracked by the collector (48,000
    with the NumPy backend: most are numba's types and typing templates); Python's collections
    over them at shutdown took 0.2-0.27 s after main returned (five runs; 0.02-0.03 s with
    ``os._exit``, 0.05-0.07 s with ``gc.freeze``).  Frozen objects are merely skipped by the
    collector: files, atexit handlers and finalisers run as before."""
    code = main()
    import gc
    gc.freeze()
    return code


if __name__ == "__main__":
    sys.exit(console_main())

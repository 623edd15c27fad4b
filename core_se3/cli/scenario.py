"""The scenario commands of ``core-se3``: ``run`` (with ``--check``), ``sweep``, ``design`` and
``warmup`` (docs/SCENARIOS.md, docs/DESIGN.md)."""
from __future__ import annotations

import os
import sys

from ..backend import launched_rank
from ..errors import CoreSE3Error, MeshWarning, ScenarioWarning, SupportWarning
from ..results.document import ROUNDOFF_NOTE, format_backends, format_residual
from .common import error_code, interrupted, output_error, whole_number

__all__ = ["add_parsers", "scenario_run", "scenario_sweep", "design_run", "warmup", "step_table", "kinds", "mesh_check"]


def add_parsers(sub):
    """The subcommands run, sweep, design and warmup of the ``core-se3`` parser."""
    srun = sub.add_parser("run", help="run a scenario file (TOML; schema in docs/SCENARIOS.md)")
    srun.add_argument("scenario", help="SCENARIO.toml")
    srun.add_argument("--out", default=None, help="output directory (default [output] dir or out/NAME)")
    srun.add_argument("--resume", action="store_true", help="continue from the checkpoint in --out")
    srun.add_argument("--force", action="store_true",
                      help="start over even if --out holds a run (deletes only that run's files)")
    srun.add_argument("--check", action="store_true", help="only validate the scenario (and estimate its memory)")
    srun.add_argument("--strict", action="store_true", help="make the plausibility warnings errors")
    _plugin(srun)
    _common(srun, "progress bar even when not on a terminal", "no progress bar, no summary")
    dsub = sub.add_parser("design", help="optimise the [design] of a scenario file (docs/DESIGN.md)")
    dsub.add_argument("scenario", help="SCENARIO.toml with a [design] section")
    dsub.add_argument("--out", default=None, help="output directory (default [output] dir or out/NAME-design)")
    dsub.add_argument("--method", default=None, help="least_squares, L-BFGS-B, SLSQP or trust-constr")
    dsub.add_argument("--max-iter", type=whole_number("max-iter"), default=None,
                      help="iterations (least_squares: evaluations; >= 1)")
    dsub.add_argument("--force", action="store_true", help="write into a directory of an earlier design")
    dsub.add_argument("-q", "--quiet", action="store_true", help="no progress, no summary")
    dsub.add_argument("-v", "--verbose", action="store_true", help="log every Newton (sub-)step")
    _plugin(dsub)
    sw = sub.add_parser("sweep", help="run a scenario over a grid of values (one CSV and plot)")
    sw.add_argument("scenario", help="SCENARIO.toml")
    sw.add_argument("--set", action="append", metavar="KEY=v1,v2,...",
                    help="a dotted key and its values (typed as in TOML; a vector as [a;b;c]); repeat for a grid")
    sw.add_argument("--out", default=None, help="directory of sweep.csv and sweep.png (default out/NAME-sweep)")
    sw.add_argument("--cold", action="store_true", help="no warm starts: every run steps from the reference")
    sw.add_argument("--resume", action="store_true", help="continue an interrupted sweep in --out")
    sw.add_argument("--force", action="store_true", help="start over in a directory of an earlier sweep")
    sw.add_argument("--strict", action="store_true", help="make the plausibility warnings errors")
    _progress_or_quiet(sw, "progress line even when not on a terminal", "no progress line, no summary")
    _plugin(sw)
    kinds = sub.add_parser("kinds", help="list the registered kinds of every section and their keys",
                           epilog="sections: generator, law, supports, loads, fields, obstacles, variables, targets")
    kinds.add_argument("section", nargs="?", default=None, help="only this section (e.g. loads)")
    _plugin(kinds)
    sub.add_parser("warmup", help="compile the numba kernels once into their cache (scripts/setup.sh runs it)")
    chk = sub.add_parser("check-mesh", help="is the mesh fine enough? the linear analysis on it and on its uniform "
                                            "refinements, compared (exit status 4 if not)")
    chk.add_argument("scenario", help="SCENARIO.toml")
    chk.add_argument("--levels", type=whole_number("levels"), default=1,
                     help="refinements after the scenario's mesh (each: four times the elements; default 1)")
    chk.add_argument("--tol", type=float, default=None, help="largest relative change accepted (default 0.05)")
    chk.add_argument("--json", default=None, metavar="PATH", help="also write the check as JSON")
    chk.add_argument("--nonlinear", action="store_true",
                     help="run the scenario itself (its solver, with its obstacles) on every mesh instead of "
                          "its linear analysis")
    chk.add_argument("--strict", action="store_true", help="make the plausibility warnings errors")
    _plugin(chk)


def _plugin(p):
    p.add_argument("--plugin", action="append", metavar="FILE", default=[],
                   help="import FILE (a .py file, or a module name) first: its registered kinds "
                        "(loads, obstacles, material laws, ...) become usable in the scenario; repeatable")


def _plugins(args):
    """Import the --plugin files (relative to the working directory) before the scenario."""
    import os
    from ..scenario.plugins import load_plugins
    load_plugins(getattr(args, "plugin", None) or [], os.getcwd(), None, "--plugin")


def kinds(args):
    """``core-se3 kinds [SECTION]``: the registered kinds and their keys (with --plugin's)."""
    from ..scenario.schema import describe_kinds
    try:
        _plugins(args)
    except CoreSE3Error as exc:
        return error_code(exc)
    text = describe_kinds(args.section)
    if not text:
        print(f"error: no section matches {args.section!r} (generator, law, supports, loads, fields, obstacles, "
              "variables, targets)", file=sys.stderr)
        return 2
    print(text)
    return 0


def _progress_or_quiet(p, progress, quiet):
    """--progress and -q/--quiet, one or the other (both: a usage error, exit status 2)."""
    both = p.add_mutually_exclusive_group()
    both.add_argument("--progress", action="store_true", help=progress)
    both.add_argument("-q", "--quiet", action="store_true", help=quiet)


def _common(p, progress, quiet):
    _progress_or_quiet(p, progress, quiet)
    p.add_argument("-v", "--verbose", action="store_true", help="log every Newton (sub-)step")


def _load_quietly(path, strict):
    """Load a scenario, its warnings kept (printed by the command, not by ``warnings``)."""
    import warnings
    from .. import scenario
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.load(path, strict=strict)


def _preamble(scn, quiet):
    """The first lines of a run: the unit system, the warnings, the load numbers (rank 0 of an
    MPI launch: every rank reads the same scenario)."""
    from ..scenario.units import describe_units
    if launched_rank() != 0:
        return
    for w in scn.warnings:
        print(f"warning: {w}", file=sys.stderr)
    if quiet:
        return
    print(f"{scn.name}: {describe_units(scn.spec['units'])}")
    for n in scn.load_numbers():
        print(f"  load number {n['name']} ({n['kind']}): {n['formula']} = {n['value']:.4g} "
              f"(span L = {n['span']:.4g}, E = {n['E']:.4g}, h = {n['h']:.4g})")


# what an interrupt while a scenario is read and validated (a large mesh file, a refinement) left:
# one line, exit status 130/143, not a traceback
_UNREAD = "it stopped while reading and checking the scenario: nothing was written"

# the warnings a run prints as ``warning:`` lines: the scenario's and those Problem.solve gives on
# its final state (model.solving.warn_final_state)
_RUN_WARNINGS = (ScenarioWarning, SupportWarning, MeshWarning)


class _warnings_once:
    """The scenario warnings of a sweep's points as ``warning: ...`` lines, each text once: every
    value is validated and then run, so each point's warnings came twice, as Python warnings
    showing an internal line of code, and the base scenario's (printed first) again per point.
    ``categories``: the warnings so printed (default ScenarioWarning; a run adds those of its
    final state, ``model.solving.warn_final_state``)."""

    def __init__(self, shown=(), categories=(ScenarioWarning,)):
        self.shown = {str(w) for w in shown}
        self.categories = categories

    def __enter__(self):
        import warnings
        self.old = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            if not issubclass(category, self.categories):
                return self.old(message, category, filename, lineno, file, line)
            if str(message) not in self.shown:
                self.shown.add(str(message))
                print(f"warning: {message}", file=sys.stderr)
        warnings.showwarning = show
        return self

    def __exit__(self, *exc):
        import warnings
        warnings.showwarning = self.old
        return False


def _check(args, scn):
    """``--check``: the summary of a valid scenario, its mesh's parts and its memory estimate
    (a warning past the machine's memory); a [sweep] section's values and points validated as
    ``core-se3 sweep`` validates them before its first run (``scenario.check_sweep``: a bad
    value passed --check and stopped the sweep)."""
    from ..scenario.memory import estimate, machine_memory
    from ..scenario.sweep import check_sweep
    points = None
    if scn.spec["sweep"]:
        try:
            with _warnings_once(scn.warnings):
                points = check_sweep(scn)[1]
        except CoreSE3Error as exc:
            return error_code(exc)
        except KeyboardInterrupt as exc:
            return interrupted(exc, "it stopped while checking the [sweep] points: nothing was written")
    print(f"{args.scenario}: valid ({scn.mesh.n_elements} elements, {scn.mesh.n_nodes} nodes, "
          f"{len(scn.spec['supports'])} supports, {len(scn.spec['loads'])} loads, "
          f"{len(scn.spec['magnets'])} magnets, {_path_summary(scn)})")
    if points is not None:
        print(f"  sweep: {len(points)} point(s) of {', '.join(scn.spec['sweep'])} valid (core-se3 sweep runs them)")
    est = estimate(scn)
    print(f"  memory: about {est.bytes / 2 ** 30:.3g} GiB ({est.describe()})")
    have = machine_memory()
    if have is not None and est.bytes > have:
        print(f"warning: {args.scenario}: the run needs about {est.bytes / 2 ** 30:.3g} GiB, more than this "
              f"machine's {have / 2 ** 30:.3g} GiB: coarsen the mesh, or run it on more memory (mpirun -n N "
              "shares it over the ranks' machines)", file=sys.stderr)
    return 0


def _path_summary(scn):
    """The solve --check announces: the load steps (their number, from load_factors too), a linear
    analysis or an arc-length path, to the final load factor (it said '10 steps', the default of
    an unused key, for a linear analysis)."""
    s, lams = scn.solver, scn.load_factors()
    if s["control"] == "linear":
        return f"a linear analysis at load factor {lams[-1]:g}"
    if s["control"] == "arclength":
        return f"arc length to load factor {s['lam_end']:g}, at most {s['max_steps']} points"
    return f"{len(lams)} steps to load factor {lams[-1]:g}"


def _open(args):
    """The scenario file of ``run``/``sweep``, its --plugin files imported first (CoreSE3Error)."""
    _plugins(args)
    return _load_quietly(args.scenario, args.strict)


def _guarded(call, kept, resume):
    """(call(), None), or (None, the exit status) of a long run's error: a CoreSE3Error, an
    OSError writing its outputs (``kept``: what is kept) or an interrupt (``resume``: where it
    stopped and how to continue); either may be a function giving it when the error comes."""
    try:
        return call(), None
    except CoreSE3Error as exc:
        return None, error_code(exc)
    except OSError as exc:
        return None, output_error(exc, kept() if callable(kept) else kept)
    except KeyboardInterrupt as exc:
        return None, interrupted(exc, resume() if callable(resume) else resume)


def _sweep_stopped(scn, out):
    """What an interrupted sweep left: its finished rows (sweep.npz in its directory: continue
    with --resume), or nothing yet (stopped while it validated its grid or ran its first point:
    --resume would find nothing to continue)."""
    import os
    from ..scenario.runner import output_directory
    if os.path.exists(os.path.join(output_directory(scn, out, "-sweep"), "sweep.npz")):
        return "the finished runs are in sweep.csv (sweep.json says where it stopped): continue with --resume"
    return "it stopped before its first finished run: nothing to continue; run it again (without --resume)"


def _run_stopped(scn, out):
    """What a run that stopped (an output it could not write, an interrupt) kept: the step and
    load factor of the checkpoint in its directory (continue with --resume), or that no load step
    converged, so nothing is kept to continue.  (Before: 'the steps converged so far are kept'
    also when none had.)"""
    from ..errors import CheckpointError
    from ..io import Checkpoint
    from ..scenario.runner import output_directory
    ck = Checkpoint(output_directory(scn, out))
    try:
        st = ck.load() if ck.exists() else None
    except (CheckpointError, OSError):
        st = None
    if st is None or st["step"] < 1:
        return (f"no load step converged: nothing is kept to continue from (no checkpoint of a load step in "
                f"{ck.directory}); run it again (with --force where {ck.directory} holds this run's files)")
    return (f"the checkpoint {ck.path} keeps step {st['step']} at load factor {st['lam']:.6g} (results.json "
            "records the steps to it): continue with --resume")


def _contradiction(args):
    """--resume (continue) and --force (start over) together: an error line, exit status 2."""
    if getattr(args, "resume", False) and getattr(args, "force", False):
        print("error: --resume continues the run in --out and --force starts it over: give one of them",
              file=sys.stderr)
        return 2
    return None


def scenario_run(args):
    """``core-se3 run``: validate the scenario, solve it step by step, write its outputs."""
    from .. import scenario
    if _contradiction(args):
        return 2
    try:
        scn = _open(args)
    except CoreSE3Error as exc:
        return error_code(exc)
    except KeyboardInterrupt as exc:
        return interrupted(exc, _UNREAD)
    _preamble(scn, args.quiet)
    if args.check:
        return _check(args, scn)
    progress = True if args.progress else (False if args.quiet else None)
    with _warnings_once(scn.warnings, _RUN_WARNINGS):
        res, code = _guarded(lambda: scenario.run(scn, out=args.out, resume=args.resume, progress=progress,
                                                  force=args.force),
                             lambda: _run_stopped(scn, args.out), lambda: _run_stopped(scn, args.out))
    if code is not None:
        return code
    if not args.quiet:
        _summary(scn, res)
    return 0


def _summary(scn, res):
    last = res.doc["steps"][-1]
    step_table(res.doc)
    print(f"{scn.name}: {len(res.doc['steps']) - 1} steps to load factor {last['load_factor']:g} "
          f"in {res.doc['timings']['total']:.2f} s")
    for name, p in last["probes"].items():
        u = p["u"]
        print(f"  probe {name}: u = ({u[0]:.6g}, {u[1]:.6g}, {u[2]:.6g}), rotation {p['rotation_angle']:.6g} rad")
    for name, r in (last.get("support_reactions") or {}).items():
        f, m, c = r["force"], r["moment_about_point"], r["point"]
        print(f"  support {name}: force ({f[0]:.6g}, {f[1]:.6g}, {f[2]:.6g}), moment ({m[0]:.6g}, {m[1]:.6g}, "
              f"{m[2]:.6g}) about its nodes' centroid ({c[0]:.6g}, {c[1]:.6g}, {c[2]:.6g}) on the shell")
    for name, c in (last.get("contact") or {}).items():
        f = c["force"]
        print(f"  contact {name}: force ({f[0]:.6g}, {f[1]:.6g}, {f[2]:.6g}) on the shell"
              + (f", {c['nodes_in_contact']} nodes in contact" if "nodes_in_contact" in c else ""))
    for c in res.doc.get("critical_points") or []:     # passed (limit_check off), snaps, arc length's
        print(f"  critical point between steps {c['step'] - 1} and {c['step']}: {c['description']}")
    for kind, path in res.files.items():
        print(f"  wrote {kind}: {path}")


def step_table(doc):
    """One line per step: load factor, the physical loads (with units), the first probe, the
    total contact force |F| of every obstacle, the total support reaction |R| (its force, lab
    total of the held dofs and springs), iterations, the relative residual, its force and moment
    parts |r_F|, |r_M| (norms on the free dofs, in the force and moment units:
    ``residual_force``, ``residual_moment``) and the step's largest Newton correction
    |eta|_s / ell (``max_correction``; '-' where not counted)."""
    import numpy as np
    steps = doc["steps"]
    phys = list((steps[-1].get("physical") or {}).items())
    probe = next(iter(steps[0]["probes"]), None)
    obstacles = list(steps[-1].get("contact") or {})
    head = f"{'step':>5} {'lam':>9}" + "".join(f" {k + ' [' + v['unit'] + ']' if v['unit'] else k:>22}"
                                             for k, v in phys)
    if probe:
        head += f" {probe + '.ux':>12} {probe + '.uy':>12} {probe + '.uz':>12}"
    head += "".join(f" {'|F ' + o + '|':>12}" for o in obstacles)
    rough = friction_obstacles(steps)
    head += "".join(f" {'N ' + o:>12} {'T ' + o:>12} {'stick/slip':>10}" for o in rough)
    reacts = any("reactions" in st for st in steps)
    if reacts:
        unit = (doc.get("unit_system") or {}).get("force")
        head += f" {'|R|' + (' [' + unit + ']' if unit else ''):>12}"
    moved = any(st.get("max_correction") is not None for st in steps)
    parts = any(st.get("residual_force") is not None for st in steps)
    head += f" {'it':>3} {'residual':>9}"
    if parts:
        us = doc.get("unit_system") or {}
        head += "".join(f" {name + (' [' + us[dim] + ']' if us.get(dim) else ''):>12}"
                        for name, dim in (("|r_F|", "force"), ("|r_M|", "moment")))
    print(head + (f" {'correction':>10}" if moved else ""))
    for st in steps:
        line = f"{st['step']:>5d} {st['load_factor']:>9.4g}"
        line += "".join(f" {(st.get('physical') or {}).get(k, {}).get('value', float('nan')):>22.6g}" for k, _ in phys)
        if probe:
            line += "".join(f" {x:>12.6g}" for x in st["probes"][probe]["u"])
        for o in obstacles:
            c = (st.get("contact") or {}).get(o)
            line += f" {float(np.linalg.norm(c['force'])) if c else 0.0:>12.6g}"
        line += "".join(friction_cells(st, o) for o in rough)
        if reacts:
            r = st.get("reactions")
            line += f" {float(np.linalg.norm(r['force'])):>12.6g}" if r else f" {'-':>12}"
        line += f" {st.get('iterations', 0):>3d} {format_residual(st)}"
        if parts:
            line += "".join(f" {st[k]:>12.2e}" if st.get(k) is not None else f" {'-':>12}"
                            for k in ("residual_force", "residual_moment"))
        if moved:
            c = st.get("max_correction")
            line += f" {c:>10.2e}" if c is not None else f" {'-':>10}"
        print(line)
    if any(format_residual(st).endswith("*") for st in steps):
        print(ROUNDOFF_NOTE)
    if format_backends(steps):
        print(format_backends(steps))


def friction_obstacles(steps):
    """The obstacles with Coulomb friction in the step records (their report has the normal
    and tangential totals and the stick/slip counts, ``model.contact_output``).

    Example
    -------
    >>> friction_obstacles([{"contact": {"a": {"force": [0, 0, 1]}, "b": {"normal_force": 1.0}}}])
    ['b']
    """
    names = []
    for st in steps:
        names += [o for o, c in (st.get("contact") or {}).items() if "normal_force" in c and o not in names]
    return names


def friction_cells(st, o):
    """The step table's cells of a rough obstacle: the normal and tangential totals [force] and
    the nodes sticking / slipping ('-' where the step has no record of it).

    Example
    -------
    >>> friction_cells({"contact": {"t": dict(normal_force=2.0, tangential_force=0.5, sticking=3, slipping=1)}}, "t")
    '            2          0.5        3/1'
    """
    c = (st.get("contact") or {}).get(o)
    if not c or "normal_force" not in c:
        return f" {'-':>12} {'-':>12} {'-':>10}"
    return (f" {c['normal_force']:>12.6g} {c['tangential_force']:>12.6g} "
            f"{str(c['sticking']) + '/' + str(c['slipping']):>10}")


def _design_files_kept(exc):
    """What a design whose output failed (``exc``, an OSError) wrote and did not: the files
    written before it (``exc.written``, by ``run_design``) are kept, design.json (written last)
    and the failed file are not."""
    written = getattr(exc, "written", None) or {}
    failed = exc.filename or "the file above"
    if not written:
        return f"no file of the design is written ({failed} failed; design.json is written last)"
    return (f"written: {', '.join(map(str, written.values()))}; not written: {failed} and the design's files after "
            "it (design.json, its summary, is written last)")


def design_run(args):
    """``core-se3 design``: optimise the [design] of a scenario, write the optimised scenario and
    the design's outputs (docs/DESIGN.md)."""
    from .. import scenario
    from ..scenario.design_runner import run_design
    try:
        _plugins(args)
        scn = scenario.load(args.scenario)
        if "design" not in scn.spec:
            print(f"error: {args.scenario} has no [design] section (docs/DESIGN.md)", file=sys.stderr)
            return 2
        r, files = run_design(scn, out=args.out, method=args.method, max_iter=args.max_iter,
                              progress=not args.quiet and launched_rank() == 0, force=args.force)
    except CoreSE3Error as exc:
        return error_code(exc)
    except OSError as exc:
        return output_error(exc, _design_files_kept(exc))
    except KeyboardInterrupt as exc:
        return interrupted(exc, "the design is not finished (its outputs are written at the end)")
    if not args.quiet and launched_rank() == 0:          # under mpirun: rank 0 reports
        print(f"{scn.name}: {r.message}")
        print(f"  objective {r.objective:.6e} after {r.iterations} iterations, {r.equilibrium_solves} equilibrium "
              f"solves, {r.newton_iterations} Newton iterations, {r.time:.2f} s")
        for label, x in zip(r.labels, r.x):
            print(f"  {label} = {x:.8g}")
        for kind, path in files.items():
            print(f"  wrote {kind}: {path}")
    return 0 if r.reached is not False else 4


def _grid(args, scn):
    from ..scenario.sweep import parse_values
    grid = {}
    for item in args.set or []:
        if "=" not in item:
            raise CoreSE3Error(f"--set expects KEY=v1,v2,..., got {item!r}")
        k, vals = item.split("=", 1)
        if k.strip() in grid:
            raise CoreSE3Error(f"--set {k.strip()} is given twice (the second would silently replace the first): "
                               "give all its values in one --set KEY=v1,v2,...")
        grid[k.strip()] = parse_values(vals, f"--set {k.strip()}")
    if not grid and not scn.spec["sweep"]:
        raise CoreSE3Error(f"{args.scenario}: nothing to sweep: give --set KEY=v1,v2,... or a [sweep] section")
    if grid and scn.spec["sweep"]:              # one grid or the other: say which is dropped
        print(f"note: {args.scenario}: --set replaces the scenario's [sweep] section "
              f"({', '.join(scn.spec['sweep'])}): its values are not run", file=sys.stderr)
    return grid or None                         # None: the scenario's [sweep] section


def scenario_sweep(args):
    """``core-se3 sweep``: the scenario over the values of --set KEY=v1,v2,... (or [sweep])."""
    from .. import scenario
    if _contradiction(args):
        return 2
    try:
        scn = _open(args)
        grid = _grid(args, scn)
    except CoreSE3Error as exc:
        return error_code(exc)
    except KeyboardInterrupt as exc:
        return interrupted(exc, _UNREAD)
    _preamble(scn, args.quiet)
    progress = True if args.progress else (False if args.quiet else None)
    with _warnings_once(scn.warnings, _RUN_WARNINGS):
        res, code = _guarded(lambda: scenario.sweep(scn, grid, out=args.out, progress=progress, warm=not args.cold,
                                                    resume=args.resume, force=args.force),
                             lambda: _sweep_stopped(scn, args.out), lambda: _sweep_stopped(scn, args.out))
    if code is not None:
        return code
    failed = [r for r in res.rows if r["status"] != "complete"]
    if not args.quiet:
        print(f"{scn.name}: {len(res.rows)} runs ({len(failed)} failed, "
              f"{sum(bool(r.get('warm')) for r in res.rows)} warm-started)")
        for kind, path in res.files.items():
            print(f"  wrote {kind}: {path}")
    return 3 if failed else 0


def mesh_check(args):
    """``core-se3 check-mesh``: the scenario's linear analysis on its mesh and refinements, the
    table and the verdict; exit status 0 (within --tol), 4 (not converged), 2 (bad input), 3 (a
    --nonlinear run that did not converge).  --json PATH gets the check with status "complete",
    or, when the check fails, status "failed" and the error (as ``run``'s results.json): a JSON
    of an earlier check is never left there to be read as this one's."""
    from ..io.files import write_json_atomic
    from ..io.lifecycle import termination_as_interrupt
    from ..scenario.mesh_check import DEFAULT_TOL, check_mesh
    try:
        scn = _open(args)
    except CoreSE3Error as exc:
        return _check_failed(args, exc, known_output=False)
    except KeyboardInterrupt as exc:        # --json PATH replaced only where it is an earlier check's
        return _check_interrupted(args, exc) if not args.json or _earlier_check(args.json) else \
            interrupted(exc, _UNREAD)
    clash = (_input_at(args.json, scn, args) or (None if _earlier_check(args.json) else
                                                  "a file that is not an earlier check's JSON")) if args.json else None
    if clash is not None:
        print(f"error: --json {args.json!r} is a directory: give the path of a file (e.g. "
              f"{os.path.join(args.json, 'check.json')!r})" if os.path.isdir(args.json) else
              f"error: --json {args.json!r} is {clash}: the check would overwrite it; give another path "
              "(e.g. check.json)", file=sys.stderr)
        return 2
    try:
        with termination_as_interrupt():
            chk = check_mesh(scn, levels=args.levels, tol=DEFAULT_TOL if args.tol is None else args.tol,
                             nonlinear=args.nonlinear)
    except CoreSE3Error as exc:
        return _check_failed(args, exc, known_output=True)
    except KeyboardInterrupt as exc:
        return _check_interrupted(args, exc)
    for w in scn.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(chk.report())
    if args.json:
        try:
            write_json_atomic(args.json, dict(status="complete", **chk.to_dict()))
        except OSError as exc:
            return output_error(exc, "the check is printed above")
    return 0 if chk.converged else 4


def _check_interrupted(args, exc):
    """The exit status of a check-mesh ended by SIGTERM or Ctrl-C (130/143), after writing --json
    PATH (atomically) as {"status": "interrupted", "signal": ..., "levels": the meshes done, ...},
    as ``run`` marks its results.json: an earlier check's verdict is not left there."""
    from ..io.files import write_json_atomic
    name = getattr(exc, "signal_name", "SIGINT")
    partial = getattr(exc, "mesh_check", None)
    done = len(partial.levels) if partial is not None else 0
    code = interrupted(exc, f"the check stopped after {done} mesh(es)" + (f"; --json {args.json} says so"
                                                                             if args.json else ""))
    if not args.json:
        return code
    doc = dict(status="interrupted", signal=name, error=f"interrupted by {name} after {done} mesh(es)",
               scenario=args.scenario, exit_status=code)
    if partial is not None:
        doc.update(name=partial.name, lam=partial.lam, tol=partial.tol, nonlinear=partial.nonlinear,
                   levels=partial.levels, changes=partial.changes, dropped=partial.dropped, warnings=partial.warnings)
    try:
        write_json_atomic(args.json, doc)
    except OSError as err:
        return output_error(err, "the check was interrupted")
    return code


def _check_failed(args, exc, known_output):
    """The exit status of a check-mesh that failed (``error_code``), after writing --json PATH
    (atomically) as {"status": "failed", "error": ..., "scenario": ...}, so that a script does not
    read an earlier check's verdict there.  ``known_output``: PATH is known not to be an input of
    the scenario (``_input_at``); when the scenario did not load, its inputs are unknown and only
    a missing file or an earlier check's JSON (a JSON object with "status" or "levels") is
    replaced."""
    from ..io.files import write_json_atomic
    code = error_code(exc)
    if not args.json:
        return code
    if not known_output and not _earlier_check(args.json):
        return code                            # not a check's JSON: perhaps an input, left alone
    try:
        write_json_atomic(args.json, dict(status="failed", error=str(exc), scenario=args.scenario, exit_status=code))
    except OSError as err:
        return output_error(err, "the error is printed above")
    return code


def _earlier_check(path):
    """True if ``path`` is missing or holds an earlier check's JSON (an object with "status" or
    "levels", not a run's results.json): --json may replace it; any other file is the user's."""
    from .common import existing_json
    exists, old = existing_json(path)
    if not exists:
        return True
    return isinstance(old, dict) and ("status" in old or "levels" in old) and "schema" not in old


def _input_at(path, scn, args):
    """What input of the scenario lies at ``path`` (its file, mesh file, magnetisation table or
    plugin), or None."""
    import os
    def at(p, base):
        return os.path.realpath(p if os.path.isabs(p) else os.path.join(base, p))
    mine = at(path, os.getcwd())
    spec = scn.spec
    inputs = [("the scenario file", at(args.scenario, os.getcwd()))]
    if "file" in spec["mesh"]:
        inputs.append(("its mesh file", at(spec["mesh"]["file"], scn.base_dir)))
    inputs += [(f"the magnetisation table of magnets[{i}]", at(m["Br_table"]["path"], scn.base_dir))
               for i, m in enumerate(spec["magnets"]) if "Br_table" in m]
    inputs += [("a plugin file", at(p, scn.base_dir)) for p in spec.get("plugins", []) if p.endswith(".py")]
    inputs += [("a --plugin file", at(p, os.getcwd())) for p in getattr(args, "plugin", None) or [] if p.endswith(".py")]
    for what, p in inputs:
        if p == mine or (os.path.exists(p) and os.path.exists(mine) and os.path.samefile(p, mine)):
            return what
    return None


def warmup(args):
    """``core-se3 warmup``: compile every numba kernel into its cache (``kernels.cache``), once
    per version of the kernels' source, so that no run pays for it."""
    from .warmup import warm_kernels
    try:
        done = warm_kernels(progress=True)
    except CoreSE3Error as exc:
        return error_code(exc)
    print(done)
    return 0

"""Run a scenario: one loop over the solver's converged steps (load-stepped Newton or arc length),
each step fed to small sinks that write its outputs and a checkpoint (``scenario.sinks``), so that
an interrupted or failed run continues with ``resume=True``.

    from core_se3 import scenario
    res = scenario.run(scenario.load("gripper.toml"), out="out/gripper")
    res.doc["steps"][-1]["probes"]["tip"]["u"], res.g

The checkpoint is the record of truth: on resume, the steps it holds are kept and the solver
continues from its restart state, repeating the computations of an uninterrupted run from the
same bits.  The output directory holds the run's own files only, listed in its manifest, and
one live run at a time (``io.rundir``); SIGTERM and Ctrl-C end a run with ``status =
"interrupted"``, a message and the checkpoint of the last converged step.

Run directory:  results.json (schema core-se3-result v1 plus status/scenario/provenance fields),
checkpoint.npz, vtu/step_NNNN.vtu + vtu/series.pvd, probes.png, shell.png,
.core-se3-manifest.json, and .core-se3.lock while the run lives.
"""
from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ..backend import rent_state, restore_rent
from ..errors import CheckpointError, ConvergenceError, CoreSE3Error, OptionError, ScenarioError
from ..fem import ELEMENTS
from ..io import Checkpoint, write_json_atomic
from ..io.lifecycle import Terminated, held_signals, termination_as_interrupt
from ..io.rundir import RunDirectory, safe_name
from ..model.solving import warn_final_state
from ..results import Result, StepRecorder, step_record
from ..solvers import ArcLengthOptions, ArcState, CriticalPoint, NewtonOptions, NewtonState, arc_length_steps
from ..solvers.linear import linear_solve
from .context import on_root, run_context
from .outputs import cell_fields, physical_record, picture, plot_probes, point_fields, unit_system_record  # noqa: F401
from .provenance import run_provenance
from .resume import check_checkpoint, check_session, session_record
from .sinks import (RUN_FILES, CheckpointSink, DocumentSink, ProgressSink, ProvenanceSink, PvdSink, RunInterrupted,
                    RunState, StepEvent, StopAfter, VtuSink, write_series_files, write_step_vtu)

__all__ = ["run", "RunResult", "RunInterrupted", "point_fields", "cell_fields", "physical_record",
           "unit_system_record", "output_directory"]


@dataclass
class RunResult:
    """What a run left: the results document, the final frames, the output files.

    Attributes: ``doc`` (the results document: schema core-se3-result v1 with status, scenario,
    fingerprint; ``status`` its status), ``g`` (n, 4, 4) the final frames, ``out`` the run
    directory, ``files``: kind -> path (results, checkpoint, pvd, probes, picture).

    Example
    -------
    >>> import tempfile
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}], "solver": {"steps": 2},
    ...     "output": {"vtu": False, "plots": False, "picture": False}})
    >>> res = run(scn, out=tempfile.mkdtemp())
    >>> res.status, len(res.doc["steps"]), sorted(res.files), res.g.shape
    ('complete', 3, ['checkpoint', 'results'], (10, 4, 4))
    """
    doc: dict
    g: np.ndarray
    out: str
    files: dict = field(default_factory=dict)

    @property
    def status(self):
        return self.doc["status"]


def output_directory(scn, out=None, suffix=""):
    """The run directory: ``out``, else ``[output] dir``, else ``out/NAME`` with the scenario's
    name made safe (``io.rundir.safe_name``: a name of ``../..`` stays under ``out/``); a sweep's
    and a design's (``suffix``) beside the run's, also from ``[output] dir`` (the three shared
    it: a sweep of a scenario with ``dir`` met its run's files).  A leading ``~`` is the home
    folder, as a shell reads it (before, ``dir = "~/runs/a"`` made a folder named '~' in the
    working directory).

    Example
    -------
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"name": "../../etc", "mesh": {"generator": "rectangle", "L": 1.0, "width": 1.0,
    ...     "nx": 2, "ny": 1}, "material": {"E": 1e3, "nu": 0.0, "h": 0.01}, "supports": [{"type": "clamp", "edge": "x0"}]})
    >>> output_directory(scn), output_directory(scn, suffix="-sweep")
    ('out/___etc', 'out/___etc-sweep')
    """
    if out:
        return os.path.expanduser(os.fspath(out))
    if scn.output["dir"]:             # "~/runs" is the home folder's, not a folder named '~' here
        base = os.path.normpath(os.path.expanduser(os.fspath(scn.output["dir"])))
        if suffix and os.path.basename(base) in ("", ".", ".."):      # dir = "." or "/": a folder in it
            return os.path.join(base, suffix.lstrip("-"))
        return base + suffix
    return os.path.join("out", safe_name(scn.name) + suffix)


def _options(s):
    common = dict(rtol=s["rtol"], dtol=s["dtol"], max_iter=s["max_iter"], linear_solver=s["linear_solver"])
    if s["control"] == "arclength":
        return ArcLengthOptions(method=s["method"], dlam0=s["dlam0"], psi=s["psi"], max_steps=s["max_steps"],
                                target_iter=s["target_iter"], ds_max_factor=s["ds_max_factor"],
                                stability=s["stability"], critical_tol=s["critical_tol"], **common)
    return NewtonOptions(max_cutbacks=s["max_cutbacks"], iteration=s["iteration"],
                         predictor=s.get("predictor", "none"), path_check=s["path_check"],
                         limit_check=s["limit_check"], critical_tol=s["critical_tol"],
                         max_substeps=s["max_substeps"],
                         snap_check=s["snap_check"], inertia_check=s["inertia_check"], end_check=s["end_check"],
                         midpoint_probe=s.get("midpoint_probe", True),
                         refine_check=s.get("refine_check", True),
                         friction_check=s["friction_check"], friction_tol=s["friction_tol"],
                         friction_halving=s["friction_halving"],
                         **common)


def run(scn, out=None, resume=False, progress=None, force=False, stop_after=None, verbose=False):
    """Solve a validated Scenario, writing its outputs in ``out`` (default [output] dir or
    out/NAME).  resume: continue from the checkpoint in ``out`` (a run stopped before its first
    checkpoint starts over); force: start over even if ``out`` holds a run (deleting only its
    files).  progress: None = only on a terminal (after 2 s), True = always.  stop_after: stop
    with RunInterrupted once that many steps are done in this call (tests).
    ConvergenceError propagates after the failure is recorded (status "failed"); SIGTERM and
    Ctrl-C raise ``io.lifecycle.Terminated`` (a KeyboardInterrupt) after status "interrupted";
    the checkpoint keeps the last converged step.  ``verbose`` is accepted for compatibility.

    Parameters: scn (Scenario) and the keywords above; a missing or foreign checkpoint, an
    ``out`` that holds a run without resume or force, files this tool did not write or another
    live run is a CheckpointError.  Returns: RunResult.

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}], "solver": {"steps": 2},
    ...     "output": {"vtu": False, "plots": False, "picture": False}})
    >>> res = run(scn, out=tempfile.mkdtemp())
    >>> [s["load_factor"] for s in res.doc["steps"]], sorted(os.listdir(res.out))
    ([0.0, 0.5, 1.0], ['.core-se3-manifest.json', 'checkpoint.npz', 'results.json'])
    """
    t0 = time.perf_counter()
    prob, s = scn.problem, scn.solver
    if resume and ELEMENTS.lookup(prob.element_name).stateful:
        raise CheckpointError(f"--resume is not supported with the stateful {s['element']} element")
    rd = RunDirectory(output_directory(scn, out), "run", RUN_FILES)
    with termination_as_interrupt():
        on_root(lambda: rd.claim(resume=resume, force=force, adopt=RUN_FILES))
        try:
            st = _resume_state(scn, rd) if resume else None
            ctx = _context(scn, st)
            try:
                return _run(scn, rd, ctx, st, progress, stop_after, t0)
            finally:
                ctx.close()
        except KeyboardInterrupt as exc:
            if not getattr(exc, "recorded", False):
                _mark_interrupted(rd, exc)
            raise
        finally:
            rd.release()


def _mark_interrupted(rd, exc):
    """A signal before the run's sinks took over (while it read its checkpoint or set up its
    context): the results document of the earlier session, if any, says so."""
    import json
    from ..backend import launched_rank
    path = os.path.join(rd.path, "results.json")
    if launched_rank() != 0 or not os.path.exists(path) or getattr(rd, "completed", False):
        return                            # (a signal while a completed run drew its plots)
    what = exc.describe() if isinstance(exc, Terminated) else "Ctrl-C (SIGINT)"
    with held_signals():
        with open(path) as fh:
            doc = json.load(fh)
        doc.update(status="interrupted", error=f"interrupted by {what} while the run started; the checkpoint keeps "
                                               "its last converged step: continue with --resume")
        write_json_atomic(rd.file("results.json"), doc)


def _context(scn, st):
    """The run's context (``scenario.context``); a [solver.petsc] option PETSc refuses is a
    ScenarioError naming its key."""
    try:
        # arc length and linear analysis run serially on every rank of an MPI launch
        return run_context(scn.problem, scn.solver, scn.solver["control"] != "load", st)
    except OptionError as exc:
        if getattr(exc, "param", None):
            raise ScenarioError(str(exc), scn.file, f"solver.{exc.param}") from None
        raise


def _resume_state(scn, rd):
    """The checkpoint to continue from, checked against the scenario (None: a run stopped before
    its first checkpoint, whose files go: it starts over).  A run whose results.json holds
    converged steps but whose checkpoint is gone (deleted to save space) is refused: it was
    started over silently, its results and VTU files replaced."""
    ck = Checkpoint(rd.path)
    lost = _lost_checkpoint(rd) if rd.existed and not ck.exists() else None
    if on_root(lambda: not ck.exists() and rd.existed and lost is None and (rd.start_over() or True)):
        return None
    if not ck.exists():
        raise CheckpointError(lost or f"no checkpoint to resume from: {ck.path} does not exist (run without --resume "
                                      "first)")
    st = ck.load()
    check_checkpoint(ck.path, st, scn)
    restore_rent(st["extra"].get("backend"))
    return st


def _lost_checkpoint(rd):
    """The refusal of a resume whose run made progress (results.json records converged steps past
    the start: the checkpoint is written before each step's record) but whose checkpoint is
    missing; None where there is nothing to lose (no or an unreadable results.json, or no step
    past the start)."""
    import json
    path = os.path.join(rd.path, "results.json")
    try:
        with open(path) as fh:
            doc = json.load(fh)
        done = [r for r in doc.get("steps") or [] if int(r.get("step", 0)) > 0]
    except (OSError, ValueError, TypeError, AttributeError):
        return None
    if not done:
        return None
    return (f"cannot resume: {os.path.join(rd.path, 'checkpoint.npz')} is missing, but {path} records {len(done)} "
            f"converged step(s) to load factor {float(done[-1].get('load_factor', float('nan'))):g} (status "
            f"{doc.get('status')!r}): they cannot be continued without it, and --resume would replace them; start "
            "over with --force, or use another --out")


def _run(scn, rd, ctx, st, progress, stop_after, t0):
    run = RunState(scn, rd, ctx, result=Result(mesh=scn.problem.mesh, element=scn.problem.element_name),
                   critical=None if scn.solver["control"] == "linear" else [],
                   provenance=run_provenance(scn, ctx), sessions=[dict(session_record(scn, ctx.ranks), first_step=0)])
    start, unwrap = _restore(run, st) if st is not None else (None, None)
    rec = StepRecorder(scn.problem, unwrap)
    ctx.barrier()                            # every rank has read the directory before rank 0 writes
    sinks = _sinks(run, progress, stop_after)
    try:
        if start is None and not run.arc:
            start = _feed(run, sinks, _initial_event(run, rec))
        run.base["setup"] = run.base.get("setup", 0.0) + time.perf_counter() - t0
        last = _drive(run, sinks, _events(run, start, rec))
    except RunInterrupted:
        for sink in sinks:
            if isinstance(sink, ProgressSink):
                sink.end(run, "running")
        raise
    except BaseException as exc:
        again = _stopped(run, sinks, exc)
        if again is not None:
            raise again from None
        raise
    return _complete(run, sinks, last or start)


def _sinks(run, progress, stop_after):
    """The sinks of a run, in the order they see each step (``scenario.sinks``); the results
    document is written at once (status running)."""
    o = run.scn.output
    doc = DocumentSink()
    vtu = VtuSink(o["vtu_every"])
    sinks = ([vtu] if o["vtu"] else []) + [CheckpointSink()] + ([PvdSink(vtu)] if o["vtu"] else [])
    sinks += [ProvenanceSink(), doc, ProgressSink(run, progress, None if run.arc else len(run.scn.load_factors()))]
    sinks += [StopAfter(stop_after)] if stop_after is not None else []
    doc.start(run)
    return sinks


def _restore(run, st):
    """Records, timings, sessions and the solver's restart state of a checkpoint: (start, unwrap)
    (a session of another package version is refused, another difference said: ``check_session``)."""
    run.records, run.base, run.done = st["records"], dict(st["timings"]), st["step"]
    run.saved = len(run.records)
    before = st["extra"].get("sessions")
    check_session(os.path.join(run.rd.path, "checkpoint.npz"), before, run.sessions[-1], say=run.root)
    run.sessions = list(before or []) + [dict(run.sessions[-1], first_step=run.done + 1)]
    if run.arc:
        start = ArcState.unpack(st["g"], st["extra"]["arc"], st["arrays"])
        run.critical = list(start.critical)
    else:
        nw = st["extra"].get("newton", {})
        run.critical = [CriticalPoint.unpack(c) for c in st["extra"].get("critical", [])]
        run.critical_before = len(run.critical)       # the earlier sessions'; this one's follow
        start = NewtonState.unpack(st["lam"], st["g"], nw, NewtonState.multipliers_of(st["arrays"]), st["arrays"])
    return start, st["unwrap"]


def _record(k, st, iterations=None, substeps=1, cutbacks=0):
    rec = dict(step=k, **step_record(st, dict(name="load factor", value=float(st.load_factor), unit="")))
    if iterations is not None:
        rec["iterations"] = int(iterations)
    rec["substeps"], rec["cutbacks"] = int(substeps), int(cutbacks)
    rec["balance_error"] = rec.pop("balance_error")
    return rec


def _initial_event(run, rec):
    """Step 0 of load control: the unloaded reference state."""
    g0 = run.scn.problem.mesh.g0.copy()
    record = _record(0, rec.step(0.0, g0, 0, [], run.ctx.initial_forces(g0)), 0, 0, 0)
    record["balance_error"] = 0.0            # the unloaded start, not an equilibrium
    record["physical"] = physical_record(run.scn, 0.0)
    extra = dict(newton=NewtonState(0.0, g0).pack(), physical=run.scn.physical, ranks=run.ctx.ranks,
                 backend=rent_state(), sessions=run.sessions)
    return StepEvent(0, record, g0, 0.0, False, extra, run.ctx.checkpoint_arrays(), rec.unwrapped)


def _feed(run, sinks, ev):
    """Give one step to every sink (its record first joins the run's records); returns the
    solver state to continue from (load control's start)."""
    run.records.append(ev.record)
    for sink in sinks:
        sink.step(run, ev)
    run.last = ev
    return NewtonState(ev.lam, ev.g) if ev.k == 0 and not run.arc else ev


def _events(run, start, rec):
    """The solver's steps as StepEvents (arc length: its path points)."""
    scn = run.scn
    opts = _options(scn.solver)
    if run.arc:
        for item in arc_length_steps(scn.problem, lam_end=scn.solver["lam_end"], start=start, result=run.result,
                                     options=opts):
            k = item.state.step
            scalars, arrays = item.state.pack()
            record = _record(k, item.step, substeps=1 if k else 0)
            st = item.step.stability               # the inertia that brackets the critical points
            record["stability"] = dict(det_sign=int(st["det_sign"]), negative_eigenvalues=st["negative_eigenvalues"])
            run.critical = list(item.state.critical)
            yield _event(run, k, record, item, bool(item.state.finished), dict(control="arclength", arc=scalars),
                         arrays, item.state.unwrap)
        return
    if scn.solver["control"] == "linear":
        yield from _linear_events(run, rec)
        return
    lams, k = scn.load_factors(), run.done
    run.path = [SimpleNamespace(g=np.array(start.g), load_factor=float(start.lam))]
    for item in run.ctx.steps(lams[k:], opts, start, rec, run.result):
        k += 1
        run.path.append(item.step)
        # the critical points load control passed (limit_check off; contact snaps): results.json's
        # critical_points, as [solver] limit_check and snap_check say -- before, only arc length's
        new = run.result.critical_points[len(run.critical) - run.critical_before:]
        run.critical += [dataclasses.replace(c, step=k) for c in new]   # the stored step that passed it
        tries = item.tries
        record = _record(k, item.step, sum(e["iterations"] for e in tries),
                         sum(e["converged"] and not e.get("augmented") for e in tries),
                         sum(not e["converged"] for e in tries))
        arrays = {**(item.state.arrays() or {}), **(run.ctx.checkpoint_arrays() or {})} or None
        yield _event(run, k, record, item, k == len(lams), dict(newton=item.state.pack(), ranks=run.ctx.ranks,
                                                                critical=[c.pack() for c in run.critical]),
                     arrays, rec.unwrapped)


def _linear_events(run, rec):
    """control = "linear": the one step of a linear analysis (``solvers.linear_solve``) at lam_end."""
    s = run.scn.solver
    res = linear_solve(run.scn.problem, lam_end=s["lam_end"], linear_solver=s["linear_solver"])
    step = res.steps[-1]
    for k, t in res.timings.items():
        run.result.timings[k] = run.result.timings.get(k, 0.0) + t
    record = _record(1, step, 1, 1, 0)
    item = SimpleNamespace(step=step)
    yield _event(run, 1, record, item, True, dict(newton=NewtonState(step.load_factor, step.g).pack(),
                                                  ranks=run.ctx.ranks), None, rec.unwrapped)


def _event(run, k, record, item, finished, extra, arrays, unwrap):
    lam = item.step.load_factor
    record["physical"] = physical_record(run.scn, lam)
    # where 'auto' stands (a resume continues from it), and what each session ran with
    extra.update(physical=run.scn.physical, backend=rent_state(), sessions=run.sessions)
    return StepEvent(k, record, item.step.g, lam, finished, extra, arrays, unwrap)


def _drive(run, sinks, events):
    """The one loop: every step to every sink; returns the last event."""
    last = None
    for ev in events:
        _feed(run, sinks, ev)
        last = ev
    return last


def _stopped(run, sinks, exc):
    """A run that stops early: the status and message in results.json (the checkpoint keeps the
    last converged step; its VTU file is written if it was not due), every other sink closed, with
    signals held while the files are written.  Returns the exception to raise instead of ``exc``
    (a ConvergenceError with the message), or None.  The document reports the steps the
    checkpoint holds (a signal during a step's writing leaves that step to the resume)."""
    del run.records[run.saved:]
    last = run.records[-1] if run.records else None
    where = "before its first step" if last is None else \
        f"after {'path point' if run.arc else 'step'} {last['step']} at load factor {last['load_factor']:.6g}"
    again = None
    if isinstance(exc, KeyboardInterrupt):
        what = exc.describe() if isinstance(exc, Terminated) else "Ctrl-C (SIGINT)"
        status = "interrupted"
        msg = (f"interrupted by {what} {where}; the checkpoint keeps it: continue with --resume" if last is not None
               else f"interrupted by {what} {where}: rerun it (--resume starts it over)")
    elif isinstance(exc, CoreSE3Error):
        status, msg = "failed", _failure(run, exc, last)
        if isinstance(exc, ConvergenceError):
            again = ConvergenceError(msg, exc.result)
    else:
        status, msg = "failed", f"{type(exc).__name__}: {exc} ({where})"
    if isinstance(exc, BaseException):
        exc.recorded = True               # results.json says it (run() need not)
    with held_signals():
        ev = run.last if run.last is not None and last is not None and run.last.k == last["step"] else None
        if status == "failed" and ev is not None and run.scn.output["vtu"] and \
                not os.path.exists(os.path.join(run.rd.path, "vtu", f"step_{ev.k:04d}.vtu")):
            _multipliers_of(run, ev)
            write_step_vtu(run, ev.k, ev.g, ev.lam, ev.record.get("physical"))
            on_root(lambda: write_series_files(run, True))
        for sink in sinks:
            sink.end(run, status, msg)
    return again


def _multipliers_of(run, ev):
    """The contact loads' multipliers and friction history of step ``ev`` again (load control):
    the sub-steps a failed step converged moved them on, and the step's VTU file showed their
    contact forces (512.8 for 0.675 on a cantilever pushed onto a floor).  Under mpirun the whole
    problem's loads (those the VTU's point fields read on rank 0; ``parallel.localize``) get them
    on every rank."""
    from ..solvers.newton_try import hooked_loads
    if run.arc or run.ctx is None:
        return
    ms = NewtonState.multipliers_of(ev.arrays or {})
    for i, ld in enumerate(hooked_loads(run.scn.problem, "update_multipliers")):
        ld.set_multipliers(None if ms is None else ms[i])


def _failure(run, exc, last):
    """The message of a step that failed (load control) or of a path that stopped (arc length)."""
    if last is None:
        return str(exc)
    k, lam = last["step"], last["load_factor"]
    if run.arc:
        return f"{exc}; the {k} converged path points are written in {run.rd.path} (the checkpoint keeps the last one)"
    lams = run.scn.load_factors()
    target = lams[k] if k < len(lams) else lams[-1]
    hint = "; change the solver controls or the steps and rerun with --resume" \
        if isinstance(exc, ConvergenceError) else ""
    return f"step {k + 1} (load factor {lam:.6g} -> {target:.6g}) failed: {exc}. The checkpoint keeps step {k}{hint}"


def _complete(run, sinks, last):
    """The end of a run whose steps ran out (``last``: the last event, or the restart state of
    a resumed run with nothing left to do): an arc-length path that stopped short of lam_end fails
    (its message says what to raise), else status complete, with the warnings ``Problem.solve``
    gives on its final state (``model.solving.warn_final_state``); then the plots."""
    scn, s = run.scn, run.scn.solver
    if isinstance(last, StepEvent):
        lam, g = last.lam, last.g
    else:
        lam, g = float(last.lam), np.asarray(last.state if run.arc else last.g)
    status, error = "complete", None
    if run.arc and abs(lam - s["lam_end"]) > 1e-9 * abs(s["lam_end"]):
        status = "failed"
        error = (f"arc length stopped after max_steps = {s['max_steps']} steps at load factor {lam:.6g} < "
                 f"lam_end = {s['lam_end']:g}; raise [solver] max_steps and continue with --resume (or raise "
                 "dlam0 and start over)")
    error = error or _end_check(run)
    status = "failed" if error else status
    with held_signals():
        for sink in sinks:
            sink.end(run, status, error)
        run.rd.completed = status == "complete"
    doc = run.document(status, error)
    if status == "failed":
        raise ConvergenceError(error + f"; the {len(run.records) - 1} converged steps are written in "
                               f"{run.rd.path} (the checkpoint keeps the last one)", run.result)
    warn_final_state(scn.problem, SimpleNamespace(g=g, load_factor=lam), stacklevel=5)   # run()'s caller
    out = run.rd.path
    files = dict(results=os.path.join(out, "results.json"), checkpoint=os.path.join(out, "checkpoint.npz"))
    return _finish(run, doc, g, files)


def _end_check(run):
    """Load control's end check (``solvers.end_check``) over the states of this run: the message
    of an even eigenvalue crossing that det K's sign did not show (the steps from the crossing on
    are written already: the message names them), or None."""
    if run.arc or run.scn.solver["control"] == "linear" or len(run.path) < 2:
        return None
    check = Result(mesh=run.scn.problem.mesh, element=run.scn.problem.element_name)
    check.steps, check.critical_points = list(run.path), list(run.result.critical_points)
    try:
        run.ctx.end_check(_options(run.scn.solver), check)
    except ConvergenceError as exc:
        lo = check.steps[-1].load_factor
        beyond = [r["step"] for r in run.records if r["load_factor"] > lo + 1e-12 * max(1.0, abs(lo))]
        steps = f"step {beyond[0]}" if len(beyond) == 1 else f"steps {beyond[0]} to {beyond[-1]}"
        return str(exc).replace("The steps before it are kept in .result",
                                f"The files keep {steps} (load factors beyond {lo:.7g}) with the others: those lie "
                                "beyond it" if beyond else "")
    return None


def _finish(run, doc, g, files):
    """Series file, probe plot and picture of a completed run (rank 0 draws); the RunResult."""
    o, prob, out = run.scn.output, run.scn.problem, run.rd.path
    if not run.root:
        o = dict(o, plots=False, picture=False)
    if o["vtu"]:
        files["pvd"] = os.path.join(out, "vtu", "series.pvd")
    if o["plots"] and prob.probes:
        files["probes"] = plot_probes(run.rd.file("probes.png"), doc)
    if o["picture"]:
        files["picture"] = picture(run.rd.file("shell.png"), run.scn, g, records=run.records,
                                   vtu_dir=os.path.join(out, "vtu") if o["vtu"] else None)
    return RunResult(doc=doc, g=g, out=out, files=files)


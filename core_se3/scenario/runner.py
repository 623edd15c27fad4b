"""Run a scenario: one loop over the solver's converged steps (load-stepped Newton or arc length),
with output and a checkpoint after every one, so that an interrupted or failed run continues
with ``resume=True``.

    from core_se3 import scenario
    res = scenario.run(scenario.load("gripper.toml"), out="out/gripper")
    res.doc["steps"][-1]["probes"]["tip"]["u"], res.g

The solver is a generator (``solvers.newton_steps`` or ``solvers.arc_length_steps``); after each
step it yields, in this order: the step's VTU file, the checkpoint (the frames, the solver's
restart state, the records so far), the .pvd collection and the results JSON, each written
atomically (``io.files``).  The checkpoint is the record of truth: on resume, the steps it
holds are kept and the solver continues from its restart state, repeating the computations of
an uninterrupted run from the same bits.

Run directory:  results.json (schema core-se3-result v1 plus status/scenario fields),
checkpoint.npz, vtu/step_NNNN.vtu + vtu/series.pvd, probes.png, shell.png.
"""
from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from ..backend import rent_state, restore_rent
from ..errors import CheckpointError, ConvergenceError, CoreSE3Error
from ..fem import ELEMENTS
from ..io import Checkpoint, Progress, atomic_path, write_json_atomic
from ..results import Result, StepRecorder, result_document, step_record
from ..solvers import ArcLengthOptions, ArcState, NewtonOptions, NewtonState, arc_length_steps
from .context import run_context
from .obstacles import obstacles_of
from .outputs import physical_record, picture, plot_probes, unit_system_record
from .resume import check_extension, check_same_scenario

__all__ = ["run", "RunResult", "RunInterrupted", "point_fields", "cell_fields", "physical_record",
           "unit_system_record"]

PHASES = ("setup", "assembly", "solve", "other")


class RunInterrupted(CoreSE3Error):
    """Raised when ``stop_after`` steps were done (to simulate an interrupted run in tests).

    The checkpoint then holds the last step: ``run(..., resume=True)`` continues and ends in the
    state of an uninterrupted run.

    Example
    -------
    >>> import tempfile
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}], "solver": {"steps": 2},
    ...     "output": {"vtu": False, "plots": False, "picture": False}})
    >>> out = tempfile.mkdtemp()
    >>> try:
    ...     run(scn, out=out, stop_after=1)
    ... except RunInterrupted as exc:
    ...     print(exc)
    stopped after step 1 as asked (stop_after=1)
    >>> bool((run(scn, out=out, resume=True).g == run(scn, out=tempfile.mkdtemp()).g).all())
    True
    """


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


def point_fields(prob, g, lam=1.0):
    """Extra VTU point fields of the problem's loads (magnetisation, magnetic couple, ...).

    Parameters: prob (Problem), g (n, 4, 4), lam.  Returns: name -> (n, k) array (empty without
    such loads).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> _ = p.add_magnetic(Br=(0.1, 0.0, 0.0), field=UniformField((0.0, 0.0, 0.01)))
    >>> sorted(point_fields(p, p.mesh.g0))
    ['magnetic_couple', 'magnetic_force', 'magnetisation_Br']
    """
    return {k: np.asarray(v) for k, v in prob.output_fields(g, lam).items()}


def cell_fields(prob, g):
    """VTU cell fields of the element (stress resultants at the element centres).

    Parameters: prob (Problem), g (n, 4, 4).  Returns: name -> (m, 3) array.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> {k: v.shape for k, v in cell_fields(p, p.mesh.g0).items() if k in ("N1", "M2")}
    {'N1': (2, 3), 'M2': (2, 3)}
    """
    return prob.element.cell_fields(g)


def _document(scn, records, timings, status, error=None, critical=None):
    mat = scn.spec["material"]
    params = {k: dict(value=mat[k], unit="") for k in ("E", "nu", "h", "shear_factor", "drilling")}
    if mat["rho"] is not None:
        params["rho"] = dict(value=mat["rho"], unit="")
    extra = dict(critical_points=_critical_doc(critical)) if critical is not None else {}
    extra["unit_system"] = unit_system_record(scn.spec["units"])
    extra["load_numbers"] = scn.load_numbers()
    return result_document(scn.name, "core_se3", scn.solver["element"], params, scn.mesh, records,
                           {k: timings.get(k, 0.0) for k in PHASES}, None,
                           control=scn.solver["control"],
                           scenario=os.path.abspath(scn.file) if not scn.file.startswith("<") else scn.file,
                           fingerprint=scn.fingerprint, units=scn.spec["units"], status=status,
                           error=error, **extra)


def _critical_doc(cps):
    return [dict(kind=c.kind, load_factor=float(c.lam), bracket=[float(x) for x in c.lam_bracket],
                 step=int(c.step), description=c.describe()) for c in cps]


def _write_vtu(path, prob, g, lam, ctx=None, physical=None):
    """One VTU file (rank 0 of a distributed run writes it; every rank computes its cells),
    with the obstacles' surfaces at lam beside it when the problem has any (ParaView)."""
    from ..io import write_vtu
    cells = cell_fields(prob, g) if ctx is None else ctx.cell_fields(g)
    if ctx is not None and not ctx.root:
        return
    values = {"load_factor": float(lam)}
    values.update({f"{k} [{v['unit']}]" if v["unit"] else k: v["value"] for k, v in (physical or {}).items()})
    with atomic_path(path) as tmp:
        write_vtu(tmp, prob.mesh.X, prob.mesh.quads, prob.mesh.g0, g,
                  point_data=point_fields(prob, g, lam), cell_data=cells, field_data=values)
    obstacles = obstacles_of(prob)
    if obstacles:
        from ..io import write_obstacles
        with atomic_path(path[:-4] + "_obstacles.vtu") as tmp:
            write_obstacles(tmp, obstacles, g[:, :3, 3], lam)


def _write_pvd(vtu_dir, records, every, last):
    from ..io import write_pvd
    entries = [(r["load_factor"], f"step_{r['step']:04d}.vtu") for r in records
               if r["step"] % every == 0 or r["step"] == last]
    with atomic_path(os.path.join(vtu_dir, "series.pvd")) as tmp:
        write_pvd(tmp, entries)
    obst = [(t, f[:-4] + "_obstacles.vtu") for t, f in entries if os.path.exists(os.path.join(vtu_dir, f[:-4] + "_obstacles.vtu"))]
    if obst:                         # the obstacles' surfaces as a series of their own
        with atomic_path(os.path.join(vtu_dir, "obstacles.pvd")) as tmp:
            write_pvd(tmp, obst)


def _clear_temporaries(out, vtu_dir):
    """Remove temporary files a killed run left behind (atomic writes that never completed)."""
    for d in (out, vtu_dir):
        if os.path.isdir(d):
            for f in os.listdir(d):
                if f.startswith(".") and ".tmp" in f:
                    os.unlink(os.path.join(d, f))


def _clear(out, vtu_dir):
    """Remove the outputs of an earlier run in ``out`` (a new run, or --force)."""
    _clear_temporaries(out, vtu_dir)
    for stale in ("results.json", "probes.png", "shell.png", "checkpoint.npz"):
        if os.path.exists(os.path.join(out, stale)):
            os.unlink(os.path.join(out, stale))
    if os.path.isdir(vtu_dir):
        for f in os.listdir(vtu_dir):
            if f.startswith("step_") and f.endswith(".vtu") or f == "series.pvd":
                os.unlink(os.path.join(vtu_dir, f))


def _record(k, st, iterations=None, substeps=1, cutbacks=0):
    rec = step_record(st, dict(name="load factor", value=float(st.load_factor), unit=""))
    rec = dict(step=k, **rec)
    if iterations is not None:
        rec["iterations"] = int(iterations)
    rec["substeps"], rec["cutbacks"] = int(substeps), int(cutbacks)
    rec["balance_error"] = rec.pop("balance_error")
    return rec


def _options(s):
    common = dict(rtol=s["rtol"], dtol=s["dtol"], max_iter=s["max_iter"], linear_solver=s["linear_solver"])
    if s["control"] == "arclength":
        return ArcLengthOptions(method=s["method"], dlam0=s["dlam0"], psi=s["psi"], max_steps=s["max_steps"],
                                target_iter=s["target_iter"], ds_max_factor=s["ds_max_factor"],
                                stability=s["stability"], critical_tol=s["critical_tol"], **common)
    return NewtonOptions(max_cutbacks=s["max_cutbacks"], iteration=s["iteration"],
                         predictor=s.get("predictor", "none"), path_check=s["path_check"],
                         limit_check=s["limit_check"], max_substeps=s["max_substeps"], **common)


def run(scn, out=None, resume=False, progress=None, force=False, stop_after=None, verbose=False):
    """Solve a validated Scenario, writing its outputs in ``out`` (default [output] dir or
    out/NAME).  resume: continue from the checkpoint in ``out``; force: start over even if
    ``out`` holds a checkpoint.  progress: None = only on a terminal (after 2 s), True =
    always.  stop_after: stop with RunInterrupted once that many steps are done in this call
    (tests).  ConvergenceError propagates after the failure is recorded (status "failed"); the
    checkpoint keeps the last converged step.  ``verbose`` is accepted for compatibility (the
    solvers log through ``logging``).

    Parameters: scn (Scenario) and the keywords above; a missing or foreign checkpoint, or an
    ``out`` that holds one without resume or force, is a CheckpointError.  Returns: RunResult.

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
    ([0.0, 0.5, 1.0], ['checkpoint.npz', 'results.json'])
    """
    t_setup0 = time.perf_counter()
    prob, s, o = scn.problem, scn.solver, scn.output
    out = os.fspath(out or o["dir"] or os.path.join("out", scn.name))
    ck = Checkpoint(out)
    if resume and ELEMENTS.lookup(prob.element_name).stateful:
        raise CheckpointError(f"--resume is not supported with the stateful {s['element']} element")
    if not resume and ck.exists() and not force:
        raise CheckpointError(f"{out} already holds a run ({ck.path}); continue it with --resume, "
                              "start over with --force, or choose another --out")
    st = ck.load() if resume else None
    if resume:
        check_same_scenario(ck.path, st, scn)
        restore_rent(st["extra"].get("backend"))
    ctx = run_context(prob, s, s["control"] == "arclength", st)
    try:
        return _run(scn, out, ck, ctx, st, resume, progress, stop_after, t_setup0)
    finally:
        ctx.close()


def _run(scn, out, ck, ctx, st, resume, progress, stop_after, t_setup0):
    prob = scn.problem
    s, o = scn.solver, scn.output
    arc = s["control"] == "arclength"
    root = ctx.root
    ctx.barrier()                        # every rank has checked the directory before rank 0 writes
    if root:
        os.makedirs(out, exist_ok=True)
    vtu_dir = os.path.join(out, "vtu")
    every = o["vtu_every"]
    lams = scn.load_factors()
    nsteps = None if arc else len(lams)
    result = Result(mesh=prob.mesh, element=prob.element_name)
    if resume:
        was_arc = st["extra"].get("control") == "arclength"
        if arc and (not was_arc or "arc" not in st["extra"]):
            raise CheckpointError(f"checkpoint {ck.path} holds no arc-length path state (written by a "
                                  "load-controlled run or by a version that could not resume arc "
                                  "length): start over with --force or use another --out")
        if not arc and was_arc:
            raise CheckpointError(f"checkpoint {ck.path} is of an arc-length run; this scenario is "
                                  "load-controlled: start over with --force or use another --out")
        if root:
            _clear_temporaries(out, vtu_dir)
        records, base, done = st["records"], dict(st["timings"]), st["step"]
        if not arc:
            check_extension(ck.path, records, lams, scn.solver)
        if arc:
            start = ArcState.unpack(st["g"], st["extra"]["arc"], st["arrays"])
            if len(records) != start.step + 1:
                raise CheckpointError(f"checkpoint {ck.path} is inconsistent: {len(records)} records for "
                                      f"path step {start.step}")
        else:
            nw = st["extra"].get("newton", {})
            start = NewtonState(st["lam"], st["g"], nw.get("dlam"), nw.get("k_ref"),
                                NewtonState.multipliers_of(st["arrays"]))
        unwrap = st["unwrap"]
        critical = list(start.critical) if arc else None
    else:
        if root:
            _clear(out, vtu_dir)
        records, base, done, start, unwrap = [], {}, 0, None, None
        critical = [] if arc else None
    rec = StepRecorder(prob, unwrap)
    if not resume and not arc:
        g0 = prob.mesh.g0.copy()
        first = rec.step(0.0, g0, 0, [], *ctx.initial_forces(g0))
        records.append(_record(0, first, 0, 0, 0))
        records[0]["balance_error"] = 0.0            # the unloaded start, not an equilibrium
        records[0]["physical"] = physical_record(scn, 0.0)
        if o["vtu"]:
            _write_vtu(os.path.join(vtu_dir, "step_0000.vtu"), prob, g0, 0.0, ctx, records[0]["physical"])
        if root:
            ck.save(scn.fingerprint, 0, 0.0, g0, rec.unwrapped, records, {k: 0.0 for k in PHASES},
                    extra=dict(newton=NewtonState(0.0, g0).pack(), physical=scn.physical, ranks=ctx.ranks),
                    arrays=ctx.checkpoint_arrays())
        if o["vtu"] and root:
            _write_pvd(vtu_dir, records, every, nsteps)
        start = NewtonState(0.0, g0)
    base["setup"] = base.get("setup", 0.0) + time.perf_counter() - t_setup0

    def timings_now():
        t = {k: float(base.get(k, 0.0)) for k in PHASES}
        for k in ("assembly", "solve", "other"):
            t[k] += float(result.timings.get(k, 0.0))
        return t

    explicit = bool(progress)
    bar = Progress(nsteps, (sys.stdout.isatty() if progress is None else explicit) and root,
                   delay=0.0 if explicit else 2.0)
    opts = _options(s)
    if arc:
        steps = arc_length_steps(prob, lam_end=s["lam_end"], start=start, result=result, options=opts)
    else:
        steps = ctx.steps(lams[done:], opts, start, rec, result)
    n_this_call, k, lam = 0, done, records[-1]["load_factor"] if records else 0.0
    last_state = start
    status, error = "complete", None
    try:
        for item in steps:
            if arc:
                k = item.state.step
                records.append(_record(k, item.step, substeps=1 if k else 0))
                finished = bool(item.state.finished)
                critical = list(item.state.critical)
                scalars, arrays = item.state.pack()
                extra = dict(control="arclength", arc=scalars)
                unwrap_now = item.state.unwrap
            else:
                k += 1
                tries = item.tries
                records.append(_record(k, item.step, sum(e["iterations"] for e in tries),
                                       sum(e["converged"] and not e.get("augmented") for e in tries),
                                       sum(not e["converged"] for e in tries)))
                finished = k == nsteps
                extra = dict(newton=item.state.pack(), ranks=ctx.ranks)
                arrays = {**(item.state.arrays() or {}), **(ctx.checkpoint_arrays() or {})} or None
                unwrap_now = rec.unwrapped
            lam, g = item.step.load_factor, item.step.g
            records[-1]["physical"] = physical_record(scn, lam)
            extra["physical"] = scn.physical
            extra["backend"] = rent_state()       # where 'auto' stands (a resume continues from it)
            last_state = item.state
            timings = timings_now()
            vtu_now = o["vtu"] and (k % every == 0 or finished)
            if vtu_now:
                _write_vtu(os.path.join(vtu_dir, f"step_{k:04d}.vtu"), prob, g, lam, ctx, records[-1]["physical"])
            if root:
                ck.save(scn.fingerprint, k, lam, g, unwrap_now, records, timings, extra=extra, arrays=arrays)
            if vtu_now and root:
                _write_pvd(vtu_dir, records, every, k if finished else (nsteps if not arc else -1))
            if root:
                write_json_atomic(os.path.join(out, "results.json"), _document(
                    scn, records, timings, "complete" if finished and not arc else "running", critical=critical))
            if k > done:
                n_this_call += 1
                dlam = lam - records[-2]["load_factor"]
                bar.update(k, lam, records[-1]["iterations"], records[-1]["residual"],
                           fraction=(lam / s["lam_end"]) if arc else None,
                           extra=f"  dlam {dlam:.3g}" + (f"  {records[-1]['substeps']} sub-steps"
                                                          if records[-1]["substeps"] > 1 else ""))
                if stop_after is not None and n_this_call >= stop_after and not finished:
                    bar.close()
                    raise RunInterrupted(f"stopped after {'path point' if arc else 'step'} {k} as asked "
                                         f"(stop_after={stop_after})")
    except ConvergenceError as exc:
        bar.close()
        timings = timings_now()
        if not arc:
            target = lams[k] if k < len(lams) else lams[-1]
            msg = (f"step {k + 1} (load factor {lam:.6g} -> {target:.6g}) failed: {exc}. The checkpoint "
                   f"keeps step {k}; change the solver controls or the steps and rerun with --resume")
            if root:
                write_json_atomic(os.path.join(out, "results.json"), _document(scn, records, timings, "failed", msg))
            raise ConvergenceError(msg, exc.result) from None
        if not records:
            raise
        status, error = "failed", str(exc)
        critical = list(result.critical_points)
    except RunInterrupted:
        raise
    except KeyboardInterrupt:
        bar.close()
        msg = (f"interrupted (Ctrl-C) after {'path point' if arc else 'step'} {k} at load factor {lam:.6g}; "
               "the checkpoint keeps it: continue with --resume")
        write_json_atomic(os.path.join(out, "results.json"),
                          _document(scn, records, timings_now(), "interrupted", msg, critical=critical))
        raise
    except CoreSE3Error as exc:              # e.g. a tangent that turned singular
        bar.close()
        if arc:
            raise
        target = lams[k] if k < len(lams) else lams[-1]
        msg = (f"step {k + 1} (load factor {lam:.6g} -> {target:.6g}) failed: {exc}. The checkpoint "
               f"keeps step {k}")
        if root:
            write_json_atomic(os.path.join(out, "results.json"), _document(scn, records, timings_now(), "failed", msg))
        raise
    bar.close()
    timings = timings_now()
    if arc:
        final = last_state
        k = final.step
        g = np.asarray(final.state)
        if status == "complete" and abs(final.lam - s["lam_end"]) > 1e-9 * abs(s["lam_end"]):
            status = "failed"
            error = (f"arc length stopped after max_steps = {s['max_steps']} steps at load factor "
                     f"{final.lam:.6g} < lam_end = {s['lam_end']:g}; raise [solver] max_steps and continue "
                     "with --resume (or raise dlam0 and start over)")
        if o["vtu"]:
            if not os.path.exists(os.path.join(vtu_dir, f"step_{k:04d}.vtu")):
                _write_vtu(os.path.join(vtu_dir, f"step_{k:04d}.vtu"), prob, final.state, final.lam, ctx)
            if root:
                _write_pvd(vtu_dir, records, every, k)
    else:
        g = last_state.g
    doc = _document(scn, records, timings, status, error, critical=critical)
    if root:
        write_json_atomic(os.path.join(out, "results.json"), doc)
    if status == "failed":
        raise ConvergenceError(error + f"; the {len(records) - 1} converged steps are written in {out} "
                               "(the checkpoint keeps the last one)", result)
    files = dict(results=os.path.join(out, "results.json"), checkpoint=ck.path)
    return _finish(o, prob, doc, scn, g, records, out, vtu_dir, files, root)


def _finish(o, prob, doc, scn, g, records, out, vtu_dir, files, root=True):
    """Series file, probe plot and picture of a completed run (rank 0 draws); the RunResult."""
    if not root:
        o = dict(o, plots=False, picture=False)
    if o["vtu"]:
        files["pvd"] = os.path.join(vtu_dir, "series.pvd")
    if o["plots"] and prob.probes:
        files["probes"] = plot_probes(os.path.join(out, "probes.png"), doc)
    if o["picture"]:
        files["picture"] = picture(os.path.join(out, "shell.png"), scn, g, records=records,
                                   vtu_dir=vtu_dir if o["vtu"] else None)
    return RunResult(doc=doc, g=g, out=out, files=files)

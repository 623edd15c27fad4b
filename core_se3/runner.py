"""Run a scenario: one Newton solve per requested load step, with output and a checkpoint after
every converged step, so that an interrupted or failed run continues with ``resume=True``.

    from core_se3 import scenario, runner
    res = runner.run(scenario.load("gripper.toml"), out="out/gripper")
    res.doc["steps"][-1]["probes"]["tip"]["u"], res.g

Step k solves lam_{k-1} -> lam_k (newton_solve with steps=1, g_init = the state at lam_{k-1},
cut-backs inside the step as the solver does them).  After it converges, in this order:
the step's VTU file, the checkpoint, the .pvd collection and the results JSON are written,
each atomically (checkpoint.py).  The checkpoint is the record of truth: on resume, the
steps it holds are kept, the others are solved again.  With control = "arclength" the same
files are written after every converged path point, the checkpoint also holding the path
follower's state (continuation.ArcState), and resume continues the path from it.

Run directory:  results.json (schema core-se3-result v1 plus status/scenario fields),
checkpoint.npz, vtu/step_NNNN.vtu + vtu/series.pvd, probes.png, shell.png.
"""
from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from .checkpoint import Checkpoint, atomic_path, write_json_atomic, write_text_atomic
from .errors import CheckpointError, ConvergenceError, CoreSE3Error
from .results import SCHEMA, VERSION, unwrap_rotation

__all__ = ["run", "RunResult", "Progress", "RunInterrupted", "point_fields", "cell_fields"]


class RunInterrupted(CoreSE3Error):
    """Raised when ``stop_after`` steps were done (to simulate an interrupted run in tests)."""


@dataclass
class RunResult:
    """What a run left: the results document, the final frames, the output files."""
    doc: dict
    g: np.ndarray
    out: str
    files: dict = field(default_factory=dict)

    @property
    def status(self):
        return self.doc["status"]


class Progress:
    """One line per load step, redrawn in place: a bar, step, load factor, Newton iterations,
    final residual, step size (and sub-steps after cut-backs).  Silent unless enabled."""

    def __init__(self, total, enabled, stream=None, width=24):
        self.total, self.enabled, self.width = total, enabled, width
        self.stream = stream or sys.stdout
        self.t0 = time.perf_counter()

    def update(self, k, lam, iterations, residual, dlam, substeps):
        if not self.enabled:
            return
        n = int(round(self.width * k / self.total))
        bar = "#" * n + "." * (self.width - n)
        cut = f"  {substeps} sub-steps" if substeps > 1 else ""
        self.stream.write(f"\r[{bar}] step {k}/{self.total}  lam {lam:.4g}  it {iterations:>2d}  "
                          f"res {residual:.1e}  dlam {dlam:.3g}{cut}  {time.perf_counter() - self.t0:.1f} s ")
        self.stream.flush()

    def close(self, message=""):
        if self.enabled:
            self.stream.write("\n" + (message + "\n" if message else ""))
            self.stream.flush()


def point_fields(prob, g, lam=1.0):
    """Extra VTU point fields: prob.output_fields(g, lam) (magnetisation, magnetic couple, ...)
    if the Problem has it."""
    fn = getattr(prob, "output_fields", None)
    if fn is None:
        return {}
    import inspect
    try:
        takes_lam = len(inspect.signature(fn).parameters) >= 2
    except (TypeError, ValueError):
        takes_lam = False
    out = fn(g, lam) if takes_lam else fn(g)
    return {k: np.asarray(v) for k, v in out.items()}


def cell_fields(prob, g):
    """VTU cell fields: stress resultants at the element centres (resultants.py)."""
    try:
        from .resultants import element_resultants
    except ImportError:
        return {}
    if getattr(prob, "element_name", "default") != "default":
        return {}
    return element_resultants(prob.element, g)


def _probe_record(prob, g, unwrap):
    out = {}
    for name, pr in prob.probes.items():
        x, R = pr.state(g)
        x0, R0 = pr.state(prob.mesh.g0)
        Rr = R @ R0.T
        unwrap[name] = unwrap_rotation(Rr, unwrap[name])
        w = unwrap[name]
        out[name] = dict(u=(x - x0).tolist(), rotation_angle=float(np.linalg.norm(w)),
                         rotation_vector=w.tolist(), rotation=Rr.tolist())
    return out


def _document(scn, records, timings, status, error=None):
    m = scn.mesh
    mat = scn.spec["material"]
    units = scn.spec["units"]
    t = dict(timings)
    t["total"] = sum(t.get(k, 0.0) for k in ("setup", "assembly", "solve", "other"))
    params = {k: dict(value=mat[k], unit="") for k in ("E", "nu", "h", "shear_factor", "drilling")}
    if mat["rho"] is not None:
        params["rho"] = dict(value=mat["rho"], unit="")
    shape = m.shape or (None, None)
    return dict(schema=SCHEMA, version=VERSION, case=scn.name, model="core_se3", control=scn.solver["control"],
                variant=scn.solver["element"], scenario=os.path.abspath(scn.file)
                if not scn.file.startswith("<") else scn.file,
                fingerprint=scn.fingerprint, units=units, status=status, error=error,
                params=params,
                mesh=dict(nx=shape[0], ny=shape[1], n_nodes=m.n_nodes, n_elements=m.n_elements,
                          n_dofs=6 * m.n_nodes),
                steps=records, timings=t, reference=None)


def _write_vtu(path, prob, g, lam):
    from .io import write_vtu
    with atomic_path(path) as tmp:
        write_vtu(tmp, prob.mesh.X, prob.mesh.quads, prob.mesh.g0, g,
                  point_data=point_fields(prob, g, lam), cell_data=cell_fields(prob, g))


def _write_pvd(vtu_dir, records, every, last):
    from .io import write_pvd
    entries = [(r["load_factor"], f"step_{r['step']:04d}.vtu") for r in records
               if r["step"] % every == 0 or r["step"] == last]
    with atomic_path(os.path.join(vtu_dir, "series.pvd")) as tmp:
        write_pvd(tmp, entries)


def run(scn, out=None, resume=False, progress=None, force=False, stop_after=None, verbose=False):
    """Solve a validated Scenario, writing its outputs in ``out`` (default [output] dir or
    out/NAME).  resume: continue from the checkpoint in ``out``; force: start over even if
    ``out`` holds a checkpoint.  progress: None = only on a terminal.  stop_after: stop with
    RunInterrupted once that many steps are done in this call (tests).  ConvergenceError
    propagates after the failure is recorded (status "failed"); the checkpoint keeps the last
    converged step."""
    t_setup0 = time.perf_counter()
    prob = scn.problem
    s, o = scn.solver, scn.output
    out = os.fspath(out or o["dir"] or os.path.join("out", scn.name))
    ck = Checkpoint(out)
    if resume and s["element"] == "seed":
        raise CheckpointError("--resume is not supported with the stateful seed element")
    if not resume and ck.exists() and not force:
        raise CheckpointError(f"{out} already holds a run ({ck.path}); continue it with --resume, "
                              "start over with --force, or choose another --out")
    os.makedirs(out, exist_ok=True)
    vtu_dir = os.path.join(out, "vtu")
    if s["control"] == "arclength":
        return _run_arclength(scn, out, ck, vtu_dir, bool(progress) or verbose, resume, stop_after,
                              t_setup0)
    lams = scn.load_factors()
    nsteps = len(lams)
    if resume:
        st = ck.load(scn.fingerprint)
        if st["extra"].get("control") == "arclength":
            raise CheckpointError(f"checkpoint {ck.path} is of an arc-length run; this scenario is "
                                  "load-controlled: start over with --force or use another --out")
        _clear_temporaries(out, vtu_dir)
        g, lam, done = st["g"], st["lam"], st["step"]
        unwrap, records, timings = st["unwrap"], st["records"], st["timings"]
        timings["setup"] = timings.get("setup", 0.0)
    else:
        _clear(out, vtu_dir)
        g, lam, done = prob.mesh.g0.copy(), 0.0, 0
        unwrap = {name: np.zeros(3) for name in prob.probes}
        records = [dict(step=0, load_factor=0.0, load=dict(name="load factor", value=0.0, unit=""),
                        probes=_probe_record(prob, g, unwrap), iterations=0, residual=0.0,
                        residual_history=[], substeps=0, cutbacks=0, balance_error=0.0)]
        timings = dict(setup=0.0, assembly=0.0, solve=0.0, other=0.0)
        if o["vtu"]:
            _write_vtu(os.path.join(vtu_dir, "step_0000.vtu"), prob, g, 0.0)
        ck.save(scn.fingerprint, 0, lam, g, unwrap, records, timings)
        if o["vtu"]:
            _write_pvd(vtu_dir, records, o["vtu_every"], nsteps)
    timings["setup"] += time.perf_counter() - t_setup0
    files = {}
    bar = Progress(nsteps, sys.stdout.isatty() if progress is None else bool(progress))
    if resume and done:
        bar.update(done, lam, records[-1]["iterations"], records[-1]["residual"], lams[0], 1)
    from .solver import newton_solve
    n_this_call = 0
    for k in range(done + 1, nsteps + 1):
        if stop_after is not None and n_this_call >= stop_after:
            bar.close()
            raise RunInterrupted(f"stopped after step {k - 1} as asked (stop_after={stop_after})")
        target = lams[k - 1]
        try:
            res = newton_solve(prob, steps=1, lam_start=lam, lam_end=target, g_init=g,
                               rtol=s["rtol"], dtol=s["dtol"], max_iter=s["max_iter"],
                               max_cutbacks=s["max_cutbacks"], verbose=verbose)
        except ConvergenceError as exc:
            bar.close()
            r = exc.result
            for key in ("assembly", "solve", "other"):
                timings[key] = timings.get(key, 0.0) + (r.timings.get(key, 0.0) if r else 0.0)
            msg = (f"step {k} (load factor {lam:.6g} -> {target:.6g}) failed: {exc}. The checkpoint "
                   f"keeps step {k - 1}; change the solver controls or the steps and rerun with --resume")
            write_json_atomic(os.path.join(out, "results.json"),
                              _document(scn, records, timings, "failed", msg))
            raise ConvergenceError(msg, r) from None
        except CoreSE3Error as exc:              # e.g. a tangent that turned singular
            bar.close()
            msg = (f"step {k} (load factor {lam:.6g} -> {target:.6g}) failed: {exc}. The checkpoint "
                   f"keeps step {k - 1}")
            write_json_atomic(os.path.join(out, "results.json"),
                              _document(scn, records, timings, "failed", msg))
            raise
        for key in ("setup", "assembly", "solve", "other"):
            timings[key] = timings.get(key, 0.0) + res.timings.get(key, 0.0)
        stp = res.final
        g, lam = stp.g, target
        log = res.log
        rec = dict(step=k, load_factor=float(lam), load=dict(name="load factor", value=float(lam), unit=""),
                   probes=_probe_record(prob, g, unwrap), iterations=int(sum(e["iterations"] for e in log)),
                   residual=float(stp.residual_history[-1]) if stp.residual_history else 0.0,
                   residual_history=[float(x) for x in stp.residual_history],
                   substeps=int(sum(e["converged"] for e in log)),
                   cutbacks=int(sum(not e["converged"] for e in log)),
                   balance_error=float(stp.balance_error))
        records.append(rec)
        write_vtu_now = o["vtu"] and (k % o["vtu_every"] == 0 or k == nsteps)
        if write_vtu_now:
            _write_vtu(os.path.join(vtu_dir, f"step_{k:04d}.vtu"), prob, g, lam)
        ck.save(scn.fingerprint, k, lam, g, unwrap, records, timings)
        if write_vtu_now:
            _write_pvd(vtu_dir, records, o["vtu_every"], nsteps)
        write_json_atomic(os.path.join(out, "results.json"),
                          _document(scn, records, timings, "running" if k < nsteps else "complete"))
        n_this_call += 1
        bar.update(k, lam, rec["iterations"], rec["residual"], target - lams[k - 2] if k > 1 else target,
                   rec["substeps"])
    bar.close()
    doc = _document(scn, records, timings, "complete")
    write_json_atomic(os.path.join(out, "results.json"), doc)
    files["results"] = os.path.join(out, "results.json")
    files["checkpoint"] = ck.path
    return _finish(o, prob, doc, scn, g, records, out, vtu_dir, files)


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


def _arc_record(k, st):
    """The results record of path point k (a StepResult of continuation.arc_length)."""
    probes = {name: dict(u=np.asarray(p["u"]).tolist(), rotation_angle=float(np.linalg.norm(p["w"])),
                         rotation_vector=np.asarray(p["w"]).tolist(), rotation=np.asarray(p["R"]).tolist())
              for name, p in st.probes.items()}
    return dict(step=k, load_factor=float(st.load_factor),
                load=dict(name="load factor", value=float(st.load_factor), unit=""),
                probes=probes, iterations=int(st.iterations),
                residual=float(st.residual_history[-1]) if st.residual_history else 0.0,
                residual_history=[float(x) for x in st.residual_history], substeps=1 if k else 0,
                cutbacks=0, balance_error=float(st.balance_error))


def _critical_doc(cps):
    return [dict(kind=c.kind, load_factor=float(c.lam), bracket=[float(x) for x in c.lam_bracket],
                 step=int(c.step), description=c.describe()) for c in cps]


def _run_arclength(scn, out, ck, vtu_dir, verbose, resume=False, stop_after=None, t_setup0=None):
    """Arc-length continuation (continuation.arc_length).  After every converged point (and the
    first one) its VTU file, the checkpoint (the frames and the follower's ArcState), the .pvd
    collection and the results JSON are written, each atomically, as for load control; resume
    continues the path from the checkpoint's ArcState (continuation.path_follow ``start``),
    which repeats the computations of an uninterrupted run from the same bits.  stop_after:
    RunInterrupted once that many points are done in this call (tests)."""
    from .continuation import ArcState, arc_length
    prob, s, o = scn.problem, scn.solver, scn.output
    t_setup0 = time.perf_counter() if t_setup0 is None else t_setup0
    if resume:
        ck_state = ck.load(scn.fingerprint)
        if ck_state["extra"].get("control") != "arclength" or "arc" not in ck_state["extra"]:
            raise CheckpointError(f"checkpoint {ck.path} holds no arc-length path state (written by a "
                                  "load-controlled run or by a version that could not resume arc "
                                  "length): start over with --force or use another --out")
        _clear_temporaries(out, vtu_dir)
        start = ArcState.unpack(ck_state["g"], ck_state["extra"]["arc"], ck_state["arrays"])
        records, base = ck_state["records"], dict(ck_state["timings"])
        if len(records) != start.step + 1:
            raise CheckpointError(f"checkpoint {ck.path} is inconsistent: {len(records)} records for "
                                  f"path step {start.step}")
    else:
        _clear(out, vtu_dir)
        start, records, base = None, [], {}
    base["setup"] = base.get("setup", 0.0) + time.perf_counter() - t_setup0
    every = o["vtu_every"]
    last = dict(state=start, timings={k: float(base.get(k, 0.0)) for k in ("setup", "assembly", "solve", "other")},
                critical=list(start.critical) if start else [], vtu=set(), n=0)

    def timings_now(res):
        return dict(setup=float(base["setup"]),
                    **{k: float(base.get(k, 0.0)) + float(res.timings.get(k, 0.0))
                       for k in ("assembly", "solve", "other")})

    def on_step(res, state):
        k = state.step
        records.append(_arc_record(k, res.steps[-1]))
        timings = timings_now(res)
        vtu_now = o["vtu"] and (k % every == 0 or bool(state.finished))
        if vtu_now:
            _write_vtu(os.path.join(vtu_dir, f"step_{k:04d}.vtu"), prob, state.state, state.lam)
            last["vtu"].add(k)
        scalars, arrays = state.pack()
        ck.save(scn.fingerprint, k, state.lam, state.state, state.unwrap, records, timings,
                extra=dict(control="arclength", arc=scalars), arrays=arrays)
        if vtu_now:
            _write_pvd(vtu_dir, records, every, k if state.finished else -1)
        doc = _document(scn, records, timings, "running")
        doc["critical_points"] = _critical_doc(state.critical)
        write_json_atomic(os.path.join(out, "results.json"), doc)
        last.update(state=state, timings=timings, critical=list(state.critical))
        if k > (start.step if start else 0):
            last["n"] += 1
            if stop_after is not None and last["n"] >= stop_after and not state.finished:
                raise RunInterrupted(f"stopped after path point {k} as asked (stop_after={stop_after})")

    status, error = "complete", None
    try:
        res = arc_length(prob, lam_end=s["lam_end"], dlam0=s["dlam0"], method=s["method"], psi=s["psi"],
                         ds_max_factor=s["ds_max_factor"], max_steps=s["max_steps"],
                         target_iter=s["target_iter"], max_iter=s["max_iter"], rtol=s["rtol"],
                         dtol=s["dtol"], stability=s["stability"], verbose=verbose,
                         linear_solver=s["linear_solver"], start=start, on_step=on_step)
    except ConvergenceError as exc:
        res, status, error = exc.result, "failed", str(exc)
        if last["state"] is None:
            raise
    timings = timings_now(res) if res is not None and res.steps else last["timings"]
    final = last["state"]
    k = final.step
    if status == "complete" and abs(final.lam - s["lam_end"]) > 1e-9 * abs(s["lam_end"]):
        status = "failed"
        error = (f"arc length stopped after max_steps = {s['max_steps']} steps at load factor "
                 f"{final.lam:.6g} < lam_end = {s['lam_end']:g}; raise [solver] max_steps and continue "
                 "with --resume (or raise dlam0 and start over)")
    if o["vtu"]:
        if k not in last["vtu"] and not os.path.exists(os.path.join(vtu_dir, f"step_{k:04d}.vtu")):
            _write_vtu(os.path.join(vtu_dir, f"step_{k:04d}.vtu"), prob, final.state, final.lam)
        _write_pvd(vtu_dir, records, every, k)
    doc = _document(scn, records, timings, status, error)
    doc["critical_points"] = _critical_doc(last["critical"])
    write_json_atomic(os.path.join(out, "results.json"), doc)
    g = np.asarray(final.state)
    if status == "failed":
        raise ConvergenceError(error + f"; the {len(records) - 1} converged steps are written in {out} "
                               "(the checkpoint keeps the last one)", res)
    files = dict(results=os.path.join(out, "results.json"), checkpoint=ck.path)
    return _finish(o, prob, doc, scn, g, records, out, vtu_dir, files)


def _finish(o, prob, doc, scn, g, records, out, vtu_dir, files):
    """Series file, probe plot and picture of a completed run; the RunResult."""
    if o["vtu"]:
        files["pvd"] = os.path.join(vtu_dir, "series.pvd")
    if o["plots"] and prob.probes:
        files["probes"] = plot_probes(os.path.join(out, "probes.png"), doc)
    if o["picture"]:
        files["picture"] = picture(os.path.join(out, "shell.png"), scn, g, records=records,
                                   vtu_dir=vtu_dir if o["vtu"] else None)
    return RunResult(doc=doc, g=g, out=out, files=files)


def plot_probes(path, doc):
    """Load factor against the displacement components of every probe (one PNG)."""
    from .io import plot_load_deflection
    lam = np.array([s["load_factor"] for s in doc["steps"]])
    disp = {}
    us = {name: np.array([s["probes"][name]["u"] for s in doc["steps"]]) for name in doc["steps"][0]["probes"]}
    big = max([np.abs(u).max() for u in us.values()] + [0.0])
    for name, u in us.items():
        for i, c in enumerate("xyz"):
            if np.abs(u[:, i]).max() > 1e-9 * big:          # leave out components that stay ~0
                disp[f"{name}.u{c}"] = u[:, i]
    length = {"N-mm-MPa": "mm", "SI": "m"}.get(doc.get("units"), "length unit")
    with atomic_path(path) as tmp:
        plot_load_deflection(tmp, lam, disp, xlabel=f"probe displacement [{length}]",
                             ylabel="load factor", title=doc["case"])
    return path


def picture(path, scn, g, title=None, records=None, vtu_dir=None):
    """PNG of the deformed shell (matplotlib 3-D, reference outline dotted): the final state
    coloured by rotation angle, or, with [output] picture_steps = k > 1, k states of the path
    (read back from the VTU files, so also after a resume) overlaid."""
    from .io import plot_sequence, plot_shell
    m = scn.mesh
    o = scn.output
    k = o.get("picture_steps", 1)
    view = list(o.get("view") or (20.0, -60.0))
    elev, azim, roll = (view + [0.0])[:3]
    with atomic_path(path) as tmp:
        if k > 1 and records and vtu_dir:
            import meshio
            have = [r for r in records
                    if os.path.exists(os.path.join(vtu_dir, f"step_{r['step']:04d}.vtu"))]
            pick = sorted({int(round(i)) for i in np.linspace(0, len(have) - 1, min(k, len(have)))})
            pos, labels = [], []
            for i in pick:
                r = have[i]
                v = meshio.read(os.path.join(vtu_dir, f"step_{r['step']:04d}.vtu"))
                pos.append(v.points + v.point_data["displacement"])
                labels.append(f"load factor {r['load_factor']:.3g}")
            plot_sequence(tmp, m.X, m.quads, pos, labels, title=title or scn.name, elev=elev, azim=azim,
                          roll=roll)
        else:
            plot_shell(tmp, m.X, m.quads, g, title=title or scn.name, elev=elev, azim=azim, roll=roll)
    return path

"""What a scenario run does with each converged step: small sinks fed, in order, by the one loop of
``scenario.runner`` over the solver's steps (load-stepped Newton or arc length, normalised to a
:class:`StepEvent`).

==================  =========================================================================
sink                writes
==================  =========================================================================
:class:`VtuSink`    ``vtu/step_NNNN.vtu`` (every ``vtu_every``-th step and the last)
:class:`CheckpointSink`  ``checkpoint.npz``: the record of truth a resume continues from
:class:`PvdSink`    ``vtu/series.pvd`` (and ``vtu/obstacles.pvd``)
:class:`DocumentSink`    ``results.json``: status ``running`` from the start, then ``complete``,
                    ``failed`` or ``interrupted`` with the message
:class:`ProgressSink`    the progress line
:class:`StopAfter`  raises RunInterrupted after a number of steps (tests)
==================  =========================================================================

The order is that of the table: a VTU file exists before the checkpoint that counts its step,
and the checkpoint before the results document that reports it.  Every file is written
atomically and registered in the run directory's manifest before it is created
(``io.rundir``).  A sink has ``step(run, event)`` and ``end(run, status, message)``; each can be
tested alone with a :class:`RunState` (``tests/test_run_lifecycle.py``).
"""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field

import numpy as np

from ..errors import CoreSE3Error
from ..io import Checkpoint, Progress, atomic_path, write_json_atomic
from ..io.lifecycle import held_signals
from ..results import result_document
from ..solvers.linear import linear_increments
from .context import on_root
from .obstacles import obstacles_of
from .outputs import unit_system_record

__all__ = ["StepEvent", "RunState", "VtuSink", "CheckpointSink", "PvdSink", "DocumentSink", "ProgressSink",
           "StopAfter", "RunInterrupted", "PHASES", "RUN_FILES", "ProvenanceSink", "write_step_vtu",
           "write_series_files", "step_files", "series_files", "write_path_vtu"]

PHASES = ("setup", "assembly", "solve", "other")
# the names a scenario run writes (a foreign file of such a name is never overwritten)
RUN_FILES = ("results.json", "checkpoint.npz", "probes.png", "shell.png", "vtu/series.pvd", "vtu/obstacles.pvd",
             "vtu/step_*.vtu")


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
    ...     scenario.run(scn, out=out, stop_after=1)
    ... except RunInterrupted as exc:
    ...     print(exc)
    stopped after step 1 as asked (stop_after=1)
    >>> bool((scenario.run(scn, out=out, resume=True).g == scenario.run(scn, out=tempfile.mkdtemp()).g).all())
    True
    """


@dataclass
class StepEvent:
    """One converged step as the sinks see it: its number ``k``, its results record, frames
    ``g``, load factor ``lam``, whether it is the last, and the solver's restart state for the
    checkpoint (``extra``: JSON scalars, ``arrays``: named arrays, ``unwrap``: the probes'
    unwrapped rotation vectors).

    Example
    -------
    >>> StepEvent(0, {"step": 0}, None, 0.0).finished
    False
    """
    k: int
    record: dict
    g: np.ndarray
    lam: float
    finished: bool = False
    extra: dict = field(default_factory=dict)
    arrays: dict | None = None
    unwrap: dict = field(default_factory=dict)


@dataclass
class RunState:
    """What the sinks of one run share: the scenario, its directory (``io.RunDirectory``), the
    run context (who writes, ``scenario.context``), the step records so far, the timings of
    earlier sessions (``base``), the solver's Result (this session's timings), the critical
    points of the path (arc length; load control: those it passed, limit_check off, and contact
    snaps), the provenance of the run and what each of its sessions ran with (``sessions``: a
    resumed run has several, ``resume.session_record``).

    Example
    -------
    >>> RunState(None, None, None).root
    True
    """
    scn: object
    rd: object
    ctx: object
    records: list = field(default_factory=list)
    base: dict = field(default_factory=dict)
    result: object = None
    critical: list | None = None
    critical_before: int = 0                         # of ``critical``: a resumed load control's earlier ones
    provenance: dict = field(default_factory=dict)
    done: int = 0
    last: object = None
    saved: int = 0
    path: list = field(default_factory=list)        # load control's states (g, load_factor): the end check's
    sessions: list = field(default_factory=list)    # what each session ran with (``resume.session_record``)

    @property
    def root(self):
        return self.ctx is None or self.ctx.root

    @property
    def arc(self):
        return self.scn.solver["control"] == "arclength"

    def timings(self):
        """Seconds per phase: earlier sessions' plus this one's."""
        t = {k: float(self.base.get(k, 0.0)) for k in PHASES}
        for k in ("assembly", "solve", "other"):
            t[k] += float((self.result.timings if self.result is not None else {}).get(k, 0.0))
        return t

    def document(self, status, error=None):
        """The results document (schema core-se3-result v1 and the run's fields)."""
        scn = self.scn
        mat = scn.spec["material"]
        params = {k: dict(value=x, unit="") for k, x in mat.items()        # the law's keys (not None)
                  if x is not None and not isinstance(x, (dict, str, bool))}
        extra = dict(critical_points=_critical_doc(self.critical)) if self.critical is not None else {}
        prov = dict(self.provenance)
        if "backend" in prov:                # what evaluated the steps so far
            prov["backend"] = dict(prov["backend"], used=sorted({r["backend"] for r in self.records if r.get("backend")}))
        if len(self.sessions) > 1:           # a resumed run: what each session ran with, from which step
            prov["sessions"] = self.sessions
        extra.update(unit_system=unit_system_record(scn.spec["units"]), load_numbers=scn.load_numbers(),
                     provenance=prov)
        return result_document(scn.name, "core_se3", scn.solver["element"], params, scn.mesh, self.records,
                               self.timings(), None, control=scn.solver["control"],
                               scenario=os.path.abspath(scn.file) if not scn.file.startswith("<") else scn.file,
                               fingerprint=scn.fingerprint, units=scn.spec["units"], status=status, error=error,
                               **extra)


def _critical_doc(cps):
    return [dict(kind=c.kind, load_factor=float(c.lam), bracket=[float(x) for x in c.lam_bracket],
                 step=int(c.step), accuracy=None if c.accuracy is None else float(c.accuracy),
                 negative_eigenvalues=[None if n is None else int(n) for n in c.negative_eigenvalues],
                 description=c.describe(), **c.extras()) for c in cps]


class Sink:
    """A consumer of the run's steps (module docstring); the default methods do nothing."""

    def step(self, run, ev):
        return None

    def end(self, run, status, message=None):
        return None


class VtuSink(Sink):
    """``vtu/step_NNNN.vtu`` of every ``every``-th step and the last (rank 0 writes; every rank
    computes its cells), with the obstacles' surfaces beside it."""

    def __init__(self, every):
        self.every = every

    def due(self, ev):
        return ev.k % self.every == 0 or ev.finished

    def step(self, run, ev):
        if self.due(ev):
            write_step_vtu(run, ev.k, ev.g, ev.lam, ev.record.get("physical"))


def write_step_vtu(run, k, g, lam, physical=None):
    """The VTU file of step k (module docstring of ``scenario.sinks``)."""
    prob = run.scn.problem
    # a linear analysis' state g0 (exp(w), v): its strains are not the linear ones (a cantilever's
    # linear deflection of L/3 stretches its chords), the fields are those of its increments; its
    # loads are those at the reference (a magnet's couple of the turned B^r is not what was solved)
    linear = run.scn.solver["control"] == "linear"
    eta = linear_increments(prob.mesh.g0, g) if linear else None
    if run.ctx is not None:
        cells = run.ctx.cell_fields(g, eta)
    else:
        cells = prob.element.cell_fields(g) if eta is None else prob.element.cell_fields(g, increments=eta)
    loads_at = prob.mesh.g0 if linear else None
    # rank 0 writes; a failure (a full disk) stops every rank alike
    on_root(lambda: step_files((run.rd, "vtu"), prob, k, g, lam, cells, physical, loads_at))


def step_files(where, prob, k, g, lam, cells, physical=None, loads_at=None):
    """``vdir/step_k.vtu`` in the run directory ``rd``, ``where = (rd, vdir)`` (frames, the loads'
    point fields, the stress resultants ``cells``, FieldData load_factor and the ``physical``
    record's values) and
    ``vdir/step_k_obstacles.vtu`` beside it: the one writer of a run's, a design's and ``bench run
    --vtu``'s step files, each registered in ``rd``'s manifest and written atomically.
    ``loads_at``: the frames at which the loads' point fields are evaluated (default g; a linear
    analysis' are the reference frames, where its loads were taken: at its state a magnet's
    couple of the turned B^r read +6.9e-5 where the solved couple is -8.0e-5)."""
    from ..io import write_obstacles, write_vtu
    from .outputs import point_fields
    rd, vdir = where
    values = {"load_factor": float(lam)}
    values.update({f"{n} [{v['unit']}]" if v["unit"] else n: v["value"] for n, v in (physical or {}).items()})
    fields = point_fields(prob, g if loads_at is None else loads_at, lam)
    with atomic_path(rd.file(f"{vdir}/step_{k:04d}.vtu")) as tmp:
        write_vtu(tmp, prob.mesh.X, prob.mesh.quads, prob.mesh.g0, g, point_data=fields,
                  cell_data=cells, field_data=values)
    obstacles = obstacles_of(prob)
    if obstacles:
        with atomic_path(rd.file(f"{vdir}/step_{k:04d}_obstacles.vtu")) as tmp:
            write_obstacles(tmp, obstacles, g[:, :3, 3], lam)


def write_path_vtu(rd, vdir, prob, steps, physical=None):
    """The VTU files of a solved path (``Result.steps``: a design's pose, ``bench run --vtu``) in
    ``rd``'s folder ``vdir``, as a run writes its steps (:func:`step_files`, :func:`series_files`),
    each step's contact multipliers set again first (its contact fields, not the last step's).
    ``physical``: lam -> the step's physical record (``outputs.physical_record``; a design's at
    its values), or None.  Returns the path of ``series.pvd``."""
    from ..results import restore_multipliers
    for k, s in enumerate(steps):
        restore_multipliers(prob, s)
        step_files((rd, vdir), prob, k, s.g, s.load_factor, prob.element.cell_fields(s.g),
                   None if physical is None else physical(s.load_factor))
    return series_files(rd, vdir, list(range(len(steps))), [s.load_factor for s in steps])


class CheckpointSink(Sink):
    """``checkpoint.npz`` after every step: frames, restart state, records, timings."""

    def step(self, run, ev):
        with held_signals():                  # the file and the count of what it holds agree
            def save():
                ck = Checkpoint(run.rd.path)
                run.rd.file("checkpoint.npz")
                ck.save(run.scn.fingerprint, dict(step=ev.k, lam=ev.lam, g=ev.g, unwrap=ev.unwrap,
                                                  records=run.records, timings=run.timings(), extra=ev.extra,
                                                  arrays=ev.arrays))
            on_root(save)
            run.saved = len(run.records)      # what a resume continues from


class PvdSink(Sink):
    """``vtu/series.pvd`` (and ``vtu/obstacles.pvd``) over the VTU files written so far."""

    def __init__(self, vtu):
        self.vtu = vtu

    def step(self, run, ev):
        if self.vtu.due(ev):
            on_root(lambda: write_series_files(run, ev.finished))


def write_series_files(run, finished):
    """The .pvd collections of the step files that exist (:func:`series_files`)."""
    vtu_dir = os.path.join(run.rd.path, "vtu")
    written = [r for r in run.records if os.path.exists(os.path.join(vtu_dir, f"step_{r['step']:04d}.vtu"))]
    series_files(run.rd, "vtu", [r["step"] for r in written], [r["load_factor"] for r in written])


def series_files(rd, vdir, steps, lams):
    """``vdir/series.pvd`` over the files of ``steps`` (and ``vdir/obstacles.pvd`` over their
    obstacles' files where written); their times are the load factors ``lams``, or the step
    numbers where those do not increase (``io.vtk.pvd_times``).  Returns the series' path."""
    from ..io.vtk import pvd_times, write_pvd
    times = pvd_times(lams, steps)
    entries = [(t, f"step_{k:04d}.vtu") for t, k in zip(times, steps)]
    with atomic_path(rd.file(f"{vdir}/series.pvd")) as tmp:
        write_pvd(tmp, entries)
    obst = [(t, f[:-4] + "_obstacles.vtu") for t, f in entries
            if os.path.exists(os.path.join(rd.path, vdir, f[:-4] + "_obstacles.vtu"))]
    if obst:                         # the obstacles' surfaces as a series of their own
        with atomic_path(rd.file(f"{vdir}/obstacles.pvd")) as tmp:
            write_pvd(tmp, obst)
    return os.path.join(rd.path, os.path.normpath(f"{vdir}/series.pvd"))


class ProvenanceSink(Sink):
    """The peak memory of every rank after each step (collective in a distributed run)."""

    def step(self, run, ev):
        from .provenance import ranks_memory
        run.provenance["peak_memory"] = [float(m) for m in ranks_memory(run.ctx)]


class DocumentSink(Sink):
    """``results.json``: written at the start (status running), after every step, and at the end
    with the status and the message."""

    def start(self, run):
        on_root(lambda: write_json_atomic(run.rd.file("results.json"), run.document("running")))

    def step(self, run, ev):
        on_root(lambda: write_json_atomic(run.rd.file("results.json"), run.document(
            "complete" if ev.finished and not run.arc else "running")))

    def end(self, run, status, message=None):
        on_root(lambda: write_json_atomic(run.rd.file("results.json"), run.document(status, message)))


class ProgressSink(Sink):
    """The progress line (``io.Progress``): None = only on a terminal (after 2 s), True = always."""

    def __init__(self, run, progress, nsteps):
        explicit = bool(progress)
        self.bar = Progress(nsteps, (sys.stdout.isatty() if progress is None else explicit) and run.root,
                            delay=0.0 if explicit else 2.0)
        self.lam_end = run.scn.solver["lam_end"]

    def step(self, run, ev):
        if ev.k <= run.done:
            return
        rec = run.records[-1]
        dlam = ev.lam - run.records[-2]["load_factor"] if len(run.records) > 1 else ev.lam
        self.bar.update(ev.k, ev.lam, rec.get("iterations", 0), rec.get("residual", 0.0),
                        fraction=(ev.lam / self.lam_end) if run.arc else None,
                        extra=f"  dlam {dlam:.3g}" + (f"  {rec['substeps']} sub-steps" if rec.get("substeps", 1) > 1
                                                       else ""))

    def end(self, run, status, message=None):
        self.bar.close()


class StopAfter(Sink):
    """Raise RunInterrupted once ``n`` new steps are done (tests of resume)."""

    def __init__(self, n):
        self.n, self.count = n, 0

    def step(self, run, ev):
        if ev.k > run.done:
            self.count += 1
            if self.count >= self.n and not ev.finished:
                raise RunInterrupted(f"stopped after {'path point' if run.arc else 'step'} {ev.k} as asked "
                                     f"(stop_after={self.n})")

"""Parameter sweeps: one scenario over a grid of values of one or more of its keys, each run
warm-started from the nearest finished one where the problem allows, with one CSV of the probes
against the swept values and a plot.

    from core_se3 import scenario
    res = scenario.sweep(scenario.load("gripper.toml"), {"fields.coil.B[2]": [0.02, 0.04, 0.06]},
                         out="out/sweep")
    res.rows[-1]["tip_0.uz"], res.files["csv"]

The same from the command line: ``core-se3 sweep FILE.toml --set KEY=v1,v2,... [--set ...]`` or
a ``[sweep]`` section in the file (``KEY = [v1, v2, ...]``).

Warm start: when the swept keys are values of loads, fields, magnets, material or solver (the
same mesh and supports), load control without prescribed motion or friction (path dependent:
its history is not a function of the final state), each run after the first is
one Newton solve at the final load factor starting from the final state of the nearest
finished run (in the swept values, scaled by each key's range); if that fails it runs the
scenario's load steps from the reference state.  Away from limit points (a single equilibrium
branch) both give the same state to the Newton tolerances; ``warm=False`` (``--cold``) always
steps from the reference.  The CSV records which runs were warm-started.

Lifecycle: every value and every point of the grid are validated before the first run
(:func:`check_sweep`, also ``core-se3 run --check`` of a file with a [sweep]); ``sweep.csv`` (and
the checkpoint ``sweep.npz``: the finished rows and their final states) are rewritten after
every finished run,
so that an interrupted sweep (SIGTERM, Ctrl-C, a kill) keeps them, and ``resume=True``
(``--resume``) continues with the next point, warm-started from the same states: the rows of a
resumed sweep are those of an uninterrupted one, bit for bit.  ``sweep.json`` holds the status
(``running``, ``complete``, ``interrupted``), the message and the provenance.  The output
directory is handled as a run's (``io.rundir``: its own files only, a lock, ``force``).
"""
from __future__ import annotations

import itertools
import os
import re
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..backend import rent_state, restore_rent
from ..errors import CheckpointError, ConvergenceError, CoreSE3Error, ElementWarning, ScenarioError
from ..io.lifecycle import Terminated, held_signals, termination_as_interrupt
from ..io.rundir import RunDirectory
from ..results.document import contact_record
from .keys import check_key, repeated_value
from .sweep_files import SWEEP_FILES, SweepCheckpoint, write_csv, write_plot, write_status

__all__ = ["sweep", "check_sweep", "SweepResult", "parse_values", "WARM_SECTIONS", "point_row"]

WARM_SECTIONS = ("loads", "fields", "magnets", "material", "solver")


@dataclass
class SweepResult:
    """What a sweep left: ``keys`` (the swept keys), ``rows`` (one dict per grid point: the swept
    values, status, warm, steps, iterations, every probe's final ux, uy, uz, rotation and rotation_vector, every
    obstacle's contact force and report), ``files`` (csv, plot, status), ``status``.

    Example
    -------
    >>> SweepResult(["material.E"], [{"material.E": 1.0, "status": "complete"}]).rows[0]["status"]
    'complete'
    """
    keys: list
    rows: list = field(default_factory=list)
    files: dict = field(default_factory=dict)
    status: str = "complete"


def _literal(item):
    """One value as TOML reads it: an integer (``8``), a number (``8.0``, ``1e6``), true/false, or
    a string (bare or quoted); the scenario's schema then checks its type (an integer key such
    as ``mesh.nx`` takes ``8``, not ``8.5``)."""
    if re.fullmatch(r"[+-]?\d+", item):
        return int(item)
    if item in ("true", "false"):
        return item == "true"
    try:
        return float(item)
    except ValueError:
        pass
    if len(item) >= 2 and item[0] == item[-1] and item[0] in "'\"":
        return item[1:-1]
    if not item or not re.fullmatch(r"[A-Za-z0-9_.+-]+", item):
        raise ValueError(item)
    return item


def parse_values(text, key="--set"):
    """The values of ``KEY=v1,v2,...``, each typed as TOML would read it: integers, numbers,
    true/false, strings, and ``[a;b;c]`` for a vector value.

    Example
    -------
    >>> parse_values("0.02,0.04"), parse_values("[0;0;0.02],[0;0;0.04]")
    ([0.02, 0.04], [[0.0, 0.0, 0.02], [0.0, 0.0, 0.04]])
    >>> parse_values("8,16"), parse_values("banded,superlu")
    ([8, 16], ['banded', 'superlu'])
    """
    out, depth, cur = [], 0, ""
    for ch in text:
        depth += ch == "["
        depth -= ch == "]"
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    out.append(cur)
    vals = []
    for item in out:
        item = item.strip()
        try:
            if item.startswith("["):
                vals.append([float(x) for x in item.strip("[]").split(";")])
            else:
                vals.append(_literal(item))
        except ValueError:
            raise ScenarioError(f"cannot read the value {item!r} of {key} (values separated by commas: numbers, "
                                "true/false, names; a vector as [a;b;c])", key=key) from None
    if not vals or any(v == "" for v in vals):
        raise ScenarioError(f"{key} needs at least one value", key=key)
    if repeated_value(vals):
        raise ScenarioError(f"{key} {repeated_value(vals)}", key=key)
    return vals


def _nearest(done, point, spans):
    """(frames, row) of the finished point nearest to ``point`` ((None, None) if none)."""
    best, dist = (None, None), np.inf
    for pt, (g, row) in done:
        if g is None:
            continue
        d = sum(_distance(a, b, s) for a, b, s in zip(pt, point, spans))
        if d < dist:
            best, dist = (g, row), d
    return best


def _unwrapped(row):
    """name -> the unwrapped rotation vector of every probe of a finished row (``NAME.rotation_vector``;
    None for no row, and a probe missing from a row of an older checkpoint starts at zero)."""
    if row is None:
        return None
    tail = ".rotation_vector"
    return {k[:-len(tail)]: np.asarray(v, float) for k, v in row.items() if k.endswith(tail)}


def _distance(a, b, span):
    if span is None:                          # names or switches: equal or not
        return 0.0 if a == b else 1.0
    return float((((np.ravel(a) - np.ravel(b)) / span) ** 2).sum())


def _span(values):
    if any(isinstance(v, (str, bool)) for v in values):
        return None
    arr = np.array([np.ravel(v) for v in values], float)
    r = arr.max(0) - arr.min(0)
    return np.where(r > 0, r, 1.0)


def _check_values(scn, grid, where):
    """Every swept value validated before the first run (one override at a time): a bad value
    is an error naming its key, not a failed row after an hour of runs."""
    for k, vals in grid.items():
        check_key(scn.raw, k, scn.file)
        for x in vals:
            try:
                scn.with_overrides({k: x})
            except ScenarioError as exc:
                raise ScenarioError(f"the swept value {x!r} of {k}: {exc.detail}", scn.file,
                                    f"{where}.{k}" if where == "sweep" else k) from None


def check_sweep(scn, grid=None):
    """Validate a sweep without solving, as :func:`sweep` does before its first run: every value
    of every key (one override at a time: the error names the value and its key), then, with
    several keys, every point of the grid (values valid one by one may not be together: a mesh
    ``nx = 2`` and a node set at x = 2.5, where that mesh has no node; such a point stopped the
    sweep when its turn came, after the runs before it).

    Parameters
    ----------
    scn : Scenario
        The base scenario.
    grid : dict, optional
        Dotted key -> values (``--set``; errors name the key); default the scenario's [sweep]
        section (errors name ``sweep.KEY``, or ``sweep`` for a point).

    Returns
    -------
    (dict, list)
        The grid and its points (tuples of values in the grid's key order).

    Example
    -------
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "edges": {"mid": {"box": {"x": [5.0, 5.0]}}}, "probes": [{"name": "mid", "edge": "mid"}]})
    >>> check_sweep(scn, {"mesh.nx": [2, 4]})[1]
    [(2,), (4,)]
    >>> check_sweep(scn, {"mesh.nx": [2, 4], "edges.mid.box.x": [[5.0, 5.0], [2.5, 2.5]]})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.ScenarioError: <dict>: [--set]: the swept point mesh.nx = 2, edges.mid.box.x = [2.5, 2.5]: [edges.mid]: selects no nodes
    """
    where = "--set" if grid is not None else "sweep"
    if grid is None:
        if not scn.spec["sweep"]:
            raise ScenarioError("nothing to sweep: give a grid or a [sweep] section", scn.file, "sweep")
        grid = dict(scn.spec["sweep"])
    keys = list(grid)
    _check_values(scn, grid, where)
    points = list(itertools.product(*[grid[k] for k in keys]))
    if len(keys) > 1:
        for pt in points:
            try:
                scn.with_overrides(dict(zip(keys, pt)))
            except ScenarioError as exc:
                said = f"[{exc.key}]: " if exc.key else ""
                raise ScenarioError(f"the swept point {', '.join(f'{k} = {x!r}' for k, x in zip(keys, pt))}: "
                                    f"{said}{exc.detail}", scn.file, where) from None
    return grid, points


def sweep(scn, grid=None, out=None, progress=None, warm=True, plot=True, resume=False, force=False):
    """Run ``scn`` at every point of ``grid`` (dotted key -> list of values; several keys: the
    product; default the scenario's own [sweep] section), warm-starting each run from the
    nearest finished one.

    Parameters
    ----------
    scn : Scenario
        The base scenario.
    grid : dict, optional
        Dotted key (as for ``Scenario.with_overrides``) -> values (a bad value is an error naming
        its key, e.g. ``material.E``); default the [sweep] section (errors name ``sweep.KEY``).
        Every value and every point is validated before the first run (:func:`check_sweep`).
    out : str, optional
        Directory of ``sweep.csv``, ``sweep.png``, ``sweep.json``, ``sweep.npz`` (default
        out/NAME-sweep).
    progress : bool, optional
        Progress line (None: only on a terminal).
    warm : bool, optional
        Warm starts (module docstring).
    plot : bool, optional
        Write ``sweep.png``.
    resume, force : bool, optional
        Continue an interrupted sweep in ``out`` (a CheckpointError where ``out`` holds no sweep:
        nothing to resume; one stopped before its first row starts over); start over in a
        directory of an earlier one.

    Returns
    -------
    SweepResult

    Example
    -------
    >>> import tempfile
    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}],
    ...     "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 1}})
    >>> res = sweep(scn, {"material.E": [1.2e6, 2.4e6]}, out=tempfile.mkdtemp(), plot=False)
    >>> a, b = (r["tip.uz"] for r in res.rows)
    >>> round(a / b, 6), [r["warm"] for r in res.rows]           # nearly linear: twice E, half the lift
    (2.0, [False, True])
    """
    from .runner import output_directory
    _one_process(scn)
    grid, points = check_sweep(scn, grid)
    keys = list(grid)
    rd = RunDirectory(output_directory(scn, out, "-sweep"), "sweep", SWEEP_FILES)
    with termination_as_interrupt(), rd.claim(resume=resume, force=force, adopt=SWEEP_FILES):
        if resume:
            _resumable(rd)
        state = SweepCheckpoint(rd, scn, grid, warm)
        result = SweepResult(keys, state.rows, status="running")
        with held_signals():
            # the checkpoint read first: one of another sweep is refused before sweep.json is
            # touched (it turned a complete sweep's status into 'running' with 0 rows)
            if resume:
                result.rows = state.load().rows
            write_status(rd.file("sweep.json"), result, scn, state)     # from the start
        try:
            _run_points(scn, keys, points, state, warm, progress)
        except KeyboardInterrupt as exc:
            what = exc.describe() if isinstance(exc, Terminated) else "Ctrl-C (SIGINT)"
            with held_signals():
                result.status = "interrupted"
                result.files = _write_all(rd, result, state, scn, plot, f"interrupted by {what} after {len(state.rows)} "
                                          f"of {len(points)} runs: the finished rows are kept; continue with --resume")
            raise
        except Exception as exc:              # (a full disk, no memory): not left 'running'
            _failed(rd, result, state, scn, exc, len(points))
            raise
        with held_signals():                  # the last files complete, then a signal that came
            result.status = "complete"
            result.files = _write_all(rd, result, state, scn, plot)
    return result


def _resumable(rd):
    """A CheckpointError where a resume in ``rd`` has nothing to continue from: no sweep there
    (before, a fresh sweep started silently), or finished rows in sweep.csv without the
    checkpoint sweep.npz (deleted: the resume started over, replacing them).  A sweep stopped
    before its first row (its sweep.json, no row) starts over."""
    if os.path.exists(os.path.join(rd.path, "sweep.npz")):
        return
    if not rd.previous and not rd.existed:      # (a manifest alone: a sweep killed as it began)
        raise CheckpointError(f"nothing to resume: {rd.path} holds no sweep (no sweep.npz, no file of an earlier "
                              "sweep); give the directory of the sweep to continue, or start one without --resume")
    try:
        with open(os.path.join(rd.path, "sweep.csv")) as fh:
            rows = sum(1 for line in fh if line.strip()) - 1
    except OSError:
        rows = 0
    if rows > 0:
        raise CheckpointError(f"cannot resume: {os.path.join(rd.path, 'sweep.npz')} is missing, but sweep.csv holds "
                              f"{rows} finished row(s): they cannot be continued without it, and --resume would "
                              "replace them; start over with --force, or use another --out")


def _one_process(scn):
    """A sweep runs its points one after another in one process (warm starts from the nearest
    point's frames): under ``mpirun -n N`` (N > 1) every rank would claim the same directory and
    all but one stopped with 'in use by another live run' (its own sibling), leaving sweep.json
    'running' with no row.  A ParallelError on every rank instead, before anything is written."""
    from ..backend import launched_ranks
    from ..errors import ParallelError
    n = launched_ranks()
    if n > 1:
        raise ParallelError(f"{scn.file}: a sweep runs its grid points one after another in one process; it "
                            f"does not run under mpirun ({n} ranks): run core-se3 sweep without mpirun, or each "
                            "point over the ranks with mpirun core-se3 run")


def _failed(rd, result, state, scn, exc, n):
    """sweep.json of a sweep stopped by an error its points do not catch (an OSError writing its
    files, a MemoryError): status 'failed' and the error, its finished rows kept (sweep.json
    said 'running' for ever).  Written as far as it can be: the error itself may be the disk's."""
    with held_signals():
        result.status = "failed"
        try:
            write_status(rd.file("sweep.json"), result, scn, state,
                         f"failed after {len(state.rows)} of {n} runs: {type(exc).__name__}: {exc}; the finished "
                         "rows are kept: continue with --resume")
        except OSError:
            pass


def _write_all(rd, result, state, scn, plot, message=None):
    files = dict(csv=write_csv(rd.file("sweep.csv"), result.keys, result.rows))
    if plot and result.rows:
        files["plot"] = write_plot(rd.file("sweep.png"), result, scn.name)
    files["status"] = write_status(rd.file("sweep.json"), result, scn, state, message)
    return files


def _run_points(scn, keys, points, state, warm, progress):
    """The loop over the grid points not done yet: each finished row is written at once."""
    from ..io import Progress
    import sys
    spans = [_span(v) for v in zip(*points)] if points else []
    can_warm = warm and all(k.split(".")[0].split("[")[0] in WARM_SECTIONS for k in keys)
    bar = Progress(len(points), sys.stdout.isatty() if progress is None else bool(progress), delay=0.0)
    try:
        for i, pt in enumerate(points):
            if i < len(state.rows):
                continue
            done = [(p, (g, r)) for p, g, r in zip(points, state.finals, state.rows)]
            g_start, near = _nearest(done, pt, spans) if can_warm and done else (None, None)
            row, g = point_row(scn.with_overrides(dict(zip(keys, pt))), dict(zip(keys, pt)), g_start,
                               _unwrapped(near))
            with held_signals():
                state.add(row, g, rent_state())
                write_csv(state.rd.file("sweep.csv"), keys, state.rows)
            bar.update(i + 1, 0.0, row.get("iterations", 0), 0.0,
                       extra=f"  {', '.join(f'{k}={v}' for k, v in zip(keys, pt))}", label=f"run {i + 1}/{len(points)}")
    finally:
        bar.close()


def point_row(s, values, g_start=None, unwrap=None):
    """Solve one grid point (the scenario ``s`` with the swept ``values``): (row, final frames or
    None).  The row holds the values, status, warm, steps, iterations, every probe's final
    displacement, rotation (angle) and rotation_vector (unwrapped along the path, as in
    results.json), every support's force and moment about its nodes' centroid
    (``supports[i].Fx`` ... ``supports[i].Mz``: ``StepResult.support_reactions``), every
    obstacle's contact force, moment and report; a failed point its error.
    ``g_start``: the frames of a warm start, ``unwrap`` (name -> (3,)): its probes' unwrapped
    rotation vectors, which the warm solve continues (a roll-up past pi kept its turns)."""
    row = dict(values)
    try:
        final, nsteps, its, warm_used = _solve(s, g_start, unwrap)
    except (ConvergenceError, CoreSE3Error) as exc:
        row.update(status="failed", warm=g_start is not None, error=str(exc).split("\n")[0][:200])
        return row, None
    row.update(status="complete", warm=warm_used, steps=nsteps, iterations=its)
    for name, p in final.probes.items():
        for c, x in zip("xyz", p["u"]):
            row[f"{name}.u{c}"] = float(x)
        row[f"{name}.rotation"] = float(np.linalg.norm(p["rotation_vector"]))
        row[f"{name}.rotation_vector"] = [float(x) for x in p["rotation_vector"]]
    for name, r in (final.support_reactions or {}).items():       # force, moment about its centroid
        for q, key in (("F", "force"), ("M", "moment_about_point")):
            row.update({f"{name}.{q}{comp}": float(x) for comp, x in zip("xyz", r[key])})
    for name, c in (final.contact or {}).items():
        rec = contact_record(c)
        for q in ("force", "moment"):
            for comp, x in zip("xyz", rec.pop(q)):
                row[f"contact.{name}.{q[0].upper()}{comp}"] = float(x)
        row.update({f"contact.{name}.{k}": v for k, v in rec.items()})
    return row, final.g


def _solve(s, g_start, unwrap=None):
    """Solve one grid point: (final StepResult, steps, iterations, warm).  Warm: one Newton
    solve at the final load factor from ``g_start``, its probes' rotations unwrapped on from
    ``unwrap`` (the start's: from zero, a tip rolled to 1.3 pi warm-started from 1.2 pi read
    2 pi - 1.3 pi = 0.7 pi, where the cold run reads 1.3 pi); cold (and on a failed warm start):
    the scenario's own load steps from the reference state."""
    from ..model.solving import warn_final_state
    from ..results import StepRecorder
    from ..solvers import NewtonOptions, NewtonState, newton_steps
    sv = s.solver
    # a path-dependent load (Coulomb friction) has no state of g alone: a warm start would
    # skip its history, so such a point steps from the reference
    path_dependent = any(getattr(ld, "path_dependent", False) for ld in s.problem.loads)
    warm = g_start is not None and sv["control"] == "load" and not s.problem.has_prescribed_motion \
        and not s.problem.element.stateful and not path_dependent
    if warm:
        lam = s.load_factors()[-1]
        # the coarse-mesh warning, as Problem.solve gives it: a warm point does not go through
        # Problem.solve, and a swept thickness or law changes the index (h 0.25 -> 0.0025 on the
        # roof 2x2: the thin point, 10.9 times its deflection, was silent)
        s.problem.check_element(stacklevel=4)
        opts = NewtonOptions(rtol=sv["rtol"], dtol=sv["dtol"], max_iter=sv["max_iter"], max_cutbacks=0,
                             linear_solver=sv["linear_solver"], iteration=sv["iteration"])
        try:
            items = list(newton_steps(s.problem, [lam], opts, start=NewtonState(lam * (1 - 1e-9), g_start),
                                      recorder=StepRecorder(s.problem, unwrap)))
            its = sum(e["iterations"] for e in items[-1].tries)
            warn_final_state(s.problem, items[-1].step, stacklevel=4)     # as Problem.solve (a cold point)
            return items[-1].step, 1, its, True
        except (ConvergenceError, CoreSE3Error):
            pass
    with warnings.catch_warnings():
        if warm:                                        # said above: the cold start would say it again
            warnings.simplefilter("ignore", ElementWarning)
        res = s.problem.solve()
    return res.final, len(res.steps) - 1, int(sum(st.iterations for st in res.steps)), False



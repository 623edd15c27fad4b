"""Path following of a Problem: arc length (a generator of converged steps and a wrapper that
returns a Result) and displacement control, on the algorithm of ``solvers.arclength``."""
from __future__ import annotations

import logging
import numbers
import time
import warnings
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from ..errors import (ConvergenceError, ElementTooDistortedError, OptionError, PathWarning, SingularSystemError,
                      did_you_mean)
from ..results import Result, StepRecorder
from .arclength import ArcState, PathError, PathInfo, arc_options, path_steps
from .corrector import LinearConstraint, StepFailed, correct
from .critical import Corrector, narrow, turned_twice
from .options import ArcLengthOptions, unknown_keywords
from .stability import analyse, locate_critical
from .step_checks import path_measures, path_refusal
from .system import ShellSystem

__all__ = ["PathStep", "arc_length_steps", "arc_length", "displacement_control"]

log = logging.getLogger(__name__)


@dataclass
class PathStep:
    """One converged point of a shell path: its StepResult (with ``stability``) and the
    ArcState to restart from (``unwrap``: the probes' unwrapped rotation vectors).

    Attributes
    ----------
    step : core_se3.StepResult
        The point, ``step.stability`` = dict(det_sign, negative_eigenvalues, q_dot_t).
    state : ArcState
        The restart state (``state.step``: the point's index on the path).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> first = next(arc_length_steps(p, dlam0=0.5))
    >>> first.step.load_factor, first.state.step, first.step.stability["negative_eigenvalues"]
    (0.0, 0, 0)
    """
    step: object
    state: ArcState


def _stability(pt):
    return dict(det_sign=pt.sign, negative_eigenvalues=pt.n_neg, q_dot_t=pt.qt)


def _record(rec, pt, sysm, log, counted):
    """The StepResult of a path point, with the tries (log entries) and factorisations
    (``sysm.factorizations``) since the previous one; ``counted`` = [entries, factorisations]
    already attributed, advanced here."""
    g, forces, local = pt.state, (pt.ev["rint"], pt.ev["fext"]), None
    if sysm.origin is not None:                 # a state relative to the part (ShellSystem.whole)
        g, local = sysm.whole(pt.state), (pt.state, sysm.origin)          # the probes read the exact positions
        if not pt.hist:                         # the start point, recorded at the whole frames as newton_solve
            ev = sysm.problem.evaluate(g, pt.lam, tangent=False)         # does (there r_int = 0 exactly)
            forces = (ev.r_int, ev.f_ext)
    st = rec.step(pt.lam, g, pt.its, pt.hist, forces, _stability(pt), local=local)
    st.residual_floor = min(float(pt.ev.get("floor", 0.0)), 1e300) if pt.hist else 0.0
    st.attempts = len(log) - counted[0]
    st.linear_solves = sysm.factorizations - counted[1]
    counted[:] = [len(log), sysm.factorizations]
    return st


def arc_length_steps(problem, lam_end=1.0, stop_at=None, lam_min=None, start=None, result=None,
                     options=None, **kw):
    """Arc-length continuation of a Problem as a generator of :class:`PathStep` (the first
    point of a new path included, the start point of a resumed one not).

    stop_at = (node, lab direction, value): stop when the displacement of ``node`` along
    ``direction`` reaches ``value`` (the last step lands on it exactly).  ``result`` (a Result)
    gets the log, the critical points and the timings as the path goes.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (loads scaled by lam; no lam-dependent prescribed motion).
    lam_end : float or None, optional
        Stop at this load factor (None: only stop_at, lam_min or max_steps stop the path).
    stop_at : (int, (3,), float), optional
        As above; lam_min: stop when lam falls below it.
    start : ArcState, optional
        Continue from this restart state.
    result : core_se3.Result, optional
        Collects the log, critical points and timings.
    options : ArcLengthOptions, optional
        The controls; keywords override its fields.

    Yields
    ------
    PathStep
        A failure raises :class:`~core_se3.errors.ConvergenceError` (with ``result``).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> [(item.state.step, round(float(item.step.load_factor), 6)) for item in arc_length_steps(p, dlam0=0.5)]
    [(0, 0.0), (1, 0.511148), (2, 1.0)]
    """
    t0 = time.perf_counter()
    opts, kw = arc_options(options, kw)
    unknown_keywords("arc_length", kw, ArcLengthOptions.__dataclass_fields__)
    sysm = ShellSystem(problem, opts.linear_solver)
    control = sysm.node_displacement(stop_at[0], stop_at[1]) if stop_at else None
    if stop_at:
        _finite_values([stop_at[2]], "stop_at's value")
    for value, name in ((lam_end, "lam_end"), (lam_min, "lam_min")):
        # a NaN lam_end never stopped the path (it ran to max_steps: a tip deflection of 428 on a strip of 10)
        if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Real)
                                  or not np.isfinite(value)):
            raise OptionError(f"{name} must be a finite load factor (or None), got {value!r}")
    result = result if result is not None else Result(mesh=problem.mesh, element=problem.element_name)
    rec = StepRecorder(problem, start.unwrap if start is not None else None)
    info = PathInfo(log=result.log)
    counted = [len(result.log), 0]
    try:
        for ev in path_steps(sysm, opts, lam_end, control, stop_at[2] if stop_at else None, lam_min,
                             start, info):
            if ev.restart:                   # the re-analysed start point is not a new cost
                counted[:] = [len(result.log), sysm.factorizations]
                continue
            st = _record(rec, ev.point, sysm, result.log, counted)
            ev.state.unwrap = {k: v.copy() for k, v in rec.unwrapped.items()}
            result.critical_points = list(ev.state.critical)
            result.timings.update(assembly=info.timers[0], solve=info.timers[1],
                                  other=time.perf_counter() - t0 - info.timers[0] - info.timers[1])
            yield PathStep(st, ev.state)
    except PathError as exc:
        result.critical_points = list(info.critical)
        tm = result.timings                  # assembly, solve as of the last converged point
        tm.update(other=time.perf_counter() - t0 - tm.get("assembly", 0.0) - tm.get("solve", 0.0))
        raise ConvergenceError(f"{exc}; the converged steps are kept in .result", result) from None
    result.critical_points = list(info.critical)
    result.timings.update(assembly=info.timers[0], solve=info.timers[1],
                          other=time.perf_counter() - t0 - info.timers[0] - info.timers[1])


def arc_length(problem, lam_end=1.0, stop_at=None, lam_min=None, start=None, on_step=None,
               options=None, **kw):
    """Arc-length continuation of a Problem (module docstring); returns a Result with every
    converged step (``steps[k].stability``) and ``critical_points`` (CriticalPoint).

    Options: an ArcLengthOptions or its fields as keywords (dlam0 sets the first arc length;
    ds_max defaults to ds_max_factor (8) times that; method, psi, target_iter, max_steps, ...).
    stop_at = (node, lab direction, value) as in :func:`arc_length_steps`.  Restart:
    ``on_step(result, arc_state)`` after the first point and after every converged point;
    ``start=arc_state`` continues the path from it with the same arguments otherwise:
    ``result.steps`` then holds only the points after the start, ``critical_points`` all of
    the path, and the final state equals that of an uninterrupted call bit for bit.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    lam_end, stop_at, lam_min, start, options
        As for :func:`arc_length_steps`.
    on_step : callable, optional
        on_step(result, arc_state), e.g. to write a checkpoint.

    Returns
    -------
    core_se3.Result

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0, 0, 1.0)); p.add_probe("tip")
    >>> res = arc_length(p, lam_end=1.0, dlam0=0.5)
    >>> bool(abs(res.final.load_factor - 1.0) < 1e-12), res.critical_points
    (True, [])
    """
    result = Result(mesh=problem.mesh, element=problem.element_name)
    item = None
    for item in arc_length_steps(problem, lam_end, stop_at, lam_min, start, result, options, **kw):
        result.steps.append(item.step)
        if on_step:
            on_step(result, item.state)
    if item is not None and item.state.finished == "max_steps" and (lam_end is not None or stop_at is not None):
        end = f"lam_end = {lam_end:g}" if stop_at is None else f"stop_at value {stop_at[2]:g}"
        warnings.warn(PathWarning(
            f"arc length stopped after max_steps = {item.state.step} points at load factor "
            f"{item.step.load_factor:.6g}, short of {end}: raise max_steps (or dlam0, ds_max), or continue with "
            "start= its last ArcState"), stacklevel=2)
    return result


def _path_check(incs):
    """Refuse (StepFailed: cut back) a converged displacement-control step whose corrections grew
    or wandered (``step_checks.path_measures`` of their relative sizes ``incs``), as load
    stepping's path check does: a corrector that left the region where it contracts from the
    predictor may have converged past a snap-back of the controlled displacement, onto a part of
    the path that displacement control does not reach continuously (the 8x8 6.35 mm roof from
    -W_C = 16.75 to 17: 16 iterations, corrections grown 11x, load factor 0.073 -> -0.126 across
    the loop of the path, reported as a limit point at -0.036 that the path does not have)."""
    why = path_refusal(*path_measures(incs))
    if why:
        raise StepFailed(f"path check: the corrections {why}, so the step may have jumped to another part of the path")


def _snap_back_hint(ct, ct0, u):
    """The failure hint of displacement control at the last converged point (controlled value
    ``u``): when d u / d lam = ``ct`` (= c . K^-1 q) has fallen below 0.3 of its start value
    ``ct0`` in size, the controlled displacement is near a turning point along the path (a
    snap-back), which displacement control cannot pass; else ''."""
    s_u = ct / ct0 if ct0 != 0 else np.inf
    if not abs(s_u) < 0.3:
        return ""
    return (f". Probable cause: d u / d lam has fallen to {s_u:.3g} of its initial value, so the controlled "
            f"displacement is near a point where it turns back along the path (a snap-back near u = {u:.6g}), "
            "which displacement control cannot pass; trace the path with arc length "
            "(core_se3.solvers.arc_length, stop_at=(node, direction, value)) or control another displacement")


def _finite_values(values, what):
    """The controlled displacements as a list of finite floats, else OptionError naming ``what``
    (before: NaN surfaced as a load's NaN scale, 'abc' as a bare ValueError)."""
    try:
        out = [float(v) for v in np.atleast_1d(np.asarray(values, dtype=object))]
    except (TypeError, ValueError):
        out = [np.nan]
    if not np.all(np.isfinite(out)):
        raise OptionError(f"{what} must be finite numbers [length], got {values!r}")
    return out


def _control_constraint(value, row, target, du, dlam):
    """The constraint of a displacement-control step to ``target`` that accumulates the step's
    increment from the predictor (du, dlam) on."""
    lin = LinearConstraint(value, row, 0.0, target)
    lin.start(du, dlam)
    return lin


def _checked_correct(sysm, state, lam, con, opts, timers):
    """The corrector of a displacement-control step with the path check (:func:`_path_check`)."""
    incs = []
    out = correct(sysm, state, lam, con, opts, timers, incs)
    _path_check(incs)
    return out


def _unlocated(bisections, accuracy, opts):
    """Whether a critical point of a displacement-control step, bisected in ``bisections``
    corrector solves, stays wider than ``opts.critical_tol`` (``accuracy``): the step is refused
    (:func:`_control_critical`)."""
    return accuracy > opts.critical_tol


def _control_critical(sysm, cur, pt, lin, control, opts, timers, step):
    """The critical point between the displacement-control points cur and pt (the step's
    converged constraint ``lin``; ``control`` = (value, row)), classified and located by
    ``stability.locate_critical`` and narrowed to ``opts.critical_tol`` by ``critical.narrow``,
    bisecting the controlled displacement as arc length bisects its step.  Before, its estimate
    from the step's ends was the result: the LTB strip's bifurcation (0.742037) from two steps at
    0.6076, the 8x8 roof's limit points (0.743551, 0.170415) from steps of 4 in -W_C at 0.7411 and
    0.1597.

    A step whose bisection does not close on the point (no interior point corrected, or the
    bracket still wider than critical_tol when the interior points fail) is refused (StepFailed:
    halved): the displacement-control path is continuous in the controlled displacement through
    a critical point of K, so its interior points exist; a step that jumped across a snap-back of
    the controlled displacement has none between its two branches.  Before, the 8x8 6.35 mm roof
    from -W_C = 15 to 18 (near branch, load factor 0.184, to the far one, -0.122; W_C turns back
    at 16.94) was kept, with a 'limit point near -0.1255 located only to 0.57 after 0 solves'
    (arc length: -0.12778), and from 16 to 18.5 ('only to 0.51 after 1 solves'); the run exited
    normally over the snap-back that steps of 1 stop at."""
    value, row = control
    u0 = value(cur.state)
    cp = locate_critical(sysm, cur, pt, row(cur.state), value(pt.state) - u0, step)
    step_con = SimpleNamespace(du=lin.du, dlam=lin.dlam, ds=lin.target - u0)
    entry = narrow(sysm, cur, pt, step_con, cp, Corrector(
        _checked_correct, lambda x: _control_constraint(value, row, u0 + x, 0.0 * lin.du, 0.0), opts, timers,
        (StepFailed,)), refused=_unlocated)
    if entry["jumped"]:                  # a bifurcation's ends that do not connect (critical.returns)
        raise StepFailed(entry["jumped"])
    if _unlocated(entry["bisections"], cp.accuracy, opts):
        raise StepFailed(f"{entry['bisections']} bisections of the step from u = {u0:.6g} (load factor "
                         f"{cur.lam:.6g}) to {value(pt.state):.6g} ({pt.lam:.6g}) do not close on the {cp.kind} "
                         f"point its ends bracket (located only to {cp.accuracy:.2g}): the step jumped to "
                         "another part of the path")
    return cp


def _control_step(sysm, cur, tgt, control, opts, timers, n_points):
    """The displacement-control step from the PathPoint ``cur`` to the controlled value ``tgt``:
    (the converged PathPoint, its critical point or None); a refused step raises StepFailed
    (the path check, two hidden turns, a critical point its bisection does not close on)."""
    value, row = control
    u0 = value(cur.state)
    dl = (tgt - u0) / (row(cur.state) @ cur.t)
    lin = _control_constraint(value, row, tgt, dl * cur.t, dl)
    s2, l2, its, hist, ev = _checked_correct(sysm, sysm.update(cur.state, dl * cur.t), cur.lam + dl, lin, opts,
                                             timers)
    pt = analyse(sysm, s2, l2, opts.stability, its, hist)
    if tgt != u0 and (why := turned_twice(sysm, cur, pt, lin.du)):   # a repeated value: no step
        raise StepFailed(why)
    changed = (pt.n_neg != cur.n_neg) if (pt.n_neg is not None and cur.n_neg is not None) else (pt.sign != cur.sign)
    if not (opts.stability and changed):
        return pt, None
    return pt, _control_critical(sysm, cur, pt, lin, control, opts, timers, n_points)


def _required(given, kw):
    """OptionError naming the missing ones of displacement control's node, direction and values
    (with a misspelt keyword's correction)."""
    missing = [k for k, v in given.items() if v is None]
    if not missing:
        return
    hints = "".join(f"; unknown keyword {k!r}{did_you_mean(k, missing)}" for k in kw if did_you_mean(k, missing))
    raise OptionError(f"displacement control: missing {', '.join(missing)}{hints}.  Give the controlled node "
                      "(an id), the lab direction (3,) of its displacement and the displacements to reach, e.g. "
                      "solve(control='displacement', node=k, direction=(0, 0, 1), values=[0.1, 0.2])")


def displacement_control(problem, node=None, direction=None, values=None, options=None, max_cutbacks=10, **kw):
    """Prescribe the displacement of ``node`` along the lab ``direction`` through ``values``
    (the load factor is the unknown that keeps it there); failed increments are halved (at
    most ``max_cutbacks`` times).  Records every requested value; ``result.critical_points`` as
    for arc_length.  Options: ArcLengthOptions fields max_iter, rtol, dtol, stability,
    linear_solver (the others do not apply).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (loads scaled by lam).
    node : int
        The controlled node (with a free translation); ``node``, ``direction`` and ``values``
        are required (an OptionError names the missing ones: ``Problem.solve(control=
        'displacement')`` without them was a bare TypeError).
    direction : (3,) array_like
        Lab direction of the controlled displacement (normalised).
    values : float or sequence of float
        The displacements to reach [length], in order.
    options : ArcLengthOptions, optional
        Keywords override its fields; ``max_cutbacks``: halvings per value.

    Returns
    -------
    core_se3.Result
        The initial state and one step per value (its ``load_factor`` the load that holds it).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> k = int(p.mesh.node_set("x1")[0])
    >>> res = displacement_control(p, k, (0.0, 0.0, 1.0), [1.0, 2.0])
    >>> [round(float(st.g[k, 2, 3]), 12) for st in res.steps], [round(float(st.load_factor), 3) for st in res.steps]
    ([0.0, 1.0, 2.0], [0.0, 0.308, 0.636])
    """
    t0 = time.perf_counter()
    _required(dict(node=node, direction=direction, values=values), kw)
    opts, kw = arc_options(options, kw)
    unknown_keywords("displacement_control", kw, ArcLengthOptions.__dataclass_fields__)
    sysm = ShellSystem(problem, opts.linear_solver)
    value, row = sysm.node_displacement(node, direction)
    values = _finite_values(values, "displacement_control values")
    result = Result(mesh=problem.mesh, element=problem.element_name)
    rec = StepRecorder(problem)
    timers = [0.0, 0.0]
    crit = []
    try:
        counted = [0, 0]
        cur = analyse(sysm, sysm.initial(), 0.0, opts.stability)
        ct0 = row(cur.state) @ cur.t                 # d u / d lam at the start
        result.steps.append(_record(rec, cur, sysm, result.log, counted))
        n_points = 1
        for target in values:
            sub = [target]
            while sub:
                tgt = sub[-1]
                u0 = value(cur.state)
                rt = row(cur.state)
                try:
                    pt, cp = _control_step(sysm, cur, tgt, (value, row), opts, timers, n_points)
                    ok, reason = True, ""
                except (StepFailed, ElementTooDistortedError, FloatingPointError,
                        SingularSystemError, ZeroDivisionError) as exc:
                    ok, reason = False, str(exc)
                result.log.append(dict(control=tgt, converged=ok, reason=reason))
                log.info("  u* %.6g: %s", tgt, f"lam {pt.lam:.6g} it {pt.its}" if ok else f"FAIL {reason}")
                if not ok:
                    if len(sub) > max_cutbacks:
                        raise PathError(f"displacement control failed at u = {tgt:.6g} ({reason}); the last "
                                        f"converged u is {u0:.6g} at load factor {cur.lam:.6g}"
                                        + _snap_back_hint(rt @ cur.t, ct0, u0), None)
                    sub.append(0.5 * (u0 + tgt))
                    continue
                sub.pop()
                if cp is not None:
                    crit.append(cp)
                    log.info("  ** %s", cp.describe())
                cur = pt
                if not sub:
                    result.steps.append(_record(rec, pt, sysm, result.log, counted))
                    n_points += 1
    except PathError as exc:
        result.critical_points = crit
        result.timings.update(assembly=timers[0], solve=timers[1],
                              other=time.perf_counter() - t0 - timers[0] - timers[1])
        raise ConvergenceError(f"{exc}; the converged steps are kept in .result", result) from None
    result.critical_points = crit
    result.timings.update(assembly=timers[0], solve=timers[1],
                          other=time.perf_counter() - t0 - timers[0] - timers[1])
    return result

"""Load-stepped Newton over MPI ranks: the serial iteration of ``solvers.newton`` (same
convergence test, mixed iteration, cut-back and regrowth, prescribed-motion splitting, limit-
point check, the same log entries), on a :class:`~core_se3.parallel.run.DistributedRun`.

Each rank evaluates its elements, the norms and dot products are global (every rank takes the
same decisions), the tangent is solved by PETSc, the owners update their frames and the ghosts
follow.  At each converged state the frames of the whole mesh are gathered, so the step
records (probes, reactions, balance) are the serial recorder's and every rank holds the same
:class:`~core_se3.results.Result`.

    mpirun -n 2 python -c "import core_se3 ..."    # Problem.solve dispatches here
"""
from __future__ import annotations

import logging
import time

import numpy as np

from ..errors import ConvergenceError, ElementTooDistortedError, LinearSolverError, SingularSystemError
from ..results import Result, StepRecorder
from ..solvers import MAX_PRESCRIBED_TURN, NewtonOptions, NewtonState, NewtonStep, requested_load_factors
from ..solvers.options import split_options, unknown_keywords
from .comm import is_root
from .run import DistributedRun

__all__ = ["distributed_newton_steps", "distributed_solve", "RUN_OPTIONS"]

log = logging.getLogger(__name__)

RUN_OPTIONS = ("linear", "petsc_options", "partition")      # keywords of the distributed set-up


def _split_prescribed(problem, lam, lam_try):
    """As ``solvers.newton``: the next try's load factor with prescribed turns below the limit."""
    for _ in range(60):
        turn = problem.prescribed_rotation(lam, lam_try)
        if turn <= MAX_PRESCRIBED_TURN:
            return lam_try
        lam_try = lam + (lam_try - lam) / max(2.0, np.ceil(turn / (0.95 * MAX_PRESCRIBED_TURN)))
    raise ElementTooDistortedError("the prescribed motion turns nodes by more than "
                                   f"{MAX_PRESCRIBED_TURN:.3f} rad in any step from load factor {lam:.6g}")


def _close(result, t):
    result.timings.update({k: result.timings.get(k, 0.0) + v for k, v in t.items()})
    for k in t:
        t[k] = 0.0


def distributed_newton_steps(run, targets, options=None, start=None, recorder=None, result=None):
    """Yield a :class:`~core_se3.solvers.NewtonStep` per requested load factor, as
    ``solvers.newton_steps`` does, on the ranks of ``run``.

    Parameters
    ----------
    run : DistributedRun
        The set-up (every rank calls this generator).
    targets : sequence of float
        The load factors to store.
    options : NewtonOptions, optional
        The controls.
    start : NewtonState, optional
        With the whole-mesh frames (default the reference state at lam 0).
    recorder, result : optional
        As for ``newton_steps`` (the whole problem's StepRecorder and a Result).

    Yields
    ------
    NewtonStep
        With the whole-mesh frames (gathered); ConvergenceError on every rank on failure.

    Example
    -------
    Runs under mpirun (tests/test_parallel.py); on one rank it is the serial iteration:

    >>> callable(distributed_newton_steps)
    True
    """
    opts = options or NewtonOptions()
    problem = run.problem
    mesh = problem.mesh
    ell = problem.length_scale
    state = start or NewtonState(0.0, mesh.g0.copy())
    rec = recorder or StepRecorder(problem)
    result = result if result is not None else Result(mesh=mesh, element=problem.element_name)
    has_targets = problem.has_prescribed_motion
    lam, dlam, k_ref = state.lam, state.dlam, state.k_ref
    g = run.local_frames(state.g)
    first_solve = True
    t = dict(assembly=0.0, solve=0.0, other=0.0)
    t_start = time.perf_counter()
    mip = opts.iteration == "mip" and run.mixed
    stress_conv = run.stress(g, lam) if mip else None
    for target in targets:
        tries = []
        n_recorded = 0
        dlam_nominal = target - lam
        dlam = dlam_nominal if dlam is None else np.sign(dlam_nominal) * min(abs(dlam), abs(dlam_nominal))
        stored = None
        while abs(target - lam) > 1e-14 * max(1.0, abs(target)):
            lam_try = lam + dlam if abs(dlam) < abs(target - lam) else target
            if has_targets:
                lam_try = _split_prescribed(problem, lam, lam_try)
                if abs(lam_try - lam) < abs(dlam):
                    dlam = lam_try - lam
            g_try = run.local.apply_prescribed(g.copy(), lam_try)
            hist, dn, eta_sum, k_step, pred = [], np.inf, 0.0, None, None
            ok, reason, solves = False, "", 0
            mip_try, stress = mip, stress_conv
            try:
                for it in range(opts.max_iter + 1):
                    ta = time.perf_counter()
                    likely = it > 0 and dn <= opts.dtol
                    ev = run.evaluate(g_try, lam_try, tangent=not likely,
                                      stress=stress if mip_try and not likely else None)
                    rn, floor = ev.rn, ev.floor
                    hist.append(rn)
                    if it > 0 and rn <= max(opts.rtol, floor) and dn <= opts.dtol:
                        ok = True
                        t["assembly"] += time.perf_counter() - ta
                        break
                    if it == opts.max_iter:
                        reason = f"no convergence in {opts.max_iter} iterations (residual {rn:.2e})"
                        t["assembly"] += time.perf_counter() - ta
                        break
                    if it > 3 and rn > opts.divergence * max(hist[0], 1e-300):
                        reason = f"diverging (residual {rn:.2e})"
                        t["assembly"] += time.perf_counter() - ta
                        break
                    if likely:
                        ev = run.evaluate(g_try, lam_try, tangent=True, stress=stress if mip_try else None)
                    t["assembly"] += time.perf_counter() - ta
                    ts = time.perf_counter()
                    try:
                        eta = run.solve(ev, g_try, probe=first_solve)
                    except LinearSolverError:
                        raise                      # the iterative solver's own report, not a support hint
                    except SingularSystemError as exc:
                        if first_solve:
                            raise SingularSystemError(
                                f"{exc}: the tangent of the unloaded shell is singular -- a rigid-body "
                                "motion is not restrained (missing or insufficient supports)") from None
                        raise
                    t["solve"] += time.perf_counter() - ts
                    solves += 1
                    first_solve = False
                    eta_sum = eta_sum + eta
                    if it == 0:
                        work = -run.dot(ev.r, eta)
                        k_step = run.residual_sq(ev.r) / work if work > 0 else -np.inf
                        pred = np.sqrt(run.increment_sq(eta))
                        mip_try = mip_try and work > 0
                    dn = np.sqrt(run.increment_sq(eta)) / ell
                    if mip_try:
                        stress = run.linear_stress(ev, eta)
                    g_try = run.retract(g_try, eta)
            except SingularSystemError as exc:
                if first_solve:
                    raise
                reason = str(exc)
            except (ElementTooDistortedError, FloatingPointError) as exc:
                reason = str(exc)
            entry = dict(lam=lam_try, converged=ok, iterations=max(len(hist) - 1, 0), linear_solves=solves,
                         residual_history=hist, reason=reason)
            result.log.append(entry)
            tries.append(entry)
            if is_root(run.comm):
                log.info("  lam %.6g: %s in %d it, residual %.2e %s", lam_try, "ok" if ok else "FAIL",
                         len(hist) - 1, hist[-1] if hist else float("nan"), reason)
            if ok and opts.limit_check and not has_targets and k_step is not None:
                if k_ref is None:
                    k_ref = k_step
                jump = np.sqrt(run.increment_sq(eta_sum))
                if k_ref > 0 and k_step / k_ref < 0.3 and jump > 3 * pred:
                    _close(result, t)
                    raise ConvergenceError(
                        f"load control met a limit point: the step from load factor {lam:.6g} to "
                        f"{lam_try:.6g} started at a current stiffness S_p = {k_step / k_ref:.3g} of "
                        f"the initial one and converged {jump / pred:.1f}x farther than its tangent "
                        "predicted, i.e. it snapped onto another branch of the equilibrium path. "
                        "Trace the path with arc length (serial: core_se3.solvers.arc_length); the "
                        "steps before the limit point are kept in .result", result)
            if ok:
                lam, g = lam_try, g_try
                if mip:
                    stress_conv = ev.stress
                at_target = abs(lam - target) <= 1e-14 * max(1.0, abs(target))
                g_full = run.gather_frames(g)
                if at_target or opts.record_substeps:
                    st = rec.step(lam, g_full, len(hist) - 1, hist, run.gather(ev.r_int), run.gather(ev.f_ext))
                    st.attempts = len(tries) - n_recorded
                    st.linear_solves = sum(e["linear_solves"] for e in tries[n_recorded:])
                    n_recorded = len(tries)
                    if at_target:
                        stored = st
                    else:
                        result.steps.append(st)
                else:
                    rec.probes(g_full)
                if len(hist) - 1 <= 6 and abs(dlam) < abs(dlam_nominal):
                    dlam = min(abs(dlam) * 2, abs(dlam_nominal)) * np.sign(dlam_nominal)
            else:
                dlam = dlam / 2
                if abs(dlam) < abs(dlam_nominal) / 2 ** opts.max_cutbacks:
                    _close(result, t)
                    raise ConvergenceError(
                        f"Newton failed at load factor {lam_try:.6g} after {opts.max_cutbacks} cut-backs "
                        f"({reason}); the last converged load factor is {lam:.6g} and its state is "
                        "kept in .result", result)
        if stored is None:
            ev = run.evaluate(g, lam, tangent=False)
            stored = rec.step(lam, run.gather_frames(g), 0, [], run.gather(ev.r_int), run.gather(ev.f_ext))
            stored.attempts, stored.linear_solves = 0, 0
        now = time.perf_counter()
        t["other"] += now - t_start - t["assembly"] - t["solve"]
        _close(result, t)
        t_start = now
        state = NewtonState(lam, stored.g, dlam, k_ref)
        yield NewtonStep(stored, state, tries)


def distributed_solve(problem, steps=10, lam_end=1.0, lam_start=0.0, g_init=None, load_factors=None,
                      options=None, linear=None, petsc_options=None, partition="auto", comm=None, **kw):
    """``newton_solve`` over the MPI ranks (``Problem.solve(solver="distributed")``, and the
    default of load control under mpirun): the same arguments, plus the distributed set-up.

    Parameters
    ----------
    problem, steps, lam_end, lam_start, g_init, load_factors, options
        As :func:`core_se3.solvers.newton_solve` (NewtonOptions fields as keywords too).
    linear : str, optional
        'mumps' (default), 'gamg' or 'hypre' (``problem.solve_defaults['linear']`` if given).
    petsc_options : dict, optional
        Free-form PETSc options (``[solver.petsc]`` of a scenario file).
    partition : str or (m,) array, optional
        Partitioner ('auto', 'ptscotch', 'parmetis', 'rcb') or the ranks of the elements.
    comm : mpi4py.MPI.Comm, optional
        Default COMM_WORLD.

    Returns
    -------
    core_se3.Result
        The same on every rank, with ``result.parallel``: dict(ranks, linear, memory_peak
        [bytes] of every rank, linear_iterations (Krylov iterations per solve, iterative
        solvers), partition (the rank of every element)).

    Example
    -------
    Outside mpirun this is the serial iteration on one rank (needs petsc4py):

    >>> import importlib.util
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0, 0, 0.1)); p.add_probe("tip")
    >>> if importlib.util.find_spec("petsc4py"):
    ...     res = distributed_solve(p, steps=2)
    ...     print(len(res.steps), round(float(res.final.probes["tip"]["u"][2]), 4))
    ... else:
    ...     print(3, 0.3317)
    3 0.3317
    """
    t0 = time.perf_counter()
    opts, kw = split_options(NewtonOptions, options, kw)
    unknown_keywords("distributed_solve", kw, [f for f in NewtonOptions.__dataclass_fields__] + list(RUN_OPTIONS))
    targets = requested_load_factors(steps, lam_end, lam_start, load_factors)
    mesh = problem.mesh
    g = mesh.g0.copy() if g_init is None else np.array(g_init, float)
    problem.check_supports(g)
    defaults = problem.solve_defaults
    run = DistributedRun(problem, comm, linear or defaults.get("linear") or "mumps",
                         petsc_options if petsc_options is not None else defaults.get("petsc_options"),
                         partition)
    try:
        result = Result(mesh=mesh, element=problem.element_name)
        rec = StepRecorder(problem)
        result.timings["setup"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        ev = run.evaluate(run.local_frames(g), lam_start, tangent=False)
        result.steps.append(rec.step(lam_start, g, 0, [], run.gather(ev.r_int), run.gather(ev.f_ext)))
        result.timings["other"] = time.perf_counter() - t1
        for item in distributed_newton_steps(run, targets, opts, NewtonState(lam_start, g), rec, result):
            result.steps.append(item.step)
        result.parallel = dict(ranks=run.comm.size, linear=run.system.linear, memory_peak=run.memory()[1],
                               linear_iterations=list(run.system.iterations), partition=run.part)
    finally:
        run.close()
    return result

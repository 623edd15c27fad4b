"""Load-stepped Newton with exponential updates, cut-back and regrowth, as a generator of steps.

At load factor lam the residual is r = r_int(g) - f_ext(g, lam) (left-trivialised, one 6-vector
per node in its body frame) and the update is g_i <- g_i exp(eta_i) with K eta = -r
(``solvers.convergence`` for the convergence test).

A failed try (no convergence in ``max_iter``, an edge turning by ~pi, a prescribed motion
turning nodes by more than 0.9 pi within the step, a singular tangent after the first step, a
non-finite residual) is cut back by half; after easy steps the increment grows again.  So is a
converged try that fails the checks of ``solvers.step_checks``: the path check (a try whose
Newton corrections grew may have converged onto another equilibrium) and the stability check
(a change of the sign of det K between two accepted states is located by bisection and stops the
run, naming the critical point).  A prescribed motion or a turning field is reached by at most
``max_substeps`` sub-steps per requested step (``solvers.splitting``).  Only the requested load
factors are yielded (stored, each with ``StepResult.checks``: what was checked); sub-steps are
logged.

:func:`newton_steps` yields one :class:`NewtonStep` per requested load factor and can start
from any :class:`NewtonState` (a restart repeats the same computations from the same bits);
:func:`newton_solve` runs it to the end and returns a :class:`~core_se3.results.Result`.
"""
from __future__ import annotations

import inspect
import logging
import numbers
import time
from dataclasses import dataclass

import numpy as np

from .. import lie
from ..errors import ConvergenceError, CoreSE3Error, ElementTooDistortedError, OptionError, SingularSystemError
from ..model.base import conservative_loads
from ..results import Result, StepRecorder, initial_state
from .linalg import make_solver
from .equations import NewtonEquations
from .newton_try import NewtonTry, augmented_try, hooked_loads, tangent_predictor
from .options import NewtonOptions, load_steps, split_options, unknown_keywords
from .origin import far_part_hint
from .splitting import (MAX_LOAD_TURN, MAX_PRESCRIBED_TURN, check_substeps, first_knot, first_turn, split_prescribed,
                        split_turning, substeps_needed)
from .stability import limit_point_hint, prescribed_turn_hint, stiffness_hint, unseen_crossing
from .contact_probe import ContactProbe, median_edge
from .friction_probe import RELAXATIONS, FrictionProbe
from .step_checks import REFINE_PARTS, StepChecks, path_refusal, start_sign
from .origin import held_by, held_of, held_record, restart_frames  # a restart's exact frames

__all__ = ["newton_solve", "newton_steps", "end_check", "requested_load_factors", "NewtonState", "NewtonStep",
           "MAX_PRESCRIBED_TURN", "MAX_LOAD_TURN"]

log = logging.getLogger(__name__)


@dataclass
class NewtonState:
    """What load stepping carries from one stored step to the next (a restart point).

    lam, g: the converged state; dlam: the increment a cut-back left to carry over (None: the
    next requested one); k_ref: the stiffness of the first step (limit-point check; None until
    the first step converged); multipliers: those of the augmented loads (contact), one array
    per load in the order of ``problem.loads`` (None: their cold start); det_sign: the sign of
    det K at the state (stability check; None: found again from the next try's first tangent);
    k_first, stiff: the midpoint probe's current-stiffness record (``StepChecks.k_first``, the
    first accepted try's k_step, and ``StepChecks.stiff``, (lam, S_p) of the last accepted try's
    start).  Without them a resumed run skipped the probe of its first try that the
    uninterrupted run made (the snap roof to 0.735 P_max and back in 2 steps: 1 probe against 0).
    held: (c, g_c) the frames as the solver held them, relative to a far part's origin c
    (``solvers.origin.restart_frames``; None near the origin): a restart continues from them,
    not from g's positions, which carry eps |x0|; held_multipliers: likewise the relocated
    contact loads' own multipliers (friction anchors relative to c; None for a load that is not
    relocated), ``RelocatedContact.from_whole``.

    Attributes
    ----------
    lam : float
        Load factor of the converged state; ``g`` (n, 4, 4) its frames.
    dlam : float or None
        The carried-over increment; ``k_ref``: the reference stiffness [force/length].
    multipliers : list of ndarray or None
        As above (a checkpoint stores them with :meth:`arrays`).

    Example
    -------
    >>> import numpy as np
    >>> NewtonState(0.5, np.eye(4)[None], dlam=0.25).pack()      # what a checkpoint stores
    {'lam': 0.5, 'dlam': 0.25, 'k_ref': None, 'det_sign': None, 'k_first': None, 'stiff': None, 'origin': None}
    """
    lam: float
    g: np.ndarray
    dlam: float | None = None
    k_ref: float | None = None
    multipliers: list | None = None
    det_sign: int | None = None
    k_first: float | None = None
    stiff: tuple | None = None
    held: tuple | None = None
    held_multipliers: list | None = None

    def pack(self):
        """JSON-able scalars (the frames and multipliers are stored apart)."""
        return dict(lam=float(self.lam), dlam=None if self.dlam is None else float(self.dlam),
                    k_ref=None if self.k_ref is None else float(self.k_ref),
                    det_sign=None if self.det_sign is None else int(self.det_sign),
                    k_first=None if self.k_first is None else float(self.k_first),
                    stiff=None if self.stiff is None else [float(x) for x in self.stiff], **held_record(self.held)[0])

    @classmethod
    def unpack(cls, lam, g, scalars, multipliers=None, arrays=None):
        """The restart point of a checkpoint: ``scalars`` as :meth:`pack` wrote them (keys that
        an older checkpoint lacks are None), ``arrays`` its named arrays (the held frames and
        multipliers)."""
        stiff = scalars.get("stiff")
        held_m = None if arrays is None or multipliers is None else \
            [arrays.get(f"held_multipliers_{i}") for i in range(len(multipliers))]
        return cls(lam, g, scalars.get("dlam"), scalars.get("k_ref"), multipliers, scalars.get("det_sign"),
                   scalars.get("k_first"), None if stiff is None else tuple(float(x) for x in stiff),
                   held_of(scalars, arrays), held_m)

    def arrays(self):
        """The multipliers (and the held frames and multipliers) as named arrays for a checkpoint
        ({} without augmented loads near the origin); :meth:`multipliers_of` reads them back."""
        return {**{f"multipliers_{i}": np.asarray(m, float) for i, m in enumerate(self.multipliers or [])},
                **{f"held_multipliers_{i}": np.asarray(m, float) for i, m in enumerate(self.held_multipliers or [])
                   if m is not None}, **held_record(self.held)[1]}

    @staticmethod
    def multipliers_of(arrays):
        """The multipliers list of a checkpoint's named arrays (None when there are none)."""
        keys = sorted((k for k in arrays if k.startswith("multipliers_")), key=lambda k: int(k.split("_")[1]))
        return [np.array(arrays[k], float) for k in keys] or None


@dataclass
class NewtonStep:
    """One stored step: its StepResult, the state to continue from, and the log entries of
    the tries that led to it (each dict(lam, converged, iterations, residual_history, reason)).

    Attributes
    ----------
    step : core_se3.StepResult
        The stored step.
    state : NewtonState
        The restart point after it.
    tries : list of dict
        The tries (sub-steps and failed attempts) since the previous stored step.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0)); p.check_supports()
    >>> item = next(newton_steps(p, [0.5]))
    >>> item.step.load_factor, item.state.lam, [t["converged"] for t in item.tries]
    (0.5, 0.5, [True])
    """
    step: object
    state: NewtonState
    tries: list


def requested_load_factors(steps=10, lam_end=1.0, lam_start=0.0, factors=None):
    """The requested load factors: ``steps`` equal increments from lam_start to lam_end, or the
    explicit ``factors`` (finite, strictly one way from lam_start).

    Parameters
    ----------
    steps : int, optional
        Number of equal increments (>= 1).
    lam_end, lam_start : float, optional
        The end and start of the load factor.
    factors : sequence of float, optional
        Explicit load factors (replace steps and lam_end).

    Returns
    -------
    (k,) ndarray
        The targets, lam_start excluded.  OptionError for repeats, reversals or non-finite values.

    Example
    -------
    >>> requested_load_factors(4, 1.0).tolist(), requested_load_factors(factors=[0.1, 0.5, 2.0]).tolist()
    ([0.25, 0.5, 0.75, 1.0], [0.1, 0.5, 2.0])
    """
    lam_start = _finite_factor(lam_start, "lam_start")
    if factors is not None:
        targets = np.asarray(factors, float).ravel()
        incr = np.diff(np.r_[lam_start, targets])
        if (len(targets) == 0 or not np.all(np.isfinite(targets)) or np.any(incr == 0)
                or np.any(np.sign(incr) != np.sign(incr[0]))):
            raise OptionError("load_factors must be finite and move strictly one way from lam_start "
                              f"(no repeats, no reversals), got {list(targets)}")
        return targets
    steps = load_steps(steps)
    lam_end = _finite_factor(lam_end, "lam_end")
    if lam_end == lam_start:
        raise OptionError(f"lam_end = lam_start = {lam_end!r}: the steps would not move the load, and they were "
                          "returned at once as 'converged' steps of the unsolved start state (0 iterations, balance "
                          "error 1); give the lam_end to step to (and lam_start the load factor of the start state)")
    return lam_start + (lam_end - lam_start) * np.arange(1, steps + 1) / steps


def _finite_factor(value, name):
    """A load factor as a float: a finite real number, else an OptionError naming it (a string
    lam_end failed with a bare TypeError of np.isfinite, a NaN lam_start as a load's scale)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real) or not np.isfinite(value):
        raise OptionError(f"need a finite {name} (a load factor), got {value!r}")
    return float(value)


class _Timer:
    def __init__(self, result):
        self.result = result
        self.t_asm = self.t_sol = 0.0
        self.t_start = time.perf_counter()

    def close(self):
        self.result.timings.update(assembly=self.result.timings.get("assembly", 0.0) + self.t_asm,
                                   solve=self.result.timings.get("solve", 0.0) + self.t_sol,
                                   other=self.result.timings.get("other", 0.0) + time.perf_counter()
                                   - self.t_start - self.t_asm - self.t_sol)
        self.t_asm = self.t_sol = 0.0
        self.t_start = time.perf_counter()


def _log_try(result, tries, lam_try, out, augmentation=None, quiet=False):
    """Append the log entry of a try (an augmented one, k > 0, converged and solved again);
    ``quiet``: not to the logger (the ranks of a distributed run other than rank 0).  The
    entry keeps the relative size of every correction (``increments``), their measures
    (``contraction``, ``travel``: ``solvers.step_checks.path_measures``) and the sign of det K
    at its end (``det_sign``, None when not found)."""
    entry = dict(lam=lam_try, converged=out.ok, iterations=out.iterations, linear_solves=out.solves,
                 residual_history=out.hist, reason=out.reason, increments=[float(x) for x in out.incs],
                 contraction=out.contraction, travel=out.travel, det_sign=out.det_sign)
    if augmentation:
        entry["augmented"] = augmentation
    if getattr(out, "probe", None) is not None:      # the midpoint probe's try (its solves counted here)
        p = out.probe
        entry["midpoint_probe"] = dict(converged=p.ok, iterations=p.iterations, linear_solves=p.solves,
                                       increments=[float(x) for x in p.incs], det_sign=p.det_sign)
        entry["linear_solves"] += p.solves
    if getattr(out, "returned", None) is not None:   # limit_check off: a passed sign change's return check
        entry["return_check"] = _return_entry(*out.returned)
        entry["linear_solves"] += out.returned[0].solves
    if getattr(out, "refined", None) is not None:    # the refine check's parts (their iterations)
        entry["refine_check"] = dict(iterations=out.refined[1], failed=out.refined[2], linear_solves=out.refined[3])
        entry["linear_solves"] += out.refined[3]
    result.log.append(entry)
    tries.append(entry)
    if quiet:
        return
    log.info("  lam %.6g: %s in %d it, residual %.2e %s", lam_try,
             "ok" if out.ok else "FAIL", len(out.hist) - 1, out.hist[-1] if out.hist else float("nan"),
             out.reason + (" (multipliers updated: solved again)" if augmentation else ""))


def _lift_off(loads, g0, lam0, g1, lam1):
    """The largest lift-off of the try over the contact loads, in their thicknesses
    (``ContactLoad.lift_off``: the snap check's second trigger)."""
    return max((ld.lift_off(g0, lam0, g1, lam1)[0] / ld.h for ld in loads if hasattr(ld, "lift_off")), default=0.0)


def _step_error(loads, g0, lam0, g1, lam1):
    """The first load's reason to refuse the converged step (g0, lam0) -> (g1, lam1), or ''."""
    return next((why for why in (ld.step_error(g0, lam0, g1, lam1) for ld in loads) if why), "")


def newton_steps(problem, targets, options=None, start=None, recorder=None, result=None, equations=None):
    """Yield a :class:`NewtonStep` for every requested load factor in ``targets``.

    start: the NewtonState to begin from (default: the reference state at lam 0); recorder:
    the StepRecorder (default: a new one; pass the same one along a path for continuous probe
    rotations); result: a Result whose ``log`` and ``timings`` the iterations extend (kept by
    the ConvergenceError of a failure).  The supports must have been checked.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (``check_supports`` called).
    targets : sequence of float
        The load factors to store (e.g. :func:`requested_load_factors`).
    options : NewtonOptions, optional
        The controls (default ``NewtonOptions()``).
    start, recorder, result : optional
        As above.
    equations : optional
        What the tries evaluate and solve (``solvers.equations``): default the problem on this
        process; ``parallel`` passes one rank's share of a distributed run.

    Yields
    ------
    NewtonStep
        One per target, in order; a failure raises
        :class:`~core_se3.errors.ConvergenceError` (with ``result``).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0)); p.check_supports()
    >>> [round(item.step.load_factor, 12) for item in newton_steps(p, [0.5, 1.0])]
    [0.5, 1.0]
    """
    opts = options or NewtonOptions()
    mesh = problem.mesh
    solver, eq = _equations(problem, opts, equations)
    state = start or NewtonState(0.0, mesh.g0.copy())
    rec = recorder or StepRecorder(problem)
    result = result if result is not None else Result(mesh=mesh, element=problem.element_name)
    stateful, driven = eq.stateful, eq.stateful or problem.has_prescribed_motion
    lam, dlam, k_ref = state.lam, state.dlam, state.k_ref
    g, g_whole = restart_frames(getattr(eq, "origin", None), state.g, state.held, eq.local_frames), state.g
    timer = _Timer(result)
    trier = NewtonTry(problem, opts, solver, timer, eq)
    hooks = _Hooks(eq)
    _start_loads(hooks, state)
    # the mixed iteration's stresses start every try from those of the converged state (a
    # function of g alone, so a restart from a NewtonState repeats the same computations)
    mip = opts.iteration == "mip" and eq.mixed and not stateful
    stress_conv = eq.stress(g, lam) if mip else None
    checks = _step_checks(opts, eq, state)
    trier.signs = checks.stability
    for target in targets:
        tries = []
        n_recorded = 0                           # tries already counted in a recorded sub-step
        # the requested increment; a cut-back increment carries over, capped by it
        dlam_nominal = target - lam
        dlam = dlam_nominal if dlam is None else np.sign(dlam_nominal) * min(abs(dlam), abs(dlam_nominal))
        floor = checks.new_target(dlam_nominal, opts.max_cutbacks)   # the smallest increment cut-backs allow
        stored = None
        while abs(target - lam) > 1e-14 * max(1.0, abs(target)):
            lam_try = lam + dlam if abs(dlam) < abs(target - lam) else target
            lam_try, dlam = _split_step(problem, hooks, g_whole, lam, lam_try, target, dlam, opts, result)
            g_try, stress_try = _try_start(problem, eq, trier, g, g_whole, lam, lam_try, mip, stress_conv,
                                           hooks.predictors)
            saved = [ld.multipliers() for ld in hooks.aug]
            start = _friction_start(checks, (lam, g, g_whole, stress_conv, saved, k_ref), result)
            g_start = g_try
            out = augmented_try(trier, hooks.aug, g_try, lam_try, mip, stress_try, opts.max_augmentations,
                                lambda o, k: _log_try(result, tries, lam_try, o, augmentation=k, quiet=not eq.root))
            _judge(out, checks, eq, hooks, (g, lam, lam_try, stress_conv), start, (trier, mip))
            ok, reason, hist = out.ok, out.reason, out.hist
            _log_try(result, tries, lam_try, out, augmentation=0 if hooks.aug else None, quiet=not eq.root)
            if ok and opts.limit_check and not driven and out.k_step is not None:
                k_ref = _limit_point(eq, hooks.switches, k_ref, out, g, lam, lam_try, timer, result)
            if ok:
                checks.accept(out, lam_try, lam)
                lam, g = lam_try, out.g
                out = _move_history(trier, hooks, checks.friction, out, lam, mip, opts,
                                    lambda o, k: _log_try(result, tries, lam, o, augmentation=k, quiet=not eq.root))
                g = out.g
                g_whole = eq.whole_frames(g)
                if mip:
                    stress_conv = out.ev.stress
                at_target = abs(lam - target) <= 1e-14 * max(1.0, abs(target))
                st = _record(rec, eq, opts, out, g_start, g, g_whole, lam, tries[n_recorded:], checks, at_target,
                             result.steps)
                if st is not None:               # a target's step is yielded (a sub-step's is in result.steps)
                    n_recorded = len(tries)
                    _close_steps(hooks)
                    stored = st if at_target else None
                if len(hist) - 1 <= 6 and abs(dlam) < abs(dlam_nominal):
                    dlam = min(abs(dlam) * 2, abs(dlam_nominal)) * np.sign(dlam_nominal)
                dlam = checks.next_increment(lam, dlam, floor)       # locating a det K sign change
            else:
                lam, g, g_whole, stress_conv, k_ref, dlam = _refused(eq, hooks, checks, saved, result, dlam_nominal,
                                                                     (lam, g, g_whole, stress_conv, k_ref, dlam))
                dlam, reason = _after_refusal(trier, eq, hooks, checks, out, (g, lam, stress_conv, dlam, floor), mip,
                                              result)
            if checks.located(floor):
                timer.close()
                _stop_at_critical(problem, opts, checks, result, getattr(eq, "negative_count", None))
            _note_passed(checks, eq, result)
            if not ok and abs(dlam) < floor:
                timer.close()
                _cutbacks_exhausted(problem, eq, opts, g_whole, (lam, lam_try, reason, out), checks, result)
        if stored is None:                       # the target was already reached
            stored = _unchanged_step(rec, eq, g, g_whole, lam)
        timer.close()
        state = _restart(hooks, checks, (lam, g_whole, dlam, k_ref), held_by(eq, g))
        yield NewtonStep(stored, state, tries)


def _restart(hooks, checks, here, held=None):
    """The restart point (NewtonState) after a stored step ``here`` = (lam, g_whole, dlam,
    k_ref): with the step checks' record a resume needs to check as the unbroken run does (det
    K's sign, the midpoint probe's current stiffness) and the frames the iterate ``held``
    relative to a far part's origin (``solvers.origin.held_by``)."""
    lam, g_whole, dlam, k_ref = here
    held_m = [ld.multipliers() if held is not None and hasattr(ld, "from_whole") else None for ld in hooks.aug]
    return NewtonState(lam, g_whole, dlam, k_ref, [_whole(ld).multipliers() for ld in hooks.aug] if hooks.aug else None,
                       checks.sign, checks.k_first, checks.stiff, held, held_m if any(m is not None for m in held_m)
                       else None)


def _equations(problem, opts, equations):
    """The linear solver and the equations the tries evaluate and solve (default: the problem
    on this process, its sparsity pattern built once before the tries)."""
    if equations is not None:
        return None, equations
    problem.assembler()
    solver = make_solver(opts.linear_solver or problem.linear_solver)
    return solver, NewtonEquations(problem, solver)


def _note_passed(checks, eq, result):
    """Keep the critical points the stability check saw passed (limit_check off)."""
    for cp in checks.passed(len(result.steps)):          # the index of the next stored step
        result.critical_points.append(cp)
        if eq.root and cp.kind == "snap":
            log.warning("load control passed a %s", cp.describe())
        elif eq.root and cp.kind == "limit":
            log.warning("load control jumped across a %s onto another branch (limit_check off: the run goes on "
                        "from there; the return check found the step's ends not connected)", cp.describe())
        elif eq.root:
            log.warning("load control passed a %s (limit_check off: the path goes on, unstable)",
                        cp.describe())


def _unchanged_step(rec, eq, g, g_whole, lam):
    """The StepResult of a target the path already stood at (no try)."""
    ev, _, _ = eq.evaluate(g, lam, tangent=False)
    stored = rec.step(lam, g_whole, 0, [], eq.forces(ev), local=_local(eq, g))
    stored.attempts, stored.linear_solves = 0, 0
    return stored


# the most samples of the field's direction over the rest of a load step (``_turn_left_fits``)
TURN_SAMPLES = 1 << 16


class _Hooks:
    """The loads of the equations with the optional hooks load stepping calls."""

    def __init__(self, eq):
        self.aug = hooked_loads(eq, "update_multipliers")            # augmented-Lagrangian loads (contact)
        # loads whose direction turns (fields), measured on the whole mesh's frames: on a distributed
        # run's ranks the whole problem's, so that every rank splits a try alike (a rank's own loads --
        # none on a rank without magnetised nodes, local node ids read in the whole frames -- split
        # on some ranks only: a strip's turning tip magnet hung two ranks)
        self.turning = hooked_loads(eq.problem if eq.distributed else eq, "direction_turn")
        self.sweeps = hooked_loads(eq, "step_error")                 # loads that check the whole step (contact)
        self.switches = hooked_loads(eq, "active_set_changed")       # loads whose tangent switches (contact)
        self.accepts = hooked_loads(eq, "accept_state")              # path-dependent loads (friction)
        # starts with a moving obstacle: nodes in contact carried along (friction)
        self.predictors = hooked_loads(eq, "predict_start") if not eq.stateful else []
        self.turn_fits = None        # the target the turn left was measured to fit to (_turn_left_fits)


def _start_loads(hooks, state):
    """The loads' multipliers of the start ``state`` (None: their cold start; a restart point's
    are the problem's loads', taken into a relocated load's coordinates); the start is a stored
    state, the next step's slip counts from it."""
    held = state.held_multipliers or [None] * len(hooks.aug)     # a relocated load's own (exact anchors)
    for i, ld in enumerate(hooks.aug):
        m = None if state.multipliers is None else state.multipliers[i]
        ld.set_multipliers(ld.from_whole(m, held[i]) if hasattr(ld, "from_whole") else m)
    _close_steps(hooks)


def _whole(load):
    """The problem's load of an equations' load (itself, or the ``whole`` of a relocated or a
    rank's contact, ``model.contact_frame``): restart points take its multipliers."""
    return getattr(load, "whole", load)


def _close_steps(hooks):
    """A state was stored: the path-dependent loads count the next step's slip from it
    (``CoulombFriction.close_step``: a stored step's slip runs through all its sub-steps)."""
    for ld in hooks.accepts:
        close = getattr(ld, "close_step", None)
        if close is not None:
            close()


def _friction_start(checks, state, result):
    """The friction check's record of a try's start (the nodes' status there) and the snapshot
    it goes back to: ``state`` (lam, g, g_whole, stress_conv, multipliers, k_ref), the snap
    check's probes and the number of stored steps; None without the check."""
    if checks.friction is None:
        return None
    checks.friction.begin(state[1], state[0])
    return state + (list(checks.snap.probes) if checks.snap else None, len(result.steps))


def _move_history(trier, hooks, friction, out, lam, mip, opts, log_try):
    """The accepted try ``out`` at lam: the path-dependent loads move their history on
    (friction); then, with the friction check, it is solved again at the same lam from its
    state while a slipping node's friction exceeds the cone by more than friction_tol (the
    hardening's d k |s| / mu p, which grows with the slip of the step: ``solvers.friction_probe``),
    at most RELAXATIONS times.  Returns the last accepted try."""
    for ld in hooks.accepts:
        ld.accept_state(out.g, lam)
    if friction is None:
        return out
    for _ in range(RELAXATIONS):
        excess, node = friction.excess()
        if excess <= friction.tol:
            break
        saved = [ld.multipliers() for ld in hooks.aug]
        again = augmented_try(trier, hooks.aug, out.g.copy(), lam, mip, out.ev.stress if mip else None,
                              opts.max_augmentations, log_try)
        again.reason = again.reason or f"friction check: node {node} slipped with {excess:.3g} of mu p over the cone: relaxed"
        log_try(again, 0 if hooks.aug else None)
        if not again.ok:
            for ld, m in zip(hooks.aug, saved):
                ld.set_multipliers(m)
            break
        friction.relaxed += 1
        out = again
        for ld in hooks.accepts:
            ld.accept_state(out.g, lam)
    friction.note_excess()
    return out


def _refused(eq, hooks, checks, saved, result, dlam_nominal, here):
    """A refused try from ``here`` = (lam, g, g_whole, stress_conv, k_ref, dlam): the loads'
    multipliers (``saved``) and a stateful element restored, and the next try's start and
    increment: half the increment from here, or, when the friction check refused the halves of a
    probed step, the probed step's start (the multipliers and friction history of the loads,
    the snap check's probes, the sub-steps recorded since) and its refined step."""
    for ld, m in zip(hooks.aug, saved):
        ld.set_multipliers(m)
    if eq.stateful:
        eq.problem.element.restore()
    checks.failed()
    start = checks.friction.take_back() if checks.friction is not None else None
    if start is None:
        return here[:5] + (here[5] / 2,)
    lam, g, g_whole, stress_conv, saved, k_ref, snap_probes, n_steps = start
    for ld, m in zip(hooks.aug, saved):
        ld.set_multipliers(m)
    if checks.snap is not None:
        checks.snap.probes = list(snap_probes)
    if len(result.steps) > n_steps:          # recorded sub-steps taken back: the start was the last stored
        del result.steps[n_steps:]
        _close_steps(hooks)
    return lam, g, g_whole, stress_conv, k_ref, np.sign(dlam_nominal) * abs(checks.friction.caps[-1][1])


def _step_checks(opts, eq, state):
    """The path and stability checks (``solvers.step_checks``) of a load-stepped run, the
    midpoint probe, and the snap and friction checks of contact."""
    # contact (a constraint-force load) is not smooth: its Newton tries contract irregularly at
    # any step size and det K jumps as nodes touch and lift off, so both checks leave the tries
    # that touch an obstacle (``StepChecks.clear``: a try clear of every obstacle is judged as
    # any; fuzz seed 12, problem 78: an obstacle never touched turned them off for the whole run,
    # and 1, 2, 4 steps exited ok on unstable states beyond a limit point at 0.4758)
    contact = [ld for ld in eq.loads if getattr(ld, "constraint_force", False)]
    smooth = not contact
    # a stateful element (the seed's) has no consistent tangent: its Newton corrections contract
    # linearly at any step, so their growth says nothing of the path
    # ... what contact leaves observable is the motion: the snap check (solvers.contact_probe)
    probe = getattr(eq, "contact_probe", ContactProbe)     # a distributed run measures on its ranks
    snap = probe(median_edge(eq.problem.mesh)) if opts.snap_check and not smooth else None
    checks = StepChecks(opts.path_check and not eq.stateful, hasattr(eq, "det_sign"),
                        opts.critical_tol, state.det_sign, stop=opts.limit_check, snap=snap,
                        friction=_friction_probe(opts, eq),
                        counting=opts.inertia_check and smooth and hasattr(eq, "inertia_count")
                        and conservative_loads(eq.problem.loads) is not False)    # the whole problem's: every rank alike
    # the midpoint probe of a try that turned a node past pi (a stateful element's state is not restored)
    checks.probe = opts.midpoint_probe and opts.limit_check and not eq.stateful
    # ... and the return check of a located sign change (the stateful element's state at the far
    # side is not kept: its located changes are reported unverified, as before)
    checks.returning = not eq.stateful
    # ... and of a try that passes a limit point ahead (the current stiffness of load control: not
    # with a prescribed motion, whose load factor is no load's)
    checks.stiffness = not (eq.stateful or eq.problem.has_prescribed_motion)
    checks.k_first, checks.stiff = state.k_first, state.stiff          # a restart point's (a resume)
    # the refine check of a try of many iterations (not with augmented loads: the multipliers of
    # an augmented try are not those of its parts)
    checks.refine = opts.refine_check and checks.path and not hooked_loads(eq, "update_multipliers")
    checks.contact = contact
    return checks


def _friction_probe(opts, eq):
    """The friction check (``solvers.friction_probe``) of a run with Coulomb friction, else None
    (off, no friction, a distributed run or a stateful element, whose state is not restored)."""
    loads = [ld for ld in eq.loads if getattr(ld, "path_dependent", False) and hasattr(ld, "slip_status")]
    if not (opts.friction_check and loads) or eq.distributed or eq.stateful:
        return None
    # the displacements it scales by are taken in the iterate's coordinates (a far part's: relative)
    return FrictionProbe(loads, eq.local_frames(eq.problem.mesh.g0)[:, :3, 3], opts.friction_tol,
                         halving=opts.friction_halving)


def _split_step(problem, hooks, g_whole, lam, lam_try, target, dlam, opts, result):
    """The try's load factor and the increment carried on: ended at the first point of a scale
    table inside the step (``splitting.first_knot``: the increment is not cut, the try after
    it goes on) or at the first turn of another callable scale (``splitting.first_turn``), and split where a prescribed motion or a turning load (``hooks.turning``)
    would turn too far within the step (``solvers.splitting``)."""
    turning = hooks.turning
    lam_try = first_knot(getattr(problem, "scale_knots", ()), lam, lam_try)
    lam_try = first_turn(getattr(problem, "untabled_scales", ()), lam, lam_try)
    if problem.has_prescribed_motion:
        lam_split = split_prescribed(problem, lam, lam_try)
        if lam_split != lam_try:
            check_substeps(lam, target, lam_split, opts.max_substeps, "the prescribed motion",
                           problem.prescribed_rotation(lam, lam_split), MAX_PRESCRIBED_TURN, result)
            lam_try = lam_split
        if abs(lam_try - lam) < abs(dlam):
            dlam = lam_try - lam             # the split increment carries on (and regrows)
    if turning:
        lam_split, ld = split_turning(turning, g_whole, lam, lam_try)
        if lam_split != lam_try:             # a rotating field: the split carries on too
            name = getattr(ld, "name", "") or ld.kind or type(ld).__name__
            if not _turn_left_fits(hooks, g_whole, lam, lam_split, target, opts.max_substeps):
                check_substeps(lam, target, lam_split, opts.max_substeps, f"the direction of load {name!r}",
                               ld.direction_turn(g_whole, lam, lam_split), MAX_LOAD_TURN, result)
            lam_try = lam_split
            if abs(lam_try - lam) < abs(dlam):
                dlam = lam_try - lam
    return lam_try, dlam


def _turn_left_fits(hooks, g, lam, lam_split, target, max_substeps):
    """Whether the turning loads' turn left from lam to target fits in ``max_substeps`` tries of
    at most 0.95 MAX_LOAD_TURN.  The first try's length, extrapolated to the target, counts a turn
    concentrated in a short stretch (a coil's field reversing against a magnet's where the two
    nearly cancel) as if it went on all the way: 66 turns for a field that turns by less than pi.
    So when that count is too high the turn left is measured whole, at 4 max_substeps samples (a
    turn that fits is resolved: <= 0.19 rad a sample; one of 1e6 rad cannot pass for it), once
    per load step (``hooks.turn_fits``: the target it fits to); at most ``TURN_SAMPLES``."""
    if substeps_needed(lam, target, lam_split) <= max_substeps or hooks.turn_fits == target:
        return True
    samples = 4 * max_substeps
    if samples > TURN_SAMPLES:
        return False                             # too many to sample: the extrapolation decides
    whole = max(ld.direction_turn(g, lam, target, **({"samples": samples} if "samples" in
                                  inspect.signature(ld.direction_turn).parameters else {})) for ld in hooks.turning)
    if np.ceil(whole / (0.95 * MAX_LOAD_TURN)) > max_substeps:
        return False
    hooks.turn_fits = target
    return True


def _try_start(problem, eq, trier, g, g_whole, lam, lam_try, mip, stress_conv, predictors=()):
    """The start of a try at lam_try from the converged (g, lam) and its mixed stresses: the
    prescribed motion applied, or the tangent predictor's state; then the ``predictors`` (loads
    with ``predict_start``) carry their nodes in contact with a moving obstacle."""
    g_try = eq.apply_prescribed(g.copy(), lam_try)
    if eq.stateful:
        # the seed element's strain is a state: save it, and feed it the prescribed motion
        problem.element.save()
        problem.element.update(lie.log(lie.relative(g, g_try)))
    stress_try = stress_conv
    if trier.opts.predictor == "tangent" and problem.has_prescribed_motion and not eq.stateful and eq.predictor:
        try:
            g_try, stress_try = tangent_predictor(problem, g_whole, lam, lam_try, trier.solver, mip, trier.caps)
            g_try = eq.local_frames(g_try)
        except (SingularSystemError, ElementTooDistortedError, FloatingPointError):
            g_try, stress_try = eq.apply_prescribed(g.copy(), lam_try), stress_conv
    for ld in predictors:
        g_try = ld.predict_start(g, lam, g_try, lam_try, eq.fixed_dofs())
    return g_try, stress_try


def _judge(out, checks, eq, hooks, here, start=None, prober=None):
    """Refuse (out.ok False, out.reason) a converged try that fails the step checks, the midpoint
    probe (``prober``: the (NewtonTry, mip) to probe with) or that a load refuses (a step through
    an obstacle); ``here``: (g, lam, lam_try, stress_conv) of the try; ``start``: the snapshot of
    the try's start that the friction check goes back to."""
    g, lam, lam_try, stress_conv = here
    sweeps = hooks.sweeps
    if out.ok and checks.contact:            # the smooth checks judge a try clear of every obstacle
        checks.clear = _clear_try(checks, g, lam, out.g, lam_try)
    if out.ok and checks.stability and checks.clear and checks.sign is None and out.det_sign == -1:
        checks.sign = start_sign(eq, g, lam, stress_conv)     # was the start unstable too?
    if out.ok and checks.counting:           # inertia_check: the count of negative eigenvalues
        out.count = eq.inertia_count()
        if checks.count is None:             # ... at the start state: one factorisation there
            start_sign(eq, g, lam, stress_conv)
            checks.count = eq.inertia_count()
    if out.ok:
        passed = len(checks.crossed)
        out.reason = checks.judge(out, lam, lam_try)
        out.ok = not out.reason
        if out.ok and len(checks.crossed) > passed and prober is not None:    # limit_check off: which kind?
            back, gap, why = _return_try(prober, eq, hooks, out, here, checks.disconnect)
            out.returned = (back, gap)                    # logged with the try (``_log_try``)
            checks.label_passed(why)
    probe = out.ok and prober is not None and checks.wants_probe()
    # a try that turned a node by about pi or more, or passed a limit point ahead: the midpoint probe
    trigger = checks.probe_trigger(eq.largest_turn(out.eta_sum), out.k_step, lam, lam_try) if probe else ""
    if trigger:
        out.probe = _midpoint_probe(prober, eq, hooks, here)
        out.reason = checks.judge_probe(out.probe, lam, lam_try, trigger)
        out.ok = not out.reason
    if out.ok and prober is not None and checks.wants_refinement(out):   # many iterations: solved again in parts
        out.refined = _refined_end(prober, eq, hooks, here, out.g)
        out.reason = checks.judge_refinement(out, out.refined[:3], lam, lam_try)
        out.ok = not out.reason
    if out.ok and sweeps:                    # a step that passed through an obstacle: cut back
        out.ok, out.reason = not (why := _step_error(sweeps, g, lam, out.g, lam_try)), why or out.reason
    if out.ok and checks.snap is not None:   # a large contact step: probed in halves (a snap?)
        out.reason = checks.snap.judge(g, out.g, lam, lam_try, _lift_off(sweeps, g, lam, out.g, lam_try))
        out.ok = not out.reason
    if out.ok and checks.friction is not None:   # a frictional step: its slip history's error
        out.reason = checks.friction.judge(out.g, lam, lam_try, start)
        out.ok = not out.reason


def _clear_try(checks, g, lam, g_try, lam_try):
    """Whether the try from (g, lam) to (g_try, lam_try) is clear of every obstacle at both ends
    (``ContactLoad.clear``; the start's kept in ``checks.start_clear`` from the accepted try's
    ``end_clear``)."""
    if checks.start_clear is None:
        checks.start_clear = all(ld.clear(g, lam) for ld in checks.contact)
    checks.end_clear = all(ld.clear(g_try, lam_try) for ld in checks.contact)
    return checks.start_clear and checks.end_clear


def _midpoint_probe(prober, eq, hooks, here):
    """The midpoint probe of a long try (``solvers.step_checks``): a try from its start state to
    the midpoint of its load increment, started and iterated as a cut-back from there would be
    (the prescribed motion, the predictors, the mixed stresses of the start); its TryOutcome
    brings the sign of det K where it converged."""
    trier, mip = prober
    g, lam, lam_try, stress_conv = here
    lam_mid = 0.5 * (lam + lam_try)
    g_whole = eq.whole_frames(g) if eq.predictor else g      # the tangent predictor's only (serial)
    g_mid, stress_mid = _try_start(eq.problem, eq, trier, g, g_whole, lam, lam_mid, mip, stress_conv, hooks.predictors)
    return trier.run(g_mid, lam_mid, mip, stress_mid)


def _after_refusal(trier, eq, hooks, checks, out, here, mip, result):
    """The next increment and the reason of the refused try ``out`` from ``here`` = (g, lam,
    stress_conv, the cut-back's dlam, floor): while a sign change of det K is located, the
    bisection's (``StepChecks.next_increment``); a located one whose sides do not connect (the
    return check, :func:`_jumped_across`) is dropped, the cut-back's dlam kept and the reason
    the return check's."""
    g, lam, stress, dlam, floor = here
    if checks.located(floor) and checks.returning and \
            (why := _jumped_across(trier, eq, hooks, checks, out, (g, lam, stress), mip, result)):
        return dlam, why
    return checks.next_increment(lam, dlam, floor), out.reason


def _jumped_across(trier, eq, hooks, checks, out, here, mip, result):
    """The return check of a located sign change (``StepChecks.judge_return``): the try ``out``
    from the current state ``here`` = (g, lam, stress_conv) to the bracket's high end converged
    with the other sign; a try from its end back to lam must land on g, else it jumped across a
    limit point, and why is returned (the bracket dropped, the reason logged with the try), else ''."""
    g, lam, stress = here
    lam_hi = checks.bracket[1]
    back, gap, why = _return_try((trier, mip), eq, hooks, out, (g, lam, lam_hi, stress), checks.judge_return)
    entry = result.log[-1] if result.log else {}
    entry["return_check"] = _return_entry(back, gap)
    entry["linear_solves"] = entry.get("linear_solves", 0) + back.solves
    if why:
        entry["reason"] = "; ".join(x for x in (entry.get("reason"), why) if x)
        if eq.root:
            log.info("  lam %.6g: %s", lam_hi, why)
    return why


def _return_try(prober, eq, hooks, out, here, judge):
    """(the return try, the distances from g of out.g and of its end or None, ``judge``'s verdict
    on it): from the state ``out.g`` the try ``out``
    converged onto at lam_hi back to lam, ``here`` = (g, lam, lam_hi, stress_conv) (the return
    check, ``solvers.step_checks``)."""
    trier, mip = prober
    g, lam, lam_hi, _ = here
    g_hi = out.g
    g_back, stress_back = _try_start(eq.problem, eq, trier, g_hi, eq.whole_frames(g_hi) if eq.predictor else g_hi,
                                     lam_hi, lam, mip, out.ev.stress if mip and out.ev is not None else None,
                                     hooks.predictors)
    back = trier.run(g_back, lam, mip, stress_back)
    gap = (eq.state_gap(g_hi, g), eq.state_gap(back.g, g)) if back.ok else None
    return back, gap, judge(back, gap, lam, lam_hi)


def _return_entry(back, gap):
    """The log entry of a return try ``back`` (``_return_try``)."""
    return dict(converged=back.ok, iterations=back.iterations, linear_solves=back.solves,
                increments=[float(x) for x in back.incs], gap=None if gap is None else list(gap))


def _refined_end(prober, eq, hooks, here, g_long):
    """The refine check's parts of a long try (``solvers.step_checks``) that ended at ``g_long``:
    REFINE_PARTS tries from its start state, each from the last one's converged state and
    stresses, started as a cut-back would be; (the distance of their end from ``g_long`` in ell,
    over the ranks, or None, their Newton iterations, why a part did not converge or was refused
    by the path check, else '', their linear solves)."""
    trier, mip = prober
    g, lam, lam_try, stress = here
    iterations = solves = 0
    for k in range(1, REFINE_PARTS + 1):
        lam_a, lam_b = lam + (lam_try - lam) * (k - 1) / REFINE_PARTS, lam + (lam_try - lam) * k / REFINE_PARTS
        g_whole = eq.whole_frames(g) if eq.predictor else g      # the tangent predictor's only (serial)
        g_b, stress_b = _try_start(eq.problem, eq, trier, g, g_whole, lam_a, lam_b, mip, stress, hooks.predictors)
        part = trier.run(g_b, lam_b, mip, stress_b)
        iterations, solves = iterations + part.iterations, solves + part.solves
        why = part.reason if not part.ok else path_refusal(part.contraction, part.travel)
        if why:
            return None, iterations, f"part {k}, {lam_a:.6g} -> {lam_b:.6g}: {why[:120]}", solves
        g, stress = part.g, (part.ev.stress if mip else None)
    return eq.state_gap(g, g_long), iterations, "", solves


def _limit_point(eq, switches, k_ref, out, g, lam, lam_try, timer, result):
    """The reference stiffness after the converged try ``out`` (None: a contact opened or
    closed, a new tangent); a step that started soft and converged far beyond its tangent's
    prediction snapped onto another branch: a ConvergenceError."""
    if switches and any(ld.active_set_changed(g, lam, out.g, lam_try) for ld in switches):
        return None
    if k_ref is None:
        k_ref = out.k_step
    jump = eq.increment_norm(out.eta_sum)
    if k_ref > 0 and out.k_step / k_ref < 0.3 and jump > 3 * out.pred:
        timer.close()
        raise ConvergenceError(
            f"load control met a limit point: the step from load factor {lam:.6g} to "
            f"{lam_try:.6g} started at a current stiffness S_p = {out.k_step / k_ref:.3g} of "
            f"the initial one and converged {jump / out.pred:.1f}x farther than its tangent "
            "predicted, i.e. it snapped onto another branch of the equilibrium path. "
            "Trace the path with arc length (core_se3.solvers.arc_length) or "
            "displacement control (core_se3.solvers.displacement_control); the "
            "steps before the limit point are kept in .result", result)
    return k_ref


def _local(eq, g):
    """The recorder's ``local`` of the iterate g: None when it is held in the problem's
    coordinates, else (g, its origin, the loads evaluated on it: ``NewtonEquations.loads``)."""
    return None if getattr(eq, "origin", None) is None else (g, eq.origin, eq.loads)


def _record(rec, eq, opts, out, g_start, g, g_whole, lam, tries, checks, at_target, steps):
    """The StepResult of the accepted try ``out`` at a target, or of any sub-step with
    record_substeps (appended to ``steps``; ``tries``: those since the last recorded one), else
    None after moving the probes' rotation record on."""
    # the try's start and increments unwrap a probe turned by more than pi
    turn = () if eq.distributed or np.isscalar(out.eta_sum) else (g_start, out.eta_sum)
    local = _local(eq, g)
    if at_target or opts.record_substeps:
        st = rec.step(lam, g_whole, len(out.hist) - 1, out.hist, eq.forces(out.ev), None, turn, local)
        st.residual_floor = min(out.floor, 1e300)      # finite in JSON when all forces are 0
        st.attempts = len(tries)
        st.linear_solves = sum(t["linear_solves"] for t in tries)
        st.max_correction = max((x for t in tries if t["converged"] for x in t["increments"]), default=0.0)
        st.checks = checks.record()
        if not at_target:
            steps.append(st)
        return st
    if local is None:
        rec.probes(g_whole, *turn)
    else:
        rec.probes(g, *turn, origin=eq.origin)
    return None


def _cutbacks_exhausted(problem, eq, opts, g_whole, last, checks, result):
    """The ConvergenceError of a try cut back ``max_cutbacks`` times, with the likeliest cause;
    ``last`` = (lam, lam_try, reason, the last try's TryOutcome)."""
    lam, lam_try, reason, out = last
    hint = next((h for h in (ld.failure_hint() for ld in hooked_loads(eq, "failure_hint")) if h),
                None) or far_part_hint(problem) or _limit_hint(problem, eq, opts, g_whole, lam, out, checks) \
        or (prescribed_turn_hint(problem, g_whole, lam, opts.linear_solver)
            if lam != 0.0 and problem.has_prescribed_motion and not eq.distributed and not eq.stateful else None)
    raise ConvergenceError(
        f"Newton failed at load factor {lam_try:.6g} after {opts.max_cutbacks} cut-backs "
        f"({reason}); the last converged load factor is {lam:.6g} and its state is "
        "kept in .result" + (f". Probable cause: {hint}" if hint else ""), result)


def _limit_hint(problem, eq, opts, g_whole, lam, out, checks):
    """The limit-point hint of a failure at the last converged load factor lam (None at 0).  A
    distributed run's is the current stiffness of the last try's first iterate over the first
    accepted try's (``out.k_step`` / ``StepChecks.k_first``), where the serial run's factorises
    the whole tangent on one process (``stability.limit_point_hint``): before, the 8x8 snap roof
    under 1.0003 times its limit load in one step failed on 2 ranks without the serial run's
    'load control has met a limit point' (S_p = 0.0136 both ways).  None with contact, as
    serially: a roller rising under a plate failed on 2 ranks naming a limit point (S_p = 0.0166)
    and arc length, which refuses contact."""
    if lam == 0.0:
        return None
    if not eq.distributed:
        return limit_point_hint(problem, g_whole, lam, opts.linear_solver)
    if hooked_loads(problem, "update_multipliers") or hooked_loads(problem, "limit_increment"):
        return None      # contact: none serially either (path following refuses it: system.ShellSystem)
    k, k_first = getattr(out, "k_step", None), checks.k_first
    return stiffness_hint(lam, k / k_first) if k is not None and k_first and checks.stiffness else None


def newton_solve(problem, steps=10, lam_end=1.0, lam_start=0.0, g_init=None, load_factors=None,
                 options=None, **kw):
    """Solve the problem from lam_start to lam_end in ``steps`` equal load increments, or
    through the explicit ``load_factors`` (a sequence moving strictly one way from lam_start;
    it replaces steps and lam_end).  Each requested load factor is a stored step; a failed
    increment is halved (at most max_cutbacks times per requested step) and grows back.

    Options: a NewtonOptions, or its fields as keywords (rtol, dtol, max_iter, max_cutbacks,
    divergence, path_check, limit_check, critical_tol, max_substeps, record_substeps,
    linear_solver, ...).  path_check: a converged try whose Newton corrections grew is cut back
    (it may have converged onto another equilibrium; docs/STEPS.md).  limit_check: stop with a
    ConvergenceError at a critical point: when det K changes sign between two accepted states
    (a bifurcation, located to critical_tol), or when a converged step has jumped past a limit
    point (snap-through: the step started where the current stiffness parameter
    S_p = k / k_0 (k = |r_0|_s^2 / (-r_0 . eta_0), the stiffness seen by the first Newton
    iterate, k_0 its value in the first step) was below 0.3, and the converged increment is
    more than 3x that first (tangent) iterate; not applied to displacement-driven problems).

    Returns a Result whose first step is the initial state.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem; its supports are checked first (SingularSystemError).
    steps : int, optional
        Number of equal load increments.
    lam_end, lam_start : float, optional
        End and start of the load factor.
    g_init : (n, 4, 4) array or StepResult, optional
        Initial frames (default the reference ones), or a stored step to continue: its frames
        and its probes' rotations, unwrapped on (``results.initial_state``; from bare frames a
        probe turned past pi starts from its angle modulo 2 pi).
    load_factors : sequence of float, optional
        Explicit load factors instead of steps and lam_end.
    options : NewtonOptions, optional
        The controls; keywords override its fields.

    Returns
    -------
    core_se3.Result
        ``steps[0]`` the initial state, then one step per requested load factor.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0, 0, 0.1)); p.add_probe("tip")
    >>> res = newton_solve(p, steps=2, rtol=1e-12)
    >>> len(res.steps), res.steps[-1].iterations <= 4
    (3, True)
    """
    t0 = time.perf_counter()
    opts, kw = split_options(NewtonOptions, options, kw)
    unknown_keywords("newton_solve", kw, [f for f in NewtonOptions.__dataclass_fields__])
    targets = requested_load_factors(steps, lam_end, lam_start, load_factors)
    mesh = problem.mesh
    g, unwrap = initial_state(g_init, mesh.g0)
    problem.check_supports(g)
    result = Result(mesh=mesh, element=problem.element_name)
    rec = StepRecorder(problem, unwrap)
    make_solver(opts.linear_solver or problem.linear_solver)         # fail early on a bad name
    result.timings["setup"] = time.perf_counter() - t0
    t_start = time.perf_counter()
    ev = problem.evaluate(g, lam_start, tangent=False)
    result.steps.append(rec.step(lam_start, g, 0, [], (ev.r_int, ev.f_ext)))
    result.timings["other"] = time.perf_counter() - t_start
    try:
        for item in newton_steps(problem, targets, opts, NewtonState(lam_start, g), rec, result):
            result.steps.append(item.step)
        end_check(problem, opts, result)
    except CoreSE3Error as exc:
        # any failure past the start (a load whose programme turns non-finite, a contact error)
        # keeps the converged steps, as ConvergenceError does
        if getattr(exc, "result", None) is None:
            exc.result = result
        raise
    return result


def _stop_at_critical(problem, opts, checks, result, count=None):
    """Stop at the located sign change of ``checks``, or at an earlier crossing that det K's
    sign did not show (:func:`end_check`)."""
    end_check(problem, opts, result, count)
    raise ConvergenceError(checks.critical_message(), result)


def end_check(problem, opts, result, count=None):
    """``end_check``: an even number of eigenvalues crossing zero within one step leaves det K's
    sign; if the last stored state (the end, or the last before a located sign change) has more
    negative eigenvalues of sym K than the start, stop at the step where they rose
    (``stability.unseen_crossing``).  Only where the stability check runs (limit_check, smooth
    conservative problems) and nothing was recorded on the way.  ``count(g, lam)``: the count
    at a whole-mesh state (default ``stability.negative_count``; a distributed run counts on
    its ranks, ``parallel.newton``).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.solvers import NewtonOptions
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> end_check(p, NewtonOptions(), newton_solve(p, steps=1, end_check=False)) is None   # stable: no stop
    True
    """
    if not (opts.end_check and opts.limit_check and not opts.inertia_check) or result.critical_points \
            or (count is None and getattr(problem.element, "stateful", False)) \
            or any(getattr(ld, "constraint_force", False) for ld in problem.loads) \
            or conservative_loads(problem.loads) is False:     # by the loads' kinds, not by K's skew part
        return
    t0 = time.perf_counter()
    found = unseen_crossing(problem, result.steps, count)
    result.timings["other"] = result.timings.get("other", 0.0) + time.perf_counter() - t0
    if found is None:
        return
    (lo, hi), (n_lo, n_hi) = found
    del result.steps[[s.load_factor for s in result.steps].index(lo) + 1:]
    raise ConvergenceError(
        f"load control crossed a critical point that det K's sign did not show: the number of negative "
        f"eigenvalues of sym K rose from {n_lo} to {n_hi} between load factors {lo:.7g} and {hi:.7g} (an even "
        "number crossed zero within that step), so the states beyond it lie on an unstable path and depend on "
        "the load steps. Locate it with inertia_check = true ([solver]) or smaller steps, or trace it with arc "
        "length (stability=True); limit_check = false continues on the unstable path. The steps before it are "
        "kept in .result", result)

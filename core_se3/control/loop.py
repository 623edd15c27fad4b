"""Closed loops on a control session: a quantity (a fingertip) tracking a target trajectory by
feedback on the Jacobian (:func:`track`), and a command trajectory planned as a sequence of
warm-started inverse problems (:func:`plan`).

Feedback (resolved-rate control by damped least squares): at every cycle k the measured y_k and
the Jacobian J_k = dy/dx at the current state (``Session.jacobian``) give the command step

    dx = s z,   z = argmin |J_k s z - gain (y*_(k+1) - y_k)|^2 + mu^2 |z|^2

(s: the variables' scales, mu: ``damping``; mu = 0 takes the least-norm solution), clipped to
the variables' bounds, and one warm update per cycle.  With gain 1 the error after the update
is the linearisation's remainder, O(|dx|^2): the denser the samples, the closer the tracking.
A command the session refuses (ControlError) is halved, at most ``max_halvings`` times.

Planning: at every sample the inverse problem min |y(x) - y*_k| is solved by Gauss-Newton on
the session (a Jacobian, a step, a warm update) from the previous sample's solution -- its
equilibrium and its command, extrapolated linearly from the two samples before -- until the
largest component of the misfit is within ``tolerance``; a step that raises the misfit, or
that the session refuses, or whose state's Jacobian it refuses (past a critical point), is
halved, and an extrapolation whose state's Jacobian is refused falls back to the last sample's
solution.  A sample not reached is flagged (``Plan.reached``, and the message says which),
never passed over; when not even the last sample's solution has a Jacobian, planning stops
and returns what it planned with the reason.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, fields

import numpy as np

from ..design import LoadMagnitude
from ..errors import ControlError, OptionError
from .commands import as_numbers

#: a quantity's response to a command step of one scale below this fraction of its size is round-off
RESPONSE_FLOOR = 1e-10

__all__ = ["track", "plan", "Feedback", "PlanOptions", "Tracking", "Plan", "least_squares_step"]


@dataclass(frozen=True)
class Feedback:
    """The feedback law of :func:`track`.

    Attributes
    ----------
    gain : float
        Feedback gain (1: a Newton step toward the next target).
    damping : float
        The damping mu of the least-squares step (0: least norm).
    max_halvings : int
        Halvings of a command step the session refuses before the cycle fails.

    Example
    -------
    >>> Feedback(damping=0.1).gain
    1.0
    """
    gain: float = 1.0
    damping: float = 0.0
    max_halvings: int = 5

    def __post_init__(self):
        _check_fields(self, gain=(0.0, False), damping=(0.0, True), max_halvings=(0, True))


@dataclass(frozen=True)
class PlanOptions:
    """The Gauss-Newton iteration of :func:`plan` at every sample.

    Attributes
    ----------
    max_iter : int
        Gauss-Newton iterations per sample.
    damping : float
        The damping mu of the least-squares step (0: least norm).
    extrapolate : bool
        Start a sample from the command extrapolated linearly from the two samples before.
    max_halvings : int
        Halvings of a step that raises the misfit or that the session refuses.

    Example
    -------
    >>> PlanOptions(max_iter=5).extrapolate
    True
    """
    max_iter: int = 20
    damping: float = 0.0
    extrapolate: bool = True
    max_halvings: int = 6

    def __post_init__(self):
        _check_fields(self, max_iter=(0, True), damping=(0.0, True), max_halvings=(0, True))
        if not isinstance(self.extrapolate, (bool, np.bool_)):
            raise OptionError(f"PlanOptions.extrapolate must be true or false, got {self.extrapolate!r}")


def _check_fields(opts, **lows):
    """OptionError unless every named field is a finite number above its low end (name -> (low,
    low allowed)), a whole one where the default is whole: before, Feedback(max_halvings=-1) ended
    in an UnboundLocalError, gain='1' in NumPy's UFuncTypeError, and a negative or NaN damping,
    PlanOptions(extrapolate='no') were read as no damping and as True."""
    for name, (low, closed) in lows.items():
        v, whole = getattr(opts, name), isinstance(low, int)
        ok = isinstance(v, (int, np.integer) if whole else (int, float, np.integer, np.floating)) and \
            not isinstance(v, (bool, np.bool_)) and np.isfinite(v) and (v >= low if closed else v > low)
        if not ok:
            kind = "a whole number" if whole else "a finite number"
            raise OptionError(f"{type(opts).__name__}.{name} must be {kind} {'>=' if closed else '>'} {low:g}, "
                              f"got {v!r}")


def _options(cls, spec, where):
    """``cls`` from None (the defaults), an instance or a dict of its fields; OptionError naming
    an unknown key."""
    if spec is None:
        return cls()
    if isinstance(spec, cls):
        return spec
    if isinstance(spec, dict):
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(spec) - set(names))
        if unknown:
            raise OptionError(f"{where}: unknown {cls.__name__} key(s) {unknown}; the keys are {names}")
        return cls(**spec)
    raise OptionError(f"{where}: expected a {cls.__name__} or a dict of its fields, got {spec!r}")


def _components(components, size):
    """The quantity's rows picked by ``components`` (an index or a list of them in 0 .. size-1), or
    OptionError (before, [2.5] was read as 2, and 2, ['z'] or [[2]] ended in NumPy's or LAPACK's
    errors)."""
    c = [components] if isinstance(components, (int, np.integer)) else components
    try:
        rows = np.asarray(c)
    except (TypeError, ValueError):
        rows = np.asarray([], float)
    whole = rows.ndim == 1 and rows.size and all(isinstance(i, (int, np.integer)) and not isinstance(i, (bool, np.bool_))
                                                 for i in rows.tolist())
    if not whole or rows.min() < 0 or rows.max() >= size:
        raise OptionError(f"components must be indices of the quantity's {size} components, 0 .. {size - 1} (an "
                          f"index or a list of them), got {components!r}")
    return rows.astype(np.int64)


def least_squares_step(J, e, scale, damping=0.0, floor=0.0):
    """The command step dx = s z, z = argmin |J s z - e|^2 + damping^2 |z|^2 (least norm when
    damping is 0), on the directions of J s whose singular value exceeds ``floor``: the response
    of the quantity to a command step of one scale, below which it is round-off (the loops take
    1e-10 of the quantity's size).  Without the floor a round-off Jacobian was inverted: a
    straight strip in a field along its axis (tip x does not respond to B at all) was commanded
    B_y = 7.3e12 T, which the session refused only as 'could not be followed'.  A quantity that
    responds to no command direction above the floor is a ControlError that says so.

    Example
    -------
    >>> import numpy as np
    >>> least_squares_step(np.array([[2.0, 0.0]]), np.array([1.0]), np.ones(2)).tolist()
    [0.5, 0.0]
    >>> least_squares_step(np.array([[2.0, 0.0], [0.0, 1e-17]]), np.array([1.0, 1.0]), np.ones(2), floor=1e-10).tolist()
    [0.5, 0.0]
    """
    Js = J * scale[None, :]
    sv = np.linalg.svd(Js, compute_uv=False)
    top = float(sv.max()) if sv.size else 0.0
    if not top > floor:
        raise ControlError(f"the quantity does not respond to the commands here: its largest response to a command "
                           f"step of one scale is {top:.1e}, at round-off (below {floor:.1e}); at this state no "
                           "command moves it to first order (a symmetric state: e.g. a straight strip magnetised "
                           "along a field parallel to it feels no couple) -- command other variables, or start the "
                           "session from a state away from the symmetry")
    if damping > 0:
        n = Js.shape[1]
        z = np.linalg.solve(Js.T @ Js + damping ** 2 * np.eye(n), Js.T @ e)
    else:
        z = np.linalg.lstsq(Js, e, rcond=max(floor / top, np.finfo(float).eps * max(Js.shape)))[0]
    return scale * z


def _check_model_variable(v, w):
    """OptionError unless the model's variable ``w`` commands what the plant's ``v`` of the same
    name does, entry by entry: the same kind and components (labels), the same loads, and regions
    in the same order -- each model region nearest (reference centroids; the model's mesh may be
    another) to the plant's region of its index.  Before, names and sizes were compared only: a
    model whose magnetisation listed the plant's two regions the other way round gave the tip's
    Jacobian by the other magnet (0.085 off in 0.18), and the loop commanded with it."""
    what = f"track(model=...): the model's variable {v.name!r}"
    if type(w) is not type(v) or list(w.labels) != list(v.labels):
        raise OptionError(f"{what} ({type(w).__name__}: {', '.join(w.labels)}) is not the plant's "
                          f"({type(v).__name__}: {', '.join(v.labels)}): make it of the same kind, form and components")
    loads = [[getattr(ld, "name", type(ld).__name__) for ld in x.loads] for x in (v, w)] \
        if isinstance(v, LoadMagnitude) else [[], []]
    if loads[0] != loads[1]:
        raise OptionError(f"{what} scales the loads {loads[1]}, the plant's {loads[0]}: give it the same loads, "
                          "in the same order")
    if hasattr(v, "regions") and hasattr(w, "regions"):
        cp, cm = _centroids(v), _centroids(w)
        if len(cp) != len(cm):
            raise OptionError(f"{what} has {len(cm)} regions, the plant's {len(cp)}")
        near = np.argmin(np.linalg.norm(cm[:, None] - cp[None], axis=2), axis=1)
        if np.any(near != np.arange(len(cp))):
            k = int(np.nonzero(near != np.arange(len(cp)))[0][0])
            raise OptionError(f"{what}: its region {k} lies where the plant's region {int(near[k])} is (reference "
                              f"centroids {np.round(cm[k], 6).tolist()} and {np.round(cp[near[k]], 6).tolist()}): "
                              "list the regions in the plant's order, so that each entry commands the same magnet "
                              "or part in both")


def _centroids(v):
    """The reference centroids (k, 3) of a region variable's regions."""
    m = v.problem.mesh
    return np.array([m.X[m.quads[np.asarray(r, int)]].reshape(-1, 3).mean(0) for r in v.regions])


class _Loop:
    """What track and plan share: the quantity's components, the variables, their commands."""

    def __init__(self, session, quantity, variables, components, model=None):
        self.s, self.model = session, model
        self.q = session.quantity(quantity)
        self.vars = session.commands.pick(variables)
        self.names = names = [v.name for v in self.vars]
        if model is not None:
            self.qm = model.quantity(quantity)
            sizes = [model.commands.lookup(n).size for n in names]
            if sizes != [v.size for v in self.vars]:
                raise OptionError(f"the model's variables {names} do not have the plant's sizes")
            for v in self.vars:
                _check_model_variable(v, model.commands.lookup(v.name))
        self.rows = np.arange(self.q.size) if components is None else _components(components, self.q.size)
        self.scale = np.concatenate([v.scale for v in self.vars])
        self.lower = np.concatenate([v.lower for v in self.vars])
        self.upper = np.concatenate([v.upper for v in self.vars])
        self.split = np.cumsum([v.size for v in self.vars])[:-1]

    def targets(self, targets):
        """The targets as a finite (samples >= 1, components) float array, or OptionError: before,
        bools and strings were read as numbers (True as 1.0, '2' as 2.0: a loop drove the tip to
        z = 1), and no samples ended track in an IndexError and planned 'all 0 samples'."""
        t = as_numbers(targets)
        shape = np.shape(targets) if t is None else t.shape
        if t is None or t.ndim != 2 or not len(t) or t.shape[1] != len(self.rows) or not np.all(np.isfinite(t)):
            raise OptionError(f"targets must be a finite array of numbers (samples >= 1, {len(self.rows)}), got "
                              f"{'shape ' + str(shape) if t is not None else repr(targets)[:80]}")
        return t

    def x(self):
        return np.concatenate([self.s.values[n] for n in self.names])

    def y(self):
        return self.q.value(self.s.problem, self.s.g, self.s.lam)[self.rows]

    def floor(self, y, e):
        """The response to a command step of one scale below which the Jacobian is round-off:
        ``RESPONSE_FLOOR`` of the quantity's size max(|y|, |e|) (least_squares_step)."""
        return RESPONSE_FLOOR * max(np.abs(y).max(initial=0.0), np.abs(e).max(initial=0.0))

    def jacobian(self):
        if self.model is not None:
            return self.model.jacobian([self.qm], self.names).jacobian[self.rows]
        return self.s.jacobian([self.q], self.vars).jacobian[self.rows]

    def command(self, x):
        """Update the session (and the model) to the command x (clipped to the bounds, and each
        group of components with a norm bound scaled onto it: its nearest point in the ball); the
        session's State."""
        parts = np.split(np.clip(x, self.lower, self.upper), self.split)
        for v, part in zip(self.vars, parts):
            for idx, top in v.norm_bounds:
                n = np.linalg.norm(part[idx])
                if n > top:
                    part[idx] *= top / n
        values = dict(zip(self.names, parts))
        if self.model is None:
            return self.s.update(**values)
        before = {n: self.model.values[n].copy() for n in self.names}
        self.model.update(**values)
        try:
            return self.s.update(**values)
        except BaseException as exc:         # whatever the plant raised (before: only a ControlError), the
            try:                             # model back to the plant's (last accepted) command, re-raised
                self.model.update(**before)
            except ControlError as back:
                if not isinstance(exc, ControlError):
                    raise ControlError(f"the plant raised {type(exc).__name__}: {exc}; and the controller's model "
                                       f"could not return to the plant's command (it stays at the new one): "
                                       f"{back}") from exc
                raise ControlError(f"{exc}; and the controller's model could not return to the plant's command "
                                   f"(it stays at the refused one): {back}") from exc
            raise

    def step(self, x, dx, max_halvings):
        """Update to x + a dx with a = 1, 1/2, ... while the session refuses; (state, a)."""
        a = 1.0
        for _ in range(max_halvings + 1):
            try:
                return self.command(x + a * dx), a
            except ControlError as exc:
                last = exc
                a /= 2
        same = " (the plant and the controller's model both stay at that command)" if self.model is not None else ""
        raise ControlError(f"the loop's command step was refused {max_halvings + 1} times, down to "
                           f"{2 * a:g} x the step; the session stays at the last accepted command{same}: {last}")


@dataclass
class Tracking:
    """The record of :func:`track`.

    Attributes
    ----------
    targets, achieved : (K, m) ndarray
        The target and the achieved quantity components at every sample (sample 0: the start).
    commands : dict
        Variable name -> (K, size) commands.
    errors : (K,) ndarray
        |achieved - target| (Euclidean, the quantity's units).
    cycle_time : (K,) ndarray
        Seconds per cycle (Jacobian, step, update; sample 0: 0).
    iterations, factorizations : (K,) ndarray
        What each update took.
    saturated : (K,) ndarray of bool
        The cycle's command step was cut by a variable's bounds or norm bound: the target lies
        beyond what the bounded commands reach (in the loop's linearisation).
    tolerance : float or None
        The error asked (``track(tolerance=...)``); ``reached``: errors <= tolerance (None
        without one); ``message``: which samples were not reached, and where the commands were
        held at their bounds.

    Example
    -------
    >>> t = Tracking(np.zeros((2, 1)), np.zeros((2, 1)), {}, np.zeros(2), np.array([0.0, 0.01]), np.zeros(2),
    ...              np.zeros(2))
    >>> round(t.rate, 6), t.max_error
    (100.0, 0.0)
    """
    targets: np.ndarray
    achieved: np.ndarray
    commands: dict
    errors: np.ndarray
    cycle_time: np.ndarray
    iterations: np.ndarray
    factorizations: np.ndarray
    saturated: np.ndarray = None
    tolerance: float = None
    message: str = ""

    @property
    def reached(self):
        """errors <= tolerance per sample (None without a tolerance)."""
        return None if self.tolerance is None else self.errors <= self.tolerance

    @property
    def all_reached(self):
        """Every sample after the start within the tolerance (None without one)."""
        return None if self.tolerance is None else bool(np.all(self.reached[1:]))

    @property
    def rate(self):
        """Cycles per second (the median cycle)."""
        return 1.0 / float(np.median(self.cycle_time[1:]))

    @property
    def max_error(self):
        """The largest error after the start."""
        return float(self.errors[1:].max())


def track(session, quantity, targets, variables=None, components=None, feedback=None, model=None, tolerance=None):
    """Track ``targets`` (K, m) with the components ``components`` of ``quantity`` (a probe name
    or a ``design`` quantity) by Jacobian feedback, one warm update per sample (module
    docstring).

    Parameters
    ----------
    session : Session
        The plant, at the start (targets[0] is recorded against the start's value): what is
        measured and commanded.
    variables : sequence of str, optional
        The commanded variables (default all of the session's; one name alone is a list of one).
    feedback : Feedback or dict, optional
        The gain, the damping mu and the halvings of a refused command (default
        ``Feedback()``: gain 1, no damping, 5 halvings).
    model : Session, optional
        The controller's model, when it is not the plant (a model error): the Jacobian is the
        model's, at the same commands (both sessions are updated every cycle; a probe name
        refers to the model's probe of that name).
    tolerance : float, optional
        The error |achieved - target| that counts as reached (``Tracking.reached``,
        ``all_reached`` and ``message`` name the samples beyond it: a target out of reach, or
        moving faster than the loop follows).

    Returns
    -------
    Tracking
        Also when the session refuses a cycle after the halvings, or its Jacobian (past a
        critical point): the ControlError raised carries the cycles done as ``.tracking``.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> from core_se3.control import Session
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.1)); p.add_probe("tip", "x1")
    >>> s = Session(p, 1.0, [LoadMagnitude(p, p.loads[0], name="P")])
    >>> z0 = s.state.probes["tip"]["x"][2]
    >>> t = track(s, "tip", [[z0], [z0 + 0.05], [z0 + 0.1]], components=[2])
    >>> bool(t.max_error < 1e-3)
    True
    """
    fb = _options(Feedback, feedback, "track")
    tolerance = None if tolerance is None else _tolerance(tolerance, "track")
    lp = _Loop(session, quantity, variables, components, model)
    T = lp.targets(targets)
    K = len(T)
    Y = np.zeros_like(T)
    X = np.zeros((K, len(lp.scale)))
    dt, its, nf, sat = np.zeros(K), np.zeros(K, int), np.zeros(K, int), np.zeros(K, bool)
    Y[0], X[0] = lp.y(), lp.x()

    def record(done, why=""):
        commands = dict(zip(lp.names, np.split(X[:done], lp.split, axis=1)))
        errors = np.linalg.norm(Y[:done] - T[:done], axis=1)
        return Tracking(T[:done], Y[:done], commands, errors, dt[:done], its[:done], nf[:done], sat[:done], tolerance,
                        _tracking_message(errors, sat[:done], tolerance, K, why))
    for k in range(1, K):
        t0 = time.perf_counter()
        try:
            e = fb.gain * (T[k] - Y[k - 1])
            dx = least_squares_step(lp.jacobian(), e, lp.scale, fb.damping, lp.floor(Y[k - 1], e))
            st, a = lp.step(X[k - 1], dx, fb.max_halvings)
        except ControlError as exc:       # the cycles done kept (before, lost with the exception)
            exc.tracking = record(k, f"tracking stopped at sample {k} of {K}: {exc}")
            raise
        Y[k], X[k] = lp.y(), lp.x()
        sat[k] = np.any(np.abs(X[k] - X[k - 1] - a * dx) > 1e-9 * np.maximum(np.abs(a * dx), lp.scale))
        dt[k] = time.perf_counter() - t0
        its[k], nf[k] = st.iterations, st.factorizations
    return record(K)


def _tracking_message(errors, saturated, tolerance, K, why=""):
    """What a :class:`Tracking` says: the samples not within ``tolerance`` (or, without one, the
    largest error), the cycles whose commands were held at their bounds, and why it stopped."""
    out = []
    if tolerance is not None:
        bad = np.nonzero(errors[1:] > tolerance)[0] + 1
        out.append(f"all {len(errors) - 1} samples after the start within {tolerance:g}" if not len(bad) else
                   f"{len(bad)} of {len(errors) - 1} samples after the start not reached (first: sample {bad[0]}, "
                   f"error {errors[bad[0]]:.3g} > {tolerance:g}; largest {errors[1:].max():.3g})")
    elif len(errors) > 1:
        out.append(f"largest error {errors[1:].max():.3g} at sample {int(np.argmax(errors[1:])) + 1} (no tolerance "
                   "given)")
    if saturated.any():
        out.append(f"the command step was cut by the variables' bounds in {int(saturated.sum())} cycles (first: "
                   f"sample {int(np.argmax(saturated))}): the targets there lie beyond the bounded commands' reach")
    return "; ".join(out + ([why] if why else []))


def _tolerance(tolerance, who):
    """A tolerance as a positive finite float, or OptionError (before, '1e-3' or None ended in
    NumPy's TypeError and True planned to within 1)."""
    if (isinstance(tolerance, (bool, np.bool_)) or not isinstance(tolerance, (int, float, np.integer, np.floating))
            or not (np.isfinite(tolerance) and tolerance > 0)):
        raise OptionError(f"{who}: the tolerance must be a positive finite number, got {tolerance!r}")
    return float(tolerance)


def _sample(lp, target, tolerance, opts, guess, previous):
    """Gauss-Newton on the session toward ``target`` (module docstring) from the command
    ``guess`` (the extrapolation; None: from the session's state) or, when the session refuses
    it or its Jacobian (a state past a critical point), from ``previous`` (the last sample's
    solution); (iterations, updates, command, quantity, misfit) at the best command found, where
    the session ends.  A step whose state the session or its Jacobian refuses is
    halved, as one that raises the misfit: before, a Jacobian refused there propagated out of
    :func:`plan` and lost the samples planned so far.  ControlError when no Jacobian is had."""
    ups = 0
    if guess is not None:
        try:
            lp.command(guess)
            ups += 1
        except ControlError:
            pass                                   # start from the last sample's solution
    y = lp.y()
    e, its, J = np.abs(y - target).max(), 0, None
    if e > tolerance and opts.max_iter > 0:
        try:
            J = lp.jacobian()
        except ControlError:
            if previous is None or np.array_equal(lp.x(), previous):
                raise
            lp.command(previous)                   # the extrapolation went past a critical point
            ups += 1
            y = lp.y()
            e, J = np.abs(y - target).max(), lp.jacobian()
    x = lp.x()
    while e > tolerance and its < opts.max_iter:
        its += 1
        dx = least_squares_step(J, target - y, lp.scale, opts.damping, lp.floor(y, target - y))
        a = 1.0
        for _ in range(opts.max_halvings + 1):
            try:
                lp.command(x + a * dx)
                ups += 1
                e_new = np.abs(lp.y() - target).max()
                # the next iteration's Jacobian, here: refused past a critical point, as the step
                J_new = lp.jacobian() if tolerance < e_new < e and its < opts.max_iter else None
            except ControlError:
                e_new = np.inf
            if e_new < e:
                break
            a /= 2
        else:
            lp.command(x)                          # back to the best point of this sample
            break
        x, y, e, J = lp.x(), lp.y(), e_new, J_new
    return its, ups, x, y, e


@dataclass
class Plan:
    """The record of :func:`plan`.

    Attributes
    ----------
    targets, achieved : (K, m) ndarray
        Targets and the quantity reached at every sample.
    commands : dict
        Variable name -> (K, size): the planned command trajectory.
    misfits : (K,) ndarray
        The largest component of |achieved - target| per sample; ``reached``: misfit <= tolerance.
    iterations : (K,) ndarray
        Gauss-Newton iterations (Jacobians) per sample; ``updates``: warm updates per sample.
    tolerance : float
        The tolerance asked; ``time`` [s]; ``message``: all reached, or which samples were not
        (and, when planning stopped -- no Jacobian even at the last sample's solution -- where
        and why: the samples from there on have NaN commands and an infinite misfit).

    Example
    -------
    >>> Plan(np.zeros((1, 1)), np.zeros((1, 1)), {}, np.zeros(1), np.ones(1, bool), np.zeros(1), np.zeros(1),
    ...      1e-3).all_reached
    True
    """
    targets: np.ndarray
    achieved: np.ndarray
    commands: dict
    misfits: np.ndarray
    reached: np.ndarray
    iterations: np.ndarray
    updates: np.ndarray
    tolerance: float
    time: float = 0.0
    message: str = field(default="")

    @property
    def all_reached(self):
        return bool(np.all(self.reached))


def plan(session, quantity, targets, tolerance, variables=None, components=None, options=None):
    """Plan the commands that put ``quantity`` (its ``components``) on every target of
    ``targets`` (K, m), each an inverse problem warm-started from the one before (module
    docstring); the session ends at the last sample.

    Parameters
    ----------
    tolerance : float
        The largest misfit component that counts as reached (the quantity's units).
    options : PlanOptions or dict, optional
        Gauss-Newton iterations per sample, damping, extrapolation and halvings (default
        ``PlanOptions()``: 20 iterations, no damping, extrapolated, 6 halvings).

    Returns
    -------
    Plan

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> from core_se3.control import Session
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.1)); p.add_probe("tip", "x1")
    >>> s = Session(p, 1.0, [LoadMagnitude(p, p.loads[0], name="P")])
    >>> z0 = s.state.probes["tip"]["x"][2]
    >>> pl = plan(s, "tip", [[z0 + 0.5], [z0 + 1.0]], 1e-9, components=[2])
    >>> pl.all_reached, bool(pl.misfits.max() <= 1e-9)
    (True, True)
    >>> plan(s, "tip", [[z0 + 1.5]], 1e-9, components=[2], options=dict(max_iter=1)).reached.tolist()
    [False]
    """
    tolerance = _tolerance(tolerance, "plan")
    opts = _options(PlanOptions, options, "plan")
    t0 = time.perf_counter()
    lp = _Loop(session, quantity, variables, components)
    T = lp.targets(targets)
    K = len(T)
    Y, X = np.zeros_like(T), np.zeros((K, len(lp.scale)))
    mis, its, ups = np.zeros(K), np.zeros(K, int), np.zeros(K, int)
    stopped = ""
    for k in range(K):
        guess = 2 * X[k - 1] - X[k - 2] if opts.extrapolate and k >= 2 else None
        try:
            its[k], ups[k], X[k], Y[k], mis[k] = _sample(lp, T[k], tolerance, opts, guess, X[k - 1] if k else None)
        except ControlError as exc:     # no Jacobian even at the last sample's solution: the progress kept
            Y[k:], X[k:], mis[k:] = np.nan, np.nan, np.inf
            stopped = f"; planning stopped at sample {k}: {exc}"
            break
    reached = mis <= tolerance
    bad = np.nonzero(~reached)[0]
    msg = (f"all {K} samples within {tolerance:g}" if not len(bad) else
           f"{len(bad)} of {K} samples not reached (first: sample {bad[0]}, misfit {mis[bad[0]]:.3g} > {tolerance:g})"
           + stopped)
    commands = dict(zip(lp.names, np.split(X, lp.split, axis=1)))
    return Plan(T, Y, commands, mis, reached, its, ups, float(tolerance), time.perf_counter() - t0, msg)

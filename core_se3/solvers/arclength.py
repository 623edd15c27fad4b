"""Path following past limit points: arc length and displacement control, as generators of
converged points.

Equilibrium path of r(g, lam) = r_int(g) - f_ext(g, lam) = 0 on the free dofs, g <- g exp(eta)
(body-frame increments, docs/CONVENTIONS.md).  With q = d f_ext / d lam (central difference
in lam at the current g, exact for linearly scaled loads, dead or follower) and K = dr/deta,
one Newton correction of the bordered system

    K du - q dlam = -r,        c_u . du + c_lam dlam = -c

is du = a + dlam b with K a = -r, K b = q (one factorisation, two solves), and dlam from the
constraint c:

* ``crisfield`` (cylindrical arc length): |Du + du|_W^2 + psi^2 u_ref^2 (Dlam + dlam)^2 = ds^2,
  Du, Dlam the increments accumulated in the step (sum of the etas); the root that keeps the
  increment closest to its previous direction is taken; for complex roots the minimum of the
  quadratic (the closest point to the constraint) is used, and more than 3 such iterations in
  a step reject it;
* ``riks`` (normal plane, Ramm's update): (Du)_W . du + psi^2 u_ref^2 Dlam dlam = 0;
* displacement control: d . (phi_k - X_k) = u* at node k (lab direction d), linearised
  c_u . du = d . R_k du_v; load control: dlam = lam* - lam.

|x|_W weights translations by 1 and rotations by ell^2 (ell = the problem's length scale, as
in ``convergence.scaled_norm``), so ds is a length.  The predictor is the tangent t = K^-1 q at the last
converged state, Dlam = +-ds / sqrt(|t|_W^2 + psi^2 u_ref^2), signed so that the new increment
continues the previous one (positive projection).  ds adapts: ds *= clip(sqrt(n_target / n),
1/2, 2) after a converged step of n iterations; a failed step (no convergence, complex root,
an edge turning by pi, a singular tangent, a converged increment pointing against its
predictor -- with the load term, or in its displacements alone --, a step over which the load
factor may have turned twice, ``critical.turned_twice``) is rejected and retried with ds / 2.

Restart: every converged point comes with an ``ArcState`` (the point, the next ds, the
previous increment that signs the next predictor, the pending branch switch, the critical
points so far); ``arc_length_steps(..., start=state)`` continues from it and repeats the same
computations from the same bits, so an interrupted and resumed path ends in the state of an
uninterrupted one.

Stability (``solvers.stability``): the negative pivots of the symmetrised tangent at every
converged point bracket limit points and bifurcations, and the step that crossed one is
bisected until its load factor is known to ``critical_tol`` (``solvers.critical``);
``branch_switch=True`` leaves a bifurcation along the buckling mode (the eigenvector of the
smallest eigenvalue, orthogonalised to t) instead of continuing on the primary path.  The
corrector and its constraints live in ``solvers.corrector``.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import ConvergenceError, CoreSE3Error, ElementTooDistortedError, OptionError, SingularSystemError
from .corrector import ArcLengthConstraint, LinearConstraint, StepFailed, correct
from .critical import Corrector, narrow, turned_twice, untraced
from .options import ArcLengthOptions, split_options, unknown_keywords
from .origin import held_by, held_of, held_record, restart_frames
from .stability import CriticalPoint, analyse, locate_critical

__all__ = ["ArcState", "PathEvent", "PathInfo", "path_steps", "path_follow", "correct",
           "LinearConstraint", "StepFailed", "PathError", "arc_options"]

log = logging.getLogger(__name__)


# ============================================================== path data ================

@dataclass
class ArcState:
    """What the arc-length follower carries from one converged point to the next (a restart).

    state: the converged point (ShellSystem: nodal frames g (n, 4, 4), in the problem's
    coordinates: ``ShellSystem.whole``); lam its load factor;
    step: converged points so far (0 = the first point of the path); ds: the arc length of the
    next step (already adapted), ds_max, ds_min its bounds; psi_u = psi |t_0|_W (length units);
    direction: sign of the first predictor's dlam; prev_du (free dofs), prev_dl: the last
    converged increment (the next predictor is signed by its W-projection on the tangent; None
    at the start and after a branch switch); switch_mode: the unit mode of a pending branch
    switch, branch_switch whether a switch is still to come; critical: the CriticalPoints found
    so far (``mode`` not needed to continue); finished: why the path stopped at this point
    ('lam_end', 'control_end', 'lam_min', 'max_steps') or ''; unwrap: the continuously
    unwrapped probe rotation vectors (arc_length's recorder; None for path_follow); held: (c,
    state relative to the origin c) as the system held it (``ShellSystem.origin``; None near the
    origin): a restart continues from it, bit for bit (``solvers.origin.restart_frames``).

    Example
    -------
    >>> st = ArcState(None, 0.5, 3, 0.1, 0.8, 1e-4, 0.0, 1.0)
    >>> scalars, arrays = st.pack(); ArcState.unpack(None, scalars, arrays) == st    # JSON round trip
    True
    """
    state: object
    lam: float
    step: int
    ds: float
    ds_max: float
    ds_min: float
    psi_u: float
    direction: float
    prev_du: np.ndarray | None = None
    prev_dl: float | None = None
    switch_mode: np.ndarray | None = None
    branch_switch: bool = False
    critical: list = field(default_factory=list)
    finished: str = ""
    unwrap: dict | None = None
    held: tuple | None = None

    def pack(self):
        """(scalars, arrays): a JSON-able dict (floats round-trip exactly through repr) and the
        arrays other than ``state``; ``ArcState.unpack(state, scalars, arrays)`` inverts it."""
        sc = dict(lam=float(self.lam), step=int(self.step), ds=float(self.ds), ds_max=float(self.ds_max),
                  ds_min=float(self.ds_min), psi_u=float(self.psi_u), direction=float(self.direction),
                  prev_dl=None if self.prev_dl is None else float(self.prev_dl),
                  branch_switch=bool(self.branch_switch), finished=str(self.finished or ""),
                  critical=[c.pack() for c in self.critical],
                  unwrap=None if self.unwrap is None else
                  {k: [float(x) for x in np.asarray(v, float)] for k, v in self.unwrap.items()})
        held_scalars, arrays = held_record(self.held)
        sc.update(held_scalars)
        if self.prev_du is not None:
            arrays["prev_du"] = np.asarray(self.prev_du, float)
        if self.switch_mode is not None:
            arrays["switch_mode"] = np.asarray(self.switch_mode, float)
        return sc, arrays

    @classmethod
    def unpack(cls, state, scalars, arrays):
        sc = scalars
        crit = [CriticalPoint.unpack(c) for c in sc.get("critical", [])]
        unwrap = None if sc.get("unwrap") is None else \
            {k: np.array(v, float) for k, v in sc["unwrap"].items()}
        return cls(state, sc["lam"], sc["step"], sc["ds"], sc["ds_max"], sc["ds_min"], sc["psi_u"],
                   sc["direction"], arrays.get("prev_du"), sc["prev_dl"], arrays.get("switch_mode"),
                   sc["branch_switch"], crit, sc["finished"], unwrap, held_of(sc, arrays))


def _fraction(cur, pt, why, lam_end, control_end, ctrl_val):
    if why == "lam_end":
        a, b, target = cur.lam, pt.lam, lam_end
    else:
        a, b, target = ctrl_val(cur.state), ctrl_val(pt.state), control_end
    return float(np.clip((target - a) / (b - a), 0.0, 1.0)) if b != a else 1.0


# ============================================================== the path follower =========

@dataclass
class PathInfo:
    """What a path follower accumulates besides its points: the log of every try, the critical
    points found, and the time spent assembling and solving ([assembly, solve] seconds).

    Example
    -------
    >>> PathInfo()                      # path_steps(..., info=PathInfo()) fills it
    PathInfo(log=[], critical=[], timers=[0.0, 0.0])
    """
    log: list = field(default_factory=list)
    critical: list = field(default_factory=list)
    timers: list = field(default_factory=lambda: [0.0, 0.0])


@dataclass
class PathEvent:
    """A converged point of the path and the ArcState to restart from it.  ``restart`` marks
    the re-analysed start point of a resumed path (not a new point).

    Example
    -------
    >>> PathEvent(point=None, state=None).restart
    False
    """
    point: object
    state: ArcState
    restart: bool = False


class PathError(ConvergenceError):
    """A path that could not go on (too many rejections); ``info`` holds its PathInfo."""

    def __init__(self, message, info):
        super().__init__(message)
        self.info = info


def path_steps(sysm, options, lam_end=1.0, control=None, control_end=None, lam_min=None,
               start=None, info=None):
    """Trace the path of ``sysm`` (ShellSystem or any object with the same methods), yielding a
    :class:`PathEvent` for the first point and for every converged point.

    Stops when lam >= lam_end (if lam_end is not None), when the controlled displacement
    ``control = (value, row)`` reaches ``control_end`` (e.g. the deflection at the end of a
    published table), when lam < lam_min, or after max_steps.  With ``land`` the last step is
    redone with load control (displacement control) so that it ends exactly on lam_end
    (control_end).  ``start=ArcState`` continues from such a point instead of the reference
    state (dlam0, ds_max, ds_min, psi and branch_switch then come from it; its re-analysed
    point comes as a ``restart`` event; a finished start yields nothing, unless it stopped at a
    max_steps now raised), repeating the computations of the uninterrupted path bit for bit.
    ``info`` (a PathInfo) collects the log, the critical points and the timers.
    Parameters: ``options`` an ArcLengthOptions, the others as above.  Yields: PathEvent; too
    many rejections raise PathError (a ConvergenceError) with ``info``.

    Example
    -------
    >>> import numpy as np; from core_se3.solvers import AlgebraicSystem
    >>> s = AlgebraicSystem(lambda u: u + u ** 3, lambda u: np.diag(1 + 3 * u ** 2), [1.0])
    >>> ev = list(path_steps(s, ArcLengthOptions(dlam0=0.5), lam_end=1.0))
    >>> [float(e.point.lam) for e in ev], ev[-1].state.finished, round(float(ev[-1].point.state[0]), 9)  # u + u^3 = 1
    ([0.0, 0.625, 1.0], 'lam_end', 0.682327804)
    """
    o = options
    info = PathInfo() if info is None else info
    timers, trylog = info.timers, info.log
    max_steps = o.max_steps
    if start is not None and start.finished and not (start.finished == "max_steps" and start.step < max_steps):
        info.critical[:] = list(start.critical)
        return
    state, lam = (sysm.initial(), 0.0) if start is None else (_restart_state(sysm, start), float(start.lam))
    first = cur = analyse(sysm, state, lam, o.stability)
    ctrl_val = control[0] if control else None
    crit = info.critical
    psi_u, ds, ds_max, ds_min, direction, prev_du, prev_dl, switch_mode, branch_switch, step = \
        _path_start(sysm, o, first, start, crit, lam_end)

    def finished(pt):
        if lam_end is not None and (pt.lam - lam_end) * np.sign(lam_end or 1.0) >= -1e-12 * max(1, abs(lam_end)):
            return "lam_end"
        if control_end is not None and (ctrl_val(pt.state) - control_end) * np.sign(control_end) >= \
                -1e-12 * abs(control_end):
            return "control_end"
        if lam_min is not None and pt.lam < lam_min:
            return "lam_min"
        return None

    def snapshot(pt, why):
        return ArcState(sysm.whole(pt.state), pt.lam, step, ds, ds_max, ds_min, psi_u, direction, prev_du, prev_dl,
                        switch_mode, branch_switch, list(crit), why or ("max_steps" if step >= max_steps else ""),
                        held=held_by(sysm, pt.state))

    yield PathEvent(first, snapshot(first, ""), restart=start is not None)
    rejections = 0
    while step < max_steps:
        du, dl = _predictor(sysm, cur.t, ds, psi_u, direction, prev_du, prev_dl, switch_mode)
        jumped, switch_mode = switch_mode is not None, None
        con = ArcLengthConstraint(o.method, ds, psi_u, sysm.w)
        con.start(du, dl)
        pt, reason, hist = _arc_try(sysm, cur, du, dl, con, psi_u, o, timers, jumped, first_step=prev_du is None)
        why = None if pt is None else finished(pt)
        if not jumped and (passed := _passed_within(sysm, cur, pt, con, lam_end, control, control_end, why)
                           or turned_twice(sysm, cur, pt, con.du)):
            pt, why, reason = None, None, passed
        if why in ("lam_end", "control_end") and o.land:
            pt, reason = _land(sysm, cur, pt, con, why, lam_end, control, control_end, o, timers)
        cp, refused = (None, "") if pt is None or jumped else \
            _critical_between(sysm, cur, pt, con, psi_u, step + 1, o, timers, trylog)
        pt, reason = (None, refused) if refused else (pt, reason)
        trylog.append(dict(step=step + 1, lam=(cur.lam + dl) if pt is None else pt.lam, ds=ds, converged=pt is not None,
                           iterations=len(hist) - 1 if pt else None, reason=reason))
        if pt is None:
            rejections += 1
            log.info("  step %d: ds %.4g REJECTED (%s); retry with ds/2", step + 1, ds, reason)
            ds /= 2
            if ds < ds_min or rejections > o.max_rejections:
                hint = (f"; ds {ds:.3g} fell below ds_min {ds_min:.3g}: start with a smaller dlam0 "
                        "or lower ds_min" if ds < ds_min and rejections <= o.max_rejections else "")
                raise PathError(f"arc length failed at lam {cur.lam:.6g} after {rejections} "
                                 f"rejections ({reason}){hint}", info)
            continue
        rejections, step = 0, step + 1
        prev_du, prev_dl = con.du, con.dlam
        event = ""
        if cp is not None:
            crit.append(cp)
            event = "  ** " + cp.describe()
            if cp.kind == "bifurcation" and branch_switch and cp.mode is not None:
                m = cp.mode - (np.sum(sysm.w * cp.mode * pt.t) / np.sum(sysm.w * pt.t * pt.t)) * pt.t
                switch_mode = m / np.sqrt(np.sum(sysm.w * m * m))
                prev_du = None
                branch_switch = False            # switch once
                event += " -> switching onto the bifurcated branch"
        if log.isEnabledFor(logging.INFO):
            _log_point(step, cur, pt, ds, ctrl_val, event + ("  (first step on the bifurcated branch)" if jumped else ""))
        if not why:
            ds = min(ds_max, ds * float(np.clip(np.sqrt(o.target_iter / max(pt.its, 1)), 0.5, 2.0)))
        cur = pt
        yield PathEvent(pt, snapshot(pt, why))
        if why:
            break


def _restart_state(sysm, start):
    """The system's state to continue from at the ArcState ``start``: the state it held there
    (relative to a far part's origin, ``solvers.origin.restart_frames``), else ``start.state``
    in the system's coordinates."""
    return restart_frames(getattr(sysm, "origin", None), start.state, start.held, sysm.local)


def _path_start(sysm, o, first, start, crit, lam_end):
    """The stepping state at the path's first point: (psi_u, ds, ds_max, ds_min, direction,
    prev_du, prev_dl, switch_mode, branch_switch, step), from the options at the reference state
    (checked against each other and ``lam_end``) or from the ArcState ``start``; ``crit`` (the
    critical points) refilled from it."""
    if start is None:
        if lam_end is not None and lam_end * o.dlam0 < 0:
            # the scenario file refuses it ([solver] dlam0); from Python, dlam0 = -0.1 to lam_end = 1
            # traced 200 steps away from it, to lam = -5.3e6, and returned them without a word
            raise OptionError(f"dlam0 = {o.dlam0:g} starts the path away from lam_end = {lam_end:g}: give dlam0 "
                              "the sign of lam_end (or lam_end=None with stop_at / lam_min)")
        tn0 = np.sqrt(np.sum(sysm.w * first.t ** 2))
        if not np.isfinite(tn0) or tn0 == 0:
            raise CoreSE3Error("the loads do not move the structure (K^-1 q = 0)")
        psi_u = o.psi * tn0                       # load term of the arc length in length units
        ds = abs(o.dlam0) * np.sqrt(tn0 ** 2 + psi_u ** 2)
        ds_max = o.ds_max or o.ds_max_factor * ds
        ds_min = o.ds_min or ds / 2 ** o.max_rejections
        if not ds_min <= ds <= ds_max:
            # ds_max = 1e-6 under the first arc length: the first step took it whole, the next 199
            # ds_max, and the path stopped at lam = 0.05 of lam_end = 1
            key, v = ("ds_max", ds_max) if ds > ds_max else ("ds_min", ds_min)
            raise OptionError(f"{key} = {v:.6g} does not admit the first arc length {ds:.6g} that dlam0 = "
                              f"{o.dlam0:g} sets: change dlam0 or {key}")
        return psi_u, ds, ds_max, ds_min, np.sign(o.dlam0) or 1.0, None, None, None, o.branch_switch, 0
    crit[:] = list(start.critical)
    prev_du = None if start.prev_du is None else np.array(start.prev_du, float)
    switch_mode = None if start.switch_mode is None else np.array(start.switch_mode, float)
    return (start.psi_u, start.ds, start.ds_max, start.ds_min, start.direction, prev_du, start.prev_dl,
            switch_mode, start.branch_switch, int(start.step))


def _predictor(sysm, t, ds, psi_u, direction, prev_du, prev_dl, switch_mode):
    """The predictor (du, dl) of arc length ds along the tangent t (K t = q), oriented by the
    previous step (the first by ``direction``); a bifurcation's ``switch_mode`` instead: a jump
    ds along the mode at fixed load."""
    if switch_mode is not None:
        return switch_mode * ds, 0.0
    tn = np.sqrt(np.sum(sysm.w * t * t))
    dl = ds / np.sqrt(tn ** 2 + psi_u ** 2)
    if prev_du is None:
        s = direction
    else:
        s = np.sign(np.sum(sysm.w * prev_du * t) + psi_u ** 2 * prev_dl) or 1.0
    dl *= s
    return dl * t, dl


def _arc_try(sysm, cur, du, dl, con, psi_u, o, timers, jumped, first_step):
    """Correct the predictor (du, dl) from ``cur`` onto the constraint ``con``: the analysed
    point (None if refused, with the reason) and the residual history."""
    hist = []
    try:
        st_pred = sysm.update(cur.state, du)
        new_state, new_lam, its, hist, ev = correct(sysm, st_pred, cur.lam + dl, con, o, timers)
        # the displacements alone too: with psi = 3 the load term kept the projection of a Riks
        # step on the cubic positive while it ran back over the loop (u = 1.45 -> -1.1)
        back = np.sum(sysm.w * con.du0 * con.du)
        if not jumped and min(back, back + psi_u ** 2 * con.dlam0 * con.dlam) <= 0:
            raise StepFailed("the corrector turned back against the predictor (path reversal)")
        if first_step and not jumped and con.dlam * con.dlam0 < 0:
            # the first step of a path starts on the stable branch through the start, so a
            # load factor moved against the predictor's is a jump onto another branch
            # (e.g. a looped elastica at a far too long first step), not a limit point
            raise StepFailed("the first step moved the load factor against the requested "
                             "direction (the corrector jumped to another branch)")
        return analyse(sysm, new_state, new_lam, o.stability, its, hist), "", hist
    except (StepFailed, ElementTooDistortedError, FloatingPointError, SingularSystemError) as exc:
        return None, str(exc), hist


def _passed_within(sysm, cur, pt, con, lam_end, control, control_end, why=None):
    """Why the converged step ``cur`` -> ``pt`` (constraint ``con``) is refused, else '': a stop
    quantity (the load factor toward lam_end, the controlled displacement ``control`` = (value,
    row) toward ``control_end``) moved toward its end at ``cur`` and turned back within the step
    (its slope along the chord changed sign), and either ``pt`` reached that end (``why``), so
    that landing from ``cur`` may find the crossing after the turn instead of the first, or the
    intersection of its tangent lines at the two ends -- an upper bound of a concave turn, or not
    finite -- reaches the end, so that the path may have passed it inside the step and a later
    point would stop it on another part of the path.  Found: the 8x8 roof of Sze s3.8(a) to
    lam_end = 0.74 (limit point 0.7436) ended at -W_C = 27.08 on the far branch from
    dlam0 >= 0.2, at 11.43 past the limit point from 1.0, at 10.15 from 0.05.  The step is
    retried shorter until a point passes the end before the turn, or the turn is resolved short
    of it.
    Slopes along sigma = c . du (c = W du / |du|_W): dlam/dsigma = 1 / (c . t) and
    du*/dsigma = (row . t) / (c . t), t = K^-1 q at each end.  '' also for no point (``pt``
    None) and for a point below lam_min (``why``); not applied to the jump of a branch switch
    (its chord is orthogonal to the tangent at ``cur``)."""
    if pt is None or why == "lam_min":
        return ""
    span = float(np.sqrt(np.sum(sysm.w * con.du ** 2)))
    if span == 0:
        return ""
    c = sysm.w * con.du / span
    with np.errstate(divide="ignore", invalid="ignore"):
        ct0, ct1 = c @ cur.t, c @ pt.t
        ends = []
        if lam_end is not None and why in (None, "lam_end"):
            ends.append(("lam_end", cur.lam, pt.lam, 1.0 / ct0, 1.0 / ct1, lam_end))
        if control_end is not None and why in (None, "control_end"):
            value, row = control
            ends.append(("the controlled displacement's end", value(cur.state), value(pt.state),
                         (row(cur.state) @ cur.t) / ct0, (row(pt.state) @ pt.t) / ct1, control_end))
        for name, q0, q1, m0, m1, target in ends:
            sense = np.sign(target - q0)
            if not (m0 * sense > 0 and m1 * sense < 0):
                continue                       # not turned back within the step
            if why is not None:
                return (f"the path passed {name} {target:.6g} and turned back within the step (ends at "
                        f"{q0:.6g} and {q1:.6g}): landing might find the crossing after the turn")
            sigma = (q1 - q0 - m1 * span) / (m0 - m1)
            bound = q0 + m0 * sigma
            if not np.isfinite(bound) or (bound - target) * sense >= 0:
                return (f"the path may have passed {name} {target:.6g} within the step and turned back "
                        f"(ends at {q0:.6g} and {q1:.6g}, tangent lines meeting at {bound:.6g})")
    return ""


def _land(sysm, cur, pt, con, why, lam_end, control, control_end, o, timers):
    """Redo the step from ``cur`` ending exactly on the stop value (lam_end or control_end)
    with load or displacement control: (the landed point, None), or (None, the reason) when
    landing fails -- the step overshot too far, and is rejected and shortened, never kept as a
    path that ends past lam_end (sze-slit-annular from dlam0 = 1 ended at 1.0335).  The step's
    increments and length in ``con`` become the landed step's: a critical point inside it is
    narrowed along it (before, along the step that overshot, toward another end: the 8x8 roof
    with psi = 1 from dlam0 = 5, Riks, took 40 bisections to a stated accuracy of 1.8e-3)."""
    if why == "lam_end":
        lin = LinearConstraint(None, None, 1.0, lam_end)
    else:
        lin = LinearConstraint(control[0], control[1], 0.0, control_end)
    try:
        frac = _fraction(cur, pt, why, lam_end, control_end, control[0] if control else None)
        st_pred = sysm.update(cur.state, frac * con.du)
        lin.start(frac * con.du, frac * con.dlam)
        s2, l2, its, hist, ev = correct(sysm, st_pred, cur.lam + frac * con.dlam, lin, o, timers)
        landed = analyse(sysm, s2, l2, o.stability, its, hist)
        con.du, con.dlam = lin.du, lin.dlam
        con.ds = float(np.sqrt(np.sum(sysm.w * lin.du ** 2) + con.c2 * lin.dlam ** 2))
        return landed, None
    except (StepFailed, ElementTooDistortedError, FloatingPointError, SingularSystemError) as exc:
        return None, f"the step passed {why} at lam {pt.lam:.6g} and landing on it failed: {exc}"


def _stability_changed(cur, pt):
    """Whether the count of negative eigenvalues (where both are counted), else the sign of det K,
    differs between the path points cur and pt."""
    if pt.n_neg is not None and cur.n_neg is not None:
        return pt.n_neg != cur.n_neg
    return pt.sign != cur.sign


def _critical_between(sysm, cur, pt, con, psi_u, step, o, timers, trylog):
    """(the critical point between the converged points cur and pt (a stability change), located
    and narrowed (its tries appended to ``trylog``); why the step is refused, else '').  A step
    whose interior no corrector reaches while its bracket is wider than critical_tol is refused:
    its ends lie on two branches, not on one path through a critical point -- the 2x2 roof at R/h
    1e4 (a near-mechanism) stepped from lam 5.2e-5 to an unstable state at -1.4e-5 and reported a
    'bifurcation' there 'located only to 0.64 after 0 solves', then limit points the load-stepped
    path does not have.  So is a step whose bisection ran all MAX_BISECTIONS halvings without
    closing (``critical.untraced``): with the area loads on the element's own geometry the same
    roof's step from 5.3e-5 to -1.5e-5 had interior points up to 1 - 2^-40 of it at lam 4.0e-6,
    1.35 steps from its end along the chord, and was kept as a 'bifurcation located only to 0.64
    after 40 solves'.  (None, '') when the stability did not change (or is not checked)."""
    if not (o.stability and _stability_changed(cur, pt)):
        return None, ""
    span = np.sqrt(np.sum(sysm.w * con.du ** 2))
    # dlam/ds changes sign across a limit point: the predictor's dlam at cur against the
    # one the next predictor will take at pt (robust where q.t also passes through 0,
    # at a turning point of the displacement conjugate to q)
    nxt = np.sum(sysm.w * con.du * pt.t) + psi_u ** 2 * con.dlam
    turned = np.sign(con.dlam0) != np.sign(nxt) if nxt != 0 else None
    cp = locate_critical(sysm, cur, pt, sysm.w * con.du / span, span, step, limit=turned)
    entry = narrow(sysm, cur, pt, con, cp, Corrector(
        correct, lambda ds: ArcLengthConstraint(o.method, ds, psi_u, sysm.w), o, timers, (StepFailed,)),
        refused=untraced)
    trylog.append(entry)
    if entry["jumped"]:                 # a bifurcation's ends that do not connect (critical.returns)
        return cp, entry["jumped"]
    if untraced(entry["bisections"], cp.accuracy, o):
        how = ("no point inside the step reaches" if entry["bisections"] == 0 else
               f"{entry['bisections']} bisections inside the step do not close on")
        return cp, (f"{how} the {cp.kind} point its ends bracket (lam {cur.lam:.6g} to {pt.lam:.6g}): the "
                    "corrector jumped to another branch")
    return cp, ""


def _log_point(step, cur, pt, ds, ctrl_val, event):
    cv = f" control {ctrl_val(pt.state):.6g}" if ctrl_val else ""
    neg = "" if pt.n_neg is None else f" neg.eig {pt.n_neg}"
    log.info(f"  step {step}: lam {pt.lam:.6g} (dlam {pt.lam - cur.lam:+.3g}) ds {ds:.4g} "
             f"it {pt.its} res {pt.hist[-1]:.1e}{cv} det {'+' if pt.sign >= 0 else '-'}{neg}{event}")


def arc_options(options, kw, method=None):
    opts, kw = split_options(ArcLengthOptions, options, kw)
    if method is not None:
        opts = replace(opts, method=method)
    return opts, kw


def path_follow(sysm, lam_end=1.0, control=None, control_end=None, lam_min=None, start=None, on_step=None,
                options=None, **kw):
    """Run :func:`path_steps` to its end; returns (points, critical points, log, timers).

    The keywords are ArcLengthOptions fields (method, dlam0, psi, branch_switch, ...);
    ``on_step(ArcState)`` is called after the first point and after every converged point (not
    for the restart point of a resumed path, which is still the first of ``points``).
    Parameters ``sysm``, ``lam_end``, ``control``, ``control_end``, ``lam_min``, ``start`` as for
    :func:`path_steps`; returns (list of PathPoint, list of CriticalPoint, log, [assembly, solve]).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.solvers import AlgebraicSystem
    >>> sysm = AlgebraicSystem(lambda u: u - 1.5 * u ** 2 + 0.5 * u ** 3,
    ...                        lambda u: np.array([[1 - 3 * u[0] + 1.5 * u[0] ** 2]]), [1.0])
    >>> pts, crit, _, _ = path_follow(sysm, lam_end=None, dlam0=0.02, psi=1.0,
    ...                               control=(lambda u: u[0], lambda u: np.array([1.0])), control_end=3.0)
    >>> [c.kind for c in crit], round(float(pts[-1].state[0]), 12)
    (['limit', 'limit'], 3.0)
    """
    opts, kw = arc_options(options, kw)
    unknown_keywords("path_follow", kw, ArcLengthOptions.__dataclass_fields__)
    info = PathInfo()
    points = []
    try:
        for ev in path_steps(sysm, opts, lam_end, control, control_end, lam_min, start, info):
            points.append(ev.point)
            if on_step and not ev.restart:
                on_step(ev.state)
    except PathError as exc:
        exc.points = points
        raise
    return points, info.critical, info.log, info.timers

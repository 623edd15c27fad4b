"""Critical points of a traced path to a stated tolerance in the load factor (arc length and
displacement control), and the steps that may hide two of them.

A critical point is first bracketed by two converged points of the path whose counts of
negative tangent eigenvalues differ (``solvers.stability``).  The bracket is as wide as the
step the path happened to take: with a first step dlam0 = 0.1, ``ds_max`` lets the step grow to
0.4 of the load, and a linear interpolation of the smallest eigenvalue over it put the lateral-
torsional buckling load of a deep cantilever strip 10 % low (0.61 ... 0.74 for first steps 0.5 ...
0.01).  :func:`refine` shrinks the bracket by bisection along the step, until the critical load
factor is known to ``critical_tol`` (relative):

* the points inside the step are corrected onto the arc-length constraint at a fraction f of
  its length from its start (predictor: from the bracket's nearer end a, at fraction f_a, the
  step's converged increment times f - f_a, its increment from the start carried into the
  constraint), and their inertia decides which half keeps the sign change; a point whose load factor the bracket's
  part of the path cannot reach (:func:`reachable`) has converged on another part of the path
  and is refused like a corrector that failed, and a refused fraction is halved toward the
  bracket's start (at most ``MAX_RETRIES`` times) before the refinement ends;
* a **bifurcation** lies on a path whose load factor moves through it, so the load factors of
  the two ends bound it: the refinement stops when they are within ``critical_tol``;
* a **limit point** is where the load factor turns: it lies above both ends (for a maximum)
  and below the intersection of the path's tangent lines at the ends (lam(s) is concave near a
  maximum; slopes dlam/dsigma = 1 / (c . t), ``stability.locate_critical``): the refinement
  stops when that interval is within ``critical_tol``; the estimate is locate_critical's.

The refined points are not path points (the path and its restart states are unchanged); only
the CriticalPoint's load factor and bracket are.

Example
-------
>>> round(bracket_width(0.5, 0.502, None), 9)              # the ends bound a bifurcation
0.003984064
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..errors import ElementTooDistortedError, SingularSystemError
from .corrector import LinearConstraint, StepFailed, correct
from .stability import analyse, locate_critical
from .step_checks import RETURN_SHARE, RETURN_TOL, path_measures, path_refusal, state_gap

__all__ = ["Corrector", "narrow", "refine", "estimate", "bracket_width", "reachable", "hidden_turns",
           "turned_twice", "untraced", "returns", "MAX_BISECTIONS"]

log = logging.getLogger(__name__)

MAX_BISECTIONS = 40
MAX_RETRIES = 4           # refused fractions halved toward the bracket's start before giving up


@dataclass(frozen=True)
class Corrector:
    """How :func:`refine` re-solves a part of a step: the path follower's corrector
    ``correct(sysm, state, lam, arc, opts, timers) -> (state, lam, iterations, history, _)``,
    ``make_constraint(ds)`` a new arc-length constraint of length ds, the options (with
    ``critical_tol``) and timers it runs with, and ``failed``: the exceptions of a rejected
    corrector (besides a singular tangent, a distorted element and a floating-point error)."""
    correct: Callable
    make_constraint: Callable
    opts: object
    timers: list
    failed: tuple = ()


def bracket_width(lam_a, lam_b, upper):
    """Relative width of the interval known to hold the critical load factor: between the two
    ends' load factors (a bifurcation: ``upper`` None), or between the end nearer to the turn and
    ``upper``, the intersection of the tangent lines (a limit point).

    Example
    -------
    >>> round(bracket_width(0.98, 0.99, 1.0), 6)                 # a maximum between 0.99 and 1.0
    0.01
    """
    if upper is None:
        lo, hi = min(lam_a, lam_b), max(lam_a, lam_b)
    else:
        near = max(lam_a, lam_b) if upper >= max(lam_a, lam_b) else min(lam_a, lam_b)
        lo, hi = min(near, upper), max(near, upper)
    return (hi - lo) / max(abs(hi), abs(lo), 1e-300)


def reachable(lam, lam_a, lam_b, slope_a, limit):
    """Whether a point of load factor ``lam`` can lie on the part of the path between two points
    of load factors lam_a and lam_b that holds one critical point: between them for a
    bifurcation (the load factor moves through it), and for a limit point on the side of the
    turn: at least the smaller end's for a maximum (``slope_a`` = dlam/dsigma at a > 0), at most
    the larger end's for a minimum.

    Parameters
    ----------
    lam : float
        The load factor of the candidate point.
    lam_a, lam_b : float
        The load factors of the bracket's ends.
    slope_a : float
        dlam/dsigma at the end a, along the step (its sign tells a maximum from a minimum).
    limit : bool
        A limit point (else a bifurcation).

    Returns
    -------
    bool

    Example
    -------
    >>> reachable(0.52, -0.064, -0.102, -1.0, True), reachable(-0.12, -0.064, -0.102, -1.0, True)
    (False, True)
    """
    if not limit:
        return min(lam_a, lam_b) <= lam <= max(lam_a, lam_b)
    return lam >= min(lam_a, lam_b) if slope_a > 0 else lam <= max(lam_a, lam_b)


def hidden_turns(lam_a, lam_b, slope_a, slope_b, span):
    """Whether the load factor may turn twice within a step whose ends agree (the same count of
    negative eigenvalues, the load factor moving the same way at both): the cubic through the
    ends' load factors lam_a, lam_b with the path's slopes dlam/dsigma there (``slope_a``,
    ``slope_b``; sigma along the step's chord, of length ``span``) has a maximum and a minimum
    inside the step.  Its slope is the quadratic p(x) = S_a + B x + A x^2 on x = sigma/span in
    [0, 1], S = slope span, whose mean is the rise lam_b - lam_a: A = 3 (S_a + S_b) - 6 (lam_b -
    lam_a), B = S_b - S_a - A; two turns when its extremum lies inside and has the other sign.
    A step over a snap-through and back (the 8x8 roof of Sze s3.8(a) from its unloaded state
    to the far branch in one arc-length step: both limit points, 0 -> 1 -> 0 negative
    eigenvalues) rises only 1.16 where the end slopes would give 6.5 and 8.3 (p = -2.0 at
    x = 0.48); a step on a smooth path has the cubic's shape as it shrinks, so that a test that
    refuses it ends.

    Parameters
    ----------
    lam_a, lam_b : float
        The load factors at the step's ends.
    slope_a, slope_b : float
        dlam/dsigma at the ends (1 / (c . t) for the chord's unit direction c, t = K^-1 q).
    span : float
        The chord's length (sigma at the far end).

    Returns
    -------
    bool

    Example
    -------
    >>> hidden_turns(0.0, 1.16, 6.52, 8.25, 1.0), hidden_turns(0.0, 1.0, 1.2, 0.8, 1.0)
    (True, False)
    """
    sa, sb, rise = slope_a * span, slope_b * span, lam_b - lam_a
    if not np.isfinite(sa + sb + rise) or sa * sb <= 0:
        return False                  # a single turn (or an infinite slope): not this test's
    A = 3.0 * (sa + sb) - 6.0 * rise
    if A == 0:
        return False
    B = sb - sa - A
    x = -B / (2.0 * A)
    return bool(0.0 < x < 1.0 and (sa - B * B / (4.0 * A)) * sa < 0)


def turned_twice(sysm, cur, pt, du):
    """Why the converged step from the PathPoint ``cur`` to ``pt`` (its increment ``du`` on the
    free dofs) is refused, else '': its ends have the same count of negative eigenvalues (or sign
    of det K) and the load factor moving the same way along the step, yet it rises so little for
    their slopes that the path may have turned twice inside it (:func:`hidden_turns`) -- two
    limit points that no count sees.  Found: the 8x8 roof of Sze s3.8(a) from dlam0 = 5 went from
    the unloaded state over the snap-through to the far branch in its first arc-length step and
    reported no critical point (from dlam0 = 0.05: limit points at 0.7436 and 0.1704); so did its
    displacement control from -W_C = 0 (or 5) to 25.  The step is retried shorter, until its
    ends bracket one turn at a time."""
    if pt is None or pt.sign != cur.sign or None not in (pt.n_neg, cur.n_neg) and pt.n_neg != cur.n_neg:
        return ""                     # a change the counts (or det K's sign) see
    span = float(np.sqrt(np.sum(sysm.w * du ** 2)))
    if span == 0:
        return ""
    c = sysm.w * du / span
    with np.errstate(divide="ignore", invalid="ignore"):
        s0, s1 = 1.0 / (c @ cur.t), 1.0 / (c @ pt.t)
    if not hidden_turns(cur.lam, pt.lam, s0, s1, span):
        return ""
    return (f"the load factor may have turned twice within the step (from {cur.lam:.6g} to {pt.lam:.6g}, rising "
            f"{pt.lam - cur.lam:.3g} where its slopes at the ends give {s0 * span:.3g} and {s1 * span:.3g}): "
            "two limit points that the counts of negative eigenvalues at the ends do not see")


def _tangent_intersection(a, b, c, span):
    """The load factor where the tangent lines of the path at the points a and b (slopes
    1 / (c . t) in sigma = c . du) meet, or None when they are parallel."""
    s0, s1 = 1.0 / (c @ a.t), 1.0 / (c @ b.t)
    if s0 == s1 or not np.isfinite(s0 + s1):
        return None
    sigma = (b.lam - a.lam - s1 * span) / (s0 - s1)
    return a.lam + s0 * sigma


def _negatives(pt):
    return pt.n_neg if pt.n_neg is not None else (0 if pt.sign >= 0 else 1)


def refine(sysm, cur, pt, con, limit, corrector):
    """Bisect the step from ``cur`` to ``pt`` (PathPoints; ``con`` the step's converged arc-
    length constraint, with its increments ``du``, ``dlam``) until the critical load factor is
    known to ``corrector.opts.critical_tol`` (module docstring); ``limit``: a limit point, not a
    bifurcation; ``corrector``: a :class:`Corrector`.  Returns (a, b, upper, bisections, span):
    the final bracket (PathPoints), the tangent-line bound of a limit point (else None), the
    number of corrector solves and the bracket's length along the step [length]; a corrector
    that fails ends the refinement with the bracket so far.
    """
    correct, make_constraint, opts, timers = corrector.correct, corrector.make_constraint, corrector.opts, \
        corrector.timers
    failures = (ElementTooDistortedError, FloatingPointError, SingularSystemError) + tuple(corrector.failed)
    w = sysm.w
    du, dl = con.du, con.dlam
    length = float(np.sqrt(np.sum(w * du * du)))
    c = w * du / max(length, 1e-300)
    a, b, fa, fb = cur, pt, 0.0, 1.0
    a_du, a_dl = 0.0 * du, 0.0             # the increment of a from cur (the constraint's)
    b_du = du                              # and of b: sigma from a to b is c . (b_du - a_du)
    n = 0

    def upper_of(a, b):
        # the span along the chord, not (fb - fa) length: a point at a fraction of the arc
        # length (with its load term, psi > 0) is not at that fraction of the chord (the
        # cubic from dlam0 = 5, Riks: the lower limit point bound -0.192443 above the exact -0.192450)
        return _tangent_intersection(a, b, c, float(c @ (b_du - a_du))) if limit else None

    upper = upper_of(a, b)
    retries = 0
    while n < MAX_BISECTIONS and bracket_width(a.lam, b.lam, upper) > opts.critical_tol:
        fm = 0.5 * (fa + fb) if not retries else 0.5 * (fa + fm)
        arc = make_constraint(fm * con.ds)
        arc.start(a_du + (fm - fa) * du, a_dl + (fm - fa) * dl)
        try:
            state, lam, its, hist, _ = correct(sysm, sysm.update(a.state, (fm - fa) * du), a.lam + (fm - fa) * dl,
                                               arc, opts, timers)
            # the 8x8 6.35 mm roof, Riks from dlam0 = 0.5: the midpoint of the step over the lower
            # limit point (-0.128, between -0.064 and -0.102) converged at lam = 0.522, and the
            # point was reported at -0.064 +- 0.018
            with np.errstate(divide="ignore"):
                slope_a = 1.0 / (c @ a.t)
            mid = analyse(sysm, state, lam, True, its, hist) if reachable(lam, a.lam, b.lam, slope_a, limit) else None
        except failures:
            mid = None
        if mid is None:
            retries += 1
            if retries > MAX_RETRIES:
                break
            continue
        retries = 0
        n += 1
        if _negatives(mid) == _negatives(a):
            a, fa, a_du, a_dl = mid, fm, arc.du.copy(), arc.dlam
        else:
            b, fb, b_du = mid, fm, arc.du.copy()
        upper = upper_of(a, b)
    return a, b, upper, n, float(c @ (b_du - a_du))


def untraced(bisections, accuracy, opts):
    """Whether the bisection of a step (``bisections`` corrector solves, the critical point then
    known to ``accuracy``; ``opts.critical_tol``) shows that its ends lie on two branches: no
    point inside the step reached the critical point (0 solves), or all MAX_BISECTIONS halvings
    ran -- the bracket shrank to 2^-40 of the step while its ends' load factors stayed
    farther apart than critical_tol, a jump of the load factor no continuous path makes (the
    2x2 roof at R/h 1e4: interior points up to 1 - 2^-40 of the step at lam 4.0e-6, its end at
    -1.5e-5, 1.35 steps away along the chord).

    Example
    -------
    >>> from types import SimpleNamespace
    >>> o = SimpleNamespace(critical_tol=1e-3)
    >>> untraced(0, 0.64, o), untraced(MAX_BISECTIONS, 0.64, o), untraced(12, 0.64, o), untraced(40, 1e-4, o)
    (True, True, False, False)
    """
    return accuracy > opts.critical_tol and (bisections == 0 or bisections >= MAX_BISECTIONS)


def _gap(sysm, s1, s2):
    """The distance of two states of ``sysm``: the largest nodal distance in ell of two frames
    (n, 4, 4) (``step_checks.state_gap``), else the largest difference of the unknowns."""
    if np.ndim(s1) == 3:
        return state_gap(s1, s2, sysm.ell)
    return float(np.max(np.abs(np.asarray(s1, float) - np.asarray(s2, float)), initial=0.0))


def returns(sysm, a, b, opts, timers):
    """'' when the two ends a, b (PathPoints) of a bifurcation's final bracket connect, else why
    not: the states of a path that goes on continuously through a bifurcation are a function of
    the load factor there, so a load-controlled correction from b back to a's load factor lands
    on a (to RETURN_TOL ell, or RETURN_SHARE of their distance); a step that jumped across a
    limit point onto another branch lands on that branch, as far from a as b is.  Found: fuzz
    problem 108 (a 3 x 1 cylindrical panel under a follower and a dead pressure; limit point at
    0.285713, the path's largest load factor, from dlam0 = 0.002) from dlam0 = 0.01 stepped from
    0.285577 to 0.285812, across the limit point onto another branch with det K of the other sign,
    and was kept as a 'bifurcation at 0.285694 +- 0.00012': b's state solved back at 0.285577 grows
    its Newton corrections 4.2x (the path check) on its way from b, 0.0136 ell from a (a real
    bifurcation's return lands within 1.6e-7 of the ends' distance: the deep strip's 5e-16 to 9e-16
    ell for ends 4e-6 to 6e-6 ell apart, the whole hinged roof's 4.2e-12 of 2.6e-5, the cubic's 0,
    docs/STEPS.md).  A correction that fails or grows (the path
    check, ``step_checks.path_refusal``) does not connect them either."""
    incs = []
    try:
        state, _, _, _, _ = correct(sysm, b.state, a.lam, LinearConstraint(None, None, 1.0, a.lam), opts, timers,
                                    incs)
        why = path_refusal(*path_measures(incs))
    except (StepFailed, ElementTooDistortedError, FloatingPointError, SingularSystemError) as exc:
        why = str(exc)
    there = _gap(sysm, a.state, b.state)
    back = None if why else _gap(sysm, state, a.state)
    if back is not None and back <= max(RETURN_TOL, RETURN_SHARE * there):
        return ""
    how = f"did not get there ({why[:120]})" if why else f"ends {back:.3g} from it ({there:.3g} between the ends)"
    return (f"the bracket's end at lam {b.lam:.7g} solved back at {a.lam:.7g} (load control) {how}: its ends do not "
            "connect, the step jumped across a limit point onto another branch")


def estimate(sysm, a, b, con, span, upper, limit):
    """(critical load factor, relative accuracy) from the final bracket of :func:`refine` (its
    length ``span`` along the step ``con``): a bifurcation at the middle of its ends' load
    factors; a limit point by the parabola through the ends with the path's slopes there
    (``stability.locate_critical``), kept inside [the nearer end, the tangent-line bound ``upper``]."""
    if not limit or upper is None:
        return 0.5 * (a.lam + b.lam), bracket_width(a.lam, b.lam, None) / 2
    w, du = sysm.w, con.du
    c = w * du / max(float(np.sqrt(np.sum(w * du * du))), 1e-300)
    s0, s1 = 1.0 / (c @ a.t), 1.0 / (c @ b.t)
    if np.sign(s0) != np.sign(s1) and span > 0:
        sc = span * s0 / (s0 - s1)
        lam = 0.5 * ((a.lam + 0.5 * s0 * sc) + (b.lam - 0.5 * s1 * (span - sc)))
    else:
        lam = max(a.lam, b.lam, key=abs)
    near = max(a.lam, b.lam) if upper >= max(a.lam, b.lam) else min(a.lam, b.lam)
    lam = float(np.clip(lam, min(near, upper), max(near, upper)))
    return lam, bracket_width(a.lam, b.lam, upper)


def narrow(sysm, cur, pt, con, cp, corrector, refused=None):
    """Narrow the CriticalPoint ``cp`` found between the path points cur and pt (the step
    ``con``) to ``corrector.opts.critical_tol`` (:func:`refine`; ``corrector``: a
    :class:`Corrector`): its load factor (a bifurcation: where the
    smallest eigenvalue interpolates to zero over the final bracket, ``stability.locate_critical``,
    exact for an eigenvalue linear in the load; a limit point: :func:`estimate`), bracket and
    accuracy are updated in place.  Returns the log entry of the bisection.  ``refused``:
    ``refused(bisections, accuracy, opts)`` True for a point the caller refuses the step for
    (arc length: :func:`untraced`; displacement control: any point not located to critical_tol),
    which is then not warned of; None: every point kept, one not located warned of."""
    limit = cp.kind == "limit"
    a, b, upper, n, span = refine(sysm, cur, pt, con, limit, corrector)
    lam, cp.accuracy = estimate(sysm, a, b, con, span, upper, limit)
    if not limit and n:
        c = sysm.w * con.du / max(float(np.sqrt(np.sum(sysm.w * con.du ** 2))), 1e-300)
        lo, hi = sorted((a.lam, b.lam))
        lam = float(np.clip(locate_critical(sysm, a, b, c, span, cp.step, limit=False).lam, lo, hi))
    cp.lam = lam if n or limit else cp.lam
    cp.lam_bracket = (a.lam, b.lam)
    dropped = refused is not None and refused(n, cp.accuracy, corrector.opts)
    # a bifurcation's ends must connect (a step across a limit point onto another branch does not)
    jumped = "" if limit or dropped else returns(sysm, a, b, corrector.opts, corrector.timers)
    if cp.accuracy > corrector.opts.critical_tol and not jumped and not dropped:
        log.warning("the %s point near lam = %.6g is located only to %.2g (critical_tol %.2g): the bisection of "
                    "its step stopped after %d solves; a smaller step (dlam0, ds_max) brackets it closer",
                    cp.kind, cp.lam, cp.accuracy, corrector.opts.critical_tol, n)
    return dict(step=cp.step, refine=cp.kind, bisections=n, lam=cp.lam, accuracy=cp.accuracy,
                converged=True, iterations=0, reason="", jumped=jumped)

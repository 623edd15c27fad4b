"""Internal splitting of a load step (``solvers.newton``): a try may turn a prescribed motion by
at most MAX_PRESCRIBED_TURN and an applied load's direction (a rotating field) by at most
MAX_LOAD_TURN, so a larger requested step is reached by several equal sub-steps; their number is
bounded by ``NewtonOptions.max_substeps``.

A field turned by 1e6 rad over a step (an angle in the wrong unit, or a typo) would otherwise be
split into about 1.3 million sub-steps of pi/4, and run for hours without output; beyond the
bound the run stops at once with a ConvergenceError that names the load, its turn over the
step and the bound.

Example
-------
>>> substeps_needed(0.0, 1.0, 0.001)
1000
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ConvergenceError, ElementTooDistortedError

__all__ = ["MAX_PRESCRIBED_TURN", "MAX_LOAD_TURN", "SCALE_SAMPLES", "first_knot", "first_turn", "split_prescribed", "split_turning", "substeps_needed",
           "check_substeps"]

MAX_PRESCRIBED_TURN = 0.9 * np.pi   # largest rotation a prescribed motion may make in one step
# largest angle an applied load's direction (a rotating field) may turn through in one try: a
# magnet in a field turned by more than pi/2 feels a couple that can flip it the other way, onto
# another equilibrium (a strip following a field turned 100 deg per step did; 50 deg did not)
MAX_LOAD_TURN = 0.25 * np.pi


def first_knot(knots, lam, lam_try):
    """The try's end: the first of ``knots`` (the points of the problem's scale tables,
    ``Problem.scale_knots``) strictly between lam and lam_try, else lam_try.

    Between two points every programme s(lam) is linear, so a try sees the load it applies at
    every load factor it passes; a try across a table's peak went from one side of it to the
    other without applying it (the hinged roof of examples/snap-roof.toml, its load taken to
    1.35 times its limit load and back in 3 steps: 'complete' on the unloaded roof, where 20
    steps stop at the limit point).  Points within 1e-12 of either end are not counted.

    Example
    -------
    >>> first_knot({0.0, 0.5, 1.0}, 1 / 3, 2 / 3), first_knot({0.5}, 1.0, 0.0), first_knot((), 0.0, 1.0)
    (0.5, 0.5, 1.0)
    """
    tol = 1e-12 * max(1.0, abs(lam), abs(lam_try))
    inside = [t for t in knots if min(lam, lam_try) + tol < t < max(lam, lam_try) - tol]
    if not inside:
        return lam_try
    return min(inside) if lam_try > lam else max(inside)


#: samples of a try on which a Python callable's scale is searched for a turning point (first_turn)
SCALE_SAMPLES = 64


def first_turn(scales, lam, lam_try, samples=SCALE_SAMPLES):
    """The try's end: the first turning point (a peak or a trough) strictly inside the try of
    any of ``scales`` -- Python callables s(lam) whose points are not known
    (``Problem.untabled_scales``) -- else lam_try.

    What :func:`first_knot` does for a table, for a callable: a try across the peak of
    s(lam) = sin(pi lam) went from the unloaded state to the unloaded state without applying the
    peak (the snap roof past its limit load, 1 step: 'complete' on the unloaded roof).  Each
    callable is sampled at ``samples`` equal intervals of the try; where its differences change
    sign (flat stretches, |ds| below 1e-13 of its range, skipped) the extremum is bracketed and
    found by golden section (the bracket shrunk to 1e-12 of the try: a kink's place to that, a
    smooth peak's to about 1e-8, where its value is the peak's to round-off).  A turn narrower than two samples
    (1/32 of the try) can be missed: give such a programme as a ``ScaleTable``.

    Example
    -------
    >>> import math
    >>> round(first_turn([lambda t: math.sin(math.pi * t)], 0.0, 1.0), 7), first_turn([abs], 1.0, 2.0)
    (0.5, 2.0)
    """
    lo, hi = min(lam, lam_try), max(lam, lam_try)
    if not scales or hi <= lo:
        return lam_try
    t = np.linspace(lam, lam_try, samples + 1)
    end = lam_try
    for s in scales:
        turn = _turn_of(s, t)
        # a turn found within 1e-9 of the try from its start or end is that end (a programme's
        # kink at a requested load factor, reached to round-off): no sliver of a try
        if turn is not None and (turn - lam) * (end - turn) > 1e-9 * (hi - lo) * abs(end - turn + turn - lam):
            end = turn
    return end


def _turn_of(s, t):
    """The first extremum of the callable ``s`` on the samples ``t`` (golden-section refined), or
    None: monotone on the samples, or not a real scalar function."""
    try:
        v = np.array([float(s(x)) for x in t])
    except (TypeError, ValueError):
        return None
    if not np.all(np.isfinite(v)):
        return None                     # the loads' own checks name a non-finite scale
    d = np.diff(v)
    sign = np.where(np.abs(d) > 1e-13 * max(np.ptp(v), np.abs(v).max(initial=0.0), 1e-300), np.sign(d), 0.0)
    moves = np.flatnonzero(sign)
    flips = moves[1:][sign[moves[1:]] != sign[moves[:-1]]]
    if not flips.size:
        return None
    j = flips[0]                                           # the first move against the one before it
    i = moves[np.searchsorted(moves, j) - 1]
    a, b, up = t[i], t[j + 1], sign[i] > 0                 # s rises (up) on [t_i, ...], falls by t_{j+1}
    f = (lambda x: -float(s(x))) if up else (lambda x: float(s(x)))
    r = (np.sqrt(5.0) - 1.0) / 2.0
    tol = 1e-12 * abs(t[-1] - t[0])
    c, e = b - r * (b - a), a + r * (b - a)
    fc, fe = f(c), f(e)
    while abs(b - a) > tol:
        if fc <= fe:
            b, e, fe = e, c, fc
            c = b - r * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, e, fe
            e = a + r * (b - a)
            fe = f(e)
    return float(0.5 * (a + b))


def split_prescribed(problem, lam, lam_try):
    """The load factor of the next try from lam toward lam_try such that the prescribed
    motion turns no node by more than 0.95 MAX_PRESCRIBED_TURN (a turn near pi is ambiguous for
    the exponential update: 2 pi lands on the same frame), found by equal splitting."""
    for _ in range(60):
        turn = problem.prescribed_rotation(lam, lam_try)
        if turn <= MAX_PRESCRIBED_TURN:
            return lam_try
        lam_try = lam + (lam_try - lam) / max(2.0, np.ceil(turn / (0.95 * MAX_PRESCRIBED_TURN)))
    raise ElementTooDistortedError("the prescribed motion turns nodes by more than "
                                   f"{MAX_PRESCRIBED_TURN:.3f} rad in any step from load factor {lam:.6g}")


def split_turning(turning, g, lam, lam_try):
    """(load factor of the next try, the load that turns most) from lam toward lam_try such
    that no load of ``turning`` (``Load.direction_turn``) turns its direction by more than
    MAX_LOAD_TURN at the state g, found by equal splitting (the request is then reached by
    several tries)."""
    for _ in range(60):
        turns = [ld.direction_turn(g, lam, lam_try) for ld in turning]
        k = int(np.argmax(turns))
        if turns[k] <= MAX_LOAD_TURN:
            return lam_try, turning[k]
        lam_try = lam + (lam_try - lam) / max(2.0, np.ceil(turns[k] / (0.95 * MAX_LOAD_TURN)))
    return lam_try, turning[k]


def substeps_needed(lam, target, lam_try):
    """The number of sub-steps of the size lam_try - lam that reach target from lam.

    Example
    -------
    >>> substeps_needed(0.2, 1.0, 0.3)
    8
    """
    return int(math.ceil(abs(target - lam) / abs(lam_try - lam) - 1e-9))


def check_substeps(lam, target, lam_try, max_substeps, what, turn, per_try, result=None):
    """Raise a ConvergenceError when reaching ``target`` from lam in sub-steps of lam_try - lam
    would take more than ``max_substeps``; ``what`` names the load (or 'the prescribed motion'),
    ``turn`` [rad] is its turn over one sub-step (the message gives the whole turn) and
    ``per_try`` the most a try may turn; ``result`` goes with the error.

    Example
    -------
    >>> check_substeps(0.0, 1.0, 1e-6, 10000, "load 'magnetic'", 0.7, MAX_LOAD_TURN)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    core_se3.errors.ConvergenceError: load 'magnetic' turns by about 7e+05 rad (1.1e+05 turns) ...
    """
    n = substeps_needed(lam, target, lam_try)
    if n <= max_substeps:
        return
    total = turn * n
    raise ConvergenceError(
        f"{what} turns by about {total:.2g} rad ({total / (2 * np.pi):.2g} turns) between load factors "
        f"{lam:.6g} and {target:.6g}: at most {per_try:.3g} rad per try, that is {n} sub-steps, more than max_substeps = {max_substeps}. Check the "
        "angle and its unit (radians: 360 is 57 turns), or raise [solver] max_substeps "
        "(NewtonOptions.max_substeps) if so many turns are meant", result)

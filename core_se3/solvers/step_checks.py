"""The checks of every converged try of load stepping (``solvers.newton``): does the state
continue the path, and has the path met a critical point?

**Path check** (``NewtonOptions.path_check``).  A large load step can converge onto another
equilibrium: the Zhao magnetic cantilever at A Br Ba L^2/(mu0 E I) = 14 in one step converged in
9 iterations to a tip angle of pi (the path's is 1.5 rad), a state with two negative tangent
eigenvalues; at 17 to a looped, *stable* state (positive-definite tangent), so the inertia of the
converged state cannot tell every such jump.  What tells it is how Newton got there.  With the
affine-covariant contraction of Newton's method (Deuflhard, *Newton Methods for Nonlinear
Problems*, 2004, ch. 2 and 5), Theta_k = |eta_{k+1}| / |eta_k| of two successive corrections: if
Newton contracts from the start of the step, the iterates stay in a ball about the first iterate
in which the solution is unique (the later corrections add up to at most |eta_0| Theta / (1 -
Theta)), and, the first correction growing with the load increment, the solutions for the
smaller increments lie in smaller balls: the converged state is the continuation of the start
state (the homotopy argument behind Deuflhard's step-size control of continuation methods).  A
Newton that grows its corrections at the scale of the step has left that region and may end
anywhere.  The check refuses a converged try when

* a correction grows (Theta_k >= 1) where the pair is at the step's scale (the larger of the two
  at least GROWTH_SCALE = 1/2 of the first correction, or of GROWTH_CAP = pi ell when the first
  is larger: a correction of rotations of more than pi is no longer local, SO(3) has diameter
  pi, so a ball that large holds other equilibria whatever Theta), or where the growth itself,
  |eta_{k+1}| - |eta_k|, is at least GROWTH_REACH = 1/4 of that scale (a correction many times
  the one before it that carries the iterate a quarter of the step away), or
* the corrections after the first add up to TRAVEL_MAX = 1.5 times the first or more (what a
  contraction of 0.6 at every iteration would reach).

A non-monotone wiggle far below the step's scale moves the iterate nowhere and is not counted:
the quarter hemisphere of Sze et al. under load control grows a correction 3.4e-2, 7.05e-5,
7.50e-5 at every step size (an inexact tangent of its penalty springs), which a plain Theta < 1
refused down to the smallest cut-back (3774 tries for its 10 steps, against 10).  Measured over
296 converged tries of the Zhao beam without the check (q = 5 ... 30, 20 to 90 elements, 1, 2
and 4 steps; ``benchmarks/robustness.py --part candidates``): each of the 17 jumps from a state on
the path grew a correction at the step's scale by 1.58 or more; 25 of the 269 tries that
converged on the path did too, and 3 more travelled 1.5 times their first correction (a
non-monotone Newton that happened to return) -- refusing those costs a cut-back, never a wrong
answer.  The change of the negative-eigenvalue count found 10 of the 17 jumps (the looped states
are stable), the ratio of the converged increment to the tangent predictor 1 (the predictor of a
large step is far off on the path too), the sign of det K none (two eigenvalues at once);
docs/STEPS.md.  The cap: without it a growth below half of a first correction of many ell went
unseen -- a clamped cylindrical panel under an oblique compressive edge force
(tests/test_step_checks.py::test_growth_beyond_pi_ell_counts_whatever_the_first_correction)
converged from 0.219 to 0.3125 of the load with corrections 9.15, 2.28, 2.85, 2.93, 1.39 ... ell
(Theta 0.25 at the step's scale then) onto a stable state 2.0 ell off the path, and its one-step
solve exited 'ok' 1.4 ell from the 16- and 128-step answers (benchmarks/invariants_fuzz.py); the
quarter hemisphere's zig-zag below (1.09 at 1.3 ell of a first 4.2 ell) stays below the capped
scale (10 tries).  The reach: a clamped plate under a follower pressure and about 5 Euler
loads (tests/test_step_checks.py::test_one_step_compressed_plate_ends_where_sixteen_steps_do)
converged from 0.578 to 0.613 of the load with corrections 0.951, 0.032, 0.021, 0.056, 0.017,
0.435 ... ell (25x, but 0.46 of the first) onto another state, and its one-step solve exited
'ok' 1.97 ell from the 2- to 256-step answers; the growth, 0.418 ell, is 0.44 of the step's
scale, where no try accepted before grew by more than 0.126 of it on the Zhao tries and the
quarter hemisphere (0.256 -> 0.522 of a first 2.1 ell), one of the fuzz campaign's 14 641 by 0.335
(no outcome changed), and the Zhao jumps by 6.8 or more; the catalogue keeps its iterations
(docs/STEPS.md).  The same rule refuses a jump across a limit point that confirmed a sign change
of det K, reported as a bifurcation (fuzz problem 108).  GROWTH_SCALE 0.4 would
catch the plate too but refused the hemisphere's zig-zag (19 tries instead of 10).  A try that
fails the check is cut back, not accepted.  Corrections below
CONTRACTION_FLOOR ell are round-off and do not count.

**Stability check** (``NewtonOptions.limit_check``).  The sign of det K of the last factorised
tangent of each converged try comes from the factors in hand (``Factorization.det_sign``: pivots
and permutation parities; free for the banded LU, an extraction of U's diagonal for SuperLU,
MUMPS' own determinant).  Between two accepted states it changes when an odd number of real
eigenvalues passed through zero: a critical point.  Under load control a limit point cannot be
passed continuously (the tries beyond it fail or jump, which the path check refuses), so a
change on the path is a bifurcation, beyond which the states depend on the step size; a long
try that contracted onto an unstable state of another branch shows a change too.  The try is
refused and the change located by bisection of the load factor to ``critical_tol`` (relative),
the last try from the bracket's low end to its high end telling the two apart (the old sign
there: a jump, the bracket is dropped).  That the path went on continuously through the change
is then verified, not assumed (the **return check**, :meth:`StepChecks.judge_return`): the state
the confirming try converged onto at the high end, solved back to the low end (one more try),
must land on the low end's state (to RETURN_TOL ell or RETURN_SHARE of the two sides' distance):
the states of a path through a bifurcation are a function of the load factor there; a try that
jumped across a limit point lands on another branch, as far from the low end as the high end is,
and the bracket is dropped and the try cut back.  Found: fuzz problem 108 (seed 4: a 3 x 1
cylindrical panel under a follower and a dead pressure; limit point at 0.2857128, the largest
load factor of its path by arc length) in 1, 4 and 16 steps stopped at a 'bifurcation' between
0.2856445 and 0.2858887 (1 step: 0.2861328): the try across it converged (corrections 0.0188,
0.0049, 0.0093, 0.0027 ... ell, Theta 0.26: the path check lets it through) onto another branch
with det K -1; solved back at 0.2856445 it lands 0.0112 ell from the state there, the sides 0.0133
ell apart.  The returns of real bifurcations land within 2.1e-11 of the sides' distance (the
Euler strips' 1e-17 ... 1e-19 ell of 1e-8 ... 1e-4, the torsion strip's 2.3e-14 of 6.1e-3).  A
critical point stops the run with a ConvergenceError naming it and what to do; with ``limit_check`` off it
is recorded where it was passed (``Result.critical_points``, bracketed by the step, no
bisection) and the path goes on; its return check (one more try) names it a bifurcation when the sides
connect, else a limit point jumped across (``StepChecks.label_passed``).  The start
state's sign is taken to be that of the first accepted state when that is +1 (an unloaded,
supported shell); a first state with det K < 0 costs one factorisation at the start to tell.

**Midpoint probe** (``NewtonOptions.midpoint_probe``).  Both checks look at the two ends of a
try; a try that turns a node by about pi or more can pass them and still have jumped:
fuzz problem 144 (``benchmarks/invariants_fuzz.py``, seed 4: a clamped 5 x 2 strip under a dead
pressure and a dead end moment of 1.9 turns) has a limit point at 0.7004 of its load, yet its
try 0.5 -> 1 contracted (corrections 15.5, 0.63, 0.28, 0.013 ... ell: Theta < 0.5) onto a state
with det K > 0 again -- two negative eigenvalues of sym K, off the path (stepping back from it
fails at 0.795) -- and 1 and 2 load steps exited ok there.  Its corrections look like the
one-step roll-up's (56.4, 2.14, 6e-9 ell, exact to 1e-12), and with a dead moment the count of
sym K rises on the right path too (docs/STEPS.md), so the ends cannot tell them apart.  The
middle can: such a try (its converged increment turns a node by more than PROBE_TURN = 0.95 pi,
within 9 degrees of the cut locus of SO(3) or past it: a margin, so that a try turning exactly pi,
as ``curved-rollup`` in 2 steps does to round-off, 3.1415926535897927 rad, is probed whichever
way the last bit falls; before, at PROBE_TURN = pi, round-off decided) is probed by a
try from its start to its midpoint load, started and iterated as a cut-back would be (the
mixed stresses of the start).  It converged onto det K of the other sign (problem 144: 7.73,
0.32, 0.025 ... ell, det K -1 at 0.75): an odd number of eigenvalues crossed zero in the first
half and again in the second, the long try jumped over a critical point and is cut back (the
cut-backs then meet the limit point as 4 to 64 steps do).  A probe that does not converge
cannot vouch for the try: cut back too.  The probe costs a Newton solve of its own (3 to 6
iterations on the catalogue's one-step cases, the roll-up's 4 doubling its 4), only for tries
that turn a node past 0.95 pi (none at the catalogue's default steps, where the roll-up turns
pi/2 a step); a distributed run probes as a serial one (the turn the largest over the ranks).

A try that turns little can jump a limit point too: fuzz problem 177 (seed 5: a clamped and
pinned 3 x 1 cylindrical panel under a dead pressure, limit point at 0.6076) in 1, 2 and 4 steps
converged from 0.5 to 0.75 (turn 0.18 rad, Theta 0.65) onto another branch and failed at 0.7555,
naming a limit point there.  Load control announces a limit point ahead: the current stiffness
S_p (Bergan's, ``TryOutcome.k_step`` over the first accepted try's) falls to zero there like the
square root of the distance in the load (the load is quadratic in the path's displacement at a
limit point), so S_p^2 of the last two accepted tries' starts, extrapolated linearly, gives its
load factor (:meth:`StepChecks.limit_ahead`): a try that passes it is probed as well.  Problem
177's try 0.5 -> 0.75 (S_p 0.45 at 0.25, 0.17 at 0.5: zero at 0.51 -- 0.54) and its cut-back retry
0.5625 -> 0.6875 (zero at 0.628) are probed, their probes at 0.625 do not converge, and the runs
stop at the limit point as 16 steps do.  Not with a prescribed motion (its load factor is no
load's).  On the catalogue (1 and 2 steps and the default) it probes magnetic-antiparallel's
default run 4 times (17 iterations), magnetic-plate's once (3) and sze-semicylinder's once (5),
none refused, the tries and iterations unchanged.

**Refine check** (``NewtonOptions.refine_check``).  A try can converge onto another equilibrium
with contracting corrections, a small turn and no sign change: fuzz problem 158
(``benchmarks/invariants_fuzz.py``, seed 8: a clamped 2 x 2 annulus under two dead edge forces,
no critical point) in 1, 2 and 4 steps converged from 0 to 0.25 in 11 iterations (corrections
1.53, 0.737, 0.322, 0.308, 0.165, 0.186 ... ell: Theta 0.481, travel 1.14, turn 0.30 rad, its
midpoint probe vouching) onto a stable state 0.142 ell off the path and exited ok 1.05 ell from
the 16-step answer; problem 206 (a clamped plate, dead end moment and gravity) in 1 and 2 steps
in 8 iterations, 1.89 ell off.  A try of more than REFINE_ITERATIONS Newton iterations is solved
again in REFINE_PARTS parts from its start (:meth:`StepChecks.judge_refinement`), each a try from
the last one's converged state and path-checked, and cut back when their end is more than
REFINE_TOL ell from its own (:func:`state_gap`) or a part fails.  Two halves do not suffice: the
half 0 -> 0.125 of 158 jumps as its try does (the halves end 1.5e-14 ell from it); four parts end
0.120 ell from it, and 1, 2 and 4 steps end where 16 steps do (1.5e-14 to 1.8e-14 ell).  The
parts of the catalogue's legitimate tries agree to 3.3e-14 ell.  The iterations, not Theta or a
cut-back, are the trigger: the catalogue's one-step tries contract by up to 0.83 and take at
most 7 iterations, so none is solved again; at the default steps 4 tries of 8 or 9 iterations are
(docs/STEPS.md).  Not with augmented loads; a distributed run takes the distance over its ranks.

Example
-------
>>> path_measures([1.0, 0.5, 0.05, 1e-6, 1e-13])[0], path_measures([1.0, 3.0, 0.2])[0]
(0.5, 3.0)
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import SingularSystemError
from .stability import CriticalPoint

__all__ = ["path_measures", "path_refusal", "start_sign", "largest_turn", "StepChecks", "CONTRACTION_MAX",
           "GROWTH_SCALE", "TRAVEL_MAX", "CONTRACTION_FLOOR", "GROWTH_CAP",
           "GROWTH_REACH", "PROBE_TURN", "REFINE_ITERATIONS", "REFINE_PARTS", "REFINE_TOL", "RETURN_TOL",
           "RETURN_SHARE", "state_gap"]

CONTRACTION_MAX = 1.0    # a try whose corrections grow at the step's scale is not accepted
GROWTH_SCALE = 0.5       # ... the step's scale: half the first correction
TRAVEL_MAX = 1.5         # the later corrections may add up to 1.5 x the first
CONTRACTION_FLOOR = 1e-8  # corrections below this (relative to ell) are round-off: not compared
GROWTH_CAP = np.pi       # ... of at most pi ell: a ball of radius pi ell holds every orientation
GROWTH_REACH = 0.25      # ... or a growth by a quarter of the step's scale, whatever the pair's size
PROBE_TURN = 0.95 * np.pi  # a try that turns a node by more than this [rad] is probed at its midpoint
REFINE_ITERATIONS = 7    # a try of more Newton iterations than this is solved again in parts ...
REFINE_PARTS = 4         # ... this many, each from the last one's converged state ...
REFINE_TOL = 1e-6        # ... and refused when their end is farther than this [ell] from its own
RETURN_TOL = 1e-6        # a located sign change's far side, solved back, lands this near [ell] (as REFINE_TOL)
RETURN_SHARE = 0.01      # ... or within this share of the two sides' distance (measured: <= 1.6e-7 against 0.85)


def path_measures(incs, floor=CONTRACTION_FLOOR):
    """(contraction, travel) of the Newton corrections of a try (relative norms ``incs``, the
    first from the start of the step): the largest ratio |eta_{k+1}| / |eta_k| over the pairs at
    the step's scale (the larger at least GROWTH_SCALE min(|eta_0|, GROWTH_CAP), or the growth
    at least GROWTH_REACH of that minimum; the second above ``floor``), and the sum of the corrections after the first over the first; (0.0, 0.0) for
    fewer than two.

    Parameters
    ----------
    incs : sequence of float
        |eta_k|_s / ell of the corrections of a try, in order.
    floor : float, optional
        Corrections below it are round-off (default CONTRACTION_FLOOR).

    Returns
    -------
    (float, float)
        Theta (>= CONTRACTION_MAX: the corrections grew at the step's scale) and the travel
        (>= TRAVEL_MAX: the iterates wandered).

    Example
    -------
    >>> [round(x, 6) for x in path_measures([1.0, 0.3, 0.01, 1e-6, 1e-12])]      # Newton
    [0.3, 0.310001]
    >>> [round(x, 6) for x in path_measures([1.0, 0.31, 1.05, 0.4, 0.02])]      # a jump
    [3.387097, 1.78]
    >>> [round(x, 3) for x in path_measures([3.4e-2, 7.05e-5, 7.5e-5, 4e-10])]  # a wiggle
    [0.002, 0.004]
    >>> round(path_measures([0.951, 0.032, 0.021, 0.056, 0.017, 0.435, 0.006])[0], 1)   # a reach
    25.6
    """
    a = np.asarray(incs, float)
    if len(a) < 2 or not a[0] > 0:
        return 0.0, 0.0
    # the step's scale is capped (GROWTH_CAP): a first correction of many ell (a ball that holds
    # other equilibria) would exempt any growth below half of it
    step = min(a[0], GROWTH_CAP)
    # ... or the growth itself reaches GROWTH_REACH of it: a correction far larger than the
    # one before it that carries the iterate a quarter of the step away (module docstring)
    big = (np.maximum(a[1:], a[:-1]) >= GROWTH_SCALE * step) | (a[1:] - a[:-1] >= GROWTH_REACH * step)
    keep = (a[1:] > floor) & (a[:-1] > 0) & big
    theta = float(np.max(a[1:][keep] / a[:-1][keep])) if np.any(keep) else 0.0
    return theta, float(a[1:].sum() / a[0])


def path_refusal(theta, travel):
    """What the path check refuses in corrections of contraction ``theta`` and ``travel``
    (:func:`path_measures`): how they grew or wandered, or '' when they may be accepted.

    Parameters
    ----------
    theta, travel : float
        The contraction and travel of :func:`path_measures`.

    Returns
    -------
    str
        '' or the reason (thresholds CONTRACTION_MAX, TRAVEL_MAX).

    Example
    -------
    >>> path_refusal(3.4, 1.8), path_refusal(0.2, 1.6), path_refusal(0.2, 0.25)
    ('grew 3.4x from one iteration to the next', 'added up to 1.6x the first', '')
    """
    if theta >= CONTRACTION_MAX:
        return f"grew {theta:.3g}x from one iteration to the next"
    if travel >= TRAVEL_MAX:
        return f"added up to {travel:.3g}x the first"
    return ""


def largest_turn(eta_sum):
    """The largest nodal rotation [rad] of a try's converged increment ``eta_sum`` ((n, 6): the
    sum of its Newton corrections, translations then rotations, unwrapped past pi); 0.0 when it
    is not known per node (a scalar: a distributed run's rank).

    Example
    -------
    >>> largest_turn(np.array([[5.0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 3.0, 4.0]])), largest_turn(0.0)
    (5.0, 0.0)
    """
    if np.isscalar(eta_sum) or np.ndim(eta_sum) != 2:
        return 0.0
    return float(np.sqrt((np.asarray(eta_sum)[:, 3:] ** 2).sum(axis=1)).max(initial=0.0))


def state_gap(g1, g2, ell):
    """The largest nodal distance of two states (n, 4, 4) in ell: |x1 - x2| / ell and the angle
    between the frames, as 2 sin(angle / 2) = |R1 - R2|_F / sqrt(2) (no arccos, whose round-off
    near 1 is 1e-8).

    Example
    -------
    >>> g = np.tile(np.eye(4), (2, 1, 1)); h = g.copy(); h[1, 0, 3] = 0.5
    >>> state_gap(g, h, 2.0)
    0.25
    """
    dx = np.linalg.norm(g1[:, :3, 3] - g2[:, :3, 3], axis=1).max(initial=0.0) / ell
    dR = np.linalg.norm(g1[:, :3, :3] - g2[:, :3, :3], axis=(1, 2)).max(initial=0.0) / np.sqrt(2)
    return float(max(dx, dR))


def start_sign(eq, g, lam, stress=None):
    """The sign of det K at the converged start state (g, lam) of a path (the equations ``eq``
    of ``solvers.equations``; ``stress``: the mixed iteration's, or None): one factorisation.
    Not the first tangent of the first try, which is at the start frames under the *next* load
    factor -- not an equilibrium, and indefinite in a field at 135 degrees for a step of 0.05.
    None when that tangent is singular (the first try reports it)."""
    try:
        ev, _, _ = eq.evaluate(g, lam, tangent=True, stress=stress, norms=False)
        eq.solve(ev, g)
    except (SingularSystemError, FloatingPointError):
        return None
    return eq.det_sign()


class StepChecks:
    """The path and stability checks of load stepping (module docstring) and their record.

    Parameters
    ----------
    path, stability : bool
        Apply the path check, the stability check (the equations give det K's sign).
    critical_tol : float
        Relative width in the load factor to which a det K sign change is located.
    sign : int or None, optional
        det K's sign at the start state (None: found with the first accepted try).
    stop : bool, optional
        A located sign change stops the run (``limit_check``; default True), else it is
        recorded and passed (:meth:`passed`).
    snap : ContactProbe, optional
        The snap check of contact steps (``solvers.contact_probe``; None: not applied).
    friction : FrictionProbe, optional
        The friction check of frictional steps (``solvers.friction_probe``; None: not applied).
    counting : bool, optional
        ``inertia_check``: each converged try brings the count of negative eigenvalues of sym K
        (``out.count``), and a change of it is located like a change of the sign of det K
        (it also sees an even number of eigenvalues crossing zero within one step).

    Attributes
    ----------
    probe : bool
        ``midpoint_probe`` (with ``limit_check``; default False, set by the caller): a try that
        turns a node by more than PROBE_TURN is probed at its midpoint (:meth:`wants_probe`,
        :meth:`judge_probe`; with the stability check only).
    returning : bool
        Apply the return check to a located sign change (:meth:`judge_return`; default True, off
        for a stateful element, whose state on the far side is not kept).
    rejected : int
        Tries refused by the path check since the last stored step (``record`` resets it).
    bracket : (float, float) or None
        (last load factor with the start's sign, first with the other) while one is located;
        ``confirmed``: the other sign was seen by a try from the low end.

    Example
    -------
    >>> import types
    >>> chk = StepChecks(True, True, 1e-3, sign=1)
    >>> ok = types.SimpleNamespace(contraction=0.2, travel=0.25, det_sign=1)
    >>> jump = types.SimpleNamespace(contraction=3.4, travel=1.8, det_sign=1)
    >>> chk.judge(ok, 0.0, 0.5), chk.judge(jump, 0.0, 1.0)[:44]
    ('', 'path check: the Newton corrections grew 3.4x')
    """

    def __init__(self, path, stability, critical_tol, sign=None, stop=True, snap=None, counting=False, friction=None):
        self.path, self.stability, self.tol, self.stop = path, stability, critical_tol, stop
        self.snap = snap                # the snap check of contact steps (solvers.contact_probe) or None
        self.friction = friction        # the friction check (solvers.friction_probe) or None
        self.counting, self.count = counting, None   # inertia_check: negative eigenvalues of sym K
        self.what = ""
        self.sign = sign
        self.bracket = None
        self.confirmed = self.probing = False
        self.crossed = []
        self.rejected = 0
        self.last = None
        self.probe = False
        self.probes = self.probe_iterations = 0    # since the last stored step
        self.refine = False
        self.returning = True       # the return check of a located sign change (judge_return)
        self.refinements = self.refine_iterations = 0    # refine check: since the last stored step
        # the current stiffness (Bergan's, TryOutcome.k_step) at the start of the last accepted try
        # over the first's: (load factor, S_p), and the first's k_step (``stiffness``: tracked)
        self.stiffness, self.stiff, self.k_first = False, None, None
        # obstacles (``contact``: their loads, set by the caller): the path and stability checks,
        # the probe and the refine check judge a try whose ends are both ``clear`` of them (no
        # contact force or stiffness: ``ContactLoad.clear``); ``start_clear`` is the current
        # state's, ``end_clear`` the last try's end's
        self.contact, self.clear, self.start_clear, self.end_clear = (), True, None, True

    def judge(self, out, lam, lam_try):
        """'' when the converged try ``out`` (a TryOutcome) from lam to lam_try may be accepted,
        else why it is refused (it is cut back; ``bracket`` is set for a det K sign change)."""
        why = path_refusal(out.contraction, out.travel) if self.path and self.clear else ""
        if why:
            self.rejected += 1
            return f"path check: the Newton corrections {why}, so the try may have converged onto another equilibrium"
        s = out.det_sign if self.clear else None
        if self.stability and s is not None and self.sign is None and s > 0:
            self.sign = s                      # module docstring: the start's sign taken as +1
        n = getattr(out, "count", None) if self.counting else None
        if self.stability and s is not None and self.sign is not None and s != self.sign:
            self.what = f"det K changed sign ({self.sign:+d} -> {s:+d})"
        elif n is not None and self.count is not None and n != self.count:
            self.what = (f"the number of negative eigenvalues of sym K changed ({self.count} -> {n}; det K kept "
                         "its sign: an even number crossed zero)")
        else:
            return ""
        if not self.stop:                     # recorded where it was passed (no bisection)
            self.crossed.append(self._point(lam, lam_try))
            return ""
        self.bracket, self.confirmed, self.probing = (lam, lam_try), True, False
        return f"stability check: {self.what} between load factors {lam:.6g} and {lam_try:.6g}"

    def wants_probe(self):
        """Whether a converged try that passed :meth:`judge` is to be probed at its midpoint when
        its converged increment turns a node by more than PROBE_TURN (module docstring):
        ``probe`` and the stability check on, and the path's sign known."""
        return bool(self.probe and self.stability and self.clear and self.sign is not None)

    def limit_ahead(self, k_step, lam, lam_try):
        """(S_p, the load factor where it extrapolates to zero) when the current stiffness S_p =
        ``k_step`` / the first accepted try's has fallen since the last accepted try started, and
        its square, linear in the load factor near a limit point (where the load is quadratic
        in the path's displacement), extrapolates to zero within the try from lam to lam_try; else
        None (module docstring)."""
        if not self.stiffness or self.stiff is None or not self.k_first or k_step is None:
            return None
        (lam0, s0), s = self.stiff, k_step / self.k_first
        if not (0.0 < s < s0) or lam == lam0:
            return None
        lam_c = lam + s * s * (lam - lam0) / (s0 * s0 - s * s)
        ahead = (lam_c - lam) * np.sign(lam_try - lam)
        return (s, lam_c) if 0.0 <= ahead < abs(lam_try - lam) and (lam - lam0) * (lam_try - lam) > 0 else None

    def probe_trigger(self, turn, k_step, lam, lam_try):
        """Why a converged try from lam to lam_try is probed at its midpoint (module docstring),
        else '': its converged increment turns a node by more than PROBE_TURN (``turn`` [rad]), or
        it passes the load factor where the current stiffness at its start (``k_step``,
        TryOutcome's) extrapolates to zero (:meth:`limit_ahead`).

        Example
        -------
        >>> chk = StepChecks(True, True, 1e-3, sign=1)
        >>> chk.stiffness, chk.k_first, chk.stiff = True, 2.0, (0.5, 0.1774)
        >>> chk.probe_trigger(6.0, 1.0, 0.0, 1.0)
        'turned a node by 6 rad (> 0.95 pi)'
        >>> chk.probe_trigger(0.18, 2 * 0.1268, 0.5625, 0.6875)[:60]
        'passed the load factor 0.627784 where the current stiffness '
        >>> chk.probe_trigger(0.18, 2 * 0.1268, 0.5625, 0.59375)
        ''
        """
        if turn > PROBE_TURN:
            return f"turned a node by {turn:.3g} rad (> 0.95 pi)"
        ahead = self.limit_ahead(k_step, lam, lam_try)
        if ahead is not None:
            return (f"passed the load factor {ahead[1]:.6g} where the current stiffness S_p = {ahead[0]:.3g} at its "
                    "start extrapolates to zero (a limit point ahead)")
        return ""

    def judge_probe(self, probe, lam, lam_try, trigger):
        """'' when the midpoint probe ``probe`` (the TryOutcome of a try from lam to the midpoint
        of lam -> lam_try) vouches for the long try, else why it is refused (cut back): the
        probe converged onto det K of the other sign than the path's, or did not converge.
        ``trigger``: why the long try was probed (:meth:`probe_trigger`)."""
        self.probes += 1
        self.probe_iterations += probe.iterations
        mid = 0.5 * (lam + lam_try)
        head = (f"midpoint probe: the try from load factor {lam:.6g} to {lam_try:.6g} {trigger} and converged "
                f"with det K {self.sign:+d}, but ")
        tail = ("; it is cut back. If the cut-backs run out: more load steps, or trace the path with arc "
                "length (core_se3.solvers.arc_length, stability=True); midpoint_probe = false ([solver]) "
                "skips the probe")
        if not probe.ok:
            return head + f"a try from its start to the midpoint {mid:.6g} did not converge ({probe.reason[:120]}), " \
                "so nothing vouches that it stayed on the path" + tail
        if probe.det_sign is not None and probe.det_sign != self.sign:
            return head + (f"a try from its start to the midpoint {mid:.6g} converged onto a state with det K "
                           f"{probe.det_sign:+d}: an odd number of eigenvalues crossed zero in each half, so it "
                           "jumped over a critical point (a limit point or a bifurcation) onto another branch") + tail
        return ""

    def wants_refinement(self, out):
        """Whether the converged try ``out`` that passed the other checks is to be solved again in
        REFINE_PARTS parts (``refine``, set by the caller: ``refine_check`` with the path check):
        it took more than REFINE_ITERATIONS Newton iterations (module docstring)."""
        return bool(self.refine and self.path and self.clear and out.iterations > REFINE_ITERATIONS)

    def judge_refinement(self, out, parts, lam, lam_try):
        """'' when the parts' end agrees with the long try ``out`` to REFINE_TOL ell, else why it
        is refused (cut back).  ``parts``: (the distance of the parts' end from the try's
        (:func:`state_gap`) or None when a part failed, their Newton iterations, why a part failed
        or ''): the first three of ``solvers.newton._refined_end``'s (the fourth, their linear solves, is
        counted in the try's ``linear_solves``).

        Example
        -------
        >>> import types
        >>> chk = StepChecks(True, True, 1e-3, sign=1)
        >>> out = types.SimpleNamespace(iterations=11)
        >>> chk.judge_refinement(out, (1e-14, 20, ""), 0.0, 0.25)
        ''
        >>> why = chk.judge_refinement(out, (0.12, 20, ""), 0.0, 0.25)
        >>> why[:62], "ends 0.12 ell from it" in why, chk.refinements, chk.refine_iterations
        ('refine check: the try from load factor 0 to 0.25 took 11 Newto', True, 2, 40)
        """
        gap, iterations, why = parts
        self.refinements += 1
        self.refine_iterations += iterations
        head = (f"refine check: the try from load factor {lam:.6g} to {lam_try:.6g} took {out.iterations} Newton "
                f"iterations (> {REFINE_ITERATIONS}), and the same step solved again in {REFINE_PARTS} parts from "
                "its start ")
        tail = ("; it is cut back. If the cut-backs run out: more load steps, or trace the path with arc length "
                "(core_se3.solvers.arc_length, stability=True); refine_check = false ([solver]) skips the check")
        if gap is None:
            return head + f"did not get there ({why}), so nothing vouches that it stayed on the path" + tail
        if gap <= REFINE_TOL:
            return ""
        return head + (f"ends {gap:.3g} ell from it (more than {REFINE_TOL:g} ell): the try converged onto "
                       "another equilibrium than the path's") + tail

    def accept(self, out, lam_try, lam=None):
        """Record the accepted try from ``lam`` (its sign becomes the path's, its current stiffness
        the last).  While a sign change is being
        located the bracket's low end moves up; a try that reached its high end with the old sign
        shows that the change seen there came from a jump, not from the path: the bracket goes."""
        if out.det_sign is not None:
            self.sign = out.det_sign if self.clear else None     # touching an obstacle: not the path's
        if not self.clear:
            self.bracket, self.confirmed, self.probing = None, False, False
        self.start_clear = self.end_clear
        k = getattr(out, "k_step", None)
        if self.stiffness and lam is not None and k is not None and np.isfinite(k):
            self.k_first = k if self.k_first is None else self.k_first
            self.stiff = (lam, k / self.k_first) if self.k_first > 0 else None
        if getattr(out, "count", None) is not None:
            self.count = out.count
        if self.snap is not None:
            self.snap.accept(out.g, lam_try)
        if self.friction is not None:
            self.friction.accept(out.g)
        if self.bracket is not None:
            lo, hi = self.bracket
            self.bracket = None if abs(hi - lam_try) <= 1e-14 * max(1.0, abs(hi)) else (lam_try, hi)
            self.confirmed = self.probing = False
        self.last = out

    def failed(self):
        """A try that did not converge (or that the path check refused): a probe of the
        bracket's high end that fails cannot confirm the change there, so the bracket goes and
        the cut-backs go on as for any failure."""
        if self.probing:
            self.bracket = None
            self.probing = False

    def judge_return(self, back, gap, lam, lam_hi):
        """'' when the located sign change between ``lam`` (the current state's load factor) and
        ``lam_hi`` connects its two sides, else why not, the bracket then dropped (a jump across a
        limit point: module docstring).  ``back``: the TryOutcome of the return try, from the
        state the confirming try converged onto at ``lam_hi`` back to ``lam``; ``gap``: the
        distances from the current state of the confirming try's end and of the return's end
        (:func:`state_gap`, ell), or None when the return did not converge.

        Example
        -------
        >>> import types
        >>> chk = StepChecks(True, True, 1e-3, sign=1)
        >>> chk.bracket, chk.confirmed = (0.2856445, 0.2858887), True
        >>> ok = types.SimpleNamespace(ok=True, reason="", contraction=0.1, travel=0.11)
        >>> chk.judge_return(ok, (6.1e-3, 2.3e-14), 0.2856445, 0.2858887), chk.bracket
        ('', (0.2856445, 0.2858887))
        >>> why = chk.judge_return(ok, (0.0133, 0.0112), 0.2856445, 0.2858887)
        >>> why[:50], "ended 0.0112 ell from the state there" in why, chk.bracket
        ('return check: the try from the state at load facto', True, None)
        """
        why = self.disconnect(back, gap, lam, lam_hi)
        if not why:
            return ""
        self.bracket, self.confirmed, self.probing = None, False, False
        return why + "; the bracket is dropped and the try cut back"

    @staticmethod
    def disconnect(back, gap, lam, lam_hi):
        """'' when the return try ``back`` (a TryOutcome from the state at ``lam_hi`` back to
        ``lam``) landed on the state there (``gap``: the distances from it of the far state and of
        the return's end, ell, or None), else why the two sides of the sign change do not connect
        (:meth:`judge_return`; with ``limit_check`` off, :meth:`label_passed`)."""
        there, back_gap = (None, None) if gap is None else gap
        why = (back.reason[:120] or "no convergence") if not back.ok else path_refusal(back.contraction, back.travel)
        if not why and back_gap <= max(RETURN_TOL, RETURN_SHARE * there):
            return ""
        head = (f"return check: the try from the state at load factor {lam_hi:.7g} on the far side of the det K "
                f"sign change back to {lam:.7g} ")
        why = (f"did not get there ({why})" if why else
               f"ended {back_gap:.3g} ell from the state there (the two sides {there:.3g} ell apart)")
        return head + why + (": the sides do not connect, the try across it jumped (a limit point, which load "
                             "control cannot pass)")

    def label_passed(self, why):
        """With ``limit_check`` off, the sign change just recorded (``crossed``) is a bifurcation
        passed on the path when its return check connected its sides (``why`` ''), else a limit
        point the step jumped across onto another branch (fuzz problem 108 with limit_check off:
        1, 4 and 16 steps recorded a 'bifurcation' between 0.2854 and 0.286084, its limit point
        0.2857128)."""
        if why and self.crossed:
            self.crossed[-1] = dataclasses.replace(self.crossed[-1], kind="limit")

    def _narrow(self, floor):
        lo, hi = self.bracket
        return abs(hi - lo) <= self.tol * max(abs(hi), abs(lo)) or abs(hi - lo) / 2 < floor * (1 + 1e-9)

    def new_target(self, dlam_nominal, max_cutbacks):
        """A new requested step of ``dlam_nominal``: the smallest increment the cut-backs allow
        (``floor``); the snap check's smallest probe follows the step too."""
        if self.snap is not None:
            self.snap.new_step(dlam_nominal)
        if self.friction is not None:
            self.friction.new_step(dlam_nominal)
        return abs(dlam_nominal) / 2 ** max_cutbacks

    def next_increment(self, lam, dlam, floor):
        """The next increment while a sign change is located, else ``dlam``: at most half the
        bracket (bisection; a failed try halves ``dlam`` as usual), and once the bracket is
        narrow (``critical_tol``, or half of it below ``floor``, the smallest increment the
        cut-backs allow) but its change was seen from an older low end, a try to its high end
        from the current one.  A contact step being probed in halves (the snap check, the
        friction check) caps it at the probed step's end."""
        if self.snap is not None:
            dlam = self.snap.next_increment(lam, dlam)
        if self.friction is not None:
            dlam = self.friction.next_increment(lam, dlam)
        if self.bracket is None:
            return dlam
        lo, hi = self.bracket
        if self._narrow(floor):
            self.probing = True
            return hi - lam
        return np.sign(hi - lam) * min(abs(dlam), abs(hi - lam) / 2)

    def located(self, floor):
        """True when the bracket is narrow (:meth:`next_increment`) and its sign change was seen
        by a try from its low end: a critical point on the path, not a jump."""
        return self.bracket is not None and self.confirmed and self._narrow(floor)

    def critical_message(self):
        """The ConvergenceError message of a located sign change."""
        lo, hi = self.bracket
        what = "det K changed sign" if self.what.startswith("det K") or not self.what else \
            "the number of negative eigenvalues of sym K changed"
        return (f"load control crossed a critical point: {what} between load factors "
                f"{lo:.7g} and {hi:.7g}, i.e. at {0.5 * (lo + hi):.7g} +- {0.5 * abs(hi - lo):.2g}. The "
                "path went on continuously through it (the state beyond it, solved back at the load factor "
                "before it, returns to the state there: the return check), so it is a "
                "bifurcation: beyond it this path is unstable and the states depend on the load "
                "steps. Trace it with arc length (core_se3.solvers.arc_length, stability=True; "
                "branch_switch=True follows the buckled branch) or add an imperfection; "
                "limit_check=False ([solver] limit_check = false) continues on the unstable path. "
                "The steps before it are kept in .result")

    @staticmethod
    def _point(lo, hi, step=-1):
        return CriticalPoint("bifurcation", step, 0.5 * (lo + hi), (lo, hi), (None, None))

    def passed(self, step):
        """The sign changes passed since the last call (``stop`` off), as CriticalPoints whose
        ``step`` is the index of the next stored step, and the snaps of the snap check; the list
        is emptied."""
        if self.snap is not None:
            self.crossed += self.snap.passed()
        out = [dataclasses.replace(cp, step=step) for cp in self.crossed]
        self.crossed.clear()
        return out

    def record(self):
        """What was checked for the stored step (``StepResult.checks``); resets the count."""
        out = self.last
        rec = dict(path_check=self.path and self.clear, contraction=None if out is None else float(out.contraction),
                   travel=None if out is None else float(out.travel), path_rejections=self.rejected,
                   det_sign=self.sign if self.stability and self.clear else None)
        if self.probe:
            rec.update(midpoint_probes=self.probes, probe_iterations=self.probe_iterations)
        if self.refinements:
            rec.update(refinements=self.refinements, refine_iterations=self.refine_iterations)
        if self.snap is not None:
            rec.update(self.snap.record())
        if self.friction is not None:
            rec.update(self.friction.record())
        self.rejected = self.probes = self.probe_iterations = self.refinements = self.refine_iterations = 0
        return rec

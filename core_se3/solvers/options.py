"""The solver controls, held once: :class:`NewtonOptions` (load and displacement-driven load
stepping) and :class:`ArcLengthOptions` (path following).  Scenario files read their fields and
defaults (``[solver]``), so a default lives here only.

Example
-------
>>> from core_se3.solvers import NewtonOptions
>>> NewtonOptions(max_iter=50).rtol
1e-10
>>> NewtonOptions(rtol=-1.0)
Traceback (most recent call last):
...
core_se3.errors.OptionError: NewtonOptions.rtol must be a number in (0, 1), got -1.0
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, fields, replace

from ..errors import OptionError, did_you_mean

__all__ = ["NewtonOptions", "ArcLengthOptions", "split_options", "unknown_keywords", "load_steps", "ITERATIONS",
           "PREDICTORS"]

ITERATIONS = ("mip", "displacement")     # NewtonOptions.iteration
PREDICTORS = ("none", "tangent")         # NewtonOptions.predictor


def _check(opts):
    for f in fields(opts):
        v = getattr(opts, f.name)
        lo, hi = f.metadata.get("range", (None, None))
        if lo is None or v is None:
            continue
        whole = f.type not in ("int", int) or (isinstance(v, numbers.Real) and float(v).is_integer())
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not whole or \
                not (lo < v < hi if f.metadata.get("open") else lo <= v <= hi):
            br = "()" if f.metadata.get("open") else "[]"
            what = "a whole number" if f.type in ("int", int) else "a number"
            raise OptionError(f"{type(opts).__name__}.{f.name} must be {what} in {br[0]}{lo:g}, {hi:g}{br[1]}, "
                              f"got {v!r}")


def _opt(default, lo=None, hi=None, open_=False, doc=""):
    return field(default=default, metadata=dict(range=(lo, hi), open=open_, doc=doc))


@dataclass(frozen=True)
class NewtonOptions:
    """Controls of load-stepped Newton (``solvers.newton``).

    rtol, dtol: relative residual and increment tolerances (``solvers.convergence``);
    max_iter: Newton iterations per try; max_cutbacks: halvings of a failed increment per
    requested step; divergence: a try whose residual exceeds this factor times its first one
    after 3 iterations is abandoned; path_check: accept a converged try only if its Newton
    corrections contracted (``solvers.step_checks``: a try that grew them may have converged onto
    another equilibrium; it is cut back); limit_check: stop with a ConvergenceError when the path
    meets a critical point: a step that snapped past a limit point (suggesting arc length), or a
    change of the sign of det K (a bifurcation, located to ``critical_tol`` of the load factor by
    bisection); max_substeps: the most sub-steps into which a requested step may be split to
    keep a prescribed motion or a turning field within its turn per try (beyond it a
    ConvergenceError names the load and the turn); snap_check: with contact, solve a try that
    moved a node by more than an element size again in halves, keep the halves' path, and report
    a jump that survives the halving as a snap (``solvers.contact_probe``); friction_check: with
    Coulomb friction, solve an accepted state whose slipping nodes exceed the cone by more than
    friction_tol (the hardening) again at its load factor; friction_halving: also solve a try over
    which a contact node changed its stick/slip status (or its slip direction) again in halves and
    refine until the halves agree with it to friction_tol of the path's displacement scale
    (``solvers.friction_probe``; off by default: its estimate does not shrink with the step on
    the walkers); inertia_check: count
    the negative eigenvalues of sym K at every converged try (one more factorisation per try) so
    that an even number of them crossing zero within one step, which leaves the sign of det K,
    is located like a sign change (``solvers.step_checks``); end_check: with limit_check and no
    critical point met, count the negative eigenvalues of sym K at the end of the solve (one
    factorisation) and, if more than at the start, stop naming the step where they rose
    (``solvers.stability.unseen_crossing``; conservative loads, no contact); midpoint_probe: with
    limit_check, a converged try that turned a node by more than 0.95 pi, or passed the load factor
    where the current stiffness extrapolates to zero, is probed by a try from its start to its
    midpoint load, and cut back when that converges onto det K of the other sign
    (it jumped over a critical point) or does not converge (``solvers.step_checks``; one more
    Newton solve per such try); refine_check: a converged try of more than 7 Newton iterations
    (path check on, no contact) is solved again in 4 parts from its start and cut back when
    their end is more than 1e-6 ell from its own (it converged onto another equilibrium;
    ``solvers.step_checks``); record_substeps: store the cut-back
    sub-steps as steps too; linear_solver: None = the problem's; iteration: 'mip' (the mixed
    integration point Newton of Magisano, Leonetti and Garcea 2017, with an element that
    supports it: the geometric part of the tangent sees element stresses updated linearly,
    ``solvers.newton``) or 'displacement' (plain Newton on the displacement residual); both
    converge to the same states; max_augmentations: multiplier updates (and solves again) per try
    of the loads that have multipliers (augmented-Lagrangian contact, ``Load.update_multipliers``).

    Attributes
    ----------
    rtol, dtol : float
        In (0, 1); default 1e-10 each.
    max_iter : int
        In [0, 1000]; default 30.
    max_cutbacks : int
        In [0, 50]; default 12.
    divergence : float
        >= 1; default 1e8.
    path_check, limit_check, snap_check, friction_check, friction_halving, inertia_check, end_check, midpoint_probe, refine_check, record_substeps : bool
        Default True, True, True, True, False, False, True, True and False.
    friction_tol : float
        In (0, 1); default 1e-7.
    critical_tol : float
        In (0, 1); default 1e-3.
    max_substeps : int
        In [1, 10^7]; default 1000.
    linear_solver : str or None
        'auto', 'superlu', 'mumps' or None.
    iteration : str
        'mip' (default) or 'displacement'.
    max_augmentations : int
        In [0, 1000]; default 25.
    predictor : str
        'none' (default: a try starts from the converged state with the prescribed nodes moved)
        or 'tangent' (with a prescribed motion: the Euler predictor of ``newton_try.tangent_predictor``,
        which carries the shell along with the prescribed nodes).

    A value outside its range raises :class:`~core_se3.errors.OptionError`.

    Example
    -------
    >>> opts = NewtonOptions(max_cutbacks=4)
    >>> opts.max_cutbacks, opts.max_iter, opts.limit_check
    (4, 30, True)
    """
    rtol: float = _opt(1e-10, 0.0, 1.0, True)
    dtol: float = _opt(1e-10, 0.0, 1.0, True)
    max_iter: int = _opt(30, 0, 1000)
    max_cutbacks: int = _opt(12, 0, 50)
    divergence: float = _opt(1e8, 1.0, float("inf"))
    limit_check: bool = True
    record_substeps: bool = False
    linear_solver: str | None = None
    iteration: str = "mip"
    max_augmentations: int = _opt(25, 0, 1000)
    predictor: str = "none"
    path_check: bool = True
    critical_tol: float = _opt(1e-3, 0.0, 1.0, True)
    max_substeps: int = _opt(1000, 1, 10_000_000)
    snap_check: bool = True
    friction_check: bool = True
    friction_halving: bool = False
    friction_tol: float = _opt(1e-7, 0.0, 1.0, True)
    inertia_check: bool = False
    end_check: bool = True
    midpoint_probe: bool = True
    refine_check: bool = True

    def __post_init__(self):
        _check(self)
        if self.predictor not in PREDICTORS:
            raise OptionError(f"NewtonOptions.predictor must be one of {', '.join(map(repr, PREDICTORS))}, "
                              f"got {self.predictor!r}")
        if self.iteration not in ITERATIONS:
            raise OptionError(f"NewtonOptions.iteration must be one of {', '.join(map(repr, ITERATIONS))}, "
                              f"got {self.iteration!r}")


@dataclass(frozen=True)
class ArcLengthOptions:
    """Controls of arc-length path following (``solvers.arclength``).

    method: 'crisfield' (cylindrical) or 'riks' (normal plane); dlam0: load factor of the first
    predictor (sets ds); psi: weight of the load term; ds_max (default ds_max_factor x the
    first ds), ds_min; max_steps: path points; target_iter: Newton iterations per step the
    step-length adaptation aims at; max_iter, rtol, dtol as for Newton; max_rejections: halvings
    of ds in a row; divergence: as for Newton; stability: count negative pivots and detect
    critical points; critical_tol: the relative accuracy in the load factor to which a critical
    point is located by bisecting the step that crossed it (``solvers.critical``);
    branch_switch: leave the first bifurcation along its mode; land: end exactly on lam_end (or
    the controlled displacement) by a last corrector.

    Attributes
    ----------
    method : str
        'crisfield' (default) or 'riks'.
    dlam0 : float
        Default 0.05 (its sign sets the direction).
    psi : float
        >= 0, default 0 (a pure displacement arc length).
    ds_max, ds_min : float or None
        Bounds of the arc length [length] (None: 8 x the first ds, and ds / 2^max_rejections).
    ds_max_factor : float
        >= 1, default 8.
    max_steps, target_iter, max_iter : int
        Defaults 200, 5, 20.
    rtol, dtol : float
        Default 1e-9 each.
    max_rejections : int
        Default 12; ``divergence``: default 1e6.
    stability, branch_switch, land : bool
        Defaults True, False, True.
    critical_tol : float
        In (0, 1); default 1e-3.
    linear_solver : str or None
        As for NewtonOptions.

    Example
    -------
    >>> ArcLengthOptions(method="riks").ds_max_factor
    8.0
    >>> ArcLengthOptions(method="arc")
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: ArcLengthOptions.method must be 'crisfield' or 'riks', got 'arc'
    """
    method: str = "crisfield"
    dlam0: float = 0.05
    psi: float = _opt(0.0, 0.0, float("inf"))
    ds_max: float | None = None
    ds_min: float | None = None
    ds_max_factor: float = _opt(8.0, 1.0, float("inf"))
    max_steps: int = _opt(200, 1, 100_000)
    target_iter: int = _opt(5, 1, 100)
    max_iter: int = _opt(20, 0, 1000)
    rtol: float = _opt(1e-9, 0.0, 1.0, True)
    dtol: float = _opt(1e-9, 0.0, 1.0, True)
    max_rejections: int = _opt(12, 0, 100)
    divergence: float = _opt(1e6, 1.0, float("inf"))
    stability: bool = True
    branch_switch: bool = False
    land: bool = True
    linear_solver: str | None = None
    critical_tol: float = _opt(1e-3, 0.0, 1.0, True)

    def __post_init__(self):
        if self.method not in ("crisfield", "riks"):
            raise OptionError(f"ArcLengthOptions.method must be 'crisfield' or 'riks', got {self.method!r}")
        _check(self)
        _check_lengths(self)


def _real(v):
    return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)


def _check_lengths(o):
    """dlam0 a finite non-zero number (its sign the direction), ds_max and ds_min None or finite
    and positive, ds_min <= ds_max.  Before, dlam0 = 0 failed after 13 rejections as a 'path
    reversal', NaN as a load's NaN scale, ds_max = -1 turned every step after the first back
    (lam_end = 1 never reached: 200 steps down to -0.38), and a negative or NaN ds_min was taken."""
    if not _real(o.dlam0) or o.dlam0 == 0:
        raise OptionError(f"ArcLengthOptions.dlam0 must be a finite non-zero number (the load factor of the first "
                          f"predictor, its sign the direction), got {o.dlam0!r}")
    for name in ("ds_max", "ds_min"):
        v = getattr(o, name)
        if v is not None and not (_real(v) and v > 0):
            raise OptionError(f"ArcLengthOptions.{name} must be None or a finite arc length > 0, got {v!r}")
    if o.ds_max is not None and o.ds_min is not None and o.ds_min > o.ds_max:
        raise OptionError(f"ArcLengthOptions.ds_min = {o.ds_min!r} exceeds ds_max = {o.ds_max!r}")


def split_options(cls, options, kwargs):
    """(options of type ``cls`` with the keyword overrides that are its fields, the other
    keywords): ``newton_solve(p, steps=3, rtol=1e-12)`` and ``newton_solve(p, steps=3,
    options=NewtonOptions(rtol=1e-12))`` mean the same."""
    names = {f.name for f in fields(cls)}
    mine = {k: kwargs.pop(k) for k in list(kwargs) if k in names}
    base = options if options is not None else cls()
    if not isinstance(base, cls):
        raise OptionError(f"options must be a {cls.__name__}, got {type(base).__name__}")
    return (replace(base, **mine) if mine else base), kwargs


def unknown_keywords(func, kwargs, known):
    """OptionError naming the first keyword that neither ``func`` nor its options take."""
    if kwargs:
        k = next(iter(kwargs))
        raise OptionError(f"{func}() got an unknown option {k!r}{did_you_mean(k, known)}")


def load_steps(steps):
    """A number of load steps as an int: a whole number >= 1 (3.0 is accepted), else OptionError.

    Example
    -------
    >>> load_steps(4), load_steps(3.0)
    (4, 3)
    >>> load_steps(2.5)
    Traceback (most recent call last):
    ...
    core_se3.errors.OptionError: the number of load steps must be a whole number >= 1, got 2.5
    """
    if (isinstance(steps, bool) or not isinstance(steps, numbers.Real) or not float(steps).is_integer()
            or steps < 1):
        raise OptionError(f"the number of load steps must be a whole number >= 1, got {steps!r}")
    return int(steps)

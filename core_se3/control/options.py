"""The controls of a control session (:class:`ControlOptions`), held once.

Example
-------
>>> ControlOptions().max_iter, ControlOptions(max_splits=4).max_splits, ControlOptions(factor_cost=None).factor_cost
(16, 4, None)
>>> ControlOptions(path_tolerance=-1.0)
Traceback (most recent call last):
...
core_se3.errors.OptionError: ControlOptions.path_tolerance must be in (0, inf), got -1.0
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ..errors import OptionError

__all__ = ["ControlOptions"]

# field -> (low, high, open interval)
_RANGES = dict(rtol=(0.0, 1.0, True), dtol=(0.0, 1.0, True), max_iter=(1, 1000, False),
               max_factorizations=(1, 100, False), max_splits=(0, 50, False), anderson=(0, 50, False),
               max_turn=(0.0, np.pi, True), path_tolerance=(0.0, np.inf, True),
               factor_cost=(0.0, np.inf, False))
# fields where None is a setting: factor_cost None prices a factorisation at its measured time
# (before, the test above looked at the default, 6, and refused the None the docs describe)
_NONE = ("factor_cost", "max_factorizations")


@dataclass(frozen=True)
class ControlOptions:
    """Controls of a session's warm updates (``control.Session``).

    Attributes
    ----------
    rtol, dtol : float
        The convergence test of the solver (``solvers.convergence``): relative residual
        <= max(rtol, round-off floor) and last increment <= dtol ell; with the held (modified
        Newton) factorisation also the error left after it, dn c / (1 - c) <= dtol (c the
        observed contraction).  Default 1e-10 each, as ``NewtonOptions``.
    max_iter : int
        Iterations (back-substitutions) on the held factors per try of a sub-step (default 16:
        on the gripper an iteration costs about a sixth of a factorisation and its tangent);
        beyond it, or when an increment is longer than the predictor (divergence), the
        sub-step starts again with the tangent factored at its start, or, if the held factors
        were made there, is split.
    anderson : int
        Memory of the Anderson acceleration of the corrector (``control.corrector``; default 5,
        0: plain modified Newton).
    max_factorizations : int or None
        Fresh factorisations a sub-step may make (the escalations of ``control.corrector``: the
        tangent at the predicted state, at the sub-step's start, and one per iteration of the
        Newton try); a sub-step that would need more fails and is split.  None (default): no
        limit beyond the ladder's own, 2 + ``max_iter``.  (Before, the option was documented
        with a default of 3 and never read: the gripper's 5 x field step made 16 factorisations
        in 11 sub-steps whatever it was set to.)
    max_splits : int
        Halvings of a command change before the command is refused (default 10).
    max_turn : float
        The largest rotation [rad] of a node that one predictor may make (default 0.5): a
        longer step is split before it is tried.
    path_tolerance : float
        A sub-step whose converged increment differs from its predictor by more than this
        fraction of the predictor left the path (default 0.5): it is tried again with a fresh
        factorisation at its start, then split; refused after ``max_splits``.
    factor_cost : float or None
        The price of a tangent and its factorisation, in corrector iterations, for the
        refactorisation rule (``control.corrector``: the held factors are renewed at a
        converged state once the iterations they cost beyond their first update's count add
        up to it).  A number (default 6: measured 5 with the NumPy backend and 8 with numba on
        the gripper, benchmarks/results/control.md): that fixed price, the same schedule and the
        same states bit for bit on every machine; None: the ratio of the two times measured as
        the session runs (adapts to the machine, but the schedule, and the states' last bits,
        then vary from run to run); inf: never renewed for ageing alone.
    stability_check : bool
        True: every update factors the tangent at its converged state (one more factorisation
        per update, unless the factors were renewed there) and refuses a state whose det K
        has another sign than at the last accepted state where it is known (the start at
        first) -- a critical point crossed, e.g. a bifurcation, which the path test does not
        see (the path goes on smoothly) -- or whose tangent is singular (a critical point
        there).
        False (default): that check runs where factors are made at a converged state anyway:
        a renewal, and every :meth:`Session.jacobian` (which ``track`` takes every cycle).
    linear_solver : str or None
        None: the problem's.

    Example
    -------
    >>> ControlOptions(rtol=1e-12).rtol
    1e-12
    """
    rtol: float = 1e-10
    dtol: float = 1e-10
    max_iter: int = 16
    max_factorizations: int | None = None
    anderson: int = 5
    max_splits: int = 10
    max_turn: float = 0.5
    path_tolerance: float = 0.5
    factor_cost: float | None = 6.0
    stability_check: bool = False
    linear_solver: str | None = None

    def __post_init__(self):
        if not isinstance(self.stability_check, (bool, np.bool_)):
            raise OptionError(f"ControlOptions.stability_check must be true or false, got {self.stability_check!r}")
        for f in fields(self):
            if f.name not in _RANGES:
                continue
            v = getattr(self, f.name)
            if v is None and f.name in _NONE:
                continue
            lo, hi, open_ = _RANGES[f.name]
            whole = f.type in ("int", "int | None")
            ok = isinstance(v, (int, np.integer) if whole else (int, float, np.floating, np.integer)) and \
                not isinstance(v, bool) and ((lo < v < hi) if open_ else (lo <= v <= hi))
            if not ok:
                br = "()" if open_ else "[]"
                raise OptionError(f"ControlOptions.{f.name} must be in {br[0]}{lo:g}, {hi:g}{br[1]}, got {v!r}")

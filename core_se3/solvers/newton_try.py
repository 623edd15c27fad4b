"""One Newton try of load stepping (``solvers.newton``): Newton at a fixed load factor from a
start state, with the optional hooks of the loads (docs/CONTACT.md):

* a refused start: loads overriding ``Load.start_error`` may refuse the start state of a try
  (contact: an obstacle that moved deep into the shell over the increment), which is cut back;
* a step cap: loads overriding ``Load.limit_increment`` scale each increment by the smallest
  factor they return (contact: a node the linearisation does not see must not land deep inside
  an obstacle);
* augmentation: loads overriding ``Load.update_multipliers`` are asked, once a try converged,
  for their constraint error over its tolerance; while it exceeds 1 they have augmented their
  multipliers and :func:`augmented_try` solves the same load factor again from the converged
  state (Uzawa), each solve a try of its own in the log.

Without such loads the iteration is the plain one, operation for operation.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..errors import ElementTooDistortedError, SingularSystemError
from ..model.base import overrides
from .convergence import relative_residual, scaled_norm
from .linalg import Factorization

__all__ = ["NewtonTry", "TryOutcome", "augmented_try", "hooked_loads"]


def hooked_loads(problem, hook):
    """The loads of ``problem`` whose class overrides the Load hook ``hook``.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
    >>> p.add_edge_force("x1", (0.0, 0.0, 1.0)); c = p.add_obstacle("sphere", centre=(0.5, 0, 1.0), radius=0.5)
    >>> [ld.kind for ld in hooked_loads(p, "update_multipliers")]
    ['contact']
    """
    return [ld for ld in problem.loads if overrides(ld, hook)]


@dataclass
class TryOutcome:
    """What a Newton try ended with.

    Attributes
    ----------
    ok : bool
        Converged; ``reason``: why not.
    g : (n, 4, 4) ndarray
        The last iterate; ``ev``: its Evaluation.
    hist : list of float
        Relative residual of every iteration; ``solves``: linear solves.
    eta_sum : ndarray or float
        Sum of the applied increments (n, 6); ``k_step``, ``pred``: the first iterate's
        stiffness estimate and increment norm (the limit-point check).

    Example
    -------
    >>> TryOutcome(True, "", None, None, [1.0, 1e-12], 1).iterations
    1
    """
    ok: bool
    reason: str
    g: object
    ev: object
    hist: list
    solves: int
    eta_sum: object = 0.0
    k_step: float | None = None
    pred: float | None = None

    @property
    def iterations(self):
        return max(len(self.hist) - 1, 0)


class NewtonTry:
    """Newton iterations at one load factor (the body of ``newton_steps``' tries).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem; ``opts``: NewtonOptions; ``solver``: a linear solver (``make_solver``).
    timer : object
        Accumulates ``t_asm`` and ``t_sol`` [s] (attributes).

    Attributes
    ----------
    first_solve : bool
        True until the first linear solve of the path (its singular tangent is an error).

    Example
    -------
    >>> import types
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.solvers import NewtonOptions, make_solver
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.1))
    >>> t = NewtonTry(p, NewtonOptions(), make_solver("auto"), types.SimpleNamespace(t_asm=0.0, t_sol=0.0))
    >>> out = t.run(p.mesh.g0.copy(), 1.0, False, None)
    >>> out.ok, out.iterations <= 5
    (True, True)
    """

    def __init__(self, problem, opts, solver, timer):
        self.problem, self.opts, self.solver, self.timer = problem, opts, solver, timer
        self.asm = problem.assembler()
        self.ell = problem.length_scale
        self.stateful = problem.element.stateful
        self.first_solve = True
        self.caps = hooked_loads(problem, "limit_increment")
        self.starts = hooked_loads(problem, "start_error")

    def run(self, g_try, lam_try, mip, stress):
        """Iterate from g_try at lam_try (mip: the mixed iteration from the stresses ``stress``);
        returns a :class:`TryOutcome`.  A singular tangent at the first solve of the path raises."""
        problem, opts, asm, ell, timer = self.problem, self.opts, self.asm, self.ell, self.timer
        for ld in self.starts:
            why = ld.start_error(g_try, lam_try)
            if why:
                return TryOutcome(False, why, g_try, None, [], 0)
        hist = []
        dn = np.inf
        eta_sum = 0.0
        k_step = pred = None
        ok = False
        reason = ""
        solves = 0
        ev = None
        mip_try = mip
        try:
            for it in range(opts.max_iter + 1):
                ta = time.perf_counter()
                # after an increment below dtol the state has likely converged: check the
                # residual first and build the tangent only if it has not
                likely = it > 0 and dn <= opts.dtol
                ev = problem.evaluate(g_try, lam_try, tangent=not likely,
                                      stress=stress if mip_try and not likely else None)
                rf = ev.r
                if not np.all(np.isfinite(rf)):
                    raise FloatingPointError("non-finite residual")
                rn, floor = relative_residual(asm, ev, ell)
                hist.append(rn)
                if it > 0 and rn <= max(opts.rtol, floor) and dn <= opts.dtol:
                    ok = True
                    timer.t_asm += time.perf_counter() - ta
                    break
                if it == opts.max_iter:
                    reason = f"no convergence in {opts.max_iter} iterations (residual {rn:.2e})"
                    timer.t_asm += time.perf_counter() - ta
                    break
                if it > 3 and rn > opts.divergence * max(hist[0], 1e-300):
                    reason = f"diverging (residual {rn:.2e})"
                    timer.t_asm += time.perf_counter() - ta
                    break
                if likely:
                    ev = problem.evaluate(g_try, lam_try, tangent=True, stress=stress if mip_try else None)
                    rf = ev.r
                timer.t_asm += time.perf_counter() - ta
                ts = time.perf_counter()
                try:
                    with Factorization(ev.K, self.solver) as fac:
                        x = fac.solve(-rf)
                        if self.first_solve:
                            fac.probe()
                except SingularSystemError as exc:
                    if self.first_solve:
                        raise SingularSystemError(
                            f"{exc}: the tangent of the unloaded shell is singular -- a rigid-body "
                            "motion is not restrained (missing or insufficient supports)") from None
                    raise
                timer.t_sol += time.perf_counter() - ts
                solves += 1
                self.first_solve = False
                eta = asm.scatter(x)
                if it == 0:
                    work = -float(rf @ x)
                    k_step = scaled_norm(asm.scatter(rf), ell) ** 2 / work if work > 0 else -np.inf
                    pred = scaled_norm(eta, ell, moment=False)
                    # guard: a first increment doing negative work starts past an
                    # instability, where the mixed iteration's reach can carry it onto
                    # another equilibrium; iterate that try on the displacements
                    mip_try = mip_try and work > 0
                if self.caps:
                    alpha = min(ld.limit_increment(g_try, eta, lam_try) for ld in self.caps)
                    if alpha < 1.0:
                        eta = alpha * eta
                eta_sum = eta_sum + eta
                dn = scaled_norm(eta, ell, moment=False) / ell
                if mip_try:
                    # the mixed update: stresses linear in the increment (no membrane
                    # overshoot of Dbar (z(g exp eta) - z0) in the geometric stiffness)
                    stress = problem.linear_stress(ev, eta)
                g_try = problem.retract(g_try, eta)
                if self.stateful:
                    problem.element.update(eta)
        except SingularSystemError as exc:
            if self.first_solve:
                raise
            reason = str(exc)
        except (ElementTooDistortedError, FloatingPointError) as exc:
            reason = str(exc)
        return TryOutcome(ok, reason, g_try, ev, hist, solves, eta_sum, k_step, pred)


def augmented_try(trier, aug, g_try, lam_try, mip, stress, max_augmentations, record):
    """A try with the multiplier updates of the loads ``aug`` (module docstring): after each
    converged solve, solve again from it while a load reports a constraint error above its
    tolerance, at most ``max_augmentations`` times; ``record(outcome, augmentation)`` logs each
    intermediate solve.  Returns the last :class:`TryOutcome` (its eta_sum the sum over the
    solves, k_step and pred the first's); a failure is an outcome with ``ok`` False.

    Example
    -------
    >>> import types
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.solvers import NewtonOptions, make_solver
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e4, 0.0, 0.02))
    >>> p.clamp("x0"); p.add_pressure(-0.004)
    >>> c = p.add_obstacle("half_space", point=(0, 0, -0.05), normal=(0, 0, 1))
    >>> t = NewtonTry(p, NewtonOptions(), make_solver("auto"), types.SimpleNamespace(t_asm=0.0, t_sol=0.0))
    >>> seen = []
    >>> out = augmented_try(t, [c], p.mesh.g0.copy(), 1.0, False, None, 25, lambda o, k: seen.append(k))
    >>> out.ok, len(seen) > 0, bool(c.gap_error <= c.tol)
    (True, True, True)
    """
    out = trier.run(g_try, lam_try, mip, stress)
    n_aug = 0
    while out.ok and aug:
        ratio = max(ld.update_multipliers(out.g, lam_try) for ld in aug)
        if ratio <= 1.0:
            break
        if n_aug >= max_augmentations:
            out.ok = False
            out.reason = (f"constraint error {ratio:.3g} x its tolerance after {max_augmentations} "
                          "multiplier updates (raise NewtonOptions.max_augmentations or the tolerance)")
            break
        n_aug += 1
        record(out, n_aug)
        first = out
        out = trier.run(out.g, lam_try, mip, out.ev.stress if mip else None)
        out.eta_sum = out.eta_sum + first.eta_sum
        out.k_step, out.pred = first.k_step, first.pred
    return out

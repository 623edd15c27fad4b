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
from dataclasses import dataclass, field

import numpy as np

from .. import lie
from ..assembly import Assembler
from ..errors import ElementTooDistortedError, LinearSolverError, SingularSystemError
from ..model.base import overrides
from .equations import NewtonEquations
from .linalg import Factorization
from .step_checks import path_measures

__all__ = ["NewtonTry", "TryOutcome", "augmented_try", "hooked_loads", "tangent_predictor"]


def hooked_loads(problem, hook):
    """The loads of ``problem`` (a Problem, or the equations of ``solvers.equations``) whose
    class overrides the Load hook ``hook``.

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
    floor : float
        The round-off floor of the relative residual at the last iterate
        (``solvers.convergence.relative_residual``; 0 when not evaluated).
    incs : list of float
        |eta|_s / ell of every applied correction; ``contraction`` and ``travel`` their measures
        of ``solvers.step_checks.path_measures`` (the largest over the solves of an augmented try).
    det_sign : int or None
        Sign of det K of the last factorised tangent (at the converged state up to the last
        correction), when :attr:`NewtonTry.signs` asks for it.

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
    floor: float = 0.0
    incs: list = field(default_factory=list)
    det_sign: int | None = None
    count: int | None = None          # negative eigenvalues of sym K (inertia_check; set by the caller)
    probe: object = None              # the midpoint probe's TryOutcome (solvers.step_checks; set by the caller)

    @property
    def contraction(self):
        return max(m[0] for m in self.measures)

    @property
    def travel(self):
        return max(m[1] for m in self.measures)

    def __post_init__(self):
        self.measures = [path_measures(self.incs)]

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
    equations : optional
        What the iterations evaluate and solve (``solvers.equations``; default the problem's
        :class:`~core_se3.solvers.equations.NewtonEquations` on this process).

    Attributes
    ----------
    first_solve : bool
        True until the first linear solve of the path (its singular tangent is an error).
    signs : bool
        Find the sign of det K of the last factorised tangent of a converged try (default
        False): ``solvers.step_checks``' stability check.

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

    def __init__(self, problem, opts, solver, timer, equations=None):
        self.problem, self.opts, self.solver, self.timer = problem, opts, solver, timer
        self.eq = equations or NewtonEquations(problem, solver)
        self.ell = problem.length_scale
        self.stateful = self.eq.stateful
        self.first_solve = True
        self.signs = False
        self.caps = hooked_loads(self.eq, "limit_increment")
        self.starts = hooked_loads(self.eq, "start_error")

    def run(self, g_try, lam_try, mip, stress):
        """Iterate from g_try at lam_try (mip: the mixed iteration from the stresses ``stress``);
        returns a :class:`TryOutcome`.  A singular tangent at the first solve of the path raises."""
        problem, opts, eq, ell, timer = self.problem, self.opts, self.eq, self.ell, self.timer
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
        floor = 0.0
        mip_try = mip
        incs = []
        try:
            for it in range(opts.max_iter + 1):
                ta = time.perf_counter()
                # after an increment below dtol the state has likely converged: check the
                # residual first and build the tangent only if it has not
                likely = it > 0 and dn <= opts.dtol
                ev, rn, floor = eq.evaluate(g_try, lam_try, tangent=not likely,
                                            stress=stress if mip_try and not likely else None)
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
                    ev, _, _ = eq.evaluate(g_try, lam_try, tangent=True, stress=stress if mip_try else None,
                                           norms=False)
                timer.t_asm += time.perf_counter() - ta
                x = self._solve(ev, g_try, lam_try)
                solves += 1
                eta = eq.increment(x)
                if it == 0:
                    work = eq.work(ev, x)
                    k_step = _current_stiffness(eq, ev, work, rn <= max(opts.rtol, floor))
                    pred = eq.increment_norm(eta)
                    # guard: a first increment doing negative work starts past an
                    # instability, where the mixed iteration's reach can carry it onto
                    # another equilibrium; iterate that try on the displacements
                    mip_try = mip_try and work > 0
                if self.caps:
                    alpha = min(ld.limit_increment(g_try, eta, lam_try) for ld in self.caps)
                    if alpha < 1.0:
                        eta = alpha * eta
                eta_sum = eta_sum + eta
                dn = eq.increment_norm(eta) / ell
                incs.append(dn)
                if mip_try:
                    # the mixed update: stresses linear in the increment (no membrane
                    # overshoot of Dbar (z(g exp eta) - z0) in the geometric stiffness)
                    stress = eq.linear_stress(ev, eta)
                g_try = eq.retract(g_try, eta)
                if self.stateful:
                    problem.element.update(eta)
        except SingularSystemError as exc:
            if self.first_solve and not isinstance(exc, _LoadedFirstTangent):
                raise
            reason = str(exc)
        except (ElementTooDistortedError, FloatingPointError) as exc:
            reason = str(exc)
        sign = eq.det_sign() if ok and self.signs and solves else None
        return TryOutcome(ok, reason, g_try, ev, hist, solves, eta_sum, k_step, pred,
                          0.0 if floor is None else float(floor), incs, sign)

    def _solve(self, ev, g_try, lam_try=0.0):
        """The Newton correction at the evaluation ``ev``; a singular tangent at the path's first
        solve is a SingularSystemError naming the unrestrained rigid-body motion -- or, when the
        tangent without the load (lam = 0) is regular, a failed try that is cut back
        (:class:`_LoadedFirstTangent`, :meth:`_loaded_singularity`)."""
        ts = time.perf_counter()
        try:
            x = self.eq.solve(ev, g_try, probe=self.first_solve)
        except SingularSystemError as exc:
            if self.first_solve and not isinstance(exc, LinearSolverError):
                loaded = self._loaded_singularity(g_try, lam_try)
                if loaded:
                    raise _LoadedFirstTangent(loaded) from None
                raise SingularSystemError(
                    f"{exc}: the tangent of the unloaded shell is singular -- a rigid-body "
                    "motion is not restrained (missing or insufficient supports)") from None
            raise
        self.timer.t_sol += time.perf_counter() - ts
        self.first_solve = False
        return x

    def _loaded_singularity(self, g_try, lam_try):
        """The reason of a first tangent singular under the load factor ``lam_try`` only (its
        lam = 0 tangent at the same state solves), else ''.

        Off equilibrium the left-trivialised tangent carries 1/2 ad* of the residual, here the
        whole first increment of the load: a clamped strip under an end compression P has a
        singular start tangent at P = 2 EI/L^2 on any mesh, where the straight strip is stable
        (Euler's load is pi^2 EI/(4 L^2)).  That is a property of the try's first Newton
        iterate, not of the path (the path's critical points are the stability checks'), so the
        try fails and the increment is cut back.  Before, the run stopped, calling the load a
        critical (buckling) load of the start state (and, earlier, a missing support).
        """
        if lam_try == 0.0:
            return ""
        ev0, _, _ = self.eq.evaluate(g_try, 0.0, tangent=True)
        try:
            self.eq.solve(ev0, g_try, probe=True)
        except SingularSystemError:
            return ""
        return (f"the first Newton tangent of the step (at its start state, under load factor {lam_try:.6g}) "
                "is singular, but not without the load: a property of this increment's first iterate "
                "(off equilibrium the tangent carries 1/2 ad* of the residual), not a critical point of "
                "the path; the increment is cut back. If the cut-backs run out: take another first step "
                "(steps, or a first load factor off it)")


class _LoadedFirstTangent(SingularSystemError):
    """The first tangent of a path is singular under the try's load increment only (regular
    without the load): a failed try, cut back like one that did not converge
    (:meth:`NewtonTry._loaded_singularity`)."""


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
        out.measures += first.measures
    return out


def tangent_predictor(problem, g, lam, lam_try, solver, mip, caps=()):
    """The start of a try from the converged state (g, lam) to lam_try along the tangent,
    prescribed increments included (``NewtonOptions.predictor = "tangent"``): with xi_p the
    increments of the prescribed dofs (the body translation R^T (phi_1 - phi_0) of a
    translation-only target, log(g^-1 g_1) otherwise), the free dofs solve

        K_ff eta_f = -r_f(g, lam_try) - K_fp xi_p,

    so that a prescribed edge takes the shell with it instead of leaving a kink in its first
    elements; the increment is capped by the loads' ``limit_increment`` (contact).  Returns
    (g_start, stresses of the mixed iteration at the start or None).

    Example
    -------
    A strip whose end x1 is lifted by 0.1: the predicted start bends the whole strip.

    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.solvers import make_solver
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> g1 = p.mesh.g0[p.mesh.node_set("x1")].copy()
    >>> lift = np.zeros((4, 4)); lift[2, 3] = 0.1             # the translation's z component
    >>> p.clamp("x0"); p.prescribe("x1", lambda lam: g1 + lam * lift)
    >>> g, _ = tangent_predictor(p, p.mesh.g0, 0.0, 1.0, make_solver("auto"), False)
    >>> bool(0.0 < g[4, 2, 3] < 0.1)                   # the mid-span node moved up
    True
    """
    n = problem.mesh.n_nodes
    g1 = problem.apply_prescribed(g.copy(), lam_try)
    xi = np.zeros((n, 6))
    for s in problem.supports:
        if s.target is None:
            continue
        a, b = g[s.nodes], g1[s.nodes]
        if s.fixed[:3].all() and not s.fixed[3:].any():
            x = np.zeros((len(s.nodes), 6))
            x[:, :3] = np.einsum("kji,kj->ki", a[:, :3, :3], b[:, :3, 3] - a[:, :3, 3])
        else:
            x = lie.log(lie.relative(a, b))
        xi[s.nodes] = np.where(s.fixed, x, 0.0)
    full = Assembler(problem.mesh, np.ones(6 * n, bool))
    ev = problem.evaluate(g, lam_try, tangent=True, assembler=full)
    free = problem.assembler().free
    K = ev.K.tocsr()
    rhs = -(ev.r[free] + K[free][:, ~free] @ xi.ravel()[~free])
    with Factorization(K[free][:, free].tocsr(), solver) as fac:
        x = fac.solve(rhs)
    eta = xi.ravel().copy()
    eta[free] = x
    eta = eta.reshape(n, 6)
    alpha = min([ld.limit_increment(g, eta, lam_try) for ld in caps] + [1.0])
    eta = alpha * eta
    stress = problem.linear_stress(ev, eta) if mip else None
    return problem.apply_prescribed(problem.retract(g, eta), lam_try), stress


def _current_stiffness(eq, ev, work, balanced):
    """Bergan's current stiffness k = |r_0|^2 / (r_0 . eta_0) of a try's first iterate (-inf for
    work <= 0), or None when its start is already in balance (``balanced``: a load that does not
    change over the try), whose residual is round-off and whose k is noise: a tip force held
    after a jump gave S_p from 0.8 to 1.1e6 by the ranks' round-off, and the midpoint probe's
    limit-point extrapolation fired on some of them (tests/test_parallel.py)."""
    if balanced:
        return None
    return eq.residual_sq(ev) / work if work > 0 else -np.inf

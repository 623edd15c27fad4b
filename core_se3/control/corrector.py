"""The warm corrector of a control session: the problem's equilibrium equations, one held
factorisation of the free tangent, and one sub-step of an update.

Predictor.  At a converged state r(g; p) = 0, new parameters p + dp (design variables, load
factor) leave the residual r(g; p + dp) = (dr/dp) dp + O(dp^2) -- exactly (dr/dp) dp for the
field, the magnetisation and load magnitudes, in which r is linear.  The first increment on the
held factors, K eta = -r(g; p + dp), is therefore the direct method's tangent predictor
eta = S dp (``design.sensitivity``: K S = -dr/dp), in one back-substitution and without forming
dr/dp; the residual's evaluation is the only other work.

Corrector.  Modified Newton, f_k = -K_F^-1 r(g_k) on the held factors K_F: a fixed-point
iteration that contracts by about |I - K_F^-1 K(g_k)| per iteration, each iteration a residual
and a back-substitution, while a Newton iteration costs a tangent and a factorisation (on the
gripper about six back-substitutions with their residuals).  Anderson acceleration (memory
``anderson``) mixes the last increments; it matters for the longer steps, whose rate the thin
shell's stiff membrane part slows.  The convergence test is the solver's
(``solvers.convergence``), at the state returned: its relative residual <= max(rtol, round-off
floor), and the increment that would leave it <= dtol ell (and shrinking: the error estimate of
a contracting iteration) -- the solver takes the increment that led to its state instead.

Secant memory.  The pairs of increments Anderson records are secant information on the
chord's error operator I - K_F^-1 K(g), which changes little while the state stays near where
they were recorded; a control loop's small steps keep coming back to the same region.  So the
mixer of a try on the same factors as the last one, when that try moved the nodes by at most
``CARRY_MOVE`` ell (root-mean-square), keeps its pairs (a new sequence of iterates: no pair
joins the last update's final state to the new predictor), and the predictor itself is mixed
with them (a secant correction of the held factors' error in it).  Measured on the gripper
(CPU time per update, benchmarks/results/control.md's commands): 0.1 % field steps 1.50 ->
1.23 ms with numba and 4.33 -> 3.62 ms with NumPy (no renewals needed: the iterations stop
growing as the factors age), 1 % steps 2.20 -> 2.00 ms; on 4x the elements 0.1 % steps 5.0 ->
3.75 ms.  Longer steps (5 %: 3.5e-4 ell) start with a new mixer: pairs from that far away
made more first corrections stale (0.48 instead of 0.29 factorisations per update).  The
convergence and path tests are unchanged: only the iterates' path differs.

Escalation.  When the held factors were made at another state (an earlier update, other
parameters) and their first correction is more than ``STALE`` of the predictor (but shorter
than it), the tangent is factored where the iteration stands -- the predicted state, nearer the
solution than the start -- and the iteration goes on from there (a restart from the start on
its tangent, as before, wasted the predictor's two iterations and kept the start's distance
from the solution in the factors' error: on the gripper's 5 % field steps 10.33 instead of
10.62 iterations and 0.21 instead of 0.29 factorisations per update).  When they diverge or do
not converge in ``max_iter`` iterations, the sub-step starts again with the tangent factored at
its start (and the new parameters); if that fails too, the solver's own Newton try runs from the
start (``solvers.newton_try``: a fresh tangent at every iterate, the mixed iteration), which
reaches further; only then does the sub-step fail.

Refactorisation.  The held factors age as the commands move the state away from where they
were made: the chord iteration contracts more slowly and an update takes more iterations than
the first update on them took.  After each update the session counts the iterations beyond that
first count, priced at the measured time of an iteration, and when their total exceeds the
measured time of a tangent and its factorisation it factors the tangent at the converged state
(:meth:`Corrector.settle`): the rule of ski rental (pay rent until it adds up to the price of
buying), which costs at most twice the best schedule in hindsight.  Small steps about one state
keep their factors; a drift away from it renews them every so often (on the gripper, 0.3 % field
steps drifting 4.5 %, priced at 2 iterations: 3 renewals, 86 instead of 89 iterations; 0.1 %
steps drifting 1.5 % need none since the secant memory below: 74 iterations, was 71 with 3
renewals and 90 without).  ``ControlOptions.factor_cost``
fixes the price in iterations instead of measuring it.  A renewal that fails (a singular
tangent) keeps the held factors.

Path.  A sub-step fails (and the session splits the command) when the predictor turns a node by
more than ``max_turn``, neither corrector converges, the tangent is singular, an element is
distorted, or the converged increment differs from the predictor by more than
``path_tolerance`` times the predictor (with factors made at the start): on a smooth path that
difference is O(dp) relative, so halving the step makes it pass; a jump to another branch (a
snap past a limit point) does not shrink with the step, and the command is refused.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from .. import backend
from ..errors import ElementTooDistortedError, SingularSystemError
from ..solvers import Factorization, NewtonOptions, make_solver
from ..solvers.convergence import increment_norm, relative_residual
from ..solvers.newton_try import NewtonTry

__all__ = ["Corrector", "SubStep", "STALE", "RESIDUAL_SHARE"]

# a first correction longer than this fraction of the predictor, on factors made at another
# state, starts the sub-step again with the tangent factored at its start (a stale predictor;
# 0.2 cost least on the gripper's 1 % and 5 % field steps, counting a factorisation with its
# tangent as 6 or 12 iterations, against 0.05, 0.5 and 1)
STALE = 0.2
# what numba saves on one residual evaluation, as a share of what it saves on a Newton iteration
# (the 'auto' rule's unit, ``backend.iteration_saving``): on the gripper 0.83 of 2.8 ms
RESIDUAL_SHARE = 0.3
# the Anderson pairs of the last try are carried into the next on the same factors while that
# try moved the nodes by at most this root-mean-square length / ell (module docstring): on the
# gripper (and on 4x its elements) 0.1 % and 1 % field steps move 7e-5 ell and gain (5 % steps,
# 3.5e-4 ell, lose: pairs recorded that far away mislead the predictor)
CARRY_MOVE = 1.5e-4


@dataclass
class SubStep:
    """The outcome of one sub-step of an update.

    Attributes
    ----------
    ok : bool
        Converged (and stayed on the path); ``reason``: why not.
    g : (n, 4, 4) ndarray
        The converged frames (the start when not ok).
    iterations : int
        Back-substitutions (the predictor's included); ``factorizations``: fresh ones.
    history : list of float
        The relative residual at every iterate.
    predictor : (n, 6) ndarray or None
        The first increment of the held factors' try; ``fatal``: the step is too long whatever
        the factors (a predictor turning nodes too far, a path test failed on fresh factors).
    residual : (nfree,) ndarray or None
        The free residual at the converged state (the next sub-step's start).

    Example
    -------
    >>> SubStep(False, None, "why").reason
    'why'
    """
    ok: bool
    g: np.ndarray
    reason: str = ""
    iterations: int = 0
    factorizations: int = 0
    history: list = field(default_factory=list)
    predictor: np.ndarray = None
    fatal: bool = False
    residual: np.ndarray = None


class Corrector:
    """The equations of ``problem`` with one held factorisation (module docstring).

    Attributes
    ----------
    F : core_se3.solvers.Factorization or None
        The held factors; ``F_g``, ``F_stamp``: the frames and the parameter stamp they were
        made at.
    counts : dict
        Residual evaluations, factorisations and back-substitutions so far.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.control import ControlOptions
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.1))
    >>> c = Corrector(p, ControlOptions())
    >>> out = c.step(p.mesh.g0, 1.0, check_path=False)      # Newton from the flat strip
    >>> out.ok, c.counts["factorizations"] >= 1
    (True, True)
    """

    def __init__(self, problem, options):
        self.problem, self.opts = problem, options
        self.asm = problem.assembler()
        self.ell = problem.length_scale
        self.solver = make_solver(options.linear_solver or problem.linear_solver)
        self.auto = problem.backend_setting == "auto"
        self.F = self.F_g = self.F_stamp = None
        self._checked = False
        self.counts = dict(residuals=0, factorizations=0, solves=0)
        # the refactorisation rule (module docstring): measured seconds of an iteration and of a
        # factorisation (running means), the iterations of the first update on the held factors
        # (of its last try) and the time spent beyond them since the factors were made
        self.cost = dict(iteration=None, factorization=None)
        self._base, self._waste, self._last_try = None, 0.0, 0
        self._mix = None                # (the factors, the Anderson mixer on them)
        self._t_factor = 0.0            # seconds spent factoring so far
        self._moved = np.inf            # the rms nodal move / ell of the last converged try

    def close(self):
        """Release the held factors."""
        if self.F is not None:
            self.F.close()
        self.F = self.F_g = self.F_stamp = None

    def residual(self, g, lam):
        """(free residual, relative residual, its round-off floor) at (g, lam)."""
        ev = self.problem.evaluate(g, lam, tangent=False)
        self.counts["residuals"] += 1
        if self.auto and self.problem.backend == "numpy":
            # the 'auto' rule counts tangents (Newton's iterations); a session's work is residuals
            backend.charge(self.problem.mesh.n_elements, RESIDUAL_SHARE)
        if not np.all(np.isfinite(ev.r)):
            raise FloatingPointError("non-finite residual")
        rn, floor = relative_residual(self.asm, ev, self.ell)
        return ev.r, rn, floor

    def factor(self, g, lam, stamp=None, keep=False):
        """Evaluate the tangent at (g, lam) and hold its factors (SingularSystemError if singular);
        ``stamp`` names the parameters it was made with (``Session`` checks it).  ``keep``: the
        held factors stay if the new ones cannot be made (else they are released first, which
        lets MUMPS reuse its analysis)."""
        t0 = time.perf_counter()
        K = self.problem.evaluate(g, lam, tangent=True).K
        if keep:
            F = Factorization(K, self.solver)
            self.close()
            self.F = F
        else:
            self.close()
            self.F = Factorization(K, self.solver)
        self.F_g, self.F_stamp, self._checked = g, stamp, False
        self.counts["factorizations"] += 1
        self._measured("factorization", time.perf_counter() - t0)
        self._t_factor += time.perf_counter() - t0
        self._base, self._waste = None, 0.0

    def _measured(self, what, seconds):
        """Fold a measured time into the running mean of ``cost[what]``."""
        old = self.cost[what]
        self.cost[what] = seconds if old is None else 0.8 * old + 0.2 * seconds

    def settle(self, g, lam, stamp, iterations):
        """After an update that ended at (g, lam) in ``iterations`` back-substitutions: factor the
        tangent there when the iterations beyond the count of the first update on the held
        factors have cost, since the factors were made, more than a factorisation (module
        docstring); True if it did."""
        if self.F is None or self.F_g is g:
            return False
        if self._base is None:                    # the first update on these factors
            self._base = self._last_try
            return False
        if self.opts.factor_cost is None:           # measured: seconds
            it, fa = self.cost["iteration"] or 0.0, self.cost["factorization"]
        else:                                       # a fixed price: iterations
            it, fa = 1.0, self.opts.factor_cost
        self._waste += max(0, iterations - self._base) * it
        if fa is None or self._waste <= fa:
            return False
        try:
            self.factor(g, lam, stamp, keep=True)
        except (SingularSystemError, ElementTooDistortedError):
            self._waste = -np.inf                     # these factors stay (the next update escalates)
            return False
        return True

    def det_sign(self):
        """The sign of det K of the held factors (+1, -1; None without factors or when the
        linear solver cannot tell): its change between two converged states means a critical
        point (a bifurcation or limit point) lies between them."""
        if self.F is None:
            return None
        try:
            return self.F.det_sign()
        except (TypeError, AttributeError, NotImplementedError):      # a solver without the sign
            return None

    def increment(self, r, check=None):
        """(eta (n, 6), |eta|_s / ell) of K_F eta = -r (``check``: ``Factorization.solve``'s
        refinement and backward-error check; default at the first solve on new factors only:
        a singular tangent shows there, and the corrector tests its answers on the residual)."""
        if check is None:
            check, self._checked = not self._checked, True
        eta = self.asm.scatter(self.F.solve(-r, check=check))
        self.counts["solves"] += 1
        return eta, increment_norm(eta, self.ell)

    def step(self, g, lam, stamp=None, check_path=True, r0=None):
        """One sub-step from the frames g to the equilibrium at lam and the parameters assigned
        now (``stamp``); a :class:`SubStep` (module docstring: held factors, then factors made
        at g, then Newton with a fresh tangent at every iterate).  ``r0``: the free residual at
        (g, lam) and these parameters when the caller has it (``Session``: the last one plus
        its exact change), else it is evaluated."""
        nf = its = 0
        cap = self.opts.max_factorizations or np.inf       # fresh factorisations this sub-step may make
        try:
            if self.F is None:
                self.factor(g, lam, stamp)
                nf += 1
            fresh = self.F_g is g and self.F_stamp == stamp
            out = self._iterate(g, lam, check_path, fresh, stamp, r0, may_renew=nf < cap)
            its += out.iterations
            nf += out.factorizations
            if not out.ok and not out.fatal and not fresh and nf < cap:
                self.factor(g, lam, stamp)                     # stale factors: again with g's
                nf += 1
                out = self._iterate(g, lam, check_path, True, stamp, r0)
                its += out.iterations
                nf += out.factorizations
            if not out.ok and not out.fatal and nf < cap:
                out = self._newton(g, lam, out.predictor, check_path, int(min(cap - nf, self.opts.max_iter)))
                nf += out.factorizations
                its += out.iterations
            elif not out.ok and not out.fatal:
                out.reason += (f" (max_factorizations = {self.opts.max_factorizations} reached: no fresher "
                               "factors tried in this sub-step)")
            out.iterations, out.factorizations = its, nf
            return out
        except (SingularSystemError, ElementTooDistortedError, FloatingPointError) as exc:
            return SubStep(False, g, str(exc), its, nf)

    def _path_error(self, predictor, total, check_path):
        """The path test (module docstring): '' or the reason it failed."""
        pred = increment_norm(predictor, self.ell)
        dev = increment_norm(total - predictor, self.ell)
        if not check_path or dev <= max(self.opts.path_tolerance * pred, 10.0 * self.opts.dtol):
            return ""
        return (f"the corrector moved {dev / pred:.2g} x the predictor's length away from it (more than "
                f"path_tolerance = {self.opts.path_tolerance:g}): the equilibrium path turns sharply or the state "
                "snapped onto another branch")

    def _iterate(self, g, lam, check_path, fresh, stamp, r0=None, may_renew=True):
        """Predictor and corrector on the held factors: a SubStep (``fatal``: the step is too long
        whatever the factors; ``predictor``: the first increment; ``residual``: the free residual
        at the state returned)."""
        opts, ell = self.opts, self.ell
        t0 = time.perf_counter()
        t_factor = self._t_factor
        out = self._chord(g, lam, check_path, fresh, stamp, r0, may_renew)
        if out.iterations:
            spent = time.perf_counter() - t0 - (self._t_factor - t_factor)    # a renewal inside not counted
            self._measured("iteration", spent / out.iterations)
        if out.ok:
            self._last_try = out.iterations
        return out

    def _chord(self, g, lam, check_path, fresh, stamp, r0, may_renew=True):
        """:meth:`_iterate`'s work (its docstring)."""
        opts, ell = self.opts, self.ell
        if r0 is None:
            r, rn, _ = self.residual(g, lam)
        else:
            r, rn = r0, np.nan
        hist = [rn]
        eta, pred = self.increment(r)                  # the predictor: S dp (module docstring)
        turn = float(np.sqrt(np.max(np.einsum("ij,ij->i", eta[:, 3:], eta[:, 3:]))))
        if turn > opts.max_turn:
            return SubStep(False, g, f"the predictor turns a node by {turn:.3g} rad (more than max_turn = "
                           f"{opts.max_turn:g})", 1, history=hist, fatal=True)
        mixer = self._mixer()
        predictor = eta
        eta = mixer.step(eta)          # the predictor too: with carried pairs, a secant correction
        total = eta.copy()
        g1 = self.problem.retract(g, eta)
        its, fn_prev, renewed = 1, pred, fresh or not may_renew     # (may_renew: max_factorizations)
        while True:
            r, rn, floor = self.residual(g1, lam)
            hist.append(rn)
            f, fn = self.increment(r)
            its += 1
            # the solver's test, at the state returned: its relative residual, and the increment
            # that would leave it (the error estimate of a contracting iteration, or far below
            # dtol: at the round-off floor the increments no longer contract)
            if rn <= max(opts.rtol, floor) and fn <= opts.dtol and (fn <= 0.5 * fn_prev or fn <= 1e-3 * opts.dtol):
                break
            if not renewed and its == 2 and STALE * pred < fn <= pred:
                # stale factors: the tangent factored here, at the predicted state (nearer the
                # solution than the start), and the iteration goes on from it (module docstring)
                self.factor(g1, lam, stamp)
                renewed, mixer = True, self._mixer()
                f, fn = self.increment(r)
                its += 1
            why = ""
            if fn > pred:
                why = f"the corrector diverges: an increment {fn / pred:.3g} x the predictor's"
            elif its > opts.max_iter:
                why = (f"no convergence in max_iter = {opts.max_iter} iterations on the held factors (residual "
                       f"{rn:.2e}, increment {fn:.2e})")
            if why:
                made = int(renewed and not fresh and may_renew)
                return SubStep(False, g, why, its, made, history=hist, predictor=predictor)
            eta = mixer.step(f)
            g1 = self.problem.retract(g1, eta)
            total += eta
            fn_prev = fn
        why = self._path_error(predictor, total, check_path)
        self._moved = np.inf if why else increment_norm(total, ell) / (ell * np.sqrt(len(total)))
        return SubStep(not why, g1 if not why else g, why, its, int(renewed and not fresh and may_renew), history=hist,
                       predictor=predictor, fatal=bool(why) and fresh, residual=None if why else r)

    def _mixer(self):
        """The Anderson mixer of a try: the last try's, with its secant pairs, when it was on the
        same factors and moved the nodes by at most ``CARRY_MOVE`` ell (rms; module docstring),
        else a new one."""
        m = self._mix
        if m is None or m[0] is not self.F or not self._moved <= CARRY_MOVE:
            self._mix = (self.F, _Anderson(self.opts.anderson, self.ell))
        else:
            m[1].restart()
        self._moved = np.inf            # until this try converges
        return self._mix[1]

    def _newton(self, g, lam, predictor, check_path, max_iter):
        """Newton with a fresh tangent at every iterate (the solver's try, ``solvers.newton_try``,
        with its mixed iteration) from g, at most ``max_iter`` iterations: for the sub-steps the
        held factors do not carry."""
        nopts = NewtonOptions(rtol=self.opts.rtol, dtol=self.opts.dtol, max_iter=max_iter,
                              linear_solver=self.opts.linear_solver, limit_check=False)
        trial = NewtonTry(self.problem, nopts, self.solver, SimpleNamespace(t_asm=0.0, t_sol=0.0))
        trial.first_solve = False                      # a singular tangent fails the try
        mip = nopts.iteration == "mip" and self.problem.element.mixed
        stress = self.problem.evaluate(g, lam, tangent=False).stress if mip else None
        out = trial.run(g.copy(), lam, mip, stress)
        self.counts["factorizations"] += out.solves
        self.counts["residuals"] += len(out.hist)
        if not out.ok:
            return SubStep(False, g, f"Newton with a fresh tangent at every iterate failed: {out.reason}",
                           out.solves, out.solves, out.hist)
        why = self._path_error(predictor, out.eta_sum, check_path) if predictor is not None else ""
        return SubStep(not why, out.g if not why else g, why, out.solves, out.solves, out.hist,
                       residual=None if why or out.ev is None else out.ev.r)


class _Anderson:
    """Anderson acceleration (Walker and Ni 2011, SIAM J. Numer. Anal. 49) of the modified-Newton
    fixed point x <- x + f(x), f = -K_F^-1 r: the step f_k - (dX + dF) gamma, gamma minimising
    |f_k - dF gamma| over the last ``m`` differences of the increments f (dF) and of the steps
    taken (dX), in the increment norm (rotations times ell).  The increments live in the body
    frames of successive iterates; their differences are compared as vectors, an error of the
    order of the corrections squared that the convergence test (on the true residual) does not
    see.  m = 0: the plain modified Newton step f."""

    def __init__(self, m, ell):
        self.m, self.ell = m, ell
        self.k = 0                      # pairs recorded so far (the last m are kept, in a ring)
        self.w = self.Fd = self.Sd = self.u = self.s = None
        self.G = np.zeros((m, m))       # Gram matrix of the kept dF (weighted)

    def restart(self):
        """A new sequence of iterates (new parameters): the kept pairs stay, but no pair joins
        the last iterate to the next."""
        self.u = self.s = None

    def step(self, f):
        """The next step from the modified-Newton increment f (n, 6)."""
        if self.m == 0:
            return f
        if self.w is None:
            self.w = np.tile([1.0, 1.0, 1.0, self.ell, self.ell, self.ell], len(f))
            self.Fd, self.Sd = np.empty((self.m, f.size)), np.empty((self.m, f.size))
        u = f.ravel() * self.w                          # weighted: the increment norm's inner product
        if self.u is not None:
            i = self.k % self.m
            np.subtract(u, self.u, out=self.Fd[i])      # dF
            np.add(self.s, self.Fd[i], out=self.Sd[i])  # dX + dF (the step taken, plus dF)
            self.k += 1
            a = min(self.k, self.m)
            self.G[i, :a] = self.G[:a, i] = self.Fd[:a] @ self.Fd[i]
        a = min(self.k, self.m)
        s = u
        if a:
            # gamma from the normal equations (a <= m columns: a small solve); a tiny Tikhonov
            # term keeps nearly dependent columns from blowing gamma up
            A = self.G[:a, :a].copy()
            A.flat[::a + 1] *= 1.0 + 1e-10
            try:
                s = u - np.linalg.solve(A, self.Fd[:a] @ u) @ self.Sd[:a]
            except np.linalg.LinAlgError:
                pass
        self.u, self.s = u, s
        return (s / self.w).reshape(f.shape)

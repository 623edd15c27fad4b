"""The equations that load stepping iterates on, on one process (:class:`NewtonEquations`).

``solvers.newton_steps`` and ``solvers.newton_try.NewtonTry`` see a problem only through this
interface, so that the same step control, convergence test, mixed iteration and cut-back run
serially and over MPI ranks (``parallel.newton.DistributedEquations`` implements the same
methods on one rank's share of the mesh, with global norms and gathered frames):

* frames: ``local_frames(g)`` the iterate of the whole-mesh frames g, ``whole_frames(g)`` back,
  ``apply_prescribed(g, lam)``, ``retract(g, eta)`` (g exp(eta));
* equations: ``evaluate(g, lam, tangent, stress, norms) -> (ev, rn, floor)`` (the Evaluation with
  its relative residual and round-off floor, ``solvers.convergence``; None, None without
  ``norms``), ``forces(ev)`` the whole-mesh
  internal and external nodal forces, ``stress(g, lam)`` the mixed iteration's stresses,
  ``linear_stress(ev, eta)``;
* the linear step: ``solve(ev, g, probe) -> x`` (K x = -r at the frames g; ``probe``: also check
  the tangent for an unrestrained mode), ``increment(x)`` the nodal increments eta (n, 6), ``work(ev, x)`` = -r . x,
  ``residual_sq(ev)`` = |r|_s^2 and ``increment_norm(eta)`` = |eta|_s (unit-scaled norms);
* what the problem has: ``loads`` (for the Load hooks), ``stateful``, ``mixed``, ``predictor``
  (the tangent predictor is available), ``distributed``, ``root`` (this process logs).
"""
from __future__ import annotations

import numpy as np

from ..fem import ELEMENTS
from .convergence import relative_residual, scaled_norm
from .linalg import Factorization

__all__ = ["NewtonEquations"]


class NewtonEquations:
    """The equations of ``problem`` on this process, solved with ``solver`` (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (its free dofs: ``problem.assembler()``).
    solver : object
        A linear solver of ``solvers.linalg.make_solver``.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.solvers import make_solver
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.01))     # P L^2 / EI = 0.01
    >>> eq = NewtonEquations(p, make_solver("auto"))
    >>> g = p.mesh.g0
    >>> for it in range(4):                      # Newton: g <- g exp(eta), K eta = -r
    ...     ev, rn, floor = eq.evaluate(g, 1.0, tangent=True)
    ...     g = eq.retract(g, eq.increment(eq.solve(ev, g)))
    >>> bool(rn <= floor)                        # at the residual's round-off floor
    True
    """
    distributed = False
    root = True
    predictor = True

    def __init__(self, problem, solver):
        self.problem, self.solver = problem, solver
        self.asm = problem.assembler()
        self.ell = problem.length_scale
        self.loads = problem.loads
        self.stateful = ELEMENTS.lookup(problem.element_name).stateful
        self.mixed = problem.element.mixed

    # ------------------------------------------------------------------ frames ----------
    def local_frames(self, g):
        return g

    def whole_frames(self, g):
        return g

    def apply_prescribed(self, g, lam):
        return self.problem.apply_prescribed(g, lam)

    def fixed_dofs(self):
        return self.problem.constraint_mask()

    def retract(self, g, eta):
        return self.problem.retract(g, eta)

    # ------------------------------------------------------------------ equations -------
    def evaluate(self, g, lam, tangent=True, stress=None, norms=True):
        ev = self.problem.evaluate(g, lam, tangent=tangent, stress=stress)
        if not norms:                    # the tangent of a state whose residual was just measured
            return ev, None, None
        if not np.all(np.isfinite(ev.r)):
            raise FloatingPointError("non-finite residual")
        rn, floor = relative_residual(self.asm, ev, self.ell)
        return ev, rn, floor

    def forces(self, ev):
        return ev.r_int, ev.f_ext

    def stress(self, g, lam):
        return self.problem.evaluate(g, lam, tangent=False).stress

    def linear_stress(self, ev, eta):
        return self.problem.linear_stress(ev, eta)

    # ------------------------------------------------------------------ linear step -----
    def solve(self, ev, g, probe=False):
        with Factorization(ev.K, self.solver) as fac:
            x = fac.solve(-ev.r)
            if probe:
                fac.probe()
        return x

    def increment(self, x):
        return self.asm.scatter(x)

    def work(self, ev, x):
        return -float(ev.r @ x)

    def residual_sq(self, ev):
        return scaled_norm(self.asm.scatter(ev.r), self.ell) ** 2

    def increment_norm(self, eta):
        return scaled_norm(eta, self.ell, moment=False)

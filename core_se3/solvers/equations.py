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
  the tangent for an unrestrained mode), ``det_sign()`` the sign of det K of that tangent (from its
  factors; None when unknown), ``increment(x)`` the nodal increments eta (n, 6), ``work(ev, x)`` = -r . x,
  ``residual_sq(ev)`` = |r|_s^2 and ``increment_norm(eta)`` = |eta|_s (unit-scaled norms);
  ``largest_turn(eta)`` its largest nodal rotation (the midpoint probe's trigger);
  ``state_gap(g1, g2)`` the largest nodal distance of two states in ell (the refine check);
* what the problem has: ``loads`` (for the Load hooks), ``stateful``, ``mixed``, ``predictor``
  (the tangent predictor is available), ``distributed``, ``root`` (this process logs).

Translation: a part far from the origin (the README cantilever at x0 = 1e4 ... 1e9) stores its
positions to an absolute round-off eps |x0|, so the strains of an iterate carry eps |x0| / h_e
and the residual stalls far above its floor (at x0 = 1e4 Newton failed at the first load step).
When every load is ``translation_invariant`` (its forces do not depend on where the shell is),
the iterate is held relative to the part's origin (:func:`part_origin`, subtracted exactly):
``local_frames`` and ``whole_frames`` translate, the problem is evaluated on the local frames,
and the iterations are those of the part at the origin, bit for bit.  A load that reads
positions but has a form relative to the part (contact with an obstacle of a built-in kind:
``solvers.origin.relocation``) is evaluated in that form (``loads``: the problem's with those in
their place; ``model.contact_frame``), and the run is that of the part at the origin to the
round-off of the translated input.
"""
from __future__ import annotations

import numpy as np

from ..fem import ELEMENTS
from ..model.base import conservative_loads
from .convergence import relative_residual, scaled_norm
from .linalg import Factorization
from .origin import part_origin, relocation
from .stability import ASYM_TOL, asymmetry, inertia
from .step_checks import largest_turn, state_gap

__all__ = ["NewtonEquations", "part_origin"]


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
        self.stateful = ELEMENTS.lookup(problem.element_name).stateful
        self.mixed = problem.element.mixed
        self.origin, self._relocated = relocation(problem)
        self.loads = problem.loads if self._relocated is None else self._relocated

    # ------------------------------------------------------------------ frames ----------
    def _moved(self, g, c):
        g = np.array(g, dtype=float)
        g[..., :3, 3] += c
        return g

    def local_frames(self, g):
        """The iterate of whole-mesh frames: positions relative to ``origin`` (when set)."""
        return g if self.origin is None else self._moved(g, -self.origin)

    def whole_frames(self, g):
        """The frames in the problem's coordinates of an iterate."""
        return g if self.origin is None else self._moved(g, self.origin)

    def apply_prescribed(self, g, lam):
        if self.origin is None:
            return self.problem.apply_prescribed(g, lam)
        # the targets are absolute: set them on a copy and bring only the prescribed nodes back
        nodes = [s.nodes for s in self.problem.supports if s.target is not None]
        if not nodes:
            return g
        whole = self.problem.apply_prescribed(self.whole_frames(g), lam)
        nodes = np.concatenate(nodes)
        g[nodes] = self._moved(whole[nodes], -self.origin)
        return g

    def fixed_dofs(self):
        return self.problem.constraint_mask()

    def retract(self, g, eta):
        return self.problem.retract(g, eta)

    # ------------------------------------------------------------------ equations -------
    def evaluate(self, g, lam, tangent=True, stress=None, norms=True):
        ev = self.problem.evaluate(g, lam, tangent=tangent, stress=stress, frame_loads=self._relocated)
        if not norms:                    # the tangent of a state whose residual was just measured
            return ev, None, None
        if not np.all(np.isfinite(ev.r)):
            raise FloatingPointError("non-finite residual")
        rn, floor = relative_residual(self.asm, ev, self.ell)
        return ev, rn, floor

    def forces(self, ev):
        return ev.r_int, ev.f_ext

    def stress(self, g, lam):
        return self.problem.evaluate(g, lam, tangent=False, frame_loads=self._relocated).stress

    def linear_stress(self, ev, eta):
        return self.problem.linear_stress(ev, eta)

    # ------------------------------------------------------------------ linear step -----
    def solve(self, ev, g, probe=False):
        with Factorization(ev.K, self.solver) as fac:
            x = fac.solve(-ev.r)
            if probe:
                fac.probe()
        self._factor = fac
        return x

    def det_sign(self):
        """Sign of det K of the tangent of the last :meth:`solve` (None: not known)."""
        fac = getattr(self, "_factor", None)
        return None if fac is None else fac.det_sign()

    def inertia_count(self, asym_tol=ASYM_TOL):
        """The number of negative eigenvalues of sym(K) of the tangent of the last :meth:`solve`
        (``solvers.stability.inertia``: one symmetric factorisation); None when not counted:
        no tangent, or K not symmetric to ``asym_tol`` (``stability.asymmetry``, Jacobi-scaled): under
        non-conservative loads (followers, dead moments on rotations) sym(K) says nothing of
        stability (the rolled-up strip's count changes where det K's sign does not)."""
        fac = getattr(self, "_factor", None)
        if fac is None or conservative_loads(self.loads) is False:       # by the loads' kinds
            return None
        K = fac.K
        if asymmetry(K, self.asm.free) > asym_tol:
            return None
        return inertia(K)[1]

    def increment(self, x):
        return self.asm.scatter(x)

    def work(self, ev, x):
        return -float(ev.r @ x)

    def residual_sq(self, ev):
        return scaled_norm(self.asm.scatter(ev.r), self.ell) ** 2

    def increment_norm(self, eta):
        return scaled_norm(eta, self.ell, moment=False)

    def largest_turn(self, eta):
        """The largest nodal rotation [rad] of the increment ``eta`` (``step_checks.largest_turn``)."""
        return largest_turn(eta)

    def state_gap(self, g1, g2):
        """The largest nodal distance of two states in ell (``step_checks.state_gap``)."""
        return state_gap(g1, g2, self.ell)

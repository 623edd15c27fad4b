"""The discrete system as the path followers see it: residual, tangent and load direction on
the free dofs, with the update of the state.

:class:`ShellSystem` wraps a Problem (state: the nodal frames g, update g <- g exp(eta));
:class:`AlgebraicSystem` is a small algebraic model r(u, lam) = f(u) - lam q with additive
updates (tests).  Both give ``evaluate(state, lam, tangent) -> dict(r, K, q, rn, floor, ...)``.
"""
from __future__ import annotations

import numbers

import numpy as np

from ..errors import CoreSE3Error, OptionError
from ..model.base import overrides
from .convergence import relative_residual, scaled_norm
from .origin import part_origin
from .linalg import make_solver

__all__ = ["ShellSystem", "AlgebraicSystem"]


class ShellSystem:
    """A Problem seen by the path follower: free-dof residual, tangent, load direction q.

    The state is the array of nodal frames g (n, 4, 4), held relative to the part's origin when
    every load is translation invariant (``solvers.equations.part_origin``, as load stepping
    does): :meth:`initial` and the states of the path are in those coordinates, :meth:`whole`
    and :meth:`local` convert (a part at x0 = 1e4 stored its iterates to eps |x0| and arc length
    and displacement control failed at their first step).  Prescribed motions (rotate_edge,
    prescribe with a target) must not depend on lam: arc length scales the loads only.  q is
    the central difference of f_ext in lam at the current g (exact for linearly scaled loads,
    dead or follower); ``difference='backward'`` uses the one-sided difference.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (path-independent element; CoreSE3Error otherwise).
    linear_solver : str, optional
        Default the problem's.
    difference : str, optional
        'central', 'backward' or 'forward' difference in lam for q.
    tables : bool, optional
        Accept scale tables that bend (``ScaleTable.kinks``; path following refuses them): for
        a diagnosis at one state (``stability.limit_point_hint``), whose one-sided q is the
        programme's at that side.

    Attributes
    ----------
    n : int
        Number of free dofs; ``w`` (n,): the weights of |x|_W (1 for translations, ell^2 for
        rotations); ``ell``: the problem's length scale.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0, 0, 1.0))
    >>> s = ShellSystem(p)
    >>> ev = s.evaluate(s.initial(), 0.0)
    >>> s.n, float(ev["q"].sum())
    (24, 1.0)
    """

    def __init__(self, problem, linear_solver=None, difference="central", tables=False):
        self.difference = difference
        if problem.element.stateful:
            raise CoreSE3Error("path following needs a path-independent element (the default one); "
                               "the seed element's incremental strain is not supported")
        for s in problem.supports:
            if s.target is not None:
                g0 = problem.mesh.g0[s.nodes]
                if not (np.allclose(s.target(0.0), g0) and np.allclose(s.target(1.0), g0)):
                    raise CoreSE3Error("path following scales loads only: a prescribed motion that "
                                       "depends on the load factor is not supported; use "
                                       "newton_solve for displacement-driven problems")
        kinked = [t for t in getattr(problem, "scale_tables", ()) if getattr(t, "kinks", ())]
        if kinked and not tables:
            raise OptionError(f"path following takes the load factor as the path's parameter, not as a load history: "
                              f"the scale table {kinked[0]!r} bends at load factor {kinked[0].kinks[0]:g}, where "
                              "q = d f_ext / d lam jumps (at a peak it vanishes); give each load a straight scale "
                              "(a table of two points) for arc length and displacement control, or use load control "
                              "(newton_solve) for a load history")
        hooked = [ld for ld in problem.loads if overrides(ld, "update_multipliers") or overrides(ld, "limit_increment")]
        if hooked:
            raise CoreSE3Error(f"path following does not support the load {hooked[0].name!r} (contact with an "
                               "obstacle: its multipliers and step cap need load stepping); use newton_solve")
        self.problem = problem
        self.origin = part_origin(problem)
        problem.check_supports()
        self.asm = problem.assembler()
        self.solver = make_solver(linear_solver or problem.linear_solver)
        self.ell = problem.length_scale
        self.n = self.asm.nfree
        self.factorizations = 0        # sparse factorisations so far (the cost of the path)
        w = np.tile(np.r_[np.ones(3), np.full(3, self.ell ** 2)], problem.mesh.n_nodes)
        self.w = w[self.asm.free]

    def initial(self):
        return self.local(self.problem.mesh.g0)

    def _moved(self, g, c):
        g = np.array(g, dtype=float)
        g[..., :3, 3] += c
        return g

    def local(self, g):
        """Frames of the problem (a copy) in the system's coordinates: relative to the origin."""
        return np.array(g, dtype=float) if self.origin is None else self._moved(g, -self.origin)

    def whole(self, g):
        """A state of the system in the problem's coordinates (for results and restarts)."""
        return g if self.origin is None else self._moved(g, self.origin)

    def update(self, g, x):
        return self.problem.retract(g, self.asm.scatter(x))

    def load_direction(self, g, lam):
        """q = d f_ext / d lam at g (n, 6), by a difference in lam."""
        d = 1e-4 * max(1.0, abs(lam))
        hi = lam if self.difference == "backward" else lam + d
        lo = lam if self.difference == "forward" else lam - d
        fp, _, _ = self.problem.external(g, hi, tangent=False)
        fm, _, _ = self.problem.external(g, lo, tangent=False)
        return (fp - fm) / (hi - lo)

    def evaluate(self, g, lam, tangent=True):
        """dict(r, K, q, rn, floor, rint, fext): free residual, tangent, load direction,
        relative residual and its round-off floor, internal and external nodal forces."""
        ev = self.problem.evaluate(g, lam, tangent=tangent)
        if not np.all(np.isfinite(ev.r)):
            raise FloatingPointError("non-finite residual")
        q = self.load_direction(g, lam)
        rn, floor = relative_residual(self.asm, ev, self.ell, abs(lam) * scaled_norm(q, self.ell))
        out = dict(r=ev.r, q=self.asm.vector(q), rint=ev.r_int, fext=ev.f_ext, rn=rn, floor=floor)
        if tangent:
            out["K"] = ev.K
        return out

    def increment_norm(self, x):
        """|x|_W / ell (relative increment, as the solver's dtol)."""
        return np.sqrt(np.sum(self.w * x * x)) / self.ell

    def node_displacement(self, node, direction):
        """(value(g), row(g)): u = d . (phi_k - X_k) and its linearisation on the free dofs.  A node
        that is not one of the mesh's (a negative index controlled the last node) or a direction
        that is not three finite numbers of non-zero length is an OptionError (before: an
        IndexError, a NaN that surfaced as a load's NaN scale, or a stop_at never reached)."""
        n_nodes = self.problem.mesh.n_nodes
        if isinstance(node, bool) or not isinstance(node, numbers.Integral) or not 0 <= node < n_nodes:
            raise OptionError(f"the controlled node must be a node number in [0, {n_nodes - 1}], got {node!r}")
        try:
            d = np.asarray(direction, float)
        except (TypeError, ValueError):
            d = np.full(1, np.nan)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.linalg.norm(d) > 0:
            raise OptionError(f"the controlled direction must be 3 finite lab components of non-zero length, "
                              f"got {direction!r}")
        d = d / np.linalg.norm(d)
        X0 = self.initial()[node, :3, 3].copy()          # the reference position, in the state's coordinates
        free_k = self.asm.free.reshape(-1, 6)[node]
        if not free_k[:3].any():
            raise CoreSE3Error(f"node {node} has no free translation to control")
        idx = np.full(self.problem.mesh.n_nodes * 6, -1)
        idx[self.asm.free] = np.arange(self.n)
        cols = idx.reshape(-1, 6)[node, :3]

        def value(g):
            return float(d @ (g[node, :3, 3] - X0))

        def row(g):
            c = np.zeros(self.n)
            body = g[node, :3, :3].T @ d                       # d . R eta_v
            for k in range(3):
                if cols[k] >= 0:
                    c[cols[k]] = body[k]
            return c

        return value, row


class AlgebraicSystem:
    """r(u, lam) = f(u) - lam q on R^n with additive updates (tests, small models).

    f(u) -> (n,), jac(u) -> (n, n) dense; q (n,) the constant load direction.

    Parameters
    ----------
    f, jac : callable
        u (n,) -> f(u) (n,) and its Jacobian (n, n).
    q : (n,) array_like
        The load direction.
    u0 : (n,) array_like, optional
        The initial state (default zeros).

    Example
    -------
    >>> import numpy as np
    >>> s = AlgebraicSystem(lambda u: u ** 3, lambda u: np.diag(3 * u ** 2 + 0), np.ones(1), np.ones(1))
    >>> float(s.evaluate(s.initial(), 1.0)["rn"])
    0.0
    """

    def __init__(self, f, jac, q, u0=None):
        self.f, self.jac, self.q = f, jac, np.asarray(q, float)
        self.n = len(self.q)
        self.u0 = np.zeros(self.n) if u0 is None else np.asarray(u0, float)
        self.w = np.ones(self.n)
        self.solver = None
        self.factorizations = 0

    def initial(self):
        return self.u0.copy()

    def local(self, u):
        """A copy of u (the algebraic state has no origin to move)."""
        return np.array(u, dtype=float)

    def whole(self, u):
        """u itself."""
        return u

    def update(self, u, x):
        return u + x

    def evaluate(self, u, lam, tangent=True):
        fu = np.asarray(self.f(u), float)
        r = fu - lam * self.q
        scale = max(np.linalg.norm(fu), abs(lam) * np.linalg.norm(self.q), 1e-300)
        out = dict(r=r, q=self.q.copy(), rn=np.linalg.norm(r) / scale, floor=1e3 * np.finfo(float).eps)
        if tangent:
            out["K"] = np.asarray(self.jac(u), float)
        return out

    def increment_norm(self, x):
        return float(np.linalg.norm(x))

"""Sensitivities of quantities at a converged state with respect to design variables.

At an equilibrium r(g, lam; p) = 0 (free dofs), a change dp moves the state by
g <- g exp(eta) with K eta = -(dr/dp) dp (K = dr/d eta, the left-trivialised tangent the
solver uses).  A quantity q(g; p) then changes by

    dq/dp = dq/dp|explicit + (dq/d eta) S,        K S = -dr/dp          (direct: one solve per p)
          = dq/dp|explicit - mu^T dr/dp,          K^T mu = (dq/d eta)^T  (adjoint: one per q)

on the free dofs (supports and prescribed motions hold the others: their eta is zero, the
prescribed targets do not depend on p).  Both reuse one factorisation
(``core_se3.solvers.linalg.Factorization``: of K for the direct method, of K^T for the
adjoint).  dq/d eta is the left-trivialised derivative d/d eps q(g_i exp(eps e_j))
(``design.objectives``), dr/dp the variables' own (``design.variables``).

Example
-------
A cantilever under a tip force P: d(tip deflection)/dP = L^3/(3 EI) for small loads.

>>> import numpy as np
>>> from core_se3 import Problem, Material, mesh
>>> from core_se3.design import LoadMagnitude, ProbePosition
>>> p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(1.2e6, 0.0, 0.1))
>>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1e-6)); p.add_probe("tip", "x1")
>>> g = p.solve(steps=1).final.g
>>> s = sensitivity(p, g, 1.0, [ProbePosition(p, "tip")], [LoadMagnitude(p, p.loads[0])])
>>> round(float(s.jacobian[2, 0]) / (1e-6 * 10.0 ** 3 / 300), 2)
1.0
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

import warnings

from ..errors import AccuracyWarning, DesignError
from ..model import ContactLoad
from ..solvers import Factorization, make_solver
from ..solvers.convergence import relative_residual
from ..solvers.origin import frames_origin, part_origin
from .objectives import Quantity

__all__ = ["Sensitivity", "SolveWith", "sensitivity", "residual_derivative", "quantity_jacobian", "at_the_cone",
           "OnPart"]


#: the relative residual (``solvers.convergence.relative_residual``) above which a state given to
#: :func:`sensitivity` is no equilibrium: the solvers converge to 1e-10 by default; a converged
#: state 1e9 from the origin, taken relative to its part, keeps 2.3e-3 of its positions' round-off
#: (tests/test_design_sensitivity.py), a loaded problem's reference state about 1 (a state of load
#: factor 0.9 taken at 1 only 0.047 on the magnetic strip: the bar catches wrong states, not
#: slightly wrong load factors)
EQUILIBRIUM_TOL = 0.05


@dataclass
class Sensitivity:
    """Values and total derivatives of quantities at a state.

    Attributes
    ----------
    values : (nq,) ndarray
        The quantities, stacked in the order given.
    jacobian : (nq, nx) ndarray
        d(values)/dx, x the variables' components stacked in the order given.
    method : str
        'adjoint' or 'direct'; ``solves``: linear solves used (one factorisation).
    labels : list of str
        The variables' component labels.

    Example
    -------
    >>> s = Sensitivity(np.zeros(1), np.ones((1, 2)), "direct", 2, ["a", "b"])
    >>> s.jacobian.shape, s.method
    ((1, 2), 'direct')
    """
    values: np.ndarray
    jacobian: np.ndarray
    method: str
    solves: int
    labels: list


def residual_derivative(problem, g, lam, variables):
    """dr/dx on the free dofs (nfree, nx) of the variables at (g, lam) (dense).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import LoadMagnitude
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 2.0))
    >>> round(float(residual_derivative(p, p.mesh.g0, 1.0, [LoadMagnitude(p, p.loads[0])]).sum()), 12)
    -2.0
    """
    free = problem.assembler().free
    cols = [v.dr_dp(problem, g, lam).reshape(6 * problem.mesh.n_nodes, v.size)[free] for v in variables]
    return np.concatenate(cols, 1) if cols else np.zeros((int(free.sum()), 0))


def quantity_jacobian(problem, g, lam, quantities):
    """(values (nq,), d values / d eta (nq, 6 n) sparse) of the quantities at (g, lam).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import NodePosition
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> v, J = quantity_jacobian(p, p.mesh.g0, 1.0, [NodePosition(p, [1])])
    >>> v.tolist(), J.shape
    ([0.5, -0.5, 0.0], (3, 36))
    """
    vals = np.concatenate([q.value(problem, g, lam) for q in quantities]) if quantities else np.zeros(0)
    J = sp.vstack([q.jacobian(problem, g, lam) for q in quantities]).tocsr() if quantities else \
        sp.csr_matrix((0, 6 * problem.mesh.n_nodes))
    return vals, J


def _explicit(problem, g, lam, quantities, variables):
    blocks = [[q.explicit(problem, g, lam, v) for v in variables] for q in quantities]
    if not blocks or not variables:
        return np.zeros((sum(q.size for q in quantities), sum(v.size for v in variables)))
    return np.block(blocks)


@dataclass(frozen=True)
class SolveWith:
    """What the linear solves of :func:`sensitivity` use (default: one factorisation of the
    problem's free tangent at (g, lam), by the problem's linear solver).

    Parameters
    ----------
    linear_solver : str, optional
        Default the problem's.
    evaluation : core_se3.model.Evaluation, optional
        The problem's evaluation at (g, lam) with its tangent, if already at hand.
    run : core_se3.parallel.DistributedRun, optional
        Solve with the tangent on the MPI ranks (a design under mpirun): the quantities and
        the variables' derivatives are the whole problem's, the linear solves distributed.
    factorization : core_se3.solvers.Factorization, optional
        A factorisation of the free tangent at (g, lam) to solve with (K and K^T on the same
        factors; a control session's, ``core_se3.control``): no tangent is evaluated or factored.

    Example
    -------
    >>> SolveWith(linear_solver="splu").linear_solver
    'splu'
    """
    linear_solver: str | None = None
    evaluation: object = None
    run: object = None
    factorization: object = None


def sensitivity(problem, g, lam, quantities, variables, method="auto", cotangent=None, solve_with=None):
    """Total derivatives of ``quantities`` by ``variables`` at the equilibrium (g, lam).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem, its variables assigned to the values of the state.
    g : (n, 4, 4) array
        A converged state at load factor ``lam``.
    quantities : sequence of Quantity
        What to differentiate (``design.objectives``).
    variables : sequence of Variable
        With respect to what (``design.variables``).
    method : str
        'adjoint' (one solve with K^T per quantity component), 'direct' (one solve with K per
        variable component) or 'auto' (the one with fewer solves).
    cotangent : (nq,) array, optional
        Only the gradient c^T dq/dx (one adjoint solve): returned as ``jacobian`` of shape (1, nx).
    solve_with : SolveWith, optional
        The linear solver, an evaluation at hand, a distributed run or given factors.

    Returns
    -------
    Sensitivity

    Example
    -------
    The two methods agree (the tangent's transpose pairs with the left-trivialised derivatives):

    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.model import UniformField
    >>> from core_se3.design import FieldVariable, ProbePosition
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e3, 0.0, 0.05)); p.clamp("x0"); p.add_probe("tip")
    >>> f = UniformField((0.0, 0.0, 0.5)); _ = p.add_magnetic((1.0, 0.0, 0.0), f, mu0=1.0)
    >>> g = p.solve(steps=2).final.g
    >>> q, v = [ProbePosition(p, "tip")], [FieldVariable(p, f)]
    >>> a, d = sensitivity(p, g, 1.0, q, v, "adjoint"), sensitivity(p, g, 1.0, q, v, "direct")
    >>> bool(np.abs(a.jacobian - d.jacobian).max() < 1e-10 * np.abs(d.jacobian).max()), a.solves, d.solves
    (True, 3, 3)
    """
    if method not in ("auto", "adjoint", "direct"):
        raise DesignError(f"sensitivity method must be 'auto', 'adjoint' or 'direct', got {method!r}")
    _check_kinds(quantities, variables)
    free = problem.assembler().free
    n = problem.mesh.n_nodes
    _warn_at_the_cone(problem, g, lam)
    w = solve_with if solve_with is not None else SolveWith()
    if w == SolveWith(linear_solver=w.linear_solver):      # the tangent evaluated here: on the part's frames
        g, quantities = on_the_part(problem, g, quantities)
    solves = _without_empty(n, _distributed_solver(w.run, g, lam) if w.run is not None else
                            _factored_solver(problem, w.factorization) if w.factorization is not None else
                            _serial_solver(problem, g, lam, w.evaluation, w.linear_solver))
    vals, Q = quantity_jacobian(problem, g, lam, quantities)
    Qh = (Q @ sp.diags(free.astype(float))).tocsr()         # dq/d eta on the free dofs
    labels = [lab for v in variables for lab in v.labels]
    nx = len(labels)
    E = _explicit(problem, g, lam, quantities, variables)
    if cotangent is not None:
        c = np.asarray(cotangent, float)
        mu = solves([(Qh.T @ c).reshape(n, 6)], True)[0]
        row = c @ E - np.concatenate([v.vjp(problem, g, lam, mu) for v in variables]) if variables else np.zeros(0)
        return Sensitivity(vals, row[None, :], "adjoint", 1, labels)
    nq = len(vals)
    if method == "auto":
        method = "adjoint" if nq <= nx else "direct"
    if method == "adjoint":
        mus = solves([Qh[k].toarray().reshape(n, 6) for k in range(nq)], True)          # (nq, n, 6)
        jac = E - np.concatenate([v.vjp(problem, g, lam, mus) for v in variables], 1) if variables else E
        return Sensitivity(vals, jac, "adjoint", nq, labels)
    Rp = np.concatenate([v.dr_dp(problem, g, lam).reshape(n, 6, v.size) for v in variables], 2) if variables \
        else np.zeros((n, 6, 0))
    S = solves([-Rp[:, :, j] for j in range(nx)], False)                                   # (nx, n, 6)
    # (no variables: the (nq, 0) jacobian; the reshape of no solutions was a bare ValueError)
    return Sensitivity(vals, E + Qh @ S.reshape(nx, 6 * n).T, "direct", nx, labels)


class OnPart(Quantity):
    """A quantity evaluated on frames relative to a far part's ``origin``
    (``solvers.origin.part_origin``): its value at the problem's frames (a position is
    absolute), its derivatives at the relative frames -- exact as for the part at the origin --
    when the quantity is ``translation_invariant`` (else at the problem's: a ``UserQuantity``
    may use absolute positions).  Used by :func:`sensitivity` and a control session.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.design import NodePosition
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1, x0=1e9), Material(1e3, 0.0, 0.01))
    >>> g = p.mesh.g0.copy(); g[:, 0, 3] -= 1e9
    >>> OnPart(NodePosition(p, [2]), np.array([1e9, 0.0, 0.0])).value(p, g, 1.0).tolist()
    [1000000002.0, -0.5, 0.0]
    """

    def __init__(self, q, origin):
        self.q, self.origin, self.name, self.size = q, origin, q.name, q.size

    def _whole(self, g):
        g = np.array(g, float)
        g[..., :3, 3] += self.origin
        return g

    def _at(self, g):
        return g if getattr(self.q, "translation_invariant", False) else self._whole(g)

    def value(self, problem, g, lam):
        return self.q.value(problem, self._whole(g), lam)

    def jacobian(self, problem, g, lam):
        return self.q.jacobian(problem, self._at(g), lam)

    def explicit(self, problem, g, lam, variable):
        return self.q.explicit(problem, self._at(g), lam, variable)


def on_the_part(problem, g, quantities):
    """(frames, quantities) to evaluate sensitivities on: for a part far from the origin
    (``solvers.origin.part_origin``, every load translation invariant) whose frames ``g`` lie
    there, its frames relative to that origin (an exact subtraction) and the quantities as
    :class:`OnPart`, so that the tangent, the variables' derivatives and the quantities'
    derivatives carry the round-off of the part's size, not of |x0| (before, a probe's
    sensitivities at x0 = 1e9 were 1.2e-4 off, a node's 1e-5); else g and the quantities.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1, x0=1e9), Material(1e3, 0.0, 0.01))
    >>> float(on_the_part(p, p.mesh.g0, [])[0][:, 0, 3].max())
    2.0
    """
    c = part_origin(problem)
    if c is None or frames_origin(problem, g, c) is None:
        return g, quantities                # a near part, or frames already relative (a control session's)
    g = np.array(g, float)
    g[:, :3, 3] -= c
    return g, [OnPart(q, c) for q in quantities]


def at_the_cone(problem, g, lam):
    """The number of frictional contact nodes at (g, lam) whose trial traction t* = P w - k s lies
    on the Coulomb cone |t*| = mu p (to 1e-6 of mu p): the stick/slip transition, where the state
    is not differentiable in the loads.  Every node that slid over an accepted step is there
    (its stored traction is on the cone and its slip since zero), and so is every state
    ``Problem.solve`` ends with a sliding node.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e4, 0.0, 0.02))
    >>> _ = p.add_obstacle("half_space", point=(0, 0, -0.1), normal=(0, 0, 1), friction=0.3)
    >>> at_the_cone(p, p.mesh.g0, 1.0)
    0
    """
    count = 0
    for ld in problem.loads:
        if not (isinstance(ld, ContactLoad) and ld.mu > 0):
            continue
        x, _, nrm, H, p, dp = ld.state(g, lam)
        _, _, _, slip = ld.friction_state(g, lam, x, nrm, H, p, dp)
        w = ld.tau @ ld.obstacle.transform(lam)[:3, :3].T
        w -= np.einsum("ki,ki->k", nrm, w)[:, None] * nrm
        trial = np.linalg.norm(w - (ld.k * ld.soft[:len(ld.nodes)])[:, None] * slip, axis=1)
        count += int(np.count_nonzero((p > 0) & (np.abs(trial - ld.mu * p) <= 1e-6 * ld.mu * p)))
    return count


def _check_kinds(quantities, variables):
    """DesignError unless ``quantities`` are Quantity objects and ``variables`` Variable objects
    (a probe's name was a bare AttributeError at its first use)."""
    from .variables import Variable
    bad = [q for q in quantities if not isinstance(q, Quantity)]
    if bad:
        raise DesignError(f"sensitivity: quantities must be design Quantity objects (ProbePosition(problem, "
                          f"'tip'), NodePosition, Orientation, ...), got {bad[0]!r}")
    if not all(isinstance(v, Variable) for v in variables):
        raise DesignError(f"sensitivity: variables must be design Variable objects (FieldVariable, "
                          f"RegionMagnetisation, MaterialVariable, LoadMagnitude), got {list(variables)!r}")


def _warn_at_the_cone(problem, g, lam):
    """An AccuracyWarning when the state has frictional contact nodes at the stick/slip
    transition (:func:`at_the_cone`): the derivatives are one-sided there."""
    k = at_the_cone(problem, g, lam)
    if k:
        warnings.warn(f"sensitivities at a state with {k} frictional contact node(s) at the stick/slip transition "
                      "(their trial traction on the Coulomb cone, as after every step in which they slid): the "
                      "state is not differentiable there; the derivatives are those of continued sliding, and a "
                      "change that makes these nodes stick moves the state differently (measured: 16 % and 2.2 "
                      "times off on a pushed strip, docs/DESIGN.md)", AccuracyWarning, stacklevel=3)


def _without_empty(n, solves):
    """``solves`` answering an empty list of right-hand sides with no solution (0, n, 6), without
    a factorisation or a solve."""
    def nonempty(rhs, transpose):
        return solves(rhs, transpose) if rhs else np.zeros((0, n, 6))
    return nonempty


def _serial_solver(problem, g, lam, evaluation, linear_solver):
    """solves(rhs, transpose): K x = b (or K^T x = b) for nodal right-hand sides b (n, 6) on one
    factorisation of the free tangent at (g, lam); the solutions (k, n, 6), zero on held dofs."""
    asm = problem.assembler()
    ev = evaluation if evaluation is not None and evaluation.K is not None else problem.evaluate(g, lam, tangent=True)
    rn, floor = relative_residual(asm, ev, problem.length_scale)
    if rn > max(EQUILIBRIUM_TOL, 10.0 * floor):
        # (the reference frames of a loaded cantilever at lam = 1 gave a jacobian, silently)
        raise DesignError(f"sensitivities need an equilibrium: the state given has a relative residual {rn:.3g} at "
                          f"load factor {lam!r} (above {EQUILIBRIUM_TOL:g}); pass a converged state of the problem as "
                          "it is now (result.final.g and its load factor, solved after the variables were set)")
    solver = make_solver(linear_solver or problem.linear_solver)

    def solves(rhs, transpose):
        with Factorization(ev.K.T.tocsr() if transpose else ev.K, solver) as F:
            return np.stack([asm.scatter(F.solve(np.asarray(b).ravel()[asm.free])) for b in rhs])
    return solves


def _factored_solver(problem, F):
    """:func:`_serial_solver`'s solves on a given factorisation F of the free tangent (its
    transposed solves for the adjoint)."""
    asm = problem.assembler()

    def solves(rhs, transpose):
        return np.stack([asm.scatter(F.solve(np.asarray(b).ravel()[asm.free], transpose)) for b in rhs])
    return solves


def _distributed_solver(run, g, lam):
    """:func:`_serial_solver`'s solves on the ranks of ``run`` (one MUMPS factorisation of the
    tangent at (g, lam), the loads localised for the variables' current values), gathered."""
    def solves(rhs, transpose):
        run.relocalize()
        run.evaluate(run.local_frames(g), lam, tangent=True)
        sols = run.system.solve_many([run.owned_rows(b) for b in rhs], transpose=transpose)
        return np.stack([run.gather(x[:run.n_own]) for x in sols])
    return solves

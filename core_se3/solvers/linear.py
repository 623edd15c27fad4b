"""Linear analysis: one solve at the reference state (``Problem.solve_linear``,
``Problem.solve(control="linear")``).

The equations are linearised about the reference frames g0 at zero load:

    K0 eta = f_ext(g0, lam_end),   K0 = d r / d eta at (g0, lam = 0),

with eta_i = (v_i, w_i) the body-frame displacement and rotation of node i.  K0 holds only the
element's material stiffness (the reference is stress free, so there is no geometric part) and
the load-independent stiffness of the loads that do not scale with the load factor (penalty
supports: ``scales_with_load_factor`` False), whatever the other loads' scales
(``reference_stiffness``).  The stiffness of every load that scales with the load factor is
proportional to the load, a geometric effect, and is left out, so that the answer is linear in
the load: a follower pressure's (its normal and area turning with the shell), a magnet's body
couple's, and a dead load's too (its lab force seen in the turning body frame, -hat(R^T F)).
With the default scale s(lam) = lam that stiffness is zero at lam = 0 and K0 is the tangent at
(g0, 0) bit for bit; a load with s(0) != 0 (scale "constant", a table) has it at lam = 0, and
counting it made the answer depend on s(0) (a dead pressure at "constant" scale moved a
cantilever's tip sideways by 1e-4 of its deflection, where the linear answer has no sideways
motion).  Prescribed motions enter through their targets at lam_end: the held components
of the rigid motions of ``rotate_edge`` / ``move_edge`` linearised, eta_p = (R0^T (s t + omega x
(X - p)), R0^T omega) with omega = s angle axis (``Prescribed.linear``: an infinitesimal rigid
motion, which does not strain the element; the target's chord (Q - I)(X - p) would, by
O(angle^2)), and of other targets (``prescribe``) eta_p = (R0^T (x_t - X), log(R0^T R_t)): the
linearisation only of a target linear in lam, so an AccuracyWarning names a target whose
increments at lam_end / 2 are not half those at lam_end (``NONLINEAR_TARGET``).

The state reported is g_i = g0_i (exp_so3(w_i), v_i) (the rotation and the translation updated
separately, not by the SE(3) exponential): its displacements are then exactly the linear ones,
u = R0 v, the rotation vector R0 w; the probes are the linearised probe maps
(``Probe.linear``: a probe between two nodes is not a function of the nodal displacements
alone, and the geodesic point of the linear state was not linear in the load).  Reactions are
those of the linear internal forces K0 eta (the forces in the reference frames) and of the
supports' penalty springs, -K_s eta (as a load-stepping step counts them:
``StepRecorder.step``), the applied loads f_ext alone; the step's force and moment totals are
taken in the reference frames and positions, where the linear equations balance.  The result
has the reference state and this one step, like a one-step solve.

The answer's accuracy is measured, not assumed: the factorisation is backward stable (its
residual is at round-off, ``linalg.Factorization``), but its error is the condition number times
that, and a thin shell's system is ill-conditioned.  One more correction from the true residual,
d = K0^-1 (f - K0 eta), is computed (not applied: once refinement has stagnated it is as inexact
as eta), and its size |d| / |eta| (unit-scaled norms) is the estimate of the relative error that
is left (Higham, Accuracy and Stability of Numerical Algorithms, 2002, ch. 12): ``error_estimate``
in the log, and an AccuracyWarning above ``ACCURACY`` (the pinched hemisphere 64x64: 1e-5 at
R/h 1e4, 1e-3 at 1e5, 0.1 at 1e6).
"""
from __future__ import annotations

import os
import sys
import time
import warnings

import numpy as np

from .. import lie
from ..assembly import Assembler
from ..errors import AccuracyWarning, OptionError, OptionWarning
from ..results import Result, StepRecorder
from .convergence import scaled_norm
from .linalg import Factorization, make_solver
from .options import NewtonOptions, unknown_keywords

__all__ = ["linear_solve", "linear_state", "linear_increments", "reference_stiffness", "unused_options", "ACCURACY"]

#: the estimated relative error of a linear solution above which it warns (the 4th digit)
ACCURACY = 1e-4


def linear_state(g0, eta):
    """Frames g0_i (exp_so3(w_i), v_i) of the linear increments eta (n, 6) (module docstring).

    Example
    -------
    >>> import numpy as np
    >>> g0 = np.eye(4)[None]
    >>> linear_state(g0, np.array([[1.0, 2.0, 3.0, 0.0, 0.0, 0.1]]))[0, :3, 3].tolist()
    [1.0, 2.0, 3.0]
    """
    eta = np.asarray(eta, float).reshape(-1, 6)
    h = np.zeros((len(eta), 4, 4))
    h[:, :3, :3] = lie.exp_so3(eta[:, 3:])
    h[:, :3, 3] = eta[:, :3]
    h[:, 3, 3] = 1.0
    return g0 @ h


def linear_increments(g0, g):
    """The increments eta (n, 6) of a linear analysis' state g = ``linear_state(g0, eta)``:
    (R0^T (x - X), log(R0^T R)), exact while every |w| < pi.

    Example
    -------
    >>> import numpy as np
    >>> eta = np.array([[1.0, 2.0, 3.0, 0.0, 0.2, 0.1]])
    >>> linear_increments(np.eye(4)[None], linear_state(np.eye(4)[None], eta)).round(12).tolist()
    [[1.0, 2.0, 3.0, 0.0, 0.2, 0.1]]
    """
    RT = np.swapaxes(g0[:, :3, :3], 1, 2)
    v = np.einsum("nij,nj->ni", RT, g[:, :3, 3] - g0[:, :3, 3])
    return np.concatenate([v, lie.log_so3(RT @ g[:, :3, :3])], 1)


def reference_stiffness(problem, assembler):
    """(K0, K_s): the stiffness of linear analysis at the reference state g0 (module docstring)
    on the dofs of ``assembler``, and the part K_s of it that the loads hold.

    K0 is the element's material stiffness plus the stiffness of the loads that do not scale
    with the load factor (``scales_with_load_factor`` False: penalty springs), K_s that of those
    loads alone (their linear forces count with the applied loads).  The stiffness of the loads
    that scale with the load factor is proportional to the load and left out whatever their
    scale at lam = 0: when it is zero there (the default scale s(lam) = lam) K0 is the problem's
    tangent at (g0, lam = 0) as evaluated (on either backend); otherwise it is evaluated without
    those loads (the NumPy path).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    assembler : core_se3.assembly.Assembler
        The dofs (linear analysis: all of them).

    Returns
    -------
    (scipy.sparse.csr_matrix, scipy.sparse matrix)
        K0 and K_s.

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import Problem, Material, mesh
    >>> from core_se3.assembly import Assembler
    >>> p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.3, 0.1), backend="numpy")
    >>> p.clamp("x0"); p.add_pressure(5.0, follower=True, scale=lambda lam: 1.0)   # at lam = 0 too
    >>> every = Assembler(p.mesh, np.ones(6 * p.mesh.n_nodes, bool))
    >>> K0, Ks = reference_stiffness(p, every)
    >>> q = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.3, 0.1), backend="numpy")
    >>> q.clamp("x0"); q.add_pressure(5.0, follower=True)                          # s(0) = 0
    >>> (K0 != reference_stiffness(q, every)[0]).nnz, float(abs(Ks).max())    # no springs
    (0, 0.0)
    """
    g0 = problem.mesh.g0
    springs = [ld for ld in problem.loads if not ld.scales_with_load_factor]
    scaled = [ld for ld in problem.loads if ld.scales_with_load_factor]
    _, Kn_p, Ke_p = problem.external(g0, 0.0, tangent=True, loads=scaled)
    geometric = bool(np.any(Kn_p)) or (Ke_p is not None and bool(np.any(Ke_p)))
    K = problem.evaluate(g0, 0.0, assembler=assembler, loads=springs if geometric else None).K.tocsr()
    _, Kn_s, Ke_s = problem.external(g0, 0.0, tangent=True, loads=springs)
    return K, assembler.matrix(Ke_s, None, Kn_s)


def _support_forces(problem, assembler, lam, eta):
    """The list of the (n, 6) linear forces f_s(g0, lam) - K_s eta of each of the supports' penalty
    springs (the loads with ``support_force``; K_s its stiffness at g0 on the dofs of
    ``assembler``): the support reactions they exert in the linear equations, which the step
    reports with the reactions (each with its support: ``StepResult.support_reactions``)."""
    n, out = problem.mesh.n_nodes, []
    for ld in (ld for ld in problem.loads if getattr(ld, "support_force", False)):
        f = problem.external(problem.mesh.g0, lam, tangent=False, loads=[ld])[0]
        _, Kn, Ke = problem.external(problem.mesh.g0, 0.0, tangent=True, loads=[ld])
        out.append(f - (assembler.matrix(Ke, None, Kn) @ eta).reshape(n, 6))
    return out


def _prescribed_increments(problem, lam):
    """(n, 6) body-frame increments of the held dofs at lam (zero where no target moves): a rigid
    motion's linearised (``Prescribed.linear``), another target's chord (``linear_increments`` of
    its frames), after an AccuracyWarning if that target is not linear in lam
    (:func:`_warn_if_not_linear`)."""
    g0 = problem.mesh.g0
    eta = np.zeros((problem.mesh.n_nodes, 6))
    for k, s in enumerate(problem.supports):
        if s.target is None:
            continue
        if getattr(s, "linear", None) is not None:          # a rigid motion, linearised
            e = s.linear(lam)
        else:
            e = linear_increments(g0[s.nodes], np.asarray(s.target(lam), float))
            _warn_if_not_linear(problem, k, s, e, lam)
        eta[s.nodes] = np.where(s.fixed, e, eta[s.nodes])
    return eta


#: the relative difference between a target's increments at lam_end / 2 and half those at lam_end
#: above which linear analysis warns that it takes the chord of a motion not linear in lam
NONLINEAR_TARGET = 1e-6


def _warn_if_not_linear(problem, k, s, e, lam):
    """An AccuracyWarning if the target of support ``k`` (``Problem.prescribe``) is not linear in
    the load factor: its held increments at lam / 2 differ from half ``e`` (those at lam) by more
    than NONLINEAR_TARGET of their size (translations / ``length_scale``, rotations in rad).
    Linear analysis prescribes its chord at lam, the linearisation only of a motion linear in lam
    (a rigid rotation's chord (Q - I)(X - p) strains the shell at second order in the angle)."""
    half = linear_increments(problem.mesh.g0[s.nodes], np.asarray(s.target(0.5 * lam), float))
    unit = np.r_[np.full(3, 1.0 / problem.length_scale), np.ones(3)] * s.fixed
    size = max(np.linalg.norm(half * unit), np.linalg.norm(0.5 * e * unit))
    off = np.linalg.norm((half - 0.5 * e) * unit)
    if size > 0 and off > NONLINEAR_TARGET * size:
        warnings.warn(AccuracyWarning(
            f"support {k} (prescribe, {len(s.nodes)} node(s)) prescribes a motion that is not linear in the load "
            f"factor: its increments at lam_end / 2 differ from half those at lam_end by {off / size:.2g} "
            f"(relative), and linear analysis prescribes the chord of the target at lam_end = {lam:g}, not the "
            f"linearised motion (a rigid rotation's chord strains the shell at second order in the angle). Give a "
            f"rigid motion with rotate_edge or move_edge (linearised exactly), or solve with control='load'."),
            stacklevel=6)


def linear_solve(problem, lam_end=1.0, steps=None, linear_solver=None, **kw):
    """Linear analysis of ``problem`` at load factor ``lam_end`` (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem
        The problem; its supports are checked first (SingularSystemError).
    lam_end : float, optional
        The load factor of the answer (the loads at lam_end on the reference geometry).
    steps : int, optional
        Not used (one solve); other than 1 (and None), an OptionWarning (:func:`unused_options`;
        ``Problem.solve`` passes it only when its call gave it, so its solve defaults are quiet).
    linear_solver : str, optional
        'auto', 'banded', 'superlu' or 'mumps' (default the problem's).
    **kw
        Fields of NewtonOptions are accepted and not used (they control iterations; other than
        their defaults, an OptionWarning).

    Returns
    -------
    core_se3.Result
        steps[0] the reference state, steps[1] the linear solution (iterations 1); its log entry
        has ``energy``, the strain energy 1/2 eta^T K0 eta [force x length].

    Example
    -------
    A cantilever strip under a small tip force: Timoshenko's deflection P L^3/(3 EI) + P L/(G A)
    (shear factor 1).

    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 32, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1e-3)); p.add_probe("tip")
    >>> u = p.solve_linear().final.probes["tip"]["u"][2]
    >>> EI, GA = 1.2e6 * 0.1 ** 3 / 12, 0.6e6 * 0.1
    >>> round(float(u / (1e-3 * (10.0 ** 3 / (3 * EI) + 10.0 / GA))), 3)
    1.0
    """
    unknown_keywords("linear_solve", {k: v for k, v in kw.items() if k not in NewtonOptions.__dataclass_fields__},
                     ["lam_end", "linear_solver", *NewtonOptions.__dataclass_fields__])
    said = unused_options(dict(steps=steps, **kw))    # Problem.solve passes only the ones its call gave
    if said:
        warnings.warn(OptionWarning(said), stacklevel=_user_level())
    if isinstance(lam_end, (str, bytes, bool, np.bool_)) or np.ndim(lam_end) != 0 \
            or np.asarray(lam_end).dtype.kind not in "iuf" or not np.isfinite(lam_end):
        raise OptionError(f"lam_end must be finite, got {lam_end!r}")     # ('1': a bare TypeError before)
    contact = [getattr(ld, "name", type(ld).__name__) for ld in problem.loads if getattr(ld, "constraint_force", False)]
    if contact:
        # a contact load is zero until a node touches: the reference tangent has none of it, and
        # a linear answer would pass through the obstacle
        raise OptionError(f"linear analysis cannot hold contact (obstacles {', '.join(map(str, contact))}): contact "
                          "is nonlinear and the linear answer would pass through the obstacle; solve with load "
                          "control (control='load') or remove the obstacles")
    t0 = time.perf_counter()
    mesh = problem.mesh
    g0 = mesh.g0
    problem.check_supports(g0)
    result = Result(mesh=mesh, element=problem.element_name)
    rec = StepRecorder(problem)
    solver = make_solver(linear_solver or problem.linear_solver)
    n = mesh.n_nodes
    free = ~problem.constraint_mask().ravel()
    every = Assembler(mesh, np.ones(6 * n, bool))
    result.timings["setup"] = time.perf_counter() - t0
    t = time.perf_counter()
    # K0 on all dofs, and the loads' own stiffness in it (penalty springs), -df/d eta: their
    # linear forces f - K_ext eta belong to the applied loads (as a load-stepping step reports
    # them), not to the internal forces, or the step's applied totals miss the springs' forces
    # and it does not balance
    K, K_ext = reference_stiffness(problem, every)
    f = problem.external(g0, lam_end, tangent=False)[0].ravel()
    eta = _prescribed_increments(problem, lam_end).ravel()
    rhs = f[free] - K[free][:, ~free] @ eta[~free]
    result.timings["assembly"] = time.perf_counter() - t
    t = time.perf_counter()
    eta[free], error = _solve_measured(solver, K[free][:, free], rhs, free, problem.length_scale)
    result.timings["solve"] = time.perf_counter() - t
    t = time.perf_counter()
    r_lin = ((K - K_ext) @ eta).reshape(n, 6)
    f_lin = (f - K_ext @ eta).reshape(n, 6)
    f_sup = _support_forces(problem, every, lam_end, eta)
    result.steps.append(rec.step(0.0, g0, 0, [], (np.zeros((n, 6)), problem.external(g0, 0.0, tangent=False)[0])))
    # the forces act in the reference frames and balance there (the linear equations): the
    # step's totals are taken in g0 (moments with the reference positions), its probes at g
    result.steps.append(rec.step(lam_end, linear_state(g0, eta), 1, [], (r_lin, f_lin, g0, f_sup)))
    result.steps[-1].probes = rec.linear_probes(eta.reshape(n, 6))      # linear between nodes too
    # the strain energy of the linear solution, 1/2 eta^T K0 eta (with the supports' penalty springs)
    energy = 0.5 * float(eta @ (K @ eta))
    result.log.append(dict(lam=lam_end, converged=True, iterations=1, reason="linear", energy=energy,
                           error_estimate=error))
    result.timings["other"] = time.perf_counter() - t
    return result


def unused_options(given):
    """The message of an :class:`~core_se3.errors.OptionWarning` for the options of ``given`` (the
    keywords a call gave, not a problem's ``solve_defaults``) that a linear analysis takes and does
    not use, or None: ``steps`` other than 1, a field of NewtonOptions other than ``linear_solver``
    that differs from its default (they control load steps and Newton iterations).
    ``Problem.solve`` warns with it (a scenario file warns of ``[solver] steps`` the same way).

    Example
    -------
    >>> unused_options(dict(steps=1, lam_end=2.0, linear_solver="superlu")) is None
    True
    >>> unused_options(dict(steps=10, max_cutbacks=3))[:43]
    'steps=10, max_cutbacks=3 not used: a linear'
    """
    defaults = NewtonOptions()
    names = [f"{k}={v!r}" for k, v in given.items()
             if k == "steps" and v is not None and v != 1
             or k in NewtonOptions.__dataclass_fields__ and k != "linear_solver" and v != getattr(defaults, k)]
    if not names:
        return None
    return (f"{', '.join(names)} not used: a linear analysis (control='linear') is one solve at lam_end (one "
            f"state, no load steps, no Newton iterations or cut-backs); drop the option{'s' * (len(names) > 1)}, "
            f"or solve with load control (control='load') to step the load")


linear_solve.unused_options = unused_options      # Problem.solve asks it (model.solving.dispatch)


def _user_level():
    """The ``stacklevel`` of the first frame outside core_se3 that led to the caller (a warning
    points at the user's line whether linear_solve was called directly or by Problem.solve)."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    frame, level = sys._getframe(2), 2
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(here + os.sep):
        frame, level = frame.f_back, level + 1
    return level


def _solve_measured(solver, A, b, free, ell):
    """(x, estimated relative error) of A x = b: the factorisation's solve, and the unit-scaled
    size of one more correction from the true residual relative to x's as the estimate (module
    docstring); an AccuracyWarning above ``ACCURACY``."""
    with Factorization(A, solver) as F:
        x = F.solve(b)                        # refined to a backward error of round-off
        d = F.solve(b - A @ x, check=False)   # ~ x_exact - x: not applied (it is as inexact as x)
    whole = lambda v: np.bincount(np.flatnonzero(free), v, len(free))     # on all dofs, for the norm
    size = scaled_norm(whole(x), ell, moment=False)
    error = float(scaled_norm(whole(d), ell, moment=False) / size) if size > 0 else 0.0
    if error > ACCURACY:
        warnings.warn(AccuracyWarning(
            f"the linear solution is accurate to about {error:.1g} (relative) only: the stiffness matrix is too "
            f"ill-conditioned for double precision (a very thin shell: the membrane stiffness exceeds the bending "
            f"stiffness by (L/h)^2; the pinched hemisphere on 64x64 elements: 1e-3 at R/h 1e5, 0.1 at 1e6). "
            f"Fewer elements or a thicker model are better conditioned; the estimate is log['error_estimate']."),
            stacklevel=4)
    return x, error

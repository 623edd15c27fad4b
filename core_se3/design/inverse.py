"""The inverse solver: the design variables that make the shell take target shapes.

    Phi(x) = 1/2 sum_poses sum_targets w_t |m_t(g_pose(x))|^2 / s_t^2  +  1/2 sum alpha |D x|^2

over one or several poses (one magnetisation shared by all, a field per pose: Lum et al. 2016's
problem), m_t the misfit of a target (``design.objectives`` with a ``target``), s_t its scale
(the problem's length for positions, 1 rad for angles), D the differences of neighbouring
regions' values (smoothness, :class:`Smoothness`).  Every evaluation starts from the
equilibrium of its pose at the best point so far (``design.equilibrium.follow``), or with
``equilibria='ramp'`` solves it from the flat state by load stepping, as ``core-se3 run`` of
the optimised scenario does (``design.equilibrium.solve_flat``).

Optimisers (scipy.optimize): 'least_squares' (trust-region reflective Gauss-Newton on the
misfit vector, its Jacobian by the direct or adjoint method, whichever needs fewer solves:
the choice for misfit targets), 'L-BFGS-B' (box bounds), 'SLSQP' and 'trust-constr' (also the
norm bounds |B^a| <= B_max, |B^r| <= B^r_max of vector forms as constraints); the scalar
methods get the adjoint gradient (one extra linear solve per pose, with K^T).

Example
-------
Find the tip force multiplier that puts a cantilever's tip 1.0 above the clamp line:

>>> import numpy as np
>>> from core_se3 import Problem, Material, mesh
>>> from core_se3.design import LoadMagnitude, ProbePosition
>>> p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
>>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 0.1)); p.add_probe("tip", "x1")
>>> P = LoadMagnitude(p, p.loads[0], lower=0.0)
>>> tip = ProbePosition(p, "tip")
>>> d = Design(p, [P], [Pose("bent", [Target(tip, components=[2], value=[1.0])])])
>>> r = d.optimise(tolerance=1e-9)
>>> r.reached, round(float(r.states[0].g[p.probes["tip"].node_a, 2, 3]), 6)
(True, 1.0)
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from ..backend import launched_ranks
from ..errors import ConvergenceError, DesignError, ParallelError, did_you_mean, warn_angle
from .equilibrium import (ElementCheck, EquilibriumOptions, EquilibriumState, assign_all, follow, multipliers,
                          restore_multipliers, solve_flat)
from .objectives import AngleInDegrees, NodePosition, Orientation, ProbePosition, RotationAngle
from .sensitivity import SolveWith, sensitivity
from .targets import DesignResult, Pose, Smoothness, Target

__all__ = ["Design", "METHODS", "EQUILIBRIA", "Target", "Pose", "Smoothness", "DesignResult"]

METHODS = ("least_squares", "L-BFGS-B", "SLSQP", "trust-constr")
EQUILIBRIA = ("follow", "ramp")


class _Reached(Exception):
    """Raised by the iteration record once every misfit is within the tolerance."""


def _check_conflicts(variables):
    """DesignError when two variables set one parameter of the problem (``Variable.controls``) in
    a pose they share (pose None: every pose): the later assignment would win and the earlier
    variable's derivative would be that of a parameter that no longer changes the state."""
    keys = [v.controls() for v in variables]
    for j, v in enumerate(variables):
        for i in range(j):
            u = variables[i]
            if (u.pose is None or v.pose is None or u.pose == v.pose) and keys[i] & keys[j]:
                same = "is given twice" if u is v else f"and variable {v.name!r} both set {_said(keys[i] & keys[j])}"
                raise DesignError(f"variable {u.name!r} {same} in the same pose: the later one would overwrite "
                                  "the earlier one, whose derivative would then be wrong; give each parameter to one "
                                  "variable (e.g. one FieldVariable with free=('x', 'z'), disjoint regions)")


def _setting(pose, v, value):
    """A pose's fixed value of ``v`` as (size,) numbers in the order of ``v.labels``: one number
    (every component), ``v.size`` numbers, or an array of the variable's own shape (regions,
    components); DesignError otherwise.  Before, a (regions, components) array, one of another
    size or a string failed at the first solve with a bare NumPy ValueError, and NaN as 12
    cut-backs of 'non-finite residual'."""
    return _values_of(f"pose {pose.name!r}: the setting of {v.name!r} ({', '.join(v.labels)})", v, value)


def _own_shape(v):
    """A variable's own shape: (regions, components) of a regional one, else (size,)."""
    k = len(getattr(v, "regions", ())) or 1
    return (k, v.size // k) if k > 1 and v.size % k == 0 else (v.size,)


def _values_of(what, v, value):
    """``value`` as (size,) numbers of ``v`` in the order of ``v.labels`` (:func:`_setting`, a
    design's start): one number (every component), ``v.size`` numbers or an array of the
    variable's own shape (:func:`_own_shape`); DesignError naming ``what`` otherwise."""
    own = _own_shape(v)
    try:
        a = np.asarray(value, float)
        ok = not isinstance(value, (bool, str, bytes)) and np.asarray(value).dtype.kind in "iuf"
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise DesignError(f"{what} must be numbers, got {value!r}")
    shape, mine = (tuple(s for s in x if s != 1) for x in (a.shape, own))     # (axes of length 1 aside)
    if len(shape) > 1 and shape != mine or len(shape) <= 1 and a.size not in (1, v.size):
        raise DesignError(f"{what} must be one number, {v.size} numbers or an array of shape {own}, got shape "
                          f"{a.shape}" + (" (components by regions? give them by region)" if a.shape == own[::-1]
                                          else ""))
    if not np.all(np.isfinite(a)):
        raise DesignError(f"{what} is not finite: {a.ravel().tolist()}")
    return np.broadcast_to(a.ravel(), (v.size,)).copy()


def _check_targets_move(problem, poses):
    """DesignError for a target on nodes, a probe or a frame whose supports hold every component
    it counts (a clamped node's position): no design moves it, and before, the design ran and
    said only "did not reach the target: misfit 1.000e+00" (a target on node 0 of a strip clamped
    there, e.g. a node id mistaken for the tip's).  A target with some free components (a whole
    shape, its clamped nodes included) is the user's.  Checked on the reference state, where these
    quantities' derivatives in the free dofs vanish only for held dofs."""
    free = problem.assembler().free.astype(float)
    for pose in poses:
        for t in pose.targets:
            if not isinstance(t.quantity, (NodePosition, ProbePosition, Orientation, RotationAngle, AngleInDegrees)):
                continue
            J = (t.quantity.jacobian(problem, problem.mesh.g0, pose.lam).multiply(free[None, :])).tocsr()[t.rows()]
            held = np.asarray(abs(J).sum(1)).ravel() == 0
            if np.all(held):
                raise DesignError(f"target {t.name!r} of pose {pose.name!r}: its component(s) "
                                  f"{t.rows().tolist()} are held by the supports: no design variable moves them; "
                                  "target a free node or probe")


def _said(keys):
    """What a set of ``Variable.controls`` keys names, for a message."""
    k = sorted(keys, key=repr)[0]
    if k[0] == "material":
        return f"{k[1]} of element {k[2]}" + (f" (and {len(keys) - 1} more)" if len(keys) > 1 else "")
    if k[0] == "magnetisation":
        return f"the magnetisation of element {k[1]}" + (f" (and {len(keys) - 1} more)" if len(keys) > 1 else "")
    return {"field": "the same field", "load": "the magnitude of the same load"}.get(k[0], "the same parameter")


def _branch_message(branch, notes, equilibria):
    """The result message's part on the poses whose solve from the flat state does not reach
    the design's equilibrium (``Design.off_branch``)."""
    msg = ""
    for name, dev in branch.items():
        msg += f"; pose {name!r}: a solve from the flat state at these values " + (
            f"stops ({notes.get(name, '')[:200]})" if dev == np.inf else
            f"reaches another equilibrium ({dev:.3g} of the length scale away; a multistable shell: the design's "
            "was reached along its path, which `core-se3 run` of the optimised scenario does not take")
        if equilibria == "follow":
            msg += "; equilibria = 'ramp' designs with the equilibria that ramp reaches"
        msg += ")" if dev != np.inf else ""
    return msg


class Design:
    """A design problem (module docstring).

    Parameters
    ----------
    problem : core_se3.Problem
        The shell, with the variables' loads and fields in it.
    variables : sequence of Variable
        The design variables (``pose`` None: shared by all poses; k: the k-th pose's own).
    poses : sequence of Pose
        The poses and their targets.
    regularisation : sequence of Smoothness, optional
        Regularisation terms.
    options : EquilibriumOptions, optional
        The equilibrium solves' controls.
    sensitivity_method : str
        'auto', 'adjoint' or 'direct' for the least-squares Jacobian.
    equilibria : str
        'follow': every evaluation follows the equilibrium of its pose at the best point so far
        (cheap; on a multistable shell it may end on a branch that a ramp of the loads from the
        flat state does not reach: the result's ``branch`` says so).  'ramp': every evaluation
        solves its pose from the flat state by load stepping, as ``core-se3 run`` of the
        optimised scenario does, so the optimiser sees only the equilibria a ramp reaches (a
        design whose ramp meets a limit point is a rejected trial point).

    Example
    -------
    See the module docstring.

    >>> METHODS[0]
    'least_squares'
    """

    def __init__(self, problem, variables, poses, regularisation=(), options=None, sensitivity_method="auto",
                 equilibria="follow"):
        self.problem, self.variables, self.poses = problem, list(variables), list(poses)
        if equilibria not in EQUILIBRIA:
            raise DesignError(f"equilibria must be one of {', '.join(map(repr, EQUILIBRIA))}, got {equilibria!r}")
        self.equilibria = equilibria
        self.run = None             # under mpirun: the ranks' share of the problem (``distributed``)
        self.regularisation = list(regularisation)
        self.options = options or EquilibriumOptions()
        self.sensitivity_method = sensitivity_method
        if not self.variables:
            raise DesignError("a design needs at least one variable")
        if not self.poses or not any(p.targets for p in self.poses):
            raise DesignError("a design needs at least one pose with a target")
        if not any(t.weight > 0 for p in self.poses for t in p.targets):
            # Phi = 0 for every x: nothing to optimise, and "did not reach" would be all it said
            raise DesignError("every target's weight is 0: the objective does not depend on the design; give a "
                              "target a positive weight ([[design.targets]] weight, default 1)")
        for v in self.variables:
            if v.pose is not None and not 0 <= v.pose < len(self.poses):
                raise DesignError(f"variable {v.name!r} belongs to pose {v.pose}, but there are {len(self.poses)} poses")
            v.check_start()
        _check_conflicts(self.variables)
        for r in self.regularisation:
            if not any(r.variable is v for v in self.variables):
                raise DesignError("a smoothness term refers to a variable that is not in the design")
        self.aux = []
        for pose in self.poses:
            for v in pose.settings:
                pose.settings[v] = _setting(pose, v, pose.settings[v])
                if not any(v is u for u in self.variables + self.aux):
                    self.aux.append(v)
            for t in pose.targets:
                t.resolve_scale(problem)
        _check_targets_move(problem, self.poses)
        self.all = self.variables + self.aux
        self.x0 = [v.value() for v in self.all]
        self.order, self.held = self._orders()
        self.slices, k = [], 0
        for v in self.variables:
            self.slices.append(slice(k, k + v.size))
            k += v.size
        self.nx = k
        self.labels = [lab for v in self.variables for lab in v.labels]
        self.xscale = np.concatenate([v.scale for v in self.variables])
        self.lower = np.concatenate([v.lower for v in self.variables])
        self.upper = np.concatenate([v.upper for v in self.variables])
        self.states = [None] * len(self.poses)
        self.best = None
        self.solves = self.newton_iterations = self.evaluations = 0
        self.failed = []
        self.trials = self.accepted = 0
        self.branch_notes = {}      # pose name -> why its solve from the flat state stopped (off_branch)
        self._cache = None
        # the element's coarse-mesh check of the design points (once per point whose element
        # changed, each cause said once per run: optimise starts a new run)
        self.element_check = ElementCheck()

    def _orders(self):
        """Per pose k: the order in which it assigns the variables -- other poses' variables and
        the other poses' fixed settings (their start), the shared variables, the pose's own fixed
        settings, its own variables: the later ones win on a shared field -- and the shared
        variables the pose holds (in its settings, or setting a parameter that its settings
        hold): they keep their start there and have no derivative in that pose.  (Before, a
        shared variable was assigned after the settings, so that a pose holding the field of a
        shared field variable at zero was bent by the optimised field.)"""
        nv, order, held = len(self.variables), [], []
        for k, pose in enumerate(self.poses):
            others = [i for i, v in enumerate(self.variables) if v.pose is not None and v.pose != k]
            shared = [i for i, v in enumerate(self.variables) if v.pose is None]
            own = [i for i, v in enumerate(self.variables) if v.pose == k]
            mine = [i for i in range(nv, len(self.all)) if self.all[i] in pose.settings]
            fixed = set().union(*[self.all[i].controls() for i in mine])
            held.append({i for i in shared if self.variables[i] in pose.settings or self.variables[i].controls() & fixed})
            order.append(others + [i for i in range(nv, len(self.all)) if i not in mine] + shared + mine + own)
        return order, held

    @property
    def distributed(self):
        """The ``parallel.DistributedRun`` of the problem when launched among several MPI ranks
        (built at the first use; None otherwise): every rank takes the same optimiser steps on
        the same gathered equilibria and sensitivities, the Newton tries and the linear solves of
        the equilibria and of the sensitivities run on the ranks' shares."""
        if self.run is None and launched_ranks() > 1:
            from ..parallel import DistributedRun
            from .material import MaterialVariable
            if any(isinstance(v, MaterialVariable) for v in self.all):
                raise ParallelError("a material variable changes the element, which every rank builds "
                                    "for its share once: run a design with material variables without mpirun")
            self.run = DistributedRun(self.problem, linear="mumps")
        return self.run

    # ------------------------------------------------------------------ evaluations --------
    def x_start(self):
        """The variables' starting values (nx,)."""
        return np.concatenate(self.x0[:len(self.variables)])

    def pose_variables(self, k):
        """The variables pose k assigns, in its order (``pose_values``)."""
        return [self.all[i] for i in self.order[k]]

    def pose_values(self, k, x):
        """The values (one array per variable of ``pose_variables(k)``) pose k sees at x."""
        pose, out = self.poses[k], []
        for i in self.order[k]:
            v = self.all[i]
            if i < len(self.variables) and (v.pose is None or v.pose == k) and i not in self.held[k]:
                out.append(np.asarray(x[self.slices[i]], float))
            elif v in pose.settings:
                out.append(np.broadcast_to(np.asarray(pose.settings[v], float), (v.size,)).copy())
            else:
                out.append(self.x0[i])
        return out

    def solve(self, x):
        """Equilibria of every pose at x (warm-started), cached; returns the states."""
        x = np.asarray(x, float)
        if self._cache is not None and np.array_equal(self._cache[0], x):
            return self._cache[1]
        self.evaluations += 1
        base = self.best[1] if self.best is not None else self.states
        for k, pose in enumerate(self.poses):
            xs = self.pose_values(k, x)
            st = base[k]
            if st is not None and all(np.array_equal(a, b) for a, b in zip(st.x, xs)):
                self.states[k] = st         # the best point's own state, not the last trial's
                continue
            if st is None or self.equilibria == "ramp":
                # the equilibrium a ramp of the loads from the flat state reaches, with the run's
                # steps and stability check in mode 'ramp' (a limit or bifurcation point on the
                # way: a ConvergenceError, a rejected trial point of least_squares)
                st = solve_flat(self.problem, self.pose_variables(k), xs, pose.lam, self.options, self.element_check,
                                as_run=self.equilibria == "ramp")
                info = st.stats
            else:
                st, info = follow(self.problem, self.pose_variables(k), xs, st, self.options, self.distributed,
                                  self.element_check)
            self.states[k] = st
            self.solves += 1
            self.newton_iterations += info["iterations"]
        self._cache = (x.copy(), list(self.states), {})
        return self._cache[1]

    def _accept(self, x, phi):
        """Keep the states of the best point so far: every evaluation follows the path from them
        (an equilibrium of a multistable shell depends on where its path starts; starting from
        the best point keeps the objective the one of the optimiser's accepted iterates)."""
        if self.best is None or phi < self.best[0]:
            self.best = (phi, list(self.solve(x)))

    def _active(self, k):
        return [i for i, v in enumerate(self.variables) if (v.pose is None or v.pose == k) and i not in self.held[k]]

    def _target_poses(self, states):
        """(k, pose, active variables) of the poses with targets, their variables assigned the
        values of pose k's state (``states``: of :meth:`solve`)."""
        for k, pose in enumerate(self.poses):
            if pose.targets:
                assign_all(self.pose_variables(k), states[k].x)
                restore_multipliers(self.problem, states[k])
                yield k, pose, self._active(k)

    def _solve_with(self):
        return SolveWith(linear_solver=self.options.linear_solver, run=self.distributed)

    def residuals(self, x):
        """The weighted misfit vector F (Phi = |F|^2 / 2), regularisation rows last."""
        states = self.solve(x)
        rows = []
        for k, pose in enumerate(self.poses):
            assign_all(self.pose_variables(k), states[k].x)
            for t in pose.targets:
                rows.append(np.sqrt(t.weight) / t.scale * t.misfit(self.problem, states[k].g, states[k].lam))
        for r in self.regularisation:
            i = next(j for j, v in enumerate(self.variables) if v is r.variable)
            rows.append(np.sqrt(r.alpha) * (r.D @ (np.asarray(x[self.slices[i]]) / r.variable.scale)))
        return np.concatenate(rows)

    def jacobian(self, x):
        """dF/dx (nF, nx): per pose, the direct or adjoint sensitivities of its targets."""
        states = self.solve(x)
        cache = self._cache[2]
        if "J" in cache:
            return cache["J"]
        blocks = []
        for k, pose, act in self._target_poses(states):
            vs = [self.variables[i] for i in act]
            s = sensitivity(self.problem, states[k].g, states[k].lam, [t.quantity for t in pose.targets], vs,
                            self.sensitivity_method, solve_with=self._solve_with())
            cols = np.concatenate([np.arange(self.nx)[self.slices[i]] for i in act])
            off = 0
            for t in pose.targets:
                J = np.zeros((t.size, self.nx))
                J[:, cols] = s.jacobian[off + t.rows()] * (np.sqrt(t.weight) / t.scale)
                off += t.quantity.size
                blocks.append(J)
        for r in self.regularisation:
            i = next(j for j, v in enumerate(self.variables) if v is r.variable)
            J = np.zeros((r.D.shape[0], self.nx))
            J[:, self.slices[i]] = np.sqrt(r.alpha) * r.D / r.variable.scale
            blocks.append(J)
        cache["J"] = np.concatenate(blocks)
        return cache["J"]

    def objective(self, x):
        """Phi(x)."""
        F = self.residuals(x)
        phi = 0.5 * float(F @ F)
        self._accept(x, phi)
        return phi

    def gradient(self, x):
        """dPhi/dx by the adjoint method: one solve with K^T per pose (the cotangent F of its
        targets), plus the regularisation's."""
        F = self.residuals(x)
        states = self.solve(x)
        cache = self._cache[2]
        if "grad" in cache:
            return cache["grad"]
        grad, off = np.zeros(self.nx), 0
        for k, pose, act in self._target_poses(states):
            c = []
            for t in pose.targets:
                ct = np.zeros(t.quantity.size)
                ct[t.rows()] = F[off:off + t.size] * np.sqrt(t.weight) / t.scale
                off += t.size
                c.append(ct)
            s = sensitivity(self.problem, states[k].g, states[k].lam, [t.quantity for t in pose.targets],
                            [self.variables[i] for i in act], cotangent=np.concatenate(c),
                            solve_with=self._solve_with())
            cols = np.concatenate([np.arange(self.nx)[self.slices[i]] for i in act])
            grad[cols] += s.jacobian[0]
        for r in self.regularisation:
            i = next(j for j, v in enumerate(self.variables) if v is r.variable)
            n = r.D.shape[0]
            grad[self.slices[i]] += np.sqrt(r.alpha) * (r.D.T @ F[off:off + n]) / r.variable.scale
            off += n
        cache["grad"] = grad
        return grad

    def misfits(self, x):
        """pose name -> target name -> max |misfit| (the targets' units) at x."""
        states = self.solve(x)
        out = {}
        for k, pose in enumerate(self.poses):
            assign_all(self.pose_variables(k), states[k].x)
            out[pose.name] = {t.name: float(np.abs(t.misfit(self.problem, states[k].g, states[k].lam)).max())
                              for t in pose.targets}
        return out

    # ------------------------------------------------------------------ the optimiser ------
    def optimise(self, method="least_squares", x0=None, max_iter=100, tol=1e-12, tolerance=None, progress=False,
                 callback=None, stop_at_tolerance=False):
        """Minimise Phi from x0 (default the variables' current values).

        Parameters
        ----------
        method : str
            One of :data:`METHODS`.
        x0 : (nx,) array, sequence or dict, optional
            The start (checked against the bounds): the nx numbers in the order of ``labels``,
            one value per variable (each of its own shape, (regions, components) for a regional
            magnetisation, or its size, or one number), or a dict {variable name: value} (the
            variables left out at their start).
        max_iter : int
            Iterations (least_squares: evaluations, scipy's ``max_nfev``: the start and every
            trial point, the rejected ones too -- each costs its equilibrium solves; the result
            gives ``iterations`` and ``rejected`` apart).
        tol : float
            The optimiser's tolerance (ftol, xtol and gtol of least_squares; tol of minimize).
        tolerance : float, optional
            ``reached`` when every misfit is within it (the targets' units).
        progress : bool
            Print objective, gradient norm and equilibrium solves per iteration.
        callback : callable, optional
            Called with the history entry of every iteration.
        stop_at_tolerance : bool
            Stop at the first iteration whose misfits are all within ``tolerance``.

        Returns
        -------
        DesignResult
            The problem is left at the design's values (the last pose's equilibrium assigned).

        Example
        -------
        See the module docstring.

        >>> "SLSQP" in METHODS
        True
        """
        x0, norm = self._check_start(method, x0, max_iter)
        for key, val, low in (("tol", tol, 0.0), ("tolerance", tolerance, -1.0)):
            if (val is not None or key == "tol") and not (isinstance(val, (int, float, np.floating, np.integer))
                                                          and not isinstance(val, bool) and np.isfinite(val)
                                                          and val > low and val >= 0):
                raise DesignError(f"{key} must be a finite number {'>' if key == 'tol' else '>='} 0, got {val!r}")
        self.element_check.reset()
        self.solves = self.newton_iterations = self.evaluations = 0     # this run's (a second optimise)
        self.failed = []                                                # least_squares' rejected trial points
        self.trials = self.accepted = 0         # least_squares' evaluations, and those it accepted (the start too)
        t0 = time.perf_counter()
        history, last = [], {}

        def record(z):
            # one history entry per optimiser iteration; _Reached once every misfit is in tolerance
            x = z * self.xscale
            phi, g = self.objective(x), self.gradient(x) * self.xscale
            entry = dict(iteration=len(history) + 1, objective=phi, gradient_norm=float(np.linalg.norm(g)),
                         equilibrium_solves=self.solves, newton_iterations=self.newton_iterations,
                         time=time.perf_counter() - t0, x=x.tolist())
            history.append(entry)
            if progress:
                print(f"design iteration {entry['iteration']:3d}: objective {phi:.6e}  |grad| "
                      f"{entry['gradient_norm']:.3e}  equilibrium solves {self.solves}", flush=True)
            if callback is not None:
                callback(entry)
            if tolerance is not None and stop_at_tolerance:
                worst = max((v for d in self.misfits(x).values() for v in d.values()), default=0.0)
                entry["max_misfit"] = worst
                if worst <= tolerance:
                    last["reached"] = z.copy()
                    raise _Reached()

        try:
            if method == "least_squares":
                z, ok, msg = self._least_squares(x0, tol, max_iter, record)
            else:
                z, ok, msg = self._minimize(method, x0, tol, max_iter, record, norm)
        except _Reached:
            z, ok, msg = last["reached"], True, "stopped at the tolerance"
        except ConvergenceError as exc:
            raise ConvergenceError(f"the design stopped: an equilibrium failed ({exc}); the last design "
                                   "iterations are in the history", exc.result) from None
        return self._result(z * self.xscale, ok, msg, tolerance, method, history, t0)

    def _check_start(self, method, x0, max_iter):
        """The start x0 (default the variables' values) inside the bounds, and the norm bounds
        [(indices, top)] of the vector forms (refused by the box-bounded methods)."""
        if method not in METHODS:
            raise DesignError(f"unknown design method {method!r}; choose one of {', '.join(METHODS)}")
        if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
            raise DesignError(f"max_iter must be a whole number >= 1, got {max_iter!r}")
        norm = [(self.slices[i].start + idx, top) for i, v in enumerate(self.variables) for idx, top in v.norm_bounds]
        if norm and method in ("least_squares", "L-BFGS-B"):
            raise DesignError(f"method {method!r} takes box bounds only; a norm bound (|B| <= B_max of a vector form) "
                              "needs 'SLSQP' or 'trust-constr', or the polar form with a bound on the magnitude")
        if x0 is None:
            x0 = self.x_start()
        else:
            x0 = self._start_of(x0)
            for lab, x in zip(self.labels, x0):        # a polar form's angle [rad]: degrees?
                if lab.endswith(".angle"):
                    warn_angle(x, f"x0's {lab}")
        if np.any(x0 < self.lower) or np.any(x0 > self.upper):
            i = int(np.nonzero((x0 < self.lower) | (x0 > self.upper))[0][0])
            raise DesignError(f"the start {x0[i]:g} of {self.labels[i]!r} lies outside its bounds "
                              f"[{self.lower[i]:g}, {self.upper[i]:g}]")
        return x0, norm

    def _start_of(self, x0):
        """A given start as (nx,) numbers in the order of ``self.labels``: the nx numbers; one
        value per variable (a sequence with an entry per variable, or a dict {name: value} whose
        variables left out keep their start), each one number, its size or its own shape
        (regions, components), as a pose's settings; or, with one variable, a value of that
        variable.  (Before, only the flat nx numbers: a two-region magnetisation's (2, 3) start
        was refused.)  DesignError naming the expected shapes otherwise."""
        vs, names = self.variables, [v.name for v in self.variables]
        shapes = ", ".join(f"{v.name!r}: {_own_shape(v)}" for v in vs)
        said = (f"x0 must be {self.nx} finite numbers ({', '.join(self.labels)}), one value per variable ({shapes}) "
                f"or a dict {{variable name: value}}")
        if isinstance(x0, dict):
            unknown = [k for k in x0 if getattr(k, "name", k) not in names]
            if unknown:
                raise DesignError(f"x0 names no variable {unknown[0]!r}{did_you_mean(str(unknown[0]), names)} "
                                  f"(the variables: {', '.join(map(repr, names))})")
            given = {getattr(k, "name", k): val for k, val in x0.items()}
            parts = [given.get(v.name, self.x0[i]) for i, v in enumerate(vs)]
        else:
            try:
                flat = np.asarray(x0, float)
            except (TypeError, ValueError):
                flat = None
            if flat is not None and flat.shape == (self.nx,) and not isinstance(x0, str):
                parts = [flat[sl] for sl in self.slices]
            elif len(vs) == 1:
                parts = [x0]
            elif isinstance(x0, (list, tuple, np.ndarray)) and not isinstance(x0, str) and len(x0) == len(vs):
                parts = list(x0)
            else:
                raise DesignError(f"{said}, got {x0!r}"[:600])
        return np.concatenate([_values_of(f"{said}: the start of {v.name!r}", v, val) for v, val in zip(vs, parts)])

    def _least_squares(self, x0, tol, max_iter, record):
        """scipy's trust-region reflective least squares on the scaled z = x / xscale; ``record``
        called once per new Jacobian point (an iteration).  A trial point whose equilibrium fails
        (a ConvergenceError after the start) returns NaN residuals: trf rejects the step and
        shrinks its radius to a quarter of it (scipy >= 1.10); the point goes to ``failed``."""
        import scipy.optimize as so
        sc, seen = self.xscale, {}

        def jac(z):
            J = self.jacobian(z * sc) * sc
            if seen.get("z") is None or not np.array_equal(seen["z"], z):
                seen["z"] = z.copy()
                self.accepted += 1
                record(z)
            return J

        def fun(z):
            self.trials += 1
            try:
                F = self.residuals(z * sc)
            except ConvergenceError as exc:
                if "nF" not in seen:                # the start: nothing to back off to
                    raise
                # a trial point whose equilibrium fails (past a limit point): trf takes a
                # non-finite residual as a rejected step and shrinks its trust region to a
                # quarter of it; never accepted, never the result
                self.failed.append(dict(x=(z * sc).tolist(), message=str(exc)))
                return np.full(seen["nF"], np.nan)
            seen["nF"] = len(F)
            self._accept(z * sc, 0.5 * float(F @ F))
            return F
        r = so.least_squares(fun, x0 / sc, jac=jac, bounds=(self.lower / sc, self.upper / sc), method="trf",
                             ftol=tol, xtol=tol, gtol=tol, max_nfev=max_iter)
        if r.status == 0:           # scipy's "maximum number of function evaluations": say what they were
            rej = self.trials - self.accepted
            spent = f"max_iter = {max_iter} evaluations spent: the start"
            if not rej:
                return r.x, False, f"{spent} and {self.accepted - 1} accepted step(s)"
            return r.x, False, (f"{spent}, {self.accepted - 1} accepted step(s) and {rej} rejected trial point(s) "
                                f"({len(self.failed)} of them because their equilibrium failed); least_squares "
                                "counts every evaluation")
        return r.x, r.success and r.status > 0, r.message

    def _minimize(self, method, x0, tol, max_iter, record, norm):
        """scipy.optimize.minimize on Phi with the adjoint gradient, the norm bounds as
        constraints |x[idx]|^2 <= top^2 (SLSQP, trust-constr)."""
        import scipy.optimize as so
        sc, kw = self.xscale, {}
        if method in ("SLSQP", "trust-constr") and norm:
            def cons(z):
                x = z * sc
                return np.array([top ** 2 - x[idx] @ x[idx] for idx, top in norm])

            def cons_jac(z):
                x = z * sc
                J = np.zeros((len(norm), len(z)))
                for j, (idx, top) in enumerate(norm):
                    J[j, idx] = -2 * x[idx] * sc[idx]
                return J
            kw["constraints"] = [so.NonlinearConstraint(cons, 0.0, np.inf, jac=cons_jac)] \
                if method == "trust-constr" else [dict(type="ineq", fun=cons, jac=cons_jac)]
        bounds = so.Bounds(self.lower / sc, self.upper / sc)
        cb = (lambda z, *a: record(z)) if method != "trust-constr" else (lambda z, state: record(z))
        r = so.minimize(lambda z: (self.objective(z * sc), self.gradient(z * sc) * sc), x0 / sc, jac=True,
                        method=method, bounds=bounds, tol=tol, callback=cb, options=dict(maxiter=max_iter), **kw)
        return r.x, bool(r.success), str(r.message)

    def _result(self, x, ok, msg, tolerance, method, history, t0):
        """The DesignResult at x, the problem left at the last pose's equilibrium."""
        mis = self.misfits(x)
        worst = max((v for d in mis.values() for v in d.values()), default=0.0)
        reached = None if tolerance is None else bool(worst <= tolerance)
        if reached is False:
            msg = f"did not reach the target: misfit {worst:.3e} > tolerance {tolerance:.3e} ({msg})"
        elif reached:
            msg = f"reached the target: misfit {worst:.3e} <= tolerance {tolerance:.3e} ({msg})"
        values = {v.name: np.asarray(x[self.slices[i]]) for i, v in enumerate(self.variables)}
        states = self.solve(x)
        idle, branch = self.idle(states), self.off_branch(x, states)
        if self.failed:
            msg += (f"; {len(self.failed)} trial point(s) rejected: their equilibrium failed (first: "
                    f"{self.failed[0]['message'][:200]})")
        msg += _branch_message(branch, self.branch_notes, self.equilibria)
        if idle:
            msg += (f"; without effect at the result (the residual of no pose with targets depends on them): "
                    f"{', '.join(idle)}")
        res = DesignResult(bool(ok), reached, msg, x, self.labels, values, self.objective(x), self.gradient(x), mis,
                           worst, len(history), self.evaluations, self.solves, self.newton_iterations,
                           time.perf_counter() - t0, method, history, list(states), idle, branch, list(self.failed),
                           self.trials - self.accepted if method == "least_squares" else None)
        assign_all(self.pose_variables(len(self.poses) - 1), states[-1].x)
        restore_multipliers(self.problem, states[-1])
        return res

    def idle(self, states):
        """The labels of the variables' components that change nothing at ``states`` (of
        :meth:`solve`): dr/dx and the targets' explicit derivatives zero in every pose with
        targets where the variable is active (a load variable of a zero load, a magnetisation
        in poses without field, a variable only of poses without targets) -- the optimiser
        cannot have moved them, whatever the result says."""
        moved = np.zeros(self.nx, bool)
        free = self.problem.assembler().free
        for k, pose, act in self._target_poses(states):
            g, lam = states[k].g, states[k].lam
            for i in act:
                v = self.variables[i]
                d = v.dr_dp(self.problem, g, lam).reshape(-1, v.size)[free]
                e = np.concatenate([t.quantity.explicit(self.problem, g, lam, v) for t in pose.targets])
                moved[self.slices[i]] |= np.any(d != 0, 0) | np.any(e != 0, 0)
        return [lab for lab, m in zip(self.labels, moved) if not m]

    def off_branch(self, x, states):
        """pose name -> the largest distance (over the length scale) between its design state
        at x and the equilibrium a solve from the flat state at the same values reaches (the
        user's run of the optimised scenario: its steps and stability check), for the poses where
        it exceeds 1e-6 (inf where that solve stops: ``branch_notes`` says why): on a
        multistable shell the design may end on a branch it reached along its own path (a
        buckled strip kept up by a force that, applied from flat, buckles it down)."""
        out, self.branch_notes = {}, {}
        saved = [multipliers(self.problem)]
        for k, pose in enumerate(self.poses):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    st = solve_flat(self.problem, self.pose_variables(k), self.pose_values(k, x), pose.lam, self.options,
                                    as_run=True)
                dev = np.abs(st.g[:, :3, 3] - states[k].g[:, :3, 3]).max() / self.problem.length_scale
            except ConvergenceError as exc:
                dev, self.branch_notes[pose.name] = np.inf, str(exc)
            if dev > 1e-6:
                out[pose.name] = float(dev)
        restore_multipliers(self.problem, EquilibriumState(None, None, None, multipliers=saved[0]))
        return out

    def assign_pose(self, k, x):
        """Set the problem to pose k's values at x (e.g. before writing its outputs)."""
        assign_all(self.pose_variables(k), self.pose_values(k, np.asarray(x, float)))

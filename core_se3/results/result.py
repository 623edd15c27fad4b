"""Results of a solve: one :class:`StepResult` per stored load step, gathered in a :class:`Result`."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import lie
from ..errors import OptionError, did_you_mean

__all__ = ["StepResult", "Result", "unwrap_rotation", "ProbeState", "ProbeTable", "UnknownProbeError"]


def unwrap_rotation(R, w_prev, log=None):
    """Rotation vector of R that is closest to w_prev among w + 2 pi k n (continuity along a
    path: a roll-up reports 6 pi, not its value modulo 2 pi).

    Parameters
    ----------
    R : (3, 3) array
        The rotation (e.g. R R0^T of a probe).
    w_prev : (3,) array
        The unwrapped rotation vector of the previous state [rad] (zeros at the start).
    log : callable, optional
        R -> its rotation vector with |w| <= pi (default ``lie.log_so3``; the recorder of a
        compiled problem passes the compiled twin).

    Returns
    -------
    (3,) ndarray
        log_so3(R) + 2 pi k n (n its axis, k integer) nearest to w_prev [rad].

    Example
    -------
    >>> import numpy as np
    >>> from core_se3 import lie
    >>> w = unwrap_rotation(lie.exp_so3([0.0, 0.0, 0.1]), np.array([0.0, 0.0, 2 * np.pi]))
    >>> round(float(w[2]), 6)
    6.383185
    """
    w = (log or lie.log_so3)(R)
    t = float(np.sqrt(w @ w))
    w_prev = np.asarray(w_prev, float)
    if t >= 1e-12:
        n = w / t
    else:
        tp = float(np.sqrt(w_prev @ w_prev))
        if tp == 0.0:
            return w
        n = w_prev / tp
    # the representations of R are w + 2 pi k n (k integer); |w + 2 pi k n - w_prev| is least
    # for the k nearest to (n . w_prev - t) / (2 pi)
    k = np.round((float(n @ w_prev) - t) / (2 * np.pi))
    return w + 2 * np.pi * k * n


class ProbeState(dict):
    """The state of a probe at a step, with the keys of the result documents (``results.json``):
    ``u`` (3,) displacement [length], ``rotation`` (3, 3) the rotation R R0^T from the
    reference, ``rotation_vector`` (3,) [rad] unwrapped continuously along the path and
    ``rotation_angle`` its norm [rad].  The short names of earlier versions, ``R`` and ``w``,
    still read ``rotation`` and ``rotation_vector``.

    Example
    -------
    >>> import numpy as np
    >>> p = ProbeState(np.zeros(3), np.eye(3), np.array([0.0, 0.0, 2 * np.pi]))
    >>> list(p), p["rotation_angle"], bool(p["w"] is p["rotation_vector"])
    (['u', 'rotation', 'rotation_vector', 'rotation_angle'], 6.283185307179586, True)
    """
    ALIASES = {"R": "rotation", "w": "rotation_vector"}

    def __init__(self, u, rotation, rotation_vector):
        super().__init__(u=u, rotation=rotation, rotation_vector=rotation_vector,
                         rotation_angle=float(np.linalg.norm(rotation_vector)))

    def __missing__(self, key):
        if key in self.ALIASES:
            return self[self.ALIASES[key]]
        raise KeyError(key)

    def get(self, key, default=None):
        return self[key] if key in self or key in self.ALIASES else default


class UnknownProbeError(OptionError, KeyError):
    """A probe name a step does not have (``StepResult.probes[name]``): an :class:`OptionError`
    that is also the ``KeyError`` a dict raises, naming the probes there are.

    Example
    -------
    >>> issubclass(UnknownProbeError, KeyError), str(UnknownProbeError("no probe 'x'"))
    (True, "no probe 'x'")
    """

    __str__ = BaseException.__str__


class ProbeTable(dict):
    """name -> ProbeState of a step: a dict whose missing name is an :class:`UnknownProbeError`
    naming the closest probe and all of them (a bare KeyError 'tip' before).

    Example
    -------
    >>> ProbeTable(tip=1)["tpi"]
    Traceback (most recent call last):
    ...
    core_se3.results.result.UnknownProbeError: no probe 'tpi'; did you mean 'tip'?; the probes: tip (Problem.add_probe adds one)
    """

    def __missing__(self, key):
        raise UnknownProbeError(f"no probe {key!r}{did_you_mean(key, self)}; the probes: "
                                f"{', '.join(map(str, self)) or 'none'} (Problem.add_probe adds one)")


@dataclass
class StepResult:
    """One converged (stored) state: its load factor, frames, Newton history, the total lab
    reaction and applied force and moment (about the origin), the probes
    (name -> :class:`ProbeState`: u, rotation R R0^T, rotation_vector unwrapped, rotation_angle), the
    scales of the balance check, and (path following) the stability of the state.

    Attributes
    ----------
    load_factor : float
        lam of the state.
    g : (n, 4, 4) ndarray
        Nodal frames.
    iterations : int
        Newton iterations of the step; ``residual_history``: the relative residual of each.
    backend : str
        'numpy' or 'numba': the backend that evaluated the converged state (``core_se3.backend``).
    max_correction : float or None
        The largest Newton correction |eta|_s / ell (relative to the length scale, rotations
        times ell: ``solvers.convergence.increment_norm``) of the converged tries since the
        previous stored step -- how far the step moved the state; None where not counted
        (linear analysis, arc length, the start).
    residual_floor : float
        The round-off floor of the last relative residual: 1e3 eps times the element's force
        scale over the residual's scale (``solvers.convergence.relative_residual``; 0 when not
        evaluated).  Where the loads vanish (a stress-free state on the path) internal and
        external forces are round-off themselves, so the relative residual is of order 1 and
        this floor exceeds it: the state is converged to round-off (see
        :func:`core_se3.results.format_residual`).
    residual_force, residual_moment : float or None
        The Euclidean norms of the force [force] and moment [force x length] parts of the
        residual r_int - f_ext on the free dofs at the state (``results.recorder.residual_parts``;
        the relative ``residual_history`` combines them over a force scale, moments / ell); None
        when not recorded.
    reaction_force, reaction_moment : (3,) ndarray
        Total lab reaction of the supports [force], its moment about the origin [force x length]:
        of the held dofs and of the penalty-spring supports (``Load.support_force``: lab,
        tilt and rotation-component springs) alike.
    applied_force, applied_moment : (3,) ndarray
        The same of the applied loads (the supports' springs not among them); at equilibrium
        they cancel the reactions
        (``balance_error``, relative to ``scale``, the sums of the nodal magnitudes).
    probes : dict
        name -> :class:`ProbeState` (u (3,) [length], rotation (3, 3), rotation_vector (3,) [rad]
        unwrapped along the path, rotation_angle [rad]): the keys of ``results.json``.
    stability : dict or None
        det_sign, negative_eigenvalues, q_dot_t of the tangent (path following only).
    attempts, linear_solves : int
        Newton tries (failed ones and sub-steps included) since the previous stored step, and
        the linear solves (sparse factorisations) they took: the cost of the step (0 for the
        initial state, None when not counted).
    contact : dict
        name -> dict(force (3,), moment (3,) about the origin, scalars such as penetration) of
        each constraint-force load (contact with an obstacle): not counted in the applied
        force; the balance is applied + reactions + contact.
    checks : dict
        What load stepping checked before accepting the state (``solvers.step_checks``):
        path_check (applied or not), contraction and travel of the accepted try's Newton
        corrections (< 1 and < 1.5: ``path_measures``), path_rejections (tries refused since the
        previous stored step), det_sign (the sign of det K at the state; None when not checked);
        with contact snap_probes and landed_elsewhere (``solvers.contact_probe``); {} when not recorded (path following, the initial state).
    support_reactions : dict
        name -> dict(force (3,), moment (3,) about the origin, point (3,), moment_about_point (3,))
        of every support (held dofs and penalty springs; names: ``results.support_names``, a
        scenario's ``supports[i]``): the lab force and moment it exerts on the shell, the
        centroid of its nodes in the state (linear analysis: in the reference) and the moment
        about that centroid.  A dof held by two supports reports with the first
        (``results.reaction_owners``).  They sum to ``reaction_force`` / ``reaction_moment``.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> st = p.solve(steps=1).final
    >>> (st.reaction_force.round(9) + 0.0).tolist(), bool(st.balance_error < 1e-9)   # balances the load
    ([0.0, 0.0, -1.0], True)
    """
    load_factor: float
    g: np.ndarray                      # (n, 4, 4) nodal frames
    iterations: int
    residual_history: list
    reaction_force: np.ndarray         # total lab reaction force at supports
    reaction_moment: np.ndarray        # total lab reaction moment about the origin
    applied_force: np.ndarray          # total applied lab force
    applied_moment: np.ndarray         # total applied lab moment about the origin
    probes: dict = field(default_factory=dict)   # name -> ProbeState
    scale: tuple = (0.0, 0.0)         # sums of nodal reaction/applied force and moment magnitudes
    stability: dict | None = None      # det_sign, negative_eigenvalues, q_dot_t (path following)
    attempts: int = 0                  # Newton tries since the previous stored step (failed included)
    linear_solves: int | None = 0      # linear solves of those tries (None: not counted)
    contact: dict = field(default_factory=dict)   # name -> dict(force, moment, ...) of contacts
    residual_floor: float = 0.0        # round-off floor of the last relative residual
    max_correction: float | None = None   # largest |eta|_s / ell of the step's converged tries
    backend: str = ""                  # the backend that evaluated the converged state ('auto' moves)
    checks: dict = field(default_factory=dict)   # what load stepping checked (solvers.step_checks)
    support_reactions: dict = field(default_factory=dict)   # name -> dict(force, moment, ...) per support
    residual_force: float | None = None    # |r| of the free force dofs [force]
    residual_moment: float | None = None   # |r| of the free moment dofs [force x length]

    def __post_init__(self):
        if not isinstance(self.probes, ProbeTable):
            self.probes = ProbeTable(self.probes)

    @property
    def balance_error(self):
        """|reactions + applied (+ contact)| relative to the sum of the nodal force (moment)
        magnitudes."""
        sF = max(self.scale[0], np.linalg.norm(self.applied_force), 1e-300)
        sM = max(self.scale[1], np.linalg.norm(self.applied_moment), 1e-300)
        F = self.reaction_force + self.applied_force
        M = self.reaction_moment + self.applied_moment
        for c in self.contact.values():
            F, M = F + c["force"], M + c["moment"]
        return max(np.linalg.norm(F) / sF, np.linalg.norm(M) / sM)


@dataclass
class Result:
    """The stored steps of a solve (``steps``; ``final`` the last), the time spent per phase
    (``timings``: setup, assembly, solve, other [s]), the per-(sub)step log, the element name
    and, for path following, the critical points found.

    Attributes
    ----------
    mesh : core_se3.mesh.Mesh
        The reference mesh.
    steps : list of StepResult
        The stored states, the initial one first; ``final`` (property): the last, or None.
    timings : dict
        Seconds per phase: setup, assembly, solve, other.
    log : list of dict
        One entry per (sub)step try: load factor, converged, iterations, residuals, reason.
    element : str
        The element's name; ``critical_points``: CriticalPoint list (path following).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> res = p.solve(steps=2)
    >>> len(res.steps), res.displacements().shape, res.timing_table().split()[:2]
    (3, (6, 3), ['phase', 'seconds'])
    """
    mesh: object
    steps: list = field(default_factory=list)
    timings: dict = field(default_factory=lambda: dict(setup=0.0, assembly=0.0, solve=0.0, other=0.0))
    log: list = field(default_factory=list)      # per (sub)step diagnostics
    element: str = "default"
    critical_points: list = field(default_factory=list)

    @property
    def final(self):
        return self.steps[-1] if self.steps else None

    def displacements(self, k=-1):
        """Nodal displacements (n, 3) of stored step k (an OptionError naming the steps there are
        for another k: a bare IndexError or TypeError before)."""
        n = len(self.steps)
        if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or not -n <= k < n:
            raise OptionError(f"step {k!r} is not stored: the result has {n} steps (k = 0 .. {n - 1}, or -1 the last)")
        return self.steps[k].g[:, :3, 3] - self.mesh.X

    def timing_table(self):
        """The timings as a small text table."""
        t = self.timings
        tot = sum(t.values())
        lines = [f"{'phase':<10}{'seconds':>10}{'share':>8}"]
        for key in ("setup", "assembly", "solve", "other"):
            lines.append(f"{key:<10}{t.get(key, 0.0):>10.3f}{100 * t.get(key, 0.0) / max(tot, 1e-300):>7.1f}%")
        lines.append(f"{'total':<10}{tot:>10.3f}")
        return "\n".join(lines)

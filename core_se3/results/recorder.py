"""The one step recorder: probe states with continuously unwrapped rotations, support reactions
and the global balance, turned into :class:`~core_se3.results.StepResult` objects.

Every solver records through it (load control, arc length, displacement control), so that a
step means the same thing whichever path produced it.
"""
from __future__ import annotations

import numpy as np

from .result import ProbeState, StepResult, unwrap_rotation

__all__ = ["StepRecorder", "lab_totals", "own_magnitudes", "restore_multipliers", "initial_state",
           "support_names", "reaction_owners", "residual_parts"]


def initial_state(g_init, g0):
    """(frames, unwrapped) of a solve's start: ``g_init`` None (the reference frames g0), frames
    (n, 4, 4), or a :class:`StepResult` -- its frames and its probes' unwrapped rotation vectors
    (name -> (3,)), which the solve continues.  From bare frames the probes' rotations start
    from their value modulo 2 pi: a strip's tip rolled to 1.2 pi and continued to 1.3 pi read
    0.8 pi and 0.7 pi.

    Example
    -------
    >>> import numpy as np
    >>> g, w = initial_state(None, np.eye(4)[None])
    >>> g.shape, w
    ((1, 4, 4), None)
    """
    if g_init is None:
        return np.array(g0, float), None
    if isinstance(g_init, StepResult):
        return np.array(g_init.g, float), {name: np.asarray(p["rotation_vector"], float)
                                           for name, p in g_init.probes.items()}
    return np.array(g_init, float), None


def lab_totals(g, f, magnitudes=False):
    """Total lab force and moment about the origin of generalised nodal forces f (n, 6) (and,
    if asked, the sums of their nodal magnitudes, the scale of the balance check).

    Parameters
    ----------
    g : (n, 4, 4) array
        Nodal frames (positions and rotations).
    f : (n, 6) array
        Body-frame forces [force] and moments [force x length] (e.g. reactions or loads).
    magnitudes : bool, optional
        Also return sum_i |F_i| and sum_i |M_i|.

    Returns
    -------
    F, M : (3,) ndarray
        sum_i R_i f_i,v and sum_i (R_i f_i,w + phi_i x R_i f_i,v); then the two sums if asked.

    Example
    -------
    >>> import numpy as np
    >>> g = np.broadcast_to(np.eye(4), (2, 4, 4)).copy(); g[1, 0, 3] = 2.0
    >>> f = np.zeros((2, 6)); f[1, 2] = 1.0                      # 1 along z at x = 2
    >>> [v.tolist() for v in lab_totals(g, f)]
    [[0.0, 0.0, 1.0], [0.0, -2.0, 0.0]]
    """
    R = g[:, :3, :3]
    F = np.einsum("nij,nj->ni", R, f[:, :3])
    M = np.einsum("nij,nj->ni", R, f[:, 3:]) + np.cross(g[:, :3, 3], F)
    if magnitudes:
        return F.sum(0), M.sum(0), np.linalg.norm(F, axis=1).sum(), np.linalg.norm(M, axis=1).sum()
    return F.sum(0), M.sum(0)


def own_magnitudes(g, loads, lam):
    """(sum |F_i|, sum |M_i|) of the applied loads' own nodal forces and moments, each load
    apart (body components: the frames' rotations do not change them), at frames g and load
    factor lam; (0, 0) for fewer than two (one load's are f_ext's).  The supports' springs and
    the constraint forces are not applied loads.  The balance's scale where loads cancel at
    their nodes (:meth:`StepRecorder.step`).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1e3, 0.0, 0.01))
    >>> p.add_pressure(2.0, follower=True); p.add_pressure(-2.0, follower=True)
    >>> [float(v) for v in own_magnitudes(p.mesh.g0, p.loads, 1.0)]    # 2 x 2 x the area
    [4.0, 0.0]
    """
    applied = [ld for ld in loads
               if not (getattr(ld, "support_force", False) or getattr(ld, "constraint_force", False))]
    if len(applied) < 2:
        return 0.0, 0.0
    f = np.stack([ld.evaluate(g, lam, tangent=False).f for ld in applied])
    return np.linalg.norm(f[..., :3], axis=-1).sum(), np.linalg.norm(f[..., 3:], axis=-1).sum()


def support_names(problem):
    """The names of the problem's supports, the keys of ``StepResult.support_reactions``: (names
    of ``problem.supports``, names of its penalty-spring loads (``Load.support_force``) in the
    order of ``problem.loads``).  A held support's is its ``name`` (scenario files:
    ``supports[i]``, the entry's index), else ``supports[i]`` with i its index in
    ``problem.supports``; a spring's is its ``support_name``, else ``loads[j]`` with j its index
    in ``problem.loads``.  Supports of one name (an entry that adds several) share one reaction.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0, 0, 1.0)); _ = p.add_lab_support("x1", (0, 0, 1), 1.0)
    >>> support_names(p)
    (['supports[0]'], ['loads[1]'])
    """
    held = [getattr(s, "name", None) or f"supports[{i}]" for i, s in enumerate(problem.supports)]
    springs = [getattr(ld, "support_name", None) or f"loads[{j}]" for j, ld in enumerate(problem.loads)
               if getattr(ld, "support_force", False)]
    return held, springs


def reaction_owners(problem):
    """(n, 6) ints: the index in ``problem.supports`` of the support that a held dof's reaction is
    reported with -- the first support holding that dof of that node (two supports may both hold
    a dof at its reference value: ``supports.check_conflict``) -- and -1 on free dofs.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1e3, 0.0, 0.01))
    >>> p.fix("x0", [2]); p.clamp([0])
    >>> reaction_owners(p)[[0, 2]].tolist()             # node 0: z to the fix, the rest to the clamp
    [[1, 1, 0, 1, 1, 1], [-1, -1, 0, -1, -1, -1]]
    """
    owner = np.full((problem.mesh.n_nodes, 6), -1, np.int64)
    for i in range(len(problem.supports) - 1, -1, -1):          # the first holding a dof wins
        s = problem.supports[i]
        owner[np.ix_(s.nodes, np.flatnonzero(s.fixed))] = i
    return owner


def _part(at, nodes, rows, f):
    """One support's share: (its nodes, their positions, then the positions, lab forces and lab
    moments of the nodes ``rows`` it acts on, from their forces f (k, 6): body components in the
    frames ``at``)."""
    R, x = at[rows, :3, :3], at[rows, :3, 3]
    F = np.einsum("nij,nj->ni", R, f[:, :3])
    return nodes, at[nodes, :3, 3], x, F, np.einsum("nij,nj->ni", R, f[:, 3:])


def _reaction_record(parts):
    """name -> dict(force, moment, point, moment_about_point) from name -> [``_part`` tuples]:
    the sums about the origin and about the centroid of the distinct nodes (the positions
    differenced first: exact for a part far from the origin)."""
    out = {}
    for name, items in parts.items():
        nodes, X, x, F, m = (np.concatenate([it[i] for it in items]) for i in range(5))
        c = X[np.unique(nodes, return_index=True)[1]].mean(0) if len(nodes) else np.zeros(3)
        out[name] = dict(force=F.sum(0), moment=(m + np.cross(x, F)).sum(0), point=c,
                         moment_about_point=(m + np.cross(x - c, F)).sum(0))
    return out


def _spring_list(springs, count):
    """The springs' forces given to ``StepRecorder.step``: a list of ``count`` (n, 6) arrays (an
    (n, 6) array alone, the older form, is the one spring's); a ValueError otherwise -- a total
    of several springs cannot be split between them.

    Example
    -------
    >>> import numpy as np
    >>> len(_spring_list(np.zeros((4, 6)), 1)), len(_spring_list([np.zeros((4, 6))] * 2, 2))
    (1, 2)
    """
    out = [springs] if isinstance(springs, np.ndarray) and springs.ndim == 2 else list(springs)
    if len(out) != count:
        raise ValueError(f"StepRecorder.step: the springs' forces must be a list of {count} (n, 6) arrays, one per "
                         f"spring support (Load.support_force), got {len(out)}")
    return out


def _compiled_log(R):
    """log_so3 of one rotation by the compiled kernel (the NumPy routine's twin, ~100x faster
    on a single 3x3 matrix: a probe is unwrapped after every converged state)."""
    from ..kernels.lie import log_so3
    w = np.empty(3)
    log_so3(np.ascontiguousarray(R, dtype=float), w)
    return w


class StepRecorder:
    """Records the steps of one path of ``problem`` (its probes, supports and length scale).

    ``probes(g)`` advances the unwrapped probe rotations to the state g (call it for every
    converged state, stored or not, so that the unwrapping is continuous); ``step(...)`` also
    computes the reactions and returns the StepResult.

    Between two converged states a probe may turn by more than pi (a roll-up into a full
    circle in one load step): its rotation R R0^T alone cannot tell 2 pi from 0.  The Newton
    solver then passes the try's start frames and the sum of its increments (g = g_start
    exp(eta_1) exp(eta_2) ...): the unwrapped vector at g_start (within pi of the previous
    state: prescribed turns are split below pi) plus R_start eta_w, the body increment's
    rotation in the lab, is the hint whose nearest 2 pi representation is taken.  That is
    exact for turns about a fixed axis (roll-ups, in-plane bending).  In 3D a multi-turn
    rotation vector is ill-conditioned wherever |w| passes near 2 pi k (exp is singular there,
    so a path near the identity has no unique continuous lift): it may then differ by 2 pi
    between step sizes, in one step or in many; positions and frames do not.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (its probes and constraint mask are read once).
    unwrapped : dict, optional
        name -> (3,) unwrapped rotation vector to start from (a resumed path).

    Example
    -------
    A rigid turn about z in steps of 2 rad: the probe's rotation vector stays continuous.

    >>> from core_se3 import Problem, Material, mesh, lie
    >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.add_probe("tip")
    >>> rec = StepRecorder(p)
    >>> [float(rec.probes(lie.exp([0, 0, 0, 0, 0, a]) @ p.mesh.g0)["tip"]["rotation_vector"][2].round(12)) for a in (2.0, 4.0, 6.0)]
    [2.0, 4.0, 6.0]
    """

    def __init__(self, problem, unwrapped=None):
        self.problem = problem
        self.g0 = problem.mesh.g0
        self.fixed = problem.constraint_mask()
        self.ell = problem.length_scale
        self.compiled = getattr(problem, "backend", "numpy") == "numba"
        self.owner = reaction_owners(problem)
        self.names = support_names(problem)
        self.reference = {name: pr.state(self.g0, compiled=self.compiled) for name, pr in problem.probes.items()}
        self.unwrapped = {name: np.zeros(3) for name in problem.probes}
        self._log = _compiled_log if self.compiled else None
        if unwrapped:
            self.unwrapped.update({k: np.array(v, float) for k, v in unwrapped.items()})

    def probes(self, g, start=None, increments=None, origin=None):
        """name -> dict(u, R, w) at the frames g, unwrapping the rotation vectors; ``start``
        (n, 4, 4) and ``increments`` (n, 6): the Newton try that reached g (class docstring);
        ``origin`` (3,): g holds positions relative to it (load stepping's iterate of a part far
        from the origin, ``solvers.equations.part_origin``), and so do the reference positions
        the displacements are taken from: u is then as exact as for the part at the origin.

        Example
        -------
        A full turn about z in one step (g = g0 exp(eta)): 2 pi with the increments, 0 without.

        >>> import numpy as np
        >>> from core_se3 import Problem, Material, mesh, lie
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01)); p.add_probe("tip")
        >>> eta = np.zeros((6, 6)); eta[:, 5] = 2 * np.pi
        >>> g = p.mesh.g0 @ lie.exp(eta)
        >>> [abs(float(StepRecorder(p).probes(g, *a)["tip"]["rotation_vector"][2].round(9))) for a in ((), (p.mesh.g0, eta))]
        [0.0, 6.283185307]
        """
        states = {}
        if origin is not None:
            g0 = self.g0.copy()
            g0[:, :3, 3] -= origin
        for name, pr in self.problem.probes.items():
            x, R = pr.state(g, compiled=self.compiled)
            x0, Rref = self.reference.get(name) or pr.state(self.g0)
            if origin is not None:
                x0 = pr.state(g0, compiled=self.compiled)[0]
            hint = self.unwrapped[name]
            if start is not None and increments is not None:
                _, Rs = pr.state(start, compiled=self.compiled)
                ws = unwrap_rotation(Rs @ Rref.T, hint, self._log)
                eta_w = pr.wa * increments[pr.node_a, 3:] + (1.0 - pr.wa) * increments[pr.node_b, 3:]
                hint = ws + Rs @ eta_w
            self.unwrapped[name] = unwrap_rotation(R @ Rref.T, hint, self._log)
            states[name] = ProbeState(x - x0, R @ Rref.T, self.unwrapped[name].copy())
        return states

    def linear_probes(self, eta):
        """name -> ProbeState of a linear analysis' increments eta (n, 6) about the reference
        (``Probe.linear``: the probes linearised, u and the rotation vector linear in the load,
        between nodes too); its rotation is exp of that vector.

        Example
        -------
        >>> import numpy as np
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1e3, 0.0, 0.01)); p.add_probe("tip")
        >>> eta = np.zeros((4, 6)); eta[:, 2] = 0.5
        >>> StepRecorder(p).linear_probes(eta)["tip"]["u"].round(12).tolist()
        [0.0, 0.0, 0.5]
        """
        from .. import lie
        out = {}
        for name, pr in self.problem.probes.items():
            u, w = pr.linear(self.g0, eta)
            self.unwrapped[name] = w
            out[name] = ProbeState(u, lie.exp_so3(w), w.copy())
        return out

    def support_forces(self, g, lam):
        """The generalised nodal forces (n, 6) of the supports' penalty springs (the problem's
        loads with ``support_force``) at the frames g: the support reactions that the springs
        exert (zero without springs).

        Example
        -------
        A lab spring k = 100 on z at the tip nodes, the tip lifted by 0.01: -1 on z at each.

        >>> import numpy as np
        >>> from core_se3 import Problem, Material, mesh
        >>> p = Problem(mesh.rectangle(1.0, 1.0, 1, 1), Material(1e3, 0.0, 0.01))
        >>> _ = p.add_lab_support("x1", (0, 0, 1), 100.0)
        >>> g = p.mesh.g0.copy(); g[p.nodes("x1"), 2, 3] = 0.01
        >>> StepRecorder(p).support_forces(g, 1.0)[:, 2].round(12).tolist()
        [0.0, -1.0, 0.0, -1.0]
        """
        f = np.zeros((len(g), 6))
        for fs in self.spring_forces(g, lam):
            f += fs
        return f

    def spring_forces(self, g, lam):
        """The list of the (n, 6) forces of each penalty-spring support (``support_force``), in the
        order of ``problem.loads``: their sum is :meth:`support_forces`."""
        return [ld.evaluate(g, lam, tangent=False).f for ld in self.problem.loads
                if getattr(ld, "support_force", False)]

    def support_reactions(self, at, reac, springs):
        """name -> dict(force, moment, point, moment_about_point) of every support (``support_names``):
        the lab force and moment about the origin that it exerts on the shell -- the held dofs'
        reactions ``reac`` (n, 6) (internal minus external force, body components in the frames
        ``at``) that it owns (:func:`reaction_owners`), or a spring's forces (``springs``: their
        list) -- and the moment about ``point``, the centroid of its nodes in ``at``.  Their sum
        is the total reaction."""
        parts = {}
        for i, s in enumerate(self.problem.supports):
            f = np.where(self.owner[s.nodes] == i, reac[s.nodes], 0.0)
            parts.setdefault(self.names[0][i], []).append(_part(at, s.nodes, s.nodes, f))
        sup = (ld for ld in self.problem.loads if getattr(ld, "support_force", False))
        for name, ld, f in zip(self.names[1], sup, springs):
            rows = np.flatnonzero(np.any(f != 0.0, axis=1))
            nodes = getattr(ld, "nodes", None)
            nodes = rows if nodes is None else np.asarray(nodes, np.int64).ravel()
            parts.setdefault(name, []).append(_part(at, nodes, rows, f[rows]))
        return _reaction_record(parts)

    def step(self, lam, g, iterations, history, forces, stability=None, turn=None, local=None):
        """The StepResult of a converged state: ``forces`` = (r_int, f_ext), the internal and
        external generalised nodal forces (n, 6) at g, or (r_int, f_ext, frames): the frames
        (n, 4, 4) they act in and the moments are taken with (default g; linear analysis: the
        reference frames, where its equations balance); ``turn`` = (start, increments) of the
        Newton try that reached g, as for :meth:`probes`; ``local``: (the frames relative to
        an origin, that origin) of the same state, which the probes read, see :meth:`probes`,
        and optionally the problem's loads restated on those frames (a far part's contact,
        ``solvers.origin.relocation``), whose forces and reports are then read there (from g, a
        stiff contact penalty k turns the positions' round-off eps |x0| into forces k eps |x0|).

        The supports' penalty springs (``Load.support_force``) are support reactions: their
        forces, part of f_ext, count with the reactions, not the applied loads (a fourth entry of
        ``forces``, the list of each spring's (n, 6) forces in the same frames, gives them: linear
        analysis, whose springs' forces are those of the linear equations; default: evaluated at
        g).  Each support's share is ``support_reactions`` (:meth:`support_reactions`).  The loads that are
        constraint forces (``Load.constraint_force``: contact) are split off the applied loads:
        ``contact`` holds each one's lab force and moment (about the origin) with its ``report``
        scalars, and the balance sums applied, reactions and contact.  The balance's scales are
        the largest sums of nodal magnitudes of the reactions (with the springs or without) and
        of the loads (f_ext, the applied loads alone, or each applied load's own, summed: loads
        that cancel at their nodes, :func:`own_magnitudes`)."""
        r_int, f_ext, at, springs = (*forces, g, None)[:4] if len(forces) == 2 else (*forces, None)[:4]
        start, increments = turn if turn else (None, None)
        probes = self.probes(g, start, increments) if local is None else self.probes(local[0], start, increments,
                                                                                   local[1])
        reac = (r_int - f_ext) * self.fixed
        springs = self.spring_forces(g, lam) if springs is None else _spring_list(springs, len(self.names[1]))
        f_sup = np.sum(springs, axis=0) if springs else np.zeros_like(reac)
        f_app = np.array(f_ext, float) - f_sup
        RF, RM, sF, sM = lab_totals(at, reac + f_sup, magnitudes=True)
        # the scales: the largest nodal magnitudes of either split (a spring's force and the load
        # on the same node cancel in f_ext, the Dirichlet reactions alone may be ~0)
        mags = [lab_totals(at, f, magnitudes=True)[2:] for f in (reac, f_ext, f_app)]
        sF, sM = max(sF, mags[0][0]), max(sM, mags[0][1])
        aF, aM = max(m[0] for m in mags[1:]), max(m[1] for m in mags[1:])
        contact = {}
        frames, loads = (local[0], local[2]) if local is not None and len(local) > 2 else (g, self.problem.loads)
        for ld in (ld for ld in loads if getattr(ld, "constraint_force", False)):
            fc = ld.evaluate(frames, lam, tangent=False).f
            f_app -= fc
            CF, CM = lab_totals(g, fc)
            # the multipliers as the problem's load holds them (a relocated one's ``whole``)
            contact[ld.name] = dict(force=CF, moment=CM, multipliers=getattr(ld, "whole", ld).multipliers(),
                                    **ld.report(frames, lam))
        AF, AM = lab_totals(at, f_app)
        # loads that cancel at their nodes (two follower pressures +-p): f_ext and the reactions
        # are round-off, whose ratio read as a balance error of order 1 (0.46); their own size is the scale
        aF, aM = np.maximum((aF, aM), own_magnitudes(frames, loads, lam))
        ell = self.ell
        st = StepResult(lam, g.copy(), iterations, list(history), RF, RM, AF, AM, probes,
                        scale=(max(sF, aF, max(sM, aM) / ell), max(sM, aM, max(sF, aF) * ell)),
                        stability=stability, contact=contact,
                        backend=str(getattr(self.problem, "backend", "")),
                        support_reactions=self.support_reactions(at, reac, springs))
        st.residual_force, st.residual_moment = residual_parts(r_int, f_ext, self.fixed)
        return st


def residual_parts(r_int, f_ext, fixed):
    """(|r_F|, |r_M|): the Euclidean norms of the force and of the moment parts of the residual
    r = r_int - f_ext (n, 6) on the free dofs (``fixed`` (n, 6) the held ones) [force], [force x
    length] -- from the forces the step records, no further assembly.  The relative residual of
    the convergence test is sqrt(|r_F|^2 + (|r_M| / ell)^2) over its force scale
    (``solvers.convergence.relative_residual``); the parts say which converged, in their units.

    Example
    -------
    >>> import numpy as np
    >>> r = np.array([[3.0, 0, 4.0, 0, 0, 2.0], [9.0, 9.0, 9.0, 9.0, 9.0, 9.0]])
    >>> residual_parts(r, np.zeros_like(r), np.array([[False] * 6, [True] * 6]))
    (5.0, 2.0)
    """
    r = np.where(fixed, 0.0, np.asarray(r_int, float) - np.asarray(f_ext, float))
    return float(np.sqrt(np.einsum("ij,ij->", r[:, :3], r[:, :3]))), float(np.sqrt(np.einsum("ij,ij->", r[:, 3:], r[:, 3:])))


def restore_multipliers(problem, step):
    """Set the multipliers of the problem's constraint-force loads (contact) to those recorded
    with ``step`` (a StepResult), so that their forces and output fields evaluated afterwards at
    ``step.g`` are those of that step (the loads keep the multipliers of the last solve otherwise).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e4, 0.0, 0.02))
    >>> p.clamp("x0"); p.add_pressure(-0.004)
    >>> c = p.add_obstacle("half_space", point=(0, 0, -0.05), normal=(0, 0, 1), name="floor")
    >>> res = p.solve(load_factors=[0.7, 1.0])
    >>> restore_multipliers(p, res.steps[1])
    >>> bool(abs(c.total(res.steps[1].g, 0.7)[0][2] - res.steps[1].contact["floor"]["force"][2]) < 1e-15)
    True
    """
    for ld in problem.loads:
        rec = step.contact.get(getattr(ld, "name", None)) if getattr(ld, "constraint_force", False) else None
        if rec is not None and rec.get("multipliers") is not None:
            ld.set_multipliers(rec["multipliers"])

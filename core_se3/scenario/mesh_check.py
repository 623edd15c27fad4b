"""Is a scenario's mesh fine enough?  Its linear analysis on the mesh and on uniform refinements
of it, compared (``core-se3 check-mesh FILE.toml``).

Each level refines every quad into four (``[mesh] refine``; the new frames on the SE(3)
geodesics of the reference frames, ``mesh.refine``), builds the scenario anew on it and solves
the linear analysis at the scenario's final load factor (``control = "linear"``).  The old nodes
keep their ids, so the displacements of one level are compared with the next one's at the
coarse mesh's nodes; with them the strain energy 1/2 eta^T K0 eta and every probe.  A mesh whose
answer changes by more than ``tol`` under one refinement is not converged: the run on it would
be wrong by about as much (a well-behaved mesh's error is about 4/3 of the change at second
order).  This is what the default element's ElementWarning on coarse thin curved meshes asks
for: a bending-dominated shell (the pinched hemisphere) passes it, the spuriously flexible
membrane-dominated one (the Scordelis-Lo roof 2x2 at R/h 1e4) does not (docs/ELEMENTS.md).

The linear check cannot see contact ([[obstacles]] are left out: a linear analysis would pass
through them) nor large rotations, wrinkles or snap-through, which may need a finer mesh than the
linear response does.  ``nonlinear=True`` (``--nonlinear``) runs the scenario itself instead (its
own [solver], with its obstacles; load or displacement control) on each mesh and compares the
final states the same way (without the energy): a gripper's grasp or a roll-up, at the price of
the runs (the refined one has four times the elements).
"""
from __future__ import annotations

import copy
import math
import tempfile
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConvergenceError, ElementWarning, OptionError, ScenarioError
from ..mesh import refine
from ..solvers.linear import linear_solve

__all__ = ["MeshCheck", "check_mesh", "check_problem_mesh", "DEFAULT_TOL"]

#: the relative change under one refinement above which a mesh is reported as not converged
DEFAULT_TOL = 0.05


@dataclass
class MeshCheck:
    """The linear answers on the mesh and its refinements (``check_mesh``).

    Attributes
    ----------
    name : str
        The scenario's name; ``lam``: the load factor compared; ``nonlinear``: the scenario's own
        runs (True) or its linear analysis (False).
    levels : list of dict
        Per mesh (0: the scenario's own): ``elements``, ``dofs``, ``energy`` [force x length;
        None for the nonlinear runs], ``load`` (the loads' resultant force at lam [force]),
        ``moment`` (their resultant moment about the coarse nodes' centroid [force x length]),
        ``length`` (the mesh's extent), ``u_max`` (largest displacement at the coarse nodes
        [length]), ``probes`` (name -> u), ``layer`` (the free-edge layer's width that the
        default element's flagged coarse thin curved elements imply [length], else None).
    changes : list of dict
        Per pair of consecutive meshes: the relative changes ``energy`` |U_k / U_k+1 - 1| (None
        for the nonlinear runs), ``load`` (of the loads' resultant force at lam, on the reference
        geometry: the refined surface's area, or a model loaded differently),
        ``displacement`` max |u_k - u_k+1| / max |u_k+1| at the coarse nodes, and per probe;
        ``load`` is also the change of the resultant moment about the coarse nodes' centroid
        (``moment`` of the levels), over its size plus the force's times the mesh's extent.
    tol : float
        The largest change accepted for the scenario's mesh.
    dropped : list of str
        Sections left out of the check (obstacles in the linear analysis, design, sweep).
    warnings : list of str
        What the element said while building each level (e.g. ElementWarning), "level k: ...".

    Example
    -------
    >>> chk = MeshCheck("plate", 1.0, 0.05, levels=[{"energy": 1.0}, {"energy": 1.1}],
    ...                 changes=[{"energy": abs(1 / 1.1 - 1), "displacement": 0.02, "probes": {}}])
    >>> round(chk.change, 4), chk.converged                  # |U0/U1 - 1| = 9.1 %: more than 5 %
    (0.0909, False)
    """
    name: str
    lam: float
    tol: float
    nonlinear: bool = False
    levels: list = field(default_factory=list)
    changes: list = field(default_factory=list)
    dropped: list = field(default_factory=list)
    warnings: list = field(default_factory=list)

    @property
    def change(self):
        """The largest relative change from the scenario's mesh to its first refinement."""
        c = self.changes[0]
        return max(x for x in [c["energy"], c["displacement"], *c["probes"].values()] if x is not None)

    @property
    def converged(self):
        """True if that change is within ``tol`` (and the refined model is loaded alike: its
        load's resultant within ``tol`` too)."""
        return self.change <= self.tol and self.changes[0].get("load", 0.0) <= self.tol

    @property
    def energy_order(self):
        """The observed order of convergence of the energy, log2 of the ratio of its first two
        changes (None with fewer than three meshes or a change of zero)."""
        if len(self.changes) < 2 or self.nonlinear:
            return None
        a, b = (abs(self.levels[k]["energy"] - self.levels[k + 1]["energy"]) for k in (0, 1))
        return math.log2(a / b) if a > 0 and b > 0 else None

    def to_dict(self):
        """A JSON-ready dict of the check."""
        return dict(name=self.name, lam=self.lam, tol=self.tol, nonlinear=self.nonlinear, change=self.change,
                    converged=self.converged,
                    energy_order=self.energy_order, levels=self.levels, changes=self.changes,
                    dropped=self.dropped, warnings=self.warnings)

    def report(self):
        """The check as text: one line per mesh, the changes, the verdict."""
        probes = list(self.levels[0]["probes"])
        head = f"{'mesh':<6}{'elements':>10}{'dofs':>10}{'energy':>14}{'max |u|':>14}" + "".join(
            f"{'|u| ' + p:>16}" for p in probes)
        what = "the scenario's run" if self.nonlinear else "linear analysis"
        out = [f"{self.name}: {what} at load factor {self.lam:g} on the mesh and {len(self.levels) - 1} "
               f"uniform refinement(s)", head]
        for k, lv in enumerate(self.levels):
            energy = "-" if lv["energy"] is None else f"{lv['energy']:.6g}"
            out.append(f"{'+' + str(k) if k else 'own':<6}{lv['elements']:>10}{lv['dofs']:>10}{energy:>14}"
                       f"{lv['u_max']:>14.6g}" + "".join(f"{np.linalg.norm(lv['probes'][p]):>16.6g}" for p in probes))
        for k, c in enumerate(self.changes):
            pr = "".join(f", probe {p} {100 * v:.3g} %" for p, v in c["probes"].items())
            energy = "" if c["energy"] is None else f"energy {100 * c['energy']:.3g} %, "
            out.append(f"change {k} -> {k + 1}: {energy}displacements at the coarse nodes {100 * c['displacement']:.3g} %{pr}")
            if c.get("load", 0.0) > 1e-6:
                out.append(f"  the loads' resultant force or moment changes by {100 * c['load']:.3g} % (the refined "
                           "surface's area, or a force or moment per node on a line, which grows with its nodes: use "
                           "an edge load; or elements selected by id, which name other elements on a refined mesh)")
        if self.energy_order is not None:
            out.append(f"observed order of the energy's convergence: {self.energy_order:.2f} (2 in the asymptotic range)")
        for w in self.warnings:
            out.append(f"note: {w}")
        if self.dropped:
            out.append(f"note: left out of the check: {', '.join(self.dropped)}")
        if self.converged:
            out.append(f"verdict: the mesh's answer changes by {100 * self.change:.3g} % under refinement, "
                       f"within {100 * self.tol:g} % (its own error is larger than the change: about 4/3 of it "
                       "where the answer converges at second order)")
        elif self.changes[0].get("load", 0.0) > self.tol:
            out.append(f"verdict: NOT comparable: the refined model is loaded differently (the resultant force or "
                       f"moment changes by {100 * self.changes[0]['load']:.3g} %, more than {100 * self.tol:g} %): a "
                       "force or moment per node on a line grows with its nodes, give it as an edge load (a total "
                       "along the line); elements selected by id are other elements on a refined mesh, select "
                       "them by region or a predicate")
        else:
            out.append(f"verdict: NOT converged: the mesh's answer changes by {100 * self.change:.3g} % under "
                       f"refinement (more than {100 * self.tol:g} %): a run on this mesh would be wrong by about as "
                       f"much; refine it ([mesh] refine = 1, or a finer mesh) and check again")
            layer = self.levels[0].get("layer")
            if layer is not None:
                out.append(f"  where this is a thin curved shell with free edges, its free-edge layer is about "
                           f"l = {layer:.3g} wide: a mesh graded toward those edges ([mesh] grade; elements about "
                           f"0.7 l = {0.7 * layer:.3g} wide there, growing by at most 1.7) resolves it with fewer "
                           f"elements than refining everywhere (docs/ELEMENTS.md, \"Graded meshes\")")
        return "\n".join(out)


def check_mesh(scn, levels=1, tol=DEFAULT_TOL, nonlinear=False):
    """The linear analysis of ``scn`` on its mesh and ``levels`` uniform refinements, compared
    (module docstring); with ``nonlinear`` the scenario's own runs.

    Parameters
    ----------
    scn : core_se3.scenario.Scenario
        The scenario (any control: the check solves its linear analysis at ``lam_end``).
    levels : int
        Refinements after the scenario's own mesh (>= 1; each has four times the elements).
    tol : float
        The largest relative change accepted under the first refinement.
    nonlinear : bool
        Run the scenario itself (its [solver], load or displacement control, and its obstacles)
        on every mesh and compare the final states (no output files are written).

    Returns
    -------
    MeshCheck

    Raises
    ------
    OptionError
        For levels < 1 or tol <= 0, a scenario that the linear analysis does not load (zero
        energy: a scene driven by contact alone), or ``nonlinear`` with arc length.
    ConvergenceError
        A run of ``nonlinear`` that did not converge (the message names the mesh).

    Example
    -------
    A cantilever strip under an end force: 8 elements are enough for 5 %.

    >>> from core_se3 import scenario
    >>> scn = scenario.from_dict({"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 8, "ny": 1},
    ...     "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
    ...     "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]})
    >>> chk = check_mesh(scn)
    >>> chk.converged, round(chk.change, 4)
    (True, 0.0029)
    """
    _check_options(levels, tol)
    if nonlinear and scn.solver["control"] == "arclength":
        raise OptionError(f"{scn.file}: arc length ends where its path ends, at a different point on every mesh: "
                          "compare the load-deflection curves (probes.png) of runs with [mesh] refine = 0 and 1, "
                          "or check the linear analysis (without --nonlinear)")
    lam = float(scn.solver.get("lam_end", 1.0))
    out = MeshCheck(scn.name, lam, float(tol), bool(nonlinear))

    def level(k):
        s, out.dropped, said = _level_scenario(scn, k, nonlinear)
        return (_run_level if nonlinear else _linear_level)(s, lam, scn.mesh.n_nodes, k) + (said,)
    return _compare(out, scn.mesh.n_nodes, levels, level,
                    f"{scn.file}: the linear analysis of {scn.name!r} has no strain energy (nothing loads the shell "
                    "without its obstacles): the mesh check needs a load or a prescribed motion")


def check_problem_mesh(build, mesh, levels=1, tol=DEFAULT_TOL, lam=1.0, nonlinear=False, **solve_options):
    """:func:`check_mesh` for a Problem built in Python: ``build(mesh) -> Problem`` is called on
    ``mesh`` and on its uniform refinements (``mesh.refine``), and the answers compared.

    ``build`` must select its nodes by name (the mesh's regions and node sets, which refinement
    carries) or by a predicate of the positions: node ids below ``mesh.n_nodes`` keep theirs, but
    a line given by ids does not get its new nodes (a support that holds both ends of an element
    edge and not the new node between them is refused), and element ids change.

    Parameters
    ----------
    build : callable
        mesh -> core_se3.Problem (supports, loads and probes on that mesh).
    mesh : core_se3.mesh.Mesh
        The mesh to check.
    levels, tol : int, float
        As :func:`check_mesh`.
    lam : float
        The load factor compared (the linear analysis at lam, or the runs to lam_end = lam).
    nonlinear : bool
        ``problem.solve(lam_end=lam, **solve_options)`` on every mesh instead of the linear
        analysis (``solve_options``: steps, control, ...; for the linear analysis: linear_solver).

    Returns
    -------
    MeshCheck

    Example
    -------
    >>> from core_se3 import Material, Problem, mesh
    >>> def strip(m):
    ...     p = Problem(m, Material(1.2e6, 0.0, 0.1))
    ...     p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1e-3)); p.add_probe("tip", "x1")
    ...     return p
    >>> chk = check_problem_mesh(strip, mesh.rectangle(10.0, 1.0, 8, 1))
    >>> chk.converged, round(chk.change, 4)                  # as the scenario's check_mesh
    (True, 0.0029)
    """
    _check_options(levels, tol)
    out = MeshCheck(getattr(build, "__name__", "problem"), float(lam), float(tol), bool(nonlinear))
    n0 = mesh.n_nodes
    held = np.zeros((n0, 6), bool)              # the dofs the unrefined problem holds

    def level(k):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            p = build(refine(mesh, k))
            p.check_element()                    # the element's warnings (supports known), caught here
        if k == 0:
            held[:] = p.constraint_mask()
        elif k == 1:
            _check_held_lines(mesh, held, p.constraint_mask())
        if nonlinear:
            try:
                with warnings.catch_warnings():         # said above, once per level
                    warnings.simplefilter("ignore", ElementWarning)
                    res = p.solve(lam_end=lam, **solve_options)
            except ConvergenceError as exc:
                raise ConvergenceError(_failed_level(k, p.mesh, str(exc), "build(mesh.refine(mesh, {k}))"),
                                       getattr(exc, "result", None)) from exc
            energy = None
        else:
            res = linear_solve(p, lam_end=lam, **solve_options)
            energy = float(res.log[-1]["energy"])
        u = res.displacements()[:n0]
        return _level(p, energy, u, res.final.probes, lam), u, _said(caught)
    return _compare(out, n0, levels, level, "the linear analysis has no strain energy (nothing loads the shell): "
                                            "the mesh check needs a load or a prescribed motion")


def _check_held_lines(mesh, held, held_refined):
    """OptionError if a dof held at both ends of an element edge of ``mesh`` is free at the new
    node between them (``held``, ``held_refined``: the constraint masks on the mesh and on its
    first refinement, whose node n_nodes + e is edge e's midpoint)."""
    E = mesh.edge_nodes
    both = held[E[:, 0]] & held[E[:, 1]]
    lost = both & ~held_refined[mesh.n_nodes + np.arange(len(E))]
    if lost.any():
        e = int(np.flatnonzero(lost.any(1))[0])
        raise OptionError(f"build(mesh) holds nodes {E[e, 0]} and {E[e, 1]} (dofs {np.flatnonzero(lost[e]).tolist()}) "
                          f"but not the new node between them on the refined mesh: the refined problem would be "
                          f"supported less; select supported lines by name (the mesh's node sets, which refinement "
                          f"carries) or by a predicate of the positions, not by ids")


def _check_options(levels, tol):
    if isinstance(levels, bool) or int(levels) != levels or levels < 1:
        raise OptionError(f"check_mesh needs levels >= 1 (refinements), got {levels!r}")
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
        raise OptionError(f"check_mesh needs a tolerance tol > 0, got {tol!r}")


def _compare(out, n0, levels, level, unloaded):
    """Fill ``out`` with ``level(k) -> (level dict, u at the n0 coarse nodes, warnings)`` for
    k = 0 ... levels and the changes between consecutive levels.  An interrupt (Ctrl-C,
    ``io.lifecycle.Terminated``) carries the levels done so far as its ``mesh_check``."""
    for k in range(int(levels) + 1):
        try:
            lv, u, said = level(k)
        except KeyboardInterrupt as exc:
            exc.mesh_check = out
            raise
        out.warnings += [f"level {k}: {w}" for w in said]
        if k == 0 and not out.nonlinear and not lv["energy"] > 0:
            raise OptionError(unloaded)
        if k:
            out.changes.append(_change(out.levels[-1], lv, u_prev, u))
        out.levels.append(lv)
        u_prev = u
    return out


def _failed_level(k, mesh, why, how):
    """The message of a run that failed on refinement level k (the run's checkpoint advice cut)."""
    why = why.split(" The checkpoint keeps")[0]          # the run's files are not kept here
    coarse = (" -- the coarser mesh's run converged, so the meshes disagree on the path (a limit point or a snap "
              f"that only the refined mesh resolves?): run {how.format(k=k)} and look") if k else ""
    return f"mesh check, refinement level {k} ({mesh.n_elements} elements): {why}{coarse}"


def _linear_level(s, lam, n0, k):
    """(level dict, displacements at the n0 coarse nodes) of the linear analysis of ``s``."""
    res = linear_solve(s.problem, lam_end=lam, linear_solver=s.solver.get("linear_solver"))
    u = res.displacements()[:n0]
    return _level(s.problem, float(res.log[-1]["energy"]), u, res.final.probes, lam), u


def _run_level(s, lam, n0, k):
    """(level dict, displacements at the n0 coarse nodes) of the run of ``s`` (no output files)."""
    from .runner import run
    with tempfile.TemporaryDirectory() as d:
        try:
            with warnings.catch_warnings():             # said when the level was built
                warnings.simplefilter("ignore", ElementWarning)
                res = run(s, out=d, progress=False)
        except ConvergenceError as exc:
            raise ConvergenceError(_failed_level(k, s.mesh, str(exc), "the scenario with [mesh] refine = {k}"),
                                   getattr(exc, "result", None)) from exc
    u = (res.g[:, :3, 3] - s.mesh.X)[:n0]
    probes = {name: p["u"] for name, p in res.doc["steps"][-1]["probes"].items()}
    return _level(s.problem, None, u, probes, lam), u


def _level(problem, energy, u, probes, lam):
    g0 = problem.mesh.g0
    f = problem.external(g0, lam, tangent=False)[0]                   # in the reference frames
    F = np.einsum("nij,nj->ni", g0[:, :3, :3], f[:, :3])              # lab forces and couples
    C = np.einsum("nij,nj->ni", g0[:, :3, :3], f[:, 3:])
    # the resultant moment about the coarse nodes' centroid (the same point at every level):
    # couples that change with the mesh (a moment per node, a magnet on elements by id) too
    x = g0[:, :3, 3] - g0[:len(u), :3, 3].mean(0)
    moment = (np.cross(x, F) + C).sum(0)
    return dict(elements=problem.mesh.n_elements, dofs=int((~problem.constraint_mask()).sum()), energy=energy,
                u_max=float(np.linalg.norm(u, axis=1).max()), load=F.sum(0).tolist(), moment=moment.tolist(),
                length=problem.mesh.length_scale, layer=problem.check_element(warn=False),
                probes={name: np.asarray(p["u"] if isinstance(p, dict) else p, float).tolist()
                        for name, p in probes.items()})


def _change(a, b, ua, ub):
    """Relative changes from level a to level b (displacements ua, ub at the coarse nodes)."""
    scale = float(np.linalg.norm(ub, axis=1).max())
    disp = float(np.linalg.norm(ua - ub, axis=1).max()) / scale if scale > 0 else 0.0
    probes = {}
    for name, pa in a["probes"].items():
        pb = np.asarray(b["probes"][name])
        nb = float(np.linalg.norm(pb))
        probes[name] = float(np.linalg.norm(np.asarray(pa) - pb)) / nb if nb > 0 else 0.0
    energy = None if a["energy"] is None else abs(a["energy"] / b["energy"] - 1.0)
    fb = np.asarray(b["load"])
    load = float(np.linalg.norm(np.asarray(a["load"]) - fb) / np.linalg.norm(fb)) if np.any(fb) else 0.0
    mb = np.asarray(b["moment"])
    scale = float(np.linalg.norm(mb) + np.linalg.norm(fb) * b["length"])   # a force's moment over the mesh
    if scale > 0:
        load = max(load, float(np.linalg.norm(np.asarray(a["moment"]) - mb)) / scale)
    return dict(energy=energy, displacement=disp, probes=probes, load=load)


def _level_scenario(scn, k, nonlinear):
    """The scenario refined k more times, with a linear [solver] (or its own, ``nonlinear``);
    (Scenario, dropped sections, the element's warnings while building it)."""
    from .spec import from_dict
    doc = copy.deepcopy(scn.raw)
    doc["mesh"] = dict(doc["mesh"], refine=int(doc["mesh"].get("refine", 0)) + k)
    if nonlinear:
        doc["output"] = {"vtu": False, "plots": False, "picture": False}
        dropped = [name for name in ("design", "sweep") if doc.pop(name, None)]
    else:
        solver = {"control": "linear", "lam_end": scn.solver.get("lam_end", 1.0)}
        for key in ("linear_solver", "element"):        # the element is the model's: check the user's own
            if key in (doc.get("solver") or {}):
                solver[key] = doc["solver"][key]
        doc["solver"] = solver
        dropped = [name for name in ("obstacles", "design", "sweep") if doc.pop(name, None)]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            s = from_dict(doc, file=scn.file, base_dir=scn.base_dir, default_name=scn.default_name, strict=scn.strict)
        except ScenarioError as exc:
            if "obstacles" not in dropped:
                raise
            raise OptionError(f"the mesh check leaves the obstacles out (a linear analysis would pass through "
                              f"them), and without them the scenario is not valid: {exc}; check the runs "
                              "themselves with --nonlinear") from None
        s.problem.check_element()               # the element's warnings (supports known), caught here
    return s, dropped, _said(caught)


def _said(caught):
    """The first sentence (what and where) of each ElementWarning caught; the rest explains
    (docs/ELEMENTS.md)."""
    return sorted({str(w.message).split(". ")[0] for w in caught if issubclass(w.category, ElementWarning)})

"""Load-stepped Newton solution of a ``core_se3.cases`` case with the fenicsx_ref shell."""
from __future__ import annotations

import time
from math import pi

import numpy as np

from core_se3.catalogue import get_case

from .reference import (apply_variant, case_domain, case_params, check_inputs, check_springs,
                        literature_error, reference_error, reference_load_factors, reference_mismatch)

__all__ = ["run_case", "torsion_constant"]

THETA_LIMIT = pi  # the 2-parameter director map is singular at |theta| = pi


class _Timer:
    def __init__(self):
        self.t = dict(setup=0.0, jit=0.0, assembly=0.0, solve=0.0, other=0.0)


class _Problem:
    """Residual/Jacobian callbacks for dolfinx.nls.petsc.NewtonSolver, with point loads added
    to the assembled residual and timings/residual norms recorded."""

    def __init__(self, L, a, bcs, model, timer):
        self.L, self.a, self.bcs, self.model, self.timer = L, a, bcs, model, timer
        self.point_dofs = []
        V = model.V
        for point, vec in model.point_loads:
            for i in range(3):
                Vi = V.sub(0).sub(i)
                Vc, _ = Vi.collapse()
                dofs = dolfinx.fem.locate_dofs_geometrical(
                    [Vi, Vc], lambda X, p=point: np.isclose(X[0], p[0]) & np.isclose(X[1], p[1]))[0]
                if len(dofs) != 1:
                    from core_se3.errors import MeshError
                    raise MeshError(f"point load at (s, y) = {tuple(point)}: no unique mesh node there "
                                    f"(found {len(dofs)}); the degree-2 grid has nodes at every half "
                                    "cell: choose nx, ny that put one at the point")
                self.point_dofs.append((int(dofs[0]), float(vec[i])))
        self.residuals = []

    def form(self, x):
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def F(self, x, b):
        t0 = time.perf_counter()
        with b.localForm() as bl:
            bl.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.L)
        if self.point_dofs:
            lam = float(self.model.lam.value)
            with b.localForm() as bl:
                for dof, val in self.point_dofs:
                    bl.array[dof] -= lam * val
        dolfinx.fem.petsc.apply_lifting(b, [self.a], bcs=[self.bcs], x0=[x], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)
        self.residuals.append(b.norm())
        self.timer.t["assembly"] += time.perf_counter() - t0

    def J(self, x, A):
        t0 = time.perf_counter()
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(A, self.a, self.bcs)
        A.assemble()
        self.timer.t["assembly"] += time.perf_counter() - t0


def _import_dolfinx():
    global dolfinx, PETSc, MPI
    import dolfinx  # noqa: F401  (fails loudly when DOLFINx is missing)
    import dolfinx.fem.petsc
    import dolfinx.geometry
    import dolfinx.nls.petsc
    from mpi4py import MPI
    from petsc4py import PETSc


_LOAD_KINDS = ("edge_force", "edge_moment", "pressure", "point_force", "edge_rotation")


def _check_supported(case, loads):
    """NotImplementedError naming what of the case this model cannot represent (before the
    inputs are checked: a case it cannot run should not be reported as a bad mesh)."""
    if case.geometry not in ("strip", "arch", "semicylinder"):
        raise NotImplementedError(f"fenicsx_ref: case {case.name!r} has geometry {case.geometry!r}; "
                                  "it supports 'strip', 'arch' and 'semicylinder'")
    family = case.extra.get("family")
    if family not in (None, "sze"):  # contact, friction, magnetic, design: built by core_se3's family
        raise NotImplementedError(f"fenicsx_ref: case {case.name!r} belongs to core_se3's {family!r} "
                                  "family (obstacles, fields or design variables built there), which "
                                  "this model does not represent")
    bad = sorted({ld["kind"] for ld in loads} - set(_LOAD_KINDS))
    if bad:
        raise NotImplementedError(f"fenicsx_ref: case {case.name!r} has load kind(s) {', '.join(bad)}; "
                                  f"it implements {', '.join(_LOAD_KINDS)}")


def _comm_size():
    return MPI.COMM_WORLD.size


def _tip_evaluator(model, point=None):
    """Returns f(w) -> (u (3,), theta (3,)) at the parameter point (s, y) of the probe
    (default: 'tip' = midpoint of the free edge x1)."""
    mesh = model.mesh
    s, y = point if point is not None else model.edge_midpoint["x1"]
    pt = np.array([[s, y, 0.0]])
    tree = dolfinx.geometry.BoundingBoxTree(mesh, mesh.topology.dim)
    cand = dolfinx.geometry.compute_collisions(tree, pt)
    cells = dolfinx.geometry.compute_colliding_cells(mesh, cand, pt)
    cell = int(cells.links(0)[0])
    t1, t2, _ = model.frame_np(s)

    subs = []
    for i in range(2):
        Vi, dofmap = model.V.sub(i).collapse()
        subs.append((dolfinx.fem.Function(Vi), np.asarray(dofmap)))
    cells_arr = np.array([cell], dtype=np.int32)

    def ev(w):
        vals = []
        for f, dofmap in subs:
            f.x.array[:] = w.x.array[dofmap]
            vals.append(np.asarray(f.eval(pt, cells_arr)).reshape(-1))
        return vals[0][:3].copy(), vals[1][0] * t1 + vals[1][1] * t2
    return ev


def _signed_angle(theta, prev):
    """Rotation angle about -y (the planar references' axis), continued across steps."""
    mag = float(np.linalg.norm(theta))
    sgn = -1.0 if theta[1] > 0 else 1.0
    a = sgn * mag
    if prev is not None:  # unwrap: choose the 2 pi multiple closest to the previous angle
        a += 2 * pi * round((prev - a) / (2 * pi))
    return a


def _newton(model, problem, timer, max_it=25, rtol=1e-10, atol=1e-14, criterion="incremental"):
    solver = dolfinx.nls.petsc.NewtonSolver(MPI.COMM_WORLD, problem)
    solver.convergence_criterion = criterion
    solver.rtol, solver.atol, solver.max_it = rtol, atol, max_it
    solver.error_on_nonconvergence = False
    solver.report = False
    ksp = solver.krylov_solver
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("lu")
    pc.setFactorSolverType("mumps")
    return solver


def run_case(name, mesh=None, overrides=None, steps=None, integration="psri", shear_factor=1.0,
             cell="quadrilateral", load_factors=None, theta_limit=THETA_LIMIT, max_cuts=10,
             include_reference_loads=True, rtol=1e-10, atol=None, keep_residuals=False,
             criterion="incremental", return_state=False, point_loads=()):
    """Solve case ``name`` and return a result dict (schema "core-se3-result", version 1).

    mesh: (nx, ny) elements (default: the case's); overrides: case parameters to change;
    steps: number of uniform load steps (default: the case's); the reference loads inside the
    load range are added to the steps so that the error is measured at each of them.
    load_factors: explicit list of load factors (replaces the uniform steps).
    point_loads: extra dead point forces [((s, y), (fx, fy, fz)), ...] at lam = 1, at mesh nodes.
    theta_limit: references whose |theta| reaches it are dropped and the path ends before them
    (the 2-parameter director map is singular at |theta| = pi).
    """
    _import_dolfinx()
    from .model import ShellModel
    if _comm_size() > 1:  # every rank raises here, before any collective call: no hang
        from core_se3.errors import ParallelError
        raise ParallelError(f"fenicsx_ref runs serial only (its probes and point loads are evaluated "
                            f"on the local process; under {_comm_size()} MPI processes one rank found no "
                            "probe cell: IndexError); run it without mpirun")

    timer = _Timer()
    t_start = time.perf_counter()
    case = get_case(name)
    params = case_params(case, overrides or {})
    loads, ref = apply_variant(case, params)
    _check_supported(case, loads)
    mesh = tuple(mesh) if mesh is not None else tuple(case.mesh)
    check_inputs(case, params, mesh, steps, shear_factor, load_factors, cell)
    check_springs(case, params)
    skipped = reference_mismatch(ref, params)
    if skipped:  # a table for other parameters: no error rather than a wrong one (as core_se3)
        skipped, ref = dict(entry=ref.entry, block=ref.block, error=None, file="elastica.json",
                            note=f"not compared: {skipped}"), None
    nx, ny = (int(n) for n in mesh)
    length, width, box = case_domain(case, params)
    rot_loads = [ld for ld in loads if ld["kind"] == "edge_rotation"]
    axes = [np.asarray(ld["direction"], float) for ld in loads if ld["kind"] == "edge_moment"]
    if any(np.linalg.norm(np.cross(axes[0], b)) > 1e-12 * np.linalg.norm(b) for b in axes[1:]):
        raise NotImplementedError(
            f"case {name!r}: edge moments about more than one axis rotate the edge about a moving "
            "axis, where m . delta(theta) is not their virtual work (fenicsx_ref carries planar moments "
            "only); use core_se3")

    # ----- load factors -------------------------------------------------------------------------
    lam0, lam1 = case.lam_range
    ref_lams, ref_info = ([], None)
    if ref is not None:
        ref_lams, lam_cap, ref_info = reference_load_factors(case, params, ref, theta_limit)
        lam1 = min(lam1, lam_cap)
    if rot_loads:  # prescribed rotations: the rotation vector alpha*axis must stay below pi
        amax = max(abs(ld["magnitude"]) for ld in rot_loads)
        if amax * lam1 >= theta_limit * (1 - 1e-9):
            lam1 = theta_limit * (1 - 1e-9) / amax
            ref_info = {"reason": f"prescribed rotation angle >= {theta_limit:.6g} beyond this load "
                                  "factor", "load_factor": lam1}
    if load_factors is None:
        n = int(steps if steps is not None else case.steps)
        base = list(np.linspace(lam0, case.lam_range[1], n + 1)[1:])
        lams = [l for l in base if l <= lam1 * (1 + 1e-12)]
        if include_reference_loads:
            lams = sorted(set(np.round(lams + ref_lams, 14)))
        else:
            lams = sorted(lams)
    else:
        lams = sorted(float(l) for l in load_factors)
    lams = [float(l) for l in lams if l > lam0]

    # ----- model ---------------------------------------------------------------------------------
    t0 = time.perf_counter()
    model = ShellModel(case.geometry, length, width, nx, ny, cell=cell,
                       integration=integration, box=box)
    model.set_params(params["E"], params["nu"], params["h"], shear_factor,
                     R=params.get("R") if case.geometry != "strip" else None)
    for ld in loads:
        mag = ld["magnitude"]
        if ld["kind"] == "edge_force":
            model.add_edge_force(ld["edge"], ld["direction"], mag, ld["follower"])
        elif ld["kind"] == "edge_moment":
            model.add_edge_moment(ld["edge"], ld["direction"], mag, ld["follower"])
        elif ld["kind"] == "pressure":
            model.add_pressure(ld["direction"], mag, ld["follower"])
        elif ld["kind"] == "point_force":  # at ld['point'], else at the midpoint of ld['edge']
            pt = ld.get("point") or model.edge_midpoint[ld["edge"]]
            model.add_point_force(pt, np.asarray(ld["direction"], float) * mag)
        elif ld["kind"] == "edge_rotation":
            pass  # prescribed Dirichlet values, below
        else:
            raise NotImplementedError(f"fenicsx_ref: load kind {ld['kind']!r} is not implemented")
    for point, vec in point_loads:  # extra dead point forces (lab vector at lam = 1)
        model.add_point_force(point, vec)
    bcs = []
    for sup in case.supports:
        kind, edge = sup[0], sup[1]
        if kind == "clamp":
            bcs += model.clamp_bcs(edge)
        elif kind == "fix":  # ("fix", edge, (component names)): homogeneous, e.g. ("uz", "rot_y")
            bcs += [model.component_bc(edge, comp)[0] for comp in sup[2]]
        else:
            raise NotImplementedError(f"support {kind!r}")
    rotations = [_PrescribedRotation(model, ld) for ld in rot_loads]
    bcs += [bc for pr in rotations for bc in pr.bcs]
    Fres, Jform = model.residual_and_jacobian()
    timer.t["setup"] += time.perf_counter() - t0

    from .model import jit_params
    t0 = time.perf_counter()
    L = dolfinx.fem.form(Fres, jit_params=jit_params())
    a = dolfinx.fem.form(Jform, jit_params=jit_params())
    timer.t["jit"] += time.perf_counter() - t0

    t0 = time.perf_counter()
    problem = _Problem(L, a, bcs, model, timer)
    if atol is None:
        atol = 1e-14 * max(length, width)  # Newton-increment norm (displacements and rotations)
    solver = _newton(model, problem, timer, rtol=rtol, atol=atol, criterion=criterion)
    probe = case.probe
    if probe == "tip":
        probe_point = model.edge_midpoint["x1"]
    elif case.extra.get("probe_edge"):
        probe_point = model.edge_midpoint[case.extra["probe_edge"]]
    else:
        raise NotImplementedError(f"probe {probe!r}")
    tip = _tip_evaluator(model, probe_point)
    timer.t["setup"] += time.perf_counter() - t0

    # ----- load stepping with cut-back --------------------------------------------------------------
    w = model.w
    steps_out, prev_angle, lam_done, status = [], 0.0, lam0, "ok"
    dlam = None
    failed = []
    for lam_target in lams:
        iters, cuts, res_hist = 0, 0, []
        while lam_done < lam_target - 1e-14:
            step = lam_target - lam_done if dlam is None else min(dlam, lam_target - lam_done)
            backup = w.x.array.copy()
            model.lam.value = lam_done + step
            for pr in rotations:
                pr.set(lam_done + step)
            problem.residuals = []
            if criterion == "incremental":
                # DOLFINx stops at |dx_k| < rtol |dx_1|, but |dx_1| scales with the step, so each
                # cut-back tightens that bar, and near |theta| = pi it falls below the round-off
                # floor of the increments (README, Solver).  Stop also at |dx_k| < rtol |w|, the
                # solution at the start of the step: a bar independent of the step size.
                solver.atol = max(atol, rtol * w.vector.norm())
            t0 = time.perf_counter()
            a0 = timer.t["assembly"]
            try:
                n_it, conv = solver.solve(w)
            except RuntimeError:
                n_it, conv = solver.max_it, False
            timer.t["solve"] += (time.perf_counter() - t0) - (timer.t["assembly"] - a0)
            ok = conv and np.all(np.isfinite(w.x.array))
            if ok:
                _, th = tip(w)
                ok = np.linalg.norm(th) < theta_limit
            if ok:
                lam_done += step
                iters += n_it
                res_hist.append(list(problem.residuals))
                dlam = None if dlam is None else min(2 * dlam, 1.0)
            else:
                failed.append((lam_done + step, list(problem.residuals)))
                w.x.array[:] = backup
                w.x.scatter_forward()
                cuts += 1
                if cuts > max_cuts:
                    status = f"failed at load factor {lam_done + step:.6g} after {max_cuts} cut-backs"
                    break
                dlam = step / 2
        if status != "ok":
            break
        u, th = tip(w)
        ang = _signed_angle(th, prev_angle)
        prev_angle = ang
        Rm = _rot(th)
        final_res = res_hist[-1][-1] if res_hist and res_hist[-1] else 0.0
        st = {"load_factor": lam_target,
              "load": {"name": case.load_name, "value": float(case.load_value(params, lam_target)),
                       "unit": case.load_unit},
              "probes": {probe: {"u": [float(c) for c in u], "rotation_angle": float(ang),
                                 "rotation": Rm.tolist()}},
              "iterations": int(iters), "residual": float(final_res), "cutbacks": int(cuts)}
        if rotations:
            t0 = time.perf_counter()
            st["reactions"] = [pr.reaction(L, lam_target) for pr in rotations]
            timer.t["assembly"] += time.perf_counter() - t0
        if keep_residuals:
            st["residual_history"] = res_hist
        steps_out.append(st)
        dlam = None if cuts == 0 else dlam

    t_total = time.perf_counter() - t_start
    tt = timer.t
    tt["other"] = max(0.0, t_total - tt["setup"] - tt["jit"] - tt["assembly"] - tt["solve"])

    reference = skipped or None
    if ref is not None:
        reference = reference_error(case, params, ref, steps_out)
    elif case.extra.get("literature"):
        reference = literature_error(case, params, steps_out, probe)
    if reference is not None and reference.get("error") is not None:
        # a failed path: the error covers only the steps that converged
        reference["path_complete"] = status == "ok"
    n_dofs = model.V.dofmap.index_map.size_global * model.V.dofmap.index_map_bs
    result = {
        "schema": "core-se3-result", "version": 1, "case": name, "model": "fenicsx_ref",
        "variant": integration,
        "params": {k: {"value": v, "unit": case.units.get(k, "")} for k, v in params.items()},
        "mesh": {"nx": int(nx), "ny": int(ny), "n_nodes": int(n_dofs // 5),
                 "n_dofs": int(n_dofs), "cell": cell, "degree": 2},
        "steps": steps_out,
        "timings": {k: float(v) for k, v in tt.items()},
        "reference": reference,
        "status": status,
        "options": {"shear_factor": shear_factor, "theta_limit": theta_limit,
                    "load_range": [lam0, lam1]},
    }
    if keep_residuals:
        result["failed_attempts"] = [{"load_factor": l, "residuals": r} for l, r in failed]
    if ref_info:
        result["options"]["reference_truncated_at"] = ref_info
    if return_state:
        return result, {"model": model, "L": L, "a": a, "bcs": bcs, "problem": problem,
                        "solver": solver}
    return result


class _PrescribedRotation:
    """Rigid rotation of an edge by angle = magnitude * lam about ``axis`` through ``point``
    (None coordinates of the point: taken from the node, i.e. any point on the axis line).

    Dirichlet values on the edge: u = R(angle a)(X - p) - (X - p) for the lab components not in
    ``free``, and the rotation vector angle * a, whose tangent components beta_i = angle a.t_i
    (the axis must be tangent to the reference surface along the edge: this model has no
    drilling rotation).  ``reaction`` returns the moment about the axis that holds the edge,
    dPi/d(angle) along the prescribed motion = sum_i r_i d g_i / d angle."""

    def __init__(self, model, ld):
        from .model import rotation_matrix_np
        self._rot = rotation_matrix_np
        self.model, self.edge = model, ld["edge"]
        self.mag = float(ld["magnitude"])
        a = np.asarray(ld["axis"] if ld.get("axis") is not None else ld["direction"], float)
        self.axis = a / np.linalg.norm(a)
        self.point = ld.get("point") or (None, None, None)
        free = set(ld.get("free") or ())
        self.parts = []  # (bc, g, dofs_V, dofs_c, X, kind, index)
        self.bcs = []
        for j, name in enumerate(("ux", "uy", "uz")):
            if j not in free:
                self._add(name, "u", j)
        for j, name in enumerate(("beta1", "beta2")):
            self._add(name, "beta", j)
        for part in self.parts:
            if part[5] == "beta":
                for s in np.unique(part[4][:, 0]):
                    d0 = model.frame_np(s)[2]
                    if abs(self.axis @ d0) > 1e-12:
                        raise NotImplementedError("edge rotation about an axis not tangent to the "
                                                  "surface (drilling) is not in this model")
                break

    def _add(self, name, kind, j):
        bc, g, dV, dc, X = self.model.component_bc(self.edge, name)
        self.parts.append((bc, g, dV, dc, X, kind, j))
        self.bcs.append(bc)

    def _values(self, angle, X, kind, j):
        """(value, d value / d angle) at the dof points X (n, 2)."""
        a = self.axis
        if kind == "beta":
            t = np.array([self.model.frame_np(s)[j] for s in X[:, 0]])
            c = t @ a
            return angle * c, c
        P0 = self.model.phi0_np(X[:, 0], X[:, 1])
        p = np.array([P0[:, i] if self.point[i] is None else np.full(len(X), float(self.point[i]))
                      for i in range(3)]).T
        r = P0 - p
        Rr = r @ self._rot(angle * a).T
        return (Rr - r)[:, j], np.cross(a, Rr)[:, j]

    def set(self, lam):
        angle = self.mag * lam
        for bc, g, dV, dc, X, kind, j in self.parts:
            g.x.array[dc] = self._values(angle, X, kind, j)[0]

    def reaction(self, L, lam):
        b = dolfinx.fem.petsc.assemble_vector(L)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        r = b.array
        angle = self.mag * lam
        T = 0.0
        for bc, g, dV, dc, X, kind, j in self.parts:
            T += float(r[dV] @ self._values(angle, X, kind, j)[1])
        b.destroy()
        return {"edge": self.edge, "axis": self.axis.tolist(), "angle": float(angle),
                "moment_about_axis": T}


def _rot(theta):
    from .model import rotation_matrix_np
    return rotation_matrix_np(theta)


def torsion_constant(mesh=None, angle=1e-4, shear_factor=1.0, integration="psri",
                     cell="quadrilateral", overrides=None, name="torsion", interior=(0.4, 0.6)):
    """Small-twist torsion constants of the ``torsion`` case's strip.

    One load step to the small end rotation ``angle`` (a linear response: the Wagner stiffening
    is O(angle^2)).  T = the moment about the strip axis that holds the rotated end edge (the
    reaction of the prescribed rotation, dPi/d angle).  Returns a dict:

    * ``J`` = T L / (G angle): the end-to-end value.  It includes the end restraint: the clamp
      and the rigid end edge both hold the rotation about the width axis (beta_2) at zero,
      which the free twist wants to be -tau y, so J exceeds the Saint-Venant value by ~ c/L;
    * ``J_interior`` = T / (G tau): tau = the twist rate d(beta_1)/ds measured between the
      stations s = interior * L on the axis, away from both end layers (the Saint-Venant
      solution has beta_1 = tau s exactly) -- the Reissner-Mindlin plate constant.
    """
    case = get_case(name)
    p = case_params(case, overrides or {})
    r, st = run_case(name, mesh=mesh, overrides=overrides, integration=integration,
                     shear_factor=shear_factor, cell=cell, load_factors=[angle / p["angle"]],
                     include_reference_loads=False, rtol=1e-12, return_state=True)
    if r["status"] != "ok":
        raise RuntimeError(f"torsion small-twist solve failed: {r['status']}")
    T = r["steps"][-1]["reactions"][0]["moment_about_axis"]
    G = p["E"] / (2 * (1 + p["nu"]))
    model = st["model"]
    s0, s1 = (f * p["L"] for f in interior)
    b0 = _tip_evaluator(model, (s0, 0.0))(model.w)[1][0]
    b1 = _tip_evaluator(model, (s1, 0.0))(model.w)[1][0]
    tau = (b1 - b0) / (s1 - s0)
    return {"J": T * p["L"] / (G * angle), "J_interior": T / (G * tau), "T": T, "angle": angle,
            "twist_rate_interior": tau, "mean_twist_rate": angle / p["L"], "G": G,
            "mesh": list(r["mesh"].values())[:2], "result": r}

"""One call per model run, returning a plain record (dict) that the studies compare.

Record: model, variant, case, mesh (nx, ny), n_dofs, overrides, lams (load factors of the
converged steps, lam = 0 excluded), u (probe displacement per step, lab components), angle
(probe rotation angle per step), attempts (Newton solves including the failed ones that were
cut back; core_se3 also iterations_all, their iterations), torque (moment about the axis of a prescribed edge rotation, per
step, or None), status ('ok' or 'failed: ...'), timings {setup, jit, assembly, solve, other},
wall (s, around the whole call), iterations (total Newton iterations).

Both models run at the same uniform load factors k/steps, k = 1..steps: fenicsx_ref is given
them explicitly (no extra reference loads), core_se3 steps uniformly by construction.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

__all__ = ["fenicsx_available", "run_core", "run_fenicsx", "run", "SEED_CAP"]

#: Newton caps for the seed element (its tangent is inconsistent: ~235 iterations per step at
#: small loads, docs/ELEMENTS.md); runs that exceed them are reported as failures.
SEED_CAP = dict(max_iter=40, max_cutbacks=0)

_FX = None


def fenicsx_available():
    """(True, version) when DOLFINx imports, else (False, reason)."""
    global _FX
    if _FX is None:
        try:
            import dolfinx  # noqa: F401
            _FX = (True, dolfinx.__version__)
        except Exception as exc:  # ImportError, or a broken binary stack
            _FX = (False, f"{type(exc).__name__}: {exc}")
    return _FX


def _empty(model, variant, name, mesh, overrides):
    return dict(model=model, variant=variant, case=name, mesh=list(mesh), n_dofs=None,
                overrides=dict(overrides or {}), lams=[], u=[], angle=[], torque=None,
                status="ok", timings=dict(setup=0.0, jit=0.0, assembly=0.0, solve=0.0, other=0.0),
                wall=0.0, iterations=0)


def run_core(name, mesh, overrides=None, steps=10, element="default", cap=None, tangent_check=False):
    """core_se3 run of a catalogue case; ConvergenceError -> status 'failed: ...' with the
    steps that converged kept."""
    from core_se3 import catalogue
    from core_se3.errors import CoreSE3Error, ConvergenceError, ElementWarning
    rec = _empty("core_se3", element, name, mesh, overrides)
    case = catalogue.get_case(name)
    p = catalogue.case_params(case, overrides)
    kw = dict(cap if cap is not None else (SEED_CAP if element == "seed" else {}))
    t0 = time.perf_counter()
    res = None
    try:
        prob = catalogue.build_problem(case, p, tuple(mesh), element)
        t_setup = time.perf_counter() - t0
        rec["n_dofs"] = 6 * prob.mesh.n_nodes
        try:
            with warnings.catch_warnings(record=True) as said:
                warnings.simplefilter("always", ElementWarning)
                res = prob.solve(steps=steps, **kw)
            # what the run said about its own answer (the element's known limits): reported
            rec["warning"] = next((str(w.message) for w in said if issubclass(w.category, ElementWarning)), None)
        except ConvergenceError as exc:
            res = exc.result
            rec["status"] = f"failed: {exc}".split(";")[0]
    except CoreSE3Error as exc:
        rec["status"] = f"failed: {type(exc).__name__}: {exc}"
        rec["wall"] = time.perf_counter() - t0
        return rec
    rec["wall"] = time.perf_counter() - t0
    if res is None:
        return rec
    t = dict(res.timings)
    t["setup"] = t.get("setup", 0.0) + t_setup
    rec["timings"] = dict(setup=t["setup"], jit=0.0, assembly=t.get("assembly", 0.0),
                          solve=t.get("solve", 0.0), other=t.get("other", 0.0))
    rot = [ld for ld in case.loads if ld.kind == "edge_rotation"]
    torque = [] if rot else None
    for st in res.steps:
        if st.load_factor <= 0.0:
            continue
        pr = st.probes["tip"]
        rec["lams"].append(float(st.load_factor))
        rec["u"].append([float(c) for c in pr["u"]])
        rec["angle"].append(float(np.linalg.norm(pr["rotation_vector"])))
        rec["iterations"] += int(st.iterations)
        if rot:
            ax = np.asarray(rot[0].axis, float)
            nodes = prob.mesh.node_set(rot[0].edge)
            point = np.array([prob.mesh.X[nodes, i].mean() if c is None else c
                              for i, c in enumerate(rot[0].point)])
            _, M = catalogue.edge_wrench(prob, st.g, rot[0].edge, point)
            torque.append(float(M @ ax))
    rec["torque"] = torque
    rec["attempts"] = len(res.log)                      # Newton solves incl. failed (cut back) ones
    rec["iterations_all"] = int(sum(l["iterations"] for l in res.log))
    if tangent_check and len(res.steps) > 1:
        from core_se3.model.verify import tangent_fd_check
        rec["tangent_check"] = float(tangent_fd_check(prob, res.final.g, res.final.load_factor)[0])
    return rec


def run_fenicsx(name, mesh, overrides=None, steps=10, integration="psri", shear_factor=1.0,
                tangent_check=False, **kw):
    """fenicsx_ref run at the load factors k/steps (see the module docstring); kw go to
    ``fenicsx_ref.run_case`` (e.g. max_cuts)."""
    rec = _empty("fenicsx_ref", integration, name, mesh, overrides)
    ok, why = fenicsx_available()
    if not ok:
        rec["status"] = f"not available ({why})"
        return rec
    from fenicsx_ref import run_case
    lams = [k / steps for k in range(1, steps + 1)]
    t0 = time.perf_counter()
    try:
        r = run_case(name, mesh=tuple(mesh), overrides=overrides or {}, integration=integration,
                     shear_factor=shear_factor, load_factors=lams, include_reference_loads=False,
                     return_state=tangent_check, **kw)
        if tangent_check:
            r, state = r
    except (RuntimeError, ValueError, NotImplementedError) as exc:
        rec["status"] = f"failed: {type(exc).__name__}: {exc}"
        rec["wall"] = time.perf_counter() - t0
        return rec
    rec["wall"] = time.perf_counter() - t0
    rec["n_dofs"] = r["mesh"]["n_dofs"]
    rec["status"] = "ok" if r["status"] == "ok" else f"failed: {r['status']}"
    t = r["timings"]
    rec["timings"] = {k: float(t.get(k, 0.0)) for k in ("setup", "jit", "assembly", "solve", "other")}
    probe = next(iter(r["steps"][0]["probes"])) if r["steps"] else "tip"
    torque = [] if r["steps"] and "reactions" in r["steps"][0] else None
    for st in r["steps"]:
        rec["lams"].append(float(st["load_factor"]))
        rec["u"].append([float(c) for c in st["probes"][probe]["u"]])
        rec["angle"].append(abs(float(st["probes"][probe]["rotation_angle"])))
        rec["iterations"] += int(st["iterations"])
        rec["attempts"] = rec.get("attempts", 0) + 1 + int(st.get("cutbacks", 0))
        if torque is not None:
            torque.append(float(st["reactions"][0]["moment_about_axis"]))
    rec["torque"] = torque
    if tangent_check and r["steps"]:
        rec["tangent_check"] = fenicsx_tangent_check(state)
    return rec


def fenicsx_tangent_check(state, n_dirs=3, eps=1e-6, seed=0):
    """max over random directions v (zero on Dirichlet dofs) of |J v - (F(w + e v) - F(w - e v))/(2e)|
    / |J v| on the free dofs, at the state left by the run (J: the assembled UFL Jacobian)."""
    import dolfinx.fem.petsc
    model, prob, L, a, bcs = (state[k] for k in ("model", "problem", "L", "a", "bcs"))
    w = model.w
    base = w.x.array.copy()
    fixed = np.unique(np.concatenate([bc.dof_indices()[0] for bc in bcs])) if bcs else np.array([], int)
    free = np.setdiff1d(np.arange(len(base)), fixed)
    A = dolfinx.fem.petsc.create_matrix(a)
    prob.J(w.vector, A)
    b = dolfinx.fem.petsc.create_vector(L)
    Jv = A.createVecLeft()
    v = A.createVecRight()
    rng = np.random.default_rng(seed)
    scale = max(np.abs(base).max(), 1e-3)
    worst = 0.0
    for _ in range(n_dirs):
        d = rng.standard_normal(len(base))
        d[fixed] = 0.0
        v.array[:] = d
        A.mult(v, Jv)
        fd = []
        for sgn in (1.0, -1.0):
            w.x.array[:] = base + sgn * eps * scale * d
            w.x.scatter_forward()
            prob.F(w.vector, b)
            fd.append(b.array.copy())
        w.x.array[:] = base
        w.x.scatter_forward()
        g = (fd[0] - fd[1]) / (2 * eps * scale)
        jv = Jv.array
        worst = max(worst, float(np.linalg.norm(jv[free] - g[free]) / max(np.linalg.norm(jv[free]), 1e-300)))
    A.destroy()
    b.destroy()
    return worst


def run(model, variant, name, mesh, overrides=None, steps=10):
    if model == "core_se3":
        return run_core(name, mesh, overrides, steps, element=variant)
    return run_fenicsx(name, mesh, overrides, steps, integration=variant)

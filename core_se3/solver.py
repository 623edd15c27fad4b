"""Load-stepped Newton with exponential updates, cut-back and regrowth.

At load factor lam the residual is r = r_int(g) - f_ext(g, lam) (left-trivialised, one 6-vector
per node in its body frame) and the update is g_i <- g_i exp(eta_i) with K eta = -r.

Convergence is judged on unit-scaled norms so that N-mm and SI problems and L/h = 1e4 behave
alike: moments are divided by a characteristic length ``ell`` (the bounding-box diagonal),
rotations of the increment are multiplied by it, and both norms are relative:

    |r_free|_s <= rtol * max(|f_ext|_s, |r_int|_s)       and   |eta|_s <= dtol * ell.

A failed step (no convergence in ``max_iter``, an edge turning by ~pi, a prescribed motion
turning nodes by more than 0.9 pi within the step, a singular tangent after the first step, a
non-finite residual) is cut back by half; after easy steps the
step grows again.  Only the requested load factors are stored; sub-steps are logged.
"""
from __future__ import annotations

import time

import numpy as np

from . import se3
from .errors import ConvergenceError, ElementTooDistortedError, SingularSystemError
from .linalg import checked_solve, make_solver
from .results import Result, StepResult, unwrap_rotation

__all__ = ["newton_solve", "MAX_PRESCRIBED_TURN"]

MAX_PRESCRIBED_TURN = 0.9 * np.pi   # largest rotation a prescribed motion may make in one step


def _scaled_norm(r, ell, moment=True):
    r = np.asarray(r).reshape(-1, 6)
    if moment:
        return np.sqrt(np.sum(r[:, :3] ** 2) + np.sum((r[:, 3:] / ell) ** 2))
    return np.sqrt(np.sum(r[:, :3] ** 2) + np.sum((r[:, 3:] * ell) ** 2))


def _lab_totals(g, f, magnitudes=False):
    """Total lab force and moment about the origin of generalised nodal forces f (n,6)
    (and, if asked, the sums of their nodal magnitudes, the scale of the balance check)."""
    R = g[:, :3, :3]
    F = np.einsum("nij,nj->ni", R, f[:, :3])
    M = np.einsum("nij,nj->ni", R, f[:, 3:]) + np.cross(g[:, :3, 3], F)
    if magnitudes:
        return F.sum(0), M.sum(0), np.linalg.norm(F, axis=1).sum(), np.linalg.norm(M, axis=1).sum()
    return F.sum(0), M.sum(0)


def check_supports(problem, g):
    """Raise SingularSystemError if the supports leave a rigid-body motion free.

    A superposed rigid motion h = exp(xi) moves every node by the body-frame increment
    eta_i = Ad_{g_i^-1} xi; the supports restrain all six rigid motions iff the fixed
    components of these increments have rank 6 (checked by SVD, unit-scaled).
    """
    fixed = problem.constraint_mask()
    ell = problem.length_scale
    c = g[:, :3, 3].mean(0)
    h = np.eye(4)
    h[:3, 3] = -c                                   # rigid motions about the centroid
    modes = se3.Ad(se3.inv(g) @ np.linalg.inv(h))   # (n, 6, 6): column k = mode k at node i
    scale = np.r_[np.ones(3), np.full(3, ell)]      # rotations * ell, comparable to translations
    B = (modes * scale[None, None, :])[fixed]        # (n_fixed, 6)
    # supports carried by loads (lab-direction springs): rows d^T R_i [I 0] Ad_{g_i^-1} xi
    rows = [B]
    for load in problem.loads:
        restraint = getattr(load, "lab_restraint", None)
        if restraint is not None:
            nodes, D = restraint()                       # (k,), (k, q, 3) lab unit directions
            lab = np.einsum("kij,kjl->kil", g[nodes, :3, :3], modes[nodes][:, :3, :] * scale)
            rows.append(np.einsum("kqi,kil->kql", D, lab).reshape(-1, 6))
    B = np.concatenate(rows)
    if B.shape[0] == 0:
        raise SingularSystemError("no supports: the shell can move as a rigid body; clamp or fix some nodes")
    U, S, Vt = np.linalg.svd(B, full_matrices=True)
    S = np.r_[S, np.zeros(6 - len(S))]
    if S[-1] < 1e-10 * S[0]:
        v = Vt[-1] * scale
        tr, rot = v[:3], v[3:]
        if np.linalg.norm(rot) * ell > 1e-8 * np.linalg.norm(tr):
            # twist (tr, rot) about the centroid c: screw axis through c + rot x tr / |rot|^2
            pt = c + np.cross(rot, tr) / (rot @ rot)
            what = (f"rotation about {np.round(rot / np.linalg.norm(rot), 3).tolist()} "
                    f"through {np.round(pt, 4).tolist()}")
        else:
            what = f"translation along {np.round(tr / np.linalg.norm(tr), 3).tolist()}"
        raise SingularSystemError("the supports leave a rigid-body motion free (" + what
                                  + "): the tangent is singular; add supports")


def _limit_point_hint(problem, g, lam, linear_solver):
    """Message suggesting arc length if the failure is a limit point (see continuation)."""
    if lam == 0.0:
        return None
    from .continuation import limit_point_hint
    return limit_point_hint(problem, g, lam, linear_solver or problem.linear_solver)


def newton_solve(problem, steps=10, lam_end=1.0, lam_start=0.0, rtol=1e-10, dtol=1e-10,
                 max_iter=30, max_cutbacks=12, g_init=None, verbose=False, linear_solver=None,
                 record_substeps=False, limit_check=True, load_factors=None):
    """Solve the problem from lam_start to lam_end in ``steps`` equal load increments, or
    through the explicit ``load_factors`` (a sequence moving strictly one way from lam_start;
    it replaces steps and lam_end).  Each requested load factor is a stored step; a failed
    increment is halved (at most max_cutbacks times per requested step) and grows back.

    limit_check: stop with a ConvergenceError that suggests arc length when a converged step
    has jumped past a limit point (snap-through): the step started where the current stiffness
    parameter S_p = k / k_0 (k = |r_0|_s^2 / (-r_0 . eta_0), the stiffness seen by the first
    Newton iterate, k_0 its value in the first step) was below 0.3, and the converged increment
    is more than 3x that first (tangent) iterate.  Not applied to displacement-driven problems.
    """
    t0 = time.perf_counter()
    if load_factors is not None:
        targets = np.asarray(load_factors, float).ravel()
        incr = np.diff(np.r_[lam_start, targets])
        if (len(targets) == 0 or not np.all(np.isfinite(targets)) or np.any(incr == 0)
                or np.any(np.sign(incr) != np.sign(incr[0]))):
            raise ValueError("load_factors must be finite and move strictly one way from lam_start "
                             f"(no repeats, no reversals), got {list(targets)}")
    elif not np.isfinite(lam_end) or steps < 1:
        raise ValueError("need a finite lam_end and steps >= 1")
    else:
        targets = lam_start + (lam_end - lam_start) * np.arange(1, steps + 1) / steps
    mesh = problem.mesh
    fixedmask = problem.constraint_mask()
    asm = problem.assembler()
    solver = make_solver(linear_solver or problem.linear_solver)
    ell = problem.length_scale
    g = mesh.g0.copy() if g_init is None else np.array(g_init, float)
    check_supports(problem, g)
    stateful = getattr(problem.element, "stateful", False)
    has_targets = any(sup.target is not None for sup in problem.supports)
    driven = stateful or has_targets
    k_ref = None
    result = Result(mesh=mesh, element=problem.element_name)
    unwrapped = {name: np.zeros(3) for name in problem.probes}
    result.timings["setup"] = time.perf_counter() - t0
    t_asm = t_sol = 0.0
    t_start = time.perf_counter()

    def record(lam, g, its, hist, rint, fext, store):
        states = {}
        for name, pr in problem.probes.items():
            x, R = pr.state(g)
            x0, Rref = pr.state(mesh.g0)
            unwrapped[name] = unwrap_rotation(R @ Rref.T, unwrapped[name])
            states[name] = dict(u=x - x0, R=R @ Rref.T, w=unwrapped[name].copy())
        if not store:
            return
        reac = (rint - fext) * fixedmask
        RF, RM, sF, sM = _lab_totals(g, reac, magnitudes=True)
        AF, AM, aF, aM = _lab_totals(g, fext, magnitudes=True)
        probes = states
        result.steps.append(StepResult(lam, g.copy(), its, list(hist), RF, RM, AF, AM, probes,
                                       scale=(max(sF, aF, max(sM, aM) / ell),
                                              max(sM, aM, max(sF, aF) * ell))))

    # initial state
    ev = problem.element.evaluate(g, tangent=False)
    f0, _, _ = problem.external(g, lam_start, tangent=False)
    record(lam_start, g, 0, [], ev["r"], f0, True)

    lam = lam_start
    dlam = None
    first_solve = True
    for target in targets:
        # the requested increment; a cut-back increment carries over, capped by it
        dlam_nominal = target - lam
        dlam = dlam_nominal if dlam is None else np.sign(dlam_nominal) * min(abs(dlam), abs(dlam_nominal))
        while abs(target - lam) > 1e-14 * max(1.0, abs(target)):
            lam_try = lam + dlam if abs(dlam) < abs(target - lam) else target
            g_try = problem.apply_prescribed(g.copy(), lam_try)
            if stateful:
                # the seed element's strain is a state: save it, and feed it the prescribed motion
                problem.element.save()
                problem.element.update(se3.log(se3.inv(g) @ g_try))
            hist = []
            eta_sum = 0.0
            k_step = pred = None
            ok = False
            reason = ""
            turn = problem.prescribed_rotation(lam, lam_try) if has_targets else 0.0
            try:
                if turn > MAX_PRESCRIBED_TURN:
                    # never a silent answer: a turn of 2 pi in one step lands on the same frame
                    raise ElementTooDistortedError(
                        f"the prescribed motion turns nodes by {turn:.3f} rad in one step "
                        f"(> {MAX_PRESCRIBED_TURN:.3f}): the step is too large for the exponential update")
                for it in range(max_iter + 1):
                    ta = time.perf_counter()
                    ev = problem.element.evaluate(g_try, tangent=True)
                    fext, Kn_ext, Ke_ext = problem.external(g_try, lam_try, tangent=True)
                    r = ev["r"] - fext
                    rf = asm.vector(r)
                    if not np.all(np.isfinite(rf)):
                        raise FloatingPointError("non-finite residual")
                    scale = max(_scaled_norm(fext, ell), _scaled_norm(ev["r"], ell), 1e-300)
                    rn = _scaled_norm(asm.scatter(rf), ell) / scale
                    # round-off floor of r = Dbar (z - z0): the cancelling terms are ~ Dbar z
                    floor = 1e3 * np.finfo(float).eps * ev["force_scale"] / scale
                    hist.append(rn)
                    if it > 0 and rn <= max(rtol, floor) and dn <= dtol:
                        ok = True
                        t_asm += time.perf_counter() - ta
                        break
                    if it == max_iter:
                        reason = f"no convergence in {max_iter} iterations (residual {rn:.2e})"
                        t_asm += time.perf_counter() - ta
                        break
                    if it > 3 and rn > 1e8 * max(hist[0], 1e-300):
                        reason = f"diverging (residual {rn:.2e})"
                        t_asm += time.perf_counter() - ta
                        break
                    # load blocks are already -d f_ext / d eta
                    Ke = ev["Ke"] if Ke_ext is None else ev["Ke"] + Ke_ext
                    Kn = ev["Kn"] + Kn_ext
                    K = asm.matrix(Ke, ev["KE"], Kn)
                    t_asm += time.perf_counter() - ta
                    ts = time.perf_counter()
                    try:
                        x = checked_solve(solver, K, -rf, probe=first_solve)
                    except SingularSystemError as exc:
                        if first_solve:
                            raise SingularSystemError(
                                f"{exc}: the tangent of the unloaded shell is singular -- a rigid-body "
                                "motion is not restrained (missing or insufficient supports)") from None
                        raise
                    t_sol += time.perf_counter() - ts
                    first_solve = False
                    eta = asm.scatter(x)
                    eta_sum = eta_sum + eta
                    if it == 0:
                        work = -float(rf @ x)
                        k_step = _scaled_norm(asm.scatter(rf), ell) ** 2 / work if work > 0 else -np.inf
                        pred = _scaled_norm(eta, ell, moment=False)
                    dn = _scaled_norm(eta, ell, moment=False) / ell
                    g_try = g_try @ se3.exp(eta)
                    if stateful:
                        problem.element.update(eta)
            except SingularSystemError as exc:
                if first_solve:
                    raise
                reason = str(exc)
            except (ElementTooDistortedError, FloatingPointError) as exc:
                reason = str(exc)
            result.log.append(dict(lam=lam_try, converged=ok, iterations=len(hist) - 1,
                                   residual_history=hist, reason=reason))
            if verbose:
                print(f"  lam {lam_try:.6g}: {'ok' if ok else 'FAIL'} in {len(hist) - 1} it, "
                      f"residual {hist[-1] if hist else float('nan'):.2e} {reason}")
            if ok and limit_check and not driven and k_step is not None:
                if k_ref is None:
                    k_ref = k_step
                jump = _scaled_norm(eta_sum, ell, moment=False)
                if k_ref > 0 and k_step / k_ref < 0.3 and jump > 3 * pred:
                    result.timings.update(assembly=t_asm, solve=t_sol,
                                          other=time.perf_counter() - t_start - t_asm - t_sol)
                    raise ConvergenceError(
                        f"load control met a limit point: the step from load factor {lam:.6g} to "
                        f"{lam_try:.6g} started at a current stiffness S_p = {k_step / k_ref:.3g} of "
                        f"the initial one and converged {jump / pred:.1f}x farther than its tangent "
                        "predicted, i.e. it snapped onto another branch of the equilibrium path. "
                        "Trace the path with arc length (core_se3.continuation.arc_length) or "
                        "displacement control (core_se3.continuation.displacement_control); the "
                        "steps before the limit point are kept in .result", result)
            if ok:
                lam = lam_try
                g = g_try
                store = abs(lam - target) <= 1e-14 * max(1.0, abs(target)) or record_substeps
                record(lam, g, len(hist) - 1, hist, ev["r"], fext, store)
                if len(hist) - 1 <= 6 and abs(dlam) < abs(dlam_nominal):
                    dlam = min(abs(dlam) * 2, abs(dlam_nominal)) * np.sign(dlam_nominal)
            else:
                if stateful:
                    problem.element.restore()
                dlam = dlam / 2
                if abs(dlam) < abs(dlam_nominal) / 2 ** max_cutbacks:
                    result.timings.update(assembly=t_asm, solve=t_sol,
                                          other=time.perf_counter() - t_start - t_asm - t_sol)
                    hint = _limit_point_hint(problem, g, lam, linear_solver)
                    raise ConvergenceError(
                        f"Newton failed at load factor {lam_try:.6g} after {max_cutbacks} cut-backs "
                        f"({reason}); the last converged load factor is {lam:.6g} and its state is "
                        "kept in .result" + (f". Probable cause: {hint}" if hint else ""), result)
    result.timings.update(assembly=t_asm, solve=t_sol,
                          other=time.perf_counter() - t_start - t_asm - t_sol)
    return result


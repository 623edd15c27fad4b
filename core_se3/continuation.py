"""Path following past limit points: arc length, displacement control, stability detection.

Equilibrium path of r(g, lam) = r_int(g) - f_ext(g, lam) = 0 on the free dofs, g <- g exp(eta)
(body-frame increments, docs/CONVENTIONS.md).  With q = d f_ext / d lam (central difference
in lam at the current g, exact for linearly scaled loads, dead or follower) and K = dr/deta,
one Newton correction of the bordered system

    K du - q dlam = -r,        c_u . du + c_lam dlam = -c

is du = a + dlam b with K a = -r, K b = q (one factorisation, two solves), and dlam from the
constraint c:

* ``crisfield`` (cylindrical arc length): |Du + du|_W^2 + psi^2 u_ref^2 (Dlam + dlam)^2 = ds^2,
  Du, Dlam the increments accumulated in the step (sum of the etas); the root that keeps the
  increment closest to its previous direction is taken; for complex roots the minimum of the
  quadratic (the closest point to the constraint) is used, and more than 3 such iterations in
  a step reject it;
* ``riks`` (normal plane, Ramm's update): (Du)_W . du + psi^2 u_ref^2 Dlam dlam = 0;
* displacement control: d . (phi_k - X_k) = u* at node k (lab direction d), linearised
  c_u . du = d . R_k du_v; load control: dlam = lam* - lam.

|x|_W weights translations by 1 and rotations by ell^2 (ell = the problem's length scale, as
in solver._scaled_norm), so ds is a length.  The predictor is the tangent t = K^-1 q at the last
converged state, Dlam = +-ds / sqrt(|t|_W^2 + psi^2 u_ref^2), signed so that the new increment
continues the previous one (positive projection).  ds adapts: ds *= clip(sqrt(n_target / n),
1/2, 2) after a converged step of n iterations; a failed step (no convergence, complex root,
an edge turning by pi, a singular tangent, a converged increment pointing against its
predictor) is rejected and retried with ds / 2.

Restart: after every converged point the follower can hand an ``ArcState`` to ``on_step``
(the point, the next ds, the previous increment that signs the next predictor, the pending
branch switch, the critical points so far); ``arc_length(..., start=state)`` continues from it
and repeats the same computations from the same bits, so an interrupted and resumed path ends
in the state of an uninterrupted one.

Stability: at each converged state the symmetric part of K is factorised (SuperLU, symmetric
ordering, diagonal pivots); the number of negative pivots is the number of negative
eigenvalues (Sylvester) and its change between two steps brackets a critical point. It is a
*limit point* when dlam/ds passes through zero with it (arc length: the sign of the predicted
load increment at the two states; displacement control: the sign of q . t), otherwise a
*bifurcation*; the critical load factor of a limit point is
interpolated where the current stiffness parameter S_p = (q . t_0)/(q . t) vanishes.
``branch_switch=True`` leaves a bifurcation along the buckling mode (the eigenvector of the
smallest eigenvalue, orthogonalised to t) instead of continuing on the primary path.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from . import se3
from .errors import ConvergenceError, CoreSE3Error, ElementTooDistortedError, SingularSystemError
from .linalg import make_solver
from .results import Result, StepResult, unwrap_rotation

__all__ = ["ShellSystem", "arc_length", "displacement_control", "path_follow", "inertia",
           "CriticalPoint", "limit_point_hint", "AlgebraicSystem", "ArcState"]


# ============================================================== linear algebra ===========

class _Factored:
    """Equilibrated factorisation of K (sparse: the project's solver; dense: LAPACK LU)."""

    def __init__(self, K, solver):
        self.dense = not sp.issparse(K)
        if self.dense:
            K = np.asarray(K, float)
            try:
                with np.errstate(all="raise"):
                    self.lu = sla.lu_factor(K, check_finite=True)
            except (FloatingPointError, ValueError, sla.LinAlgError) as exc:
                raise SingularSystemError(f"tangent is singular ({exc})") from None
            if np.any(np.abs(np.diag(self.lu[0])) < 1e-14 * np.abs(K).max()):
                raise SingularSystemError("tangent is singular (zero pivot)")
            self.K = K
            return
        d = np.abs(K.diagonal())
        d[d == 0] = 1.0
        self.s = 1.0 / np.sqrt(d)
        S = sp.diags(self.s)
        self.Ks = (S @ K @ S).tocsr()
        self._ctx = solver.factor(self.Ks)
        self._solve = self._ctx.__enter__()

    def solve(self, b):
        if self.dense:
            return sla.lu_solve(self.lu, b)
        bs = self.s * b
        y = self._solve(bs)
        for _ in range(2):                                   # iterative refinement
            rs = bs - self.Ks @ y
            if np.linalg.norm(rs) <= 1e-14 * np.linalg.norm(bs):
                break
            y = y + self._solve(rs)
        res = np.linalg.norm(self.Ks @ y - bs)
        kn = abs(self.Ks).sum(axis=1).max()
        if not np.isfinite(res) or res > 1e-8 * (kn * np.linalg.norm(y) + np.linalg.norm(bs)):
            raise SingularSystemError("tangent is singular or nearly so (backward error "
                                      f"{res / (kn * np.linalg.norm(y) + np.linalg.norm(bs)):.1e})")
        return self.s * y

    def close(self):
        if not self.dense:
            self._ctx.__exit__(None, None, None)


def _perm_parity(p):
    """+1 for an even permutation, -1 for an odd one (cycle count)."""
    p = np.asarray(p)
    seen = np.zeros(len(p), bool)
    parity = 0
    for i in range(len(p)):
        if not seen[i]:
            j, length = i, 0
            while not seen[j]:
                seen[j] = True
                j = p[j]
                length += 1
            parity += length - 1
    return -1 if parity % 2 else 1


def inertia(K):
    """(sign det, number of negative eigenvalues or None) of the symmetric part of K.

    Sparse: SuperLU of the equilibrated sym(K) with a symmetric ordering and diagonal pivots,
    i.e. an LDL^T-type factorisation whose negative pivots count the negative eigenvalues
    (Sylvester's law of inertia); if SuperLU had to pivot off the diagonal only the sign of the
    determinant is returned.  Dense: the eigenvalues.
    """
    if not sp.issparse(K):
        Ks = 0.5 * (np.asarray(K) + np.asarray(K).T)
        ev = np.linalg.eigvalsh(Ks)
        return (1 if np.sum(ev < 0) % 2 == 0 else -1), int(np.sum(ev < 0))
    Ks = (0.5 * (K + K.T)).tocsc()
    d = np.abs(Ks.diagonal())
    d[d == 0] = 1.0
    S = sp.diags(1.0 / np.sqrt(d))
    Ks = (S @ Ks @ S).tocsc()
    try:
        lu = spla.splu(Ks, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options=dict(SymmetricMode=True))
        u = lu.U.diagonal()
        if not np.all(np.isfinite(u)) or np.any(u == 0):
            raise RuntimeError("zero pivot")
    except RuntimeError:
        lu = spla.splu(Ks, permc_spec="COLAMD")
        u = lu.U.diagonal()
    sign = int(np.prod(np.sign(u))) * _perm_parity(lu.perm_r) * _perm_parity(lu.perm_c)
    if np.array_equal(lu.perm_r, lu.perm_c):
        return sign, int(np.sum(u < 0))
    return sign, None


def _smallest_mode(K, fac, n_iter=30, seed=7):
    """Eigenvector of sym(K) of smallest |eigenvalue| by inverse iteration on the factor of K
    (K is symmetric at equilibrium up to the residual); returns (mu, phi)."""
    n = K.shape[0]
    x = np.random.default_rng(seed).standard_normal(n)
    x /= np.linalg.norm(x)
    mu = 0.0
    for k in range(n_iter):
        y = fac.solve(x)
        y /= np.linalg.norm(y)
        mu_new = float(y @ (K @ y))
        x, done = y, k > 3 and abs(mu_new - mu) <= 1e-10 * max(abs(mu_new), 1e-300)
        mu = mu_new
        if done:
            break
    return mu, x


# ============================================================== systems ===================

class ShellSystem:
    """A Problem seen by the path follower: free-dof residual, tangent, load direction q.

    The state is the array of nodal frames g (n, 4, 4).  Prescribed motions (rotate_edge,
    prescribe with a target) must not depend on lam: arc length scales the loads only.
    """

    def __init__(self, problem, linear_solver=None, difference="central"):
        self.difference = difference
        if getattr(problem.element, "stateful", False):
            raise CoreSE3Error("path following needs a path-independent element (the default one); "
                               "the seed element's incremental strain is not supported")
        for s in problem.supports:
            if s.target is not None:
                g0 = problem.mesh.g0[s.nodes]
                if not (np.allclose(s.target(0.0), g0) and np.allclose(s.target(1.0), g0)):
                    raise CoreSE3Error("path following scales loads only: a prescribed motion that "
                                       "depends on the load factor is not supported; use "
                                       "newton_solve for displacement-driven problems")
        self.problem = problem
        self.asm = problem.assembler()
        self.solver = make_solver(linear_solver or problem.linear_solver)
        self.ell = problem.length_scale
        self.n = self.asm.nfree
        w = np.tile(np.r_[np.ones(3), np.full(3, self.ell ** 2)], problem.mesh.n_nodes)
        self.w = w[self.asm.free]

    def initial(self):
        return self.problem.mesh.g0.copy()

    def update(self, g, x):
        return g @ se3.exp(self.asm.scatter(x))

    def load_direction(self, g, lam):
        d = 1e-4 * max(1.0, abs(lam))
        hi = lam + d if self.difference == "central" else lam
        fp, _, _ = self.problem.external(g, hi, tangent=False)
        fm, _, _ = self.problem.external(g, lam - d, tangent=False)
        return (fp - fm) / (hi - lam + d)

    def evaluate(self, g, lam, tangent=True):
        """dict(r, K, q, rn, floor): free residual, tangent, load direction, relative residual."""
        from .solver import _scaled_norm
        prob = self.problem
        ev = prob.element.evaluate(g, tangent=tangent)
        fext, Kn_ext, Ke_ext = prob.external(g, lam, tangent=tangent)
        r = ev["r"] - fext
        rf = self.asm.vector(r)
        if not np.all(np.isfinite(rf)):
            raise FloatingPointError("non-finite residual")
        q = self.load_direction(g, lam)
        scale = max(_scaled_norm(fext, self.ell), _scaled_norm(ev["r"], self.ell),
                    abs(lam) * _scaled_norm(q, self.ell), 1e-300)
        out = dict(r=rf, q=self.asm.vector(q), rint=ev["r"], fext=fext,
                   rn=_scaled_norm(self.asm.scatter(rf), self.ell) / scale,
                   floor=1e3 * np.finfo(float).eps * ev["force_scale"] / scale)
        if tangent:
            Ke = ev["Ke"] if Ke_ext is None else ev["Ke"] + Ke_ext
            out["K"] = self.asm.matrix(Ke, ev["KE"], ev["Kn"] + Kn_ext)
        return out

    def increment_norm(self, x):
        """|x|_W / ell (relative increment, as the solver's dtol)."""
        return np.sqrt(np.sum(self.w * x * x)) / self.ell

    # ------------------------------------------------------ displacement of one node ------
    def node_displacement(self, node, direction):
        """(value(g), row(g)): u = d . (phi_k - X_k) and its linearisation on the free dofs."""
        d = np.asarray(direction, float)
        d = d / np.linalg.norm(d)
        X0 = self.problem.mesh.X[node].copy()
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
    """

    def __init__(self, f, jac, q, u0=None):
        self.f, self.jac, self.q = f, jac, np.asarray(q, float)
        self.n = len(self.q)
        self.u0 = np.zeros(self.n) if u0 is None else np.asarray(u0, float)
        self.w = np.ones(self.n)
        self.solver = None

    def initial(self):
        return self.u0.copy()

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


# ============================================================== constraints ===============

class _Failed(Exception):
    pass


class _ArcLength:
    def __init__(self, method, ds, psi_u, w):
        self.method, self.ds, self.c2, self.w = method, ds, psi_u ** 2, w

    def start(self, du, dlam):
        self.du, self.dlam = du.copy(), dlam
        self.du0, self.dlam0 = du.copy(), dlam                  # predictor (normal of Riks)

    def dlam_for(self, sysm, state, a, b):
        w = self.w
        if self.method == "riks":
            den = np.sum(w * self.du * b) + self.c2 * self.dlam
            if den == 0:
                raise _Failed("Riks constraint is tangent to the path")
            return -np.sum(w * self.du * a) / den
        ua = self.du + a
        A = np.sum(w * b * b) + self.c2
        B = 2 * (np.sum(w * ua * b) + self.c2 * self.dlam)
        Cc = np.sum(w * ua * ua) + self.c2 * self.dlam ** 2 - self.ds ** 2
        disc = B * B - 4 * A * Cc
        if disc < 0:
            # complex roots: take the point of the correction line closest to the sphere
            # (minimum of the quadratic); the next iterations return to the constraint
            self.complex_roots = getattr(self, "complex_roots", 0) + 1
            if self.complex_roots > 3:
                raise _Failed("arc-length constraint has no real root (complex roots)")
            return -B / (2 * A)
        roots = ((-B + np.sqrt(disc)) / (2 * A), (-B - np.sqrt(disc)) / (2 * A))
        # choose the root whose increment makes the smallest angle with the previous one
        score = [np.sum(w * self.du * (ua + x * b)) + self.c2 * self.dlam * (self.dlam + x)
                 for x in roots]
        return roots[int(np.argmax(score))]

    def accept(self, x, dl):
        self.du += x
        self.dlam += dl


class _Linear:
    """c(state, lam) = value(state) + c_lam lam - target, linearised by row . du + c_lam dlam."""

    def __init__(self, value, row, c_lam, target):
        self.value, self.row, self.c_lam, self.target = value, row, c_lam, target
        self.lam = None

    def dlam_for(self, sysm, state, a, b):
        c = (self.value(state) if self.value else 0.0) + self.c_lam * self.lam - self.target
        ru = self.row(state) if self.row else None
        num = c + (ru @ a if ru is not None else 0.0)
        den = (ru @ b if ru is not None else 0.0) + self.c_lam
        if den == 0 or not np.isfinite(den):
            raise _Failed("the controlled displacement does not respond to the load (c_u . b = 0)")
        return -num / den

    def accept(self, x, dl):
        pass


# ============================================================== path data ================

@dataclass
class CriticalPoint:
    """A critical point bracketed by two converged steps (indices into result.steps)."""
    kind: str                # 'limit' or 'bifurcation'
    step: int                # first step past the critical point
    lam: float               # estimated critical load factor
    lam_bracket: tuple
    negative_eigenvalues: tuple
    mode: np.ndarray | None = field(default=None, repr=False)

    def describe(self):
        a, b = self.lam_bracket
        neg = "" if None in self.negative_eigenvalues else \
            f", negative eigenvalues {self.negative_eigenvalues[0]} -> {self.negative_eigenvalues[1]}"
        return f"{self.kind} point at lam ~ {self.lam:.6g} (between {a:.6g} and {b:.6g}{neg})"


@dataclass
class PathPoint:
    state: object
    lam: float
    t: np.ndarray            # tangent K^-1 q at the state
    qt: float                # q . t
    sign: int
    n_neg: int | None
    its: int = 0
    hist: list = field(default_factory=list)
    ev: dict | None = None


@dataclass
class ArcState:
    """What the arc-length follower carries from one converged point to the next (a restart).

    state: the converged point (ShellSystem: nodal frames g (n, 4, 4)); lam its load factor;
    step: converged points so far (0 = the first point of the path); ds: the arc length of the
    next step (already adapted), ds_max, ds_min its bounds; psi_u = psi |t_0|_W (length units);
    direction: sign of the first predictor's dlam; prev_du (free dofs), prev_dl: the last
    converged increment (the next predictor is signed by its W-projection on the tangent; None
    at the start and after a branch switch); switch_mode: the unit mode of a pending branch
    switch, branch_switch whether a switch is still to come; critical: the CriticalPoints found
    so far (``mode`` not needed to continue); finished: why the path stopped at this point
    ('lam_end', 'control_end', 'lam_min', 'max_steps') or ''; unwrap: the continuously
    unwrapped probe rotation vectors (arc_length's recorder; None for path_follow).
    """
    state: object
    lam: float
    step: int
    ds: float
    ds_max: float
    ds_min: float
    psi_u: float
    direction: float
    prev_du: np.ndarray | None = None
    prev_dl: float | None = None
    switch_mode: np.ndarray | None = None
    branch_switch: bool = False
    critical: list = field(default_factory=list)
    finished: str = ""
    unwrap: dict | None = None

    def pack(self):
        """(scalars, arrays): a JSON-able dict (floats round-trip exactly through repr) and the
        arrays other than ``state``; ``ArcState.unpack(state, scalars, arrays)`` inverts it."""
        sc = dict(lam=float(self.lam), step=int(self.step), ds=float(self.ds), ds_max=float(self.ds_max),
                  ds_min=float(self.ds_min), psi_u=float(self.psi_u), direction=float(self.direction),
                  prev_dl=None if self.prev_dl is None else float(self.prev_dl),
                  branch_switch=bool(self.branch_switch), finished=str(self.finished or ""),
                  critical=[dict(kind=c.kind, step=int(c.step), lam=float(c.lam),
                                 lam_bracket=[float(x) for x in c.lam_bracket],
                                 negative_eigenvalues=[None if x is None else int(x)
                                                       for x in c.negative_eigenvalues])
                            for c in self.critical],
                  unwrap=None if self.unwrap is None else
                  {k: [float(x) for x in np.asarray(v, float)] for k, v in self.unwrap.items()})
        arrays = {}
        if self.prev_du is not None:
            arrays["prev_du"] = np.asarray(self.prev_du, float)
        if self.switch_mode is not None:
            arrays["switch_mode"] = np.asarray(self.switch_mode, float)
        return sc, arrays

    @classmethod
    def unpack(cls, state, scalars, arrays):
        sc = scalars
        crit = [CriticalPoint(c["kind"], c["step"], c["lam"], tuple(c["lam_bracket"]),
                              tuple(c["negative_eigenvalues"])) for c in sc.get("critical", [])]
        unwrap = None if sc.get("unwrap") is None else \
            {k: np.array(v, float) for k, v in sc["unwrap"].items()}
        return cls(state, sc["lam"], sc["step"], sc["ds"], sc["ds_max"], sc["ds_min"], sc["psi_u"],
                   sc["direction"], arrays.get("prev_du"), sc["prev_dl"], arrays.get("switch_mode"),
                   sc["branch_switch"], crit, sc["finished"], unwrap)


class _Recorder:
    """Shell results in the project's Result/StepResult form (probes, reactions, balance)."""

    def __init__(self, problem):
        self.problem = problem
        self.result = Result(mesh=problem.mesh, element=problem.element_name)
        self.unwrapped = {name: np.zeros(3) for name in problem.probes}
        self.fixed = problem.constraint_mask()

    def __call__(self, pt):
        from .solver import _lab_totals
        prob, mesh, g = self.problem, self.problem.mesh, pt.state
        states = {}
        for name, pr in prob.probes.items():
            x, R = pr.state(g)
            x0, Rref = pr.state(mesh.g0)
            self.unwrapped[name] = unwrap_rotation(R @ Rref.T, self.unwrapped[name])
            states[name] = dict(u=x - x0, R=R @ Rref.T, w=self.unwrapped[name].copy())
        ev = pt.ev
        reac = (ev["rint"] - ev["fext"]) * self.fixed
        RF, RM, sF, sM = _lab_totals(g, reac, magnitudes=True)
        AF, AM, aF, aM = _lab_totals(g, ev["fext"], magnitudes=True)
        ell = prob.length_scale
        st = StepResult(pt.lam, g.copy(), pt.its, list(pt.hist), RF, RM, AF, AM, states,
                        scale=(max(sF, aF, max(sM, aM) / ell), max(sM, aM, max(sF, aF) * ell)))
        st.stability = dict(det_sign=pt.sign, negative_eigenvalues=pt.n_neg, q_dot_t=pt.qt)
        self.result.steps.append(st)


# ============================================================== the path follower =========

def _analyse(sysm, state, lam, stability, its=0, hist=(), ev=None):
    """Tangent t = K^-1 q, q . t and the inertia of K at a converged state."""
    ev = sysm.evaluate(state, lam, tangent=True) if ev is None or "K" not in ev else ev
    fac = _Factored(ev["K"], sysm.solver)
    try:
        t = fac.solve(ev["q"])
    finally:
        fac.close()
    sign, nneg = inertia(ev["K"]) if stability else (0, None)
    return PathPoint(state, lam, t, float(ev["q"] @ t), sign, nneg, its, list(hist), ev)


def _correct(sysm, state, lam, con, rtol, dtol, max_iter, timers):
    """Newton on the bordered system from the predicted (state, lam); returns the converged
    (state, lam, iterations, residual history, evaluation at the solution)."""
    hist = []
    dn = np.inf
    for it in range(max_iter + 1):
        ta = time.perf_counter()
        ev = sysm.evaluate(state, lam, tangent=True)
        timers[0] += time.perf_counter() - ta
        rn = ev["rn"]
        hist.append(rn)
        if it > 0 and rn <= max(rtol, ev["floor"]) and dn <= dtol:
            return state, lam, it, hist, ev
        if it == max_iter:
            raise _Failed(f"no convergence in {max_iter} iterations (residual {rn:.2e})")
        if it > 3 and rn > 1e6 * max(hist[0], 1e-300):
            raise _Failed(f"diverging (residual {rn:.2e})")
        ts = time.perf_counter()
        fac = _Factored(ev["K"], sysm.solver)
        try:
            a = fac.solve(-ev["r"])
            b = fac.solve(ev["q"])
        finally:
            fac.close()
        timers[1] += time.perf_counter() - ts
        if isinstance(con, _Linear):
            con.lam = lam
        dl = con.dlam_for(sysm, state, a, b)
        x = a + dl * b
        dn = sysm.increment_norm(x)
        state = sysm.update(state, x)
        lam = lam + dl
        con.accept(x, dl)


def path_follow(sysm, constraint="crisfield", lam_end=1.0, dlam0=0.05, ds_max=None, ds_min=None,
                psi=0.0, max_steps=200, target_iter=5, max_iter=20, rtol=1e-9, dtol=1e-9,
                max_rejections=12, control=None, control_end=None, lam_min=None, stability=True,
                branch_switch=False, land=True, verbose=False, record=None, log=None,
                ds_max_factor=8.0, start=None, on_step=None, timers=None):
    """Trace the path of ``sysm`` (ShellSystem or any object with the same methods).

    Stops when lam >= lam_end (if lam_end is not None), when the controlled displacement
    ``control = (value, row)`` reaches ``control_end`` (e.g. the deflection at the end of a
    published table), when lam < lam_min, or after max_steps.  With ``land`` the last step is
    redone with load control (displacement control) so that it ends exactly on lam_end
    (control_end).  Returns (points, critical points, log, timers).

    on_step(ArcState) is called after the first point and after every converged point, with
    what a restart needs; ``start=ArcState`` continues from such a point instead of the
    reference state (dlam0, ds_max, ds_min, psi and branch_switch then come from it; the start
    point is not passed to ``record`` again; a finished start returns at once, unless it stopped
    at a max_steps now raised), repeating the computations of the uninterrupted path bit for
    bit.  timers: [assembly, solve] seconds, accumulated in place.
    """
    timers = [0.0, 0.0] if timers is None else timers
    log = [] if log is None else log
    if start is not None and start.finished and not (start.finished == "max_steps" and start.step < max_steps):
        return [], list(start.critical), log, timers
    if start is None:
        state, lam = sysm.initial(), 0.0
    else:
        state, lam = start.state, float(start.lam)
    first = _analyse(sysm, state, lam, stability)
    points = [first]
    ctrl_val = control[0] if control else None
    if start is None:
        if record:
            record(first)
        crit = []
        tn0 = np.sqrt(np.sum(sysm.w * first.t ** 2))
        if not np.isfinite(tn0) or tn0 == 0:
            raise CoreSE3Error("the loads do not move the structure (K^-1 q = 0)")
        psi_u = psi * tn0                       # load term of the arc length in length units
        ds = abs(dlam0) * np.sqrt(tn0 ** 2 + psi_u ** 2)
        ds_max = ds_max or ds_max_factor * ds
        ds_min = ds_min or ds / 2 ** max_rejections
        direction = np.sign(dlam0) or 1.0
        prev_du, prev_dl = None, None
        switch_mode = None
        step = 0
    else:
        crit = list(start.critical)
        psi_u, ds, ds_max, ds_min = start.psi_u, start.ds, start.ds_max, start.ds_min
        direction = start.direction
        prev_du = None if start.prev_du is None else np.array(start.prev_du, float)
        prev_dl = start.prev_dl
        switch_mode = None if start.switch_mode is None else np.array(start.switch_mode, float)
        branch_switch = start.branch_switch
        step = int(start.step)

    def finished(pt):
        if lam_end is not None and (pt.lam - lam_end) * np.sign(lam_end or 1.0) >= -1e-12 * max(1, abs(lam_end)):
            return "lam_end"
        if control_end is not None and (ctrl_val(pt.state) - control_end) * np.sign(control_end) >= \
                -1e-12 * abs(control_end):
            return "control_end"
        if lam_min is not None and pt.lam < lam_min:
            return "lam_min"
        return None

    def snapshot(pt, why):
        return ArcState(pt.state, pt.lam, step, ds, ds_max, ds_min, psi_u, direction, prev_du, prev_dl,
                        switch_mode, branch_switch, list(crit),
                        why or ("max_steps" if step >= max_steps else ""))

    if start is None and on_step:
        on_step(snapshot(first, ""))
    rejections = 0
    while step < max_steps:
        cur = points[-1]
        t = cur.t
        tn = np.sqrt(np.sum(sysm.w * t * t))
        jumped = switch_mode is not None
        if jumped:
            du = switch_mode * ds
            dl = 0.0
            switch_mode = None
        else:
            dl = ds / np.sqrt(tn ** 2 + psi_u ** 2)
            if prev_du is None:
                s = direction
            else:
                s = np.sign(np.sum(sysm.w * prev_du * t) + psi_u ** 2 * prev_dl) or 1.0
            dl *= s
            du = dl * t
        con = _ArcLength("riks" if constraint == "riks" else "crisfield", ds, psi_u, sysm.w)
        con.start(du, dl)
        reason = ""
        try:
            st_pred = sysm.update(cur.state, du)
            new_state, new_lam, its, hist, ev = _correct(sysm, st_pred, cur.lam + dl, con, rtol, dtol,
                                                         max_iter, timers)
            if not jumped and np.sum(sysm.w * con.du0 * con.du) + psi_u ** 2 * con.dlam0 * con.dlam <= 0:
                raise _Failed("the corrector turned back against the predictor (path reversal)")
            pt = _analyse(sysm, new_state, new_lam, stability, its, hist)
        except (_Failed, ElementTooDistortedError, FloatingPointError, SingularSystemError) as exc:
            reason = str(exc)
            pt = None
        log.append(dict(step=step + 1, lam=(cur.lam + dl) if pt is None else pt.lam, ds=ds,
                        converged=pt is not None, iterations=len(hist) - 1 if pt else None,
                        reason=reason))
        if pt is None:
            rejections += 1
            if verbose:
                print(f"  step {step + 1}: ds {ds:.4g} REJECTED ({reason}); retry with ds/2")
            ds /= 2
            if ds < ds_min or rejections > max_rejections:
                raise _PathError(f"arc length failed at lam {cur.lam:.6g} after {rejections} "
                                 f"rejections ({reason})", points, crit, log)
            continue
        why = finished(pt)
        if why in ("lam_end", "control_end") and land:
            # redo the step, ending exactly on the stop value
            if why == "lam_end":
                lin = _Linear(None, None, 1.0, lam_end)
            else:
                lin = _Linear(control[0], control[1], 0.0, control_end)
            try:
                frac = _fraction(cur, pt, why, lam_end, control_end, ctrl_val)
                st_pred = sysm.update(cur.state, frac * con.du)
                s2, l2, its, hist, ev = _correct(sysm, st_pred, cur.lam + frac * con.dlam, lin,
                                                 rtol, dtol, max_iter, timers)
                pt = _analyse(sysm, s2, l2, stability, its, hist)
            except (_Failed, ElementTooDistortedError, FloatingPointError, SingularSystemError) as exc:
                if verbose:
                    print(f"  landing failed ({exc}); keeping the arc-length step")
        rejections = 0
        step += 1
        prev_du, prev_dl = con.du, con.dlam
        points.append(pt)
        if record:
            record(pt)
        # critical points between cur and pt
        event = ""
        changed = (pt.n_neg != cur.n_neg) if (pt.n_neg is not None and cur.n_neg is not None) \
            else (pt.sign != cur.sign)
        if stability and changed and not jumped:
            span = np.sqrt(np.sum(sysm.w * con.du ** 2))
            # dlam/ds changes sign across a limit point: the predictor's dlam at cur against the
            # one the next predictor will take at pt (robust where q.t also passes through 0,
            # at a turning point of the displacement conjugate to q)
            nxt = np.sum(sysm.w * con.du * pt.t) + psi_u ** 2 * con.dlam
            turned = np.sign(con.dlam0) != np.sign(nxt) if nxt != 0 else None
            cp = _critical(sysm, cur, pt, sysm.w * con.du / span, span, step, limit=turned)
            crit.append(cp)
            event = "  ** " + cp.describe()
            if cp.kind == "bifurcation" and branch_switch and cp.mode is not None:
                m = cp.mode - (np.sum(sysm.w * cp.mode * pt.t) / np.sum(sysm.w * pt.t * pt.t)) * pt.t
                switch_mode = m / np.sqrt(np.sum(sysm.w * m * m))
                prev_du = None
                branch_switch = False            # switch once
                event += " -> switching onto the bifurcated branch"
        if verbose:
            cv = f" control {ctrl_val(pt.state):.6g}" if ctrl_val else ""
            neg = "" if pt.n_neg is None else f" neg.eig {pt.n_neg}"
            if jumped:
                event += "  (first step on the bifurcated branch)"
            print(f"  step {step}: lam {pt.lam:.6g} (dlam {pt.lam - cur.lam:+.3g}) ds {ds:.4g} "
                  f"it {pt.its} res {pt.hist[-1]:.1e}{cv} det {'+' if pt.sign >= 0 else '-'}{neg}{event}")
        if not why:
            ds = min(ds_max, ds * float(np.clip(np.sqrt(target_iter / max(pt.its, 1)), 0.5, 2.0)))
        if on_step:
            on_step(snapshot(pt, why))
        if why:
            break
    return points, crit, log, timers


def _critical(sysm, cur, pt, c, span, step, limit=None):
    """Classify and locate the critical point between two converged states.

    Along the step, measure progress by sigma = c . du (c = W du/|du| for arc length, the
    control row for displacement control); the path slope dlam/dsigma = 1/(c . t).  A limit
    point is where the slope passes through zero (arc length: the predicted dlam changes sign between the two states;
    displacement control: q . t changes sign): with the slope linear in
    sigma, sigma_c = span s0/(s0 - s1) and lam_c = lam_0 + s0 sigma_c / 2 (a parabola; the
    estimate from the far end is averaged in).  A bifurcation (q . t keeps its sign) is located
    where the smallest eigenvalue of sym(K), from inverse iteration, interpolates to zero.
    """
    if limit is None:
        limit = np.sign(pt.qt) != np.sign(cur.qt)
    mode = None
    if limit:
        s0, s1 = 1.0 / (c @ cur.t), 1.0 / (c @ pt.t)
        if np.sign(s0) != np.sign(s1):
            sc = span * s0 / (s0 - s1)
            lam_c = 0.5 * ((cur.lam + 0.5 * s0 * sc) + (pt.lam - 0.5 * s1 * (span - sc)))
        else:
            lam_c = max(cur.lam, pt.lam, key=abs)
        kind = "limit"
    else:
        kind = "bifurcation"
        mu0, _ = _mode_at(sysm, cur)
        mu1, mode = _mode_at(sysm, pt)
        if mu0 is not None and mu1 is not None and mu0 != mu1 and np.sign(mu0) != np.sign(mu1):
            lam_c = cur.lam + (pt.lam - cur.lam) * mu0 / (mu0 - mu1)
        else:
            lam_c = 0.5 * (cur.lam + pt.lam)
    return CriticalPoint(kind, step, float(lam_c), (cur.lam, pt.lam), (cur.n_neg, pt.n_neg), mode)


def _fraction(cur, pt, why, lam_end, control_end, ctrl_val):
    if why == "lam_end":
        a, b, target = cur.lam, pt.lam, lam_end
    else:
        a, b, target = ctrl_val(cur.state), ctrl_val(pt.state), control_end
    return float(np.clip((target - a) / (b - a), 0.0, 1.0)) if b != a else 1.0


def _mode_at(sysm, pt):
    """(smallest eigenvalue, mode) of sym(K) at a converged point, or (None, None)."""
    try:
        fac = _Factored(pt.ev["K"], sysm.solver)
        try:
            return _smallest_mode(pt.ev["K"], fac)
        finally:
            fac.close()
    except SingularSystemError:
        return None, None


class _PathError(ConvergenceError):
    def __init__(self, message, points, crit, log):
        super().__init__(message)
        self.points, self.crit, self.log = points, crit, log


# ============================================================== Problem front ends ========

def _result(problem, sysm, run):
    t0 = time.perf_counter()
    rec = _Recorder(problem)
    log = rec.result.log
    try:
        points, crit, _, timers = run(rec, log)
    except _PathError as exc:
        rec.result.critical_points = exc.crit
        tm = rec.result.timings                  # assembly, solve as of the last converged point
        tm.update(other=time.perf_counter() - t0 - tm.get("assembly", 0.0) - tm.get("solve", 0.0))
        raise ConvergenceError(f"{exc}; the converged steps are kept in .result", rec.result) from None
    rec.result.critical_points = crit
    rec.result.timings.update(assembly=timers[0], solve=timers[1],
                              other=time.perf_counter() - t0 - timers[0] - timers[1])
    return rec.result


def arc_length(problem, lam_end=1.0, dlam0=0.05, method="crisfield", psi=0.0, ds_max=None,
               ds_max_factor=8.0, max_steps=200, target_iter=5, max_iter=20, rtol=1e-9, dtol=1e-9, stop_at=None,
               lam_min=None, stability=True, branch_switch=False, land=True, verbose=False,
               linear_solver=None, start=None, on_step=None):
    """Arc-length continuation of a Problem (see module docstring).

    dlam0: load factor of the first predictor (sets the arc length ds); ds_max defaults to
    ds_max_factor (8) times that.  stop_at = (node, lab direction, value): stop when the displacement of ``node``
    along ``direction`` reaches ``value`` (the last step lands on it exactly).  Returns a
    Result with every converged step; ``result.critical_points`` lists the limit and
    bifurcation points found (CriticalPoint), each step has ``.stability``.

    Restart: ``on_step(result, arc_state)`` is called after the first point and after every
    converged point (result: the Result so far, its last step the new point, its timings and
    critical_points up to date; arc_state: the ArcState to restart from, with the probes'
    unwrapped rotation vectors).  ``start=arc_state`` continues the path from it with the same
    arguments otherwise: ``result.steps`` then holds only the points after the start (path step
    ``start.step + 1`` onwards), ``critical_points`` all of the path (steps numbered along the
    whole path), and the final state equals that of an uninterrupted call bit for bit.
    """
    sysm = ShellSystem(problem, linear_solver)
    control = sysm.node_displacement(stop_at[0], stop_at[1]) if stop_at else None

    def run(rec, log):
        timers = [0.0, 0.0]
        t0 = time.perf_counter()
        if start is not None and start.unwrap is not None:
            rec.unwrapped.update({k: np.array(v, float) for k, v in start.unwrap.items()})

        def step_cb(st):
            st.unwrap = {k: v.copy() for k, v in rec.unwrapped.items()}
            rec.result.critical_points = list(st.critical)
            rec.result.timings.update(assembly=timers[0], solve=timers[1],
                                      other=time.perf_counter() - t0 - timers[0] - timers[1])
            on_step(rec.result, st)

        return path_follow(sysm, method, lam_end, dlam0, ds_max, None, psi, max_steps, target_iter,
                           max_iter, rtol, dtol, control=control,
                           control_end=stop_at[2] if stop_at else None, lam_min=lam_min,
                           stability=stability, branch_switch=branch_switch, land=land,
                           verbose=verbose, record=rec, log=log, ds_max_factor=ds_max_factor,
                           start=start, on_step=step_cb if on_step else None, timers=timers)

    return _result(problem, sysm, run)


def displacement_control(problem, node, direction, values, max_iter=20, rtol=1e-9, dtol=1e-9,
                         max_cutbacks=10, stability=True, verbose=False, linear_solver=None):
    """Prescribe the displacement of ``node`` along the lab ``direction`` through ``values``
    (the load factor is the unknown that keeps it there); failed increments are halved.
    Records every requested value; ``result.critical_points`` as for arc_length."""
    sysm = ShellSystem(problem, linear_solver)
    value, row = sysm.node_displacement(node, direction)
    values = [float(v) for v in np.atleast_1d(values)]

    def run(rec, log):
        timers = [0.0, 0.0]
        cur = _analyse(sysm, sysm.initial(), 0.0, stability)
        rec(cur)
        points, crit = [cur], []
        for target in values:
            sub = [target]
            while sub:
                tgt = sub[-1]
                u0 = value(cur.state)
                rt = row(cur.state)
                try:
                    dl = (tgt - u0) / (rt @ cur.t)
                    st_pred = sysm.update(cur.state, dl * cur.t)
                    s2, l2, its, hist, ev = _correct(sysm, st_pred, cur.lam + dl,
                                                     _Linear(value, row, 0.0, tgt),
                                                     rtol, dtol, max_iter, timers)
                    pt = _analyse(sysm, s2, l2, stability, its, hist)
                    ok, reason = True, ""
                except (_Failed, ElementTooDistortedError, FloatingPointError,
                        SingularSystemError, ZeroDivisionError) as exc:
                    ok, reason = False, str(exc)
                log.append(dict(control=tgt, converged=ok, reason=reason))
                if verbose:
                    print(f"  u* {tgt:.6g}: " + (f"lam {pt.lam:.6g} it {pt.its}" if ok else f"FAIL {reason}"))
                if not ok:
                    if len(sub) > max_cutbacks:
                        raise _PathError(f"displacement control failed at u = {tgt:.6g} ({reason})",
                                         points, crit, log)
                    sub.append(0.5 * (u0 + tgt))
                    continue
                sub.pop()
                changed = (pt.n_neg != cur.n_neg) if (pt.n_neg is not None and cur.n_neg is not None) \
                    else (pt.sign != cur.sign)
                if stability and changed:
                    crit.append(_critical(sysm, cur, pt, row(cur.state), value(pt.state) - value(cur.state),
                                          len(points)))
                    if verbose:
                        print("  ** " + crit[-1].describe())
                cur = pt
                if not sub:
                    rec(pt)
                    points.append(pt)
        return points, crit, log, timers

    return _result(problem, sysm, run)


def limit_point_hint(problem, g, lam, linear_solver=None):
    """Diagnose a load-control failure at the converged state (g, lam): the current stiffness
    parameter S_p = (q.t_0 / q.t) (t = K^-1 q, 1 at the start, 0 at a limit point, negative
    past it).  Returns a message suggesting arc length when S_p < 0.3, else None."""
    try:
        sysm = ShellSystem(problem, linear_solver, difference="backward")
        p0 = _analyse(sysm, problem.mesh.g0.copy(), 0.0, False)
        p1 = _analyse(sysm, np.asarray(g, float), lam, False)
    except (CoreSE3Error, FloatingPointError, ValueError):
        return None
    sp_ = p0.qt / p1.qt if p1.qt != 0 else 0.0
    if sp_ < 0.3:
        return (f"the load-displacement stiffness at load factor {lam:.6g} has fallen to "
                f"S_p = {sp_:.3g} of its initial value: load control has met a limit point "
                "(the load cannot increase further on this path); trace it with arc length "
                "(core_se3.continuation.arc_length) or displacement control "
                "(core_se3.continuation.displacement_control)")
    return None

"""Stability of converged states: the inertia of the symmetrised tangent, the critical points
it brackets (limit points and bifurcations), and the diagnosis of a load-control failure.

At each converged state the symmetric part of K is factorised (SuperLU, symmetric ordering,
diagonal pivots; MUMPS LDL^T from AUTO_MUMPS_MIN unknowns); the number of negative pivots is the number of negative eigenvalues
(Sylvester) and its change between two steps brackets a critical point.  It is a *limit point*
when dlam/ds passes through zero with it (arc length: the sign of the predicted load increment
at the two states; displacement control: the sign of q . t), otherwise a *bifurcation*; the
critical load factor of a limit point is interpolated where the current stiffness parameter
S_p = (q . t_0)/(q . t) vanishes.
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from functools import partial

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import CoreSE3Error, SingularSystemError
from ..model.base import conservative_loads, overrides
from .linalg import AUTO_MUMPS_MIN, Factorization, available_solvers, make_solver, mumps_inertia
from .system import ShellSystem

__all__ = ["inertia", "asymmetry", "stability_of", "negative_count", "unseen_crossing", "smallest_mode", "CriticalPoint", "PathPoint", "analyse", "locate_critical",
           "limit_point_hint", "prescribed_turn_hint", "TURN_HINT"]

TURN_HINT = 0.05    # prescribed_turn_hint: the smallest eigenvalue's fraction of its start value
ASYM_TOL = 1e-10    # stability_of / negative_count: K symmetric (conservative loads) to this (asymmetry)


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

    Parameters
    ----------
    K : scipy.sparse matrix or (N, N) array
        The tangent (only its symmetric part counts).

    Returns
    -------
    (int, int or None)
        +1 or -1, and the count of negative eigenvalues (None when it could not be counted).

    Example
    -------
    >>> import numpy as np, scipy.sparse as sp
    >>> K = np.diag([2.0, -1.0, 3.0])
    >>> inertia(K), inertia(sp.csr_matrix(K))
    ((-1, 1), (-1, 1))
    """
    if not sp.issparse(K):
        Ks = 0.5 * (np.asarray(K) + np.asarray(K).T)
        ev = np.linalg.eigvalsh(Ks)
        return (1 if np.sum(ev < 0) % 2 == 0 else -1), int(np.sum(ev < 0))
    Ks = (0.5 * (K + K.T)).tocsr()
    d = np.abs(Ks.diagonal())
    d[d == 0] = 1.0
    s = 1.0 / np.sqrt(d)
    # S Ks S on the same structure (a congruence: the inertia is unchanged)
    Ks.data *= s[np.repeat(np.arange(Ks.shape[0]), np.diff(Ks.indptr))] * s[Ks.indices]
    if Ks.shape[0] >= AUTO_MUMPS_MIN and "mumps" in available_solvers():
        # large: MUMPS' LDL^T counts the negative pivots (measured 4x faster than SuperLU at
        # 14k unknowns on the pinched cylinder); a null pivot is a singular matrix
        nneg, _, _ = mumps_inertia(Ks)
        return (-1 if nneg % 2 else 1), nneg
    Ks = Ks.tocsc()
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


def smallest_mode(K, fac, n_iter=30, seed=7):
    """Eigenvector of sym(K) of smallest |eigenvalue| by inverse iteration on the factor of K
    (K is symmetric at equilibrium up to the residual); returns (mu, phi).

    Parameters
    ----------
    K : scipy.sparse matrix or array
        The tangent.
    fac : Factorization
        Its factorisation.
    n_iter : int, optional
        Inverse iterations at most; ``seed``: of the random start vector.

    Returns
    -------
    mu : float
        The Rayleigh quotient phi . K phi (the eigenvalue estimate).
    phi : (N,) ndarray
        The unit mode.

    Example
    -------
    >>> import numpy as np
    >>> K = np.diag([4.0, 0.5, 2.0])
    >>> with Factorization(K, None) as F:
    ...     mu, phi = smallest_mode(K, F)
    >>> round(mu, 6), np.abs(phi).round(3).tolist()
    (0.5, [0.0, 1.0, 0.0])
    """
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


@dataclass
class CriticalPoint:
    """A critical point bracketed by two converged steps (indices into result.steps).

    Attributes
    ----------
    kind : str
        'limit' or 'bifurcation'.
    step : int
        The first step past the critical point.
    lam : float
        The estimated critical load factor; ``lam_bracket``: the load factors of the two steps.
    negative_eigenvalues : tuple
        The negative-eigenvalue counts of the two steps (None where not counted).
    mode : ndarray or None
        The buckling mode of a bifurcation (free dofs), not in the repr.
    accuracy : float or None
        Relative width of the interval known to hold the critical load factor after the
        bracket was refined (``solvers.critical``; None: not refined).

    Example
    -------
    >>> print(CriticalPoint("limit", 5, 0.742, (0.74, 0.745), (0, 1)).describe())  # doctest: +NORMALIZE_WHITESPACE
    limit point not located: lam between 0.74 and 0.745 (bracket only, not narrowed: its accuracy is the
    bracket; estimate ~ 0.742, negative eigenvalues 0 -> 1)
    >>> CriticalPoint.unpack(CriticalPoint("limit", 5, 0.742, (0.74, 0.745), (0, 1), accuracy=1e-4).pack()).describe()
    'limit point at lam = 0.742 +- 7.4e-05 (refined between 0.74 and 0.745, negative eigenvalues 0 -> 1)'
    """
    kind: str                # 'limit' or 'bifurcation'
    step: int                # first step past the critical point
    lam: float               # estimated critical load factor
    lam_bracket: tuple
    negative_eigenvalues: tuple
    mode: np.ndarray | None = field(default=None, repr=False)
    accuracy: float | None = None

    def __init_subclass__(cls, kind=None, **kw):
        """A subclass ``class SnapPoint(CriticalPoint, kind="snap")`` is what :meth:`unpack`
        makes of a packed point of that kind (with its own fields)."""
        super().__init_subclass__(**kw)
        if kind is not None:
            _KINDS[kind] = cls

    def extras(self):
        """The JSON-able fields a subclass adds (a snap's node, travel, min_step; {} here)."""
        base = {f.name for f in fields(CriticalPoint)}
        vals = {f.name: getattr(self, f.name) for f in fields(self) if f.name not in base}
        return {k: v.item() if isinstance(v, np.generic) else v for k, v in vals.items()}

    def pack(self):
        """A JSON-able dict of the point (not its mode) with a subclass's fields (:meth:`extras`);
        :meth:`unpack` inverts it (a checkpoint's): a resumed run's snap is still a snap, with
        its node and travel."""
        return dict(kind=self.kind, step=int(self.step), lam=float(self.lam),
                    lam_bracket=[float(x) for x in self.lam_bracket],
                    negative_eigenvalues=[None if x is None else int(x) for x in self.negative_eigenvalues],
                    accuracy=None if self.accuracy is None else float(self.accuracy), **self.extras())

    @classmethod
    def unpack(cls, d):
        klass = _KINDS.get(d["kind"], cls)
        extra = {f.name: d[f.name] for f in fields(klass) if f.name not in _BASE_PACKED and f.name in d}
        return klass(d["kind"], d["step"], d["lam"], tuple(d["lam_bracket"]), tuple(d["negative_eigenvalues"]),
                     accuracy=d.get("accuracy"), **extra)

    def describe(self):
        """One line for a person.  A point not narrowed (``accuracy`` None: load control's
        bracket, limit_check off) says so plainly: it is known only to lie in the bracket."""
        a, b = self.lam_bracket
        neg = "" if None in self.negative_eigenvalues else \
            f", negative eigenvalues {self.negative_eigenvalues[0]} -> {self.negative_eigenvalues[1]}"
        if self.accuracy is not None:
            return (f"{self.kind} point at lam = {self.lam:.6g} +- {self.accuracy * abs(self.lam):.2g} "
                    f"(refined between {a:.6g} and {b:.6g}{neg})")
        return (f"{self.kind} point not located: lam between {a:.6g} and {b:.6g} (bracket only, not narrowed: "
                f"its accuracy is the bracket; estimate ~ {self.lam:.6g}{neg})")


_KINDS = {}                  # kind -> CriticalPoint subclass (__init_subclass__)
_BASE_PACKED = {"kind", "step", "lam", "lam_bracket", "negative_eigenvalues", "mode", "accuracy"}


@dataclass
class PathPoint:
    """A converged point of a path as the path follower sees it (:func:`analyse`).

    Attributes
    ----------
    state : object
        The state (ShellSystem: frames (n, 4, 4)); ``lam`` its load factor.
    t : ndarray
        The tangent K^-1 q on the free dofs; ``qt`` = q . t.
    sign, n_neg : int, int or None
        Inertia of sym(K) (:func:`inertia`; 0 and None without the stability analysis).
    its, hist, ev
        Iterations and residual history of the corrector, the system's evaluation (with K).

    Example
    -------
    >>> import numpy as np
    >>> from core_se3.solvers import AlgebraicSystem
    >>> s = AlgebraicSystem(lambda u: u + u ** 3, lambda u: np.diag(1 + 3 * u ** 2), [1.0])
    >>> pt = analyse(s, s.initial(), 0.0, True)            # K = 1, q = 1 at u = 0
    >>> pt.t.tolist(), pt.qt, pt.sign, pt.n_neg
    ([1.0], 1.0, 1, 0)
    """
    state: object
    lam: float
    t: np.ndarray            # tangent K^-1 q at the state
    qt: float                # q . t
    sign: int
    n_neg: int | None
    its: int = 0
    hist: list = field(default_factory=list)
    ev: dict | None = None


def analyse(sysm, state, lam, stability, its=0, hist=(), ev=None):
    """The PathPoint of a converged state: tangent t = K^-1 q, q . t and the inertia of K
    (:func:`stability_of`)."""
    ev = sysm.evaluate(state, lam, tangent=True) if ev is None or "K" not in ev else ev
    sysm.factorizations += 1
    with Factorization(ev["K"], sysm.solver) as fac:
        t = fac.solve(ev["q"])
    loads = getattr(getattr(sysm, "problem", None), "loads", ())
    sign, nneg = stability_of(ev["K"], fac, free=getattr(getattr(sysm, "asm", None), "free", None),
                              counted=conservative_loads(loads) is not False) if stability else (0, None)
    return PathPoint(state, lam, t, float(ev["q"] @ t), sign, nneg, its, list(hist), ev)


def asymmetry(K, free=None):
    """max |K_ij - K_ji| / sqrt(|K_ii K_jj|) of a tangent on the free dofs (its skew part in the
    Jacobi-scaled D^-1/2 K D^-1/2, D = |diag K|), outside the diagonal blocks of the nodes a
    support holds (``free``: the (6 n,) mask of the free dofs; None: everywhere).

    Jacobi scaling makes the measure independent of the units (any diagonal scaling of the dofs
    cancels) and of the thickness: max |K - K^T| / max |K|, used before, compared a moment's skew
    term in the rotation blocks with the membrane stiffness, so the rolled-up strip under its
    dead end moment measured 6.3e-4 in its units and 6.3e-10 in metres (counted as conservative:
    a spurious 'critical point' stopped it), the arch under its follower force 1.3e-7 (counted as
    conservative in its own units).  Measured on the catalogue's final states: conservative
    problems <= 3.0e-14 (contact, magnets at equilibrium, the Sze shells), the
    non-conservative >= 5.1e-5 (arch-follower; rollup 9.2e-3, friction 0.25).  A load's skew part
    falls like (h/L)^2 with the thickness (the rotations' diagonal is the transverse shear's, ~h;
    a bending moment ~h^3): the rollup 9.2e-7 at L/h 1e4 and 9.2e-9 at 1e5, hence ASYM_TOL = 1e-10
    (1e-6 before: those strips counted as conservative and stopped on a spurious critical point).

    The left-trivialised tangent carries a skew term 1/2 ad*(r) of each node's unbalanced wrench r
    (the derivative of the gradient along g exp(eta)); at an equilibrium r vanishes except at a
    held node, where it is the support's reaction.  So a conservative problem's K is symmetric
    outside those blocks (to round-off), and the skew part inside them is the reactions', not a
    non-conservative load's: the Scordelis-Lo roof 16x16 under its self-weight, held on symmetry
    planes, measures 4.1e-5 in all and 4.1e-15 outside them -- counted as all, its end check and
    arc length's counts of negative eigenvalues were switched off as if its loads were followers.

    Example
    -------
    >>> import numpy as np
    >>> K = np.eye(12); K[0, 4] = 1e-3            # a skew term in node 0's block
    >>> free = np.ones(12, bool); free[2] = False  # node 0 held in z: its block is a reaction's
    >>> round(asymmetry(K[np.ix_(free, free)]), 6), asymmetry(K[np.ix_(free, free)], free)
    (0.001, 0.0)
    """
    K = sp.csr_matrix(K)
    diag = np.abs(K.diagonal())
    if diag.size == 0 or abs(K).max() == 0:
        return 0.0
    dof = np.nonzero(np.asarray(free, bool))[0] if free is not None else np.arange(len(diag))
    top = np.zeros(6)                                   # per component (x, y, z, rx, ry, rz): a
    np.maximum.at(top, dof % 6, diag)                   # floor for dofs without stiffness that
    d = 1.0 / np.sqrt(np.maximum(diag, 1e-16 * top[dof % 6] + 1e-300))   # no change of units moves
    Kc = sp.coo_matrix(K - K.T)
    keep = np.ones(Kc.nnz, bool)
    if free is not None:
        free = np.asarray(free, bool)
        node = dof // 6                                 # the node of each free dof
        held = ~free.reshape(-1, 6).all(axis=1)
        keep = ~((node[Kc.row] == node[Kc.col]) & held[node[Kc.row]])
    return float(np.abs(Kc.data[keep] * d[Kc.row[keep]] * d[Kc.col[keep]]).max(initial=0.0))


def stability_of(K, fac=None, asym_tol=ASYM_TOL, free=None, counted=True):
    """(sign of det K, count of negative eigenvalues or None) at a converged state: the inertia of
    sym(K) (:func:`inertia`) when K is symmetric to ``asym_tol`` (:func:`asymmetry`, Jacobi-scaled:
    conservative loads, <= 3.0e-14 measured on the catalogue), else the sign of det K
    itself (from the factors ``fac`` in hand, or an LU of K) and no count.  With non-conservative
    loads sym(K) says nothing of a critical point, which is where K itself is singular: Beck's
    column (a cantilever strip under a compressive follower end force, 15 EI/L^2, below its
    flutter load 20.05 EI/L^2 and with no static instability at all) was reported to have a
    'bifurcation point at lam = 0.65918 +- 0.0002' where an eigenvalue of sym(K) passed zero,
    while the smallest |eigenvalue| of K grew from 0.027 to 0.115.  ``counted`` False (loads
    that are not conservative by their kinds, ``model.base.conservative_loads``): the sign only.

    Example
    -------
    >>> import numpy as np
    >>> stability_of(np.array([[1.0, 3.0], [-3.0, 1.0]]))      # sym part indefinite, det K = 10
    (1, None)
    """
    Kd = K if sp.issparse(K) else np.asarray(K)
    if counted and (abs(Kd).max() == 0 or asymmetry(Kd, free) <= asym_tol):
        return inertia(K)
    sign = fac.det_sign() if fac is not None else None
    if sign is None:
        if sp.issparse(K):
            lu = spla.splu(sp.csc_matrix(K), permc_spec="COLAMD")
            sign = int(np.prod(np.sign(lu.U.diagonal()))) * _perm_parity(lu.perm_r) * _perm_parity(lu.perm_c)
        else:
            sign = int(np.linalg.slogdet(Kd)[0])
    return sign, None


def locate_critical(sysm, cur, pt, c, span, step, limit=None):
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
        mu0, _ = mode_at(sysm, cur)
        mu1, mode = mode_at(sysm, pt)
        if mu0 is not None and mu1 is not None and mu0 != mu1 and np.sign(mu0) != np.sign(mu1):
            lam_c = cur.lam + (pt.lam - cur.lam) * mu0 / (mu0 - mu1)
        else:
            lam_c = 0.5 * (cur.lam + pt.lam)
    return CriticalPoint(kind, step, float(lam_c), (cur.lam, pt.lam), (cur.n_neg, pt.n_neg), mode)


def mode_at(sysm, pt):
    """(smallest eigenvalue, mode) of sym(K) at a converged point, or (None, None)."""
    try:
        sysm.factorizations += 1
        with Factorization(pt.ev["K"], sysm.solver) as fac:
            return smallest_mode(pt.ev["K"], fac)
    except SingularSystemError:
        return None, None


def limit_point_hint(problem, g, lam, linear_solver=None):
    """Diagnose a load-control failure at the converged state (g, lam): the current stiffness
    parameter S_p = (q.t_0 / q.t) (t = K^-1 q, 1 at the start, 0 at a limit point, negative
    past it).  Returns a message suggesting arc length when S_p < 0.3, else None.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem.
    g : (n, 4, 4) array
        The last converged state; ``lam`` its load factor.
    linear_solver : str, optional
        Default the problem's.

    Returns
    -------
    str or None
        The hint (None also when the diagnosis itself fails).

    Example
    -------
    The unloaded strip is as stiff as at the start (S_p = 1): no hint.

    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> limit_point_hint(p, p.mesh.g0, 0.5) is None
    True
    """
    if contact_loads(problem):
        return contact_limit_hint(problem, g, lam, linear_solver)
    tables = bool(getattr(problem, "scale_tables", ()))
    try:
        sysm = ShellSystem(problem, linear_solver, difference="forward" if tables else "backward", tables=True)
        p0 = analyse(sysm, sysm.initial(), 0.0, False)
        sysm.difference = "backward"
        p1 = analyse(sysm, sysm.local(g), lam, False)
    except (CoreSE3Error, FloatingPointError, ValueError):
        return None
    if tables:                       # the flexibility along the load, free of the tables' slopes
        f0, f1 = _rayleigh(p0), _rayleigh(p1)
        if f0 is None or f1 is None:
            return None              # no load rate at one end (a flat stretch): nothing to compare
        sp_ = f0 / f1 if f1 != 0 else 0.0
    else:
        sp_ = p0.qt / p1.qt if p1.qt != 0 else 0.0
    return stiffness_hint(lam, sp_)


def stiffness_hint(lam, sp_):
    """The limit-point hint for a current stiffness S_p = ``sp_`` at load factor ``lam`` (below
    0.3), else None: :func:`limit_point_hint`'s, and a distributed run's, whose S_p is that of the
    failed try's first iterate (``TryOutcome.k_step`` over the first accepted try's).

    Example
    -------
    >>> stiffness_hint(0.5, 0.8) is None, stiffness_hint(0.5, 0.01)[:52]
    (True, 'the load-displacement stiffness at load factor 0.5 h')
    """
    if sp_ >= 0.3:
        return None
    return (f"the load-displacement stiffness at load factor {lam:.6g} has fallen to "
            f"S_p = {sp_:.3g} of its initial value: load control has met a limit point "
            "(the load cannot increase further on this path); trace it with arc length "
            "(core_se3.solvers.arc_length) or displacement control "
            "(core_se3.solvers.displacement_control)")


def _rayleigh(pt):
    """q . K^-1 q / |q|^2 at a PathPoint (None for q = 0): the current flexibility along the
    load, free of the programme's slope s'(lam) (a scale table's, which differs from stretch to
    stretch: q = s' q_1 scales q . t by s'^2).  Load stepping's limit point hint with scale
    tables compares it at the start (q from above) and at the last state (from below); the
    backward q at 0 of a table that starts at (0, 0) is 0, so every failure was called 'a limit
    point, S_p = 0' (the snap roof's, and any other)."""
    qq = float(pt.ev["q"] @ pt.ev["q"])
    return pt.qt / qq if qq != 0.0 else None


def prescribed_turn_hint(problem, g, lam, linear_solver=None):
    """Diagnose a load-stepping failure of a problem driven by a prescribed motion at the
    converged state (g, lam): the smallest eigenvalue of its tangent on the free dofs (the
    prescribed ones held), by inverse iteration (:func:`smallest_mode`), against its value at the
    reference state.  Below ``TURN_HINT`` of it the equilibrium under the prescribed motion is
    about to turn back (a snap-back in the prescribed displacement: the 8x8 6.35 mm roof with its
    crown pushed down stopped at -W_C = 16.95 after 12 cut-backs, with no cause named), and no
    load stepping passes it.

    Parameters
    ----------
    problem : core_se3.Problem
        The problem (with a prescribed motion).
    g : (n, 4, 4) array
        The last converged state; ``lam`` its load factor.
    linear_solver : str, optional
        Default the problem's.

    Returns
    -------
    str or None
        The hint (None also when the diagnosis itself fails).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> prescribed_turn_hint(p, p.mesh.g0, 0.5) is None              # as stiff as at the start
    True
    """
    ratio = _ratio(_smallest_eigenvalue(problem, problem.mesh.g0.copy(), 0.0, linear_solver),
                   _smallest_eigenvalue(problem, g, lam, linear_solver))
    if ratio is None or not abs(ratio) < TURN_HINT:
        return None
    return (f"the smallest eigenvalue of the tangent with the prescribed motion held has fallen to {ratio:.3g} of "
            f"its initial value at load factor {lam:.6g}: the equilibrium under the prescribed motion is about to "
            "turn back (a snap-back in the prescribed displacement), which load stepping cannot pass; trace it "
            "with arc length under a load (core_se3.solvers.arc_length, stop_at) or prescribe another displacement")


def _smallest_eigenvalue(problem, g, lam, linear_solver=None):
    """The smallest eigenvalue of the tangent on the free dofs at (g, lam)
    (:func:`smallest_mode`), or None when it cannot be found."""
    try:
        K = problem.tangent(np.asarray(g, float), lam)
        with Factorization(K, make_solver(linear_solver or problem.linear_solver)) as fac:
            return smallest_mode(K, fac)[0]
    except (CoreSE3Error, FloatingPointError, ValueError):
        return None


def _ratio(mu0, mu1):
    """mu1 / mu0 (inf for mu0 = 0), or None when either is unknown."""
    if mu0 is None or mu1 is None:
        return None
    return mu1 / mu0 if mu0 != 0 else np.inf


def contact_loads(problem):
    """The problem's loads with a multiplier state (contact: ``Load.update_multipliers``),
    which path following refuses (``ShellSystem``)."""
    return [ld for ld in getattr(problem, "loads", ()) if overrides(ld, "update_multipliers")]


def contact_limit_hint(problem, g, lam, linear_solver=None):
    """The limit-point hint of a failed run with contact at its last converged state (g, lam):
    the smallest eigenvalue of the tangent (:func:`smallest_mode`) with the contact's active set
    and multipliers held at that state's, over its value at the reference state (the contact at
    its cold start there).  Under load control the path turns where this tangent is singular: a
    limit point of the loads (a contact-stiffened roof), or a turn of the path of a shell driven
    by a moving obstacle (a snap-back).  Below ``TURN_HINT`` (negative: an unstable state) the
    message says so; else None.  Path following, the remedy for a shell alone
    (:func:`limit_point_hint`, whose ``ShellSystem`` refuses contact), does not take contact:
    the 8x8 hinged roof of Sze s3.8(a) propped by a ball under its free edge stopped at load
    factor 0.8068 with "no convergence" and no cause (alone its limit point is at 0.7436).

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    >>> p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 1.0))
    >>> c = p.add_obstacle("sphere", centre=(5.0, 0.5, -20.0), radius=1.0)
    >>> contact_limit_hint(p, p.mesh.g0, 0.5) is None                # as stiff as at the start
    True
    """
    loads = contact_loads(problem)
    held = [ld.multipliers() for ld in loads]
    try:
        for ld in loads:
            ld.set_multipliers(None)
        mu0 = _smallest_eigenvalue(problem, problem.mesh.g0, 0.0, linear_solver)
        for ld, m in zip(loads, held):
            ld.set_multipliers(m)
        ratio = _ratio(mu0, _smallest_eigenvalue(problem, g, lam, linear_solver))
    finally:
        for ld, m in zip(loads, held):
            ld.set_multipliers(m)
    if ratio is None or not ratio < TURN_HINT:
        return None
    return (f"the smallest eigenvalue of the tangent at load factor {lam:.6g}, with the contact held as it is there "
            f"(its active set and multipliers), has fallen to {ratio:.3g} of its initial value: the equilibrium path "
            "turns there (a limit point of the load, or a snap-back of a shell driven by a moving obstacle), and "
            "load stepping cannot pass it; arc length and displacement control do not take contact: end the load "
            "below this load factor, or drive the shell by a prescribed displacement whose path does not turn")


def negative_count(problem, g, lam, asym_tol=ASYM_TOL):
    """The number of negative eigenvalues of sym K at the state (g, lam) on the free dofs, or
    None when it says nothing of stability or cannot be counted: K not symmetric to
    ``asym_tol`` (:func:`asymmetry`: non-conservative loads) or the count not available
    (:func:`inertia`).  One tangent assembly and one symmetric factorisation.

    Example
    -------
    >>> from core_se3 import Problem, Material, mesh
    >>> p = Problem(mesh.rectangle(1.0, 0.2, 2, 1), Material(1e3, 0.0, 0.02))
    >>> p.clamp("x0")
    >>> negative_count(p, p.mesh.g0, 0.0)
    0
    """
    if conservative_loads(problem.loads) is False:      # by the loads' kinds, however small K's skew part
        return None
    K = problem.tangent(g, lam)
    if abs(K).max() == 0 or asymmetry(K, problem.assembler().free) > asym_tol:
        return None
    return inertia(K)[1]


def unseen_crossing(problem, steps, count=None):
    """Load factors (lo, hi) and counts (n_lo, n_hi) of the first stored step over which the
    number of negative eigenvalues of sym K rose, when the last stored state has more than the
    first; None when it has not (or cannot be counted).

    The sign of det K, checked at every step, misses an even number of eigenvalues crossing
    zero within one step; this count at the end of a load-stepped solve sees them (one
    factorisation when the end state is stable, as most are; a bisection over the stored
    states, log2 of their number more, when it is not).  ``steps``: StepResults with ``g`` and
    ``load_factor``, the first the start; ``count(g, lam)``: the count at a state (default
    :func:`negative_count` of ``problem``; a distributed run's counts on its ranks).
    """
    stored = [s for s in steps if getattr(s, "g", None) is not None]
    if len(stored) < 2:
        return None
    counted = {}

    def n(i):
        if i not in counted:
            counted[i] = (count or partial(negative_count, problem))(stored[i].g, stored[i].load_factor)
        return counted[i]

    last = len(stored) - 1
    if not n(last) or n(0) is None or n(last) is None or n(last) <= n(0):
        return None
    lo, hi = 0, last                       # n(lo) <= n(0) < n(hi): bisect over the stored states
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if n(mid) is None:
            break
        lo, hi = (mid, hi) if n(mid) <= n(0) else (lo, mid)
    return (stored[lo].load_factor, stored[hi].load_factor), (n(lo), n(hi))

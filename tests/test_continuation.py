"""Path following (issue 6, item 1): arc length, displacement control, limit and bifurcation
detection, branch switching, and the load-control failure message.

Exact references: two algebraic systems with closed-form paths (below), and the shell
benchmark of Sze et al. (2004) s3.8(a), core_se3/data/literature.json ``sze3.8a_hinged_roof``
(its curve bars are in tests/test_sze_roof.py).

* cubic snap-through: f(u) = u - 3/2 u^2 + 1/2 u^3 = lam; limit points where f'(u) = 0,
  u = 1 -+ 1/sqrt 3, lam = +-1/(3 sqrt 3) = +-0.19245;
* pitchfork from V = u^2/2 + v^2 (1 - u)/2 + v^4/4 under load lam on u: primary path v = 0,
  u = lam, bifurcation at lam = 1; secondary path u = 1 + v^2, lam = 1 + v^2/2.
"""
import numpy as np
import pytest
import scipy.sparse as sp

from core_se3 import catalogue, solvers as C
from core_se3.catalogue import get_case
from core_se3.errors import ConvergenceError, CoreSE3Error, OptionError

LAM_LIMIT = 1 / (3 * np.sqrt(3))


def cubic():
    f = lambda u: np.array([u[0] - 1.5 * u[0] ** 2 + 0.5 * u[0] ** 3])
    jac = lambda u: np.array([[1 - 3 * u[0] + 1.5 * u[0] ** 2]])
    return C.AlgebraicSystem(f, jac, [1.0]), f


def pitchfork():
    f = lambda x: np.array([x[0] - 0.5 * x[1] ** 2, x[1] * (1 - x[0]) + x[1] ** 3])
    jac = lambda x: np.array([[1.0, -x[1]], [-x[1], 1 - x[0] + 3 * x[1] ** 2]])
    return C.AlgebraicSystem(f, jac, [1.0, 0.0])


@pytest.mark.parametrize("method", ["crisfield", "riks"])
def test_cubic_snap_through_traced_through_both_limit_points(method):
    """Arc length passes both limit points of the cubic (lam rises, falls below zero, rises
    again) to u = 3, where the last step lands exactly (displacement control).  Every point is
    an equilibrium to round-off; the limit points are detected with the right sign change and
    located within 1 % of +-0.19245 (parabolic interpolation across a step: measured 0.14 % and
    0.33 %, crisfield)."""
    sysm, f = cubic()
    pts, crit, log, _ = C.path_follow(sysm, method=method, lam_end=None, dlam0=0.02, psi=1.0,
                                      control=(lambda u: u[0], lambda u: np.array([1.0])),
                                      control_end=3.0)
    u = np.array([p.state[0] for p in pts])
    lam = np.array([p.lam for p in pts])
    assert np.all(np.diff(u) > 0)                        # the path is monotone in u
    assert abs(u[-1] - 3.0) < 1e-12 and abs(lam[-1] - f([3.0])[0]) < 1e-12
    assert np.abs(lam - np.array([f([x])[0] for x in u])).max() < 1e-12
    mid = u < 1.9                                        # before the last rising branch
    assert lam[mid].max() < LAM_LIMIT + 1e-12 and lam.min() > -LAM_LIMIT - 1e-12
    assert lam.max() > 0.9 * LAM_LIMIT                   # it did climb to the limit
    assert [c.kind for c in crit] == ["limit", "limit"]
    assert [c.negative_eigenvalues for c in crit] == [(0, 1), (1, 0)]
    assert abs(crit[0].lam - LAM_LIMIT) < 0.01 * LAM_LIMIT
    assert abs(crit[1].lam + LAM_LIMIT) < 0.01 * LAM_LIMIT
    for c in crit:                                       # bracketed by the two steps
        assert min(c.lam_bracket) - 0.01 <= c.lam <= max(c.lam_bracket) + 0.01 * LAM_LIMIT + 0.05


def test_cubic_displacement_control_is_exact():
    """Displacement control of u through the whole cubic: lam = f(u) at every target."""
    sysm, f = cubic()
    # displacement_control takes a Problem; the bordered corrector it uses is path_follow's
    pts, crit, log, _ = C.path_follow(sysm, method="crisfield", lam_end=None, dlam0=0.05,
                                      control=(lambda u: u[0], lambda u: np.array([1.0])),
                                      control_end=2.5)
    for p in pts:
        assert abs(p.lam - f(p.state)[0]) < 1e-12


def test_pitchfork_detected_and_branch_switch():
    """The primary path crosses the bifurcation at lam = 1 (eigenvalue 1 - lam, so the
    eigenvalue interpolation is exact); q . t keeps its sign, so it is classed a bifurcation.
    Without switching the path stays on v = 0; with branch_switch the next steps lie on the
    secondary path lam = 1 + v^2/2, u = 1 + v^2 (to 1e-12) and are stable again."""
    pts, crit, _, _ = C.path_follow(pitchfork(), method="crisfield", lam_end=1.6, dlam0=0.15)
    assert [c.kind for c in crit] == ["bifurcation"]
    assert abs(crit[0].lam - 1.0) < 1e-10
    assert all(abs(p.state[1]) < 1e-14 for p in pts)
    assert pts[-1].n_neg == 1                             # primary path unstable past lam = 1
    pts, crit, _, _ = C.path_follow(pitchfork(), method="crisfield", lam_end=1.6, dlam0=0.15,
                                    branch_switch=True)
    assert [c.kind for c in crit] == ["bifurcation"]
    after = [p for p in pts if p.lam > 1.0 and abs(p.state[1]) > 0.1]
    assert len(after) >= 2 and abs(pts[-1].lam - 1.6) < 1e-12
    for p in after:
        u, v = p.state
        assert abs(p.lam - 1 - 0.5 * v * v) < 1e-12 and abs(u - 1 - v * v) < 1e-12
        assert p.n_neg == 0


def test_inertia_counts_negative_eigenvalues():
    """Sparse inertia (SuperLU, symmetric ordering) equals the count of negative eigenvalues
    of a random symmetric indefinite matrix (dense eigvalsh), and the determinant's sign."""
    rng = np.random.default_rng(3)
    n = 60
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    for k in (0, 1, 3):
        ev = np.r_[-np.linspace(1, 2, k), np.linspace(0.5, 3, n - k)]
        A = (Q * ev) @ Q.T
        sign, neg = C.inertia(sp.csr_matrix(A))
        assert sign == (-1) ** k
        assert neg in (k, None)
        assert C.inertia(A) == ((-1) ** k, k)


@pytest.mark.parametrize("shift_index", [0, 1, 6])
def test_inertia_of_large_matrices_matches_the_analytic_count(shift_index):
    """From AUTO_MUMPS_MIN unknowns the inertia comes from MUMPS' LDL^T (petsc4py), else from
    SuperLU: both must count the negative eigenvalues of a shifted 1-D Laplacian exactly
    (eigenvalues 2 - 2 cos(k pi / (n + 1)), the shift halfway between two of them), with the
    determinant's sign (-1)^count."""
    from core_se3.solvers.linalg import AUTO_MUMPS_MIN
    n = AUTO_MUMPS_MIN + 100
    lam = 2 - 2 * np.cos(np.arange(1, n + 1) * np.pi / (n + 1))
    shift = 0.5 * (lam[shift_index] + lam[shift_index + 1]) if shift_index else 0.5 * lam[0]
    K = (sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n)) - shift * sp.eye(n)).tocsr()
    k = int(np.sum(lam < shift))
    assert k == (shift_index + 1 if shift_index else 0)
    assert C.inertia(K) == ((-1) ** k, k)


# ------------------------------------------------------------------ shell ---------------

@pytest.fixture(scope="module")
def roof8():
    case = get_case("sze-hinged-roof")
    return case, catalogue.case_params(case)


def test_roof_arc_length_equals_displacement_control(roof8):
    """Hinged roof 8x8 quarter: displacement control of -W_C through the deflections that arc
    length reached gives the same load factors there (both are converged to 1e-9 on the same
    equations: bar 1e-6), and both find the same two limit points (within 1e-2 in P/P_max:
    different brackets)."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    arc = C.arc_length(prob, lam_end=None, dlam0=0.05, stop_at=(node, d, 28.0))
    w = np.array([-s.probes["C"]["u"][2] for s in arc.steps])
    lam = np.array([s.load_factor for s in arc.steps])
    assert np.all(np.diff(w) > 0) and abs(w[-1] - 28.0) < 1e-9
    assert lam[w < 12].max() > 0.74 and lam[(w > 12) & (w < 22)].min() < 0.2   # it snapped through
    prob2 = catalogue.build_problem(case, p, (8, 8))
    dc = C.displacement_control(prob2, node, d, w[1:])
    w2 = np.array([-s.probes["C"]["u"][2] for s in dc.steps[1:]])
    lam2 = np.array([s.load_factor for s in dc.steps[1:]])
    assert np.abs(w2 - w[1:]).max() < 1e-9
    assert np.abs(lam[1:] - lam2).max() < 1e-6
    assert [c.kind for c in arc.critical_points] == ["limit", "limit"]
    assert [c.kind for c in dc.critical_points] == ["limit", "limit"]
    for c1, c2 in zip(arc.critical_points, dc.critical_points):
        assert abs(c1.lam - c2.lam) < 1e-2
    # every step is an equilibrium whose reactions balance the load
    assert max(s.balance_error for s in arc.steps) < 1e-8


def test_roof_bordered_newton_converges_quadratically(roof8):
    """Within every arc-length step of the roof the residual falls quadratically once it is
    below 1e-3: r_{k+1} <= 100 r_k^2 (or hits the round-off floor 1e-9; measured constant up to
    10.2).  A linearly converging corrector (inconsistent tangent or load direction) with even a
    0.01 rate would give r_{k+1} = 1e-7 from 1e-5, 100x over this bar."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    res = C.arc_length(prob, lam_end=None, dlam0=0.05, stop_at=(node, d, 29.374))
    checked = 0
    for st in res.steps[1:]:
        h = st.residual_history
        for a, b in zip(h[:-1], h[1:]):
            if 1e-8 < a < 1e-3:
                assert b <= max(100 * a * a, 1e-9), h
                checked += 1
    assert checked >= 10
    assert max(st.iterations for st in res.steps[1:]) <= 6


def test_load_control_past_limit_point_fails_suggesting_arc_length(roof8):
    """Load control of the roof to P_max in 20 steps snaps through the limit point near
    P/P_max = 0.742 (on to the far stable branch): newton_solve stops with a ConvergenceError
    that names the limit point and suggests arc length, keeping the steps up to 0.7."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (8, 8))
    with pytest.raises(ConvergenceError) as exc:
        prob.solve(steps=20)
    msg = str(exc.value)
    assert "limit point" in msg and "arc length" in msg
    lams = [s.load_factor for s in exc.value.result.steps]
    assert abs(lams[-1] - 0.7) < 1e-12 and len(lams) == 15


def test_bad_input(roof8):
    """Path following refuses the stateful seed element and lam-dependent prescribed motions;
    a step that cannot converge (max_iter = 0) is rejected ds/2 at a time and the error keeps
    the converged steps (the initial state)."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (4, 4), element="seed")
    with pytest.raises(CoreSE3Error, match="path-independent"):
        C.arc_length(prob)
    prob = catalogue.build_problem(get_case("torsion"), catalogue.case_params(get_case("torsion")), (4, 2))
    with pytest.raises(CoreSE3Error, match="prescribed motion"):
        C.arc_length(prob)
    prob = catalogue.build_problem(case, p, (4, 4))
    with pytest.raises(ConvergenceError) as exc:
        C.arc_length(prob, max_iter=0)
    assert "rejections" in str(exc.value)
    assert len(exc.value.result.steps) == 1


def test_limit_point_hint_on_the_failure_path(roof8):
    """The message added when load control exhausts its cut-backs: at the roof's state with
    -W_C = 10 (just before the limit point, P/P_max = 0.74) the current stiffness parameter
    S_p = q.t_0 / q.t is below 0.3 and the hint suggests arc length; at -W_C = 2 (S_p ~ 0.9)
    there is no hint."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    dc = C.displacement_control(prob, node, d, [2.0, 10.0])
    near, early = dc.steps[2], dc.steps[1]
    msg = C.limit_point_hint(prob, near.g, near.load_factor)
    assert msg is not None and "arc length" in msg and "limit point" in msg
    assert C.limit_point_hint(prob, early.g, early.load_factor) is None


def test_a_far_too_long_first_step_is_retried_shorter_not_taken_onto_another_branch():
    """A very slender cantilever (1 x 0.2, E = 1e3, h = 0.01: P L^2 / EI = 6e4 at lam = 1) with
    dlam0 = 0.05: the first arc lengths are several strip lengths long.  Found in a stress run:
    the halved step converged on the sphere at lam = -1.8e-4 with the tip at u = (-1.18, 0, 0.47)
    -- folded back past the clamp, against the load, an unstable state (one negative
    eigenvalue) of another branch.  The first step of a path starts on the stable branch through
    the unloaded state, so its load factor must move the way the predictor asked: now such a
    step is rejected and halved until it follows the load (lam > 0, tip displaced along +z, the
    tangent positive definite)."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e3, 0.0, 0.01))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0))
    p.add_probe("tip", "x1")
    it = C.arc_length_steps(p, dlam0=0.05)
    next(it)                                              # the initial state
    first = next(it).step
    assert first.load_factor > 0.0
    assert first.probes["tip"]["u"][2] > 0.0
    assert first.stability["negative_eigenvalues"] == 0


@pytest.fixture(scope="module")
def roof635():
    case = get_case("sze-hinged-roof-6.35")
    return case, catalogue.case_params(case)


def test_displacement_control_stops_at_a_snap_back_of_the_controlled_displacement(roof635):
    """The 6.35 mm roof (8x8 quarter) snaps back in W_C: along the path W_C reverses near 16.94
    (table 17.008) and turns forward again near 14.5 (table 14.451), so W_C between them has
    three equilibria and displacement control cannot pass the reversal continuously.  Found:
    displacement control through -W_C = 1, 2, ..., 38 converged at 17 (16 iterations, corrections
    grown 11x) at load factor -0.126 on the far side of the loop (0.073 at 16.75), exit normal,
    and reported a limit point at lam ~ -0.036 that the path does not have (arc length: the
    lower limit point is at -0.1278).  Now such a step is refused by the path check and, the
    cut-backs exhausted at the reversal, the run stops naming the snap-back and arc length; the
    steps kept lie on the path before the reversal (load factor positive, -W_C below 17.008)
    with the upper limit point only (0.1969, arc length's 0.19693)."""
    case, p = roof635
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    with pytest.raises(ConvergenceError) as exc:
        C.displacement_control(prob, node, d, np.arange(1.0, 39.0))
    msg = str(exc.value)
    assert "snap-back" in msg and "arc length" in msg, msg
    res = exc.value.result
    w = np.array([-s.probes["C"]["u"][2] for s in res.steps])
    lam = np.array([s.load_factor for s in res.steps])
    assert w.max() < 17.008 and w[-1] >= 16.0
    assert lam[1:].min() > 0.0
    assert [c.kind for c in res.critical_points] == ["limit"]
    assert abs(res.critical_points[0].lam - 0.19693) < 1e-3


@pytest.mark.parametrize("method", ["crisfield", "riks"])
def test_limit_point_refinement_stays_on_the_bracketed_part_of_the_path(roof635, method):
    """The 6.35 mm roof's lower limit point from a long first step (dlam0 = 0.5): refined to
    critical_tol = 1e-3 it must agree with its value on a fine path (dlam0 = 0.01, ds_max_factor
    1: lam = -0.127783 +- 2e-6) within 1e-3 (plus the reference's 2e-6), and within the accuracy
    it states.  Found: with Riks the bisection's midpoint of the step over the limit point
    (between load factors -0.064 and -0.102) converged on another part of the path, at
    lam = 0.522, was kept as a bracket end, and the point was reported at -0.0643 +- 0.018 (off
    by 0.063); with Crisfield a midpoint at -0.089 (above both ends, so not on the step's part of
    the path) was kept too.  Now such points are refused and the bisection predicts from the
    bracket's nearer end: -0.12775 (Riks) and -0.12777 (Crisfield)."""
    case, p = roof635
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    res = C.arc_length(prob, lam_end=None, dlam0=0.5, method=method, stop_at=(node, d, 38.45))
    cps = [c for c in res.critical_points if c.kind == "limit"]
    assert len(cps) == 2
    ref = -0.127783
    low = cps[1]
    assert abs(low.lam - ref) <= 1e-3 * abs(ref) + 2e-6, low.describe()
    assert abs(low.lam - ref) <= low.accuracy * abs(low.lam) + 2e-6, low.describe()
    assert low.accuracy <= 1e-3
    assert abs(max(low.lam_bracket) - ref) < 0.01          # the bracket narrowed onto it


@pytest.mark.parametrize("method", ["crisfield", "riks"])
def test_arc_length_stops_where_the_path_first_reaches_lam_end(roof8, method):
    """lam_end = 0.74 lies just below the roof's upper limit point (0.7436, 8x8 quarter), so the
    path first reaches it before the snap, at -W_C = 10.145 (dlam0 = 0.05, steps well inside the
    rise), and again on the far branch.  Found: from dlam0 = 0.2, 0.5 and 1.0 a step went over the
    limit point with both ends below 0.74 and the path stopped at the far crossing, -W_C = 27.08
    (0.2, 0.5), or landed from a step that ended past the turn at 11.43, on the descending side
    (1.0): the final state depended on the first step.  Now a step over which the load factor
    turned back with its tangent lines meeting above lam_end (or that reached lam_end past the
    turn) is retried shorter: every first step ends at the same state (bar 1e-8: both are
    converged to 1e-9)."""
    case, p = roof8
    w = []
    for dlam0 in (0.05, 0.5, 1.0):
        prob = catalogue.build_problem(case, p, (8, 8))
        res = C.arc_length(prob, lam_end=0.74, dlam0=dlam0, method=method)
        assert abs(res.final.load_factor - 0.74) < 1e-12
        assert res.final.stability["negative_eigenvalues"] == 0
        w.append(-res.final.probes["C"]["u"][2])
    assert 10.0 < w[0] < 10.3, w
    assert np.abs(np.array(w) - w[0]).max() < 1e-8 * w[0], w


@pytest.mark.parametrize("dlam0", [0.2, 0.5])
def test_arc_length_stops_where_the_controlled_displacement_first_reaches_its_end(roof635, dlam0):
    """The 6.35 mm roof's W_C turns back near 16.94 (snap-back) and reaches 16.9 three times
    along the path.  stop_at -W_C = 16.9 must end at the first, on the rising part of W_C at
    load factor 0.04533 (dlam0 = 0.05, steps that resolve the turn), not on the far side of the
    loop.  Found: from dlam0 = 0.2 and 0.5 (Riks and Crisfield) a step went over the turn with
    both ends below 16.9 and the path stopped at the third crossing, load factor -0.12668."""
    case, p = roof635
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    res = C.arc_length(prob, lam_end=None, dlam0=dlam0, method="riks", stop_at=(node, d, 16.9))
    w = np.array([-s.probes["C"]["u"][2] for s in res.steps])
    assert abs(w[-1] - 16.9) < 1e-9
    assert np.all(np.diff(w) > 0)                   # W_C never turned back on the way
    assert abs(res.final.load_factor - 0.04533) < 1e-4, res.final.load_factor


def test_displacement_control_without_its_node_direction_or_values_names_them():
    """Problem.solve(control='displacement') without node / direction / values was a bare
    TypeError ('displacement_control() missing 3 required positional arguments'), and a misspelt
    node= ('nod') was reported as node missing without the misspelling.  Now an OptionError names
    the missing keys, a misspelling's correction and an example call."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0))
    for kw, missing in ((dict(), "node, direction, values"), (dict(node=3), "direction, values"),
                        (dict(node=3, direction=(0, 0, 1)), "values")):
        with pytest.raises(OptionError, match=f"displacement control: missing {missing}.  Give the controlled node"):
            p.solve(control="displacement", **kw)
    with pytest.raises(OptionError, match="missing node; unknown keyword 'nod'; did you mean 'node'"):
        p.solve(control="displacement", nod=3, direction=(0, 0, 1), values=[0.1])
    res = p.solve(control="displacement", node=3, direction=(0, 0, 1), values=[0.5])   # given: solved
    assert abs(res.final.g[3, 2, 3] - 0.5) < 1e-9

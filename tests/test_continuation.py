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
import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from core_se3 import catalogue, solvers as C
from core_se3.catalogue import get_case
from core_se3.errors import ConvergenceError, CoreSE3Error, OptionError, PathWarning

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


@pytest.mark.parametrize("method", ["crisfield", "riks"])
@pytest.mark.parametrize("dlam0", [2.0, 3.0, 5.0])
def test_two_limit_points_within_one_step_are_found(method, dlam0):
    """The cubic from a first step so long that it reaches the last rising branch (dlam0 = 2:
    u = 0 -> 2.58; 3 and 5: straight to u = 3): the load factor rose, fell to -0.19245 and rose
    again inside the step, both ends stable (0 negative eigenvalues) and rising, so no count
    changed.  Found: the path ended at u = 3 and reported no critical point.  Now the step whose
    rise is too small for its end slopes (critical.hidden_turns) is retried shorter and both
    limit points are located to critical_tol (the exact +-1/(3 sqrt 3); bar 1e-3 and the
    accuracy each states)."""
    sysm, f = cubic()
    pts, crit, log, _ = C.path_follow(sysm, method=method, lam_end=None, dlam0=dlam0, psi=1.0,
                                      control=(lambda u: u[0], lambda u: np.array([1.0])),
                                      control_end=3.0)
    assert abs(pts[-1].state[0] - 3.0) < 1e-12
    assert [c.kind for c in crit] == ["limit", "limit"], [c.describe() for c in crit]
    for c, exact in zip(crit, (LAM_LIMIT, -LAM_LIMIT)):
        assert abs(c.lam - exact) <= 1e-3 * LAM_LIMIT, c.describe()
        assert abs(c.lam - exact) <= c.accuracy * abs(c.lam) + 1e-12, c.describe()
    assert any("turned twice" in e["reason"] for e in log if e.get("reason"))


@pytest.mark.parametrize("dlam0", [0.1, 0.15])
def test_a_step_with_a_load_term_does_not_jump_back_over_the_loop(dlam0):
    """Riks with psi = 3 on the cubic: past the upper limit point, on the way down to the lower
    one (u = 1.45, lam = -0.18), a step converged at u = -1.1, lam = -3.6 -- back across the
    whole loop, onto the curve below the start: its displacement ran against the predictor's
    and only the load term, which dominates at psi = 3, kept the increment's projection positive.
    Found: the path ran on to lam = -162 (-243) until max_steps, never reaching u = 3, and
    reported a 'bifurcation' at -0.270 (-0.251) of a one-dof system.  Now the displacement part
    must not turn back either (the path-reversal check of psi = 0, with the load term): the path
    ends at u = 3 with both limit points at +-0.19245 (1e-3), u never below its start."""
    sysm, f = cubic()
    pts, crit, _, _ = C.path_follow(sysm, method="riks", lam_end=None, dlam0=dlam0, psi=3.0,
                                    control=(lambda u: u[0], lambda u: np.array([1.0])), control_end=3.0)
    u = np.array([p.state[0] for p in pts])
    assert abs(u[-1] - 3.0) < 1e-12 and u.min() >= 0.0
    assert [c.kind for c in crit] == ["limit", "limit"], [c.describe() for c in crit]
    for c, exact in zip(crit, (LAM_LIMIT, -LAM_LIMIT)):
        assert abs(c.lam - exact) <= 1e-3 * LAM_LIMIT, c.describe()


def test_a_non_conservative_load_reports_no_critical_point_where_k_is_regular():
    """Beck's column: a cantilever strip (10 x 1 x 0.1, EI = 100) under a compressive follower end
    force 15 EI/L^2, below its flutter load 20.05 EI/L^2; it has no static instability (K stays
    regular along the straight path: its smallest |eigenvalue| grows from 0.027 to 0.115).
    Found: 'bifurcation point at lam = 0.65918 +- 0.0002', where an eigenvalue of sym(K) -- which
    says nothing of stability with a non-symmetric K -- passed zero.  Now a non-symmetric tangent
    (stability.stability_of) is judged by the sign of det K itself: no critical point."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(10.0, 1.0, 20, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (-15.0, 0.0, 0.0), follower=True)
    res = C.arc_length(p, lam_end=1.0, dlam0=0.1)
    assert res.final.load_factor == 1.0
    assert res.critical_points == []
    assert all(st.stability["det_sign"] == 1 for st in res.steps)


def test_a_limit_point_of_a_non_symmetric_system_is_where_det_k_vanishes():
    """r = (u - 3/2 u^2 + 1/2 u^3 + c v, v - d u) - lam (1, 0), c = 0.5, d = -0.2: K is not
    symmetric, the path v = d u has lam = (1 + c d) u - 3/2 u^2 + 1/2 u^3 with limit points where
    det K = 0, +0.1529822 and -0.3529822 (sym K is singular elsewhere); both are found within
    critical_tol and the accuracy each states (main, by sym K's inertia: 0.152906 +- 1.3e-4)."""
    c, d = 0.5, -0.2
    f = lambda x: np.array([x[0] - 1.5 * x[0] ** 2 + 0.5 * x[0] ** 3 + c * x[1], x[1] - d * x[0]])
    jac = lambda x: np.array([[1 - 3 * x[0] + 1.5 * x[0] ** 2, c], [-d, 1.0]])
    us = 1 + np.array([-1.0, 1.0]) * np.sqrt(1 - 2 * (1 + c * d) / 3)
    exact = (1 + c * d) * us - 1.5 * us ** 2 + 0.5 * us ** 3
    pts, crit, _, _ = C.path_follow(C.AlgebraicSystem(f, jac, [1.0, 0.0]), lam_end=None, dlam0=0.02, psi=1.0,
                                    control=(lambda x: x[0], lambda x: np.array([1.0, 0.0])), control_end=3.0)
    assert [cp.kind for cp in crit] == ["limit", "limit"]
    for cp, ex in zip(crit, exact):
        assert abs(cp.lam - ex) <= min(1e-3, cp.accuracy) * abs(ex) + 1e-12, cp.describe()


@pytest.mark.parametrize("method", ["crisfield", "riks"])
@pytest.mark.parametrize("lam_end, u_first", [(0.1, 0.12111493375002719), (0.19, 0.3702470653010267)])
def test_lam_end_is_met_where_the_path_first_reaches_it_past_two_hidden_turns(method, lam_end, u_first):
    """The cubic to lam_end = 0.1 (0.19), first reached at u = 0.1211 (0.3702), before the upper
    limit point, from dlam0 = 2 (psi = 0): the first step went over both limit points to
    u = 2.09 (2.15) and landed there on the last crossing -- both ends rising, so the test of a
    step that passed the end and turned back saw no turn.  Now the step that may have turned twice
    is halved and the path ends on the first crossing (bar 1e-9: converged to 1e-12)."""
    sysm, f = cubic()
    pts, _, _, _ = C.path_follow(sysm, method=method, lam_end=lam_end, dlam0=2.0, psi=0.0)
    assert abs(pts[-1].lam - lam_end) < 1e-12
    assert abs(pts[-1].state[0] - u_first) < 1e-9, pts[-1].state


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


def _strip():
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0))
    return p


@pytest.mark.parametrize("kw, match", [
    (dict(dlam0=0.0), "dlam0 must be a finite non-zero number"),
    (dict(dlam0=float("nan")), "dlam0 must be a finite non-zero number"),
    (dict(dlam0="0.1"), "dlam0 must be a finite non-zero number"),
    (dict(dlam0=-0.1), "away from lam_end"),
    (dict(ds_max=-1.0), "ds_max must be None or a finite arc length > 0"),
    (dict(ds_min=float("nan")), "ds_min must be None or a finite arc length > 0"),
    (dict(ds_min=2.0, ds_max=1.0), "ds_min = 2.0 exceeds ds_max = 1.0"),
    (dict(ds_max=1e-6), "ds_max = 1e-06 does not admit the first arc length"),
    (dict(ds_min=10.0), "ds_min = 10 does not admit the first arc length"),
    (dict(max_steps=2.5), "max_steps must be a whole number"),
    (dict(critical_tol=float("nan")), "critical_tol must be"),         # refused before too
])
def test_arc_length_refuses_bad_controls_naming_the_key(kw, match):
    """Arc-length controls that cannot mean what they say are refused with an OptionError naming
    the key.  Found (lam_end = 1 on a cantilever strip): dlam0 = 0 failed after 13 rejections as a
    'path reversal', NaN as a load's NaN scale, '0.1' with a bare TypeError; dlam0 = -0.1 traced
    200 steps away from lam_end, to lam = -5.3e6, and ds_max = -1 turned every step after the
    first back (200 steps, to -0.38), both returned without a word; ds_max = 1e-6 under the
    first arc length (0.64) ended after 200 steps at lam = 0.05; a NaN or too large ds_min and
    max_steps = 2.5 (3 steps) were taken."""
    with pytest.raises(OptionError, match=match):
        C.arc_length(_strip(), lam_end=1.0, **kw)


@pytest.mark.parametrize("node, direction, values, match", [
    (-1, (0.0, 0.0, 1.0), [1.0], "controlled node must be a node number in \\[0, 9\\], got -1"),
    (10 ** 6, (0.0, 0.0, 1.0), [1.0], "controlled node must be a node number"),
    (2.5, (0.0, 0.0, 1.0), [1.0], "controlled node must be a node number"),
    (None, (0.0, 0.0, 0.0), [1.0], "controlled direction must be 3 finite lab components"),
    (None, (0.0, 0.0, float("nan")), [1.0], "controlled direction must be 3 finite lab components"),
    (None, (0.0, 1.0), [1.0], "controlled direction must be 3 finite lab components"),
    (None, (0.0, 0.0, 1.0), [float("nan")], "values must be finite numbers"),
    (None, (0.0, 0.0, 1.0), "abc", "values must be finite numbers"),
])
def test_displacement_control_refuses_a_bad_node_direction_or_value(node, direction, values, match):
    """Found: node -1 controlled the last node without a word; 10**6 and 2.5 failed with a bare
    IndexError, a 2-component direction with a bare matmul ValueError, 'abc' with a bare
    ValueError; a zero or NaN direction and a NaN value surfaced as "load 'edge force': its
    scale(lam) is nan", naming a load that is fine.  Now OptionError names what is wrong."""
    p = _strip()
    node = int(p.mesh.node_set("x1")[0]) if node is None else node
    with pytest.raises(OptionError, match=match):
        C.displacement_control(p, node, direction, values)


@pytest.mark.parametrize("direction, value", [((0.0, 0.0, 0.0), 1.0), ((0.0, 0.0, 1.0), float("nan"))])
def test_arc_length_refuses_a_stop_at_it_could_never_reach(direction, value):
    """stop_at with a zero direction or a NaN value never stopped the path (it ran to max_steps
    and returned); now OptionError."""
    p = _strip()
    with pytest.raises(OptionError, match="controlled direction|stop_at's value"):
        C.arc_length(p, lam_end=None, stop_at=(int(p.mesh.node_set("x1")[0]), direction, value), max_steps=5)


def test_arc_length_warns_when_its_steps_run_out_short_of_its_end():
    """A path that stops after max_steps short of lam_end says so (PathWarning), naming where it
    stopped; one that reaches lam_end does not."""
    with pytest.warns(PathWarning, match="max_steps = 2 points at load factor 0.1146"):
        res = C.arc_length(_strip(), lam_end=1.0, dlam0=0.05, max_steps=2)
    assert len(res.steps) == 3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert C.arc_length(_strip(), lam_end=1.0, dlam0=0.5).final.load_factor == 1.0


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


@pytest.mark.parametrize("values", [[15.0, 18.0], [16.0, 18.5]])
def test_displacement_control_refuses_a_step_whose_critical_point_its_bisection_does_not_close_on(roof635, values):
    """The 6.35 mm roof (8x8 quarter) in one displacement-control step across the snap-back of
    -W_C (it turns back at 16.94): from 15 (load factor 0.184, one negative eigenvalue) to 18 the
    step converged on the far side of the loop (-0.122, none); no point inside it reached the
    lower limit point its ends bracket (0 solves), and the run exited normally, reporting a limit
    point 'near -0.1255 located only to 0.57' (arc length: -0.12778).  From 16 to 18.5 a sub-step
    16.94 -> 17.25 jumped likewise, its bisection closing to 0.51 after 1 solve.  As arc length
    refuses such a step (critical.untraced), displacement control now refuses a step whose
    critical point is not located to critical_tol and halves it: the run stops at the snap-back
    as steps of 1 do, naming it and arc length, with the upper limit point only."""
    case, p = roof635
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    with pytest.raises(ConvergenceError) as exc:
        C.displacement_control(prob, node, d, values)
    msg = str(exc.value)
    assert "snap-back" in msg and "arc length" in msg, msg
    res = exc.value.result
    w = np.array([-s.probes["C"]["u"][2] for s in res.steps])
    assert w.max() < 17.008 and np.all(np.array([s.load_factor for s in res.steps[1:]]) > 0.0)
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


@pytest.mark.parametrize("method", ["crisfield", "riks"])
@pytest.mark.parametrize("psi", [0.0, 1.0])
def test_a_first_step_over_the_snap_through_and_back_finds_both_limit_points(roof8, method, psi):
    """The 8x8 roof of Sze s3.8(a) to -W_C = 29.374 from dlam0 = 5: the first step went from the
    unloaded state over both limit points to the far branch (load factor 0 -> 1.157 (Crisfield),
    2.009 (Riks), 0 negative eigenvalues at both ends) and the run reported none.  Now both are
    found and agree with their values refined to 1e-7 on the path from dlam0 = 0.05 (0.7435513,
    0.1704150) within critical_tol = 1e-3, and state that accuracy; the end state is the same
    (bar 1e-8: converged to 1e-9).  With psi = 1 (Riks) the lower limit point lies in the last
    step, landed on -W_C = 29.374: it was narrowed along the step that overshot, not the landed
    one, and stopped after 40 bisections at a stated accuracy of 1.8e-3 (arclength._land now
    hands the landed step's increments on)."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    res = C.arc_length(prob, lam_end=None, dlam0=5.0, method=method, psi=psi, stop_at=(node, d, 29.374))
    assert [c.kind for c in res.critical_points] == ["limit", "limit"]
    for c, ref in zip(res.critical_points, (0.7435513, 0.1704150)):
        assert abs(c.lam - ref) <= 1e-3 * ref and c.accuracy <= 1e-3, c.describe()
    assert abs(res.final.load_factor - 1.1078501) < 1e-6


@pytest.mark.parametrize("values", [list(np.arange(4.0, 29.0, 4.0)), [25.0, 29.0], [29.0]])
def test_displacement_control_locates_limit_points_to_critical_tol(roof8, values):
    """The 8x8 roof by displacement control of -W_C in steps of 4, in two steps (25, 29) and in
    one: its limit points agree with their values refined to 1e-7 by arc length (0.7435513,
    0.1704150) within critical_tol = 1e-3, and within the accuracy each states.  Found: the
    estimate from the step's ends was kept -- 0.741093 and 0.159700 (3.3e-3 and 6.3e-2 off) from
    steps of 4, and from (25, 29) or one step no critical point at all (the step from 0 to 25
    passes both: 0 negative eigenvalues at its ends).  Now the step is bisected in the controlled
    displacement as arc length bisects its step (critical.narrow), and a step whose load factor
    rises too little for its end slopes is halved (critical.turned_twice)."""
    case, p = roof8
    prob = catalogue.build_problem(case, p, (8, 8))
    node, d = prob.control
    dc = C.displacement_control(prob, node, d, values)
    assert len(dc.steps) == len(values) + 1                  # the requested values only
    assert [c.kind for c in dc.critical_points] == ["limit", "limit"], [c.describe() for c in dc.critical_points]
    for c, ref in zip(dc.critical_points, (0.7435513, 0.1704150)):
        assert abs(c.lam - ref) <= 1e-3 * ref, c.describe()
        assert c.accuracy <= 1e-3 and abs(c.lam - ref) <= c.accuracy * c.lam + 1e-6, c.describe()


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


def test_a_step_whose_interior_no_corrector_reaches_is_refused_not_a_critical_point(tmp_path):
    """The Scordelis-Lo roof 2x2 at R/h 1e4 (a near-mechanism: smallest tangent eigenvalue 0.045
    against 1e8) traced by arc length to 1e-3 of its self-weight: its second step went from lam
    5.2e-5 to an unstable state at -1.4e-5 (det K < 0), was kept, and reported a 'bifurcation
    point near lam = 7.57e-06 located only to 0.64 after 0 solves' -- no point inside the step
    reached it -- then limit points at -1.1e-5, -1.3e-4, 7.5e-4, ... and failed at lam -0.055.
    Load stepping meets no critical point up to 1e-3.  Now such a step is refused and halved
    (its ends lie on two branches): the path reaches 1e-3 with no critical point, at the load-
    stepped state.  With the area loads on the element's own geometry (the self-weight 0.5 %
    heavier) the same step, 5.28e-5 to -1.47e-5, has interior points: all 40 bisections kept the
    start's side, up to 1 - 2^-40 of the step at lam 4.05e-6 and 6.73 (1.35 steps) from its end
    along the chord, and the step was kept as a 'bifurcation near -2.16e-6 located only to 0.64
    after 40 solves', then failed at lam -0.055 (an edge turning by pi); a bisection that runs out
    without closing is now refused too (critical.untraced)."""
    import json
    import warnings
    from core_se3 import scenario
    from core_se3.catalogue import shell_course as sc
    doc = sc.scenario_doc("scordelis-lo", 2, 25.0 / 1e4)
    doc.setdefault("solver", {}).update(control="arclength", lam_end=1e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                       # the coarse thin roof's ElementWarning
        scenario.run(scenario.from_dict(doc), str(tmp_path / "arc"))
        ref = scenario.from_dict(doc).problem.solve(steps=20, lam_end=1e-3)
    res = json.loads(next((tmp_path / "arc").rglob("results.json")).read_text())
    assert res["critical_points"] == []
    assert [s["load_factor"] for s in res["steps"]][-1] == pytest.approx(1e-3, rel=1e-12)
    u_ref = ref.final.probes["A"]["u"]
    u_arc = res["steps"][-1]["probes"]["A"]["u"]
    assert np.abs(np.asarray(u_arc) - u_ref).max() <= 1e-6 * np.abs(u_ref).max()

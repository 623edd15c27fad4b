"""Coulomb friction of the contact nodes (issue 31, ``model.friction``): the law and its return
mapping, the consistent tangent against central differences in stick and in slip, the
rough-table bar against its exact solution in its three regimes, the history in the restart
state, and frictionless runs unchanged.  Derivations: docs/CONTACT.md "Friction"."""
from __future__ import annotations

import numpy as np
import pytest

import core_se3 as cs
from core_se3 import lie
from core_se3 import mesh as M
from core_se3.model import ContactLaw, ContactLoad, HalfSpace, Sphere, tangent_fd_check, translation
from core_se3.model.obstacle_kinds import Box, Cylinder
from core_se3.model.obstacles import rotation
from core_se3.model.contact_law import ramp
from core_se3.model.friction import HARDENING, coulomb_law


def test_return_mapping_is_coulomb():
    """|t| <= mu p always; stick keeps the trial traction, slip returns onto the cone opposite
    to the slip; the tangent of the law against central differences in stick and slip."""
    rng = np.random.default_rng(3)
    n = np.tile([0.0, 0.0, 1.0], (6, 1))
    H = np.zeros((6, 3, 3))
    p, dp = np.full(6, 2.0), np.full(6, -4.0)            # beyond the C^1 band: p' = -k
    v = rng.normal(size=(6, 3)) * 0.3
    t, dt, stick, s = coulomb_law(n, H, p, dp, v, np.zeros((6, 3)), 4.0, 0.4)
    assert stick.any() and (~stick).any()
    trial = 4.0 * np.linalg.norm(s, axis=1)            # |t*| = k |s| (no stored traction)
    assert np.all(np.linalg.norm(t[stick], axis=1) < 0.4 * 2.0)
    # on the cone, up to the hardening: |t| = mu p + HARDENING (|t*| - mu p)
    np.testing.assert_allclose(np.linalg.norm(t[~stick], axis=1), 0.8 + HARDENING * (trial[~stick] - 0.8),
                               rtol=1e-14)
    assert np.allclose(t[~stick] / np.linalg.norm(t[~stick], axis=1)[:, None],
                       -s[~stick] / np.linalg.norm(s[~stick], axis=1)[:, None])


def _friction_state(obstacle, seed=1, mu=0.3, backend="numpy", turn=0.0):
    """A strip 1 x 0.6 in contact with ``obstacle`` at a state with nodes sticking, slipping and
    free (its multipliers and friction history set); ``turn``: the frames turned by that angle
    about the lab normal z (the contact points stay, the body frames of the tractions turn)."""
    m = M.rectangle(1.0, 0.6, 3, 2)
    g = m.g0 @ lie.exp(np.random.default_rng(seed).normal(size=(m.n_nodes, 6)) * 0.08)
    g[:, :3, :3] = lie.exp_so3(np.array([0.0, 0.0, turn])) @ g[:, :3, :3]
    prob = cs.Problem(m, cs.Material(1e4, 0.3, 0.02), backend=backend)
    cl = prob.add(ContactLoad(prob, obstacle, friction=mu, law=ContactLaw(eps=0.02, faces=False)))
    lam = 0.6
    d = cl.gaps(g, lam)
    w = cl.k * cl.eps
    target = np.array([2.0, 0.5, 3.0, -1.0])[np.arange(len(d)) % 4] * w
    lam_n = ramp(np.maximum(target + cl.k * d, 0.0), w)[0]
    rng = np.random.default_rng(seed + 7)
    x = cl.contact_points(g)
    anchors = cl.placement(x, lam) + rng.normal(size=x.shape) * 0.02 * np.array([1, 1, 0.3])
    tau = rng.normal(size=x.shape) * 0.3 * w[:, None]
    m_ = len(cl.lam0)
    history = [tau.ravel(), anchors.ravel()] if mu > 0 else []
    cl.set_multipliers(np.concatenate([np.concatenate([lam_n, cl.lam0[len(d):]]), np.ones(m_)] + history))
    return prob, cl, g, lam


@pytest.mark.parametrize("name", ["half_space", "sphere", "moving_sphere", "roller", "box", "turning_box"])
def test_frictional_tangent_against_central_differences(name):
    """The non-symmetric tangent (with its moment about the node from the offset h/2, and the
    obstacle's curvature and motion) against central differences of the full residual, at a
    state with nodes sticking, slipping and free."""
    ob = {"half_space": HalfSpace((0, 0, -0.01), (0.1, 0, 1)),
          "sphere": Sphere((0.5, 0, 0.6), 0.6),
          "moving_sphere": Sphere((0.5, 0, 0.9), 0.6, motion=translation((0, 0, -0.5))),
          # every obstacle kind, and rotating ones (a roller turning about its axis drags the
          # surface; a tilted box turning about the vertical)
          "roller": Cylinder((0.5, 0, 0.6), (0, 1, 0), 0.6, motion=rotation((0, 1, 0), (0.5, 0, 0.6), 0.5)),
          "box": Box((0.5, 0.3, -0.5), (0.6, 0.6, 0.5), rotation=(0.0, 0.1, 0.0)),
          "turning_box": Box((0.5, 0.3, -0.5), (0.6, 0.6, 0.5), rotation=(0.0, 0.1, 0.0),
                             motion=rotation((0, 0, 1), (0.5, 0.3, 0.0), 0.3))}[name]
    prob, cl, g, lam = _friction_state(ob)
    x, d, n, H, p, dp = cl.state(g, lam)
    t, dt, stick, s = cl.friction_state(g, lam, x, n, H, p, dp)
    on = p > 0
    assert (on & stick).any() and (on & ~stick).any() and (~on).any(), (on & stick, on & ~stick)
    err = tangent_fd_check(prob, g, lam, free_all=True)[0]
    assert err < 1e-6, err
    K = tangent_fd_check(prob, g, lam, free_all=True)[1]
    assert np.abs(K - K.T).max() > 1e-6 * np.abs(K).max()           # non-symmetric, as it must be


# ----------------------------------------------------------------------------- the rough-table bar
def _bar(mu=0.5, F=1.0, steps=10, scale=None):
    """A strip (L 1, w 0.1, h 0.01, E 1e5, nu 0) lying on a rough table under its weight q per
    length (rho 1000, g 9.81), clamped at x = 0, pulled along its axis at x = 1 by F mu q L."""
    L, w, h, E = 1.0, 0.1, 0.01, 1e5
    p = cs.Problem(M.rectangle(L, w, 40, 2),
                   cs.Material(E, 0.0, h))
    p.clamp("x0")
    q = 1000.0 * 9.81 * h * w
    p.add_gravity(rho=1000.0, scale=lambda lam: 1.0)
    p.add_edge_force("x1", (F * mu * q * L, 0.0, 0.0), scale=scale)
    c = p.add_obstacle("half_space", point=(0, 0, -h / 2), normal=(0, 0, 1), name="table", friction=mu)
    return p, c, dict(EA=E * w * h, q=q, L=L, mu=mu)


def _tip(st):
    return float(np.mean(st.g[[40, 81, 122], 0, 3]) - 1.0)


def test_rough_table_bar_partial_slip():
    """F < mu q L: a slip zone of length F/(mu q) from the tip; u_tip = F^2 / (2 EA mu q)."""
    p, c, k = _bar(F=0.6)
    res = p.solve(steps=6)
    F = 0.6 * k["mu"] * k["q"] * k["L"]
    exact = F ** 2 / (2 * k["EA"] * k["mu"] * k["q"])
    assert abs(_tip(res.final) / exact - 1) < 0.02, (_tip(res.final), exact)
    rep = c.report(res.final.g, 1.0)
    assert rep["sticking"] > 0 and rep["slipping"] > 0


def test_rough_table_bar_full_slip():
    """F > mu q L: the whole bar slides; u_tip = (F L - mu q L^2 / 2) / EA."""
    p, c, k = _bar(F=1.5)
    res = p.solve(steps=10)
    F = 1.5 * k["mu"] * k["q"] * k["L"]
    exact = (F * k["L"] - k["mu"] * k["q"] * k["L"] ** 2 / 2) / k["EA"]
    assert abs(_tip(res.final) / exact - 1) < 0.02, (_tip(res.final), exact)


def test_rough_table_bar_release_keeps_its_hysteresis():
    """Pulled to F < mu q L and released: the tip keeps F^2 / (4 EA mu q)."""
    p, c, k = _bar(F=0.6, scale=lambda lam: 1.0 - abs(2 * lam - 1.0))
    res = p.solve(steps=12)
    F = 0.6 * k["mu"] * k["q"] * k["L"]
    exact = F ** 2 / (4 * k["EA"] * k["mu"] * k["q"])
    assert abs(_tip(res.final) / exact - 1) < 0.02, (_tip(res.final), exact)


# ----------------------------------------------------------------------------- the incline
def _incline(f, mu=0.3):
    """A free 1 x 1 plate (4 x 4, h 0.01, E 1e5) on a rough incline of slope angle f atan(mu),
    written in the incline's frame (gravity tilted by the angle)."""
    a = f * np.arctan(mu)
    p = cs.Problem(M.rectangle(1.0, 1.0, 4, 4), cs.Material(1e5, 0.3, 0.01))
    p.add_gravity(rho=1000.0, g=(9.81 * np.sin(a), 0.0, -9.81 * np.cos(a)))
    c = p.add_obstacle("half_space", point=(0, 0, -0.005), normal=(0, 0, 1), name="incline", friction=mu)
    return p, c


def test_incline_holds_below_the_friction_angle():
    """tan(alpha) = 0.99 mu: the plate holds (elastic creep only; a corner node may slip where
    the moment of the friction at the face offset lowers its pressure), the tangential over the
    normal force is tan(alpha)."""
    p, c = _incline(0.99)
    st = p.solve(steps=4).final
    rep = c.report(st.g, 1.0)
    assert rep["sticking"] + rep["slipping"] == 25 and rep["sticking"] >= 20
    assert abs(rep["tangential_force"] / rep["normal_force"] - np.tan(0.99 * np.arctan(0.3))) < 1e-6
    assert np.abs(st.g[:, :3, 3] - p.mesh.g0[:, :3, 3]).max() < 1e-4


def test_incline_above_the_friction_angle_says_it_slides():
    """tan(alpha) = 1.01 mu: no static equilibrium; the error says so (not a bare
    non-convergence)."""
    p, c = _incline(1.01)
    with pytest.raises(cs.ConvergenceError, match="no static equilibrium: it slides"):
        p.solve(steps=4)


def _dragged(steps, slide=0.1, mu=0.5):
    """The strip of :func:`_bar` (10 x 1) clamped at x = 0 on a rough table that slides by
    ``slide`` along x under it (more than the exact stick length's reach: every node slips)."""
    p = cs.Problem(M.rectangle(1.0, 0.1, 10, 1), cs.Material(1e5, 0.0, 0.01))
    p.clamp("x0")
    p.add_gravity(rho=1000.0, scale=lambda lam: 1.0)
    c = p.add_obstacle("half_space", point=(0, 0, -0.005), normal=(0, 0, 1), name="table", friction=mu,
                       motion=dict(translate=(slide, 0.0, 0.0)))
    return p.solve(steps=steps), c


def test_a_clamped_strip_on_a_table_sliding_under_it():
    """The table drags the strip by mu N and no more: all nodes slip, the tangential force is mu
    times the normal force, the clamped nodes slip by the table's motion of each step, and 1 and
    4 steps end alike (the sliding direction never turns: no path dependence).  Before, the
    clamped nodes (resting at d = 0 with the cold start's pressure, 2.6e-6 of the table's 98)
    made the cone check refuse every step down to 2.4e-5 of slide: "the friction at node 0
    exceeds mu p by 0.002", a ConvergenceError for a plain slide."""
    one, c = _dragged(1)
    four, _ = _dragged(4)
    for res in (one, four):
        assert res.steps[-1].load_factor == pytest.approx(1.0)
        rec = res.steps[-1].contact["table"]
        assert rec["sticking"] == 0 and rec["slipping"] == 22
        assert abs(rec["tangential_force"] / (0.5 * rec["normal_force"]) - 1) < 1e-6
    assert abs(four.steps[-1].contact["table"]["largest_slip"] / 0.025 - 1) < 1e-9
    tip = [r.final.g[[10, 21], 0, 3].mean() - 1.0 for r in (one, four)]
    # all slipping: the strip in tension N(x) = mu q (L - x), u_tip = mu q L^2 / (2 EA) (q = 9.81,
    # EA = 100: 0.024525; measured 0.024406, the clamp's nodes carrying their share of the weight)
    assert abs(tip[0] / tip[1] - 1) < 1e-6 and abs(tip[1] / (0.5 * 9.81 / (2 * 100.0)) - 1) < 0.01, tip


def test_face_samples_of_a_rough_obstacle_warn_that_they_carry_no_friction():
    """Friction acts at the nodes; face samples (on by 'auto' for an obstacle thinner than the
    elements) are frictionless.  A free strip (24 x 1, elements 0.05 x 0.1) on two rough
    rollers (radius 0.05, mu 0.3) pressed by a third was carried by face samples alone (0 nodes
    in contact): mu was silently lost, and the strip slid along the rollers' axes by 1.3e-5 in
    1 step and 5.0e-3 in 5 (nothing resists it); with faces = false the nodes carry it, no slide.
    Now adding such an obstacle warns, naming the loss and the fixes."""
    from core_se3.errors import AccuracyWarning
    import warnings

    def roller(**kw):
        p = cs.Problem(M.rectangle(1.2, 0.1, 24, 1), cs.Material(1e5, 0.0, 0.01))
        return p.add_obstacle("cylinder", point=(0.3, 0, -0.055), axis=(0, 1, 0), radius=0.05, name="left", **kw)
    with pytest.warns(AccuracyWarning, match="friction 0.3 acts at the contact nodes only.*faces = false"):
        roller(friction=0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        roller(friction=0.0)                                   # frictionless: the samples lose nothing
        with pytest.warns(AccuracyWarning, match="thinner"):   # nodes only: the usual warning alone
            roller(friction=0.3, law=dict(faces=False))


def test_the_normal_force_of_a_rough_obstacle_counts_its_face_samples():
    """A strip on two rough rollers (radius 0.05, faces 'auto'), pressed down between them by a
    third: the face samples carry the whole contact (no node touches).  The reported
    normal_force summed the nodes' alone: 0 for a roller pushing with 1.9e-3; now it is the
    samples' force (frictionless: the obstacle's whole force)."""
    import warnings

    from core_se3.errors import AccuracyWarning
    p = cs.Problem(M.rectangle(1.2, 0.1, 24, 1), cs.Material(1e5, 0.0, 0.01))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AccuracyWarning)       # the face samples carry no friction
        for x0, name in ((0.3, "left"), (0.9, "right")):
            p.add_obstacle("cylinder", point=(x0, 0, -0.055), axis=(0, 1, 0), radius=0.05, name=name, friction=0.3)
        p.add_obstacle("cylinder", point=(0.6, 0, 0.055), axis=(0, 1, 0), radius=0.05, name="top", friction=0.3,
                       motion=dict(translate=(0.0, 0.0, -0.01)))
    rec = p.solve(steps=1).final.contact
    for name in ("left", "right", "top"):
        assert rec[name]["nodes_in_contact"] == 0 and rec[name]["faces_in_contact"] > 0
        force = np.linalg.norm(rec[name]["force"])
        assert force > 9e-4 and abs(rec[name]["normal_force"] / force - 1) < 1e-12, (name, rec[name]["normal_force"])


# ----------------------------------------------------------------------------- scenario, restart
BAR = """
name = "rough-bar"
units = "SI"
[mesh]
generator = "rectangle"
L = 1.0
width = 0.1
nx = 20
ny = 2
[material]
E = 1.0e5
nu = 0.0
h = 0.01
[[supports]]
type = "clamp"
edge = "x0"
[[loads]]
type = "gravity"
rho = 1000.0
scale = "constant"
[[loads]]
type = "edge_force"
edge = "x1"
force = [2.5, 0.0, 0.0]
scale = [[0.0, 0.0], [0.5, 1.0], [1.0, 0.3]]
[[obstacles]]
type = "half_space"
name = "table"
point = [0.0, 0.0, -0.005]
normal = [0.0, 0.0, 1.0]
friction = 0.5
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = 4
[output]
plots = false
picture = false
"""


def test_scenario_friction_outputs_and_bit_identical_resume(tmp_path, pinned_backend):
    """`friction` in [[obstacles]]; results.json carries the stick/slip counts and the largest
    slip; a run stopped after 2 of 4 steps (pull, then partial release) and resumed from its
    checkpoint ends bit for bit in the uninterrupted run's state (the friction history is in
    the checkpoint: without it the released bar would not keep its hysteresis)."""
    import json

    from core_se3 import scenario
    from core_se3.scenario import runner
    scn = scenario.loads(BAR, file="bar.toml")
    ref = runner.run(scn, out=str(tmp_path / "ref"))
    doc = json.load(open(ref.files["results"]))
    c = doc["steps"][2]["contact"]["table"]
    assert c["slipping"] > 0 and c["sticking"] > 0 and c["largest_slip"] > 0 and c["tangential_force"] > 0
    out = str(tmp_path / "cut")
    with pytest.raises(runner.RunInterrupted):
        runner.run(scn, out=out, stop_after=2)
    res = runner.run(scn, out=out, resume=True)
    np.testing.assert_array_equal(res.g, ref.g)
    with pytest.raises(cs.errors.ScenarioError, match=r"obstacles\[0\].friction"):
        scenario.loads(BAR.replace("friction = 0.5", "friction = -0.1"), file="bar.toml")


def test_frictionless_contact_has_no_friction_state():
    """mu = 0 (the default) keeps the frictionless code path and restart state."""
    p = cs.Problem(M.rectangle(1.0, 0.2, 4, 1), cs.Material(1e4, 0.0, 0.02))
    c = p.add_obstacle("half_space", point=(0, 0, -0.05), normal=(0, 0, 1))
    assert c.mu == 0 and len(c.multipliers()) == 2 * len(c.lam0) and "sticking" not in c.report(p.mesh.g0, 0.0)


def test_friction_in_the_step_table_and_the_sweep_rows(tmp_path, capsys):
    """The step table has the normal and tangential totals and the stick/slip counts of a rough
    obstacle; a sweep's rows carry them, and a sweep does not warm-start a path-dependent
    problem: pulled and partly released, each point keeps its hysteresis (a warm start, one
    solve from another point's final state, restarts the friction history from the reference:
    where it converges it gives the monotonic answer; here it failed and fell back)."""
    from core_se3 import scenario
    from core_se3.cli import scenario as cli_scenario
    scn = scenario.loads(BAR, file="bar.toml")
    rows = scenario.sweep(scn, {"loads[1].force[0]": [2.5, 2.0]}, out=str(tmp_path / "w"), plot=False).rows
    assert [r["warm"] for r in rows] == [False, False]
    cold = scenario.loads(BAR.replace("force = [2.5, 0.0, 0.0]", "force = [2.0, 0.0, 0.0]"), file="bar.toml")
    res = cold.problem.solve()
    assert rows[1]["tip.ux"] == pytest.approx(float(res.final.probes["tip"]["u"][0]), rel=1e-9)
    rec = res.final.contact["table"]
    for k in ("normal_force", "tangential_force", "sticking", "slipping", "largest_slip"):
        assert rows[1][f"contact.table.{k}"] == pytest.approx(rec[k], rel=1e-9)
    doc = dict(steps=[dict(step=k, load_factor=st.load_factor, probes={}, iterations=st.iterations,
                           residual=0.0, contact={n: {q: v for q, v in c.items() if q != "multipliers"}
                                                   for n, c in st.contact.items()})
                      for k, st in enumerate(res.steps)])
    cli_scenario.step_table(doc)
    lines = capsys.readouterr().out.splitlines()
    assert "N table" in lines[0] and "T table" in lines[0] and "stick/slip" in lines[0]
    last = rec["sticking"], rec["slipping"]
    assert f"{last[0]}/{last[1]}" in lines[-1].split()


def test_a_node_off_the_obstacle_feels_no_friction():
    """A node off contact (p = 0) carries no force from a rough obstacle: the cone's hardening
    acts with the slope of the normal law, 0 off contact.  Before, the hardening gave every node
    10^-8 k |s| of its motion s over the step wherever it was: a cantilever under a tip load,
    a rough floor 0.5 below it that it never reaches, ended 1.6e-6 (1e-5 of its deflection)
    from the frictionless run in 1 step, 9.3e-7 in 4 steps (an answer depending on the steps);
    now the two runs agree to round-off."""
    n, H = np.tile([0.0, 0.0, 1.0], (2, 1)), np.zeros((2, 3, 3))
    t, dt, stick, _ = coulomb_law(n, H, np.zeros(2), np.zeros(2), np.array([[0.3, 0.1, 0.0], [0.0, -2.0, 0.0]]),
                                  np.zeros((2, 3)), 5.0, 0.5)
    assert not stick.any() and np.all(t == 0.0) and np.all(dt == 0.0)

    def tip(mu):
        p = cs.Problem(M.rectangle(1.0, 0.05, 20, 1), cs.Material(1.2e6, 0.0, 0.01))
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.0, -2.5e-3))
        p.add_obstacle("half_space", point=(0, 0, -0.5), normal=(0, 0, 1), name="floor", friction=mu)
        return p.solve(steps=1).final.g[:, :3, 3]
    smooth, rough = tip(0.0), tip(0.5)
    assert np.abs(rough - smooth).max() < 1e-12 * np.abs(smooth).max(), np.abs(rough - smooth).max()


def test_friction_refuses_a_user_sdf_whose_gradient_is_not_unit():
    """A user's 'SDF' with |grad d| = 1.1 (a plane z = -h/2 written as 1.1 (z + h/2)): its
    frictionless contact is consistent (the gap and the force scale alike), but Coulomb's law
    needs the tangent plane I - n n^T to be a projector: the plate holding on an incline at
    0.9 of the friction angle failed with "tangent is singular", the cause unnamed.  Now a
    ContactError at add_obstacle names the gradient's length and the fix."""
    from core_se3.model import UserSDF
    p = cs.Problem(M.rectangle(1.0, 1.0, 4, 4), cs.Material(1e5, 0.3, 0.01))
    ob = UserSDF(lambda y: 1.1 * (y[:, 2] + 0.005), lambda y: np.tile([0.0, 0.0, 1.1], (len(y), 1)), name="incline")
    from core_se3.errors import ContactError
    with pytest.raises(ContactError, match=r"friction needs the unit normal .* \|grad d\| = 1.1 at node 0") as exc:
        p.add_obstacle(ob, friction=0.3)
    assert exc.value.param == "grad"
    p.add_obstacle(ob)                     # frictionless: accepted


def _grasp(pull):
    """A free strip (L 1, w 0.05, h 0.01, E 1e5, 50 x 1) threaded between three rough rollers
    (radius 0.1, mu 0.3): two below at x = 0.2 and 0.6, one above at x = 0.4 that comes down by
    delta = 0.01 over load factor 0 -> 0.5 (three-point bending: P = 48 EI delta / l^3 on the top
    one, P/2 on each other, l = 0.4), then an axial pull ``pull`` x mu (2P) at x = 1 (0.5 -> 1)."""
    E, w, h, mu = 1e5, 0.05, 0.01, 0.3
    P = 48 * E * w * h ** 3 / 12 * 0.01 / 0.4 ** 3
    p = cs.Problem(M.rectangle(1.0, w, 50, 1), cs.Material(E=E, nu=0.0, h=h))
    rollers = [p.add_obstacle("cylinder", point=(0.2, 0, -0.1 - h / 2), axis=(0, 1, 0), radius=0.1, name="left",
                              friction=mu),
               p.add_obstacle("cylinder", point=(0.6, 0, -0.1 - h / 2), axis=(0, 1, 0), radius=0.1, name="right",
                              friction=mu),
               p.add_obstacle("cylinder", point=(0.4, 0, 0.1 + h / 2), axis=(0, 1, 0), radius=0.1, name="top",
                              friction=mu, motion=dict(translate=(0, 0, -0.01), scale=lambda lam: min(1.0, 2 * lam)))]
    F = pull * mu * 2 * P
    p.add_edge_force("x1", (F, 0, 0), scale=lambda lam: max(0.0, 2 * lam - 1))
    return p, rollers, P, F, mu


def test_a_grasp_by_three_rough_rollers_meets_coulomb_node_by_node():
    """The grasp pulled by half of mu times the sum of its normal forces holds.  At every stored
    step, node by node: the traction is tangential and within the cone, a slipping node's on it
    (the hardening's 1e-8 k |s| beyond) and opposite to its slip over the step; the balance of
    the pull, the rollers' forces and no reactions to 1e-9 of P (3e-11 measured).  The top roller's force
    at the end of the squeeze is P (+0.64 %: the strip's rotations), its nodes stick throughout
    (|t| at 0.97 of the cone at the full pull), while the outer ones slip from the start (the
    bending strip draws its ends in)."""
    from core_se3.results import restore_multipliers
    p, rollers, P, F, mu = _grasp(0.5)
    res = p.solve(steps=10)
    prev = None
    for st in res.steps[1:]:
        lam = st.load_factor
        total = sum(st.contact[c.name]["force"] for c in rollers)
        assert np.linalg.norm(total + st.applied_force + st.reaction_force) < 1e-9 * P
        for c in rollers:
            y_prev = None
            if prev is not None:
                c.set_multipliers(prev.contact[c.name]["multipliers"])
                y_prev = c.y_a.copy()
            restore_multipliers(p, st)
            x, _, n, _, pp, _ = c.state(st.g, lam)
            t = c.tau @ c.obstacle.transform(lam)[:3, :3].T                 # the traction at the state
            on = pp > 0
            assert on.any() and np.abs(np.einsum("ki,ki->k", t, n)[on]).max() < 1e-12 * mu * pp[on].max()
            ratio = np.linalg.norm(t, axis=1)[on] / (mu * pp[on])
            assert ratio.max() < 1 + 1e-6
            slipping = on & (np.linalg.norm(t, axis=1) > (1 - 1e-6) * mu * pp)
            if y_prev is not None and slipping.any():
                T = c.obstacle.transform(lam)
                s = x - (y_prev @ T[:3, :3].T + T[:3, 3])
                s -= np.einsum("ki,ki->k", s, n)[:, None] * n
                cos = np.einsum("ki,ki->k", s, t)[slipping] / (np.linalg.norm(s, axis=1) * np.linalg.norm(t, axis=1))[slipping]
                assert cos.max() < -0.999
        prev = st
        if lam == 0.5:
            assert abs(st.contact["top"]["normal_force"] / P - 1) < 0.01
        assert st.contact["top"]["slipping"] == 0 and st.contact["left"]["sticking"] == 0
    assert abs(st.applied_force[0] / F - 1) < 1e-7              # the pull (9e-9 measured)


def test_a_grasp_pulled_beyond_what_friction_holds_says_it_slides():
    """The same grasp pulled by twice mu times its normal forces: no state holds beyond about
    1.15 of them (the pull itself presses the strip on the rollers), and the run stops there.
    The error blamed the mesh ("edge [39, 40] turns by 3.109 rad ... refine the mesh or the load
    step": the last iterate had been flung off every roller, and the hint looked at it and at one
    obstacle at a time); now it names the sliding over all three rollers."""
    p, rollers, P, F, mu = _grasp(2.0)
    with pytest.raises(cs.ConvergenceError, match="no static equilibrium: it slides -- all .* on obstacles") as info:
        p.solve(steps=10)
    msg = str(info.value)
    assert all(repr(c.name) in msg.split("Probable cause")[1] for c in rollers)
    assert "the last converged load factor is 0.78" in msg          # pull 1.15 mu (2P)
    assert all(st.balance_error < 1e-8 for st in info.value.result.steps[1:])

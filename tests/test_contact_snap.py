"""The snap check of load stepping with contact (issue 29, docs/STEPS.md,
``core_se3.solvers.contact_probe``): a contact step that moved a node by more than an element
size is solved again in halves; a too-big step that had landed elsewhere is cut back to the
halves' path, and a jump that survives halving the step is reported as a snap.  Each test fails
on the code before the check (contact steps were accepted as they converged, silently)."""
import logging

import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.catalogue import run_case
from core_se3.catalogue.case import case_params, get_case
from core_se3.catalogue.run import build_problem
from core_se3.solvers.contact_probe import SNAP_HALVINGS, ContactProbe, median_edge


def _largest_motion(res):
    """The largest motion of a node over one stored step, and the load factor it ends at."""
    x = np.array([st.g[:, :3, 3] for st in res.steps])
    jump = np.linalg.norm(np.diff(x, axis=0), axis=2).max(1)
    k = int(np.argmax(jump))
    return float(jump[k]), res.steps[k + 1].load_factor


def _jumping_cantilever():
    """A 10 x 1 strip whose tip force jumps from 0 to 1 at load factor 0.5 (tip deflection 3 =
    30 % of L: a discontinuity of the quasi-static path), with a sphere far below it, so the
    problem has contact (the path and stability checks leave it)."""
    p = Problem(mesh.rectangle(10.0, 1.0, 10, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0), scale=lambda lam: 0.0 if lam < 0.5 else 1.0)
    p.add_obstacle("sphere", centre=(5.0, 0.5, -20.0), radius=1.0)
    return p


def test_a_jump_that_survives_halving_is_reported_as_a_snap(caplog):
    """The jump at load factor 0.5 is bracketed to 1/64 of the requested step (0.25), stored
    as a critical point of kind 'snap' with the node and its travel, and warned about once;
    the run goes on to the end on the state the jump lands on."""
    prob = _jumping_cantilever()
    with caplog.at_level(logging.WARNING):
        res = prob.solve(steps=4)
    assert res.steps[-1].load_factor == 1.0
    (snap,) = res.critical_points
    lo, hi = snap.lam_bracket
    assert snap.kind == "snap" and lo < 0.5 <= hi and hi - lo <= 0.25 / 2 ** SNAP_HALVINGS + 1e-12
    assert snap.travel > 3.0 and snap.node in prob.mesh.node_set("x1")
    assert res.steps[snap.step].load_factor == 0.5           # the stored step past the snap
    warned = [r.getMessage() for r in caplog.records if "snap between load factors" in r.getMessage()]
    assert len(warned) == 1 and "dynamic analysis" in warned[0]
    assert res.steps[2].checks["snap_probes"] == SNAP_HALVINGS


def test_snap_check_off_accepts_the_jump_silently():
    """``snap_check = False`` (the [solver] key) restores the old acceptance: one try per step."""
    res = _jumping_cantilever().solve(steps=4, snap_check=False)
    assert res.critical_points == [] and [st.attempts for st in res.steps[1:]] == [1, 1, 1, 1]


def test_walker_at_mu_0p7_is_cut_back_to_its_path():
    """The frictional walker at mu 0.7 (catalogue friction-walker, its set-up ramp to load
    factor 1 in 10 steps): without the check one step moved a node by 1.6 L (the walker 'stood
    up on one foot', the record of benchmarks/friction_walker.py); probed in halves, that step
    had landed elsewhere: the halves follow a path on which no node moves more than 0.03 L per
    stored step, and the same path as 40 steps give (to 1e-3 L at load factor 1)."""
    case = get_case("friction-walker")
    p = dict(case_params(case), mu=0.7, cycles=0.0)
    ends = []
    for n in (10, 40):
        res = build_problem(case, p).solve(load_factors=[k / n for k in range(1, n + 1)])
        jump, _ = _largest_motion(res)
        assert jump < 0.05 * p["L"] and res.critical_points == []
        ends.append(res.steps[-1].g[:, :3, 3])
        if n == 10:
            assert sum(st.checks["landed_elsewhere"] for st in res.steps[1:]) >= 1
    assert np.linalg.norm(ends[0] - ends[1], axis=1).max() < 1e-3 * p["L"]


@pytest.mark.parametrize("name, steps", [("contact-lift", 1), ("contact-propped", None), ("contact-lift", None)])
def test_no_false_snaps_on_the_contact_catalogue(name, steps):
    """The contact catalogue's continuous paths (one step and the default) report no snap and
    no step that landed elsewhere."""
    _, res, _ = run_case(name, steps=steps)
    assert res.critical_points == []
    assert all(st.checks["landed_elsewhere"] == 0 for st in res.steps[1:])


def test_probe_logic_on_given_states():
    """ContactProbe alone: a try within one element size is accepted; a larger one is probed;
    a half that travels as far again is probed in turn; one that shrank is accepted; a jump
    in a step of 1/64 of the requested one is a snap; the halves' end compared with the probed
    try's state counts a step that landed elsewhere."""
    m = mesh.rectangle(4.0, 1.0, 4, 1)
    assert median_edge(m) == 1.0
    g0 = m.g0.copy()

    def moved(dz, node=9):
        g = g0.copy()
        g[node, 2, 3] += dz
        return g

    probe = ContactProbe(median_edge(m))
    probe.new_step(1.0)
    assert probe.judge(g0, moved(0.9), 0.0, 1.0) == ""
    assert probe.judge(g0, moved(4.0), 0.0, 1.0).startswith("snap check")       # probed
    assert probe.next_increment(0.0, 0.5) == 0.5 and probe.next_increment(0.75, 0.5) == 0.25
    assert probe.judge(g0, moved(2.0), 0.0, 0.5) == ""                         # shrank: 2 <= 0.75 * 4
    probe.accept(moved(2.0), 0.5)
    assert probe.judge(moved(2.0), moved(4.0), 0.5, 1.0) == ""
    probe.accept(moved(4.0), 1.0)                     # the halves end where the probed try did
    assert probe.probes == [] and probe.record() == dict(snap_probes=1, landed_elsewhere=0)
    probe.judge(g0, moved(4.0), 0.0, 1.0)
    assert probe.judge(g0, moved(3.5), 0.0, 0.5).startswith("snap check")      # as far again: probed
    probe.accept(moved(0.4), 0.25)
    probe.accept(moved(3.5), 0.5)
    probe.accept(moved(5.0), 1.0)                     # the halves ended 1 element size away from 4
    assert probe.record() == dict(snap_probes=2, landed_elsewhere=1)
    assert probe.judge(g0, moved(4.0), 0.0, 1.0 / 64) == "" and probe.passed()[0].kind == "snap"


def test_a_snap_keeps_its_node_and_travel_through_a_checkpoint():
    """A snap as a checkpoint stores it (``pack``, JSON) and ``--resume`` reads it back
    (``CriticalPoint.unpack``): still a SnapPoint with its node, travel and step, so the resumed
    run's results.json describes the same snap.  Before, it came back a plain CriticalPoint (node
    and travel lost; described as 'snap point at lam ~ 0.5')."""
    import json

    from core_se3.scenario.sinks import _critical_doc
    from core_se3.solvers.stability import CriticalPoint
    res = _jumping_cantilever().solve(steps=4)
    (snap,) = res.critical_points
    back = CriticalPoint.unpack(json.loads(json.dumps(snap.pack())))
    assert type(back) is type(snap) and back == snap and back.describe() == snap.describe()
    (doc,) = _critical_doc([back])
    assert doc["node"] == snap.node and doc["travel"] == snap.travel and doc["description"].startswith("snap between")


def test_a_resumed_scenario_writes_the_snap_it_found_before_the_interruption(tmp_path):
    """The jumping cantilever as a scenario (the tip force's scale table jumps from 0 to 1 at
    load factor 0.5, a sphere far below), 4 steps, interrupted after step 3 (past the snap) and
    resumed: results.json's snap is the uninterrupted run's -- node 10, travel 3.063, its
    description.  Before, the resumed run wrote 'snap point at lam ~ 0.501953 (between 0.5 and
    0.503906)' with no node nor travel."""
    import warnings

    from core_se3 import scenario

    def scn():
        return scenario.from_dict(dict(
            mesh=dict(generator="rectangle", L=10.0, width=1.0, nx=10, ny=1), material=dict(E=1.2e6, nu=0.0, h=0.1),
            supports=[dict(type="clamp", edge="x0")],
            loads=[dict(type="edge_force", edge="x1", force=[0.0, 0.0, 1.0],
                        scale=[[0.0, 0.0], [0.5, 0.0], [0.5000001, 1.0], [1.0, 1.0]])],
            obstacles=[dict(type="sphere", centre=[5.0, 0.5, -20.0], radius=1.0)],
            solver=dict(steps=4), output=dict(vtu=False, plots=False, picture=False)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = scenario.run(scn(), out=str(tmp_path / "whole")).doc["critical_points"]
        with pytest.raises(scenario.RunInterrupted):
            scenario.run(scn(), out=str(tmp_path / "cut"), stop_after=3)
        resumed = scenario.run(scn(), out=str(tmp_path / "cut"), resume=True).doc["critical_points"]
    assert [c["description"] for c in resumed] == [c["description"] for c in whole]
    (snap,) = whole
    assert snap["kind"] == "snap" and snap["step"] == 3 and snap["travel"] > 3.0 and resumed == whole


def _propped_roof(prop=True):
    """The 8 x 8 quarter of Sze's hinged roof s3.8(a) (h 12.7, limit point at 0.7436 of its
    point load alone), with a ball of radius 30 under its free edge at x = 222, 0.45 below the
    contact face (``prop``; else far below the roof): the ball props the edge from load factor
    about 0.6 on and moves the limit point."""
    case = get_case("sze-hinged-roof")
    p = build_problem(case, case_params(case), mesh=(8, 8))
    gap, depth = (0.45, 0.0) if prop else (0.45, 5000.0)
    z = np.sqrt(2540.0 ** 2 - 222.0 ** 2) - 12.7 / 2 - gap - 30.0 - depth
    p.add_obstacle("sphere", centre=(222.0, 254.0, z), radius=30.0, name="prop")
    return p


@pytest.mark.parametrize("prop, lam_stop", [(True, 0.806763), (False, 0.74353)])
def test_a_contact_run_that_stops_at_a_limit_point_says_so(prop, lam_stop):
    """Load control stops at the roof's limit point (0.806763 propped, 0.74353 with the ball
    far away), and the error names it: the smallest eigenvalue of the tangent with the contact
    held has fallen to 0.0037 (0.0039) of its initial value (the roof alone's S_p there is
    0.0064).  Before, ``limit_point_hint``'s ShellSystem refused the contact load and the error
    said only 'no convergence in 30 iterations', with no cause."""
    from core_se3.errors import ConvergenceError
    with pytest.raises(ConvergenceError) as err:
        _propped_roof(prop).solve(steps=4)
    msg = str(err.value)
    assert f"the last converged load factor is {lam_stop}" in msg
    assert "Probable cause: the smallest eigenvalue of the tangent" in msg and "the equilibrium path turns" in msg
    assert "arc length and displacement control do not take contact" in msg
    ratio = float(msg.split("has fallen to ")[1].split(" ")[0])
    assert 0 < ratio < 0.01
    force = err.value.result.steps[-1].contact["prop"]["force"][2]
    assert (force > 100.0) if prop else (force == 0.0)          # propped: the ball carries 121 at 0.75


def _pushed_roof():
    """The 8 x 8 quarter of Sze's thicker hinged roof (h 6.35) pushed at its crown by a ball of
    radius 20 descending 30 over the load factor (no other load): the roof follows the ball down
    to about 15 at load factor 0.5, then snaps through ahead of it (a snap-back of the crown's
    displacement)."""
    case = get_case("sze-hinged-roof-6.35")
    prm = case_params(case)
    prm["load_max"] = 0.0
    p = build_problem(case, prm, mesh=(8, 8))
    top = 2540.0 + prm["h"] / 2
    p.add_obstacle("sphere", centre=(0.0, 0.0, top + 20.01), radius=20.0, name="pusher",
                   motion=dict(translate=(0.0, 0.0, -30.0)))
    return p


def test_a_shell_that_snaps_away_from_a_pushing_obstacle_is_not_passed_silently():
    """Before, 10 steps completed: between load factors 0.5 and 0.6 the crown jumped from -15.0
    to -24.8 (9.8, a third of an element, so the snap check's travel of one element size never
    looked), contact lost, and no critical point.  Now the node's lift-off from the ball by its
    own motion (6.8 = 1.07 h > LIFT_OFF h) probes the step in halves; the jump survives them
    and the run stops where the path in contact turns (0.5651, the tangent with the contact held
    at 0.003 of its initial value), saying so."""
    from core_se3.errors import ConvergenceError
    with pytest.raises(ConvergenceError) as err:
        _pushed_roof().solve(steps=10)
    msg = str(err.value)
    last = float(msg.split("the last converged load factor is ")[1].split(" ")[0])
    assert 0.5 < last < 0.6 and "the equilibrium path turns" in msg
    steps = err.value.result.steps
    assert all(st.contact["pusher"]["force"][2] < -50.0 for st in steps[1:])      # in contact throughout (-59 ... -145)


def test_lift_off_of_carried_released_and_jumping_nodes():
    """ContactLoad.lift_off on given states of a 2 x 1 plate on a floor: nodes carried up by a
    rising floor, or left behind by a falling one, lift off by 0; nodes that jump 0.3 above a
    fixed floor lift off by 0.3 (in lengths; the node named)."""
    p = Problem(mesh.rectangle(1.0, 0.5, 2, 1), Material(1e4, 0.0, 0.02))
    c = p.add_obstacle("half_space", point=(0.0, 0.0, -0.01), normal=(0.0, 0.0, 1.0), name="floor",
                       motion=dict(translate=(0.0, 0.0, 0.2)))
    g0 = p.mesh.g0.copy()
    up = g0.copy()
    up[:, 2, 3] += 0.2                       # carried by the rising floor to load factor 1
    assert c.lift_off(g0, 0.0, up, 1.0)[0] == pytest.approx(0.0, abs=1e-12)
    assert c.lift_off(up, 1.0, up, 0.0)[0] == pytest.approx(0.0, abs=1e-12)   # floor falls away: released
    jump = g0.copy()
    jump[4, 2, 3] += 0.3
    lift, node = c.lift_off(g0, 0.0, jump, 0.0)
    assert lift == pytest.approx(0.3, rel=1e-12) and node == 4

"""The friction catalogue cases (``catalogue.cases_friction``) against what the mechanics says
exactly, and the walker example (examples/walker.toml) on a small mesh:

* friction-pushed-cantilever: the end sticks to the sliding wall (u = s) while the lateral force
  H = s / f (f = (tan kL - kL)/(P k), the cantilever beam-column) is below mu P, then slips at
  H = mu P with the end held at s* = mu P f;
* friction-gripper-hold: the largest force held is below, and within 5 % of, the bound
  sum_i N_i (n_z,i + mu sqrt(1 - n_z,i^2)) of the contact normal forces;
* the walkers: the asymmetric one walks forward, the same every cycle once the first is done;
  the mirror-symmetric one stays where it is (to 1e-8 L).
Derivations: docs/CONTACT.md "Friction" and "Walking"."""
from __future__ import annotations

import os
try:
    import tomllib
except ModuleNotFoundError:     # Python 3.10 (README: the core tests run on any Python >= 3.10)
    import tomli as tomllib

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.catalogue import run_case
from core_se3.catalogue.cases_friction import HOLD_PARAMS, PUSH_PARAMS, WALKER_PARAMS, push_formula
from core_se3.model.friction import CONE_EXCESS

EXAMPLES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "examples")


@pytest.fixture(scope="module")
def pushed():
    return run_case("friction-pushed-cantilever")          # 40 x 1, the wall slides 2 s* in 9 steps


def test_pushed_cantilever_sticks_then_slips_at_mu_P(pushed):
    """Stick: the end moves with the wall (u = s, up to the penalty's tangential compliance
    H / (k A), measured 1e-6 of s) and H is the beam-column's s / f within 2e-3 (the linear
    formula leaves out the geometric terms of order (s*/L)^2 = 7.5e-4; measured 7.5e-4 at the
    last stick step).  Slip: H = mu P within CONE_EXCESS (the law's bound; measured 4e-10), the
    end held at s* within 2e-3 (the same terms; measured 3.4e-4) and not moving while the wall
    goes on.  The normal force is P (the root slides) to Newton's tolerance (measured 1.3e-9)."""
    doc, _, _ = pushed
    r = push_formula(PUSH_PARAMS)
    steps = doc["steps"][1:]
    m = [s["measures"] for s in steps]
    stick = [i for i, x in enumerate(m) if x["regime"] == "stick"]
    slip = [i for i, x in enumerate(m) if x["regime"] == "slip"]
    assert len(stick) == 4 and len(slip) == 5                # s* = 0.0274 inside the fifth wall step
    for i in stick:
        c = steps[i]["contact"]["wall"]
        assert c["sticking"] == 2 and c["slipping"] == 0
        assert abs(m[i]["u"] / m[i]["s"] - 1) < 1e-5
        assert abs(m[i]["H"] / (m[i]["s"] / r["f"]) - 1) < 2e-3
    for i in slip:
        c = steps[i]["contact"]["wall"]
        assert c["sticking"] == 0 and c["slipping"] == 2
        assert abs(m[i]["H"] / (PUSH_PARAMS["mu"] * r["P"]) - 1) < CONE_EXCESS
        assert abs(m[i]["u"] / r["s_star"] - 1) < 2e-3
        assert abs(m[i]["u"] - m[slip[0]]["u"]) < 1e-6 * r["s_star"]
    for x in m:
        assert abs(x["N"] / x["N_exact"] - 1) < 1e-7


def test_pushed_cantilever_frictionless_does_not_hold():
    """mu = 0: nothing holds the end across the wall's motion -- the lateral force is zero and
    the end does not follow the wall (the test the frictionless contact fails)."""
    doc, _, _ = run_case("friction-pushed-cantilever", overrides=dict(mu=0.0), steps=3)
    for s in doc["steps"][1:]:
        assert abs(s["measures"]["H"]) < 1e-12 * push_formula(PUSH_PARAMS)["P"]
        assert abs(s["measures"]["u"]) < 1e-9


def test_gripper_holds_up_to_the_bound_of_its_normal_forces():
    """The sphere rises out of the grasp: the force the fingers hold it back with is at every
    step at most the cone's bound sum N_i (n_z,i + mu |n_perp,i|) (each node's force lies in
    its cone, up to CONE_EXCESS), and the largest within 5 % of it (measured 0.9953: all but
    a few nodes slip along z there)."""
    doc, _, _ = run_case("friction-gripper-hold")           # 10 x 3 per finger, 20 pull steps
    for s in doc["steps"][11:]:
        m = s["measures"]
        assert m["hold"] <= m["bound"] * (1 + CONE_EXCESS) + 1e-15
    h = doc["hold"]
    assert 0.95 <= h["ratio"] <= 1 + CONE_EXCESS, h


def _walk(name, **over):
    doc, _, _ = run_case(name, mesh=(10, 1), steps=20, overrides=dict(cycles=2.0, **over))
    assert doc["walk"]["largest_step_motion_over_L"] < 0.25          # a continuous path: no snap
    return doc["walk"]["per_cycle"]


def test_walker_walks_and_the_symmetric_one_does_not():
    """The asymmetric walker moves forward (+x) every cycle, by about a sixth of its length; the
    mirror-symmetric one (mz = 0, Bx = 0) has both feet slip alike and stays put: |net| below
    1e-8 L per cycle (measured below 1e-10 L; the residual tolerance of Newton).  Neither path
    jumps: no node moves by a quarter of L in one step (a snap does: at mu 0.7 the strip stands
    up on its front foot during the set-up, 1.3 L in one step, benchmarks/friction_walker.py)."""
    L = WALKER_PARAMS["L"]
    per = _walk("friction-walker")
    assert all(v > 0.05 * L for v in per), per
    per_sym = _walk("friction-walker-symmetric")
    assert all(abs(v) < 1e-8 * L for v in per_sym), per_sym


def test_walker_example_walks_as_the_catalogue_case(tmp_path):
    """examples/walker.toml (two uniform fields, four magnet entries) is the catalogue's
    friction-walker written as a scenario: on 10 x 1 elements with 20 steps per cycle its second
    cycle moves the rear foot by the catalogue's second-cycle displacement (a periodic state is
    reached after the first cycle, so the different set-up steps do not matter: to 1e-6)."""
    from core_se3.scenario import runner
    path = os.path.join(EXAMPLES, "walker.toml")
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    doc["mesh"]["nx"] = 10
    doc["output"] = dict(vtu=False)
    scn = scenario.from_dict(doc, file=path, base_dir=EXAMPLES, default_name="walker")
    res = runner.run(scn, out=str(tmp_path / "walker"))
    steps = {round(s["load_factor"], 9): s for s in res.doc["steps"]}
    step = steps[3.0]["probes"]["rear"]["u"][0] - steps[2.0]["probes"]["rear"]["u"][0]
    per = _walk("friction-walker")
    assert res.status == "complete"
    assert abs(step / per[1] - 1) < 1e-6, (step, per)


def _free_strip(mu):
    return {"name": "free", "units": "N-mm-MPa",
            "mesh": dict(generator="rectangle", L=4.0, width=1.5, nx=4, ny=1),
            "material": dict(E=0.07, nu=0.0, h=0.2, rho=1.86e-9),
            "loads": [dict(type="gravity", scale="constant")],
            "obstacles": [dict(type="half_space", name="floor", point=[0.0, 0.0, -0.1], normal=[0.0, 0.0, 1.0], friction=mu)],
            "solver": dict(steps=1)}


def test_a_free_shell_may_rest_on_a_rough_floor_but_not_on_a_smooth_one(tmp_path):
    """No [[supports]] with an obstacle: on a rough floor the strip lies under its weight (the
    floor carries it: the contact force is the weight, to Newton's tolerance); on a smooth one
    the run is refused naming the free motion (a translation along the floor), not a singular
    tangent."""
    from core_se3.errors import CoreSE3Error
    from core_se3.scenario import runner
    res = runner.run(scenario.from_dict(_free_strip(0.3), default_name="free"), out=str(tmp_path / "rough"))
    weight = 1.86e-9 * 0.2 * 4.0 * 1.5 * 9810.0
    assert res.status == "complete"
    assert abs(res.doc["steps"][-1]["contact"]["floor"]["force"][2] / weight - 1) < 1e-8
    with pytest.raises(CoreSE3Error, match="rigid-body motion free .translation along"):
        runner.run(scenario.from_dict(_free_strip(0.0), default_name="free"), out=str(tmp_path / "smooth"))


def test_friction_is_refused_on_distributed_runs():
    """A rough obstacle split over ranks (what mpirun does to each load) is refused with a
    ContactError naming the obstacle and the fix (one process), never run with friction lost;
    the same obstacle without friction is split."""
    from core_se3 import Material, Problem, mesh
    from core_se3.errors import ContactError
    from core_se3.parallel.local import subdomain
    from core_se3.parallel.localize import localize_load
    p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e4, 0.0, 0.02))
    smooth = p.add_obstacle("half_space", point=(0, 0, -0.5), normal=(0, 0, 1), name="smooth")
    rough = p.add_obstacle("half_space", point=(0, 0, -0.5), normal=(0, 0, 1), name="rough", friction=0.3)
    s = subdomain(p.mesh, np.array([0, 1]), rank=1, size=2)
    part = localize_load(smooth, s)[0]           # its owned nodes; the face's others with zero area
    assert part.nodes[part.A > 0].tolist() == [0, 1] and part.nodes.tolist() == [0, 1, 2, 3]
    with pytest.raises(ContactError, match="'rough': friction is not distributed over ranks yet; run it on one"):
        localize_load(rough, s)


def test_the_walker_quasi_static_check_weighs_the_centroid_inertia_against_friction():
    """The quasi-static stride does not vanish as mu -> 0 (the feet's forces balance; which one
    slips does not depend on mu's size: 0.650, 0.710, 0.743, 0.754 mm per cycle at mu 1, 0.5,
    0.2, 0.1 on 20 x 1 elements; at mu 0.02 and 0.005 the runs stop), while a real walker's
    does: the changes of its centroid's horizontal velocity need the floor's friction, at most
    mu m g, for sum |dv| / (mu g) of the period.  States whose centroid moves as x = a t^2 / 2
    (t = period x load factor) with a vertical bob that friction need not carry: over 6 states
    the midpoint velocities change by a dt four times, so ``friction_time_over_period`` is
    4 a dt / (mu g period) exactly, and above QS_FRICTION it warns with the period at which it
    would be QS_FRICTION.  Before, the check compared the inertia with the weight alone (1 % at
    mu 0.5), which says nothing as mu -> 0."""
    import warnings

    from core_se3.catalogue.family_friction import QS_FRICTION, quasi_static_check, quasi_static_warning
    from core_se3.errors import AccuracyWarning
    p = dict(WALKER_PARAMS)
    g0 = np.tile(np.eye(4), (5, 1, 1))
    a, dlam = 0.2 * p["g"], 1.0 / 20
    dt = p["period"] * dlam
    states = []
    for tk in dt * np.arange(6):
        g = g0.copy()
        g[:, 0, 3] += np.arange(5) + a * tk ** 2 / 2
        g[:, 2, 3] += 3.0 * a * tk ** 2 / 2               # vertical: carried by the normal force
        states.append(g)
    for mu, warns in ((0.5, False), (0.3, True), (0.01, True)):
        q = quasi_static_check(None, dict(p, mu=mu), states, dlam)
        exact = 4 * a * dt / (mu * p["g"] * p["period"])      # 0.04 / mu
        assert abs(q["friction_time_over_period"] - exact) < 1e-9 * exact
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            quasi_static_warning(q, mu)
        said = [str(w.message) for w in seen if issubclass(w.category, AccuracyWarning)]
        assert bool(said) == warns
        if warns:
            slow = p["period"] * np.sqrt(exact / QS_FRICTION)
            assert f"raise the period to at least {slow:.3g} s or mu" in said[0]

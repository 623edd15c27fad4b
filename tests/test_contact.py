"""Frictionless contact with rigid obstacles (issue 16): the SDFs and their derivatives, the contact
tangent against central differences across the active-set states, the catalogue cases against
their formulas and the elastica reference (``data/contact_lift_elastica.json``), penetration and
balance, quadratic convergence with a fixed active set, the solver hooks, scenario validation and
the outputs.  Derivations: docs/CONTACT.md."""
from __future__ import annotations

import importlib.util
import json
import os

import numpy as np
import pytest

import core_se3 as cs
from core_se3 import lie, scenario
from core_se3 import mesh as M
from core_se3.catalogue import contact_lift_elastica, lifted_length_from_gaps, run_case
from core_se3.errors import ContactError, ConvergenceError, ScenarioError
from core_se3.model import (Box, ContactLaw, ContactLoad, Cylinder, HalfSpace, Sphere, UserSDF, check_sdf, rotation,
                            tangent_fd_check, translation)
from core_se3.model.contact import contact_wrench, normal_law, ramp, ramp_inverse

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def obstacles():
    """One obstacle of every kind, placed to cut through the perturbed 3 x 2 plate below."""
    return {
        "half_space": HalfSpace((0, 0, -0.01), (0.1, 0, 1)),
        "sphere": Sphere((0.5, 0, 0.6), 0.6),
        "cylinder": Cylinder((0, 0, 0.5), (0.3, 1, 0), 0.5),
        "capped_cylinder": Cylinder((0.5, 0, 0.3), (0, 0, 1), 0.35, length=0.6, rounding=0.05),
        "box": Box((0.5, 0, -0.3), (0.4, 0.2, 0.3), rotation=lie.exp_so3(np.array([0.1, 0.2, 0.3])), rounding=0.05),
        "user_fd_hessian": UserSDF(lambda y: y[:, 2] + 0.05 * np.sin(3 * y[:, 0]),
                                   lambda y: np.stack([0.15 * np.cos(3 * y[:, 0]), 0 * y[:, 0], 1 + 0 * y[:, 0]], 1)),
        "moving_sphere": Sphere((0.5, 0, 0.9), 0.6, motion=translation((0, 0, -0.5))),
        "rotating_box": Box((0.5, 0, -0.25), (0.4, 0.2, 0.25), rounding=0.05,
                            motion=rotation((0, 1, 0), (0.5, 0, 0), 0.2)),
    }


def _state(seed=1):
    m = M.rectangle(1.0, 0.6, 3, 2)
    g = m.g0 @ lie.exp(np.random.default_rng(seed).normal(size=(m.n_nodes, 6)) * 0.08)
    return m, g


def _load_fd(load, g, lam, h=1e-7):
    """Max relative difference of the load's own -df/deta blocks against central differences."""
    n = len(g)
    ev = load.evaluate(g, lam)
    K = np.zeros((n, 6, n, 6))                     # the nodal blocks and the face samples' element blocks
    K[np.arange(n), :, np.arange(n), :] = ev.node_blocks
    if ev.element_blocks is not None:
        for e, blk in zip(*ev.element_blocks):
            q = load_mesh_quads(load)[e]
            for a in range(4):
                for b in range(4):
                    K[q[a], :, q[b], :] += blk[a, b]
    err, scale = 0.0, 0.0
    for i in range(n):
        for k in range(6):
            d = np.zeros((n, 6))
            d[i, k] = h
            col = -(load.evaluate(g @ lie.exp(d), lam, False).f - load.evaluate(g @ lie.exp(-d), lam, False).f) / (2 * h)
            err = max(err, np.abs(col - K[:, :, i, k]).max())
            scale = max(scale, np.abs(col).max())
    return err / scale


def load_mesh_quads(load):
    """The mesh quads of a contact load's problem (its face samples' element ids index them)."""
    return load._mesh_quads


# ----------------------------------------------------------------------------- laws, SDFs
def test_ramp_law_is_c1_and_shifted():
    w = 0.7
    u = np.linspace(-1, 2, 3001)
    p, dp = ramp(u, w)
    assert np.all(p >= 0) and np.all(np.diff(p) >= -1e-15)
    assert np.allclose(np.gradient(p, u)[1:-1], dp[1:-1], atol=2e-3)
    lam = np.array([0.0, 1e-3, 0.1, 0.35, 2.0])
    assert np.allclose(ramp(ramp_inverse(lam, w), w)[0], lam)
    # p(d = 0) = lam for every multiplier: the Uzawa fixed points are the exact contact conditions
    assert np.allclose(normal_law(np.zeros(5), lam, 3.0, w / 3.0)[0], lam)


@pytest.mark.parametrize("name", list(obstacles()))
def test_sdf_gradient_and_hessian(name):
    ob = obstacles()[name]
    x = np.random.default_rng(3).normal(size=(60, 3)) * 0.8 + np.array([0.5, 0, 0])
    x = x[np.abs(ob.distance(x, 0.6)) > 1e-3]            # off the medial kinks at the surface
    dn, dH = check_sdf(ob, x, 0.6)
    assert dn < 1e-7
    assert dH < (1e-4 if ob.approximate_hessian else 1e-6)


def test_rounded_box_is_c1_across_edges():
    b = Box((0, 0, 0), (0.5, 0.4, 0.3), rounding=0.05)
    x = np.stack([np.linspace(0.3, 0.6, 3001), np.zeros(3001), np.full(3001, 0.31)], 1)
    d, n, H = b.evaluate(x)
    assert np.abs(np.linalg.norm(n, axis=1) - 1).max() < 1e-12
    assert np.allclose(n[0], [0, 0, 1]) and n[-1, 0] > 0.9
    assert np.abs(np.diff(n, axis=0)).max() < 2e-3             # no jump of the normal
    assert np.abs(H).max() <= 1 / 0.05 + 1e-9                   # curvature bounded by 1/rounding


def test_obstacle_surfaces_lie_on_the_obstacles():
    bounds = np.array([[-1.0, -1.0, -1.0], [2.0, 1.0, 1.0]])
    for name, ob in obstacles().items():
        surf = ob.surface(0.6, bounds)
        if surf is None:
            assert name.startswith("user")
            continue
        pts, quads = surf
        assert quads.shape[1] == 4 and quads.max() < len(pts)
        tol = 0.06 if isinstance(ob, (Box, Cylinder)) and getattr(ob, "rounding", None) else 1e-9
        assert np.abs(ob.distance(pts, 0.6)).max() < tol        # rounded bodies are drawn sharp


# ----------------------------------------------------------------------------- tangents
@pytest.mark.parametrize("name", list(obstacles()))
def test_tangent_fd_in_band_and_out_of_contact(name):
    """Central differences along g exp(eps eta) of the full problem and of the contact load
    alone, at a state with nodes deep in contact, inside the C^1 band and free."""
    m, g = _state()
    prob = cs.Problem(m, cs.Material(1e4, 0.3, 0.02))
    cl = prob.add(ContactLoad(prob, obstacles()[name], law=ContactLaw(eps=0.02)))      # a wide band: all states testable
    lam = 0.6
    d = cl.gaps(g, lam)
    w = cl.k * cl.eps
    target = np.array([2.0, 0.5, -1.0])[np.arange(len(d)) % 3] * w      # u = u0(lam) - k d
    cl.set_multipliers(ramp(np.maximum(target + cl.k * d, 0.0), w)[0])
    _, d, _, _, p, dp = cl.state(g, lam)
    deep, band, out = dp == -cl.k, (p > 0) & (dp > -cl.k), p == 0
    assert deep.any() and band.any() and out.any(), (deep.sum(), band.sum(), out.sum())
    assert tangent_fd_check(prob, g, lam, free_all=True)[0] < 1e-7
    assert _load_fd(cl, g, lam) < (1e-5 if cl.approximate_tangent else 1e-7)


def test_tangent_fd_default_band_and_penalty_mode():
    m, g = _state(2)
    for mode in ("al", "penalty"):
        prob = cs.Problem(m, cs.Material(1e4, 0.3, 0.02), backend="numpy")
        cl = prob.add(ContactLoad(prob, Sphere((0.5, 0, 0.6), 0.6), law=ContactLaw(mode=mode)))
        _, d, _, _, p, _ = cl.state(g, 0.0)
        assert (p > 0).any() and (p == 0).any()
        assert tangent_fd_check(prob, g, 0.0, free_all=True)[0] < 1e-7
        assert _load_fd(cl, g, 0.0) < 1e-7


def test_offset_force_exerts_its_moment():
    R = lie.exp_so3(np.array([[0.3, -0.2, 0.5]]))
    n = np.array([[0.2, 0.1, 0.97]]) / np.linalg.norm([0.2, 0.1, 0.97])
    f, K = contact_wrench(R, np.array([-0.01]), np.array([2.0]), n, np.zeros((1, 3, 3)), np.array([5.0]),
                          np.array([-10.0]))
    Fb = R[0].T @ (10.0 * n[0])
    assert np.allclose(f[0, :3], Fb) and np.allclose(f[0, 3:], np.cross(-0.01 * np.array([0, 0, 1.0]), Fb))


# ----------------------------------------------------------------------------- the cases
@pytest.fixture(scope="module")
def lift():
    return run_case("contact-lift")                      # delta / L = 0.01, 80 x 1, 2 steps


@pytest.fixture(scope="module")
def lift_large():
    return run_case("contact-lift", overrides=dict(delta=0.2), steps=10)


@pytest.fixture(scope="module")
def propped():
    return run_case("contact-propped")                   # g / L = 0.01, 40 x 1, 10 steps


def test_lift_against_the_small_deflection_formula(lift):
    doc, res, prob = lift
    m = doc["steps"][-1]["measures"]
    assert abs(m["delta"] - 0.01) < 1e-15
    assert abs(m["l_error_formula"]) < 0.01 and abs(m["F_error_formula"]) < 0.01
    # on the model's side of the difference: the elastica tends to the formula as delta -> 0
    errs = [abs(s["measures"]["l_elastica"] / s["measures"]["l_formula"] - 1) for s in doc["steps"][1:]]
    assert errs[0] < errs[1] < 1e-3
    assert abs(m["horizontal_reaction"]) < 1e-8 * 0.1          # frictionless: no horizontal reaction
    # the detachment falls between two nodes
    assert m["lifted_length"] % (1.0 / 80) > 1e-4


def test_lift_difference_shrinks_as_delta_goes_to_zero():
    """At a fixed resolution of the lifted part (about 26 elements on it: nx ~ delta^(-1/4)) the
    differences of the lifted length and of the lift force from the small-deflection formula fall
    with delta (measured: l +0.32, +0.12, +0.023 %; F +0.58, +0.080, -0.004 %)."""
    dl, dF = [], []
    for delta, nx in ((0.04, 57), (0.01, 80), (0.0025, 113)):
        doc, _, _ = run_case("contact-lift", mesh=(nx, 1), overrides=dict(delta=delta), steps=2)
        m = doc["steps"][-1]["measures"]
        dl.append(abs(m["l_error_formula"]))
        dF.append(abs(m["F_error_formula"]))
    assert dl[0] > dl[1] > dl[2] and dF[0] > dF[1] > dF[2], (dl, dF)
    assert dl[1] < 0.01 and dF[1] < 0.01


def test_lift_against_the_elastica_at_large_deflection(lift_large):
    doc, res, prob = lift_large
    m = doc["steps"][-1]["measures"]
    assert abs(m["delta"] - 0.2) < 1e-12 and m["elastica_interpolated"] is False
    assert abs(m["l_error_elastica"]) < 0.005 and abs(m["F_error_elastica"]) < 0.005
    assert abs(m["end_angle"] / m["end_angle_elastica"] - 1) < 0.005
    assert m["l_error_formula"] > 0.02                   # far beyond small deflection


def test_propped_against_the_formula(propped):
    doc, res, prob = propped
    for s in doc["steps"][1:]:
        m = s["measures"]
        if m["R_formula"] == 0:
            assert m["R"] == 0 and not m["nodes_with_force"]       # no contact before lam = 1/2
        else:
            assert abs(m["R_error"]) < 0.01
            assert set(m["nodes_with_force"]) == set(m["tip_nodes"])   # the tip only
            assert m["min_gap_off_tip"] > 0
    assert abs(doc["steps"][-1]["measures"]["R_error"]) < 0.01         # g / L = 0.01 at lam = 1


@pytest.mark.parametrize("which", ["lift", "lift_large", "propped"])
def test_penetration_and_balance(which, request):
    doc, res, prob = request.getfixturevalue(which)
    c = [ld for ld in prob.loads if isinstance(ld, ContactLoad)][0]
    for st, rec in zip(res.steps[1:], doc["steps"][1:]):
        assert st.contact[c.name]["penetration"] <= c.tol               # 1e-6 h
        assert st.balance_error < 1e-8                                   # applied + reactions + contact
        assert np.allclose(rec["contact"][c.name]["force"], st.contact[c.name]["force"])
    # the balance check means what it says: without the contact forces it fails
    st = res.final
    F = st.reaction_force + st.applied_force
    assert np.linalg.norm(F) > 0.5 * np.linalg.norm(st.contact[c.name]["force"])


def test_quadratic_convergence_once_the_active_set_is_fixed(lift):
    """Newton (displacement iteration) from the converged lift with its multipliers, to a lift 2 %
    higher: the active set does not change, and once the residual is below 1e-2 each next one is
    below 10 r^2 or at the round-off floor."""
    import types
    from core_se3.results import restore_multipliers
    from core_se3.solvers import NewtonOptions, make_solver
    from core_se3.solvers.newton_try import NewtonTry
    doc, res, prob = lift
    restore_multipliers(prob, res.final)
    c = [ld for ld in prob.loads if isinstance(ld, ContactLoad)][0]
    t = NewtonTry(prob, NewtonOptions(rtol=1e-14, dtol=1e-14, max_iter=12), make_solver("auto"),
                  types.SimpleNamespace(t_asm=0.0, t_sol=0.0))
    active = c.state(res.final.g, 1.0)[4] > 0
    out = t.run(prob.apply_prescribed(res.final.g.copy(), 1.02), 1.02, False, None)
    assert out.ok and np.array_equal(c.state(out.g, 1.02)[4] > 0, active)
    r = out.hist
    pairs = [(a, b) for a, b in zip(r, r[1:]) if a < 1e-2]
    assert pairs and all(b < 10 * a * a or b < 1e-8 for a, b in pairs), r


def test_gripper_grasp_converges_without_step_tuning():
    doc, res, prob = run_case("magnetic-gripper-grasp")
    assert len(res.steps) == 21 and abs(res.final.load_factor - 1) < 1e-12
    m = doc["steps"][-1]["measures"]
    assert m["nodes_in_contact"] + m["faces_in_contact"] >= 4 and np.linalg.norm(m["force_on_sphere"]) > 0
    assert all(s["balance_error"] < 1e-8 for s in doc["steps"][1:])
    assert m["penetration"] <= [ld for ld in prob.loads if isinstance(ld, ContactLoad)][0].tol
    assert doc["timings"]["total"] < 60


# ----------------------------------------------------------------------------- solver hooks
def test_no_hooks_no_change():
    """A problem without contact never calls the hooks: the log entries carry no augmentation."""
    p = cs.Problem(M.rectangle(10.0, 1.0, 4, 1), cs.Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0, 0, 1.0))
    res = p.solve(steps=2)
    assert all("augmented" not in e for e in res.log) and res.final.contact == {}


def test_augmentations_are_counted_and_failures_restore_the_multipliers():
    doc, res, prob = run_case("contact-propped", steps=10)
    aug = [e for e in res.log if e.get("augmented")]
    tries = sum(s.attempts for s in res.steps)
    assert tries == len(res.log) and sum(s.linear_solves for s in res.steps) == sum(e["linear_solves"] for e in res.log)
    # first contact without cut-backs: the new contact meets a soft penalty (soft_start; 4 failed
    # tries before it)
    assert all(e["converged"] for e in res.log)
    assert len(aug) >= 1
    # no augmentation allowed: every try fails on its gap error, and the multipliers are restored
    from core_se3.catalogue import build_problem, case_params, get_case
    case = get_case("contact-lift")
    prob = build_problem(case, case_params(case))
    c = [ld for ld in prob.loads if isinstance(ld, ContactLoad)][0]
    with pytest.raises(cs.ConvergenceError, match="multiplier updates"):
        prob.solve(steps=2, max_augmentations=0, max_cutbacks=1, predictor="tangent")
    assert np.array_equal(c.multipliers(), np.concatenate([c.lam0, c.soft0]))


def test_arc_length_refuses_contact():
    p = cs.Problem(M.rectangle(1.0, 0.2, 4, 1), cs.Material(1e4, 0.0, 0.02))
    p.clamp("x0")
    p.add_pressure(-0.004)
    p.add_obstacle("half_space", point=(0, 0, -0.05), normal=(0, 0, 1))
    with pytest.raises(cs.CoreSE3Error, match="path following"):
        p.solve(control="arclength")


# ----------------------------------------------------------------------------- front door
BASE = """
[mesh]
generator = "rectangle"
L = 10.0
width = 1.0
nx = 8
ny = 1
[material]
E = 1.2e6
nu = 0.0
h = 0.1
[[supports]]
type = "clamp"
edge = "x0"
[[loads]]
type = "edge_force"
edge = "x1"
force = [0.0, 0.0, -0.5]
[solver]
steps = 2
"""


@pytest.mark.parametrize("entry,key,message", [
    ('type = "sphere"\ncentre = [5.0, 0.0, -1.0]\nradius = 1.0', "obstacles[0]", "already intersects the undeformed shell"),
    ('type = "sphere"\ncentre = [5.0, 0.0, -2.0]\nradius = -1.0', "obstacles[0].radius", "expected a number > 0"),
    ('type = "sphere"\ncentre = [5.0, 0.0, nan]\nradius = 1.0', "obstacles[0].centre", "expected finite numbers"),
    ('type = "cylinder"\npoint = [5.0, 0.0, -2.0]\naxis = [0.0, 1.0, 0.0]\nradius = inf', "obstacles[0].radius",
     "expected a finite number"),
    ('type = "sphre"\ncentre = [5.0, 0.0, -2.0]\nradius = 1.0', "obstacles[0].type", "did you mean 'sphere'"),
    ('type = "box"\ncentre = [5.0, 0.0, -2.0]\nhalf_sizes = [1.0, 1.0, 0.0]', "obstacles[0].half_sizes",
     "must be positive"),
    ('type = "sphere"\ncentre = [5.0, 0.0, -2.0]\nradius = 1.0\nradus = 1.0', "obstacles[0].radus",
     "did you mean 'radius'"),
    ('type = "sphere"\ncentre = [5.0, 0.0, -2.0]\nradius = 1.0\nmode = "barrier"', "obstacles[0].mode",
     "unknown value 'barrier'"),
    # an angle without its axis was dropped: the obstacle only translated
    ('type = "box"\ncentre = [5.0, 0.0, -2.0]\nhalf_sizes = [1.0, 1.0, 1.0]\n'
     'motion = {translate = [0.0, 0.0, 0.5], angle = 0.5}', "obstacles[0].motion.axis", "needs its rotation 'axis'"),
    ('type = "sphere"\ncentre = [5.0, 0.0, -2.0]\nradius = 1.0\nfaces = 1', "obstacles[0].faces",
     'expected true, false or "auto", got 1'),
    ('type = "sphere"\ncentre = [5.0, 0.0, -2.0]\nradius = 1.0\nfaces = "yes"', "obstacles[0].faces",
     'expected true, false or "auto"'),
])
def test_scenario_validation_errors(entry, key, message):
    with pytest.raises(ScenarioError) as exc:
        scenario.loads(BASE + "[[obstacles]]\n" + entry + "\n", file="grasp.toml")
    assert exc.value.file == "grasp.toml" and exc.value.key == key and message in str(exc.value)


@pytest.mark.parametrize("faces", [True, False, "auto"])
def test_a_scenarios_faces_key_reaches_the_contact_law(faces):
    """The contact warnings (face_cut, an obstacle smaller than the elements) ask for `faces =
    true`; the scenario file refused that key ("unknown key 'faces'"), so a file's user could not
    follow them.  Now [[obstacles]] faces = true / false / "auto" is the law's ``faces``."""
    value = {True: "true", False: "false", "auto": '"auto"'}[faces]
    scn = scenario.loads(BASE + '[[obstacles]]\ntype = "sphere"\ncentre = [5.0, 0.0, -2.0]\nradius = 1.0\n'
                         + f"faces = {value}\n", file="grasp.toml")
    ld = next(ld for ld in scn.problem.loads if hasattr(ld, "law"))
    assert ld.law.faces is faces or ld.law.faces == faces


def test_a_failed_runs_last_vtu_has_the_contact_forces_of_its_step(tmp_path):
    """A step that fails after converging sub-steps (1.5 -> 1e5: it got to 1025) moved the contact
    multipliers on; the VTU file of the last converged step, written when the run fails, showed
    them: contact_force summed to 512.8 where results.json has the step's 0.675.  Now the step's
    multipliers are set again first."""
    import meshio
    text = BASE.replace("steps = 2", "load_factors = [0.5, 1.0, 1.5, 1e5]\nmax_cutbacks = 0\nmax_iter = 8") + """
[output]
vtu_every = 10
plots = false
picture = false
[[obstacles]]
type = "half_space"
name = "floor"
point = [0.0, 0.0, -0.3]
normal = [0.0, 0.0, 1.0]
"""
    with pytest.raises(ConvergenceError, match="step 4 .* failed"):
        scenario.run(scenario.loads(text, file="floor.toml"), out=str(tmp_path / "o"))
    doc = json.load(open(tmp_path / "o" / "results.json"))
    last = doc["steps"][-1]
    assert doc["status"] == "failed" and last["step"] == 3 and last["contact"]["floor"]["force"][2] > 0.5
    v = meshio.read(str(tmp_path / "o" / "vtu" / "step_0003.vtu"))
    assert v.point_data["contact_force"][:, 2].sum() == pytest.approx(last["contact"]["floor"]["force"][2], rel=1e-12)


def test_obstacles_of_one_vtu_field_name_are_refused():
    """Obstacles 'floor a' and 'floor_a' both write contact_gap_floor_a: the VTU summed the two
    gaps (floor plus sphere distance at every node) under one name.  Refused, naming both."""
    two = BASE + """[[obstacles]]
type = "half_space"
name = "floor a"
point = [0.0, 0.0, -0.3]
normal = [0.0, 0.0, 1.0]
[[obstacles]]
type = "sphere"
name = "{}"
centre = [5.0, 0.0, 3.0]
radius = 1.0
"""
    with pytest.raises(ScenarioError, match=r"\[obstacles\[1\].name\]: obstacles 'floor a' and 'floor_a' have one VTU "
                                            r"field name, contact_gap_floor_a"):
        scenario.loads(two.format("floor_a"), file="f.toml")
    assert len(scenario.loads(two.format("ball"), file="f.toml").spec["obstacles"]) == 2


def test_python_obstacles_of_one_vtu_field_name_are_refused():
    """Problem.add_obstacle took 'floor a' and 'floor_a': contact_gap_floor_a read 3.07 at the
    flat plate's corner nodes, the floor's gap 0.995 plus the sphere's 2.077.  The check of the
    scenario's [[obstacles]] now holds for the Python API too (one helper)."""
    p = cs.Problem(M.rectangle(1.0, 1.0, 2, 1), cs.Material(1e3, 0.0, 0.01))
    p.add_obstacle("half_space", point=(0, 0, -1), normal=(0, 0, 1), name="floor a")
    with pytest.raises(ContactError, match=r"obstacles 'floor a' and 'floor_a' have one VTU field name, "
                                           r"contact_gap_floor_a") as ei:
        p.add_obstacle("sphere", centre=(0.5, 0.0, 3.0), radius=1.0, name="floor_a")
    assert ei.value.param == "name" and len(p.loads) == 1
    p.add_obstacle("sphere", centre=(0.5, 0.0, 3.0), radius=1.0, name="ball")
    gap = p.output_fields(p.mesh.g0, 1.0)["contact_gap_floor_a"]          # 1 - h/2 from the mid-surface
    np.testing.assert_allclose(gap, 0.995, rtol=0, atol=1e-12)


def test_python_api_errors():
    p = cs.Problem(M.rectangle(1.0, 1.0, 2, 1), cs.Material(1e3, 0.0, 0.01))
    with pytest.raises(ContactError, match="already intersects"):
        p.add_obstacle("sphere", centre=(0.5, 0.0, 0.0), radius=0.2)    # between the nodes
    with pytest.raises(ContactError, match="no parameter 'radus'"):
        p.add_obstacle("sphere", centre=(0.5, 0.0, 1.0), radus=0.2)
    with pytest.raises(ContactError, match="unknown obstacle kind"):
        p.add_obstacle("torus", centre=(0.5, 0.0, 1.0))
    p.add_obstacle("half_space", point=(0, 0, -1), normal=(0, 0, 1))
    with pytest.raises(ContactError, match="already an obstacle named"):
        p.add_obstacle("half_space", point=(0, 0, -2), normal=(0, 0, 1))


def test_a_ball_between_the_check_points_of_an_element_is_found_at_load_0():
    """A ball of radius 0.05 through the 1 x 1 element of a plate (h 0.01) at (0.25, 0.25),
    between the 3 x 3 points of the check of the undeformed shell (0.35 away from the nearest):
    accepted before, the solve then ended with zero force, penetration 0 and the ball through the
    plate.  The check takes each face's deepest point too: the ball lies 0.045 inside the face."""
    p = cs.Problem(M.rectangle(1.0, 1.0, 1, 1), cs.Material(1e4, 0.0, 0.01))
    with pytest.raises(ContactError, match="already intersects .* element 0 lies 0.045 inside"):
        p.add_obstacle("sphere", centre=(0.25, 0.25, 0.0), radius=0.05, name="ball")
    p.add_obstacle("sphere", centre=(0.25, 0.25, -0.06), radius=0.05, name="below")     # clear: 0.005 away


def test_a_shell_pinched_between_two_obstacles_is_named():
    """A strip (h 0.01) on a floor under a ball that comes down 0.002 from 0.001 above node 17: from
    load factor 0.5 on the room between the two is less than h, and no state exists (the shell is
    not squeezed through its thickness).  The run stopped with "raise max_augmentations or the
    tolerance", which cannot help; now the hint names the node and the two obstacles."""
    h = 0.01
    p = cs.Problem(M.rectangle(0.5, 0.1, 10, 2), cs.Material(1e5, 0.0, h))
    p.clamp("x0")
    p.add_obstacle("half_space", point=(0, 0, -h / 2), normal=(0, 0, 1), name="floor")
    p.add_obstacle("sphere", centre=(0.3, 0, h / 2 + 0.201), radius=0.2, name="lid",
                   motion=dict(translate=(0, 0, -0.002)))
    with pytest.raises(cs.ConvergenceError, match="node 17 is pinched between obstacles '(floor|lid)' and "
                                                  "'(floor|lid)': the room between them there is 0.0099"):
        p.solve(steps=2)


def test_a_ball_too_large_for_the_round_off_is_named():
    """A ball of radius 1e5 under the tip of a strip (h 0.01, tol 1e-8) that a pressure bends onto
    it: d = |y - centre| - R carries a round-off of 1e5 * 2.2e-16 = 2.2e-11, which the contact
    stiffness turns into residual noise (the tangent 1.8e-3 off central differences at first
    contact; a half-space at the same place converges in 10 steps, balance 1.5e-11).  The run
    stopped with a bare "no convergence in 30 iterations"; now the hint names the round-off and
    the half-space."""
    p = cs.Problem(M.rectangle(1.0, 0.05, 40, 1), cs.Material(1.2e6, 0.0, 0.01))
    p.clamp("x0")
    p.add_pressure(0.016, direction=(0, 0, -1))
    p.add_obstacle("sphere", centre=(1.0, 0, -0.015 - 1e5), radius=1e5, name="o")
    with pytest.raises(cs.ConvergenceError, match="centre lies 1e\\+05 from the contact nodes, so its distances carry "
                                                  "a round-off of 2.2e-11 .* use a half_space"):
        p.solve(steps=10)


def test_scenario_run_writes_contact_outputs(tmp_path):
    text = BASE + """
[[obstacles]]
type = "half_space"
name = "floor"
point = [0.0, 0.0, -1.0]
normal = [0.0, 0.0, 1.0]
"""
    scn = scenario.loads(text, file="floor.toml")
    res = scenario.run(scn, out=str(tmp_path / "o"))
    doc = json.load(open(res.files["results"]))
    last = doc["steps"][-1]
    assert last["contact"]["floor"]["force"][2] > 0 and last["balance_error"] < 1e-8
    vtu = tmp_path / "o" / "vtu"
    assert (vtu / "obstacles.pvd").exists() and (vtu / "step_0002_obstacles.vtu").exists()
    import meshio
    v = meshio.read(str(vtu / "step_0002.vtu"))
    F = v.point_data["contact_force"]
    assert abs(F[:, 2].sum() - last["contact"]["floor"]["force"][2]) < 1e-12 and "contact_gap_floor" in v.point_data
    assert os.path.getsize(res.files["picture"]) > 0


# ----------------------------------------------------------------------------- references
def _elastica_script():
    spec = importlib.util.spec_from_file_location("contact_lift_elastica",
                                                  os.path.join(ROOT, "benchmarks", "contact_lift_elastica.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_elastica_reference_two_methods_and_the_packaged_table():
    mod = _elastica_script()
    for d in (0.05, 1.0):
        a, b = mod.shoot(d), mod.collocate(d)
        assert abs(a["l"] - b["l"]) < 1e-8 and abs(a["F"] - b["F"]) < 1e-8
    a = mod.shoot(1e-4)                                          # small-deflection limit
    assert abs(a["l"] / (24e-4) ** 0.25 - 1) < 1e-3 and abs(a["F"] / a["l"] - 0.5) < 1e-3
    tab = contact_lift_elastica()
    row = [r for r in tab["rows"] if r["delta_over_L"] == 0.2][0]
    mine = mod.shoot(0.2 * tab["params"]["Q"] ** (1 / 3))
    assert abs(mine["l"] / tab["params"]["Q"] ** (1 / 3) - row["l_over_L"]) < 1e-10
    assert "benchmarks/contact_lift_elastica.py" in tab["source"]


def test_gap_estimator_between_nodes():
    ql, EI, l = 0.1, 0.005, 0.3137
    xc = np.linspace(0, 1, 61)
    s = l - xc
    gap = np.where(s > 0, ql / (24 * EI) * s ** 3 * (2 * l - s), 0.0)
    xd, nfit = lifted_length_from_gaps(xc, gap, np.where(s > 0, 0.0, 1.0))
    assert abs(xd - l) < 1e-6 * l and nfit >= 4


def test_a_motion_angle_without_its_axis_is_refused():
    """motion=dict(translate=..., angle=...) with no axis turned nothing (T(1) a pure translation,
    the angle silently dropped); a misspelt motion key was a bare TypeError.  Both now name the key."""
    p = cs.Problem(M.rectangle(1.0, 0.05, 4, 1), cs.Material(1.2e6, 0.0, 0.01))
    with pytest.raises(ContactError, match="angle 0.5 needs its rotation axis") as exc:
        p.add_obstacle("box", centre=(0.5, 0, -1), half_sizes=(0.2, 0.2, 0.2),
                       motion=dict(translate=(0, 0, 0.1), angle=0.5))
    assert exc.value.param == "axis"
    with pytest.raises(ContactError, match="unknown motion key 'translation'; did you mean 'translate'") as exc:
        p.add_obstacle("box", centre=(0.5, 0, -1), half_sizes=(0.2, 0.2, 0.2), motion=dict(translation=(0, 0, 0.1)))
    assert exc.value.param == "translation"


def test_side_and_friction_take_what_they_mean():
    """side = 'bottom' (the scenario file's word) was a bare ValueError, side = True was taken as
    +1 (the top face) and friction = True as mu = 1, silently; now the names of [[obstacles]]
    side are accepted and the others are ContactErrors naming the key."""
    p = cs.Problem(M.rectangle(1.0, 0.05, 4, 1), cs.Material(1.2e6, 0.0, 0.01))
    floor = dict(point=(0, 0, -0.5), normal=(0, 0, 1))
    assert np.all(p.add_obstacle("half_space", side="bottom", name="a", **floor).side == -1.0)
    assert np.all(p.add_obstacle("half_space", side="mid", name="b", **floor).side == 0.0)
    for bad in ("Auto", True, None):
        with pytest.raises(ContactError, match="side must be one of 'auto', 'top', 'bottom', 'mid'") as exc:
            p.add_obstacle("half_space", side=bad, name="c", **floor)
        assert exc.value.param == "side"
    for bad in (True, [0.3], "0.3"):
        with pytest.raises(ContactError, match="friction coefficient must be a number") as exc:
            p.add_obstacle("half_space", friction=bad, name="d", **floor)
        assert exc.value.param == "friction"


def test_renaming_a_shared_obstacle_instance_keeps_the_first_contacts_name():
    """One Obstacle instance added twice (two contacts, e.g. two regions) under two names: the
    second name was written into the shared instance, so the first contact's obstacle -- its
    crossing messages, its surface in vtu/obstacles -- was called by the second's name."""
    from core_se3.model import make_obstacle
    p = cs.Problem(M.rectangle(1.0, 0.05, 4, 1), cs.Material(1.2e6, 0.0, 0.01))
    ob = make_obstacle("half_space", point=(0, 0, -0.5), normal=(0, 0, 1))
    a = p.add_obstacle(ob, name="left")
    b = p.add_obstacle(ob, name="right")
    assert (a.name, a.obstacle.name, b.name, b.obstacle.name, ob.name) == ("left", "left", "right", "right",
                                                                             "half_space")


def test_a_contact_penalty_of_the_wrong_shape_is_a_contact_error_naming_k():
    """law k per node of the wrong length (5 for 6 contact nodes), a 2-D array, a string or a
    bool: a bare NumPy broadcast ValueError, or read as a number ('1e5', True -> 1.0); now a
    ContactError naming the key k and the shape (6,) expected.  A number or (6,) still work.  A bool
    among numbers (NumPy makes [1e5, ..., True] a float array) was read as a penalty of 1.0 on that
    node (docs/CONTACT.md: a bool is a ContactError naming k)."""
    for k in (np.full(5, 1e5), np.full((6, 1), 1e5), np.full((2, 3), 1e5), "1e5", True, [1e5] * 5 + [True]):
        p = cs.Problem(M.rectangle(2.0, 1.0, 2, 1), cs.Material(1e4, 0.0, 0.02))
        with pytest.raises(ContactError, match=r"penalty k must be a number or one per contact node, shape \(6,\)") \
                as err:
            p.add_obstacle("sphere", centre=(1.5, 0.0, -0.5), radius=0.4, law=dict(k=k))
        assert err.value.param == "k"
    for k, first in ((2e5, 2e5), (np.arange(1.0, 7.0) * 1e5, 1e5)):
        p = cs.Problem(M.rectangle(2.0, 1.0, 2, 1), cs.Material(1e4, 0.0, 0.02))
        c = p.add_obstacle("sphere", centre=(1.5, 0.0, -0.5), radius=0.4, law=dict(k=k))
        assert c.k.shape == (6,) and c.k[0] == first



def test_an_obstacle_pressing_into_a_clamped_node_is_named():
    """A plane rising 0.3 under a clamped strip reaches the clamped nodes at load factor 0.317:
    no state has them outside it.  The run stopped with "constraint error 6.84e+03 x its
    tolerance after 25 multiplier updates (raise NewtonOptions.max_augmentations or the
    tolerance)", a fix that cannot help; now the error names the obstacle, the held node and
    the cause."""
    p = cs.Problem(M.rectangle(1.0, 0.1, 20, 1), cs.Material(1e5, 0.0, 0.01))
    p.clamp("x0")
    p.add_obstacle("half_space", point=(0, 0, -0.1), normal=(0, 0, 1), name="lift", motion=dict(translate=(0, 0, 0.3)))
    with pytest.raises(cs.ConvergenceError, match=r"obstacle 'lift' presses .* into node (0|21), whose translations a "
                                                   r"support holds") as exc:
        p.solve(steps=1)
    assert "the last converged load factor is 0.316" in str(exc.value)


def test_a_far_part_with_an_obstacle_names_the_distance_when_newton_stalls():
    """A 1 x 1 plate of 0.25 elements, clamped on two edges and pressed, under a small sphere it
    does not reach: converged at 1e2 and 1e3 from the origin (iterations as at the origin) and
    stalled at the first step from 1e4 on (the obstacle was not translation invariant, so the
    iterate was held in the problem's coordinates: docs/STEPS.md).  The ConvergenceError said only
    'no convergence in 30 iterations (residual 8.06e-04)'; it named the distance, the load and
    the fix.  A built-in obstacle is now evaluated relative to the part (``model.contact_frame``):
    1.15e4 converges as at the origin; the obstacle as a user's SDF of absolute coordinates
    cannot be so, and still stalls with the hint."""
    import warnings
    from core_se3.errors import ConvergenceError
    from core_se3.mesh.core import Mesh
    m0 = M.rectangle(1.0, 1.0, 4, 4)

    def solve(shift, user=False):
        g0 = m0.g0.copy()
        g0[:, :3, 3] += shift
        p = cs.Problem(Mesh(g0=g0, quads=m0.quads, edges=m0.edges, shape=m0.shape), cs.Material(1e4, 0.3, 0.02))
        p.clamp("x0")
        p.clamp("x1")
        p.add_pressure(-3.0)
        centre = np.array([0.40, 0.10, 0.071]) + shift
        if user:
            ball = UserSDF(lambda y: np.linalg.norm(y - centre, axis=1) - 0.06,
                           lambda y: (y - centre) / np.linalg.norm(y - centre, axis=1)[:, None])
            p.add_obstacle(ball, name="ball", law=dict(faces=True))
        else:
            p.add_obstacle("sphere", centre=tuple(centre), radius=0.06, name="ball", law=dict(faces=True))
        return p.solve(steps=2, max_cutbacks=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        its = [s.iterations for s in solve(np.zeros(3)).steps]
        assert [s.iterations for s in solve(np.array([1e3, 5e2, -2.5e2])).steps] == its
        assert [s.iterations for s in solve(np.array([1e4, 5e3, -2.5e3])).steps] == its
        with pytest.raises(ConvergenceError, match=r"the part lies 1\.15e\+04 from the origin .*'ball' \(ContactLoad\) "
                                                   r"is not translation invariant.*near the origin"):
            solve(np.array([1e4, 5e3, -2.5e3]), user=True)


def _far_case(case, shift):
    """(problem, load factors) of a contact case translated by ``shift`` (part, supports, obstacle)."""
    from core_se3.catalogue.cases_friction import PUSH_PARAMS as q, RAMP, push_formula
    from core_se3.mesh.core import Mesh

    def moved(m):
        g0 = m.g0.copy()
        g0[:, :3, 3] += shift
        return Mesh(g0=g0, quads=m.quads, edges=m.edges, shape=m.shape)
    if case == "rough_table":          # test_friction's bar: partial slip on a rough plane
        p = cs.Problem(moved(M.rectangle(1.0, 0.1, 40, 2)), cs.Material(1e5, 0.0, 0.01))
        p.clamp("x0")
        p.add_gravity(rho=1000.0, scale=lambda lam: 1.0)
        p.add_edge_force("x1", (0.6 * 0.5 * 9.81, 0.0, 0.0))
        p.add_obstacle("half_space", point=tuple(np.array([0, 0, -0.005]) + shift), normal=(0, 0, 1), name="ob",
                       friction=0.5)
        return p, [k / 6 for k in range(1, 7)]
    if case == "ball_faces":           # a plate pressed onto a small ball held by its face samples
        p = cs.Problem(moved(M.rectangle(1.0, 1.0, 4, 4)), cs.Material(1e4, 0.3, 0.02))
        p.clamp("x0")
        p.clamp("x1")
        p.add_pressure(-3.0)
        p.add_obstacle("sphere", centre=tuple(np.array([0.5, 0.5, -0.07]) + shift), radius=0.04, name="ob",
                       law=dict(faces=True))
        return p, [0.5, 1.0]
    if case == "tilting_floor":        # a rough floor turning about a (far) axis under a strip lying on it
        p = cs.Problem(moved(M.rectangle(1.0, 0.1, 20, 1)), cs.Material(1e5, 0.0, 0.01))
        p.clamp("x0")
        p.add_gravity(rho=1000.0, scale=lambda lam: 1.0)
        point = tuple(np.array([0.0, 0.0, -0.005]) + shift)
        p.add_obstacle("half_space", point=point, normal=(0, 0, 1), name="ob", friction=0.3,
                       motion=dict(axis=(0, 1, 0), point=point, angle=-0.02))
        return p, [k / 4 for k in range(1, 5)]
    r = push_formula(q)                # friction-pushed-cantilever: a rough wall sliding across the end
    p = cs.Problem(moved(M.rectangle(1.0, 0.1, 40, 1)), cs.Material(q["E"], 0.0, q["h"]))
    p.fix("x0", (1, 2, 3, 4, 5))
    p.add_edge_force("x0", (r["P"], 0.0, 0.0), scale=lambda lam: min(lam / RAMP, 1.0))
    p.add_obstacle("half_space", point=tuple(np.array([1.0, 0, 0]) + shift), normal=(-1.0, 0.0, 0.0), nodes="x1",
                   side=0, name="ob", friction=q["mu"], motion=dict(
                       translate=(0.0, 0.0, r["travel"]), scale=lambda lam: max(0.0, (lam - RAMP) / (1.0 - RAMP))))
    return p, [RAMP / 2, RAMP] + [RAMP + (1 - RAMP) * k / 9 for k in range(1, 10)]


@pytest.mark.parametrize("case", ["rough_table", "ball_faces", "sliding_wall", "tilting_floor"])
def test_contact_far_from_the_origin_is_the_contact_at_the_origin(case):
    """The whole model (part, supports, obstacle, its motion) translated by t = 1e6 L along
    (1, 0.5, -0.25): a rough table under a pulled strip, a ball held by face samples, a rough
    wall sliding across a pushed cantilever, a rough floor turning about an axis through the
    far part.  Contact was not translation invariant, so the iterate of a far part was held in
    absolute positions (eps |t| = 2.5e-10 L): all four stalled at their first step from 1e4 L on
    (the rough table from 1e2 L).  Now load stepping holds it relative to the part with the
    obstacle restated there (``model.contact_frame``; a turning motion conjugated): the same
    iterations and tries per step as at the origin, displacements within eps |t| (measured
    0.27 / 0.18 / 0.23 / 0.23 of it; the final positions are stored to eps |t|) and contact forces
    within eps |t| / |u| of the force (0.12 / 0.014 / 0.11 / 0.19 of it: the obstacle's input is
    rounded to eps |t| too)."""
    import warnings
    t = 1e6 * np.array([1.0, 0.5, -0.25])
    eps_t = np.finfo(float).eps * np.linalg.norm(t)
    out = []
    for shift in (np.zeros(3), t):
        p, lams = _far_case(case, shift)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = p.solve(load_factors=lams)
        st = res.final
        out.append(dict(u=st.g[:, :3, 3] - p.mesh.g0[:, :3, 3], F=np.asarray(st.contact["ob"]["force"]),
                        its=[(s.iterations, s.attempts) for s in res.steps],
                        slips=np.array([s.contact["ob"].get("largest_slip", 0.0) for s in res.steps])))
    near, far = out
    # the stick/slip counts of nodes resting at d = 0 (the clamped ones, at the cold start's
    # pressure) are the round-off's: a slip of 6e-11 (0.25 eps |t|) made two of the tilting
    # floor's slip at 1e6; the slips themselves agree to eps |t|
    assert far["its"] == near["its"] and np.abs(far["slips"] - near["slips"]).max() <= 4 * eps_t
    u_scale = np.abs(near["u"]).max()
    assert np.abs(far["u"] - near["u"]).max() <= 4 * eps_t, np.abs(far["u"] - near["u"]).max() / eps_t
    dF = np.abs(far["F"] - near["F"]).max() / np.abs(near["F"]).max()
    assert dF <= 4 * eps_t / u_scale, dF / (eps_t / u_scale)


@pytest.mark.parametrize("options, match", [
    (dict(motion=dict(axis=(0, 1, 0), angle="abc")), r"a motion's angle must be a finite number \[rad\], got 'abc'"),
    (dict(motion=dict(translate=(0, 0, 1), scale=2.0)), r"a motion's scale must be a function of the load factor"),
    (dict(motion=dict(translate="abc")), r"translation vector must be a finite 3-vector, got 'abc'"),
])
def test_an_obstacle_motion_of_the_wrong_type_is_a_contact_error(options, match):
    """A motion's angle 'abc' was a bare ValueError of float(), a scale of 2.0 a bare TypeError
    ('float' object is not callable) at the first evaluation, a translation 'abc' a bare
    ValueError of NumPy: now ContactErrors naming the key."""
    from core_se3.errors import ContactError
    p = cs.Problem(M.rectangle(10.0, 1.0, 16, 1), cs.Material(E=1.2e6, nu=0.0, h=0.1))
    with pytest.raises(ContactError, match=match):
        p.add_obstacle("sphere", centre=(0.0, 0.0, 11.0), radius=10.0, **options)



@pytest.mark.parametrize("mesh, bore", [
    (M.cylinder_panel(1.0, 0.1, -0.8, 0.8, 4, 1), dict(kind="cylinder", point=(0, 0, 0), axis=(0, 1, 0))),  # 0.4 rad
    (M.hemisphere_quarter(1.0, 60.0, 2, 4), dict(kind="sphere", centre=(0, 0, 0))),     # a cap, 0.26 x 0.39 rad
], ids=["cylinder", "sphere"])
def test_contact_areas_on_curved_elements_are_the_elements_own(mesh, bore):
    """A curved panel pressed by a uniform pressure q into a rigid bore of its own radius (its
    outer face touching it at the nodes) passes the pressure straight on: the contact pressure of
    every node off the support is q, and a penalty k's penetration is q / k.  The nodal areas
    were the bilinear chords' (short by sin(a/2)/(a/2) at a rad per element, while the pressure
    is integrated over the element's own area): pressure and penetration 1.0067 q and 1.0067 q / k
    on the cylinder, 1.0096 to 1.0109 on the cap; now 1 to 4e-5 (the shell's strain under the
    penetration q / k carries the rest).  Flat meshes keep the bilinear areas to the bit."""
    h, q, k = 0.01, 1.0, 1e7
    p = cs.Problem(mesh, cs.Material(E=1e5, nu=0.3, h=h))
    held = np.nonzero(np.abs(mesh.X[:, 0]) < 1e-12)[0] if bore["kind"] == "cylinder" else mesh.node_set("x0")
    p.clamp(held)                                   # the middle generator, the cap's hole: no rigid turn
    p.add_pressure(q, follower=True)                # outward, onto the bore
    bore = dict(bore)
    kind = bore.pop("kind")
    c = p.add_obstacle(kind, radius=1.0 + h / 2, inside=True, name="bore", law=dict(mode="penalty", k=k), **bore)
    st = p.solve(steps=1).final
    P = c.output_fields(st.g, 1.0)["contact_pressure"][c.nodes][~np.isin(c.nodes, held)]
    assert np.abs(P / q - 1).max() < 1e-4
    assert abs(c.penetration(st.g, 1.0) * k / q - 1) < 1e-4
    flat = M.rectangle(1.0, 0.3, 3, 2)
    j0 = cs.model.loads.element_area(cs.Problem(flat, cs.Material(E=1e5, nu=0.3, h=h)), None)
    assert np.array_equal(cs.model.contact_law.nodal_areas(flat, None, j0), cs.model.contact_law.nodal_areas(flat))


@pytest.mark.parametrize("s", [1e-4, 1e-3, 1e3])
def test_a_user_sdfs_difference_hessian_follows_the_length_unit(s):
    """A user SDF without its Hessian takes it by central differences of its gradient.  The step
    was a fixed 1e-6: 1e-6 of a unit sphere but 1e-2 of a sphere of radius 1e-4 (a 0.1 mm ball
    in metres), whose Hessian came out 4.5e-7 off, and round-off at R 500 (7.9e-7).  Now 1e-6 of
    the points' size: within 2e-10 of (I - n n) / |y| at every scale (the unit sphere's 1e-10)."""
    from core_se3.model.obstacle_kinds import UserSDF
    R = 0.5 * s
    sdf = UserSDF(lambda y: np.linalg.norm(y, axis=1) - R, lambda y: y / np.linalg.norm(y, axis=1)[:, None])
    y = np.random.default_rng(1).normal(size=(5, 3))
    y *= (1.3 * R / np.linalg.norm(y, axis=1))[:, None]
    _, n, H = sdf.local(y)
    exact = (np.eye(3) - n[:, :, None] * n[:, None, :]) / np.linalg.norm(y, axis=1)[:, None, None]
    assert np.abs(H - exact).max() <= 2e-10 * np.abs(exact).max()


def test_a_large_obstacle_s_edge_cutting_the_faces_between_nodes_is_reported_and_warned():
    """A box (half sizes 0.6 x 0.8 x 0.6, turned 45 deg about y: an edge up, default rounding)
    pressed 0.1 into a 2 x 1 plate clamped at both ends (8 x 4, h 0.02), its edge at x = 0.8
    between the node lines x = 0.75 and 1.0: no face samples ('auto': the box is thicker than an
    element), so the plate rests on the box's sides at its nodes and the edge ends 0.037 (1.8 h)
    inside the faces between them.  Before, the results said penetration 1.4e-9 and nothing
    else; now ``face_cut`` reports the faces' deepest point and an AccuracyWarning names faces =
    true (with it the same run reports penetration 4.4e-4, in 51 s instead of 0.6 s)."""
    from core_se3.errors import AccuracyWarning
    a, h = 0.6, 0.02
    p = cs.Problem(M.rectangle(2.0, 1.0, 8, 4), cs.Material(1e4, 0.3, h))
    p.clamp("x0"), p.clamp("x1")
    p.add_obstacle("box", centre=(0.8, 0.0, -0.01 - a * np.sqrt(2)), half_sizes=(a, 0.8, a),
                   rotation=(0, np.pi / 4, 0), motion=dict(translate=(0, 0, 0.11)), name="edge")
    with pytest.warns(AccuracyWarning, match=r"cuts .* into the shell's contact faces between their nodes"):
        st = p.solve(steps=4).final
    c = st.contact["edge"]
    assert c["penetration"] < 1e-6 and c["face_cut"] > h          # measured 1.4e-9 and 0.037

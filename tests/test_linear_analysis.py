"""Linear analysis (``Problem.solve_linear``) against the nonlinear solve at a tiny load, scaled:
prescribed rigid motions and penalty springs (review findings; each test fails on the code before)."""
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh

pytestmark = pytest.mark.core

def _strip(build):
    p = Problem(mesh.rectangle(10.0, 1.0, 16, 2), Material(1.2e6, 0.3, 0.1))
    p.add_probe("tip", "x1")
    build(p)
    return p


def _linear_and_scaled(build, eps=1e-5):
    lin = _strip(build).solve_linear().final
    nl = _strip(build).solve(steps=1, lam_end=eps, rtol=1e-13).final
    return lin, nl, eps


def test_a_rotated_end_is_the_linearised_rigid_turn_not_its_chord():
    # clamp x0, turn x1 by 0.3 rad about y through the origin: the linear tip motion is
    # omega x X = (0, 0, -3); the old code prescribed the chord (cos 0.3 - 1, 0, -sin 0.3) * 10 =
    # (-0.447, 0, -2.955), pulling the end in by 4.5 % of L (an axial force of E h b 0.0447 = 5.4e3)
    lin, nl, eps = _linear_and_scaled(lambda p: (p.clamp("x0"), p.rotate_edge("x1", (0, 1, 0), 0.3)))
    u_lin, u_nl = lin.probes["tip"]["u"], nl.probes["tip"]["u"] / eps
    assert np.allclose(u_lin, [0.0, 0.0, -3.0], atol=1e-12)
    assert np.allclose(u_lin, u_nl, atol=1e-4)
    assert np.allclose(lin.probes["tip"]["rotation_vector"], [0.0, 0.3, 0.0], atol=1e-12)


def test_a_rigidly_moved_free_strip_is_unstrained():
    # the whole strip carried by its end's rigid twist (0.4 rad about x) and lift: no strain
    # energy (the chord strained the end: the old energy was 92.5)
    p = _strip(lambda p: p.move_edge("x0", translate=(0.0, 0.0, 0.2), axis=(1, 0, 0), angle=0.4))
    res = p.solve_linear()
    assert res.log[-1]["energy"] < 1e-16
    assert np.allclose(res.final.probes["tip"]["u"], [0.0, 0.0, 0.2], atol=1e-10)


@pytest.mark.parametrize("spring", ["lab", "tilt", "rotation_component"])
def test_penalty_springs_count_with_the_applied_loads_and_the_step_balances(spring):
    # the springs' linear forces K_s eta were counted as internal forces: the applied totals
    # missed them (lab spring: 1 instead of 1e-4) and the step did not balance (balance_error
    # 1.0 for the lab spring, 0.109 for the tilt and rotation-component springs)
    add = {"lab": lambda p: p.add_lab_support("x1", [(0.0, 0.0, 1.0)], 1e3),
           "tilt": lambda p: p.add_lab_tilt_support("x1", [(1.0, 0.0, 0.0)], 1e3),
           "rotation_component": lambda p: p.add_rotation_component_support("x1", (0.0, 1.0, 0.0), 1e3)}[spring]
    lin, nl, eps = _linear_and_scaled(lambda p: (p.clamp("x0"), add(p), p.add_edge_force("x1", (0.0, 0.0, 1.0))))
    assert lin.balance_error < 1e-9
    assert np.allclose(lin.applied_force, nl.applied_force / eps, rtol=1e-4, atol=1e-6)
    assert np.allclose(lin.applied_moment, nl.applied_moment / eps, rtol=1e-4, atol=1e-6)
    # the nonlinear reactions carry the round-off of r_int - f_ext at the clamp, ~1e-11 absolute
    # whatever the load (x: -5.7e-12, -1.0e-11, 1.6e-14 at eps = 1e-4, 1e-5, 1e-6): 1e-6 of
    # the unit load once divided by eps = 1e-5, which atol = 1e-6 did not allow
    assert np.allclose(lin.reaction_force, nl.reaction_force / eps, rtol=1e-4, atol=1e-5)


def test_the_linear_cell_fields_are_those_of_the_linear_strains(tmp_path):
    # a cantilever under an end shear, linear tip deflection L/3: the strains of its linear
    # state g0 (exp(w), v) stretch the chords, and the VTU's membrane force N11 read 1.4e4 at
    # the tip element (the shear force is 1, the linear N11 0); the linear fields are the
    # nonlinear ones at a tiny load, scaled
    import meshio
    from core_se3 import scenario
    from core_se3.solvers.linear import linear_increments
    p = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0))
    g = p.solve_linear().final.g
    lin = p.element.cell_fields(g, increments=linear_increments(p.mesh.g0, g))
    eps = 1e-5
    q = Problem(mesh.rectangle(10.0, 1.0, 16, 1), Material(1.2e6, 0.0, 0.1))
    q.clamp("x0")
    q.add_edge_force("x1", (0.0, 0.0, 1.0))
    small = q.element.cell_fields(q.solve(steps=1, lam_end=eps, rtol=1e-13).final.g)
    for k in ("N1", "M1", "N1_local", "M1_local"):
        assert np.allclose(lin[k], small[k] / eps, rtol=0, atol=1e-4 * np.abs(lin[k]).max())
    assert np.allclose(lin["N1_local"], [0.0, 0.0, 1.0], atol=1e-9)
    doc = {"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 16, "ny": 1},
           "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
           "solver": {"control": "linear"}}
    res = scenario.run(scenario.from_dict(doc), str(tmp_path / "run"))
    vtu = meshio.read(str(tmp_path / "run" / "vtu" / "step_0001.vtu"))
    assert np.allclose(vtu.cell_data["N1_local"][0], lin["N1_local"], atol=1e-9)
    assert res is not None


def _cantilever(load, scale, backend="numpy"):
    """A cantilever strip under one load at the given scale (None: the default s = lam)."""
    from core_se3.model import UniformField
    p = Problem(mesh.rectangle(10.0, 1.0, 16, 2), Material(1.2e6, 0.3, 0.1), backend=backend)
    p.add_probe("tip", "x1")
    p.clamp("x0")
    if load == "follower pressure":
        p.add_pressure(2.0, follower=True, scale=scale)
    elif load == "dead pressure":
        p.add_pressure(2.0, scale=scale)
    elif load == "dead edge force":
        p.add_edge_force("x1", (0.0, 0.0, 1.0), scale=scale)
    else:                                   # a magnet's body couple in a uniform field
        p.add_magnetic((0.0, 0.0, 1.0), UniformField((1.0, 0.0, 1.0), scale=scale), mu0=1.0)
    return p


@pytest.mark.parametrize("load", ["follower pressure", "dead pressure", "dead edge force", "magnet"])
@pytest.mark.parametrize("scale", ["constant", "table"])
def test_the_linear_answer_does_not_depend_on_the_scale_at_lam_zero(load, scale):
    # K0 = dr/deta at (g0, lam = 0) held the stiffness of the loads whose scale is not 0 at
    # lam = 0 (scale "constant", a table from s(0) = 0.5): the follower pressure's (its normal
    # turning with the shell), the magnet's body couple's, and a dead load's (its lab force in
    # the turning body frame, -hat(R^T F)); the answer depended on s(0) and was not linear in
    # the load.  At lam_end = 1 the loads are equal (s(1) = 1), so the linear answers are: the
    # old code took 3.8 % off the magnet's tip deflection (0.3164 for 0.3290, "constant") and
    # moved the tip sideways by 2.5e-3 (dead pressure), 5.5e-6 (follower pressure), 4.1e-5
    # (dead edge force), where the linear answer has no sideways motion
    s = (lambda lam: 1.0) if scale == "constant" else (lambda lam: 0.5 + 0.5 * lam)
    ref = _cantilever(load, None).solve_linear().final
    got = _cantilever(load, s).solve_linear().final
    assert np.abs(ref.probes["tip"]["u"]).max() > 0.1
    assert np.array_equal(got.g, ref.g)                 # the NumPy path: bit for bit
    assert np.array_equal(got.probes["tip"]["u"], ref.probes["tip"]["u"])


@pytest.mark.parametrize("load", ["follower pressure", "dead pressure", "magnet"])
def test_default_scaled_loads_keep_the_tangent_at_lam_zero_as_k0(load):
    # with s(lam) = lam (s(0) = 0) the loads' geometric stiffness is zero at lam = 0: K0 is the
    # problem's own tangent at (g0, 0) bit for bit, as before the rule was written out; with
    # s(0) != 0 it is that K0 too (the loads' stiffness left out), not the tangent at (g0, 0)
    from core_se3.assembly import Assembler
    from core_se3.solvers.linear import reference_stiffness
    p = _cantilever(load, None)
    every = Assembler(p.mesh, np.ones(6 * p.mesh.n_nodes, bool))
    K0, Ks = reference_stiffness(p, every)
    assert (K0 != p.evaluate(p.mesh.g0, 0.0, assembler=every).K).nnz == 0
    assert abs(Ks).max() == 0.0
    q = _cantilever(load, lambda lam: 1.0)
    assert (reference_stiffness(q, every)[0] != K0).nnz == 0
    assert (q.evaluate(q.mesh.g0, 0.0, assembler=every).K != K0).nnz > 0


def _tip_loaded_strip():
    p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1e-3))
    p.add_probe("tip", "x1")
    return p


@pytest.mark.parametrize("call", ["solve_linear", "solve"])
def test_load_stepping_options_of_a_linear_analysis_are_named_not_dropped(call):
    # steps=10 and max_cutbacks=3 were dropped without a word (one solve at lam_end either
    # way); a scenario file warns of [solver] steps with control = "linear", and so does Python
    from core_se3.errors import OptionWarning
    p = _tip_loaded_strip()
    solve = p.solve_linear if call == "solve_linear" else (lambda **kw: p.solve(control="linear", **kw))
    with pytest.warns(OptionWarning) as said:
        res = solve(steps=10, max_cutbacks=3)
    assert len(said) == 1
    text = str(said[0].message)
    assert "steps=10, max_cutbacks=3 not used" in text and "one solve at lam_end" in text
    assert "control='load'" in text
    assert len(res.steps) == 2                                  # one solve all the same


def test_linear_solve_called_directly_names_its_unused_options_once():
    # solvers.linear_solve(p, steps=10, max_cutbacks=3) dropped them without a word (only
    # Problem.solve warned); it now warns itself, once, pointing at the caller's line, and
    # Problem.solve does not warn a second time
    from core_se3.errors import OptionWarning
    from core_se3.solvers import linear_solve
    p = _tip_loaded_strip()
    for call in (lambda: linear_solve(p, steps=10, max_cutbacks=3),
                 lambda: p.solve(control="linear", steps=10, max_cutbacks=3)):
        with pytest.warns(OptionWarning) as said:
            call()
        assert len(said) == 1 and "steps=10, max_cutbacks=3 not used" in str(said[0].message)
        assert said[0].filename == __file__


def test_a_linear_analysis_is_quiet_for_one_step_and_for_the_problem_s_defaults():
    # steps=1, the linear solver and lam_end are used or harmless; the problem's own defaults
    # (a scenario's or a catalogue case's [solver], steps = 20 included) do not warn
    import warnings
    p = _tip_loaded_strip()
    p.solve_defaults = dict(steps=20, max_cutbacks=4, rtol=1e-8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        u1 = p.solve_linear(steps=1, linear_solver="superlu", lam_end=2.0).final.probes["tip"]["u"]
        u2 = p.solve(control="linear", lam_end=2.0, max_cutbacks=12, linear_solver="superlu").final.probes["tip"]["u"]
    assert np.array_equal(u1, u2)


def _turned_by_prescribe(angle):
    """The strip clamped at x0, its x1 end turned rigidly about y through the origin by
    angle * lam, given as a target of Problem.prescribe (its frames), not as rotate_edge."""
    from core_se3 import lie

    def build(p):
        nodes = p.nodes("x1")
        X = p.mesh.g0[nodes]

        def target(lam):
            Q = np.eye(4)
            Q[:3, :3] = lie.exp_so3([0.0, angle * lam, 0.0])
            return Q @ X
        p.clamp("x0")
        p.prescribe("x1", target)
    return _strip(build)


def test_a_prescribed_target_not_linear_in_the_load_factor_is_named():
    # the same turn as test_a_rotated_end_is_the_linearised_rigid_turn_not_its_chord, given as a
    # target: linear analysis holds its chord (the end pulled in by 4.5 % of L), silently; now an
    # AccuracyWarning says the motion is not linear in lam and names rotate_edge / move_edge
    from core_se3.errors import AccuracyWarning
    with pytest.warns(AccuracyWarning) as said:
        lin = _turned_by_prescribe(0.3).solve_linear().final
    assert len(said) == 1
    text = str(said[0].message)
    assert "support 1 (prescribe, 3 node(s)) prescribes a motion that is not linear in the load factor" in text
    assert "rotate_edge or move_edge" in text and "control='load'" in text
    assert lin.probes["tip"]["u"][0] == pytest.approx(10.0 * (np.cos(0.3) - 1.0), rel=1e-12)   # the chord, as said


def test_a_prescribed_target_linear_in_the_load_factor_is_quiet():
    # a lift linear in lam: its chord is its linearisation, as move_edge's; rotate_edge and
    # move_edge are linearised exactly and never warn
    import warnings

    def lift(p):
        nodes = p.nodes("x1")
        X = p.mesh.g0[nodes]

        def target(lam):
            g = X.copy()
            g[:, 2, 3] += 0.1 * lam
            return g
        p.clamp("x0")
        p.prescribe("x1", target)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        u = _strip(lift).solve_linear().final.probes["tip"]["u"]
        moved = _strip(lambda p: (p.clamp("x0"), p.move_edge("x1", translate=(0.0, 0.0, 0.1)))).solve_linear()
        _strip(lambda p: (p.clamp("x0"), p.rotate_edge("x1", (0, 1, 0), 0.3))).solve_linear()
        _turned_by_prescribe(1e-7).solve_linear()            # relative difference 2.5e-8: the chord is the tangent
    assert np.array_equal(u, moved.final.probes["tip"]["u"]) and u[2] == 0.1


def _panel_corner_load(s):
    p = Problem(mesh.cylinder_panel(1.0, 2.0, -0.6, 0.6, 4, 1), Material(1e4, 0.3, 0.02))
    p.clamp("y0")
    p.add_nodal_load(lambda X: np.isclose(X[:, 1], 2.0) & (X[:, 0] > 0.5), force=(0.0, 0.0, -0.02 * s))
    p.add_probe("edge", "x1")              # two nodes: the geodesic point halfway between them
    return p


def test_a_probe_between_nodes_is_linear_in_the_load():
    """A linear analysis' probe halfway along a free edge (two nodes) read u/s 0.053, 0.217,
    -0.169 at the loads s = 1, 2, 4: the geodesic point of the linear state (its frames turned by
    up to 2.5 rad) is not linear in the load.  Now the probe map is linearised, and equals the
    nonlinear solve at a tiny load, scaled (to its relative nonlinearity, 1e-6)."""
    u = {s: _panel_corner_load(s).solve_linear().final.probes["edge"] for s in (1.0, 4.0)}
    for key in ("u", "rotation_vector"):
        np.testing.assert_allclose(u[4.0][key] / 4.0, u[1.0][key], rtol=1e-12, atol=1e-14)
    eps = 1e-6
    nl = _panel_corner_load(eps).solve(steps=1, rtol=1e-13).final.probes["edge"]
    for key in ("u", "rotation_vector"):
        np.testing.assert_allclose(nl[key] / eps, u[1.0][key], rtol=2e-5, atol=2e-6)

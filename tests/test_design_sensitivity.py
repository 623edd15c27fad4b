"""Sensitivities of converged states (core_se3.design, issue 15 item 1): adjoint and direct
derivatives of every quantity kind with respect to every variable kind, checked against central
finite differences of FULL re-solves (each perturbed state is a converged equilibrium, followed
from the base state to rtol = dtol = 1e-12).

Tolerance 1e-6 relative (the issue's): the finite differences use a step of 1e-4 of each
variable's scale, so their truncation error is ~1e-8 relative and the re-solves' convergence
error ~1e-12 / 1e-4 = 1e-8; measured agreement is 1e-8 .. 1e-11.  The states: a strip rolled
past pi by a follower end moment (tip rotation 4.35 rad) with a magnet in a uniform field; a
strip under a follower pressure and a follower edge force in a uniform-gradient field (magnetic
body force and its Hessian-free tangent); polar forms of field and magnetisation."""
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, lie, mesh
from core_se3.design import (Design, Energy, EquilibriumOptions, EquilibriumState, FieldGradientVariable, FieldVariable, LoadMagnitude,
                             MaterialVariable, NodePosition, Orientation, ProbePosition, RegionMagnetisation,
                             Pose, RotationAngle, Target, assign_all, follow, sensitivity, solve_flat)
from core_se3.design.sensitivity import at_the_cone
from core_se3.errors import AccuracyWarning, DesignError
from core_se3.model import GradientField, UniformField

pytestmark = pytest.mark.core


def fd_jacobian(p, variables, quantities, g, lam=1.0, rel=1e-4):
    xs = [v.value() for v in variables]
    st = EquilibriumState(g, lam, xs)
    cols = []
    for iv, v in enumerate(variables):
        for k in range(v.size):
            vals = []
            for sgn in (1, -1):
                xx = [x.copy() for x in xs]
                xx[iv][k] += sgn * rel * v.scale[k]
                s2, _ = follow(p, variables, xx, st)
                vals.append(np.concatenate([q.value(p, s2.g, lam) for q in quantities]))
            cols.append((vals[0] - vals[1]) / (2 * rel * v.scale[k]))
    assign_all(variables, xs)
    return np.array(cols).T


def check(p, variables, quantities, g, tol=1e-6):
    FD = fd_jacobian(p, variables, quantities, g)
    scale = np.abs(FD).max(0)
    assert np.all(scale > 0), "every variable must move some quantity"
    out = {}
    for method in ("adjoint", "direct"):
        s = sensitivity(p, g, 1.0, quantities, variables, method)
        err = np.abs(s.jacobian - FD).max(0) / scale
        assert err.max() < tol, (method, dict(zip(s.labels, err)))
        out[method] = err.max()
    return out


def rolled_strip():
    L, w, h, E = 1.0, 0.2, 0.02, 1e4
    m = mesh.rectangle(L, w, 12, 1)
    p = Problem(m, Material(E, 0.0, h))
    p.clamp("x0")
    p.add_probe("tip", "x1")
    EI = E * w * h ** 3 / 12
    p.add_edge_moment("x1", (0, -1.4 * np.pi * EI / L, 0), follower=True)
    f = UniformField((0.0, 0.3, 1.0))
    p.add_magnetic((0.5, 0.0, 0.2), f, elements=np.arange(6), mu0=1.0)
    return p, f, m


def test_rotations_past_pi_every_variable_and_quantity_kind():
    p, f, m = rolled_strip()
    variables = [FieldVariable(p, f), RegionMagnetisation(p, [np.arange(3), np.arange(3, 6)]),
                 MaterialVariable(p, [np.arange(6), np.arange(6, 12)], "E"),
                 MaterialVariable(p, [np.arange(8, 12)], "h"), LoadMagnitude(p, p.loads[0])]
    res = p.solve(steps=8, rtol=1e-12, dtol=1e-12)
    assert np.linalg.norm(res.final.probes["tip"]["w"]) > np.pi + 1.0          # 4.35 rad
    tip_node = int(m.node_set("x1")[0])
    quantities = [ProbePosition(p, "tip"), Orientation(p, node=tip_node), RotationAngle(p, probe="tip", reference=4.0),
                  RotationAngle(p, node=tip_node, reference=4.0), Energy(), NodePosition(p, [5, 10])]
    check(p, variables, quantities, res.final.g)


def test_follower_loads_in_a_gradient_field_and_polar_forms():
    m = mesh.rectangle(1.0, 0.3, 8, 2)
    p = Problem(m, Material(2e4, 0.3, 0.02))
    p.clamp("x0")
    p.add_probe("tip", "x1")
    p.add_pressure(0.02, follower=True)
    p.add_edge_force("x1", (0.0, 0.0, 4e-3), follower=True)
    G = np.array([[0.4, 0.1, 0.0], [0.1, -0.1, 0.2], [0.0, 0.2, -0.3]])
    f = GradientField((0.3, 0.0, 0.8), G, x0=(0.2, 0.0, 0.1))
    p.add_magnetic((0.6, 0.0, 0.1), f, mu0=1.0)
    variables = [FieldVariable(p, f, form="polar", plane=((1, 0, 0), (0, 0, 1))),
                 FieldGradientVariable(p, f),
                 RegionMagnetisation(p, [np.arange(8), np.arange(8, 16)], form="polar"),
                 LoadMagnitude(p, p.loads[0]), LoadMagnitude(p, p.loads[1]),
                 MaterialVariable(p, [np.arange(16)], "E")]
    res = p.solve(steps=6, rtol=1e-12, dtol=1e-12)
    assert np.linalg.norm(res.final.probes["tip"]["w"]) > 0.5
    quantities = [ProbePosition(p, "tip"), Orientation(p, probe="tip"), Energy()]
    check(p, variables, quantities, res.final.g)


def test_adjoint_gradient_of_a_weighted_sum_is_one_solve():
    p, f, m = rolled_strip()
    v = [FieldVariable(p, f)]
    g = p.solve(steps=8, rtol=1e-12, dtol=1e-12).final.g
    q = [ProbePosition(p, "tip")]
    c = np.array([0.3, -1.0, 2.0])
    full = sensitivity(p, g, 1.0, q, v, "direct")
    one = sensitivity(p, g, 1.0, q, v, cotangent=c)
    assert one.solves == 1
    assert np.abs(one.jacobian[0] - c @ full.jacobian).max() < 1e-10 * np.abs(c @ full.jacobian).max()


def test_bad_input():
    p, f, m = rolled_strip()
    with pytest.raises(DesignError, match="do not exist"):
        NodePosition(p, [1000])
    with pytest.raises(DesignError, match="no probe 'tpi'; did you mean 'tip'"):
        ProbePosition(p, "tpi")
    with pytest.raises(DesignError, match="unknown region"):
        RegionMagnetisation(p, ["fingers"])
    with pytest.raises(DesignError, match="inside and outside"):
        RegionMagnetisation(p, [np.arange(3)])
    with pytest.raises(DesignError, match="thickness of a region with a magnet"):
        MaterialVariable(p, [np.arange(4)], "h")
    with pytest.raises(DesignError, match="did you mean 'angle'"):
        FieldVariable(p, f, form="polar", plane=((0, 1, 0), (0, 0, 1)), free=("angel",))
    v = FieldVariable(p, f, form="polar", plane=((0, 1, 0), (0, 0, 1)), B_max=0.5)
    with pytest.raises(DesignError, match="outside its bounds"):
        v.check_start()


def test_material_variable_over_a_non_uniform_region_is_refused():
    # E 1e4 on elements 0-1 and 3e4 on 2-3, one E variable over all four: before, its value was
    # the first element's (1e4) and the design's start set the whole region to it, silently
    # solving another shell than the user's (a tip force: deflection 0.2163 became 0.2322)
    from core_se3.fem import RegionMaterial
    p = Problem(mesh.rectangle(1.0, 0.2, 4, 1), Material(1e4, 0.0, 0.02))
    p.set_material(RegionMaterial([Material(1e4, 0.0, 0.02), Material(3e4, 0.0, 0.02)], np.array([0, 0, 1, 1])))
    with pytest.raises(DesignError, match="E varies over region 0 .10000 .. 30000."):
        MaterialVariable(p, [np.arange(4)], "E")
    v = MaterialVariable(p, [np.arange(2), np.arange(2, 4)], "E")
    assert v.value().tolist() == [1e4, 3e4]


def test_magnetisation_variable_over_a_non_uniform_magnet_is_refused():
    # B^r (0.2, 0, 0), (0.1, 0, 0), (0, 0, 0.1), (0, 0, 0.1) on elements 0..3, one variable region
    # per two elements: before, the per-region least-squares fit (misfit 0.151 of the nodal
    # moments, computed and dropped) silently replaced the magnets -- the magnetic load changed by
    # 0.162 of its largest nodal value, so the design started from another shell than the user's
    def strip(Br):
        p = Problem(mesh.rectangle(4.0, 0.5, 4, 1), Material(1e3, 0.0, 0.1))
        p.add_magnetic(np.array(Br, float), UniformField((0.0, 0.0, 1.0)), elements=[0, 1, 2, 3], mu0=1.0)
        return p, p.external(p.mesh.g0, 1.0, tangent=False)[0]
    p, _ = strip([[0.2, 0, 0], [0.1, 0, 0], [0, 0, 0.1], [0, 0, 0.1]])
    with pytest.raises(DesignError, match=r"B\^r varies over region 0 .*misfit of 0.151 > 1e-08"):
        RegionMagnetisation(p, [[0, 1], [2, 3]], name="Br")
    v = RegionMagnetisation(p, [[0, 1], [2, 3]], start=[[0.15, 0, 0], [0, 0, 0.1]], name="Br")   # a start given
    assert v.value().tolist() == [0.15, 0, 0, 0, 0, 0.1]
    p, f0 = strip([[0.2, 0, 0], [0.2, 0, 0], [0, 0, 0.1], [0, 0, 0.1]])         # uniform per region: kept exactly
    v = RegionMagnetisation(p, [[0, 1], [2, 3]], name="Br")
    assert v.start_misfit < 1e-14
    assert np.allclose(p.external(p.mesh.g0, 1.0, tangent=False)[0], f0, rtol=1e-13, atol=1e-16)


def test_magnetisation_of_one_material_in_two_fields_keeps_both_fields():
    """The walker's spelling (examples/walker.toml): a magnet per field on each region, the same
    B^r.  Before, the variable (field given: without it a DesignError asked for one) dropped the
    magnets of the other field and fitted their sum: the start was 0.156 T instead of 0.078 and
    the magnetic load changed by 1.00 of its largest nodal value.  Now it acts in both fields,
    the loads are kept (to round-off), its sensitivities (in both fields) match re-solves, and
    a field other than the magnets' is refused."""
    m = mesh.rectangle(4.0, 1.5, 8, 1)
    V, H = UniformField((0.0, 0.0, 0.003)), UniformField((0.0005, 0.0, 0.0004))
    rear, front = np.arange(4), np.arange(4, 8)
    p = Problem(m, Material(0.07, 0.0, 0.2))
    p.clamp("x0")
    p.add_probe("tip", "x1")
    for els, Br in ((rear, (0.078, 0.0, 0.0156)), (front, (-0.078, 0.0, 0.0156))):
        for f in (V, H):
            p.add_magnetic(Br, f, elements=els, mu0=1.2566370614359173)
    g = p.mesh.g0 @ lie.exp(np.random.default_rng(2).normal(size=(m.n_nodes, 6)) * 0.1)
    f0 = p.external(g, 1.0, tangent=False)[0]
    with pytest.raises(DesignError, match="other field"):
        RegionMagnetisation(p, [rear, front], field=UniformField((0.0, 0.0, 1.0)))
    v = RegionMagnetisation(p, [rear, front], field=V)
    assert np.allclose(v.value(), [0.078, 0.0, 0.0156, -0.078, 0.0, 0.0156], rtol=1e-13, atol=1e-16)
    assert [ld.field for ld in p.loads] == [V, H]
    assert np.abs(p.external(g, 1.0, tangent=False)[0] - f0).max() <= 1e-13 * np.abs(f0).max()
    res = p.solve(steps=2, rtol=1e-12, dtol=1e-12)
    check(p, [v], [ProbePosition(p, "tip")], res.final.g)


def test_thickness_of_a_region_in_contact_is_refused():
    # The contact keeps the surface offset h/2 and the penalty it was built with.  Before, a
    # thickness variable there solved with the old offset: a strip pressed onto a half-space
    # at z = -0.1, h designed 0.02 -> 0.04, came to rest with its tip at z = -0.0901 (the old
    # h/2 = 0.01 above the plane) where the same strip built with h = 0.04 (the optimised
    # scenario) rests at -0.0801: 0.01 = the change of h/2, a converged-looking wrong state.
    p = Problem(mesh.rectangle(1.0, 0.2, 8, 1), Material(1e4, 0.0, 0.02))
    p.clamp("x0"); p.add_edge_force("x1", (0, 0, -3e-2))
    p.add_obstacle("half_space", point=(0, 0, -0.1), normal=(0, 0, 1), region=np.arange(4, 8))
    with pytest.raises(DesignError, match="thickness of a region in contact .obstacle 'half_space'"):
        MaterialVariable(p, [np.arange(8)], "h")
    MaterialVariable(p, [np.arange(3)], "h")          # off the contact elements' nodes: allowed
    MaterialVariable(p, [np.arange(8)], "E")


def test_E_of_a_region_in_a_penalty_contact_is_refused():
    # A penalty contact's answer depends on its penalty k = beta K_i / A_i, built from the shell's
    # stiffness (linear in E) and then kept.  Before, an E variable 1e4 -> 4e4 on a strip pressed
    # onto a half-space in mode 'penalty' solved with the old k: penetration 3.4e-6 and the tip
    # 2.6e-6 below the 8.6e-7 and the tip of the same strip built with E = 4e4 (the optimised
    # scenario; 130 gap tolerances).  Mode 'al' converges to the Signorini answer whatever k: the
    # same change there leaves the tip 6e-11 from the rebuilt strip's (below its tolerance 2e-8).
    def strip(E, law):
        p = Problem(mesh.rectangle(1.0, 0.2, 8, 1), Material(E, 0.0, 0.02))
        p.clamp("x0"); p.add_probe("tip")
        p.add_pressure(-3e-2, direction=(0, 0, 1))
        p.add_obstacle("half_space", point=(0, 0, -0.1), normal=(0, 0, 1), region=np.arange(4, 8), law=law)
        return p
    p = strip(1e4, dict(mode="penalty"))
    with pytest.raises(DesignError, match="E of a region in contact .obstacle 'half_space'. in mode 'penalty'"):
        MaterialVariable(p, [np.arange(8)], "E")
    MaterialVariable(p, [np.arange(3)], "E")                     # off the contact elements' nodes
    MaterialVariable(strip(1e4, dict(mode="penalty", k=1e6)), [np.arange(8)], "E")     # a penalty given
    p = strip(1e4, dict(mode="al"))
    MaterialVariable(p, [np.arange(8)], "E").assign([4e4])
    tip = p.solve(steps=4).final.probes["tip"]["u"][2]
    assert abs(tip - strip(4e4, dict(mode="al")).solve(steps=4).final.probes["tip"]["u"][2]) < 2e-8


def test_partials_in_E_use_the_linearity():
    """dr/dE_j and dPi/dE_j at a rolled state (4.35 rad): the residual and the energy are linear in
    E, so one law per component (not the four of a Richardson-extrapolated central difference)
    gives them; checked against a central difference of +-50 % (exact for a linear function) to
    1e-13 relative, and the law is restored."""
    p, f, m = rolled_strip()
    v = MaterialVariable(p, [np.arange(6), np.arange(6, 12)], "E")
    g = p.solve(steps=8, rtol=1e-12, dtol=1e-12).final.g
    x = v.value()
    laws, set_material = [], p.set_material
    p.set_material = lambda law: (laws.append(law), set_material(law))
    dr = v.dr_dp(p, g, 1.0)
    dPi = Energy().explicit(p, g, 1.0, v)
    p.set_material = set_material
    assert len(laws) == 2 * (v.size + 1)          # a law per component and the restored one, twice
    r0 = p.element.evaluate(g, tangent=False).r
    for j in range(v.size):
        vals = []
        for s in (0.5, -0.5):
            xx = x.copy()
            xx[j] *= 1 + s
            v.assign(xx)
            ev = p.element.evaluate(g, tangent=False)
            vals.append((ev.r, ev.energy))
        v.assign(x)
        fd_r = (vals[0][0] - vals[1][0]) / x[j]
        assert np.abs(dr[:, :, j] - fd_r).max() < 1e-13 * np.abs(fd_r).max()
        assert abs(dPi[0, j] - (vals[0][1] - vals[1][1]) / x[j]) < 1e-13 * abs(dPi[0, j])
    assert np.array_equal(p.element.evaluate(g, tangent=False).r, r0)


def pressed_strip(P=1.0, friction=0.0):
    """A cantilever pressed onto a half-space by a dead pressure (contact in mode 'al'), pushed
    along by an end force."""
    p = Problem(mesh.rectangle(1.0, 0.2, 8, 1), Material(1e4, 0.0, 0.02))
    p.clamp("x0"); p.add_probe("tip")
    p.add_pressure(-3e-2 * P, direction=(0, 0, 1))
    p.add_obstacle("half_space", point=(0, 0, -0.1), normal=(0, 0, 1), friction=friction)
    p.add_edge_force("x1", (2e-3, 0, 0))
    return p


def test_design_equilibria_in_contact_are_the_solver_s():
    # A design's equilibria must be those Problem.solve (and the optimised scenario) reaches:
    # the contact's multipliers updated until the gap error is within its tolerance
    # (1e-6 h = 2e-8).  Before, follow() ran Newton with the multipliers last left, a penalty
    # solution: the tip at P = 1.2 ended 1.9e-6 below the solver's (penetration 6.8e-6 = 340
    # gap tolerances; 2.4e-11 from it now), and a pose's sensitivities used the multipliers of
    # the pose solved last (d misfit / dE of two poses 3.5e-4 off central differences, 9e-9 now).
    p = pressed_strip()
    P, E = LoadMagnitude(p, p.loads[0]), MaterialVariable(p, [np.arange(8)], "E")
    st = solve_flat(p, [P, E], [np.array([1.0]), E.value()], options=EquilibriumOptions())
    moved, _ = follow(p, [P, E], [np.array([1.2]), E.value()], st)
    q = pressed_strip(1.2)
    fresh = q.solve(steps=10, rtol=1e-12, dtol=1e-12).final.g
    assert np.abs(moved.g[:, :3, 3] - fresh[:, :3, 3]).max() < 1e-7
    # two poses of different pressure: each pose's sensitivities with its own multipliers
    tip, mid = ProbePosition(p, "tip"), NodePosition(p, [4])
    d = Design(p, [E], [Pose("light", [Target(tip), Target(mid)], settings={P: [1.0]}),
                        Pose("heavy", [Target(tip), Target(mid)], settings={P: [3.0]})])
    x = d.x_start()
    J = d.jacobian(x)
    FD = np.array([(d.residuals(x + 1e-4 * x * e) - d.residuals(x - 1e-4 * x * e)) / (2e-4 * x[0])
                   for e in np.eye(1)]).T
    assert np.abs(J - FD).max() < 1e-6 * np.abs(FD).max()


def test_sensitivity_at_the_stick_slip_transition_says_it_is_one_sided():
    # The pushed strip's end slides (mu = 0.3): at the solved state its stored traction is on
    # the cone, where the state is not differentiable.  The sensitivities are those of
    # continued sliding: d tip_x / d push 9.02e-5 equals the forward difference (sliding on),
    # while a decrease sticks the end: 4.13e-5; d tip_x / d pressure -1.033e-3 against -0.890e-3
    # for an increase.  Before, the derivatives came without a word.
    p = pressed_strip(friction=0.3)
    v = [LoadMagnitude(p, p.loads[0]), LoadMagnitude(p, p.loads[2])]
    xs = [x.value() for x in v]
    st = solve_flat(p, v, xs)
    with pytest.warns(AccuracyWarning, match="2 frictional contact node.s. at the stick/slip transition"):
        s = sensitivity(p, st.g, 1.0, [ProbePosition(p, "tip")], v, "direct")
    tip = p.probes["tip"].state(st.g)[0][0]
    one_sided = []
    for sign in (1, -1):
        moved, _ = follow(p, v, [xs[0], xs[1] + sign * 1e-5], st)
        one_sided.append((p.probes["tip"].state(moved.g)[0][0] - tip) / (sign * 1e-5))
        assert at_the_cone(p, moved.g, 1.0) == 0         # sliding on, or stuck: off the transition
    assert abs(s.jacobian[0, 1] - one_sided[0]) < 1e-4 * abs(one_sided[0])
    assert abs(one_sided[1] - one_sided[0]) > 0.3 * abs(one_sided[0])
    q = pressed_strip()                                  # frictionless: no transition, no warning
    u = [LoadMagnitude(q, q.loads[0])]
    st = solve_flat(q, u, [u[0].value()])
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        sensitivity(q, st.g, 1.0, [ProbePosition(q, "tip")], u)


def test_sensitivities_of_a_part_far_from_the_origin_are_those_at_the_origin():
    # The README cantilever (10 x 1, 16 elements, tip force 4) translated to x0 = 1e9.  Its state is stored to the ulp of 1e9 (1.2e-7); taken relative to
    # the part (an exact subtraction) it is a state of the part at x0 = 0.  Before, the
    # sensitivities at 1e9 differed from those of that same state at 0 by 1.2e-4 relative (the
    # probe's finite differences of absolute positions: 8.4e-4 on its Jacobian dq/d eta) and 1e-5
    # (a node's: the tangent evaluated on the absolute frames).  Now the probe's differences are
    # taken relative to the part and the tangent, the variables' and the quantities' derivatives
    # on the frames relative to the part's origin: they agree to round-off (1e-12).  (With the
    # state solved at 0 they agree only as the states do: the far state's positions, rounded by
    # up to 1.2e-7, put membrane strains of 2e-7 in it, E h 2e-7 = 0.02 of membrane force, and its
    # sensitivities differ by up to 5e-5 -- the stored state's round-off, not the sensitivities'.)
    def make(x0):
        p = Problem(mesh.rectangle(10.0, 1.0, 16, 1, x0=x0), Material(E=1.2e6, nu=0.0, h=0.1), backend="numpy")
        p.clamp("x0"); p.add_edge_force("x1", (0.0, 0.0, 4.0)); p.add_probe("tip", "x1")
        p.add_edge_force("x1", (0.0, 1.0, 0.0), follower=True)
        return p

    def sens(p, g):
        q = [ProbePosition(p, "tip"), Orientation(p, probe="tip"), RotationAngle(p, probe="tip"), NodePosition(p, [20])]
        v = [LoadMagnitude(p, p.loads[0]), LoadMagnitude(p, p.loads[1], name="Q")]
        dq = np.vstack([qq.jacobian(p, g, 1.0).toarray() for qq in q])
        return [sensitivity(p, g, 1.0, q, v, m) for m in ("adjoint", "direct")], dq

    p0 = make(0.0)
    g0 = p0.solve(steps=10).final.g
    far = make(1e9)
    gf = far.solve(steps=10).final.g
    gr = gf.copy(); gr[:, 0, 3] -= 1e9                     # exact: the far state relative to the part
    assert np.abs(gr - g0).max() < 2e-7                    # the positions' rounding at 1e9
    (ar, dr), qr = sens(p0, gr)
    (af, df), qf = sens(far, gf)
    assert np.abs(qf - qr).max() <= 1e-13 * np.abs(qr).max()
    scale = np.abs(ar.jacobian).max(0)
    for s_far, s_rel in ((af, ar), (df, dr)):
        assert np.all(np.abs(s_far.jacobian - s_rel.jacobian).max(0) <= 1e-12 * scale)
        np.testing.assert_allclose(s_far.values - s_rel.values, np.r_[1e9, 0, 0, np.zeros(4), 1e9, 0, 0], atol=1e-6)


@pytest.mark.parametrize("off", [1.03, 0.97])
def test_thickness_derivatives_next_to_the_kink_of_the_shear_stabilisation_floor(off):
    """A shear-stabilised strip (alpha 0.1, floor c 0.05) whose thickness lies 3 % from the kink of
    the floor, h = hk / off with hk = L sqrt(c alpha / (1 - c)) on its elements of size L = 0.125:
    the thickness differences of the partials (d = 0.02 h and 2d) straddled the kink and the
    tip deflection's adjoint derivative was 3.9e-5 (below it) and 3.8e-5 (above) off the re-solves'
    central differences (audit finding); they now stay off the kink (measured 1.3e-10)."""
    nx = 8
    hk = (1.0 / nx) * np.sqrt(0.05 * 0.1 / 0.95)
    h = hk / off
    m = mesh.rectangle(1.0, 0.1, nx, 1)
    p = Problem(m, Material(1e4, 0.3, h, shear_stabilisation=0.1, shear_stabilisation_floor=0.05))
    p.clamp("x0")
    p.add_nodal_load("x1", force=(0.0, 0.0, 1e2 * h ** 3))
    variables = [MaterialVariable(p, [np.arange(nx)], "h")]
    g = p.solve(steps=2, rtol=1e-12, dtol=1e-12).final.g
    check(p, variables, [NodePosition(p, [int(m.node_set("x1")[0])])], g)


def _design_strip():
    p = Problem(mesh.rectangle(0.0172, 0.005, 10, 1), Material(E=0.8969e6, nu=0.0, h=0.42e-3))
    p.clamp("x0")
    p.add_probe("tip", "x1")
    f = UniformField((0.0, 0.0, 0.01))
    p.add_magnetic(Br=(0.143, 0.0, 0.0), field=f)
    return p, f


def test_sensitivities_at_a_state_that_is_no_equilibrium_are_refused():
    """sensitivity() at the reference frames of the loaded strip (relative residual 0.987) gave a
    jacobian, silently; now a DesignError.  A converged state still gives one."""
    from core_se3.errors import DesignError
    p, f = _design_strip()
    res = p.solve(load_factors=[0.5, 1.0])
    q, v = [ProbePosition(p, "tip")], [FieldVariable(p, f)]
    assert sensitivity(p, res.final.g, 1.0, q, v).jacobian.shape == (3, 3)
    with pytest.raises(DesignError, match=r"need an equilibrium: the state given has a relative residual 0.98"):
        sensitivity(p, p.mesh.g0, 1.0, q, v)


def test_design_inputs_of_the_wrong_kind_are_design_errors():
    """A probe's name as a quantity was a bare AttributeError; no variables a bare ValueError of
    a reshape (now the (3, 0) jacobian); a field no magnet is in was taken (every derivative 0,
    the variable ignored); node 1.5 was read as node 1."""
    from core_se3.errors import DesignError
    p, f = _design_strip()
    g = p.solve(steps=2).final.g
    with pytest.raises(DesignError, match="quantities must be design Quantity objects"):
        sensitivity(p, g, 1.0, ["tip"], [FieldVariable(p, f)])
    assert sensitivity(p, g, 1.0, [ProbePosition(p, "tip")], [], method="direct").jacobian.shape == (3, 0)
    with pytest.raises(DesignError, match="no magnet of the problem is in this field"):
        FieldVariable(p, UniformField((0.0, 0.0, 0.01)))
    with pytest.raises(DesignError, match=r"node ids must be whole numbers, got \[1.5\]"):
        NodePosition(p, [1.5])


def test_a_rotation_angle_is_about_the_lab_axis_whatever_the_nodes_frames():
    """RotationAngle dotted the lab axis with log(Rref^T R), the rotation's components in the
    node's (probe's) reference frame: where that frame is not the lab's (any curved mesh, a file's
    frames, d1 turned by quarter turns across a cut) a node turned by 0.5 rad about -y read 0 with
    d1 turned by 90 deg about the normal and -0.5 with 180 deg, and on the quarter hemisphere whose
    d1 are turned by random quarter turns the sensitivities of a node's angle were 0.42 off those
    of the generator's frames (relative; every other quantity 1e-11).  Now R_0^T axis: the lab
    angle, and its jacobian the derivative of that value (checked by differences along each
    rotation dof)."""
    from core_se3.mesh.gauge import turned_about_normal
    for turn in (0.0, 0.7, 0.5 * np.pi, np.pi):
        m = mesh.rectangle(2.0, 1.0, 2, 1)
        m.g0 = turned_about_normal(m.g0, np.full(m.n_nodes, turn))
        p = Problem(m, Material(1e3, 0.0, 0.01))
        p.add_probe("tip", "x1")
        g = lie.exp(np.array([0, 0, 0, 0.2, -0.5, 0.1])) @ m.g0
        for q in (RotationAngle(p, node=2, axis=(0, -1, 0)), RotationAngle(p, probe="tip", axis=(0, -1, 0))):
            assert abs(q.value(p, g, 1.0)[0] - _twist([0.2, -0.5, 0.1], [0, -1, 0])) < 1e-12, turn
            J = q.jacobian(p, g, 1.0).toarray()[0]
            for node in (2, 4, 5):
                for k in range(3, 6):
                    d = []
                    for s in (1e-6, -1e-6):
                        gg = g.copy()
                        gg[node] = g[node] @ lie.exp(s * np.eye(6)[k])
                        d.append(q.value(p, gg, 1.0)[0])
                    assert abs((d[0] - d[1]) / 2e-6 - J[6 * node + k]) < 1e-8, (turn, node, k)


def _twist(psi, axis):
    """The twist about the unit ``axis`` of the rotation exp(psi), from its quaternion
    (cos(t/2), sin(t/2) psi/t), t = |psi|: 2 atan2(sin(t/2) axis . psi/t, cos(t/2))."""
    t = np.linalg.norm(psi)
    return 2 * np.arctan2(np.sin(t / 2) * np.dot(axis, psi) / t, np.cos(t / 2))


def test_a_rotation_angle_is_a_function_of_the_state():
    """A node turned by 1.7 rad about +y and swung by 0.3 rad about x (a swing past a quarter turn
    from the reference 0, so the reference follows it).  Before, theta = reference + axis .
    log(exp(-reference axis) R): the same state read 1.7 on the first evaluation and 1.71104 on
    every later one (the reference had followed it; 2.5 and 2.5547 for 2.5 rad and a swing of
    0.6), and quantities started at other references read other values.  Now the twist of the
    swing-twist decomposition, whatever the reference and the history: 1.711102 here (exact
    from the quaternion, to 1e-14)."""
    p = Problem(mesh.rectangle(2.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    p.add_probe("tip", "x1")
    for psi in ([0.3, 1.7, 0.0], [0.6, 2.5, 0.0], [0.2, -4.0, 0.4]):
        g = p.mesh.g0.copy()
        g[[2, 5], :3, :3] = lie.exp_so3(np.array(psi))
        exact = _twist(psi, [0, 1, 0])
        exact += 2 * np.pi * np.round((psi[1] - exact) / (2 * np.pi))      # the branch of the turn
        for ref in (0.0, 1.0, 2.0, psi[1]):
            for q in (RotationAngle(p, node=2, axis=(0, 1, 0), reference=ref),
                      RotationAngle(p, probe="tip", axis=(0, 1, 0), reference=ref)):
                v = [q.value(p, g, 1.0)[0] for _ in range(3)]
                if abs(ref - psi[1]) < 0.5 * np.pi + 0.1:                # on the branch of the turn
                    assert np.abs(np.array(v) - exact).max() < 1e-14, (psi, ref, v, exact)
                else:                                                   # counted a turn short: the same modulo 2 pi
                    assert np.abs((np.array(v) - exact + np.pi) % (2 * np.pi) - np.pi).max() < 1e-12, (psi, ref, v)
                    assert max(v) - min(v) < 1e-14, (psi, ref, v)


def test_angle_sensitivities_at_a_twisted_large_deformation_started_from_the_reference():
    """A strip under a dead edge force with a sideways component, its weight, a dead pressure, dead
    and follower end moments, turned 4.27 rad; the angle about y of its tip probe (a swing off y) with the default
    reference 0.  Before, the first finite-difference re-solve moved the reference and the angle
    it measured with it: d angle / dP read 56.8 against the adjoint's 0.28 (1.005 relative).  Now
    the adjoint and the direct method agree with central differences of full re-solves to 1e-6
    (measured 6e-9)."""
    m = mesh.rectangle(1.0, 0.3, 10, 2)
    p = Problem(m, Material(2e4, 0.3, 0.02))
    p.clamp("x0")
    p.add_probe("tip", "x1")
    p.add_edge_force("x1", (0.0, 0.02, 0.03))
    p.add_gravity(rho=1.0, g=(0.0, 0.0, -20.0))
    p.add_pressure(0.01, direction=(0.0, 0.3, 1.0))
    p.add_nodal_load("x1", (0, 0, 0), (0.0, -0.01, 0.0))
    p.add_edge_moment("x1", (0.0, -0.005, 0.002), follower=True)
    res = p.solve(steps=8, rtol=1e-12, dtol=1e-12)
    assert np.linalg.norm(res.final.probes["tip"]["w"]) > 4.0
    q = RotationAngle(p, probe="tip", axis=(0, 1, 0))
    check(p, [LoadMagnitude(p, p.loads[0])], [q], res.final.g)

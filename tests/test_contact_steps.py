"""Contact over whole load steps (issue 29, contact items): no node or face crosses an obstacle
between two accepted states (continuous collision detection, ``model.contact_sweep``), face
samples that feel an obstacle smaller than an element (``model.contact_faces``, with their
tangent against central differences), and a first contact that converges on a fine, very
flexible strip (``soft_start``).  Each case here failed, or passed through, before.
Derivations: docs/CONTACT.md."""
from __future__ import annotations

import json

import numpy as np
import pytest

import core_se3 as cs
from core_se3 import lie
from core_se3 import mesh as M
from core_se3.model import Box, ContactLaw, ContactLoad, Cylinder, Sphere, tangent_fd_check, translation
from core_se3.model.contact_law import ramp
from core_se3.model.contact_sweep import crossing_report, face_grid, swept_depth


def _surface_depth(c, g, lam, spacing=0.05):
    """The deepest point of the contact surface (nodes and a fine grid on every face) inside the
    obstacle at (g, lam): min d (negative inside)."""
    x = c.contact_points(g)
    W = face_grid(spacing, 1.0)
    pts = np.concatenate([x, np.einsum("qa,mai->mqi", W, x[c._quads]).reshape(-1, 3)])
    return float(c.obstacle.distance(pts, lam).min())


def _rising_ball(dist=6.0):
    """Issue 29's case: a 16 x 1 cantilever (L 10, h 0.1) over a ball of radius 1 under x = 8
    that rises by ``dist``."""
    p = cs.Problem(M.rectangle(10.0, 1.0, 16, 1), cs.Material(1e6, 0.0, 0.1))
    p.clamp("x0")
    c = p.add_obstacle("sphere", centre=(8.0, 0.0, -1.1), radius=1.0, motion=dict(translate=(0, 0, dist)),
                       name="ball")
    return p, c


# ----------------------------------------------------------------------------- the sweep check
def test_swept_depth_finds_a_ball_that_passed_through():
    """Both end states outside; the path through the ball's centre is found, its depth bounded."""
    ball = Sphere((0.0, 0.0, -2.0), 1.0, motion=translation((0.0, 0.0, 4.0)))
    x = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    found, lower = swept_depth(ball, x, x, 0.0, 1.0, depth=0.05)
    assert found[0] < -0.05 and found[1] > 1.0 and lower[1] <= found[1]
    assert ball.distance(x, 0.0)[0] > 0 and ball.distance(x, 1.0)[0] > 0


def test_a_path_through_the_centre_of_a_ball_is_a_crossing_not_an_error():
    """The crossing check samples distances along the paths; a face point whose path meets a
    ball's (or an infinite cylinder's) centre exactly, where the distance is defined (-R) but the
    normal is not, stopped the run with ContactError "a point is at the centre of the sphere"
    (a ball of radius 0.05 pressed 0.05 up into a plate under round coordinates, in 2 steps:
    a face point's end state); now the sweep takes the distance there."""
    for ball in (Sphere((0.0, 0.0, 0.0), 0.05), Cylinder((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 0.05)):
        out, centre = np.array([[0.0, 0.0, -0.1]]), np.array([[0.0, 0.0, 0.0]])
        assert ball.distance(centre)[0] == -0.05
        # ending (or starting) at the centre: the end state's own depth is forgiven by the sweep
        assert crossing_report(ball, np.zeros((0, 4), int), out, centre, 0.0, 1.0, 0.01, [7]) == ""
        assert crossing_report(ball, np.zeros((0, 4), int), centre, out, 0.0, 1.0, 0.01, [7]) == ""
        assert "passes through" in crossing_report(ball, np.zeros((0, 4), int), out, -out, 0.0, 1.0, 0.01, [7])

def test_a_small_ball_between_the_nodes_is_found_on_the_face():
    """A ball of radius 0.1 rising through the middle of a 1 x 1 face: the nodes never come
    near it (nodal sampling misses it), the face grid does."""
    ball = Sphere((0.5, 0.5, -0.5), 0.1, motion=translation((0.0, 0.0, 1.0)))
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    quads = np.array([[0, 1, 2, 3]])
    assert swept_depth(ball, x, x, 0.0, 1.0, 0.05)[0].min() > 0.5                 # the nodes see nothing
    msg = crossing_report(ball, quads, x, x, 0.0, 1.0, 0.05, np.arange(4))
    assert "face of element 0" in msg and "passes through obstacle" in msg
    assert crossing_report(ball, quads, x, x + [0.0, 0.0, 2.0], 0.0, 1.0, 0.05, np.arange(4)) == ""   # carried along


def test_a_rotating_roller_is_followed_along_its_arc():
    """A point carried by a cylinder that turns by 2 rad about its axis: its lab chord cuts 0.46
    deep, the path carried along the arc does not: not a crossing (a step is clear when the
    lab-linear or the carried path is)."""
    roller = Cylinder((0.0, 0.0, -1.0), (0.0, 1.0, 0.0), 1.0,
                      motion=lambda lam: np.block([[lie.exp_so3(np.array([0.0, 2.0 * lam, 0.0])),
                                                    (np.eye(3) - lie.exp_so3(np.array([0.0, 2.0 * lam, 0.0])))
                                                    @ [[0.0], [0.0], [-1.0]]], [np.zeros((1, 3)), np.ones((1, 1))]]))
    x0 = np.array([[0.0, 0.0, 0.0]])
    x1 = roller.transform(1.0)[:3, :3] @ x0[0] + roller.transform(1.0)[:3, 3]
    assert swept_depth(roller, x0, x1[None], 0.0, 1.0, 0.05)[0][0] < -0.05          # the lab chord cuts in
    assert crossing_report(roller, np.zeros((0, 4), int), x0, x1[None], 0.0, 1.0, 0.05, [0]) == ""


# ----------------------------------------------------------------------------- whole runs
def test_rising_ball_in_two_steps_does_not_pass_through():
    """Issue 29: with 2 steps the ball passed through the strip (flat strip, ball above it,
    'complete', no contact force).  The crossing check refuses that step: whatever the run
    reaches with few cut-backs, every stored state has the whole strip outside the ball, and a
    state with the ball above the strip's reference position has the strip on it (force > 0);
    a run that cannot follow the path says so.  (The full path takes minutes: docs/CONTACT.md.)"""
    p, c = _rising_ball()
    try:
        res, err = p.solve(steps=2, max_cutbacks=4), None
    except cs.ConvergenceError as exc:
        res, err = exc.result, str(exc)
    assert err is None or "passes through" in err or "inside the shell" in err or "cut-backs" in err
    for st in res.steps:
        assert _surface_depth(c, st.g, st.load_factor) > -10 * c.tol
        if st.load_factor >= 0.2:                    # the ball's bottom is above the flat strip
            assert st.contact["ball"]["force"][2] > 0.1


def test_a_ball_moved_a_thousand_lengths_does_not_pass_through():
    """1000 L in two steps: the run stops with the reason, and no stored state has the strip
    inside the ball (before: 'complete', the ball above the flat strip)."""
    p, c = _rising_ball(1e4)
    with pytest.raises(cs.ConvergenceError) as info:
        p.solve(steps=2)
    assert "inside the shell" in str(info.value) or "passes through" in str(info.value)
    for st in info.value.result.steps:
        assert _surface_depth(c, st.g, st.load_factor) > -10 * c.tol


def test_fine_flexible_strip_settles_on_a_table():
    """Issue 29: 200 elements, 100 x 10 x 1 mm, E 1 MPa, rho 1000 kg/m^3 under gravity, clamped
    1 mm above a table (0.5 mm gap under its face): the first contact stalled (no convergence at
    lam 3.7e-4 after 12 cut-backs); 100 elements worked.  The deflection without the table would
    be 1.47 m, the touchdown length l = (24 EI delta / q)^(1/4) = 17.8 mm (docs/CONTACT.md)."""
    p = cs.Problem(M.rectangle(0.1, 0.01, 200, 1), cs.Material(1e6, 0.3, 1e-3))
    p.clamp("x0")
    p.add_gravity(rho=1000.0)
    c = p.add_obstacle("half_space", point=(0, 0, -0.001), normal=(0, 0, 1), name="table")
    res = p.solve(steps=10)
    st = res.final
    assert abs(st.load_factor - 1) < 1e-12 and c.penetration(st.g, 1.0) <= c.tol
    assert st.balance_error < 1e-8
    # the table carries the weight beyond the touchdown point (about 82 % of the strip)
    weight = 1000.0 * 9.81 * 1e-3 * 0.1 * 0.01
    assert 0.7 * weight < st.contact["table"]["force"][2] < weight


# ----------------------------------------------------------------------------- face samples
def _faces_obstacles():
    return {"sphere": Sphere((0.5, 0, 0.6), 0.6),
            "cylinder": Cylinder((0, 0, 0.5), (0.3, 1, 0), 0.5),
            "box": Box((0.5, 0, -0.3), (0.4, 0.2, 0.3), rotation=lie.exp_so3(np.array([0.1, 0.2, 0.3])), rounding=0.05),
            "moving_sphere": Sphere((0.5, 0, 0.9), 0.6, motion=translation((0, 0, -0.5)))}


@pytest.mark.parametrize("name", list(_faces_obstacles()))
def test_face_sample_tangent_against_central_differences(name):
    """The face samples' forces and their tangent (with the motion of the closest point) against
    central differences of the full residual, with samples deep in contact and in the band."""
    m = M.rectangle(1.0, 0.6, 3, 2)
    g = m.g0 @ lie.exp(np.random.default_rng(1).normal(size=(m.n_nodes, 6)) * 0.08)
    prob = cs.Problem(m, cs.Material(1e4, 0.3, 0.02), backend="numpy")
    cl = prob.add(ContactLoad(prob, _faces_obstacles()[name], law=ContactLaw(eps=0.02, faces=True)))
    s, pf, _ = cl.face_state(g, 0.6)
    lam = cl.lam0.copy()
    lam[len(cl.nodes):] = ramp(np.maximum(0.5 * cl.kf * cl.eps + cl.kf * s["d"], 0.0), cl.kf * cl.eps)[0]
    cl.set_multipliers(np.concatenate([lam, np.ones(len(lam))]))
    s, pf, _ = cl.face_state(g, 0.6)
    assert (pf > 0).any(), "no face sample in contact"
    assert tangent_fd_check(prob, g, 0.6, free_all=True)[0] < 1e-7


def test_a_ball_smaller_than_an_element_is_held_by_the_face():
    """A ball of radius 0.05 pressed up into the middle of a 1 x 1 element of a clamped plate:
    nodal sampling lets it through; the face sample (faces='auto') carries it, the face point
    stays on the ball's surface and the balance closes."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 2, 1), cs.Material(1e4, 0.0, 0.02))
    p.clamp("x0")
    c = p.add_obstacle("sphere", centre=(1.5, 0.0, -0.07), radius=0.05, motion=dict(translate=(0, 0, 0.1)),
                       name="pin")
    assert len(c.face_el) == 2                      # auto: thinner than an element
    res = p.solve(steps=4)
    st = res.final
    assert st.contact["pin"]["force"][2] > 0 and st.balance_error < 1e-8
    assert _surface_depth(c, st.g, 1.0, 0.02) > -10 * c.tol
    assert c.report(st.g, 1.0)["faces_in_contact"] >= 1


@pytest.mark.parametrize("where", [(1.25, 0.25), (1.1, -0.4)])
def test_a_ball_off_the_middle_of_an_element_is_found_by_the_face(where):
    """The same ball under the point (1.25, 0.25) (or (1.1, -0.4)) of the 1 x 1 element: seen
    from the face's centre the ball's d is cone-like, a full Newton step of the face minimiser
    overshot to a corner and back, and the sample was never found: the ball rose 0.1 through the
    plate (0.08 of it above the contact face, the shell 0.02 thick) with zero force, penetration
    0 and no error.  Now the steps are halved until d decreases: the face sample holds it."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 2, 1), cs.Material(1e4, 0.0, 0.02))
    p.clamp("x0")
    c = p.add_obstacle("sphere", centre=(*where, -0.07), radius=0.05, motion=dict(translate=(0, 0, 0.1)),
                       name="pin")
    st = p.solve(steps=4).final
    assert st.contact["pin"]["force"][2] > 2e-4 and st.balance_error < 1e-8
    assert _surface_depth(c, st.g, 1.0, 0.01) > -10 * c.tol
    assert c.report(st.g, 1.0)["faces_in_contact"] == 1


def test_a_roller_across_the_strip_lifts_it_in_one_step_or_ten():
    """A cylinder (radius 0.1, thinner than the 0.05 x 0.1 elements' diameter 0.112: face samples
    on by 'auto') lying across a clamped strip, axis along the width, rises 0.1 under it.  Along
    the axis d is flat on a face: a line of minima, where the sample's coordinate was set by the
    sign of round-off and jumped between the face's two long edges at every evaluation (xi_2 =
    -1, +1, -1, ...): Newton stalled at a residual of 0.54 at first contact with 1 or 10 steps
    (ConvergenceError at load factor 0.1).  Now the sample stays on the face's middle line, and
    1 and 10 steps end alike (frictionless: path independent)."""
    def lift(steps):
        p = cs.Problem(M.rectangle(1.0, 0.1, 20, 1), cs.Material(1e5, 0.0, 0.01))
        p.clamp("x0")
        c = p.add_obstacle("cylinder", point=(0.7, 0, -0.115), axis=(0, 1, 0), radius=0.1, name="roller",
                           motion=dict(translate=(0.0, 0.0, 0.1)))
        res = p.solve(steps=steps)
        assert res.steps[-1].load_factor == pytest.approx(1.0) and len(c.face_el)
        s, pf, _ = c.face_state(res.final.g, 1.0)
        assert np.all(s["xi"][pf > 0, 1] == 0.0) and (pf > 0).any()      # the middle line
        return res.final.g[:, :3, 3]
    one, ten = lift(1), lift(10)
    assert one[20, 2] > 0.14 and np.abs(one - ten).max() < 1e-9, np.abs(one - ten).max()


def test_a_roller_oblique_to_the_strip_lifts_it():
    """The same roller with its axis oblique to the elements, (0.3, 1, 0): d is flat along the
    axis, which is no face coordinate, so the face minimiser's M is singular and the bounded
    gradient steps (or a Newton step clipped per coordinate, turned into an ascent) swung between
    edges: Newton stopped at load factor 0.1104 after 12 cut-backs (residual 1.11).  With the line
    search it completes in 10 steps, and 1 step ends within 2e-13 of them."""
    p = cs.Problem(M.rectangle(1.0, 0.1, 20, 1), cs.Material(1e5, 0.0, 0.01))
    p.clamp("x0")
    c = p.add_obstacle("cylinder", point=(0.7, 0, -0.115), axis=(0.3, 1, 0), radius=0.1, name="roller",
                       motion=dict(translate=(0.0, 0.0, 0.1)))
    st = p.solve(steps=10).final
    assert st.load_factor == pytest.approx(1.0) and st.balance_error < 1e-8
    assert st.g[20, 2, 3] == pytest.approx(0.152299200258, abs=1e-9)      # the 1-step run's tip
    assert _surface_depth(c, st.g, 1.0, 0.01) > -10 * c.tol


def test_a_ball_through_the_face_between_nodes_is_refused_without_face_samples():
    """The same ball raised 0.3 (through the plate) in 4 steps with faces = false: the nodes never
    feel it, and before the run ended with the ball on the far side (zero force, no error); raised
    0.05 it ended 0.04 through the contact face (the shell is 0.02 thick), zero force, no error.
    Now faces = false on an obstacle thinner than the elements warns at once, naming the key, and
    a state with the ball's middle beyond the face, or the thin ball deeper than h, is refused; a
    ball pressed into the face short of both is the nodal sampling's chord, not a crossing."""
    from core_se3.errors import AccuracyWarning

    def plate(faces):
        p = cs.Problem(M.rectangle(2.0, 1.0, 2, 1), cs.Material(1e4, 0.0, 0.02))
        p.clamp("x0")
        c = p.add_obstacle("sphere", centre=(1.5, 0.0, -0.07), radius=0.05, motion=dict(translate=(0, 0, 0.3)),
                           name="pin", law=dict(faces=faces))
        return p, c
    with pytest.warns(AccuracyWarning, match="faces = false: it can pass between the nodes"):
        p, c = plate(False)
    g0 = p.mesh.g0
    assert c.face_crossing(g0, 0.07) == "" and c.obstacle.distance([[1.5, 0.0, -0.01]], 0.07)[0] < -0.01
    assert "through the shell" in c.face_crossing(g0, 0.15)         # 0.035 deep, more than h = 0.02
    assert "element 1" in c.face_crossing(g0, 0.25)                 # centre at z = 0.005, the face at -0.01
    with pytest.raises(cs.ConvergenceError, match="faces = true"):
        p.solve(steps=4)
    p, c = plate("auto")
    st = p.solve(steps=4).final
    assert st.contact["pin"]["force"][2] > 0 and c.face_crossing(st.g, 1.0) == ""



def test_a_cam_edge_through_a_face_that_no_sample_holds_is_refused():
    """A box cam (half sizes 0.1 x 0.05, the default edge rounding 5e-4) turning about its axis
    under a 20 x 1 strip (elements 0.05 x 0.1): between two states its edge enters a face between
    the nodes deeper than its rounding, where the box's distance is not smooth (the ridge inside
    the edge) and the face sample is dropped.  The quarter turn in 10 steps ended the steps at
    load factors 0.5 and 0.6 with the strip flat, no force, penetration 0, the edge 0.0078 and
    0.011 through its contact face (six of its ten stored states had it unfelt in a face).  Such a state is now refused, naming the rounding and the fix
    (10 steps stop at 0.696 with it; a rounding larger than the edge's reach is not refused)."""
    def cam(**kw):
        p = cs.Problem(M.rectangle(1.0, 0.1, 20, 1), cs.Material(1e5, 0.0, 0.01))
        p.clamp("x0")
        c = p.add_obstacle("box", centre=(0.8, 0, -0.1), half_sizes=(0.1, 0.2, 0.05), name="cam",
                           motion=dict(axis=(0, 1, 0), angle=np.pi / 2, point=(0.8, 0, -0.1)), **kw)
        return p.mesh.g0, c
    g0, c = cam()
    assert c.obstacle.rounding == 5e-4 and len(c.face_el) == 20            # face samples on ('auto')
    assert c.penetration(g0, 0.5) == 0.0 and _surface_depth(c, g0, 0.5, 0.01) < -0.0076
    assert c.face_crossing(g0, 0.3) == ""                                   # below the strip
    for lam, deep in ((0.5, "0.00782"), (0.6, "0.0109")):
        why = c.step_error(g0, lam - 0.01, g0, lam)
        assert f"reaches {deep} into the contact face of element 15" in why and "rounded by 0.0005" in why
        assert "larger rounding" in why and "more load steps" in why
    g0, c = cam(rounding=0.02)                                              # the edge within its rounding
    assert c.face_crossing(g0, 0.5) == "" and c.face_crossing(g0, 0.6) == ""


def test_a_cam_with_a_rounded_edge_turns_in_ten_steps():
    """The cam above with the rounding the refusal advises (0.005, a tenth of its smallest half
    size) makes its quarter turn in 10 steps (1 to 5 tries each), every stored state with the
    strip outside it; at load factor 0.8 (72 degrees) its edge at (0.817, 0.0106) pushes the
    strip's face up: tip 0.0192 (a cantilever pushed there by 0.0156 - the rounding's 0.002:
    0.0209 - 0.0027; the sharp cam's run ended that step at 0.0140, the strip on the face)."""
    p = cs.Problem(M.rectangle(1.0, 0.1, 20, 1), cs.Material(1e5, 0.0, 0.01))
    p.clamp("x0")
    c = p.add_obstacle("box", centre=(0.8, 0, -0.1), half_sizes=(0.1, 0.2, 0.05), name="cam", rounding=0.005,
                       motion=dict(axis=(0, 1, 0), angle=np.pi / 2, point=(0.8, 0, -0.1)))
    res = p.solve(steps=10)
    tip = p.mesh.node_set("x1")
    for st in res.steps:
        assert _surface_depth(c, st.g, st.load_factor, 0.01) > -10 * c.tol and c.unfelt_face(st.g, st.load_factor)[0] is None
    assert 0.018 < res.steps[8].g[tip, 2, 3].mean() < 0.0209



def _sliding_ball(press, steps, tries=None):
    """The ball of the sliding tests below after ``steps`` equal steps: its rise to ``press`` past
    the plate's bottom face (load factor 0 -> 0.5), then its slide of 1.0 along it (0.5 -> 1).
    Returns the final positions after checking that the ball presses and has not passed through
    (and appends each stored step's tries to the list ``tries``)."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 8, 4), cs.Material(E=1e4, nu=0.3, h=0.02))
    p.clamp("x0"), p.clamp("x1")

    def motion(lam):
        T = np.eye(4)
        T[2, 3], T[0, 3] = (0.02 + press) * min(1.0, 2 * lam), max(0.0, 2 * lam - 1)
        return T
    c = p.add_obstacle("sphere", centre=(0.6, 0.1, -0.08), radius=0.05, motion=motion, name="ball")
    res = p.solve(steps=steps)
    st = res.final
    if tries is not None:
        tries.extend(s.attempts for s in res.steps[1:])
    assert st.contact["ball"]["force"][2] > 0 and _surface_depth(c, st.g, 1.0, 0.01) > -10 * c.tol
    return st.g[:, :3, 3]


@pytest.mark.parametrize("press", [0.01, 0.05])
def test_a_small_ball_sliding_along_a_plate_in_two_steps_or_eight(press):
    """A ball of radius 0.05 (face samples: the plate's elements are 0.25) rises under a plate
    clamped at both ends (2 x 1, h 0.02, E 1e4) until it presses ``press`` past its bottom face
    (load factor 0 -> 0.5), then slides 1.0 along it, four elements (0.5 -> 1): in 2 steps the
    slide is one step, the contact lost at the old place and regained four elements on.
    Frictionless, the end state is that of 8 steps: 7.7e-10 (press 0.01, the contact tolerance
    2e-8) and 7.7e-16 (press 0.05, deeper than h: the face points' sweep meets the ball's centre,
    where the run stopped with "a point is at the centre of the sphere" before)."""
    x2, x8 = _sliding_ball(press, 2), _sliding_ball(press, 8)
    assert np.abs(x2 - x8).max() < 1e-8


def test_a_small_ball_sliding_under_a_node_line_in_twenty_steps():
    """The ball above pressed 0.05 and slid in 20 steps: at load factor 0.7 it sits under the node
    line x = 1.0, held by the samples of the two faces either side, 3.4e-3 apart on the ball (the
    line a ridge between the bilinear faces): nearly redundant, the Uzawa update moved force from
    one to the other at a contraction of 0.982 per update (gaps +-2.1e-8 against the tolerance
    2e-8, multipliers 0.570 and 0.004), and the run stopped with "constraint error 1.06 x its
    tolerance after 25 multiplier updates" (9.87 x after 80).  With the geometric series of the
    updates summed (``ContactLoad._extrapolated``) it completes, and ends where 8 steps end:
    3.1e-9, within the contact tolerance 2e-8.  The ball is held by face samples alone (no node
    carries force), which the start of a try did not carry with the ball: each slide step started
    with the contact lost (the first residual 0.16 of the forces, whatever the step), and its
    first two took 125 and 113 tries; with the faces carried (``ContactLoad._face_shift``) 3 and
    4, and no step of the 20 more than 7 (the rise's steps 1 to 3, as before)."""
    tries = []
    assert np.abs(_sliding_ball(0.05, 20, tries) - _sliding_ball(0.05, 8)).max() < 2e-8
    assert max(tries) <= 10 and sum(tries) < 100


def test_a_ball_sliding_into_a_clamped_line_between_its_nodes_is_named():
    """The plate of the sliding tests with the node line x = 1.0 clamped too, the ball (y = 0.1,
    between the line's nodes at y = 0 and 0.25) pressed 0.015 past the plate's bottom face and
    slid in 2 steps: it must pass through the held edge, which no state allows.  The run stopped
    with "raise NewtonOptions.max_augmentations or the tolerance" (the deepest node, which the
    held-node hint looks at, was not inside it: the face samples were); now it names the held
    edge (0.000125 deep at load factor 0.682, the ball 0.036 from the line)."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 8, 4), cs.Material(E=1e4, nu=0.3, h=0.02))
    p.clamp("x0"), p.clamp("x1"), p.clamp(np.nonzero(np.abs(p.mesh.X[:, 0] - 1.0) < 1e-9)[0])

    def motion(lam):
        T = np.eye(4)
        T[2, 3], T[0, 3] = 0.035 * min(1.0, 2 * lam), max(0.0, 2 * lam - 1)
        return T
    p.add_obstacle("sphere", centre=(0.6, 0.1, -0.08), radius=0.05, motion=motion, name="ball")
    with pytest.raises(cs.ConvergenceError, match=r"obstacle 'ball' presses .* into the edge between nodes \d+ and "
                                                   r"\d+ of element \d+, whose translations a support holds"):
        p.solve(steps=2)


def test_a_ball_sliding_toward_a_clamped_line_names_the_line_ahead():
    """The plate above with the node line x = 1.25 clamped instead: the ball slid in 2 steps
    stopped at load factor 0.789 (its centre at x = 1.178, 0.072 from the line, whose edge it
    does not reach yet) with "raise NewtonOptions.max_augmentations" alone (about 5 minutes of
    cut-backs: the face next to the line props the ball ever more stiffly, a lever about the held
    edge, and the multiplier updates contract ever more slowly).  The stall is the updates' at
    the flat plate of that load factor, the sample 0.015 inside; the hint now looks along the
    ball's way on and names the edge it reaches at load factor (1.25 - 0.0357 + 0.4) / 2 =
    0.8071 (the ball's bottom-face circle of radius sqrt(0.05^2 - 0.035^2) = 0.0357 meets the
    line; 33 load factors from 0.789 to 1: within 0.0066 after it)."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 8, 4), cs.Material(E=1e4, nu=0.3, h=0.02))
    p.clamp("x0"), p.clamp("x1"), p.clamp(np.nonzero(np.abs(p.mesh.X[:, 0] - 1.25) < 1e-9)[0])

    def motion(lam):
        T = np.eye(4)
        T[2, 3], T[0, 3] = 0.035 * min(1.0, 2 * lam), max(0.0, 2 * lam - 1)
        return T
    c = p.add_obstacle("sphere", centre=(0.6, 0.1, -0.08), radius=0.05, motion=motion, name="ball")
    assert c.update_multipliers(p.mesh.g0, 0.789) > 1.0          # the stalled updates' state
    hint = c.failure_hint()
    assert "into the edge between nodes" in hint and "whose translations a support holds at load factor" in hint
    lam_k = float(hint.split("at load factor ")[1].split(",")[0])
    assert 0.8071 < lam_k < 0.8071 + 0.0066


def _roller_under_plate(steps):
    """A roller (radius 0.06, axis along y under x = 0.8, between the node lines 0.75 and 1.0)
    rising 0.15 under a 2 x 1 plate (8 x 4, h 0.02, E 1e4, nu 0.3) clamped at both ends: first
    contact at load factor 1/3, then pressed 0.1 in.  Face samples by 'auto' (0.06 < 0.35)."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 8, 4), cs.Material(E=1e4, nu=0.3, h=0.02))
    p.clamp("x0"), p.clamp("x1")
    c = p.add_obstacle("cylinder", point=(0.8, 0.5, -0.12), axis=(0, 1, 0), radius=0.06,
                       motion=dict(translate=(0, 0, 0.15)), name="roller")
    return p, c, p.solve(steps=steps).final


def test_a_roller_pressed_across_a_plate_between_its_node_lines():
    """A line contact across the faces: the roller's axis lies along the faces' eta lines, where
    d is linear (no curvature), so each face's closest point was the lower end of its line; the
    force there tilted the face the other way, and the next iterate took the other end (or
    none): Newton alternated at first contact and the run stopped after 12 cut-backs ('no
    convergence in 30 iterations (residual 1.00e+00)' at load factor 0.333374), also with 3
    steps and for a box's rounded edge.  Now a ruled coordinate keeps the face's middle line
    (``contact_faces._flat``): 4 and 8 steps end alike (frictionless: no path dependence) to the
    contact tolerance, the state is mirror symmetric about its middle line y = 0, and the reported penetration
    is that of the lines' lower ends (4.2e-4), at least the surface's actual depth (3.9e-4 on a
    0.01 grid; the samples alone said 9e-10)."""
    p, c, four = _roller_under_plate(4)
    _, _, eight = _roller_under_plate(8)
    x4, x8 = four.g[:, :3, 3], eight.g[:, :3, 3]
    assert np.abs(x4 - x8).max() < 2e-8
    X = p.mesh.X
    mirror = [int(np.argmin(np.abs(X - [x, -y, z]).sum(1))) for x, y, z in X]
    assert np.abs(x4[mirror] * [1, -1, 1] - x4).max() < 2e-8
    F = four.contact["roller"]["force"]
    assert F[2] > 0.1 and abs(F[1]) < 1e-9 * F[2]
    depth = -_surface_depth(c, four.g, 1.0, 0.01)
    assert 0 < depth <= four.contact["roller"]["penetration"] + c.tol


def _edge_under_plate(steps):
    """The plate of :func:`_roller_under_plate` under a box's edge instead (half sizes 0.2 x 0.8 x
    0.2 turned 45 degrees about y, edge up at x = 0.8, the default rounding 0.002; face samples by
    'auto'), rising 0.075: first contact at load factor 2/3, pressed 0.025 in (1.25 h)."""
    p = cs.Problem(M.rectangle(2.0, 1.0, 8, 4), cs.Material(E=1e4, nu=0.3, h=0.02))
    p.clamp("x0"), p.clamp("x1")
    c = p.add_obstacle("box", centre=(0.8, 0.0, -0.06 - 0.2 * np.sqrt(2)), half_sizes=(0.2, 0.8, 0.2),
                       rotation=(0, np.pi / 4, 0), motion=dict(translate=(0, 0, 0.075)), name="edge")
    return c, p.solve(steps=steps).final


def test_a_box_edge_pressed_across_a_plate_between_its_node_lines():
    """The roller's line contact with a box's rounded edge: the faces' iterates came to the edge
    over the box's flat sides (no curvature: not a ruled line there) with their eta moved off
    the middle, were held wherever they met the edge, and jumped between those places; Newton
    stopped at first contact (load factor 0.678 after 12 cut-backs, 'no convergence ... residual
    1.00e+00', in 3 steps and in 6).  A ruled line met off its middle now goes to its middle:
    3 and 6 steps end alike (frictionless), the force is vertical and symmetric."""
    c, three = _edge_under_plate(3)
    _, six = _edge_under_plate(6)
    assert np.abs(three.g[:, :3, 3] - six.g[:, :3, 3]).max() < 2e-8
    F = three.contact["edge"]["force"]
    assert F[2] > 0.01 and abs(F[1]) < 1e-9 * F[2] and abs(F[0]) < 1e-2 * F[2]
    assert 0 < three.contact["edge"]["penetration"] < 0.1 * c.h


# ----------------------------------------------------------------------------- lift-off
HINGED_STRIP = """
name = "hinged-strip"
units = "N-mm-MPa"
[mesh]
generator = "rectangle"
L = 17.2
width = 5.0
nx = 20
ny = 1
[material]
E = 0.8969
nu = 0.4801
h = 0.42
[[supports]]
type = "fix"
edge = "x0"
dofs = [0, 1, 2, 3, 5]
[[obstacles]]
type = "half_space"
name = "floor"
point = [0.0, 0.0, -0.21]
normal = [0.0, 0.0, 1.0]
[[loads]]
type = "gravity"
rho = 1.8e-9
scale = "constant"
g = [0.0, 0.0, -9810.0]
[fields.rotating]
type = "uniform"
B = [0.005, 0.0, 0.0]
scale = [[0.0, 0.0], [0.1, 1.0], [1.0, 1.0]]
rotate = { axis = [0.0, -1.0, 0.0], angle = 3.0, start = 0.1, end = 1.0 }
[[magnets]]
Br = [0.143, 0.0, 0.0]
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = STEPS
"""


def test_lift_off_is_not_a_limit_point(tmp_path):
    """Issue 29: a magnetic strip hinged at x = 0 on a floor, lifted by a field that turns up
    from +x through +z toward -x, and laid down again: the lift-off step stopped with 'load
    control met a limit point' (S_p 0.137, a jump 26.8x the tangent's prediction: the tangent
    of the strip held by its contact springs).  Now the run completes, and 40 and 80 steps give
    the same states at the common load factors (a continuous path, not a snap)."""
    from core_se3 import scenario
    tips = {}
    for steps in (40, 80):
        scn = scenario.loads(HINGED_STRIP.replace("STEPS", str(steps)), file="hinged.toml")
        res = scenario.run(scn, out=str(tmp_path / f"o{steps}"))
        doc = json.load(open(res.files["results"]))
        assert doc["status"] == "complete" and abs(doc["steps"][-1]["load_factor"] - 1) < 1e-12
        tips[steps] = {round(s["load_factor"], 9): np.array(s["probes"]["tip"]["u"]) for s in doc["steps"]}
        assert max(u[2] for u in tips[steps].values()) > 10.0                         # it did lift off
    for lam, u in tips[40].items():
        assert np.linalg.norm(u - tips[80][lam]) < 1e-5 * 17.2, lam

"""Trustworthy load steps (issue 29, docs/STEPS.md): the path check, the stability check, the
sign of det K from the factors, bounded splitting, translation invariance, and critical points
of arc length located to a tolerance whatever the first step.  Each test fails on the code
before these checks."""
import re
import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from core_se3 import Material, Problem, mesh, scenario
from core_se3.catalogue import run_case
from core_se3.errors import ConvergenceError, MeshWarning
from core_se3.model.fields import UniformField, rotating_direction
from core_se3.solvers import NewtonOptions, arc_length, displacement_control, make_solver
from core_se3.solvers.direct import available_solvers
from core_se3.solvers.linalg import Factorization
from core_se3.solvers.step_checks import path_measures, state_gap

ZHAO = dict(nu=0.0, L=17.2, h=0.42)


def _zhao(q, nx, steps=1, **kw):
    """The Zhao et al. beam at q = A Br Ba L^2 / (mu0 E I) (Ba = 7.8328 mT q / 20)."""
    return run_case("magnetic-cantilever", mesh=(nx, 1), steps=steps,
                    overrides=dict(ZHAO, Ba_max=0.0078328 * q / 20), **kw)


# ------------------------------------------------------------------ the path check -----------
@pytest.mark.parametrize("q, nx", [(14, 40), (17, 40), (20, 40), (15, 90)])
def test_one_step_zhao_beam_ends_on_the_elastica(q, nx):
    """The issue's cases: in one step these converged (exit 0) to a tip angle of pi or a looped
    state, 82-130 % off the elastica (3_magnetic_perpendicular_field); the path check refuses
    the tries whose Newton corrections grew, and the cut-backs end on the path (the 20 ... 120
    element sweep of benchmarks/robustness.py: at most 0.16 %)."""
    doc, res, _ = _zhao(q, nx)
    assert doc["reference"]["error"] < 0.005
    refused = [e for e in res.log if e["reason"].startswith("path check")]
    assert refused and all(e["contraction"] >= 1.0 or e["travel"] >= 1.5 for e in refused)
    assert all(e["contraction"] < 1.0 and e["travel"] < 1.5 for e in res.log if e["converged"])
    checks = res.final.checks
    assert checks["path_check"] and checks["contraction"] < 1.0 and checks["det_sign"] == 1
    assert checks["path_rejections"] == len(refused)


def test_without_the_path_check_the_jump_is_accepted():
    """The same run with path_check and midpoint_probe off lands on the wrong state (what the
    checks prevent).  With the probe alone the jump is refused too: the try turned a node by
    4.39 rad, its probe 0 -> 0.5 does not converge (an element turns by pi), it is cut back and
    the cut-backs land on the elastica."""
    doc, res, _ = _zhao(17, 40, path_check=False, midpoint_probe=False)
    assert doc["reference"]["error"] > 0.5 and res.log[0]["converged"] and res.log[0]["contraction"] > 3
    doc, res, _ = _zhao(17, 40, path_check=False)
    assert res.log[0]["reason"].startswith("midpoint probe") and not res.log[0]["midpoint_probe"]["converged"]
    assert doc["reference"]["error"] < 0.005


def test_one_step_rollup_keeps_its_iterations():
    """The roll-up in one step contracts at once (Theta < 0.1): 4 iterations, one try.  Its
    converged increment turns the tip past pi, so the midpoint probe runs too: a try from the
    flat strip to half the moment, 4 more Newton iterations (28.2, 1.78, 1.4e-9 ... ell), det K +1
    as on the path -- 8 linear solves in all, against 4 with midpoint_probe off."""
    doc, res, _ = run_case("rollup", steps=1)
    assert len(res.log) == 1 and res.log[0]["iterations"] == 4 and doc["reference"]["error"] < 1e-12
    probe = res.log[0]["midpoint_probe"]
    assert probe["converged"] and probe["det_sign"] == 1 and probe["iterations"] == 4
    assert res.final.checks["midpoint_probes"] == 1 and res.final.checks["probe_iterations"] == 4
    assert res.final.linear_solves == 8
    doc_off, res_off, _ = run_case("rollup", steps=1, midpoint_probe=False)
    assert res_off.final.linear_solves == 4 and "midpoint_probe" not in res_off.log[0]
    assert np.array_equal(res_off.final.g, res.final.g)


@pytest.mark.parametrize("name, steps", [("curved-rollup", 2), ("rollup", 6)])
def test_a_try_that_turns_a_node_by_pi_is_probed_whichever_way_round_off_falls(name, steps, pinned_backend):
    """A roll-up stepped by exactly pi a step turns its tip by pi to round-off: curved-rollup in
    2 steps by 3.1415926535897927 and ...913 rad (an ulp or two below pi), rollup in 6 steps by
    pi, pi, pi, pi + 4e-16, pi - 5e-15, pi + 5e-15.  With the trigger at pi the last bit decided:
    curved-rollup was not probed, rollup in 6 steps probed its 4th and 6th steps only.  The
    trigger has a margin (PROBE_TURN = 0.95 pi): every such step is probed (3 Newton iterations
    each), the tries and their iterations (6 and 19) unchanged, none refused.  (One backend for
    both runs, ``pinned_backend``: 'auto' switches to numba after a count of work, and the two
    runs' work differs by the probes, so the switch could fall at different steps: final frames
    1.4e-16 apart under NumPy 2 after the end check stopped assembling tangents for a dead
    moment, which is not conservative by its kind.)"""
    from core_se3.solvers.step_checks import PROBE_TURN
    assert 0.9 * np.pi < PROBE_TURN < np.pi * (1 - 1e-6)
    doc, res, _ = run_case(name, steps=steps)
    _, off, _ = run_case(name, steps=steps, midpoint_probe=False)
    assert [s.checks["midpoint_probes"] for s in res.steps[1:]] == [1] * steps
    assert [s.iterations for s in res.steps] == [s.iterations for s in off.steps] and len(res.log) == steps
    assert all(e["midpoint_probe"]["converged"] and e["midpoint_probe"]["det_sign"] == 1 for e in res.log)
    assert np.array_equal(res.final.g, off.final.g)


def _fuzz_strip_144():
    """A clamped strip 5 x 2 (its four inner nodes moved) under a dead pressure and a dead end
    moment of 1.9 turns (benchmarks/invariants_fuzz.py, seed 4, problem 144)."""
    m = mesh.rectangle(0.44761960125930955, 0.2544472431567919, 5, 2)
    g0 = m.g0.copy()
    g0[[7, 8, 9, 10], :3, 3] += [[0.007196496522220874, 0.004509266984213194, 0.0],
                                 [0.006656615246067699, 0.004148399770708501, 0.0],
                                 [-0.0037722843859819832, -0.004219913497637306, 0.0],
                                 [-0.0020540157169191553, 0.00435072954661461, 0.0]]
    p = Problem(mesh.Mesh(g0, m.quads, m.edges, shape=m.shape),
                Material(E=9403657.000003621, nu=0.21800779161573836, h=0.007998715156835508, rho=1.0))
    p.clamp("x0")
    p.add_pressure(0.04529166965900603, direction=(0.15296855214681812, -0.8983184652594932, 0.4118550194278744))
    p.add_edge_moment("x1", (0.0, -2.845960815518026, 0.0))
    return p


@pytest.mark.parametrize("steps", [1, 2])
def test_a_long_try_over_a_limit_point_is_refused_by_the_midpoint_probe(steps):
    """Problem 144 has a limit point at 0.7004 of its load (arc length); 4, 16 and 64 steps stop
    there.  In 1 and 2 steps the try 0.5 -> 1 contracted (corrections 15.5, 0.63, 0.28, 0.013 ...
    ell) onto a state with det K +1 (sym K: 2 negative eigenvalues, lambda_min / lambda_max
    -5.6e-6) and the solve exited ok at 1.0, off the path.  The try turned a node by 6.0 rad:
    probed, a try from 0.5 to 0.75 converges (7.73, 0.32, 0.025 ... ell) onto det K -1, so it is
    cut back, and the cut-backs stop at the limit point as 4 steps do."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError, match="after 12 cut-backs") as info:
            _fuzz_strip_144().solve(steps=steps)
        res = info.value.result
        refused = [e for e in res.log if e["reason"].startswith("midpoint probe")]
        assert len(refused) == 1 and refused[0]["lam"] == 1.0 and refused[0]["midpoint_probe"]["det_sign"] == -1
        assert "converged onto a state with det K -1" in refused[0]["reason"] and "arc length" in refused[0]["reason"]
        last = float(re.search(r"the last converged load factor is ([0-9.]+)", str(info.value)).group(1))
        assert 0.69 < last < 0.7004
        # what the probe prevents: without it the solve exits ok at the full load
        assert _fuzz_strip_144().solve(steps=steps, midpoint_probe=False).final.load_factor == 1.0


def _fuzz_panel_177():
    """A 3 x 1 cylindrical panel (R/h 1240), clamped on x0 and pinned on x1, under a dead pressure
    (benchmarks/invariants_fuzz.py, seed 5, problem 177): a limit point at 0.607643 +- 0.00052 of
    the load (arc length)."""
    p = Problem(mesh.cylinder_panel(0.40115115487002156, 0.16296229852984703, -0.3104180227372994,
                                    0.3104180227372994, 3, 1),
                Material(E=533611619.6309353, nu=0.04734222007885219, h=0.0003235678601587087, rho=1.0))
    p.clamp("x0")
    p.fix("x1", (0, 1, 2))
    p.add_pressure(23.368707229878428, direction=(-0.9231435205145561, 0.27482395844596713, -0.2688453689318093))
    return p


@pytest.mark.parametrize("steps", [1, 4])
def test_a_try_past_the_limit_point_its_current_stiffness_announces_is_probed(steps):
    """Fuzz problem 177: 16 steps fail at its limit point ('met a limit point', last converged
    0.607559).  In 1, 2 and 4 steps the try 0.5 -> 0.75 (turn 0.18 rad, corrections 0.17, 0.11,
    0.025 ... ell) converged with det K +1 onto another branch (stepping back from it fails at
    0.660), and after it the runs failed at 0.7555, naming a limit point there, with that state kept
    (4 steps stored it as their step at 0.75).  The current stiffness S_p at 0.5 (0.17 of the first
    step's, 0.45 at 0.25) extrapolates to zero at 0.51 -- 0.54, within the try: it is probed, its
    probe at 0.625 does not converge, it is cut back, and so is the cut-back try 0.5625 -> 0.6875
    (S_p 0.13, zero at 0.628); the runs stop at the limit point as 16 steps do."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError, match="limit point") as info:
            _fuzz_panel_177().solve(steps=steps)
    res = info.value.result
    last = float(re.search(r"the last converged load factor is ([0-9.]+)", str(info.value)).group(1))
    assert 0.6 < last < 0.6077 and max(s.load_factor for s in res.steps) < 0.6077
    refused = [e for e in res.log if e["reason"].startswith("midpoint probe")]
    assert refused and all("current stiffness" in e["reason"] for e in refused)


# benchmarks/invariants_fuzz.py, seed 8, problems 158 and 206: one-step answers off the path that
# neither the path check nor the midpoint probe sees (docs/STEPS.md)
_ANNULUS_158 = {"mesh": ("annulus", (0.19820654962114895, 0.3119974961870658, 0.5730164961304531, 2, 2)),
                "L": 0.11357562257401756, "perturb": 0.07988844578558214, "pseed": 1052288158,
                "E": 1019.8135393878902, "nu": 0.12057236232992696, "h": 0.00020637736181889618, "support": "clamp",
                "loads": [("edge_force", "x1", [4.4043074957918465e-09, -4.2081028373951467e-10,
                                                1.1239693391170171e-08]),
                          ("edge_force", "x1", [-5.779342735438861e-08, 9.79835660707923e-11,
                                                2.461205805926261e-10])],
                "alpha": 1.8063962014984463}
_PLATE_206 = {"mesh": ("rectangle", (0.10549003466104424, 0.029132301687481838, 2, 2)), "L": 0.10549003466104424,
              "perturb": 0.0016338780053809954, "pseed": 182272822, "E": 335730710.9599362,
              "nu": 0.47619974747245764, "h": 0.00011828718002590931, "support": "clamp",
              "loads": [("edge_moment", "x1", [-6.20073236620597e-05, -1.3005919081961277e-05,
                                               -4.123896581755797e-05]),
                        ("gravity", 1971.3417472557571, [-0.07521320646433102, 0.9942643417831738,
                                                         -0.07603546693370118])],
              "alpha": 4.571112118447354}


def _fuzz_problem(spec):
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
    import invariants_fuzz as fuzz
    return fuzz.build(spec)


@pytest.mark.parametrize("spec, steps, off", [(_ANNULUS_158, 1, 1.05), (_ANNULUS_158, 2, 1.05),
                                              (_ANNULUS_158, 4, 1.05), (_PLATE_206, 1, 1.89),
                                              (_PLATE_206, 2, 1.89)])
def test_a_try_of_many_iterations_onto_another_equilibrium_is_refused_by_its_parts(spec, steps, off):
    """Problem 158 (a clamped 2 x 2 annulus under two dead edge forces; conservative, no critical
    point) in 1, 2 and 4 steps converged from 0 to 0.25 in 11 iterations (corrections 1.53, 0.737,
    0.322, 0.308, 0.165, 0.186 ... ell: Theta 0.481, travel 1.14, turn 0.30 rad; the midpoint probe
    vouched) onto a stable state 0.142 ell off the path, and exited ok 1.05 ell from the 16- and
    256-step answers; problem 206 (a clamped 2 x 2 plate, dead end moment and gravity) in 1 and 2
    steps in 8 iterations (Theta 0.359 and 0.557), 1.89 ell off.  Solved again in 4 parts, the try
    0 -> 0.25 of 158 ends 0.120 ell from it (the parts of the legitimate tries of the catalogue
    agree to 3e-14 ell), so it is cut back, and every run ends where 16 steps do."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = _fuzz_problem(spec)
        r16 = p.solve(steps=16)
        res = _fuzz_problem(spec).solve(steps=steps)
        ell = p.length_scale
        assert state_gap(res.final.g, r16.final.g, ell) < 1e-9
        refused = [e for e in res.log if e["reason"].startswith("refine check")]
        assert any("ell from it" in e["reason"] for e in refused) and "arc length" in refused[0]["reason"]
        # the parts' solves are the try's too (a try's linear_solves counts its Newton solves and its checks')
        for e in res.log:
            if "refine_check" in e:
                own = e["linear_solves"] - e["refine_check"]["linear_solves"] - e.get("midpoint_probe", {}).get("linear_solves", 0)
                assert e["refine_check"]["linear_solves"] >= e["refine_check"]["iterations"] > 0 and own >= e["iterations"]
        # what the check prevents: without it the run exits ok on a state that far off the path
        wrong = _fuzz_problem(spec).solve(steps=steps, refine_check=False)
        assert wrong.final.load_factor == 1.0 and state_gap(wrong.final.g, r16.final.g, ell) > 0.9 * off


def test_the_count_of_sym_k_is_no_refusal_criterion_for_a_dead_moment():
    """Why the end check counts nothing for a non-symmetric K (fuzz problem 144, docs/STEPS.md):
    the count of negative eigenvalues of the Jacobi-scaled sym K is unit-free for any K (a
    diagonal congruence keeps the inertia), but with a dead end moment it rises on the right
    path: the one-step roll-up ends on the closed-form circle (1e-12) with 2, as problem 144's
    wrong one-step answer does; a start-versus-end comparison would refuse both.  Measured along
    its 12 steps: 0 up to 0.5 of the moment, 1 at 0.583, 2 from 0.667 on."""
    from core_se3.solvers.stability import ASYM_TOL, asymmetry, inertia
    doc, res, p = run_case("rollup", steps=1)
    K = p.tangent(res.final.g, 1.0)
    assert doc["reference"]["error"] < 1e-12 and asymmetry(K, p.assembler().free) > 1e3 * ASYM_TOL
    assert inertia(p.tangent(p.mesh.g0, 0.0))[1] == 0 and inertia(K) == (1, 2)


def test_path_measures_count_growth_at_the_step_scale_only():
    assert path_measures([1.0, 0.4, 0.02, 1e-6, 1e-12, 3e-12])[0] == pytest.approx(0.4)
    assert path_measures([1.0, 1.2, 1e-3])[0] == pytest.approx(1.2)          # a jump grows at once
    assert path_measures([1.0, 0.31, 1.05, 0.4])[0] == pytest.approx(1.05 / 0.31)    # ... or later
    # a wiggle 500x below the first correction (the hemisphere's penalty springs) is not counted
    assert path_measures([3.4e-2, 7.05e-5, 7.5e-5, 4e-10])[0] < 0.01
    assert path_measures([1.0, 0.45, 0.45, 0.45, 0.3])[1] == pytest.approx(1.65)   # a long wander
    assert path_measures([0.5]) == (0.0, 0.0)


def test_growth_beyond_pi_ell_counts_whatever_the_first_correction():
    """A first correction of many ell (rotations past pi) holds other equilibria in its ball: a
    growth at a few ell counts even below half of it.  The corrections of the try that jumped
    (the panel below, 0.219 -> 0.3125 of its load): Theta 0.25 counted at 1/2 of 9.15 ell."""
    assert path_measures([9.15416, 2.27637, 2.85071, 2.93294, 1.3877, 1.16847, 0.31542])[0] > 1.0
    assert path_measures([4.16, 1.21, 1.32, 0.226, 0.428])[0] < 1.0     # the hemisphere's zig-zag


def test_a_growth_by_a_quarter_of_the_step_counts_whatever_the_pair():
    """A correction 25x the one before it, 0.46 of the first (the plate below, 0.578 -> 0.613 of
    its load): the growth 0.418 ell is 0.44 of the step's scale (GROWTH_REACH 1/4).  The largest
    growth of an accepted try measured, the quarter hemisphere's 0.256 -> 0.522 of a first 2.1 ell
    (0.13 of it), still does not count; nor does a growth of 0.2 of the step, however fast."""
    assert path_measures([0.951, 0.0316, 0.0211, 0.0556, 0.0171, 0.435, 0.0057, 0.0307])[0] > 25
    assert path_measures([2.1, 0.256, 0.522, 0.0254, 0.0725, 0.000437, 0.00117])[0] < 1.0
    assert path_measures([1.0, 0.01, 0.21, 0.01, 1e-4])[0] < 1.0


def _oblique_panel(steps):
    """A clamped cylindrical panel 2 x 2 (one inner node moved) under a compressive edge force
    oblique to its free edge (benchmarks/invariants_fuzz.py, seed 4, problem 38)."""
    m = mesh.cylinder_panel(0.1637278128039579, 0.10498708007622841, -0.5771916919432326,
                            0.5771916919432326, 2, 2)
    g0 = m.g0.copy()
    g0[4, :3, 3] += (0.0021330031819409363, 0.0007595369649474951, 0.0)
    p = Problem(mesh.Mesh(g0, m.quads, m.edges, shape=m.shape),
                Material(E=5977.117247077262, nu=0.37797630667687593, h=0.0039032364467068642))
    p.clamp("x0")
    p.add_edge_force("x1", (-0.0011243807732677624, -2.766229201817546e-06, 5.018295416958634e-06))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return p, p.solve(steps=steps)


def test_one_step_oblique_panel_ends_where_sixteen_steps_do():
    """In one step (cut back to 0.125, 0.219, 0.3125, ...) it exited 'ok' on a stable state 1.40
    ell from the 16-step (and 128-step) answer: the try 0.219 -> 0.3125 converged with corrections
    9.15, 2.28, 2.85, 2.93 ... ell onto another equilibrium.  Now that try is refused; all agree
    to round-off (1e-14 ell)."""
    p, r16 = _oblique_panel(16)
    for steps in (1, 2):
        _, res = _oblique_panel(steps)
        assert np.abs(res.final.g - r16.final.g).max() < 1e-9 * p.length_scale


def _compressed_plate(steps):
    """A clamped plate 4 x 2 (three inner nodes moved) under a follower pressure and an edge force
    of about 5 Euler loads 1 % off its axis (benchmarks/invariants_fuzz.py, seed 4, problem 82)."""
    m = mesh.rectangle(6.128727735321672, 1.936039187878415, 4, 2)
    g0 = m.g0.copy()
    g0[[6, 7, 8], :3, 3] += [[0.049468317539284934, 0.07703383891764673, 0.0],
                             [-0.045667939820909886, 0.074140452088936, 0.0],
                             [-0.056386096952471654, -0.029040266767528824, 0.0]]
    p = Problem(mesh.Mesh(g0, m.quads, m.edges, shape=m.shape),
                Material(E=95821335112.07649, nu=0.24161289977156608, h=0.10110366534437852))
    p.clamp("x0")
    p.add_pressure(8.048088877146736, follower=True)
    p.add_edge_force("x1", (-1831882.0087996104, 12849.889693128865, 7805.068975530234))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return p, p.solve(steps=steps)


def test_one_step_compressed_plate_ends_where_sixteen_steps_do():
    """In one step the cut-back try 0.578 -> 0.613 converged with corrections 0.951, 0.032, 0.021,
    0.056, 0.017, 0.435 ... ell onto another equilibrium (0.81 ell off the path; 1.97 ell at the
    end) and exited 'ok': the growth 0.017 -> 0.435 (25x) lay below half of the first correction.
    A growth that carries the iterate a quarter of the step's scale beyond the correction before
    it (GROWTH_REACH) now counts too: the try is refused, and 1 step ends where 16 do."""
    p, r16 = _compressed_plate(16)
    _, res = _compressed_plate(1)
    assert np.abs(res.final.g - r16.final.g).max() < 1e-9 * p.length_scale


# benchmarks/invariants_fuzz.py, seed 4, problem 108: a clamped and pinned cylindrical panel 3 x 1
# under a follower pressure and a dead pressure of the same size, oblique
_PANEL_108 = {"mesh": ("cylinder_panel", (0.2314910529772749, 0.18829688713191461, -0.7483032251942563,
                                          0.7483032251942563, 3, 1)),
              "L": 0.3464510030930185, "perturb": 0.1286852574727477, "pseed": 117060767, "E": 46888.19504659504,
              "nu": 0.18761021978776873, "h": 0.0003625921147245226, "support": "clamp+pin",
              "loads": [("follower_pressure", -0.0011280491061585727),
                        ("pressure", 0.0011280491061585727, [0.7596969865099951, -0.00943267707896301,
                                                             -0.6502088228336774])],
              "alpha": 242.9710429321577}


def _panel_108(chords):
    """Fuzz problem 108; ``chords``: its two pressures integrated over the bilinear quads between
    the nodes (``SurfaceLoad`` without the element's j0, as every pressure was before the area
    loads took the element's own geometry), else as ``add_pressure`` gives them."""
    import copy
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
    import invariants_fuzz as fuzz
    from core_se3.model.loads import SurfaceLoad
    if not chords:
        return fuzz.build(_PANEL_108)
    spec = copy.deepcopy(_PANEL_108)
    (_, pf), (_, pd, d) = spec.pop("loads")
    spec["loads"] = []
    p = fuzz.build(spec)
    p.add(SurfaceLoad(p.mesh, pf, True, name="follower pressure"))
    p.add(SurfaceLoad(p.mesh, pd * np.asarray(d) / np.linalg.norm(d), False, name="dead pressure"))
    return p


def test_a_limit_point_is_not_called_a_bifurcation_after_a_jump_across_it(monkeypatch):
    """Arc length finds a limit point at 0.290822 +- 0.00026 of this panel's load (the largest load
    factor on the path 0.290828).  In 4 and 16 steps the try from 0.290741 to 0.2910156, beyond it,
    converged with corrections 0.035, 0.0125, 0.0038, 0.0152 ... ell (a growth of 0.33 of the step's
    scale, its pair just below half of it) onto another state and confirmed the sign change of det K
    there: the run stopped calling the point a bifurcation the path 'went on continuously through'.
    That try is now refused (GROWTH_REACH): the run fails at the limit point and says so.

    The panel's pressures are the chords' (``_panel_108``): on the element's own geometry (its
    3 elements turn by 0.499 rad each) the follower pressure is 1 / 0.959 and the dead one
    1 / 0.990 of the chords' and, the two nearly balancing, the path changes: its limit point
    moves to 0.2857128 (the next tests; read there as a bifurcation before the return check).  Scaling the follower pressure by 0.90 ... 0.97 (2 to 16
    steps), or it by 0.955 ... 0.965 and the dead one by 0.99 ... 1.0 (lam_end 0.8 ... 1.2, 3 and 4
    steps), gave no panel whose outcome GROWTH_REACH decides (the jumps grow at the step's scale
    or the point is a bifurcation); with the chords' pressures it does.  The return check (a
    located sign change's far side solved back to its near side must land there) refuses the same
    try on its own: its end solved back at 0.290741 grows its Newton corrections (the path check)
    and lands 0.0093 ell from the state there, the sides 0.020 ell apart; without both the jump is
    called a bifurcation."""
    from core_se3.solvers import step_checks

    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(ConvergenceError) as exc:
                _panel_108(chords=True).solve(steps=4)
        return exc.value
    err = run()
    msg = str(err)
    assert "limit point" in msg and "bifurcation" not in msg, msg
    assert err.result.steps[-1].load_factor <= 0.290828
    monkeypatch.setattr(step_checks, "GROWTH_REACH", np.inf)         # the return check tells them apart too
    err = run()
    assert "limit point" in str(err) and "bifurcation" not in str(err), str(err)
    assert any(e.get("return_check") and "return check" in e["reason"] for e in err.result.log)
    monkeypatch.setattr(step_checks.StepChecks, "judge_return", lambda *a: "")   # neither: a 'bifurcation'
    assert "bifurcation" in str(run())


_LIMIT_108 = 0.2857128    # arc length, dlam0 = 0.002, ds_max_factor 1: +- 3.2e-6, the path's largest load factor


@pytest.mark.parametrize("steps", [1, 4, 16])
def test_panel_108_on_its_elements_geometry_stops_at_its_limit_point_and_names_it(steps):
    """With the pressures on the element's own geometry (``add_pressure``) the panel's path has a
    limit point at 0.2857128 +- 3.2e-6 (arc length from dlam0 = 0.002 with ds_max_factor 1: the
    largest load factor of the path, which turns back down to a second limit point at 0.141985;
    load control in 4000 steps, checks off, fails there with S_p 2.2e-4 of its start).  1, 4 and
    16 steps stopped at a 'bifurcation' between 0.2856445 and 0.2858887 (1 step: 0.2861328) that
    'the path went on continuously through': the try 0.2856445 -> 0.2858887 converged beyond the
    limit point onto another branch (corrections 0.0188, 0.0049, 0.0093, 0.0027 ... ell, Theta
    0.26, travel 0.96: the path check lets it through) with det K -1 and confirmed the sign change.
    Now the located change is checked for continuity (the return check): that state solved back at
    0.2856445 lands 0.0112 ell from the state there, the two sides being 0.0133 ell apart (a real
    bifurcation's return lands within 1e-17 ell), so the bracket is dropped and the runs fail at
    the limit point, its load factor between the last converged one and the failed one, saying
    'limit point'."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError) as exc:
            _panel_108(chords=False).solve(steps=steps)
    msg = str(exc.value)
    assert "limit point" in msg and "bifurcation" not in msg, msg
    failed = float(re.search(r"Newton failed at load factor ([0-9.]+)", msg).group(1))
    last = float(re.search(r"the last converged load factor is ([0-9.]+)", msg).group(1))
    assert last <= _LIMIT_108 + 1e-5 and failed >= _LIMIT_108 - 1e-5, (last, failed)
    assert failed - last <= 2.5e-4                 # the smallest increment of 1 step's cut-backs: 2^-12


def test_arc_length_reads_panel_108s_limit_point_from_a_step_across_it():
    """From dlam0 = 0.01 arc length stepped from 0.285577 to 0.285812, across the limit point
    (0.2857128) onto another branch with det K of the other sign and the load factor rising at both
    ends, and reported a 'bifurcation at 0.285694 +- 0.00012' on a path rising on to 0.35.  The
    bracket's far end solved back at 0.285577 (load control) grows its Newton corrections 4.2x (the
    path check) and does not reach its near end, 0.0136 ell away: the ends do not connect, so the
    step is refused and halved (``critical.returns``; the deep strip's ends, 4e-6 ell apart, connect
    to 9e-16 ell); the shorter steps follow the path over its limit point and report it at 0.285713
    +- 9.5e-6."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        arc = arc_length(_panel_108(chords=False), lam_end=0.35, dlam0=0.01)
    first = arc.critical_points[0]
    assert first.kind == "limit", [cp.describe() for cp in arc.critical_points]
    assert abs(first.lam - _LIMIT_108) <= first.accuracy * first.lam + 1e-5
    assert not [cp for cp in arc.critical_points if cp.kind == "bifurcation"]


def test_a_shell_with_an_inexact_tangent_is_not_cut_back_forever():
    """The quarter hemisphere (penalty springs) in load control: its Newton repeats a correction
    of the order of 1e-3 of the first at every step size; counting it refused every try down to the
    smallest cut-back (3774 tries instead of 10).  Now the 10 steps take 10 tries."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).parent))
    from parallel_cases import build
    prob, steps, kw = build("sze-hemisphere")
    res = prob.solve(steps=steps, solver="serial", **kw)
    assert len(res.log) == steps


# ------------------------------------------------------------------ det K ---------------------
@pytest.mark.parametrize("name", available_solvers())
def test_determinant_sign_from_the_factors(name):
    """Against numpy's slogdet on symmetric indefinite and non-symmetric matrices."""
    rng = np.random.default_rng(5)
    for trial in range(20):
        n = 30
        A = sp.diags([rng.standard_normal(n - 1), 2.5 + rng.standard_normal(n), rng.standard_normal(n - 1),
                      0.3 * rng.standard_normal(n - 3)], [-1, 0, 1, 3]).tocsr()
        with Factorization(A, make_solver(name)) as F:
            F.solve(np.ones(n))
        assert F.det_sign() == np.linalg.slogdet(A.toarray())[0], (name, trial)


# ------------------------------------------------------------------ the stability check ------
def _column(nx=10, P=4.4):
    """A cantilever strip 10 x 1 x 0.1 (E 1.2e6, nu 0) under a dead end compression P: Euler's
    load pi^2 EI / (4 L^2) = 2.467 for a beam, i.e. lam ~ 0.561.  (P = 4 put the first of 2 steps
    on the straight start state's singular tangent, 2 EI/L^2 at lam 0.5 on any mesh: see
    test_a_first_load_on_the_start_states_buckling_load_is_not_called_a_missing_support.)"""
    p = Problem(mesh.rectangle(10.0, 1.0, nx, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (-P, 0.0, 0.0))
    p.add_probe("tip", "x1")
    return p


def _smallest_eigenvalue(p, lam):
    from scipy.sparse.linalg import eigsh
    st = p.solve(steps=1, lam_end=lam, limit_check=False).final
    K = p.evaluate(st.g, lam).K
    return float(eigsh((0.5 * (K + K.T)).tocsc(), k=1, sigma=0.0, which="LM", return_eigenvectors=False)[0])


def test_load_control_stops_at_a_bifurcation_and_names_it():
    """The straight compressed strip: Newton converges on the straight path past Euler's load
    (old code: exit 0 on an unstable state); the sign change of det K is located to 1e-3 and
    stops the run, the message naming the bifurcation and what to do."""
    p = _column()
    with pytest.raises(ConvergenceError) as exc:
        p.solve(steps=2)
    msg = str(exc.value)
    assert "bifurcation" in msg and "arc length" in msg and "limit_check" in msg
    lo, hi = [float(x) for x in msg.split("between load factors ")[1].split(",")[0].split(" and ")]
    assert hi - lo <= 1e-3 * hi
    # the eigenvalue of the symmetric tangent changes sign inside the bracket
    assert _smallest_eigenvalue(p, lo) > 0 > _smallest_eigenvalue(p, hi)
    assert abs(0.5 * (lo + hi) / (0.6168 * 4.0 / 4.4) - 1) < 0.02     # Euler's column
    assert [s.load_factor for s in exc.value.result.steps] == [0.0, 0.5]   # the steps before are kept


def test_limit_check_off_records_the_bifurcation_and_goes_on():
    res = _column().solve(steps=2, limit_check=False)
    (cp,) = res.critical_points
    assert cp.kind == "bifurcation" and cp.lam_bracket == (0.5, 1.0) and cp.step == 2
    assert res.steps[-1].load_factor == 1.0 and res.final.checks["det_sign"] == -1


# fuzz seed 12 (benchmarks/results/invariants_fuzz_seed12.md): problem 78 (``_PANEL_78`` of
# tests/test_invariants_fuzz.py), a pinned 2 x 1 cylindrical panel under two dead pressures and a
# third pressing it toward a half-space 0.0052 L below its face; problem 246, a clamped 2 x 2 plate
# under 2.7 Euler loads (1 % off-axis) and a follower pressure, a half-space 0.178 L below
_PLATE_246 = dict(mesh=("rectangle", (2.0778287034676044, 0.8776266630962353, 2, 2)), L=2.0778287034676044,
                  perturb=0.12548768233400864, pseed=474031738, E=2689650.422733381, nu=0.3047270665361927,
                  h=0.060974992400938954, support="clamp",
                  loads=[("edge_force", "x1", [-75.55484028435292, -0.490235372957005, 0.4326336138082702]),
                         ("follower_pressure", 0.0021363728217391573)],
                  alpha=0.0003421459526459525, law=("shear_stabilisation", 0.012939396785682677),
                  extra=("contact", dict(gap=0.17841800868817093, q=0.0021363728217391573)))


@pytest.mark.parametrize("steps", [1, 2, 4])
def test_an_obstacle_the_path_never_touches_leaves_the_step_checks_on(steps):
    """An obstacle (a constraint-force load) turned the path and stability checks off for the
    whole run, since contact's Newton tries contract irregularly and det K jumps as nodes touch:
    problem 78 (never touching the half-space: contact force 0 on the way and at the end) exited
    ok at load 1 in 1, 2 and 4 steps on unstable states (sym K lambda_min / lambda_max -3.7e-4,
    -2.1e-4) beyond its limit point at 0.4758 (64 and 256 steps stop there; without the obstacle
    every step count fails there), its one-step try's corrections growing 2.95x; problem 246
    in 1, 2 and 4 steps ended 1.92 ell from the 16-step state (its 16, 64, 256 steps agree to
    8e-15 ell) on an unstable state.  The checks now judge every try whose two ends are clear of
    the obstacles (no contact force or stiffness: ``ContactLoad.clear``): 78 fails at its limit
    point, 246 lands on the path."""
    from test_invariants_fuzz import _PANEL_78
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError) as exc:
            _fuzz_problem(_PANEL_78).solve(steps=steps)
        last = float(re.search(r"the last converged load factor is ([0-9.]+)", str(exc.value)).group(1))
        assert 0.47 < last < 0.4762, str(exc.value)
        ref = _fuzz_problem(_PLATE_246).solve(steps=16).final.g
        got = _fuzz_problem(_PLATE_246).solve(steps=steps).final.g
    assert state_gap(got, ref, _PLATE_246["L"]) < 1e-9


@pytest.mark.parametrize("steps", [1, 4, 16])
def test_limit_check_off_names_a_limit_point_jumped_across_a_limit_point(steps):
    """limit_check off, fuzz problem 108 to 0.35 of its load: its path has a limit point at
    0.2857128 (arc length, ``_LIMIT_108``), where 1, 4 and 16 load steps jump onto another
    branch between 0.2854 and 0.286084, and the run recorded and logged 'load control passed a
    bifurcation point' there.  The passed change's return check (the state beyond solved back
    at 0.2854: its Newton corrections grow, 0.0198, 0.0103, 0.0709 ... ell, the path check's
    refusal: the step's ends do not connect) now names it a limit point; the return's try is in the step's log.  The Euler column's passed crossing still
    returns and stays a bifurcation (the tests above and below)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = _panel_108(chords=False).solve(steps=steps, lam_end=0.35, limit_check=False)
    (cp,) = res.critical_points
    lo, hi = cp.lam_bracket
    assert cp.kind == "limit" and lo <= _LIMIT_108 <= hi, cp.describe()
    back = [e["return_check"] for e in res.log if "return_check" in e]
    assert len(back) == 1 and back[0]["linear_solves"] > 0


def test_a_passed_bifurcation_known_only_by_its_bracket_says_it_was_not_located(tmp_path):
    """limit_check off, 2 steps: the bifurcation (Euler ~0.561) is known only to lie between the
    steps 0.5 and 1.  Its description -- the warning, results.json's ``description`` -- says it was
    not located and that the bracket is its accuracy; before it read 'bifurcation point at lam ~
    0.75 (between 0.5 and 1)', a value 22 % off that reads as located."""
    res = _column().solve(steps=2, limit_check=False)
    (cp,) = res.critical_points
    assert cp.accuracy is None and cp.lam_bracket == (0.5, 1.0)
    text = cp.describe()
    assert text.startswith("bifurcation point not located: lam between 0.5 and 1") and "bracket only" in text
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        doc = scenario.run(_column_scenario(2), out=str(tmp_path / "run")).doc
    (c,) = doc["critical_points"]
    assert c["accuracy"] is None and "not located" in c["description"] and "bracket only" in c["description"]


def test_a_first_step_onto_the_start_tangents_singular_load_is_cut_back_not_called_buckling():
    """The clamped strip compressed by 4 in 2 steps: the first evaluation, at the straight state
    under load factor 0.5, has a singular tangent (smallest eigenvalue 1.6e-11, 0.073 at lam 0).
    That is the try's first Newton iterate (off equilibrium the tangent carries 1/2 ad* of the
    residual: singular at P = 2 EI/L^2 on any mesh), not the path: the straight strip is stable
    there (Euler's load pi^2 EI/(4 L^2) = 2.467, lam 0.6168).  The try is cut back and load
    control goes on to Euler's bifurcation, located to critical_tol on 6, 10 and 20 elements.
    Before: 6 elements stopped at 0.5 with 'a critical (buckling) load of the start state' (and,
    before that, 'missing supports'); 10 and 20 went on only because the first solve's random
    right-hand side grew 3.9e14 / 6.8e14 (limit 1e15)."""
    for nx, tol in ((6, 0.01), (10, 0.003), (20, 0.001)):        # the beam's discretisation error
        with pytest.raises(ConvergenceError) as exc:
            _first_step_on_buckling_load(nx).solve(steps=2)
        msg = str(exc.value)
        assert "bifurcation" in msg and "buckling load" not in msg and "supports" not in msg
        lo, hi = (float(x) for x in re.search(r"between load factors ([0-9.]+) and ([0-9.]+)", msg).groups())
        assert hi - lo <= 1e-3 * hi and abs(0.5 * (lo + hi) / 0.6168 - 1) < tol
        lam = [s.load_factor for s in exc.value.result.steps]
        assert lam[:2] == [0.0, 0.5]                                 # past the start tangent's singular load


def _first_step_on_buckling_load(nx=6):
    """The clamped strip (nx elements) compressed by 4: its start state's tangent is singular at
    load factor 0.5 (also run on two ranks: tests/test_parallel.py)."""
    p = Problem(mesh.rectangle(10.0, 1.0, nx, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (-4.0, 0.0, 0.0))
    return p


def _column_scenario(steps):
    return scenario.from_dict(dict(
        mesh=dict(generator="rectangle", L=10.0, width=1.0, nx=10, ny=1), material=dict(E=1.2e6, nu=0.0, h=0.1),
        supports=[dict(type="clamp", edge="x0")], loads=[dict(type="edge_force", edge="x1", force=[-4.4, 0.0, 0.0])],
        solver=dict(steps=steps, limit_check=False), output=dict(vtu=False, plots=False, picture=False)))


@pytest.mark.parametrize("stop_after", [None, 2, 3])
def test_a_scenario_writes_the_critical_points_load_control_passed(tmp_path, stop_after):
    """The compressed strip as a scenario, [solver] limit_check = false, 4 steps: the bifurcation
    passed between 0.5 and 0.75 (Euler ~0.561) is in results.json's critical_points, as the key's
    documentation says, with the stored step that passed it (3), once -- also when the run was
    interrupted before (2) or after (3) that step and resumed.  Found: results.json had no
    critical_points for load control (Result.critical_points had it)."""
    out = str(tmp_path / "run")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if stop_after is not None:
            with pytest.raises(scenario.RunInterrupted):
                scenario.run(_column_scenario(4), out=out, stop_after=stop_after)
        res = scenario.run(_column_scenario(4), out=out, resume=stop_after is not None)
    (cp,) = res.doc["critical_points"]
    assert cp["kind"] == "bifurcation" and cp["bracket"] == [0.5, 0.75] and cp["step"] == 3
    assert res.doc["steps"][-1]["load_factor"] == 1.0


# ------------------------------------------------------------------ even crossings (inertia_check)
def _sandwich_strip(f):
    """The sandwich strip of docs/EXTENDING.md recipe 6 (its law taken from the recipe) under an
    end tension f C w: its tangent loses several eigenvalues close together near N = G_c c
    (Haringx)."""
    import os
    text = open(os.path.join(os.path.dirname(__file__), "..", "docs", "EXTENDING.md"), encoding="utf-8").read()
    recipe = text[text.index("## Recipe 6"):]
    code = recipe[recipe.index("class SandwichLaw"):recipe.index("register_material(")]
    ns = dict(np=np, Material=Material)
    exec(code, ns)
    law = ns["SandwichLaw"](7.0e4, 0.5, 10.0, 50.0)
    p = Problem(mesh.rectangle(200.0, 20.0, 8, 2), law)
    p.clamp("x0")
    p.add_edge_force("x1", (f * law.C * 20.0, 0.0, 0.0))
    return p


def _stop_bracket(p, steps, **kw):
    with pytest.raises(ConvergenceError) as exc:
        p.solve(steps=steps, **kw)
    msg = str(exc.value)
    assert "crossed a critical point" in msg
    return [float(x) for x in msg.split("between load factors ")[1].split(",")[0].split(" and ")]


def test_inertia_check_sees_an_even_number_of_crossings_in_one_step():
    """The sandwich strip loaded to 0.2 C w: in one or two steps det K keeps its sign (12 and 6
    negative eigenvalues at the ends: old code, exit 0 on the unstable uniform stretch), in five
    steps the sign check stops at the wrong, later crossing (0.533 of the load).  With
    ``inertia_check`` the count of negative eigenvalues of sym K changes in the first step and is
    located like a sign change: every step count stops at the first crossing, 0.04264 (40 steps,
    the det K sign check alone), i.e. N = 0.00853 C w."""
    # (5 steps also ended with "Newton failed after 12 cut-backs" when the bracket's half equalled
    # the smallest increment to the last bit: StepChecks._narrow now counts it as narrow)
    first = 0.5 * sum(_stop_bracket(_sandwich_strip(0.2), 40))
    assert abs(first - 0.04264) < 1e-4
    assert _sandwich_strip(0.2).solve(steps=1, end_check=False).final.checks["det_sign"] == 1   # the old answer
    assert 0.5 * sum(_stop_bracket(_sandwich_strip(0.2), 5, end_check=False)) > 0.5   # the wrong crossing
    for steps in (1, 2, 5):
        lo, hi = _stop_bracket(_sandwich_strip(0.2), steps, inertia_check=True)
        # located to critical_tol, or to the smallest increment the cut-backs allow (1/2**12 of
        # the step: 5.7e-3 of the load factor in one step) when that is coarser
        assert lo <= first <= hi and hi - lo <= max(1e-3 * hi, 2.0 / steps / 2 ** 12) * (1 + 1e-9)


def test_the_end_check_stops_an_even_crossing_by_default():
    """Without inertia_check (its price: a factorisation per try), the count at the end of the
    solve (one factorisation) still sees the sandwich strip's even crossings: on the old code
    one and two steps to 0.2 C w exit 0 on the unstable uniform stretch (12 and 6 negative
    eigenvalues), five and ten stop at a later crossing (0.533, 0.236); now each stops naming
    the first step over which the count rose (the count is also taken before a located sign
    change stops the run) and keeps the steps before it.  Below the bifurcation nothing
    changes."""
    for steps, bracket, counts in ((1, (0.0, 1.0), (0, 12)), (2, (0.0, 0.5), (0, 6)), (5, (0.0, 0.2), (0, 4)),
                                   (10, (0.0, 0.1), (0, 2))):
        with pytest.raises(ConvergenceError) as exc:
            _sandwich_strip(0.2).solve(steps=steps)
        msg = str(exc.value)
        assert "det K's sign did not show" in msg and "inertia_check = true" in msg
        assert f"rose from {counts[0]} to {counts[1]} between load factors {bracket[0]:.7g} and {bracket[1]:.7g}" in msg
        assert [s.load_factor for s in exc.value.result.steps] == [0.0]
    res = _sandwich_strip(0.005).solve(steps=2)            # N = 0.005 C w < 0.0085 C w: stable
    assert res.steps[-1].load_factor == 1.0 and not res.critical_points


# ------------------------------------------------------------------ splitting ---------------
def _rotating(angle, steps=4):
    p = Problem(mesh.rectangle(17.2, 5.0, 10, 1), Material(0.8969, 0.0, 0.42))
    p.clamp("x0")
    field = UniformField((0.0, 0.0, 0.005), scale=lambda lam: 1.0,
                         direction=rotating_direction((0, 1, 0), (0, 0, 1), turns_per_unit=angle / (2 * np.pi)))
    p.add_magnetic((0.143, 0.0, 0.0), field, mu0=4e-7 * np.pi * 1e6)
    return p


def test_a_field_turned_by_1e6_rad_stops_at_once_naming_the_load():
    """Old code: about 1.3 million sub-steps of pi/4 without output."""
    with pytest.raises(ConvergenceError, match=r"load 'magnetic' turns by about .* max_substeps = 1000"):
        _rotating(1e6).solve(steps=1)
    # a bound the user raises: the same turn would be accepted (the check only counts)
    opts = NewtonOptions(max_substeps=10_000_000)
    assert opts.max_substeps == 10_000_000


def test_a_coil_reversing_against_a_magnets_dipole_is_not_counted_as_66_turns():
    """A strip in a coil's field ramped with the load factor plus a permanent magnet's dipole
    (constant): where the two nearly cancel at a node the net field reverses there in a short
    stretch of the load factor (its whole turn over the path is 2.99 rad).  The first try's
    length, extrapolated to the end, counted 1596 tries: 'turns by about 4.1e+02 rad (66 turns)
    ... more than max_substeps = 1000', and solve(steps=5) stopped.  Now a count that high is
    checked on the turn left, measured whole: 36 tries, the tip of 80 steps to 1e-10 of the
    length (the 1e6 rad field above still stops at once)."""
    from core_se3.model.fields import DipoleField, Superposition

    def strip():
        p = Problem(mesh.rectangle(1.0, 0.1, 20, 2), Material(1e3, 0.0, 0.01))
        p.clamp("x0")
        p.add_probe("tip")
        f = Superposition(UniformField((0.0, 0.0, 1e-5)),
                          DipoleField((0.0, 0.0, 1e-7), (1.0, 0.05, 0.05), mu0=1.0, scale=lambda lam: 1.0))
        return p, p.add_magnetic((1.0, 0.0, 0.0), f, mu0=1.0)
    p, ld = strip()
    assert 2.5 < ld.direction_turn(p.mesh.g0, 0.0, 1.0) < np.pi
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshWarning)        # the dipole is 1 element size away
        tip = [strip()[0].solve(steps=n).final.probes["tip"]["u"] for n in (5, 80)]
    assert abs(tip[1][2]) > 5e-4 and np.abs(tip[0] - tip[1]).max() < 1e-10         # length 1


def test_angles_of_more_than_ten_turns_are_warned_about():
    doc = dict(units="N-mm-MPa", mesh=dict(generator="rectangle", L=17.2, width=5.0, nx=4, ny=1),
               material=dict(E=0.8969, nu=0.0, h=0.42), supports=[dict(type="clamp", edge="x0")],
               fields=dict(f=dict(type="uniform", B=[0.0, 0.0, 0.005],
                                  rotate=dict(axis=[0.0, 1.0, 0.0], angle=360.0))),
               magnets=[dict(Br=[0.143, 0.0, 0.0])])
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        scn = scenario.from_dict(doc)
    assert any("fields.f.rotate.angle" in str(w.message) and "57.3 turns" in str(w.message) for w in seen)
    assert scn.solver["path_check"] and scn.solver["limit_check"] and scn.solver["max_substeps"] == 1000


# ------------------------------------------------------------------ translation --------------
def _readme_cantilever(x0):
    # one backend for all (the 'auto' rule could move a later problem to numba: round-off apart)
    p = Problem(mesh.rectangle(10.0, 1.0, 16, 1, x0=x0), Material(E=1.2e6, nu=0.0, h=0.1), backend="numpy")
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 4.0))
    p.add_probe("tip", "x1")
    return p


def test_a_part_far_from_the_origin_iterates_as_at_the_origin():
    """Old code: no convergence at x0 = 1e4 and beyond (residual stalled at 6e-3)."""
    ref = _readme_cantilever(0.0).solve(steps=10)
    for x0 in (1e4, 1e9):
        res = _readme_cantilever(x0).solve(steps=10)
        assert [s.iterations for s in res.steps] == [s.iterations for s in ref.steps]
        np.testing.assert_array_equal(res.final.probes["tip"]["u"], ref.final.probes["tip"]["u"])
        assert np.abs(res.final.g[:, 0, 3] - x0 - ref.final.g[:, 0, 3]).max() <= 1e-15 * x0


def test_path_following_of_a_part_far_from_the_origin_iterates_as_at_the_origin():
    """Arc length and displacement control hold the iterate relative to the part too
    (ShellSystem): before, the README cantilever at x0 = 1e4 failed in both at the first step
    (arc length after 13 rejections, residual stalled at 3.3e-3; displacement control at u =
    1e-3, 1.7e-3), at 1e9 with residuals 2.6e-2 and 1.0; now x0 = 1e4 and 1e9 take the same
    iterations as x0 = 0 and the same probe displacements, to the last bit.  A resumed path
    (ArcState in the problem's coordinates) goes on as the unbroken one (to the round-off of the
    stored frames)."""
    from core_se3.solvers import arc_length, arc_length_steps, displacement_control
    p0 = _readme_cantilever(0.0)
    k = int(p0.mesh.node_set("x1")[0])
    runs = {"arc": lambda p: arc_length(p, lam_end=1.0, dlam0=0.2),
            "disp": lambda p: displacement_control(p, k, (0.0, 0.0, 1.0), [1.0, 2.0, 3.0])}
    for name, run in runs.items():
        ref = run(p0)
        for x0 in (1e4, 1e9):
            res = run(_readme_cantilever(x0))
            assert [s.iterations for s in res.steps] == [s.iterations for s in ref.steps], (name, x0)
            assert [s.load_factor for s in res.steps] == [s.load_factor for s in ref.steps], (name, x0)
            np.testing.assert_array_equal(res.final.probes["tip"]["u"], ref.final.probes["tip"]["u"])
            assert np.abs(res.final.g[:, 0, 3] - x0 - ref.final.g[:, 0, 3]).max() <= 1e-15 * x0
    far = _readme_cantilever(1e9)
    steps = list(arc_length_steps(far, lam_end=1.0, dlam0=0.2))
    assert steps[1].state.state[0, 0, 3] == 1e9                       # the restart state: whole frames
    resumed = list(arc_length_steps(_readme_cantilever(1e9), lam_end=1.0, dlam0=0.2, start=steps[1].state))
    # the restart frames hold the positions to eps x0 = 2.2e-7 (0.6 m elements): the resumed
    # path agrees to that, not to the last bit
    lam_r, lam_s = np.array([s.step.load_factor for s in resumed]), np.array([s.step.load_factor for s in steps[2:]])
    assert len(lam_r) == len(lam_s) and np.abs(lam_r - lam_s).max() <= 1e-6
    u_r, u_s = resumed[-1].step.probes["tip"]["u"], steps[-1].step.probes["tip"]["u"]
    assert np.abs(u_r - u_s).max() <= 1e-6 * np.abs(u_s).max()


# ------------------------------------------------------------------ critical points ---------
def _ltb_strip():
    p = Problem(mesh.rectangle(10.0, 1.0, 40, 4), Material(1.2e6, 0.0, 0.05))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 1.0, 0.0))
    return p


def test_arc_length_locates_a_bifurcation_whatever_the_first_step():
    """Lateral-torsional buckling of a deep cantilever strip: the old linear interpolation over
    the step gave 0.608 (first step 0.5) and 0.654 (0.1) for a load near 0.742; now both, and the
    first step 0.01, agree to 1e-3 (benchmarks/robustness.md: 1.5e-8 ... 2.7e-7 of the value
    refined to 1e-6)."""
    lams = []
    for d in (0.5, 0.1, 0.01):
        res = arc_length(_ltb_strip(), lam_end=1.0, dlam0=d)
        (cp,) = res.critical_points
        assert cp.kind == "bifurcation" and cp.accuracy <= 1e-3
        lams.append(cp.lam)
    assert max(lams) - min(lams) <= 1e-3 * min(lams)
    assert abs(lams[0] / 0.742 - 1) < 2e-3


def test_displacement_control_locates_a_bifurcation_to_critical_tol():
    """The deep strip's lateral-torsional buckling by displacement control of the tip's in-plane
    deflection (0.0669 at lam = 1 on the primary path) in two steps: the bifurcation agrees with
    its value refined to 1e-7 by arc length (0.7420368) within critical_tol = 1e-3.  Found: the
    smallest eigenvalue interpolated over the step from 0.5 to 1.0 was the result, 0.6076 (18 %
    low; 0.7371 from four steps).  Now the step is bisected as arc length's is."""
    p = _ltb_strip()
    k = int(p.mesh.node_set("x1")[0])
    res = displacement_control(p, k, (0.0, 1.0, 0.0), [0.0334, 0.0669])
    (cp,) = res.critical_points
    assert cp.kind == "bifurcation" and cp.accuracy <= 1e-3
    assert abs(cp.lam - 0.7420368) <= 1e-3 * 0.7420368, cp.describe()


def test_a_sign_change_seen_across_a_jump_is_not_a_critical_point():
    """magnetic-antiparallel's tilted field in ONE step: the big tries land on states with
    det K < 0 (a jump past the buckling load, not the tilted path's doing); the bisection moves
    its low end along the path up to the high end, reaches it with the old sign, drops the
    bracket and goes on (a first version bisected forever, then would have reported a critical
    point that is not there).  The post-buckled state agrees with the case's own 40 steps."""
    doc1, res1, _ = run_case("magnetic-antiparallel", steps=1)
    assert any(e["reason"].startswith("stability check") for e in res1.log)
    doc, res, _ = run_case("magnetic-antiparallel")
    u1, u = res1.final.probes["tip"]["u"], res.final.probes["tip"]["u"]
    assert np.abs(u1 - u).max() <= 1e-6 * np.abs(u).max()
    assert not res1.critical_points


def test_arc_length_ends_on_lam_end_when_landing_fails():
    """An arc-length step that overshoots lam_end so far that landing on it fails (u' = 1 -
    tanh^2 underflows at the overshoot: a singular tangent) ended the path past lam_end, at
    0.999988 for 0.99, reported as finished (sze-slit-annular from dlam0 = 1: 1.0335 for 1;
    benchmarks/results/robustness.md).  Now the step is rejected and shortened: the path ends on
    lam_end."""
    from core_se3.solvers import AlgebraicSystem
    from core_se3.solvers.arclength import path_follow
    s = AlgebraicSystem(np.tanh, lambda u: np.diag(1.0 - np.tanh(u) ** 2), [1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")            # the overshoot's singular tangent
        pts, _, _, _ = path_follow(s, lam_end=0.99, dlam0=2.0)
    assert pts[-1].lam == pytest.approx(0.99, abs=1e-12)
    assert np.tanh(pts[-1].state[0]) == pytest.approx(0.99, abs=1e-12)


def test_a_prescribed_motion_stopped_at_a_snap_back_names_it():
    """The 6.35 mm roof of Sze s3.8(d) (8x8 quarter) without its load, its crown pushed down by a
    prescribed translation (-W_C = 38 lam in 38 steps): W_C turns back along the path near 16.94
    (arc length; the table's 17.008), so no load stepping of W_C passes it.  The run stopped
    there after 12 cut-backs with no cause named; now the failure adds that the smallest
    eigenvalue of the tangent with the prescribed motion held has fallen to 7e-4 of its initial
    value (below TURN_HINT = 0.05; 0.10 at -W_C = 16, still on the path) and names the snap-back
    and arc length.  The stored steps are those before it (-W_C = 1 ... 16)."""
    from core_se3 import catalogue
    from core_se3.catalogue import get_case
    case = get_case("sze-hinged-roof-6.35")
    prob = catalogue.build_problem(case, catalogue.case_params(case), (8, 8))
    node, _ = prob.control
    prob.loads.clear()
    g0 = prob.mesh.g0[[node]].copy()

    def target(lam):
        g = g0.copy()
        g[:, 2, 3] -= 38.0 * lam
        return g

    prob.prescribe(np.array([node]), target, fixed=(False, False, True, False, False, False))
    with pytest.raises(ConvergenceError) as exc:
        prob.solve(steps=38)
    msg = str(exc.value)
    assert "snap-back" in msg and "arc length" in msg, msg
    w = [-s.probes["C"]["u"][2] for s in exc.value.result.steps]
    assert abs(w[-1] - 16.0) < 1e-9


def test_the_negative_eigenvalues_are_counted_on_a_shell_held_on_symmetry_planes():
    """The Scordelis-Lo roof 16x16 under its self-weight, held on its symmetry planes: the
    tangent's skew part lies in the held nodes' diagonal blocks (their reactions' 1/2 ad* term:
    4.1e-5 of max |K| there, 4.1e-15 outside), yet it was read as a non-conservative load's, so the
    end check's count (``negative_count``), load stepping's inertia_check and arc length's counts
    were None -- switched off without a word on a conservative problem.  Now they count (0: the
    roof is stable), and a follower load's skew part still switches them off."""
    import warnings
    from core_se3.catalogue import shell_course as sc
    from core_se3 import scenario
    from core_se3.solvers import stability
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = scenario.from_dict(sc.scenario_doc("scordelis-lo", 16, 0.25)).problem
        g = p.solve(steps=4).final.g
    K = p.tangent(g, 1.0)
    assert abs(K - K.T).max() > 1e-5 * abs(K).max()                    # the reactions' skew part
    assert stability.asymmetry(K, p.assembler().free) < 1e-12
    assert stability.negative_count(p, g, 1.0) == 0
    p.add_edge_force("x1", (0.0, 0.0, -1e4), follower=True)             # a follower: not conservative
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = p.solve(steps=4).final.g
    assert stability.negative_count(p, g, 1.0) is None


def test_asymmetry_is_unit_free_and_separates_non_conservative_loads():
    """``stability.asymmetry`` decides whether sym K's inertia says anything (conservative loads).
    It was max |K - K^T| / max |K|, whose blocks carry force/length, force and force*length: the
    rolled-up strip under its dead end moment measured 6.3e-4 in its units but 6.3e-10 in metres
    (E x 1e6, lengths x 1e-3), below ASYM_TOL 1e-6, so load control counted sym K's eigenvalues of
    a non-conservative problem and stopped on a spurious 'critical point' (ConvergenceError at
    lam 0.5 .. 0.58); the arch under a follower force measured 1.3e-7 in its own units.  Now the
    skew part is Jacobi-scaled (|K_ij - K_ji| / sqrt|K_ii K_jj|): the same in any units (9.2e-3),
    5.1e-5 for the follower arch, <= 3.0e-14 on the catalogue's conservative problems."""
    from core_se3.catalogue import case_params, get_case
    from core_se3.solvers import stability
    p = case_params(get_case("rollup"), None)
    m_units = {k: (v / 1e-6 if k == "E" else v * 1e-3) for k, v in p.items() if k in ("E", "h", "L", "width")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        doc0, res0, prob0 = run_case("rollup")
        doc, res, prob = run_case("rollup", overrides=m_units)           # before: ConvergenceError
    assert len(res.steps) == len(res0.steps) and res.final.load_factor == 1.0
    u0 = res0.final.g[:, :3, 3] - prob0.mesh.g0[:, :3, 3]
    u = res.final.g[:, :3, 3] - prob.mesh.g0[:, :3, 3]
    assert np.abs(u / 1e-3 - u0).max() <= 1e-12 * np.abs(u0).max()
    K0, K = prob0.tangent(res0.final.g, 1.0), prob.tangent(res.final.g, 1.0)
    a0, a = stability.asymmetry(K0, prob0.assembler().free), stability.asymmetry(K, prob.assembler().free)
    assert a0 > 1e3 * stability.ASYM_TOL and abs(a - a0) <= 1e-9 * a0
    # a change of units scales the translation and rotation dofs: the measure does not see it
    free = prob0.assembler().free
    for a_t, a_r in ((1e-3, 1.0), (1.0, 1e4), (1e8, 1e-8)):
        D = sp.diags(np.tile([a_t] * 3 + [a_r] * 3, prob0.mesh.n_nodes)[free])
        assert abs(stability.asymmetry(D @ K0 @ D, free) - a0) <= 1e-9 * a0
    # the follower arch is not conservative in its own units either
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, res_a, prob_a = run_case("arch-follower", steps=3)
    Ka = prob_a.tangent(res_a.final.g, res_a.final.load_factor)
    assert stability.asymmetry(Ka, prob_a.assembler().free) > 10 * stability.ASYM_TOL


@pytest.mark.parametrize("h", [1e-3, 1e-4])
def test_thin_rolled_strip_under_a_dead_moment_is_not_counted_as_conservative(h):
    """The rollup strip (L 10, 10 x 1, dead end moment of 3 turns, one step) at L/h 1e4 and 1e5:
    its tangent's Jacobi-scaled skew part falls like (h/L)^2 (9.2e-7, 9.2e-9: the rotations'
    diagonal is the transverse shear's), below the 1e-6 that counted K as symmetric before, so
    the end check counted sym K ('the number of negative eigenvalues of sym K rose from 0 to 2')
    and stopped a path whose tip lies on the exact circle to 2e-16.  Now (ASYM_TOL 1e-10) it is
    judged non-conservative at both thicknesses and ends on the circle."""
    from core_se3.solvers.stability import ASYM_TOL, asymmetry
    doc, res, prob = run_case("rollup", mesh=(10, 1), steps=1, overrides=dict(h=h))
    L, k = 10.0, 3.0
    R = L / (2 * np.pi * k)
    exact = np.array([R * np.sin(2 * np.pi * k) - L, 0.0, R * (1 - np.cos(2 * np.pi * k))])
    assert np.abs(res.final.probes["tip"]["u"] - exact).max() <= 1e-12 * L
    K = prob.evaluate(res.final.g, 1.0).K
    assert 10 * ASYM_TOL < asymmetry(K, prob.assembler().free) < 1e-5     # non-conservative, with margin

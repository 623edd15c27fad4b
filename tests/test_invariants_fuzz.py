"""Property: a successful solve of a random valid problem is right, checked independently
(benchmarks/invariants_fuzz.py, whose full campaign is in benchmarks/results/invariants_fuzz.md):
the residual on the other backend at the Newton tolerance, reactions + applied loads = 0 (force
and moment about the origin, the applied loads recomputed from the load data), 1, 2, 4 and 16
load steps ending on the same state, the problem moved by a random rigid motion (translations of
the part's size and 1e6 times it) moving its answer exactly, and sym K at an end reported stable
positive semi-definite.  Tolerances: the module docstring of the benchmark."""
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
import invariants_fuzz as fuzz  # noqa: E402


@pytest.mark.parametrize("seed", [4, 5])
def test_random_problems_keep_every_invariant(seed):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")              # coarse-mesh warnings of the random shells
        rec = fuzz.campaign(3, seed, log=None)
    checked = [o for o in rec if "runs" in o]
    assert checked and not [o.get("error") for o in rec if "error" in o]
    assert sum(r["ok"] for o in checked for r in o["runs"].values()) >= 4
    assert {n: fuzz.violations(o) for n, o in enumerate(checked) if fuzz.violations(o)} == {}
    t = fuzz.tally(rec)
    assert t["path"][0] > 0 and t["frame1e+06"][0] > 0 and t["stab"][0] > 0


def test_the_checks_see_a_wrong_answer():
    """The checks can fail: a state off the equilibrium (one free node of the converged state
    moved by 1e-6 ell) fails the equilibrium check, and the start state is far from the end."""
    rng = np.random.default_rng(4)
    spec = fuzz.random_problem(rng)
    p = fuzz.build(spec)
    res = p.solve(steps=2)
    g = res.final.g.copy()
    free = np.nonzero(~p.constraint_mask().any(1))[0]
    g[free[0], 2, 3] += 1e-6 * p.length_scale
    res.final.g = g
    assert fuzz.check_equilibrium(spec, res, "numpy", 1e-10)[0] > fuzz.EQ_TOL
    assert fuzz.state_distance(g, p.mesh.g0, p.length_scale) > 1e-3


def test_loads_that_cancel_keep_the_balance_check_s_scale():
    """Two follower pressures +-q on a pinned annulus (the shifted seed-4 campaign's problem 183)
    cancel: f_ext = 0 and the reactions are round-off (5e-26).  Relative to the sum of the nodal
    forces, floored at 1e-300, that read 5e274 (a 'violation'); each load's own magnitude is the
    scale now, and the balance is at round-off."""
    q = 1.1234211120885231e-09
    spec = dict(mesh=("annulus", (1.5612844304784201, 2.899333294955783, 2.085902431998667, 1, 5)),
                L=3.2566869905765903, perturb=0.001918166394232479, pseed=293416936, E=34686.56733224245,
                nu=0.42263078605198073, h=0.003971554339445271, support="pin-pin",
                loads=[("follower_pressure", -q), ("follower_pressure", q)], alpha=0.00017601709969814144)
    res = fuzz.build(spec, backend="numba").solve(steps=1)          # solved on numba, checked on numpy
    _, p2, ev, tol_abs = fuzz.check_equilibrium(spec, res, "numba", 1e-10)
    mine, reported, vs, tol = fuzz.check_balance(spec, p2, ev, res.final, tol_abs)
    assert max(mine, reported, vs) <= tol


# a clamped 3 x 2 cylindrical panel (R 1.3, 1.2 rad, its inner nodes moved by up to 0.15 of an
# element in the tangent plane) under a dead oblique pressure and its own weight
_PANEL = dict(mesh=("cylinder_panel", (1.3, 0.9, -0.6, 0.6, 3, 2)), L=1.56, perturb=0.15, pseed=12345, E=1e5,
              nu=0.3, h=0.02, support="clamp", loads=[("pressure", 0.02, [0.3, -0.2, 1.0]),
                                                      ("gravity", 1.0, [0.0, 0.0, -1.0])], alpha=1.0)


def _panel_balance():
    res = fuzz.build(_PANEL).solve(steps=1)                     # solved on numpy, checked on numba
    _, p2, ev, tol_abs = fuzz.check_equilibrium(_PANEL, res, "numpy", 1e-10)
    return fuzz.check_balance(_PANEL, p2, ev, res.final, tol_abs)


def test_the_elements_own_area_is_a_cylinder_s_exact_area():
    """The check's own area element (exact arcs, written in the benchmark) integrates a cylinder
    panel's exact area R theta length to round-off, at 0.4 rad an element, where the flat quads
    between the nodes are 0.67 % smaller (sin(0.2) / 0.2 - 1)."""
    from core_se3 import mesh
    R, length, t0, t1 = _PANEL["mesh"][1][:4]
    exact = R * length * (t1 - t0)
    assert abs(fuzz.element_areas(mesh.cylinder_panel(*_PANEL["mesh"][1])).sum() / exact - 1) < 1e-14
    flat = mesh.cylinder_panel(*_PANEL["mesh"][1])
    x1 = flat.X[flat.quads]
    chords = sum(np.linalg.norm(np.cross(x1[:, 1] - x1[:, 0], x1[:, 3] - x1[:, 0]), axis=1))
    assert abs(chords / exact - np.sin(0.2) / 0.2) < 1e-14         # the flat quads: rectangles here


def test_a_curved_panel_s_area_loads_balance_on_the_elements_own_area():
    """The package integrates dead area loads over the curved element's own area (model/loads.py,
    "Curved elements"); the check summed p A and rho h g A over the flat quads between the nodes,
    so this panel read a 'violation' of 1.13e-3 (tolerance 2.0e-6, the residual's at the Newton
    tolerance) -- seed 9's campaign had 23 such panels, 3.2e-4 ... 1.6e-2.  On the elements' own area, written in the
    benchmark, the balance holds to round-off."""
    mine, reported, vs, tol = _panel_balance()
    assert max(mine, reported, vs) <= tol


def test_a_package_integrating_over_the_chords_is_caught(monkeypatch):
    """A real imbalance is still seen: the package's earlier rule (the loads integrated over the
    flat quads, ``element_area`` giving none) balances reactions that are short of the load data's
    p A + rho h g A by the chords' deficit: 1.14e-3 of the nodal forces here, 570 x the tolerance."""
    from core_se3.model import loads
    monkeypatch.setattr(loads, "element_area", lambda problem, elements: None)
    mine, _, _, tol = _panel_balance()
    assert mine > 100 * tol


# ------------------------------------------------------------ the extended families ---
def _fingerprint(seed, extended):
    import hashlib
    import json
    rng = np.random.default_rng(seed)
    specs = [fuzz.random_problem(rng, extended) for _ in range(250)]
    return hashlib.sha256(json.dumps(specs).encode()).hexdigest()[:16]


def test_seeds_4_9_and_10_draw_the_problems_of_their_reports():
    """The extended families are drawn from seed EXTENDED_FROM (11) on, after the rest of each
    problem: seeds 4, 9 and 10 draw the base problems of their reports (benchmarks/results/),
    fingerprinted by the first 250 specs as drawn before the families existed (main at 5dfc881);
    seed 11 does draw the families."""
    assert fuzz.EXTENDED_FROM > 10
    prints = {s: _fingerprint(s, s >= fuzz.EXTENDED_FROM) for s in (4, 9, 10)}
    assert prints == {4: "1a30d67a8fe91d5c", 9: "75fb347823c698d9", 10: "afe9f78672f85712"}
    assert "law" in fuzz.random_problem(np.random.default_rng(11), True)


# a clamped 5 x 2 plate (shear-stabilised law) under a dead edge moment and an oblique pressure,
# pressed onto a half-space 0.0036 L below its face (penalty contact): seed 11's problem 5
_CONTACT = dict(mesh=("rectangle", (1.0099931267629063, 0.3277407959795587, 5, 2)), L=1.0099931267629063,
                perturb=0.11663368529545165, pseed=201626380, E=21316.90416702652, nu=0.23870878896017042,
                h=0.0021074035126577365, support="clamp",
                loads=[("edge_moment", "x1", [1.0107808375743675e-07, 2.438067792568977e-07, 6.349797546737058e-08]),
                       ("pressure", 8.119671561028043e-07, [0.08733489528619391, 0.9088125278185204,
                                                            -0.40796127922323794])],
                alpha=0.04744907679696667, law=("shear_stabilisation", 0.6310379743233975),
                extra=("contact", dict(gap=0.0036197459243172553, q=8.119671561028043e-07)))


def test_the_reported_applied_force_is_compared_without_the_contact_forces():
    """``StepResult`` reports the contact forces apart from the applied loads (its
    ``applied_force`` is the rest, ``contact[name]['force']`` the obstacle's); the check compared
    the package's applied force with its own total including the contact, a 'violation' of
    0.406 at every step count of this plate (tolerance 1.2e-3; seed 11's first run).  Now the
    reported and recomputed forces agree to round-off, and the contact does carry a force (a
    third of the applied load's scale, so the comparison sees it)."""
    p = fuzz.build(_CONTACT, backend="numba")                   # solved on numba, checked on numpy
    res = p.solve(steps=1)
    st = res.final
    _, p2, ev, tol_abs = fuzz.check_equilibrium(_CONTACT, res, "numba", 1e-10)
    mine, reported, vs, tol = fuzz.check_balance(_CONTACT, p2, ev, st, tol_abs)
    assert max(mine, reported, vs) <= tol
    AF, _, _, _, CF = fuzz.applied_totals(p2, _CONTACT, st.g, st.load_factor)
    assert np.allclose(CF, st.contact["half_space"]["force"], rtol=1e-9, atol=1e-12 * np.abs(AF).max())
    assert np.linalg.norm(CF) > 0.3 * np.linalg.norm(AF - CF)


# one problem of each feature of the extended families, each with another law
_EXTENDED = {
    "magnet_turning": dict(mesh=("rectangle", (0.41, 0.11, 4, 1)), L=0.41, perturb=0.18, pseed=794539958, E=24063.0,
                           nu=0.012, h=0.0198, support="clamp", loads=[], alpha=1.0, law=("classical_shell", None),
                           extra=("magnet_turning", dict(Br=[0.8647, 0.4818, -0.1417], B=[0.02, 0.03, 0.05],
                                                         axis=[-0.8445, 0.4739, 0.2496], turns=0.239))),
    "rotate_edge": dict(mesh=("rectangle", (1.0, 0.3, 4, 1)), L=1.0, perturb=0.1, pseed=5, E=1e5, nu=0.3, h=0.01,
                        support="clamp", loads=[("pressure", 1e-3, [0.0, 0.0, 1.0])], alpha=1.0,
                        law=("regions", 10.0), extra=("rotate_edge", dict(axis=[0.0, 1.0, 0.0], strip_axis=True,
                                                                          angle=2.0))),
}


@pytest.mark.parametrize("kind", sorted(_EXTENDED))
def test_an_extended_family_keeps_every_invariant(kind):
    """A hard magnet in a field turning by 0.24 of a turn (body couples turning the tip by ~1
    rad), and a strip twisted by 2 rad at its end (prescribed rotation, half its elements 10 x
    stiffer): every check holds, and the feature does act (the state is far from the start)."""
    spec = _EXTENDED[kind]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        o = fuzz.run_one(spec, np.random.default_rng(1), "numpy", [])
    assert all(r["ok"] for r in o["runs"].values()) and fuzz.violations(o) == []
    assert len(o["path"]) == 3 and len(o["frame"]) == 2
    res = fuzz.build(spec).solve(steps=4)
    assert fuzz.state_distance(res.final.g, fuzz.build(spec).mesh.g0, spec["L"]) > 0.2


# seed 12's problem 78: a pinned 2 x 1 cylindrical panel (h/L 0.063) under two dead pressures and
# a third pressing it toward a half-space 0.0052 L below its face
_PANEL_78 = dict(mesh=("cylinder_panel", (2.936026195837851, 2.7293602886249966, -0.9456213388412026,
                                          0.9456213388412026, 2, 1)),
                 L=5.552738044362063, perturb=0.04255721758915232, pseed=534377356, E=1095441992.255931,
                 nu=0.10273996279498798, h=0.3507179182163402, support="pin-pin",
                 loads=[("pressure", 5369379.807451757, [0.5645864849246599, 0.5367399628070835, -0.6270185909255543]),
                        ("pressure", 5369379.807451757, [-0.10781281805071394, -0.4201194709399129,
                                                         0.9010416341108392])],
                 alpha=230.96975749235614, law=("cosserat", None),
                 extra=("contact", dict(gap=0.005193805851486636, q=5369379.807451757)))


def test_a_run_with_contact_claims_no_stable_end():
    """``solvers.newton.end_check`` leaves problems with contact alone (a constraint force), so
    their ends claim nothing; the check took this one-step end (sym K lambda_min / lambda_max
    -3.7e-4) for a stable end reported unstable, a 'violation'.  Now it is listed among the
    unclaimed ones (its own finding, for the lead: the obstacle, never touched on the way, turned
    the path and stability checks off for the whole run; now they judge the tries clear of it, and
    its 1-step run fails at the limit point: the state is reached here with those checks off); a
    problem without contact still claims."""
    p = fuzz.build(_PANEL_78)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = p.solve(steps=1, path_check=False, limit_check=False)
    assert fuzz.min_eig(p, res.final.g, 1.0) < -1e-4
    assert not fuzz.claims_stable(p, res.final.g, 1.0)
    q = fuzz.build(_PANEL)
    assert fuzz.claims_stable(q, q.solve(steps=1).final.g, 1.0)


def test_the_cubed_sphere_is_closed_and_oriented_outward():
    """The closed family's mesh: every quad edge shared by exactly two quads in opposite
    directions (closed, consistently oriented), V - E + F = 2, every quad's normal outward."""
    for n in (2, 4):
        X, Q = fuzz.cubed_sphere(1.3, n)
        edges = np.concatenate([Q[:, [0, 1]], Q[:, [1, 2]], Q[:, [2, 3]], Q[:, [3, 0]]])
        assert len({tuple(e) for e in edges}) == len(edges)            # no edge twice the same way
        assert {tuple(e) for e in edges} == {tuple(e[::-1]) for e in edges}
        assert len(X) - len(edges) // 2 + len(Q) == 2
        x = X[Q]
        assert np.all(np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 3] - x[:, 0]), x.mean(1)) > 0)
        assert np.allclose(np.linalg.norm(X, axis=1), 1.3, rtol=1e-14)


def test_a_closed_shell_keeps_every_invariant():
    """A cubed sphere read as a file's mesh (cross-field frames, quarter-turn cuts), clamped at
    its south pole, under a follower pressure of 0.026 classical buckling pressures (a closed
    shell's follower pressure has a potential) and a dead force at its north pole: every check
    holds, and the shell does deform (by more than 1e-3 ell)."""
    spec = dict(mesh=("cubed_sphere", (1.2, 2)), L=float(np.pi * 0.6), perturb=0.0, pseed=0, E=1e4, nu=0.3,
                h=0.03, support="clamp", loads=[("follower_pressure", -0.2), ("nodal", "x1", [0.01, 0.0, 0.02])],
                alpha=1.0, law=("cosserat", None))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        o = fuzz.run_one(spec, np.random.default_rng(1), "numpy", [])
        assert all(r["ok"] for r in o["runs"].values()) and fuzz.violations(o) == []
        assert len(o["path"]) == 3 and len(o["frame"]) == 2
        p = fuzz.build(spec)
        g = p.solve(steps=2).final.g
    assert fuzz.state_distance(g, p.mesh.g0, spec["L"]) > 1e-3

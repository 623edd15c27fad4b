"""Lab-frame supports of scenario files (``[[supports]] type = "lab"`` / ``"lab_rotation"``):
the exact, path-independent alternative that the SupportWarning of a turning ``fix`` names
(issue 29), reachable without Python.

Before them a scenario could only hold body-frame dofs (``fix``): on nodes that turn about
another axis the held component drifts and the state depends on the load steps
(tests/test_support_drift.py: 2.4e-6 between 1 and 8 steps on this strip).
"""
import copy
import warnings

import numpy as np
import pytest

from core_se3 import lie, scenario
from core_se3.errors import ScenarioError, SupportWarning

STRIP = {
    "name": "turning-root strip",
    "mesh": {"generator": "rectangle", "L": 1.0, "width": 0.5, "nx": 2, "ny": 1},
    "material": {"E": 1e4, "nu": 0.3, "h": 0.05},
    "supports": [{"type": "fix", "edge": "x0", "dofs": [0, 1, 2]},
                 {"type": "lab", "edge": "x1", "direction": [0.0, 0.0, 1.0], "penalty": 2e3},   # a roller, 1e6 [force/length]
                 {"type": "lab_rotation", "edge": "x0", "axis": [0.0, 1.0, 0.0]}],
    "loads": [{"type": "edge_moment", "edge": "x1", "moment": [0.1, 0.0, 0.2]}],
    "solver": {"steps": 1},
}


def _solve(tmp_path, doc, steps):
    d = copy.deepcopy(doc)
    d["solver"]["steps"] = steps
    path = tmp_path / f"s{steps}.toml"
    path.write_text(scenario.dumps(d))
    scn = scenario.load(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        g = scn.problem.solve(steps=steps).steps[-1].g
    return scn.problem, g, [w for w in caught if issubclass(w.category, SupportWarning)]


def test_lab_rotation_holds_the_root_exactly_and_is_path_independent(tmp_path):
    p, g1, w1 = _solve(tmp_path, STRIP, 1)
    _, g8, w8 = _solve(tmp_path, STRIP, 8)
    assert not w1 and not w8
    assert np.abs(g1 - g8).max() < 1e-12                        # fix (0, 1, 2, 4) instead: 8.4e-7
    root, tip = p.nodes("x0"), p.nodes("x1")
    rel = np.swapaxes(p.mesh.g0[:, :3, :3], 1, 2) @ g1[:, :3, :3]
    assert np.abs(lie.log_so3(rel[root])[:, 1]).max() < 1e-6    # the lab-y rotation component, held
    assert np.abs(g1[root, :3, 3] - p.mesh.X[root]).max() == 0.0
    # the roller's penalty 2e3 E h = 1e6: held to its reaction / k, 1e-5 of the displacement
    assert np.abs(g1[tip, 2, 3] - p.mesh.X[tip, 2]).max() < 1e-4 * np.abs(g1[:, :3, 3] - p.mesh.X).max()


def test_the_same_support_held_by_fix_drifts_and_the_warning_names_the_scenario_kinds(tmp_path):
    doc = copy.deepcopy(STRIP)
    doc["supports"] = [{"type": "fix", "edge": "x0", "dofs": [0, 1, 2, 4]}, STRIP["supports"][1]]
    _, g1, w1 = _solve(tmp_path, doc, 1)
    _, g8, _ = _solve(tmp_path, doc, 8)
    assert np.abs(g1 - g8).max() > 3e-7         # 8.4e-7 (2.4e-6 before fem/membrane_enhanced.py)
    assert len(w1) == 1
    msg = str(w1[0].message)
    assert 'type = "lab"' in msg and 'type = "lab_rotation"' in msg and "direction" in msg


def test_a_lab_pin_matches_the_exact_pin_to_the_penalty(tmp_path):
    """Translations held by three lab springs (default penalty 1e6 E h) against fix (0, 1, 2),
    exact for any turn: 1.6e-8 apart (1.6e-2 / penalty)."""
    doc = copy.deepcopy(STRIP)
    doc["supports"] = [{"type": "fix", "edge": "x0", "dofs": [0, 1, 2]},
                       {"type": "fix", "edge": "x1", "dofs": [0, 1, 2]}]
    doc["loads"] = [{"type": "edge_moment", "edge": "x1", "moment": [0.0, 0.1, 0.02]}]
    _, g_fix, _ = _solve(tmp_path, doc, 2)
    doc["supports"][1:] = [{"type": "lab", "edge": "x1", "direction": d} for d in np.eye(3).tolist()]
    _, g_lab, _ = _solve(tmp_path, doc, 2)
    assert np.abs(g_lab - g_fix).max() < 1e-7


@pytest.mark.parametrize("entry, fragment", [
    ({"type": "lab", "edge": "x1", "direction": [0.0, 0.0, 0.0]}, "direction"),
    ({"type": "lab", "edge": "x1", "direction": [0.0, 1.0]}, "direction"),
    ({"type": "lab", "edge": "x1", "axes": ["z"]}, "axes"),
    ({"type": "lab_rotation", "edge": "x0", "axis": [0.0, 1.0, 0.0], "penalty": 0.0}, "penalty"),
    ({"type": "lab", "edge": "x1"}, "direction"),
])
def test_bad_lab_supports_are_refused_by_key(tmp_path, entry, fragment):
    doc = copy.deepcopy(STRIP)
    doc["supports"][1] = entry
    path = tmp_path / "bad.toml"
    path.write_text(scenario.dumps(doc))
    with pytest.raises(ScenarioError) as ei:
        scenario.load(path)
    assert ei.value.key.startswith("supports[1]") and fragment in str(ei.value), str(ei.value)


@pytest.mark.parametrize("penalty", [1e2, 1e4, 1e6, 1e8])
def test_a_stiff_penalty_support_converges_and_errs_like_one_over_k(penalty):
    """The springs' cancelling terms k P x - k P X join the residual's round-off floor
    (Load.round_off_scale): before, 1e4 E h stalled at a residual of 4e-10 (rtol 1e-10) and 1e6 E h
    failed after 12 cut-backs; now every penalty converges in the same iterations and the
    state's distance from the exact pin falls like 1/k (1.6e-2 / penalty here)."""
    from core_se3 import Material, Problem, mesh

    def strip(pin):
        p = Problem(mesh.rectangle(1.0, 0.5, 2, 1), Material(1e4, 0.3, 0.05))
        p.fix("x0", (0, 1, 2))
        pin(p)
        p.add_edge_moment("x1", (0.0, 0.1, 0.02))
        r = p.solve(steps=2)
        return r.steps[-1].g, [s.iterations for s in r.steps[1:]]

    g_exact, it_exact = strip(lambda p: p.fix("x1", (0, 1, 2)))
    g, it = strip(lambda p: p.add_lab_support("x1", np.eye(3), penalty * 1e4 * 0.05))
    assert it == it_exact
    err = np.abs(g - g_exact).max()
    assert 0.5e-2 / penalty < err < 5e-2 / penalty


def _four_node_edge():
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(1.0, 0.5, 2, 3), Material(1e4, 0.3, 0.05))
    assert len(p.nodes("x1")) == 4
    return p


def test_one_lab_direction_per_node_is_shape_n_1_3_and_n_rows_are_refused():
    """``add_lab_support``'s (q, 3) is a set held at every node (add_lab_tilt_support's (k, 3) is
    one row per node): four rows meant one per node of a four-node edge were read as four
    directions held at every node, whose sum of d d^T is no projector (here it held y and z with twice
    the stiffness: P = diag(0, 2, 2) at every node, silently).  More than 3 rows cannot be a set
    of lab directions: refused, naming (n, 1, 3); the per-node shape holds one each."""
    from core_se3.errors import SupportError
    per_node = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(SupportError, match=r"4 rows \(shape \(4, 3\)\).*per node give shape \(4, q, 3\).*\(4, 1, 3\)"):
        _four_node_edge().add_lab_support("x1", per_node, 1e3)
    spring = _four_node_edge().add_lab_support("x1", per_node[:, None, :], 1e3)
    assert np.array_equal(spring.P, np.einsum("ni,nj->nij", per_node, per_node))


def test_as_many_lab_directions_as_nodes_is_refused_as_ambiguous():
    """(q, 3) with q equal to the number of selected nodes reads two ways: np.eye(3) on a
    three-node edge was held as the whole translation at every node (P = I), while a user
    meaning one direction per node wanted e_i e_i^T at node i.  Refused when the rows differ,
    naming both explicit spellings; (1, q, 3) is the set at every node, (n, 1, 3) one per node,
    and the same (3, 3) on a four-node edge (unambiguous) still holds the set everywhere."""
    from core_se3 import Material, Problem, mesh
    from core_se3.errors import SupportError
    def three_node_edge():
        p = Problem(mesh.rectangle(1.0, 0.5, 2, 2), Material(1e4, 0.3, 0.05))
        assert len(p.nodes("x1")) == 3
        return p
    with pytest.raises(SupportError, match=r"reads two ways.*\(3, 1, 3\) for one direction per node, \(1, 3, 3\)"):
        three_node_edge().add_lab_support("x1", np.eye(3), 1e3)
    assert np.array_equal(three_node_edge().add_lab_support("x1", np.eye(3)[None], 1e3).P,
                          np.broadcast_to(np.eye(3), (3, 3, 3)))
    assert np.array_equal(three_node_edge().add_lab_support("x1", np.eye(3)[:, None, :], 1e3).P,
                          np.einsum("ni,nj->nij", np.eye(3), np.eye(3)))
    assert np.array_equal(_four_node_edge().add_lab_support("x1", np.eye(3), 1e3).P, np.broadcast_to(np.eye(3), (4, 3, 3)))
    same = three_node_edge().add_lab_support("x1", [[0.0, 0.0, 1.0]] * 1, 1e3)         # one row: one reading
    assert np.array_equal(same.P, np.broadcast_to(np.diag([0.0, 0.0, 1.0]), (3, 3, 3)))


def test_dependent_or_unnormalised_lab_directions_do_not_change_the_spring():
    """A direction given twice doubled its spring (P = 2 e_z e_z^T), a row of length 2 quadrupled
    it, and two rows that are not orthogonal held their plane with a stiffness that varied by
    direction (P = D^T D, eigenvalues 1.71 and 0.29): dependent rows are refused, rows are
    normalised and P is the projector on their span."""
    from core_se3.errors import SupportError
    with pytest.raises(SupportError, match="linearly dependent.*hold their common direction twice"):
        _four_node_edge().add_lab_support("x1", [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]], 1e3)
    with pytest.raises(SupportError, match="linearly dependent"):
        _four_node_edge().add_lab_support("x1", np.tile([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]], (4, 1, 1)), 1e3)
    assert np.array_equal(_four_node_edge().add_lab_support("x1", [[0.0, 0.0, 2.0]], 1e3).P,
                          np.broadcast_to(np.diag([0.0, 0.0, 1.0]), (4, 3, 3)))
    skew = _four_node_edge().add_lab_support("x1", [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], 1e3)
    assert np.abs(skew.P - np.diag([1.0, 1.0, 0.0])).max() < 4 * np.finfo(float).eps
    with pytest.raises(SupportError, match=r"got shape \(2, 2, 3\)"):
        _four_node_edge().add_lab_support("x1", np.ones((2, 2, 3)), 1e3)


def test_lab_supports_on_a_mesh_with_material_regions_take_the_stiffness_around_their_nodes(tmp_path):
    """With [material.regions] of another E (a documented feature) every `lab` or `lab_rotation`
    support failed to load: "E differs between regions ([10000.0, 20000.0]); use
    per_element('E')" -- a Python hint in a scenario file.  The penalty is now times the E h
    (E h^3) of the elements around the supported nodes, and the lab pin of a two-material strip
    matches the exact pin (fix 0, 1, 2) as on one material."""
    doc = copy.deepcopy(STRIP)
    doc["regions"] = {"tip": {"elements": [1]}}
    doc["material"]["regions"] = {"tip": {"E": 2e4}}
    root_turn = {"type": "lab_rotation", "edge": "x0", "axis": [1.0, 0.0, 0.0], "penalty": 1.0}
    doc["supports"] = [{"type": "fix", "edge": "x0", "dofs": [0, 1, 2]}, root_turn,
                       {"type": "fix", "edge": "x1", "dofs": [0, 1, 2]}]
    doc["loads"] = [{"type": "edge_moment", "edge": "x1", "moment": [0.0, 0.1, 0.02]}]
    p, g_fix, _ = _solve(tmp_path, doc, 2)
    assert p.loads[0].k == pytest.approx(1e4 * 0.05 ** 3)                      # the root element's E h^3
    doc["supports"][2:] = [{"type": "lab", "edge": "x1", "direction": d} for d in np.eye(3).tolist()]
    p, g_lab, _ = _solve(tmp_path, doc, 2)
    assert [ld.k for ld in p.loads[1:4]] == [1e6 * 2e4 * 0.05] * 3             # the tip element's E h
    assert np.abs(g_lab - g_fix).max() < 1e-7


def _propped_cantilever():
    """A clamp at x0 and a lab roller (a penalty spring on z) at x1 under an edge force 4 on z
    at x1: the roller carries nearly all of it."""
    from core_se3 import Material, Problem, mesh
    p = Problem(mesh.rectangle(1.0, 0.2, 8, 2), Material(1e4, 0.3, 0.02))
    p.clamp("x0")
    p.add_lab_support("x1", (0, 0, 1), 1e6)
    p.add_edge_force("x1", (0, 0, 4.0))
    return p


@pytest.mark.parametrize("linear", [False, True])
def test_a_penalty_roller_reports_its_force_as_a_support_reaction(linear):
    """The reactions are what the supports exert, the clamp's and the roller spring's: before,
    the spring's force counted with the applied loads, and reaction_force was the clamp's alone,
    -4.8e-9 on z (applied 4.8e-9) under the edge force 4, in both load stepping and linear
    analysis.  Now reaction = -applied edge force to round-off (1e-10 of 4), and the moment
    about the origin too (the force acts at x = 1)."""
    p = _propped_cantilever()
    st = (p.solve_linear() if linear else p.solve(steps=2)).steps[-1]
    assert np.abs(st.applied_force - [0, 0, 4.0]).max() < 1e-10 * 4
    assert np.abs(st.reaction_force + [0, 0, 4.0]).max() < 1e-10 * 4
    assert np.abs(st.applied_moment - [0, -4.0, 0]).max() < 1e-10 * 4
    assert np.abs(st.reaction_moment + st.applied_moment).max() < 1e-10 * 4
    assert st.balance_error < 1e-10


def test_a_scenario_lab_support_reaction_balances_the_edge_moment(tmp_path):
    """The STRIP scenario (a body-frame fix at x0, a lab roller on z at x1, a lab_rotation spring
    at x0) under an edge moment at x1 alone: the reactions' force is zero (the fix's and the
    roller's z forces form a couple) and their moment is minus the applied edge moment (0.1, 0,
    0.2), a dead lab moment.  Before, the springs' forces counted as applied: applied_force was
    (0, 0, -0.00684) (the roller's) where no force is applied, and applied_moment (0.00022, 0,
    0.19999): the lab_rotation spring's couple had absorbed the x moment 0.1 of the load."""
    path = tmp_path / "strip.toml"
    path.write_text(scenario.dumps(STRIP))
    st = scenario.load(path).problem.solve(steps=1).final
    M = np.array(STRIP["loads"][0]["moment"])
    assert np.abs(st.applied_force).max() < 1e-12
    assert np.abs(st.reaction_force).max() < 1e-10 * np.abs(M).max()
    assert np.abs(st.applied_moment - M).max() < 1e-12 * np.abs(M).max()
    assert np.abs(st.reaction_moment + st.applied_moment).max() < 1e-10 and st.balance_error < 1e-10


def test_results_json_carries_the_support_reactions_and_the_applied_loads(tmp_path):
    """A scenario's results.json gives each step's lab totals of the support reactions (held dofs
    and penalty springs) and of the applied loads, as the Python StepResult does: the STRIP under
    its edge moment M alone, the reactions' moment -M and force 0, the applied moment M exactly
    (a dead lab moment).  Before, results.json had neither (a scenario user could not read a
    reaction at all)."""
    import json
    path = tmp_path / "strip.toml"
    path.write_text(scenario.dumps(STRIP))
    scenario.load(path).run(out=tmp_path / "out", progress=False)
    last = json.loads((tmp_path / "out" / "results.json").read_text())["steps"][-1]
    M = np.array(STRIP["loads"][0]["moment"])
    assert np.abs(np.array(last["applied"]["moment"]) - M).max() < 1e-12 * np.abs(M).max()
    assert np.abs(np.array(last["applied"]["force"])).max() < 1e-12
    assert np.abs(np.array(last["reactions"]["moment"]) + M).max() < 1e-10 * np.abs(M).max()
    assert np.abs(np.array(last["reactions"]["force"])).max() < 1e-10 * np.abs(M).max()


def test_the_step_table_shows_the_total_support_reaction(tmp_path, capsys):
    """`core-se3 run`'s step table showed no reaction although results.json has each step's
    (one lab total of the held dofs and springs).  Now a column |R| [force unit]: a cantilever
    under a tip force of 2 N in two steps, |R| = 0, 1, 2 N, as results.json's reactions."""
    import json
    from core_se3 import cli
    doc = {"name": "cantilever", "units": "SI",
           "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
           "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 2.0]}], "solver": {"steps": 2},
           "output": {"vtu": False, "plots": False, "picture": False}}
    path = tmp_path / "c.toml"
    path.write_text(scenario.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o")]) == 0
    lines = capsys.readouterr().out.splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.lstrip().startswith("step"))
    cols = lines[head].split()
    assert "|R|" in cols and cols[cols.index("|R|") + 1] == "[N]"
    at = lines[head].index("[N]", lines[head].index("|R|")) + 3           # the column's right end
    shown = [float(ln[at - 12:at]) for ln in lines[head + 1:head + 4]]
    steps = json.loads((tmp_path / "o" / "results.json").read_text())["steps"]
    np.testing.assert_allclose(shown, [np.linalg.norm(s["reactions"]["force"]) for s in steps], rtol=1e-5, atol=1e-12)
    np.testing.assert_allclose(shown, [0.0, 1.0, 2.0], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("k", [-0.5, 0.0, float("nan"), "1", True])
def test_a_spring_support_of_no_positive_stiffness_is_refused(k):
    """add_lab_support with k = -0.5 pushed the tip of a cantilever (force 0.01 up: 0.0332 free,
    0.0077 on k = 0.5) to -0.0143, converged and silent; NaN gave NaN residuals, "1" was read as
    1.0.  The tilt and rotation-component springs take the same check."""
    from core_se3 import Material, Problem, mesh
    from core_se3.errors import SupportError
    p = Problem(mesh.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
    for add in (lambda: p.add_lab_support("x1", (0.0, 0.0, 1.0), k),
                lambda: p.add_lab_tilt_support("x1", (0.0, 1.0, 0.0), k),
                lambda: p.add_rotation_component_support("x1", (0.0, 0.0, 1.0), k)):
        with pytest.raises(SupportError, match="must be a positive number"):
            add()

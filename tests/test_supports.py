"""Supports: a rigid-body motion left free is reported by name before any solve (issue 2, item 8)."""
import json
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.errors import SingularSystemError


def _strip():
    return Problem(mesh.rectangle(10.0, 1.0, 8, 2), Material(1.2e6, 0.3, 0.1))


def test_free_drilling_rotation_is_named():
    # one node with translations and two rotations fixed: the rigid rotation about the
    # normal through that node (0, -0.5, 0) stays free
    p = _strip()
    p.fix([0], [0, 1, 2, 3, 4])
    p.add_edge_force("x1", (0, 0, 1.0))
    with pytest.raises(SingularSystemError, match=r"rotation about \[0\.0, 0\.0, 1\.0\] through \[0\.0, -0\.5"):
        p.solve(steps=1)


def test_translations_only_on_a_line_leave_rotation_free():
    # pinning every node of the edge x0 leaves the rotation about that edge free
    p = _strip()
    p.fix("x0", [0, 1, 2])
    p.add_edge_force("x1", (0, 0, 1.0))
    with pytest.raises(SingularSystemError, match=r"rotation about \[0\.0, -?1\.0, 0\.0\]"):
        p.solve(steps=1)


def test_clamped_edge_restrains_all_rigid_motions():
    p = _strip()
    p.clamp("x0")
    p.add_edge_force("x1", (0, 0, 1e-3))
    res = p.solve(steps=1)
    assert np.isfinite(res.final.g).all()


@pytest.mark.parametrize("length_unit", [1e-6, 1e-3, 1e3, 1e6, 1e9])
def test_the_support_check_and_the_solution_do_not_depend_on_the_unit_of_length(length_unit):
    """The same cantilever (10 x 1 x 0.1, PL^2/EI = 4) in another unit of length, E scaled to
    keep the load number: the tip displacement over the unit matches to round-off and Newton
    takes the same iterations; and a line of pins still leaves its rotation free.  Found in a
    stress run: with L = 10^4 (a 10 m strip in mm) the check called the clamp singular -- the
    lever arms of its rotation modes entered scaled by the mesh size squared."""
    def strip(s, clamp=True):
        E, h = 1.2e6 / s ** 2, 0.1 * s                   # E h^3 w / L^2 scales as 1/s^2 * s^2
        p = Problem(mesh.rectangle(10.0 * s, 1.0 * s, 16, 1), Material(E, 0.0, h))
        EI = E * s * h ** 3 / 12
        (p.clamp("x0") if clamp else p.fix("x0", [0, 1, 2]))
        p.add_edge_force("x1", (0.0, 0.0, 4.0 * EI / (10.0 * s) ** 2))
        p.add_probe("tip", "x1")
        return p
    ref, scaled = strip(1.0).solve(steps=4), strip(length_unit).solve(steps=4)
    u_ref, u = ref.final.probes["tip"]["u"], scaled.final.probes["tip"]["u"] / length_unit
    assert np.abs(u - u_ref).max() < 1e-12 * np.abs(u_ref).max()
    assert [s.iterations for s in scaled.steps] == [s.iterations for s in ref.steps]
    with pytest.raises(SingularSystemError, match=r"rotation about \[0\.0, -?1\.0, 0\.0\]"):
        strip(length_unit, clamp=False).solve(steps=1)


def test_bad_support_input_names_the_cause():
    """fix([-1]) used to fix the rotation about d3 silently (a negative index), fix([7]) raised
    a bare IndexError, and a NaN rotation angle was accepted until the solve."""
    from core_se3.errors import SupportError
    for dofs in ([-1], [7], [], [1.5], [True]):
        with pytest.raises(SupportError, match="dofs must be one or more of 0, 1, 2"):
            _strip().fix("x0", dofs)
    with pytest.raises(SupportError, match=r"dofs lists \[0\] more than once"):   # [0, 0]: was [0, 1] meant?
        _strip().fix("x0", [0, 0])
    for angle in (float("nan"), float("inf"), "pi"):
        with pytest.raises(SupportError, match="rotation angle must be a finite number"):
            _strip().rotate_edge("x1", (1.0, 0.0, 0.0), angle)
    with pytest.raises(SupportError, match="rotation point must be a finite 3-vector"):
        _strip().rotate_edge("x1", (1.0, 0.0, 0.0), 1.0, point=(0.0, np.nan, 0.0))
    p = _strip()
    p.fix("x0", np.array([0, 5]))
    assert p.constraint_mask()[p.nodes("x0")][:, [0, 5]].all() and not p.constraint_mask()[:, 1:5].any()


def test_a_node_selection_by_fractional_ids_or_by_a_mask_is_read_as_meant():
    """select_nodes cast any array to int64: ids [2.7, 5.2] held nodes 2 and 5 silently, and a
    boolean mask over the nodes (X[:, 0] == 1.0) was read as the ids 0 and 1 ('lists node 0 4
    times'); a predicate returning floats selected every node where it is non-zero.  Now a mask
    selects its True nodes (as Mesh.elements does), fractional ids and a predicate that is not
    one boolean per node are refused naming the cause."""
    from core_se3.errors import MeshError, SupportError
    p = _strip()
    x1 = p.nodes("x1").tolist()
    assert p.nodes(np.isclose(p.mesh.X[:, 0], p.mesh.X[:, 0].max())).tolist() == x1
    assert p.nodes(np.array(x1, float)).tolist() == x1                 # whole floats are ids
    with pytest.raises(SupportError, match="whole numbers"):
        p.nodes([x1[0] + 0.7])
    with pytest.raises(SupportError, match="one entry per node"):
        p.nodes(np.ones(3, bool))
    for pred in (lambda X: X[:, 0] - 1.0, lambda X: X == 0.0):
        with pytest.raises(MeshError, match="one boolean per node"):
            p.clamp(pred)
    assert not p.supports


def test_a_probe_on_a_predicate_is_the_midpoint_of_the_line_not_of_the_ids():
    """On a refined mesh the new nodes come after the old ones, so a predicate's nodes in id
    order put the probe of the edge x = 4 (y in [-0.5, 0.5]) at the corner y = 0.5 instead of
    the middle y = 0; the probe now orders the nodes along their line, and a set that is no
    line (a patch) is refused instead of recording one of its nodes."""
    from core_se3.errors import OptionError
    m = mesh.refine(mesh.rectangle(4.0, 1.0, 4, 2))
    p = Problem(m, Material(1e3, 0.0, 0.01))
    p.add_probe("by_name", "x1")
    p.add_probe("by_predicate", lambda X: np.isclose(X[:, 0], 4.0))
    p.add_probe("two_nodes", m.edges["x1"][[0, -1]])                    # halfway between two nodes
    for name in p.probes:
        assert np.allclose(p.probes[name].state(m.g0)[0], [4.0, 0.0, 0.0]), name
    with pytest.raises(OptionError, match="not a line of element edges"):
        p.add_probe("patch", lambda X: X[:, 0] < 1.1)


def test_a_scenario_probe_on_nodes_that_are_no_line_is_refused_by_its_key(tmp_path):
    """[[probes]] nodes = [3, 10, 17] (three nodes no element edge joins) was valid and recorded
    node 10, the middle of the list, as 'the midpoint'; now a ScenarioError naming
    probes[0].nodes, as an edge that is no line already was."""
    from core_se3 import scenario
    from core_se3.errors import ScenarioError
    doc = {"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 10, "ny": 1},
           "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
           "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
           "probes": [{"name": "odd", "nodes": [3, 10, 17]}]}
    path = tmp_path / "probe.toml"
    path.write_text(scenario.dumps(doc))
    with pytest.raises(ScenarioError, match="not a line of element edges") as ei:
        scenario.load(path)
    assert ei.value.key == "probes[0].nodes"
    doc["probes"] = [{"name": "line", "nodes": [10, 21]}, {"name": "two", "nodes": [0, 21]}]
    path.write_text(scenario.dumps(doc))
    assert sorted(scenario.load(path).problem.probes) == ["line", "two"]


def test_a_free_direction_of_a_rotated_edge_must_be_parallel_to_the_rotation_axis():
    """The free translation of a rigid motion is a body dof, which turns with the nodes.
    rotate_edge('x1', axis y, -0.8 rad, free x) was accepted (x perpendicular to the axis), and
    the end slid along its turned d1 = (0.70, 0, 0.72): z = -0.4167 where the motion holds z = 0,
    the same at 1, 4 and 16 steps.  Now a SupportError; free along the axis still works (a twist
    about x, free in x: the end stays on the axis, y and z held)."""
    from core_se3.errors import SupportError
    p = _strip()
    with pytest.raises(SupportError, match="must be parallel to the rotation axis"):
        p.rotate_edge("x1", (0.0, 1.0, 0.0), -0.8, point=(10.0, 0.0, 0.0), free=(0,))
    with pytest.raises(SupportError, match="must be parallel to the rotation axis"):
        p.move_edge("x1", axis=(0.0, 0.0, 1.0), angle=0.3, free=(1,))
    p.move_edge("x1", translate=(0.0, 0.0, 1.0), free=(0,))              # no rotation: any body axis
    q = _strip()
    q.clamp("x0")
    q.rotate_edge("x1", (1.0, 0.0, 0.0), 0.5, point=(0.0, 0.0, 0.0), free=(0,))
    g = q.solve(steps=2).final.g
    x1 = q.nodes("x1")
    R = np.array([[1, 0, 0], [0, np.cos(0.5), -np.sin(0.5)], [0, np.sin(0.5), np.cos(0.5)]])
    assert np.allclose(g[x1, 1:3, 3], (q.mesh.X[x1] @ R.T)[:, 1:], atol=1e-12)


@pytest.mark.parametrize("target, match", [
    (lambda lam: np.eye(4), r"must return \(2, 4, 4\) frames \(one per node\), got shape \(4, 4\)"),
    (lambda lam: np.broadcast_to(np.eye(4), (3, 4, 4)), r"got shape \(3, 4, 4\)"),
    (lambda lam: np.full((2, 4, 4), np.nan), "is not a frame"),
    (lambda lam: np.broadcast_to(np.diag([1.0 + lam, 1.0, 1.0, 1.0]), (2, 4, 4)), "is not a frame"),
])
def test_a_prescribed_target_that_is_not_one_frame_per_node_is_a_support_error(target, match):
    """Problem.prescribe(where, target): a target of shape (4, 4) failed as a bare IndexError, one
    for 3 nodes on an edge of 2 as a NumPy broadcast ValueError, NaN frames after 12 cut-backs
    ('non-finite residual') and a stretched frame after 12 cut-backs ('edge turns by 3.095 rad').
    Each is now a SupportError naming the shape or the frame, at the first load factor asked."""
    from core_se3.errors import SupportError
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.prescribe("x1", target)
    with pytest.raises(SupportError, match=match):
        p.solve(steps=2)


@pytest.mark.parametrize("distance", [0.0, 1e8, 1e9])
def test_a_free_rotation_of_a_far_turned_part_is_named(distance):
    """A strip pinned along its edge x0 (translations held) is free to turn about that edge.
    Turned and placed 1e8 or 1e9 from the origin, the rigid-motion check missed it (the modes'
    lever arms were formed as -R^T p + R^T c, eps |p| off, and the free mode's singular value
    came out above 1e-10 of the largest); the solve then stopped with the generic 'tangent is
    singular' message.  Now named at every distance, with the edge's direction."""
    from core_se3 import lie
    from core_se3.mesh.core import Mesh
    Q = np.eye(4)
    Q[:3, :3] = lie.exp_so3(2.19 * np.array([1.2, -0.8, 1.5]) / np.linalg.norm([1.2, -0.8, 1.5]))
    Q[:3, 3] = np.array([3.0, -1.0, 2.0]) / 3.7 * distance
    m0 = mesh.rectangle(10.0, 1.0, 8, 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                     # the far-from-origin MeshWarning
        m = Mesh(g0=Q @ m0.g0, quads=m0.quads, edges=m0.edges, shape=m0.shape)
    p = Problem(m, Material(1.2e6, 0.3, 0.1))
    p.fix("x0", dofs=(0, 1, 2))
    with pytest.raises(SingularSystemError, match=r"rigid-body motion free \(rotation about") as exc:
        p.check_supports()
    axis = np.array(json.loads(str(exc.value).split("rotation about ")[1].split(" through")[0]))
    assert abs(abs(axis @ Q[:3, 1]) - 1.0) < 2e-3                  # the edge's direction (3 digits)


def test_a_node_of_no_element_is_named_or_held_by_its_clamp():
    """A Mesh built by hand with a node that no quad lists (the readers drop such nodes): unheld it
    is a SingularSystemError naming the node and the fix (before, the part check failed with a bare
    IndexError on its empty element list); clamped, the rest solves as without it."""
    from core_se3.mesh import Mesh
    m = mesh.rectangle(10.0, 1.0, 4, 1)
    g0 = np.concatenate([m.g0, m.g0[:1]])
    g0[-1, 0, 3] = 50.0
    loose = Mesh(g0, m.quads, edges=m.edges)
    tips = []
    for msh, extra in ((loose, None), (loose, [10]), (m, None)):
        p = Problem(msh, Material(1e6, 0.0, 0.1))
        p.clamp("x0")
        if extra:
            p.clamp(extra)
        p.add_edge_force("x1", (0.0, 0.0, 1.0))
        p.add_probe("tip", "x1")
        if msh is loose and extra is None:
            with pytest.raises(SingularSystemError, match=r"node\(s\) \[10\] .*belong to no element.*or clamp them"):
                p.solve(steps=1)
            continue
        tips.append(p.solve(steps=1).final.probes["tip"]["u"])
    assert np.array_equal(tips[0], tips[1])

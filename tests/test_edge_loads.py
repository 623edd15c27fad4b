"""Edge loads (a total force or moment along a line, ``model.loads.edge_weights``): the line is
the set's own element edges, so its order, its pieces and a closed loop's closing edge do not
change the consistent nodal shares (exact: each node gets half the length of each edge it ends)."""
import numpy as np
import pytest

from core_se3 import Material, Problem, mesh
from core_se3.errors import LoadError
from core_se3.model.loads import edge_weights
from meshes import closed_ring

pytestmark = pytest.mark.core


def test_a_line_in_order_keeps_its_weights_bit_for_bit():
    """The generators' named lines (one line in its order): half of each adjacent segment, as
    the list's consecutive pairs gave before."""
    m = mesh.cylinder_arch(3.0, 2.0, 1.0, 7, 2)
    for name in ("x0", "x1", "y0", "y1"):
        ids = m.edges[name]
        seg = np.linalg.norm(np.diff(m.X[ids], axis=0), axis=1)
        old = np.zeros(len(ids))
        old[:-1] += seg / 2
        old[1:] += seg / 2
        assert np.array_equal(edge_weights(m, ids), old / old.sum())


def test_a_closed_loop_loads_its_closing_edge():
    """A ring's hole (a regular 8-gon of nodes, the slit of the annulus closed): every node ends
    two equal edges, so each gets 1/8.  Before, the closing edge was lost: its two nodes got
    1/14 and the others 1/7."""
    ring, hole = closed_ring(nt=8)
    np.testing.assert_allclose(edge_weights(ring, hole), np.full(8, 1 / 8), rtol=1e-14)
    np.testing.assert_allclose(edge_weights(ring, mesh.chain_order(np.stack([hole, np.roll(hole, -1)], 1))),
                               np.full(8, 1 / 8), rtol=1e-14)         # as the Gmsh reader orders a loop


def test_two_lines_in_one_set_share_by_length_without_jumps():
    """Both ends of a 10 x 1 strip (2 x 2 elements) in one set, listed by sorted id (how a
    Gmsh curve of two pieces arrives): each end gets half the load, 1/8, 1/4, 1/8 along it.
    Before, the sorted ids' consecutive pairs jumped between the ends (10 long) and loaded the
    middle nodes of the list ten times more."""
    m = mesh.rectangle(10.0, 1.0, 2, 2)
    ends = np.sort(np.concatenate([m.edges["x0"], m.edges["x1"]]))
    w = dict(zip(ends.tolist(), edge_weights(m, ends)))
    for name in ("x0", "x1"):
        np.testing.assert_allclose([w[i] for i in m.edges[name]], [1 / 8, 1 / 4, 1 / 8], rtol=1e-14)


def test_the_solution_does_not_depend_on_the_order_of_the_line():
    """A tip force on the strip's end given in any order of its nodes: the same tip deflection."""
    def tip(order):
        p = Problem(mesh.rectangle(10.0, 1.0, 4, 3), Material(1.2e6, 0.3, 0.1))
        p.clamp("x0")
        p.add_edge_force(p.mesh.edges["x1"][order], (0.0, 0.0, 1e-3))
        return p.solve_linear().displacements()[p.mesh.edges["x1"], 2]
    np.testing.assert_allclose(tip([2, 0, 3, 1]), tip([0, 1, 2, 3]), rtol=1e-12)


def test_points_that_no_element_edge_joins_are_refused():
    """Two opposite corners of a strip are no line: an edge load there is refused by name (it was
    split 50 / 50 over a 'segment' through the shell)."""
    m = mesh.rectangle(10.0, 1.0, 4, 1)
    with pytest.raises(LoadError, match="no element edge of the set joins"):
        edge_weights(m, [0, m.n_nodes - 1])


def test_an_edge_load_on_two_lines_follows_a_refinement(tmp_path):
    """A scenario's edge force on a Gmsh curve of two pieces (both ends of a strip, one set):
    with [mesh] refine = 1 the set's new nodes join the line, so the refined model is loaded as
    the same strip built at the finer mesh: its resultant and its nodal shares (1/16, 1/8, 1/8,
    1/8, 1/16 along each end)."""
    import meshio
    from core_se3 import scenario
    m = mesh.rectangle(10.0, 1.0, 2, 2)
    segs = np.concatenate([np.stack([ln[:-1], ln[1:]], 1) for ln in (m.edges["x0"], m.edges["x1"])])
    meshio.write(str(tmp_path / "strip.msh"),
                 meshio.Mesh(m.X, [("quad", m.quads), ("line", segs)],
                             cell_data={"gmsh:physical": [np.full(m.n_elements, 1), np.full(len(segs), 2)],
                                        "gmsh:geometrical": [np.full(m.n_elements, 1), np.full(len(segs), 2)]},
                             field_data={"shell": np.array([1, 2]), "ends": np.array([2, 1])}),
                 file_format="gmsh22", binary=False)
    doc = {"mesh": {"file": "strip.msh", "refine": 1}, "material": {"E": 1.2e6, "nu": 0.3, "h": 0.1},
           "supports": [{"type": "clamp", "nodes": [0]}],
           "loads": [{"type": "edge_force", "edge": "ends", "force": [0.0, 0.0, 1.0]}]}
    s = scenario.from_dict(doc, base_dir=str(tmp_path))
    f = s.problem.external(s.mesh.g0, 1.0, tangent=False)[0]
    fz = np.einsum("nij,nj->ni", s.mesh.g0[:, :3, :3], f[:, :3])[:, 2]
    X = s.mesh.X
    assert fz.sum() == pytest.approx(1.0, rel=1e-14)
    for x in (0.0, 10.0):
        on = np.flatnonzero(np.abs(X[:, 0] - x) < 1e-12)
        on = on[np.argsort(X[on, 1])]
        np.testing.assert_allclose(fz[on], [1 / 16, 1 / 8, 1 / 8, 1 / 8, 1 / 16], rtol=1e-12)


def test_a_patch_of_nodes_is_no_line():
    """A block of nodes (two rows of a strip) has element edges inside it: an edge load there is
    refused, not spread over them."""
    m = mesh.rectangle(10.0, 1.0, 4, 2)
    block = np.flatnonzero(m.X[:, 0] > 4.0)
    with pytest.raises(LoadError, match="not a line of element edges"):
        edge_weights(m, block)


@pytest.mark.parametrize("scale", [2.0, "constant", [[0.0, 0.0], [1.0, 1.0]]])
def test_a_load_or_motion_scale_that_is_no_function_is_refused_where_it_is_given(scale):
    """Problem.add_edge_force(..., scale=2.0) (or the scenario's spellings 'constant' or a table)
    was accepted and the solve failed with a bare "TypeError: 'float' object is not callable";
    rotate_edge the same.  Now a LoadError / SupportError at the call naming scale."""
    from core_se3.errors import LoadError, SupportError
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    with pytest.raises(LoadError, match="scale must be a function of the load factor"):
        p.add_edge_force("x1", (0.0, 0.0, 1.0), scale=scale)
    with pytest.raises(SupportError, match="scale must be a function of the load factor"):
        p.rotate_edge("x1", (1.0, 0.0, 0.0), 0.1, scale=scale)
    assert not p.loads and not p.supports


def test_a_load_scale_returning_an_array_is_named():
    """scale = lambda lam: np.array([lam, lam]) failed as 'TypeError: only size-1 arrays can be
    converted to Python scalars' inside the solve; now a LoadError naming the load."""
    from core_se3.errors import LoadError
    p = Problem(mesh.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.add_edge_force("x1", (0.0, 0.0, 1.0), scale=lambda lam: np.array([lam, lam]))
    with pytest.raises(LoadError, match="'edge force': its scale.lam. must return one number"):
        p.solve(steps=2)


def test_a_union_of_named_lines_loads_those_lines_only():
    """Both ends of a strip one element long (2 x 1, refined once in the scenario): one node set
    of both ends is a closed loop through the strip's sides, and a third of the total (1/6 on
    each side's midpoint) acted at mid-length.  Named one by one (``edge = ["x0", "x1"]``, or
    ``where=["x0", "x1"]``) each end keeps its own element edges: 1/8, 1/4, 1/8 on each end and
    nothing on the sides; the unequal ends of a trapezoid share the total by length (1 : 3)."""
    from core_se3 import scenario
    doc = {"mesh": {"generator": "rectangle", "L": 2.0, "width": 1.0, "nx": 1, "ny": 1, "refine": 1},
           "material": {"E": 1.2e6, "nu": 0.3, "h": 0.1}, "supports": [{"type": "clamp", "nodes": [0]}],
           "loads": [{"type": "edge_force", "edge": ["x0", "x1"], "force": [0.0, 0.0, 1.0]}]}
    s = scenario.from_dict(doc)
    fz = s.problem.external(s.mesh.g0, 1.0, tangent=False)[0][:, 2]
    X = s.mesh.X
    assert fz.sum() == pytest.approx(1.0, rel=1e-14)
    assert np.abs(fz[np.abs(X[:, 0] - 1.0) < 1e-12]).max() == 0.0            # nothing on the sides
    for x in (0.0, 2.0):
        on = np.flatnonzero(np.abs(X[:, 0] - x) < 1e-12)
        np.testing.assert_allclose(fz[on[np.argsort(X[on, 1])]], [1 / 8, 1 / 4, 1 / 8], rtol=1e-14)
    g0 = np.stack([np.eye(4)] * 4)
    g0[:, :3, 3] = [[0, 0, 0], [1, -1, 0], [1, 2, 0], [0, 1, 0]]      # ends 1 (x = 0) and 3 (x = 1)
    trap = mesh.Mesh(g0, [[0, 1, 2, 3]], edges={"a": [0, 3], "b": [1, 2], "ab": [0, 3, 2]})
    p = Problem(trap, Material(1.2e6, 0.3, 0.1))
    p.add_edge_force(["a", "b"], (0.0, 0.0, 4.0))
    f = p.external(trap.g0, 1.0, tangent=False)[0][:, 2]
    np.testing.assert_allclose(f, [0.5, 1.5, 1.5, 0.5], rtol=1e-14)
    with pytest.raises(LoadError, match="share the element edge"):
        p.add_edge_force(["a", "ab"], (0.0, 0.0, 1.0))
    with pytest.raises(LoadError, match="names a line twice"):
        p.add_edge_force(["a", "a"], (0.0, 0.0, 1.0))

"""Meshes: structured generators, frames, validation, and import through meshio."""
import re

import numpy as np
import pytest

from core_se3 import mesh as M
from core_se3.errors import MeshError, MeshWarning


def test_frames_are_orthonormal_with_normal_third_axis():
    for m in (M.rectangle(2.0, 1.0, 3, 2), M.cylinder_arch(0.5, np.pi, 0.1, 8, 1),
              M.cylinder_panel(1.016, 3.048, -np.pi / 2, np.pi / 2, 6, 4), M.annulus(6.0, 10.0, 2 * np.pi, 2, 12)):
        R = m.g0[:, :3, :3]
        assert np.allclose(R @ np.swapaxes(R, 1, 2), np.eye(3), atol=1e-14)
        assert np.allclose(np.linalg.det(R), 1.0)
        # d3 is normal to the mesh: orthogonal to every element edge incident to the node, up to the
        # chord-vs-tangent angle of a curved surface (half the element angle)
        X = m.X
        for a, b in m.edge_nodes:
            e = (X[b] - X[a]) / np.linalg.norm(X[b] - X[a])
            assert abs(e @ R[a][:, 2]) < 0.3


def test_edges_named_and_ordered():
    m = M.rectangle(2.0, 1.0, 4, 2)
    assert np.allclose(m.X[m.edges["x1"], 0], 2.0)
    assert np.all(np.diff(m.X[m.edges["x1"], 1]) > 0)
    assert len(m.edges["y0"]) == 5


@pytest.mark.parametrize("bad", ["collapsed", "clockwise", "outside"])
def test_degenerate_meshes_rejected(bad):
    m = M.rectangle(1.0, 1.0, 1, 1)
    q = m.quads.copy()
    if bad == "collapsed":
        q[0, 2] = q[0, 1]
    elif bad == "clockwise":
        q = q[:, ::-1]
    else:
        q[0, 0] = 99
    with pytest.raises(MeshError):
        M.Mesh(m.g0, q, m.edges)


def test_meshio_roundtrip_reproduces_cylinder_frames(tmp_path):
    import meshio
    ref = M.cylinder_panel(1.0, 2.0, -0.5, 0.5, 4, 3)
    path = tmp_path / "panel.vtu"
    meshio.write(str(path), meshio.Mesh(ref.X, [("quad", ref.quads)]))
    m = M.from_meshio(str(path), d1_hint=(1.0, 0.0, 0.0))
    assert m.n_nodes == ref.n_nodes and m.n_elements == ref.n_elements
    # averaged facet normals of a cylinder equal the exact normals at interior nodes
    inner = np.setdiff1d(np.arange(ref.n_nodes), np.concatenate(list(ref.edges.values())))
    assert np.allclose(m.g0[inner, :3, 2], ref.g0[inner, :3, 2], atol=1e-12)


def test_meshio_flipped_normal_rejected():
    import meshio
    ref = M.rectangle(2.0, 1.0, 2, 1)
    q = ref.quads.copy()
    q[1] = q[1, ::-1]
    with pytest.raises(MeshError, match="flip"):
        M.from_meshio(meshio.Mesh(ref.X, [("quad", q)]))


def test_meshio_triangles_rejected():
    import meshio
    with pytest.raises(MeshError, match="quadrilateral"):
        M.from_meshio(meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))


def test_meshio_line_group_off_the_shell_is_a_mesh_error():
    """A group of lines through a point no quad uses: that point was remapped to -1, so the
    edge held node -1 -- the mesh's last node -- and a support or load on it acted there."""
    import meshio
    ref = M.rectangle(2.0, 1.0, 2, 1)
    X = np.vstack([ref.X, [[5.0, 5.0, 0.0]]])                  # point 6: on no quad
    x1 = [int(i) for i in ref.edges["x1"]]
    m = meshio.Mesh(X, [("quad", ref.quads), ("line", np.array([x1, [x1[1], 6]]))],
                    cell_sets={"edge": [np.zeros(0, int), np.array([0, 1])]})
    with pytest.raises(MeshError, match=r"group 'edge' has 1 of its 2 line cell\(s\) off the shell"):
        M.from_meshio(m)


@pytest.mark.parametrize("cells, message", [
    ([("quad", np.array([[0, 1, 4, 3], [1, 2, 5, 9]]))], r"\['quad'\] cells refer to points that do not exist"),
    ([("quad", np.zeros((0, 4), int))], "no quad cells"),
    ([("quad9", np.arange(9)[None])], r"\['quad9'\] cells: second-order elements.*Mesh.ElementOrder = 1"),
    ([("quad8", np.arange(8)[None]), ("line3", np.array([[0, 2, 1]]))], r"second-order elements"),
])
def test_meshio_bad_cells_are_named(cells, message):
    """A quad naming point 9 of 9 points was a bare IndexError, an empty quad block a bare
    ValueError (zero-size reduction), quad8/quad9 (Gmsh's second order) 'only quadrilateral
    shells are supported' without the fix."""
    import meshio
    X = np.c_[np.arange(9) % 3, np.arange(9) // 3, np.zeros(9)].astype(float)
    with pytest.raises(MeshError, match=message):
        M.from_meshio(meshio.Mesh(X, cells))


def test_meshio_bad_points_are_named():
    """A point at nan was 'g0 must be a finite (n, 4, 4) array of SE(3) frames', a quad of zero
    area (all four nodes on one line) 'a node has no well-defined normal': neither named the
    points or quads."""
    import meshio
    X = np.c_[np.arange(9) % 3, np.arange(9) // 3, np.zeros(9)].astype(float)
    q = np.array([[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    Xn = X.copy()
    Xn[8, 0] = np.nan
    with pytest.raises(MeshError, match=r"mesh points \[8\] \(1 of the quads' 9\) have coordinates that are not finite"):
        M.from_meshio(meshio.Mesh(Xn, [("quad", q)]))
    line = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0.0]])
    with pytest.raises(MeshError, match=r"node\(s\) \[0, 1, 2, 3\] have no normal \(the quads at them, \[0\]"):
        M.from_meshio(meshio.Mesh(line, [("quad", np.array([[0, 1, 2, 3]]))]))


def test_node_ids_numbered_from_one_are_named_with_the_fix():
    """Quads numbered from 1 (Gmsh's, Abaqus' and Fortran's convention): a file's said "cells refer
    to points that do not exist ... write it again", a Mesh's "quad connectivity refers to nodes
    that do not exist" -- no element, no id, no fix.  Now the cell, the id, the range, and the fix
    where no element uses 0 and the largest id is the number of nodes; other ids out of range are
    named without it."""
    import meshio
    from core_se3.mesh.core import Mesh
    m = M.rectangle(2.0, 1.0, 2, 2)
    with pytest.raises(MeshError, match=r"quad cell 3 refers to node 9, which does not exist \(ids 1 \.\.\. 9 for 9 "
                                        r"nodes.*numbered from 1.*cells - 1"):
        M.from_meshio(meshio.Mesh(m.X, [("quad", m.quads + 1)]))
    with pytest.raises(MeshError, match=r"quad 3 refers to node 9.*numbered from 1.*subtract 1 from them"):
        Mesh(m.g0, m.quads + 1)
    with pytest.raises(MeshError, match=r"quad 0 refers to node -1, .*do not belong together"):
        Mesh(m.g0, m.quads - 1)


@pytest.mark.parametrize("change, match", [
    ("clockwise", r"quads \[1\] .*; quad 1: its nodes \[5, 6, 2, 1\] run clockwise .* list them the other way round, "
                  r"\[1, 2, 6, 5\]"),
    ("coincident", r"quads \[0, 1\] .*; quad 0 \(of 2 such quads\): its nodes 1 and 5 are at one point .* merge them"),
    ("re-entrant", r"quads \[0\] .*; quad 0: its corner at node 5 is re-entrant .* move node 5 so that the quad is convex"),
    ("straight", r"quads \[0\] .*; quad 0: its corner at node 5 is straight \(180 deg.* move node 5 off the line"),
])
def test_a_degenerate_quad_says_which_of_the_causes_it_is(change, match):
    """A strip of three quads with one listed clockwise, two nodes at one point, a re-entrant or a
    straight corner: each was 'quads [...] are degenerate, non-convex or listed clockwise about
    their normal (corner k)' -- three causes and no node; the coincident nodes named one of their
    two quads.  Now the quad, the node(s), which cause and its fix."""
    m = M.rectangle(3.0, 1.0, 3, 1)                                     # quads [0, 1, 5, 4], [1, 2, 6, 5], ...
    X, q = m.X.copy(), m.quads.copy()
    if change == "clockwise":
        q[1] = q[1][::-1]
    else:
        X[5] = {"coincident": X[1], "re-entrant": (0.3, -0.1, 0.0), "straight": (0.5, 0.0, 0.0)}[change]
    g = M.frames_from(X, np.tile([1.0, 0.0, 0.0], (8, 1)), np.tile([0.0, 0.0, 1.0], (8, 1)))
    with pytest.raises(MeshError, match=match):
        M.Mesh(g, q)


def test_a_degenerate_quad_of_a_file_is_named_by_the_files_point_ids():
    """The same from a file with an unused point first (file point ids = the reader's + 1): two
    nodes of quad cell 0 at one point were named 1 and 4 -- the reader's numbers; now 2 and 5."""
    import meshio
    m = M.rectangle(2.0, 1.0, 2, 1)                                     # quads [0, 1, 4, 3], [1, 2, 5, 4]
    X = np.r_[[[9.0, 9.0, 9.0]], m.X]
    X[5] = X[2]                                                         # file points 2 and 5 at one point
    with pytest.raises(MeshError, match=r"mesh file: quad cells \[0, 1\] .*quad cell 0 \(of 2 such quad cells\): "
                                        r"its nodes 2 and 5 are at one point.*\(point ids of the file\)"):
        M.from_meshio(meshio.Mesh(X, [("quad", m.quads + 1)]))


def test_quads_listed_the_other_way_round_are_named_in_the_files_ids():
    """A 3 x 3 plate whose file has an unused point first (file point ids = the reader's + 1) and
    one quad listed clockwise: the reader said 'quad normals flip across the edge (5, 9)' -- its
    own node numbers, not the file's (6, 10), and no cell.  Now the two cells, the edge in the
    file's ids, which quads to reverse (the fewer orientation of each part); a Moebius strip is
    said to have no orientation."""
    import meshio
    x, y = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 4))
    X = np.r_[[[9.0, 9.0, 9.0]], np.c_[x.ravel(), y.ravel(), np.zeros(16)]]
    q = np.array([[j * 4 + i, j * 4 + i + 1, (j + 1) * 4 + i + 1, (j + 1) * 4 + i] for j in range(3) for i in range(3)]) + 1
    with pytest.raises(MeshError, match=r"quad cells 3 and 4 run along their shared edge \(6, 10\) the same way.*"
                                        r"1 of the 9 quads \(cells \[4\]\) are listed the other way round"):
        M.from_meshio(meshio.Mesh(X, [("quad", np.r_[q[:4], q[4:5, ::-1], q[5:]])]))
    with pytest.raises(MeshError, match=r"3 of the 9 quads \(cells \[0, 1, 2\]\)"):
        M.from_meshio(meshio.Mesh(X, [("quad", np.r_[q[:3], q[3:, ::-1]])]))
    t = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
    P = np.array([[(1 + s * np.cos(a / 2)) * np.cos(a), (1 + s * np.cos(a / 2)) * np.sin(a), s * np.sin(a / 2)]
                  for a in t for s in (-0.3, 0.3)])
    strip = [[2 * k, 2 * k + 2, 2 * k + 3, 2 * k + 1] for k in range(7)] + [[14, 1, 0, 15]]   # joined with a twist
    with pytest.raises(MeshError, match=r"a non-orientable surface, a Moebius strip"):
        M.from_meshio(meshio.Mesh(P, [("quad", np.array(strip))]))


@pytest.mark.parametrize("order, before", [([1, 6, 2, 5], "quad normals flip across the edge (6, 2)"),
                                           ([1, 2, 5, 6], "degenerate, non-convex or listed clockwise")])
def test_a_bow_tie_quad_is_named_with_its_node_order_and_the_fix(order, before):
    """A strip of three quads whose middle one lists its nodes across itself (a bow-tie, two edges
    crossing): the reader said '{before}' -- flipped normals or a clockwise quad, not what is
    wrong.  Now: the quad, its node order, the crossing edges and the order around its boundary;
    a Mesh built directly says the same (its node ids)."""
    import meshio
    from core_se3.mesh.core import Mesh
    X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0], [3, 1, 0.0]])
    q = np.array([[0, 1, 5, 4], order, [2, 3, 7, 6]])
    with pytest.raises(MeshError, match=r"quad cell 1 is self-intersecting \(a bow-tie\): its node order "
                                        + re.escape(str(order)) + r" crosses its edges .*boundary, \[1, 2, 6, 5\]"):
        M.from_meshio(meshio.Mesh(X, [("quad", q)]))
    m = M.rectangle(3.0, 1.0, 3, 1)
    bad = m.quads.copy()
    bad[1] = bad[1][[0, 1, 3, 2]]
    with pytest.raises(MeshError, match=r"quad 1 is self-intersecting \(a bow-tie\)"):
        Mesh(g0=m.g0, quads=bad, edges=m.edges, shape=m.shape)


def test_meshio_d1_hint_along_the_normal_and_y():
    """A plate normal to y with d1_hint = y: the hint degenerates and so did its fallback, the
    global y axis -- 'g0 must be a finite (n, 4, 4) array of SE(3) frames' after a division by zero.
    Now x is taken where y degenerates too: the frames of the hint x."""
    import meshio
    X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 0, 1], [1, 0, 1], [2, 0, 1]], float)
    raw = meshio.Mesh(X, [("quad", np.array([[0, 1, 4, 3], [1, 2, 5, 4]]))])
    m, mx = M.from_meshio(raw, d1_hint=(0.0, 1.0, 0.0)), M.from_meshio(raw, d1_hint=(1.0, 0.0, 0.0))
    assert np.isfinite(m.g0).all() and np.array_equal(m.g0, mx.g0) and m.g0[0, :3, 0].tolist() == [1.0, 0.0, 0.0]


def test_meshio_unreadable_file(tmp_path):
    with pytest.raises(MeshError, match="cannot read"):
        M.from_meshio(str(tmp_path / "nope.msh"))


def test_meshio_garbage_file_is_a_mesh_error(tmp_path):
    """meshio answers a file it cannot parse by printing and calling sys.exit; from_meshio turns
    that into a MeshError that names the file (the process must not exit)."""
    path = tmp_path / "garbage.msh"
    path.write_text("not a mesh\n")
    with pytest.raises(MeshError, match="garbage.msh"):
        M.from_meshio(str(path))


def test_an_arch_or_panel_angle_beyond_a_turn_is_refused():
    """The generators' angles are radians: cylinder_arch(1, 180, 0.5, 400, 2) (180 meant as
    degrees) built 1203 nodes winding 28.6 turns over each other, and cylinder_panel(theta0=-90,
    theta1=90) likewise, with no error (annulus already refused more than 2 pi).  Now a
    MeshError naming the angle and its value in radians; a full turn is still a slit ring."""
    for build in (lambda: M.cylinder_arch(1.0, 180.0, 0.5, 400, 2),
                  lambda: M.cylinder_panel(1.0, 1.0, -90.0, 90.0, 400, 2),
                  lambda: M.annulus(0.5, 1.0, 180.0, 2, 400)):
        with pytest.raises(MeshError, match=r"must be in \(0, 2 pi\] \[rad\], got 180 \(3.14159 if 180 is in degrees"):
            build()
    with pytest.raises(MeshError, match="winds the surface over itself"):
        M.cylinder_arch(1.0, 3 * np.pi, 0.5, 16, 2)
    ring = M.cylinder_arch(1.0, 2 * np.pi, 0.5, 16, 2)
    assert np.allclose(ring.X[ring.node_set("x0")], ring.X[ring.node_set("x1")])


def test_a_quad_flat_to_round_off_is_refused_at_the_mesh():
    """annulus(0.5, 1, 2 pi, 1, 2): each of the two elements spans half a turn, its four corners
    on the x axis (the sine of every corner 2.4e-16, from sin(pi)), and passed the mesh check
    (corner cross products > 0 by round-off); the solve then failed with 'edge turns by 3.142
    rad: refine the mesh or the load step'.  A corner whose sine is at round-off is degenerate."""
    from core_se3.mesh.generators import _patch
    with pytest.raises(MeshError, match=r"quads \[0, 1\] are degenerate"):    # the mesh's own check
        _patch(np.array([0.5, 1.0]), np.array([0.0, np.pi, 2 * np.pi]),
               lambda R, T: (np.stack([R * np.cos(T), R * np.sin(T), 0 * T], -1),
                             np.stack([np.cos(T), np.sin(T), 0 * T], -1), np.tile([0, 0, 1.0], (T.size, 1))))
    with pytest.raises(MeshError, match=r"nt = 2 element\(s\) around .* at least nt = 3"):   # the generator's
        M.annulus(0.5, 1.0, 2 * np.pi, 1, 2)
    assert M.annulus(0.5, 1.0, 2 * np.pi, 1, 3).n_elements == 3         # a third of a turn each: fine
    with pytest.warns(MeshWarning, match="from the origin"):           # an aspect ratio of 1e12: not
        assert M.rectangle(1e6, 1e-6, 1, 1).n_elements == 1              # degenerate, but 1e12 widths out


def test_a_mesh_far_from_the_origin_warns_of_its_round_off():
    """Positions are stored absolutely, to eps |X|: a cantilever of shortest edge 0.5 and tip
    deflection 1.3e-3 placed at 1e10 is 4.7e-4 off the same cantilever at the origin, 3.4 % at
    1e12 (converged: nothing said).  A mesh farther than FAR_FROM_ORIGIN (1e10) of its shortest edge
    now warns; at 1e9 edges (the far-part tests) it does not."""
    import warnings
    for x0, warns in ((0.0, False), (1e9, False), (1e11, True)):
        m = M.rectangle(10.0, 1.0, 8, 1)
        g = m.g0.copy()
        g[:, 0, 3] += x0
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            M.Mesh(g, m.quads, dict(m.edges))
        assert [("from the origin" in str(w.message)) for w in rec] == ([True] if warns else [])


@pytest.mark.parametrize("x0", [1e17, 1e300])
def test_a_mesh_whose_edges_are_below_its_positions_round_off_says_so(x0):
    """A 1 x 0.2 strip placed 1e17 (or 1e300) from the origin has edges of 0 in double precision
    (eps |X| = 22): it was refused as 'degenerate, non-convex or listed clockwise', which sends the
    user to the node order; the error now names the distance and the fix."""
    with pytest.raises(MeshError, match=r"degenerate.*the mesh lies 1e\+(17|300) from the origin, where positions "
                                        r"are stored to eps \|X\| = .*translate the mesh toward the origin"):
        M.rectangle(1.0, 0.2, 4, 1, x0=x0)
    meshio = pytest.importorskip("meshio")
    X = np.array([[0, 0, 0], [1, 0, 0], [1, 0, 0], [0, 1, 0.0]])          # a collapsed quad at the origin
    with pytest.raises(MeshError) as ei:
        M.from_meshio(meshio.Mesh(X, [("quad", np.array([[0, 1, 2, 3]]))]))
    assert "from the origin" not in str(ei.value)


@pytest.mark.parametrize("edges, regions, match", [
    ({"tip": [4, 4]}, {}, r"node set 'tip' lists node 4 2 times"),
    ({}, {"r": [3, 3]}, r"region 'r' lists element 3 2 times"),
    ({"tip": [99]}, {}, r"node set 'tip' must list existing node ids \(0 \.\. 9\)"),
    ({"tip": [0.5, 1.7]}, {}, r"node set 'tip' must be whole numbers"),
    ({}, {"r": [0.5]}, r"region 'r' must be whole numbers"),
])
def test_a_named_set_listing_an_id_twice_or_not_an_id_is_refused(edges, regions, match):
    """A named node set or region of a Mesh built by hand is checked as ids given directly are:
    before, a region listing element 3 twice doubled its pressure (tip deflection 16.06 against
    8.03) and its gravity, a node set listing node 4 twice doubled a nodal load (7.88 against
    3.94), and a region's 0.5 was read as element 0 -- all silently."""
    m = M.rectangle(10.0, 1.0, 4, 1)
    with pytest.raises(MeshError, match=match):
        M.Mesh(m.g0, m.quads, edges={**m.edges, **edges}, regions=regions)


def test_quads_that_are_not_whole_ids_and_frames_that_are_not_homogeneous_are_refused():
    """Quads of 0.7 were read as node 0 (a shifted connectivity, silently), and frames whose last
    row is not [0, 0, 0, 1] were taken (a position typed into the last row was dropped)."""
    m = M.rectangle(10.0, 1.0, 4, 1)
    with pytest.raises(MeshError, match="quads must be whole numbers"):
        M.Mesh(m.g0, m.quads + 0.7)
    g0 = m.g0.copy()
    g0[:, 3, :3] = g0[:, :3, 3]
    with pytest.raises(MeshError, match=r"last rows must be \[0, 0, 0, 1\].*node 0's is \[0.0, -0.5, 0.0, 1.0\]"):
        M.Mesh(g0, m.quads)
    assert M.Mesh(m.g0, m.quads.astype(float)).quads.dtype == np.int64       # whole floats are ids

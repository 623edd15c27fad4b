"""Meshes as Gmsh writes them (issue 18, finding 1): files written during the test by the `gmsh`
Python package (PyPI) in MSH 4.1 and 2.2, ASCII and binary, with physical groups of curves,
surfaces and points; all-quad and quad-dominant meshes; the same through the Python API and
scenario files.  Skipped cleanly where gmsh is not installed.

The checks are exact: a transfinite 10 x 2 plate is the same mesh as ``mesh.rectangle`` (up to
the node order), so the cantilever solved on the file equals the one solved on the generator
to round-off.
"""
import numpy as np
import pytest

from core_se3 import mesh as M
from core_se3 import scenario
from core_se3.errors import MeshError, MeshWarning, ScenarioError

try:                                    # the wheel needs X11/OpenGL libraries: an OSError without them
    import gmsh
except (ImportError, OSError):
    gmsh = None
if gmsh is None:
    pytest.skip("gmsh (PyPI) is not installed or cannot load its libraries", allow_module_level=True)

FORMATS = [(4.1, 0), (4.1, 1), (2.2, 0), (2.2, 1)]


def _start():
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("t")


def _write(path, version, binary):
    gmsh.option.setNumber("Mesh.MshFileVersion", version)
    gmsh.option.setNumber("Mesh.Binary", binary)
    gmsh.write(str(path))
    gmsh.finalize()
    return str(path)


def plate_file(path, version=4.1, binary=0, nx=10, ny=2, surfaces=True, names=True):
    """10 x 2 plate of two 5 x 2 halves (physical surfaces 'left', 'right'), transfinite nx x ny
    quads; physical curves 'clamped' (x = 0) and 'tip' (x = 10), physical point 'corner' (10, 2);
    ``surfaces="left"``: only the left half a physical surface (so only it is saved); ``names=False``:
    the groups numbered (surfaces 1, 2, curves 1 (x = 0), 2 (x = 10), point 3) without names,
    ``names="some"``: the same numbers, all named but the curve 2."""
    _start()
    occ = gmsh.model.occ
    a = occ.addRectangle(0, 0, 0, 5, 2)
    b = occ.addRectangle(5, 0, 0, 5, 2)
    occ.fragment([(2, a)], [(2, b)])
    occ.synchronize()
    for dim, tag in gmsh.model.getEntities(1):
        x0, y0, _, x1, y1, _ = gmsh.model.getBoundingBox(dim, tag)
        gmsh.model.mesh.setTransfiniteCurve(tag, (ny if abs(x1 - x0) < 1e-5 else nx // 2) + 1)
    for _, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
        gmsh.model.mesh.setRecombine(2, tag)

    def at(dim, x=None, y=None):
        out = []
        for _, tag in gmsh.model.getEntities(dim):
            c = gmsh.model.occ.getCenterOfMass(dim, tag) if dim else gmsh.model.getValue(0, tag, [])
            if (x is None or abs(c[0] - x) < 1e-9) and (y is None or abs(c[1] - y) < 1e-9):
                out.append(tag)
        return out
    def group(dim, tags, name, number):       # names=False: tags 1, 2, ... alone (e.g. for FEniCS)
        gmsh.model.addPhysicalGroup(dim, tags, number if names is not True else -1, name=name if names else "")
    if surfaces:
        group(2, at(2, x=2.5), "left", 1)
    if surfaces is True:
        group(2, at(2, x=7.5), "right", 2)
    group(1, at(1, x=0.0), "clamped", 1)
    group(1, at(1, x=10.0), "tip" if names != "some" else "", 2)
    group(0, at(0, x=10.0, y=2.0), "corner", 3)
    gmsh.model.mesh.generate(2)
    return _write(path, version, binary)


def disk_file(path, version=4.1, binary=0):
    """A quad-dominant disk (radius 5, simple recombination leaves triangles), physical
    surface 'disk' and curve 'rim'."""
    _start()
    d = gmsh.model.occ.addDisk(0, 0, 0, 5, 5)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMax", 1.3)
    gmsh.option.setNumber("Mesh.Algorithm", 6)
    gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 0)
    gmsh.model.mesh.setRecombine(2, d)
    gmsh.model.addPhysicalGroup(2, [d], name="disk")
    gmsh.model.addPhysicalGroup(1, [t for _, t in gmsh.model.getEntities(1)], name="rim")
    gmsh.model.mesh.generate(2)
    return _write(path, version, binary)


def _cantilever(where):
    doc = {"mesh": where, "material": {"E": 1.2e6, "nu": 0.3, "h": 0.1},
           "supports": [{"type": "clamp", "edge": "clamped" if "file" in where else "x0"}],
           "loads": [{"type": "edge_force", "edge": "tip" if "file" in where else "x1",
                      "force": [0.0, 0.0, 1.0]}],
           "probes": [{"name": "tip", "edge": "tip" if "file" in where else "x1"}],
           "solver": {"steps": 2}}
    return doc


@pytest.mark.parametrize("version,binary", FORMATS, ids=["4.1-ascii", "4.1-binary", "2.2-ascii", "2.2-binary"])
def test_gmsh_formats_groups_of_curves_surfaces_points(tmp_path, version, binary):
    path = plate_file(tmp_path / "plate.msh", version, binary)
    m = M.from_meshio(path)
    assert m.n_elements == 20 and m.n_nodes == 33
    assert sorted(m.regions) == ["left", "right"]
    assert len(m.regions["left"]) == 10 and len(m.regions["right"]) == 10
    centroids = m.X[m.quads].mean(1)
    assert np.all(centroids[m.regions["left"], 0] < 5) and np.all(centroids[m.regions["right"], 0] > 5)
    assert sorted(m.edges) == ["clamped", "corner", "tip"]
    assert m.X[m.edges["tip"]].tolist() in ([[10.0, 0, 0], [10.0, 1, 0], [10.0, 2, 0]],
                                           [[10.0, 2, 0], [10.0, 1, 0], [10.0, 0, 0]])   # ordered
    assert m.X[m.edges["corner"]].tolist() == [[10.0, 2.0, 0.0]]
    assert np.allclose(m.g0[:, :3, 2], [0, 0, 1])              # normals +z


def overlapping_groups_file(path, version, binary):
    """The 10 x 2 plate of two 5 x 2 halves, every element in two physical groups: surfaces
    'left', 'right' and 'shell' (both), the curve x = 10 in 'tip' and 'loaded', the corner point
    (10, 2) in 'corner' and 'probe'."""
    _start()
    occ = gmsh.model.occ
    a, b = occ.addRectangle(0, 0, 0, 5, 2), occ.addRectangle(5, 0, 0, 5, 2)
    occ.fragment([(2, a)], [(2, b)])
    occ.synchronize()
    for _, tag in gmsh.model.getEntities(1):
        x0, _, _, x1, _, _ = gmsh.model.getBoundingBox(1, tag)
        gmsh.model.mesh.setTransfiniteCurve(tag, 3 if abs(x1 - x0) < 1e-5 else 6)
    surf = {}
    for _, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
        gmsh.model.mesh.setRecombine(2, tag)
        surf["left" if occ.getCenterOfMass(2, tag)[0] < 5 else "right"] = tag
    tip = [t for _, t in gmsh.model.getEntities(1) if abs(occ.getCenterOfMass(1, t)[0] - 10) < 1e-9]
    corner = [t for _, t in gmsh.model.getEntities(0) if np.allclose(gmsh.model.getValue(0, t, []), [10, 2, 0])]
    for name, tag in surf.items():
        gmsh.model.addPhysicalGroup(2, [tag], name=name)
    gmsh.model.addPhysicalGroup(2, list(surf.values()), name="shell")
    for name in ("tip", "loaded"):
        gmsh.model.addPhysicalGroup(1, tip, name=name)
    for name in ("corner", "probe"):
        gmsh.model.addPhysicalGroup(0, corner, name=name)
    gmsh.model.mesh.generate(2)
    return _write(path, version, binary)


@pytest.mark.parametrize("version,binary", FORMATS, ids=["4.1-ascii", "4.1-binary", "2.2-ascii", "2.2-binary"])
def test_gmsh_elements_in_two_groups_are_read_once(tmp_path, version, binary):
    """MSH 2.2 writes an element once per physical group it is in: every quad of a surface in
    'left' and 'shell' came twice (40 quads for 20), and the reader refused the file with "quad
    normals flip across the edge" (the repeated quads run their edges the same way); MSH 4.1
    writes it once.  Every format now gives the same mesh."""
    m = M.from_meshio(overlapping_groups_file(tmp_path / "two.msh", version, binary))
    assert m.n_elements == 20 and m.n_nodes == 33
    assert sorted(m.regions) == ["left", "right", "shell"] and m.regions["shell"].tolist() == list(range(20))
    assert sorted(np.r_[m.regions["left"], m.regions["right"]].tolist()) == list(range(20))
    assert np.all(m.X[m.quads].mean(1)[m.regions["left"], 0] < 5)
    for name in ("tip", "loaded"):
        assert m.X[m.edges[name], 1].tolist() in ([0.0, 1.0, 2.0], [2.0, 1.0, 0.0])     # ordered, once each
        assert np.allclose(m.X[m.edges[name], 0], 10.0)
    assert m.X[m.edges["corner"]].tolist() == m.X[m.edges["probe"]].tolist() == [[10.0, 2.0, 0.0]]


def shared_name_file(path, version=4.1, binary=0):
    """A 4 x 1 plate of 4 x 1 quads whose physical surface and the point (4, 1) are both named
    'plate' (Gmsh allows one name for groups of different dimensions), curve x = 0 'clamped'."""
    _start()
    s = gmsh.model.occ.addRectangle(0, 0, 0, 4, 1)
    gmsh.model.occ.synchronize()
    for _, tag in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(tag, 5 if gmsh.model.occ.getMass(1, tag) > 2 else 2)
    gmsh.model.mesh.setTransfiniteSurface(s)
    gmsh.model.mesh.setRecombine(2, s)
    corner = [t for _, t in gmsh.model.getEntities(0) if np.allclose(gmsh.model.getValue(0, t, []), [4, 1, 0])]
    left = [t for _, t in gmsh.model.getEntities(1) if abs(gmsh.model.occ.getCenterOfMass(1, t)[0]) < 1e-9]
    gmsh.model.addPhysicalGroup(2, [s], 7, name="plate")
    gmsh.model.addPhysicalGroup(0, corner, 9, name="plate")
    gmsh.model.addPhysicalGroup(1, left, 8, name="clamped")
    gmsh.model.mesh.generate(2)
    return _write(path, version, binary)


@pytest.mark.parametrize("version,binary", FORMATS, ids=["4.1-ascii", "4.1-binary", "2.2-ascii", "2.2-binary"])
def test_gmsh_one_name_for_groups_of_two_dimensions_is_a_mesh_warning(tmp_path, version, binary):
    """meshio keeps one group per name: the point 'plate' came as the set '9', and a support on
    'plate' meant for the corner held every node of the surface (10 of 10), silently before."""
    path = shared_name_file(tmp_path / "plate.msh", version, binary)
    with pytest.warns(MeshWarning) as caught:
        m = M.from_meshio(path)
    said = [str(w.message) for w in caught if "physical groups are named" in str(w.message)]
    assert len(said) == 1 and "2 physical groups are named 'plate' (point 9, surface 7)" in said[0]
    assert "'plate' is the surface 7" in said[0] and "the point 9 as '9'" in said[0]
    assert len(m.node_set("plate")) == m.n_nodes == 10 and m.X[m.edges["9"]].tolist() == [[4.0, 1.0, 0.0]]


def test_a_scenario_names_the_mesh_file_key_for_a_shared_group_name(tmp_path):
    shared_name_file(tmp_path / "plate.msh")
    doc = {"mesh": {"file": "plate.msh"}, "material": {"E": 1e6, "nu": 0.3, "h": 0.05},
           "supports": [{"type": "clamp", "edge": "clamped"}],
           "loads": [{"type": "nodal", "nodes": {"near": [4.0, 1.0, 0.0]}, "force": [0.0, 0.0, 1e-6]}]}
    with pytest.warns(Warning):
        scn = scenario.from_dict(doc, base_dir=str(tmp_path))
    assert any("mesh.file" in w and "named 'plate'" in w for w in map(str, scn.warnings))


def test_a_quad_listed_twice_outside_gmsh_is_a_mesh_error():
    import meshio
    X = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]])
    with pytest.raises(MeshError, match=r"quad cells 0 and 1 .* list the same nodes \[0, 1, 2, 3\]"):
        M.from_meshio(meshio.Mesh(X, [("quad", np.array([[0, 1, 2, 3], [0, 1, 2, 3]]))]))


@pytest.mark.parametrize("version,binary", [(4.1, 0), (2.2, 1)], ids=["4.1-ascii", "2.2-binary"])
def test_gmsh_file_scenario_equals_generator(tmp_path, version, binary):
    """The scenario on the Gmsh file and on mesh.rectangle (the same 10 x 2 quads) agree to
    round-off (1e-12 of the tip lift)."""
    plate_file(tmp_path / "plate.msh", version, binary)
    on_file = scenario.from_dict(_cantilever({"file": "plate.msh"}), base_dir=str(tmp_path))
    on_gen = scenario.from_dict(_cantilever({"generator": "rectangle", "L": 10.0, "width": 2.0,
                                             "nx": 10, "ny": 2, "x0": 0.0}))
    a = on_file.problem.solve().final.probes["tip"]["u"]
    b = on_gen.problem.solve().final.probes["tip"]["u"]
    assert abs(a[2]) > 1.0
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * abs(b[2]))


def test_gmsh_quad_dominant_mesh_split_into_quads(tmp_path):
    path = disk_file(tmp_path / "disk.msh")
    with pytest.raises(MeshError, match=r"only quadrilateral shells.*triangles = \"split\".*SubdivisionAlgorithm"):
        M.from_meshio(path)
    import meshio
    raw = meshio.read(path)
    n_tri = sum(len(c.data) for c in raw.cells if c.type == "triangle")
    n_quad = sum(len(c.data) for c in raw.cells if c.type == "quad")
    assert n_tri > 0 and n_quad > 0
    m = M.from_meshio(path, triangles="split")
    assert m.n_elements == 4 * n_quad + 3 * n_tri
    assert len(m.regions["disk"]) == m.n_elements
    # the split keeps the area of the polygonal disk exactly; the rim stays a closed line of nodes
    area = lambda X, q: 0.5 * np.abs(np.cross(X[q[:, 2]] - X[q[:, 0]], X[q[:, 3]] - X[q[:, 1]])[:, 2]).sum()
    X0 = np.asarray(raw.points)
    a0 = area(X0, np.concatenate([c.data for c in raw.cells if c.type == "quad"]))
    tri = np.concatenate([c.data for c in raw.cells if c.type == "triangle"])
    a0 += 0.5 * np.abs(np.cross(X0[tri[:, 1]] - X0[tri[:, 0]], X0[tri[:, 2]] - X0[tri[:, 0]])[:, 2]).sum()
    np.testing.assert_allclose(area(m.X, m.quads), a0, rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(m.X[m.edges["rim"], :2], axis=1)[::2], 5.0, rtol=1e-12)
    # the same from a scenario file
    doc = {"mesh": {"file": "disk.msh", "triangles": "split"}, "material": {"E": 1e3, "nu": 0.3, "h": 0.1},
           "supports": [{"type": "clamp", "edge": "rim"}]}
    scn = scenario.from_dict(doc, base_dir=str(tmp_path))
    assert scn.mesh.n_elements == m.n_elements
    doc["mesh"].pop("triangles")
    with pytest.raises(ScenarioError, match=r"\[mesh.file\]: bad mesh 'disk.msh': only quadrilateral"):
        scenario.from_dict(doc, base_dir=str(tmp_path))


def test_gmsh_file_without_physical_surface_names_the_fix(tmp_path):
    path = plate_file(tmp_path / "curves.msh", surfaces=False)
    with pytest.raises(MeshError, match=r"no quad cells; .*physical groups of curves .* Mesh.SaveAll = 1"):
        M.from_meshio(path)


def test_gmsh_curve_off_the_saved_surface_names_the_group(tmp_path):
    """Only the left half a physical surface, so Gmsh saves only its quads, while the physical
    curve 'tip' (x = 10) bounds the unsaved right half: its nodes belong to no quad and were
    remapped to -1, so mesh.edges['tip'] was [-1] -- the mesh's last node, at (4, 1, 0) -- and a
    scenario's load on 'tip' failed with "node selection array([-1]) refers to nodes that do not
    exist".  Now a MeshError names the group and the fix."""
    path = plate_file(tmp_path / "half.msh", surfaces="left")
    with pytest.raises(MeshError, match=r"group 'tip' has 2 of its 2 line cell\(s\) off the shell.*Mesh.SaveAll = 1"):
        M.from_meshio(path)
    doc = _cantilever({"file": path})
    with pytest.raises(ScenarioError, match=r"has 2 of its 2 line cell\(s\) off the shell"):   # the name elided:
        # an error never shows a file's text (io.files.without_contents)
        scenario.from_dict(doc, base_dir=str(tmp_path))


@pytest.mark.parametrize("version,binary", [(4.1, 0), (2.2, 0), (2.2, 1)], ids=["4.1-ascii", "2.2-ascii", "2.2-binary"])
def test_gmsh_groups_without_names_are_named_by_number(tmp_path, version, binary):
    """Physical groups given by number alone (no $PhysicalNames; FEniCS scripts use tags) were
    dropped: no node sets or regions, and a scenario's edge = "1" was 'unknown edge ... no named
    edges'.  Now a group without a name is named by its number (curves 1, 2 and surfaces 1, 2
    share numbers: node sets and regions are apart); named groups stay as they were."""
    named = M.from_meshio(plate_file(tmp_path / "named.msh", version, binary))
    m = M.from_meshio(plate_file(tmp_path / "numbered.msh", version, binary, names=False))
    assert sorted(m.edges) == ["1", "2", "3"] and sorted(m.regions) == ["1", "2"]
    for a, b in (("1", "clamped"), ("2", "tip"), ("3", "corner")):
        assert m.edges[a].tolist() == named.edges[b].tolist()
    for a, b in (("1", "left"), ("2", "right")):
        assert m.regions[a].tolist() == named.regions[b].tolist()
    some = M.from_meshio(plate_file(tmp_path / "some.msh", version, binary, names="some"))
    assert sorted(some.edges) == ["2", "clamped", "corner"] and sorted(some.regions) == ["left", "right"]
    doc = _cantilever({"file": "numbered.msh"})
    doc["supports"][0]["edge"], doc["loads"][0]["edge"], doc["probes"][0]["edge"] = "1", "2", "2"
    assert scenario.from_dict(doc, base_dir=str(tmp_path)).mesh.edges["2"].tolist() == named.edges["tip"].tolist()


def test_element_ids_on_a_gmsh_file_warn_that_they_are_not_the_files_tags(tmp_path):
    """A strip of 4 quads saved by Gmsh with two boundary lines first: Gmsh tags the quads 3 ... 6
    (lines 1, 2), meshio keeps no tags, and core_se3 numbers the quads 0 ... 3.  A region
    `elements = [3]` copied from Gmsh (the quad at x in [0, 1]) selected the quad at x in [3, 4],
    silently.  The ids stay core_se3's (its VTU cell ids and messages use them), but on a Gmsh
    file (or one with other cells, or split triangles) they now warn at the key, pointing at
    physical surfaces and boxes; a VTU file of quads alone (whose cell ids they are) warns not."""
    import meshio
    import warnings
    m = M.rectangle(4.0, 1.0, 4, 1)
    lines = np.array([m.edges["x0"], m.edges["x1"]])
    cells = [("line", lines), ("quad", m.quads)]
    meshio.write(str(tmp_path / "strip.msh"),
                 meshio.Mesh(m.X, cells, cell_data={"gmsh:physical": [np.array([2, 3]), np.full(4, 1)],
                                                    "gmsh:geometrical": [np.array([2, 3]), np.full(4, 1)]},
                             field_data={"shell": np.array([1, 2]), "clamped": np.array([2, 1]),
                                         "tip": np.array([3, 1])}),
                 file_format="gmsh22", binary=False)
    meshio.write(str(tmp_path / "strip.vtu"), meshio.Mesh(m.X, [("quad", m.quads)]))
    doc = {"mesh": {"file": "strip.msh"}, "material": {"E": 1e6, "nu": 0.3, "h": 0.01},
           "supports": [{"type": "clamp", "edge": "clamped"}], "regions": {"picked": {"elements": [3]}},
           "loads": [{"type": "pressure", "p": 1.0, "region": "picked"}]}
    with pytest.warns(UserWarning):
        s = scenario.from_dict(doc, base_dir=str(tmp_path))
    assert s.mesh.X[s.mesh.quads[s.regions["picked"]]].mean(1)[0, 0] == pytest.approx(3.5)   # core_se3's id 3
    hit = [w for w in s.warnings if w.key == "regions.picked.elements"]
    assert hit and "not the file's element numbers" in str(hit[0]) and "physical surface" in str(hit[0])
    with pytest.raises(ScenarioError, match="Gmsh mesh, whose element tags count every element"):
        scenario.from_dict(doc, base_dir=str(tmp_path), strict=True)
    doc["mesh"]["file"] = "strip.vtu"
    doc["supports"] = [{"type": "clamp", "nodes": [0, 5]}]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not scenario.from_dict(doc, base_dir=str(tmp_path)).warnings

"""core_se3.scenario: TOML scenario files validated before anything runs.

Each kind of bad input gets its own test asserting the error type, the dotted key it names and
what was expected.  The exact mechanics checks at the end (axial stretch, pure bending) compare
against closed-form strip solutions: u = F L / (E h w) and the bent circle of radius EI / M.
"""
import copy
import math
import re
import warnings

import meshio
import numpy as np
import pytest

from core_se3 import scenario
from core_se3.errors import ConvergenceError, ScenarioError

BASE = {
    "name": "strip",
    "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
    "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1},
    "supports": [{"type": "clamp", "edge": "x0"}],
    "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
    "probes": [{"name": "tip", "edge": "x1"}],
    "solver": {"steps": 2},
}


def base():
    return copy.deepcopy(BASE)


def load_text(tmp_path, text, name="s.toml"):
    p = tmp_path / name
    p.write_text(text)
    return scenario.load(p)


def load_doc(tmp_path, doc):
    return load_text(tmp_path, scenario.dumps(doc))


def bad(tmp_path, doc, key, *fragments):
    """The scenario must fail validation naming the file, ``key`` and every fragment."""
    with pytest.raises(ScenarioError) as ei:
        load_doc(tmp_path, doc)
    e = ei.value
    assert e.file.endswith("s.toml"), e.file
    assert e.key == key, (e.key, str(e))
    assert str(e).startswith(str(tmp_path / "s.toml") + f": [{key}]: ") if key else True
    for f in fragments:
        assert f in str(e), (f, str(e))
    return e


# ----------------------------------------------------------------------------- valid input
def test_valid_scenario_defaults_and_problem(tmp_path):
    scn = load_doc(tmp_path, base())
    assert scn.name == "strip"
    assert scn.solver["steps"] == 2 and scn.solver["rtol"] == 1e-10 and scn.solver["element"] == "default"
    assert scn.spec["loads"][0]["scale"] == "linear" and scn.spec["loads"][0]["follower"] is False
    assert scn.output == dict(dir=None, vtu=True, vtu_every=1, plots=True, picture=True, picture_steps=1,
                              view=None)
    assert scn.mesh.n_elements == 4 and set(scn.problem.probes) == {"tip"}
    assert scn.load_factors() == [0.5, 1.0]
    assert len(scn.problem.loads) == 1 and len(scn.problem.supports) == 1


def test_dumps_roundtrip_and_fingerprint(tmp_path):
    d = base()
    d["loads"][0]["scale"] = [[0.0, 0.0], [0.5, 1.0], [1.0, 1.0]]
    d["edges"] = {"mid": {"box": {"x": [5.0, 5.0]}}}
    a = load_doc(tmp_path, d)
    from core_se3.scenario.spec import tomllib
    assert tomllib.loads(scenario.dumps(d)) == d
    # solver tolerances and outputs do not change the fingerprint; physics does
    d2 = copy.deepcopy(d)
    d2["solver"].update(rtol=1e-8, max_iter=5)
    d2["output"] = {"vtu": False}
    assert load_doc(tmp_path, d2).fingerprint == a.fingerprint
    d3 = copy.deepcopy(d)
    d3["material"]["E"] = 1.3e6
    assert load_doc(tmp_path, d3).fingerprint != a.fingerprint
    # the user node set 'mid' (box x = 5) is ordered along the line
    assert a.mesh.edges["mid"].tolist() == [2, 7]


def test_dumps_writes_numpy_scalars_as_plain_toml():
    from core_se3.scenario.spec import tomllib
    doc = {"a": np.float64(0.5), "b": np.int64(3), "c": [np.float32(0.25), np.bool_(True)]}
    assert tomllib.loads(scenario.dumps(doc)) == {"a": 0.5, "b": 3, "c": [0.25, True]}


def test_dumps_writes_unicode_names_tomllib_reads(tmp_path):
    """Region and probe names beyond ASCII (a Gmsh group 'région', 'k²') were written as bare
    keys, and characters beyond U+FFFF (an emoji in the name) as JSON's surrogate pairs
    '\\ud83d\\ude00': tomllib refused both ("Expected ']' at the end of a table declaration",
    "not a Unicode scalar value"), so e.g. a design's optimised.toml could not be read back."""
    from core_se3.scenario.spec import tomllib
    d = base()
    d["name"] = "gripper 😀 v2"
    d["regions"] = {"région": {"box": {"x": [0.0, 5.0]}}, "k²": {"box": {"x": [5.0, 10.0]}}}
    d["material"]["regions"] = {"région": {"E": 2.4e6}}
    d["probes"][0]["name"] = "tête\x7f"
    text = scenario.dumps(d)
    assert tomllib.loads(text) == d
    scn = load_text(tmp_path, text)
    assert scn.name == "gripper 😀 v2" and sorted(scn.regions) == ["k²", "région"] and set(scn.problem.probes) == {"tête\x7f"}


def test_load_number_messages_do_not_read_as_the_value_of_D(tmp_path):
    """'F L^2/(D w) + M L/(D w), D = E h^3/12 = 8e+05' read as D = 8e+05 (it is 8.3e-5 for E = 1,
    h = 0.1; 8e+05 is the load number): the definition of D is now in parentheses."""
    d = base()
    d["material"]["E"] = 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scn = load_doc(tmp_path, d)
    n = scn.load_numbers()[0]
    assert n["formula"] == "F L^2/(D w) + M L/(D w) (D = E h^3/12)"
    assert any(f"(D = E h^3/12) = {n['value'] / 2:.3g} in the first step" in str(w) for w in scn.warnings)


def test_scale_tables():
    f = scenario.make_scale([[0.0, 0.0], [0.5, 1.0], [1.0, 1.0]])
    assert [f(x) for x in (0.0, 0.25, 0.5, 0.9, 2.0)] == [0.0, 0.5, 1.0, 1.0, 1.0]
    assert scenario.make_scale("constant")(0.3) == 1.0 and scenario.make_scale("linear")(0.3) == 0.3


# ----------------------------------------------------------------------------- bad input: one test per kind
def test_bad_toml_syntax(tmp_path):
    with pytest.raises(ScenarioError, match=r"s.toml: not valid TOML: .*line 2"):
        load_text(tmp_path, 'name = "x"\n[mesh\n')


def test_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="cannot read the scenario file"):
        scenario.load(tmp_path / "nope.toml")


def test_unknown_key_with_suggestion(tmp_path):
    d = base()
    d["material"]["thickness"] = 0.1
    bad(tmp_path, d, "material.thickness", "unknown key 'thickness'", "allowed here: E, nu, h")
    d = base()
    d["solver"]["setps"] = 3
    bad(tmp_path, d, "solver.setps", "did you mean 'steps'?")


def test_unknown_top_level_table(tmp_path):
    d = base()
    d["load"] = [{"type": "gravity"}]
    bad(tmp_path, d, "load", "unknown key 'load'", "did you mean 'loads'?")


def test_wrong_type(tmp_path):
    d = base()
    d["material"]["E"] = "steel"
    bad(tmp_path, d, "material.E", "expected a number, got a string 'steel'")
    d = base()
    d["mesh"]["nx"] = 4.5
    bad(tmp_path, d, "mesh.nx", "expected an integer, got a number 4.5")
    d = base()
    d["loads"][0]["follower"] = 1
    bad(tmp_path, d, "loads[0].follower", "expected true or false, got an integer 1")


def test_missing_required(tmp_path):
    d = base()
    del d["material"]["h"]
    bad(tmp_path, d, "material.h", "missing required key")
    d = base()
    del d["mesh"]
    bad(tmp_path, d, "mesh", "missing required key")


def test_negative_thickness(tmp_path):
    d = base()
    d["material"]["h"] = -0.1
    bad(tmp_path, d, "material.h", "expected a number > 0, got -0.1")


def test_poisson_ratio_at_least_half(tmp_path):
    d = base()
    d["material"]["nu"] = 0.5
    bad(tmp_path, d, "material.nu", "expected a number < 0.5, got 0.5")


def test_nonpositive_modulus(tmp_path):
    d = base()
    d["material"]["E"] = 0
    bad(tmp_path, d, "material.E", "expected a number > 0, got 0")


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_nan_and_infinite_values(tmp_path, value):
    d = base()
    d["loads"][0]["force"] = [0.0, value, 1.0]
    bad(tmp_path, d, "loads[0].force", "expected finite numbers")
    d = base()
    d["mesh"]["L"] = value
    bad(tmp_path, d, "mesh.L", "expected a finite number")


def test_unknown_edge(tmp_path):
    d = base()
    d["supports"][0]["edge"] = "x00"
    bad(tmp_path, d, "supports[0].edge", "unknown edge 'x00'", "did you mean 'x0'?", "x0, x1, y0, y1")
    d = base()
    d["probes"][0]["edge"] = "tip"
    bad(tmp_path, d, "probes[0].edge", "unknown edge 'tip'")


def test_unknown_region(tmp_path):
    d = base()
    d["loads"].append({"type": "pressure", "p": 1.0, "region": "skin"})
    bad(tmp_path, d, "loads[1].region", "unknown region 'skin'", "defined regions: none")


def test_no_supports(tmp_path):
    d = base()
    del d["supports"]
    bad(tmp_path, d, "supports", "no supports", "rigid body")


def test_insufficient_supports_name_the_free_motion(tmp_path):
    d = base()
    d["supports"] = [{"type": "fix", "edge": "x0", "dofs": [0, 1, 2]}]
    bad(tmp_path, d, "supports", "leave a rigid-body motion free", "rotation about")


def test_wrong_vector_length(tmp_path):
    d = base()
    d["loads"][0]["force"] = [0.0, 1.0]
    bad(tmp_path, d, "loads[0].force", "expected an array of 3 numbers")


def test_unknown_choice(tmp_path):
    d = base()
    d["mesh"]["generator"] = "rectangel"
    bad(tmp_path, d, "mesh.generator", "unknown value 'rectangel'", "did you mean 'rectangle'?")
    d = base()
    d["loads"][0]["type"] = "force"
    bad(tmp_path, d, "loads[0].type", "unknown value 'force'", "'edge_force'")


def test_mesh_generator_and_file_both_or_neither(tmp_path):
    d = base()
    d["mesh"]["file"] = "m.msh"
    bad(tmp_path, d, "mesh", "exactly one of 'generator'")


def test_element_count_and_limits(tmp_path):
    d = base()
    d["mesh"]["nx"] = 0
    bad(tmp_path, d, "mesh.nx", "expected an integer >= 1, got 0")
    d = base()
    d["solver"]["steps"] = 0
    bad(tmp_path, d, "solver.steps", "expected an integer >= 1")
    d = base()
    d["mesh"].update(nx=2000, ny=2000)
    bad(tmp_path, d, "mesh", "exceed the limit")


def test_fix_dofs_out_of_range(tmp_path):
    d = base()
    d["supports"].append({"type": "fix", "edge": "x1", "dofs": [2, 6]})
    bad(tmp_path, d, "supports[1].dofs", "dof numbers 0..5")


def test_zero_rotation_axis(tmp_path):
    d = base()
    d["supports"].append({"type": "rotate", "edge": "x1", "axis": [0.0, 0.0, 0.0], "angle": 1.0})
    bad(tmp_path, d, "supports[1].axis", "non-zero vector")


def test_bad_scale_table(tmp_path):
    d = base()
    d["loads"][0]["scale"] = [[0.0, 0.0], [0.5, 1.0], [0.5, 2.0]]
    bad(tmp_path, d, "loads[0].scale", "must increase strictly")
    d["loads"][0]["scale"] = "quadratic"
    bad(tmp_path, d, "loads[0].scale", "unknown value 'quadratic'")


def test_overlapping_material_regions(tmp_path):
    d = base()
    d["regions"] = {"a": {"box": {"x": [0.0, 7.0]}}, "b": {"box": {"x": [3.0, 10.0]}}}
    d["material"]["regions"] = {"a": {"E": 2e6}, "b": {"E": 3e6}}
    bad(tmp_path, d, "material.regions.b", "overlap")


def _two_materials(load):
    d = base()
    d["mesh"]["nx"] = 8
    d["regions"] = {"tip": {"box": {"x": [5.0, 10.0]}}}               # elements in x = 5 .. 10
    d["material"]["regions"] = {"tip": {"E": 2.4e6, "h": 0.08}}
    d["loads"] = [load]
    return d


def test_per_region_material_stretch_exact(tmp_path):
    """Two materials in series: u = F/w (L1/(E1 h1) + L2/(E2 h2)) (exact, constant strains)."""
    scn = load_doc(tmp_path, _two_materials({"type": "edge_force", "edge": "x1", "force": [100.0, 0, 0]}))
    u = scn.problem.solve(steps=1).final.probes["tip"]["u"]
    np.testing.assert_allclose(u[0], 100.0 * (5.0 / (1.2e6 * 0.1) + 5.0 / (2.4e6 * 0.08)), rtol=1e-10)


def test_per_region_material_bending_exact(tmp_path):
    """End moment M on a strip of two materials (nu = 0): curvatures M/(w D_i), D_i = E_i h_i^3/12,
    so the tip turns by M (L1/D1 + L2/D2) / w (pure bending is exact on any mesh)."""
    M = 2.0
    scn = load_doc(tmp_path, _two_materials({"type": "edge_moment", "edge": "x1", "moment": [0, -M, 0]}))
    tip = scn.problem.solve(steps=2).final.probes["tip"]
    D1, D2 = 1.2e6 * 0.1 ** 3 / 12, 2.4e6 * 0.08 ** 3 / 12
    np.testing.assert_allclose(-tip["w"][1], M * (5.0 / D1 + 5.0 / D2), rtol=1e-9)
    from core_se3.fem import element_resultants
    f = element_resultants(scn.problem.element, scn.problem.solve(steps=2).final.g)
    np.testing.assert_allclose(f["M1"][:, 1], -M, rtol=1e-8)          # the same moment in both


def test_per_region_gravity_uses_each_region_density_and_thickness(tmp_path):
    d = _two_materials({"type": "gravity", "g": [0.0, 0.0, -10.0]})
    d["units"] = "SI"
    d["material"]["rho"] = 2.0
    d["material"]["regions"]["tip"]["rho"] = 3.0
    scn = load_doc(tmp_path, d)
    f, _, _ = scn.problem.external(scn.mesh.g0, 1.0, tangent=False)
    np.testing.assert_allclose(f[:, 2].sum(), -10.0 * (2.0 * 0.1 * 5.0 + 3.0 * 0.08 * 5.0), rtol=1e-12)


def test_per_region_magnetisation_uses_each_region_thickness(tmp_path):
    """A magnet over two regions of different thickness: total dipole moment
    int h Br dA / mu0 = Br (h1 A1 + h2 A2) / mu0, split into one load per thickness."""
    d = _two_materials({"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 0.1]})
    d["fields"] = {"f": {"type": "uniform", "B": [0.0, 0.0, 1e-3]}}
    d["magnets"] = [{"Br": [0.1, 0.0, 0.0]}]
    d["units"] = "SI"
    scn = load_doc(tmp_path, d)
    mags = [ld.mag for ld in scn.problem.loads if hasattr(ld, "mag")]
    assert sorted(m.h for m in mags) == [0.08, 0.1]
    total = sum(m.total_lab for m in mags)
    np.testing.assert_allclose(total, [0.1 * (0.1 * 5.0 + 0.08 * 5.0), 0, 0], rtol=1e-12)


def test_region_selecting_nothing(tmp_path):
    d = base()
    d["regions"] = {"far": {"box": {"x": [50.0, 60.0]}}}
    bad(tmp_path, d, "regions.far", "selects no elements")


def test_gravity_without_density(tmp_path):
    d = base()
    d["loads"].append({"type": "gravity"})
    bad(tmp_path, d, "loads[1].rho", "gravity needs a density")


def test_magnet_without_field(tmp_path):
    d = base()
    d["magnets"] = [{"Br": [0.1, 0.0, 0.0]}]
    bad(tmp_path, d, "magnets[0]", "needs an applied field")
    d["fields"] = {"a": {"type": "uniform", "B": [0, 0, 0.01]}}
    d["magnets"] = [{"Br": [0.1, 0.0, 0.0], "field": "b"}]
    bad(tmp_path, d, "magnets[0].field", "unknown value 'b'")


def test_duplicate_probe_name(tmp_path):
    d = base()
    d["probes"].append({"name": "tip", "edge": "x0"})
    bad(tmp_path, d, "probes[1].name", "must be unique")


def test_a_dof_listed_twice_is_refused_not_merged(tmp_path):
    """dofs = [0, 0] held one dof where two were likely meant ([0, 1]); before, the list was
    sorted into a set and the run went on; now refused, naming the key and the repeat; a lab
    axis twice in a rigid motion's ``free`` likewise."""
    d = base()
    d["supports"].append({"type": "fix", "edge": "x1", "dofs": [0, 0]})
    bad(tmp_path, d, "supports[1].dofs", "lists [0] more than once", "was another meant?")
    d["supports"][1] = {"type": "rotate", "edge": "x1", "axis": [1, 0, 0], "angle": 0.1, "free": ["x", "x"]}
    bad(tmp_path, d, "supports[1].free", "lists ['x'] more than once")


def test_node_ids_that_do_not_exist(tmp_path):
    d = base()
    d["supports"][0] = {"type": "clamp", "nodes": [0, 99]}
    bad(tmp_path, d, "supports[0].nodes", "ids [99] do not exist", "0 .. 9")


def test_edge_load_on_a_set_that_is_not_a_line(tmp_path):
    d = base()
    d["edges"] = {"corners": {"nodes": [0, 9]}}
    d["loads"][0]["edge"] = "corners"
    bad(tmp_path, d, "loads[0].edge", "no element edge of the set joins")


def test_arclength_controls_need_arclength_and_no_prescribed_rotation(tmp_path):
    d = base()
    d["solver"]["dlam0"] = 0.1
    bad(tmp_path, d, "solver.dlam0", 'only with control = "arclength"')
    d["solver"]["control"] = "arclength"
    d["supports"].append({"type": "rotate", "edge": "x1", "axis": [1.0, 0.0, 0.0], "angle": 0.1})
    bad(tmp_path, d, "supports[1].type", "arc length scales the loads only")
    d = base()
    d["solver"].update(control="arclength", dlam0=-0.1)
    bad(tmp_path, d, "solver.dlam0", "of the sign of lam_end")


def test_table_expected(tmp_path):
    d = base()
    d["supports"] = {"type": "clamp", "edge": "x0"}
    bad(tmp_path, d, "supports", "expected an array of tables ([[supports]])")


# ----------------------------------------------------------------------------- mesh files
def _write_quads(path, X, quads, **kw):
    meshio.write(path, meshio.Mesh(np.asarray(X, float), [("quad", np.asarray(quads))], **kw))


def _file_doc(fname):
    d = base()
    d["mesh"] = {"file": fname}
    d["supports"] = [{"type": "clamp", "nodes": [0, 3]}]
    d["loads"] = [{"type": "nodal", "nodes": [2], "force": [0.0, 0.0, 1.0]}]
    d["probes"] = []
    return d


def test_mesh_file_of_a_dome_without_d1_hint_takes_its_edges(tmp_path):
    """[mesh] file without d1_hint: a doubly curved part takes d1 along the mesh's edges (the
    reader's default: a lat-long dome's parallels or meridians; before, the projection of +x,
    which locked thin domes), and a given d1_hint is projected as before."""
    from core_se3.mesh import from_meshio
    lat, lon = np.meshgrid(np.linspace(0.0, 1.2, 4), np.linspace(0.0, 2 * np.pi, 13)[:-1], indexing="ij")
    X = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], -1).reshape(-1, 3)
    i = np.arange(48).reshape(4, 12)
    q = np.stack([i[:-1], np.roll(i, -1, 1)[:-1], np.roll(i, -1, 1)[1:], i[1:]], -1).reshape(-1, 4)
    _write_quads(tmp_path / "dome.vtu", X, q)
    par = np.stack([-np.sin(lon), np.cos(lon), 0 * lon], -1).reshape(-1, 3)
    for hint, along in ((None, True), ([1.0, 0.0, 0.0], False)):
        d = _file_doc("dome.vtu")
        if hint is not None:
            d["mesh"]["d1_hint"] = hint
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scn = load_doc(tmp_path, d)
            direct = from_meshio(str(tmp_path / "dome.vtu"), d1_hint=hint)
        cos = np.abs(np.einsum("ni,ni->n", scn.mesh.g0[:, :3, 0], par))
        assert np.array_equal(scn.mesh.g0, direct.g0)
        assert (np.minimum(1.0 - cos, cos).max() < 1e-12) == along
        assert ("d1_hint" in scn.spec["mesh"]) == (hint is not None)


def test_mesh_file_ok(tmp_path):
    X = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]]
    _write_quads(tmp_path / "m.vtu", X, [[0, 1, 4, 3], [1, 2, 5, 4]])
    scn = load_doc(tmp_path, _file_doc("m.vtu"))
    assert scn.mesh.n_elements == 2 and scn.spec["mesh"] == {"file": "m.vtu"}      # no d1_hint: none kept


def test_mesh_file_node_ids_after_a_dropped_point_are_named(tmp_path):
    """A file whose point 0 no quad uses (a Gmsh circle's centre, saved without physical groups):
    the reader drops it and renumbers the rest, so nodes = [2] selects the file's point 3, at
    (2, 0, 0), not its point 2 at (1, 0, 0) -- silently.  Now a warning at every key that selects
    by id names the shift (strict: an error); without dropped points, or with ids before the
    first dropped point, nothing is said."""
    X = [[9, 9, 0], [0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]]
    _write_quads(tmp_path / "m.vtu", X, [[1, 2, 5, 4], [2, 3, 6, 5]])
    d = _file_doc("m.vtu")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scn = load_doc(tmp_path, d)
    assert re.search(r"\[loads\[0\].nodes\]: node ids count the mesh's nodes.*1 point\(s\) that no quad uses "
                     r"\(point 0\).*node 2 is the file's point 3, at \(2, 0, 0\)", str(caught[-1].message))
    assert scn.mesh.X[2].tolist() == [2.0, 0.0, 0.0]
    assert [w.split(": ")[1] for w in map(str, scn.warnings) if "node ids" in w] == \
        ["[supports[0].nodes]", "[loads[0].nodes]"]
    with pytest.raises(ScenarioError, match=r"\[supports\[0\].nodes\]: node ids count"):
        scenario.load(tmp_path / "s.toml", strict=True)
    X[0] = [2, 2, 0]                                     # the unused point last: no renumbering
    _write_quads(tmp_path / "m.vtu", X[1:] + [X[0]], [[0, 1, 4, 3], [1, 2, 5, 4]])
    assert not [w for w in load_doc(tmp_path, d).warnings if "node ids" in str(w)]


def test_mesh_file_point_sets_are_node_sets(tmp_path):
    """An Abaqus .inp's node sets (*NSET: meshio point_sets) were dropped -- a scenario's clamp on
    'clamped' was 'unknown edge ...; the mesh has: no named edges'.  Now they are node sets, and the
    cantilever on the file is the generator's (the same quads): tip lift equal to round-off."""
    from core_se3 import mesh as M
    ref = M.rectangle(10.0, 1.0, 6, 1)
    meshio.write(tmp_path / "strip.inp", meshio.Mesh(ref.X, [("quad", ref.quads)], point_sets={
        "clamped": ref.edges["x0"], "tip": ref.edges["x1"], "off": np.array([0])}))
    d = base()
    d["mesh"] = {"file": "strip.inp"}
    d["supports"][0]["edge"], d["loads"][0]["edge"], d["probes"][0]["edge"] = "clamped", "tip", "tip"
    scn = load_doc(tmp_path, d)
    assert sorted(scn.mesh.edges) == ["clamped", "off", "tip"] and scn.mesh.edges["tip"].tolist() == sorted(ref.edges["x1"])
    d2 = base()
    d2["mesh"] = {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 6, "ny": 1}
    a, b = (s.problem.solve().final.probes["tip"]["u"] for s in (scn, load_doc(tmp_path, d2)))
    assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max() and abs(b[2]) > 0.1


def test_mesh_file_missing(tmp_path):
    bad(tmp_path, _file_doc("missing.msh"), "mesh.file", "does not exist")


def test_mesh_file_unreadable(tmp_path):
    (tmp_path / "junk.msh").write_text("this is not a mesh\n")
    bad(tmp_path, _file_doc("junk.msh"), "mesh.file", "cannot read mesh file 'junk.msh'")


def test_mesh_file_degenerate_quad(tmp_path):
    X = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 0, 0], [2, 1, 0]]   # node 4 on node 1
    _write_quads(tmp_path / "m.vtu", X, [[0, 1, 4, 3], [1, 2, 5, 4]])
    bad(tmp_path, _file_doc("m.vtu"), "mesh.file", "bad mesh 'm.vtu'", "degenerate")


def test_mesh_file_nonconvex_quad(tmp_path):
    X = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [0.3, 0.3, 0], [2, 1, 0]]  # re-entrant corner
    _write_quads(tmp_path / "m.vtu", X, [[0, 1, 4, 3], [1, 2, 5, 4]])
    bad(tmp_path, _file_doc("m.vtu"), "mesh.file", "non-convex")


def test_mesh_file_flipped_normals(tmp_path):
    X = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]]
    _write_quads(tmp_path / "m.vtu", X, [[0, 1, 4, 3], [1, 4, 5, 2]])      # second quad clockwise
    bad(tmp_path, _file_doc("m.vtu"), "mesh.file", "run along their shared edge (1, 4) the same way", "normals flip there", "reverse their node order")


def test_mesh_file_with_triangles(tmp_path):
    X = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    meshio.write(tmp_path / "t.vtu", meshio.Mesh(np.array(X, float), [("triangle", np.array([[0, 1, 2]]))]))
    bad(tmp_path, _file_doc("t.vtu"), "mesh.file", "only quadrilateral shells")


def test_gmsh_file_named_regions_and_lines(tmp_path):
    """Physical curves become edges, physical surfaces regions (Gmsh 2.2 written by meshio)."""
    X = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], float)
    cells = [("line", np.array([[0, 3]])), ("line", np.array([[2, 5]])),
             ("quad", np.array([[0, 1, 4, 3]])), ("quad", np.array([[1, 2, 5, 4]]))]
    phys = [np.array([1]), np.array([2]), np.array([3]), np.array([4])]
    m = meshio.Mesh(X, cells, cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                    field_data={"root": np.array([1, 1]), "tip": np.array([2, 1]),
                                "base": np.array([3, 2]), "pad": np.array([4, 2])})
    meshio.write(tmp_path / "m.msh", m, file_format="gmsh22", binary=False)
    d = _file_doc("m.msh")
    d["supports"] = [{"type": "clamp", "edge": "root"}]
    d["loads"] = [{"type": "edge_force", "edge": "tip", "force": [0.0, 0.0, 1.0]},
                  {"type": "pressure", "p": 1.0, "region": "pad"}]
    scn = load_doc(tmp_path, d)
    assert sorted(scn.mesh.edges) == ["root", "tip"]
    assert scn.regions["pad"].tolist() == [1] and scn.regions["base"].tolist() == [0]
    assert sorted(scn.mesh.X[scn.mesh.edges["tip"], 0]) == [2.0, 2.0]


# ----------------------------------------------------------------------------- exact mechanics
def test_scenario_problem_axial_stretch_exact(tmp_path):
    """Strip under an end force along its axis: u = F L / (E h w) (exact for nu = 0)."""
    d = base()
    d["loads"][0]["force"] = [1000.0, 0.0, 0.0]
    scn = load_doc(tmp_path, d)
    res = scn.problem.solve(steps=1)
    np.testing.assert_allclose(res.final.probes["tip"]["u"][0], 1000.0 * 10.0 / (1.2e6 * 0.1 * 1.0),
                               rtol=1e-10)


def test_resultants_exact_stretch_and_bending(tmp_path):
    """Stress resultants at element centres: N1 = F/w along the axis for an end force F;
    M1 = M/w for an end moment M (the bent circle has constant moment)."""
    from core_se3.fem import element_resultants
    d = base()
    d["mesh"]["ny"] = 2
    d["loads"][0]["force"] = [1000.0, 0.0, 0.0]
    scn = load_doc(tmp_path, d)
    g = scn.problem.solve(steps=1).final.g
    f = element_resultants(scn.problem.element, g)
    np.testing.assert_allclose(f["N1"], np.tile([1000.0, 0, 0], (8, 1)), atol=1e-8)
    np.testing.assert_allclose(f["N2"], 0.0, atol=1e-8)
    d["loads"][0] = {"type": "edge_moment", "edge": "x1", "moment": [0.0, -10.0, 0.0]}
    scn = load_doc(tmp_path, d)
    res = scn.problem.solve(steps=2)
    f = element_resultants(scn.problem.element, res.final.g)
    np.testing.assert_allclose(f["M1"], np.tile([0.0, -10.0, 0.0], (8, 1)), atol=1e-8)
    np.testing.assert_allclose(f["M1_local"], np.tile([0.0, -10.0, 0.0], (8, 1)), atol=1e-8)
    np.testing.assert_allclose(f["N1"], 0.0, atol=1e-7)
    # the strip bends into a circle of radius EI/M = 10: tip at (R sin 1, 0, R (1 - cos 1))
    R = 1.2e6 * 1.0 * 0.1 ** 3 / 12 / 10.0
    np.testing.assert_allclose(res.final.probes["tip"]["u"],
                               [R * np.sin(1.0) - 10.0, 0.0, R * (1 - np.cos(1.0))], atol=1e-9)


def test_resultants_converge_to_cantilever_equilibrium_at_second_order(tmp_path):
    """Large-deflection cantilever, dead tip force P: the moment on the cut through the centre of
    the middle element must equal (phi_tip - phi_c) x P (statics of the outer part); the error of
    the element-centre resultant falls ~4x per mesh halving (measured 0.28 %, 0.068 %)."""
    from core_se3.fem import element_resultants
    errs = []
    for nx in (6, 12):
        d = base()
        d["mesh"]["nx"] = nx
        d["loads"][0]["force"] = [0.0, 0.0, 2.0]
        scn = load_doc(tmp_path, d)
        g = scn.problem.solve(steps=3).final.g
        f = element_resultants(scn.problem.element, g)
        e = nx // 2
        c = g[scn.mesh.quads[e], :3, 3].mean(0)
        exact = np.cross(g[scn.mesh.edges["x1"], :3, 3].mean(0) - c, [0.0, 0.0, 2.0])
        errs.append(np.linalg.norm(f["M1"][e] - exact) / np.linalg.norm(exact))
    assert errs[0] < 4e-3 and errs[1] < errs[0] / 3.5, errs


def test_explicit_load_factors(tmp_path):
    """[solver] load_factors = [...] gives the steps' load factors directly (replacing steps and
    lam_end); bad lists are refused naming the key.  Since issue 18 the load factors are not part
    of the fingerprint (a finished run may be extended); ``--resume`` checks instead that the
    steps done are the first of the new ones (tests/test_frontdoor.py)."""
    d = base()
    d["solver"] = {"load_factors": [0.1, 0.25, 0.6, 1.0]}
    scn = load_doc(tmp_path, d)
    assert scn.load_factors() == [0.1, 0.25, 0.6, 1.0]
    assert scn.solver["steps"] == 4 and scn.solver["lam_end"] == 1.0
    d2 = base()
    d2["solver"] = {"load_factors": [0.1, 0.25, 0.7, 1.0]}
    assert load_doc(tmp_path, d2).fingerprint == scn.fingerprint
    d = base()
    d["solver"] = {"load_factors": [-0.5, -1.0]}                 # unloading direction is fine
    assert load_doc(tmp_path, d).load_factors() == [-0.5, -1.0]
    for lf, frag in (([0.5, 0.5, 1.0], "strictly in one direction"), ([0.5, 0.2], "no reversals"),
                     ([0.0, 1.0], "strictly"), ([], "non-empty array"), ([0.5, "1"], "array of numbers")):
        d = base()
        d["solver"] = {"load_factors": lf}
        bad(tmp_path, d, "solver.load_factors", frag)
    d = base()
    d["solver"] = {"load_factors": [0.5, 1.0], "steps": 2}
    bad(tmp_path, d, "solver.steps", "either load_factors or steps and lam_end")
    d = base()
    d["solver"] = {"control": "arclength", "load_factors": [0.5, 1.0]}
    bad(tmp_path, d, "solver.load_factors", 'control = "load"')


def test_a_shell_thinner_than_h_over_L_1e_4_warns_of_a_unit_slip(tmp_path):
    """A thickness in m with lengths in mm (1000 times too thin) was silent whenever no load number
    flagged it (a prescribed rotation, or a load scaled by the same slip): the strip of span 10
    with h = 1e-4 (h/L 2e-5) said nothing.  Now a warning at material.h (and a region's h) naming
    the ratio and the slip; h/L = 1e-4 itself (the package's thin benchmarks) stays silent, and
    --strict makes it an error.  Both ends held: L = 5, the largest distance to a support."""
    d = base()
    d["units"] = "N-mm-MPa"
    d["material"]["E"] = 1.2
    d["loads"] = []
    d["supports"].append({"type": "rotate", "edge": "x1", "axis": [0.0, 1.0, 0.0], "angle": 0.5})
    d["material"]["h"] = 1e-4
    said = [str(w) for w in load_doc(tmp_path, d).warnings]
    assert any("[material.h]: h / L = 0.0001 / 5 = 2e-05 (L/h = 5e+04) < 0.0001" in w and "h is in mm" in w
               and "1000 times too thin" in w for w in said), said
    d["material"]["h"] = 5e-4                                          # h/L = 1e-4: silent
    assert not [w for w in load_doc(tmp_path, d).warnings if "h / L" in str(w)]
    d["regions"] = {"tip": {"box": {"x": [5.0, 10.0]}}}
    d["material"]["regions"] = {"tip": {"h": 1e-6}}
    said = [str(w) for w in load_doc(tmp_path, d).warnings]
    assert [w for w in said if "h / L" in w][0].split(": ")[1] == "[material.regions.tip.h]", said
    (tmp_path / "t.toml").write_text(scenario.dumps(d))
    with pytest.raises(ScenarioError, match=r"\[material.regions.tip.h\].*with --strict"):
        scenario.load(tmp_path / "t.toml", strict=True)


@pytest.mark.parametrize("tol", [None, 0.05])
def test_critical_tol_applies_to_load_control(tmp_path, tol):
    """[solver] critical_tol, the accuracy to which load control's limit_check locates a critical
    point (its documented `limit_check` key says so; NewtonOptions.critical_tol), is read under
    control = "load": the strip compressed by 4 (the 6-element bifurcation at load factor 0.6203) in 2 steps
    stops at the bifurcation with a bracket of relative width <= critical_tol -- 7.9e-4 at the
    default 1e-3, 0.05 (0.594 .. 0.625) at 0.05.  Before, the file's critical_tol was refused
    ('an arc-length control: only with control = "arclength"') and load control kept 1e-3."""
    d = base()
    d["mesh"]["nx"] = 6
    d["loads"] = [{"type": "edge_force", "edge": "x1", "force": [-4.0, 0.0, 0.0]}]
    d["output"] = {"vtu": False, "plots": False, "picture": False}
    if tol is not None:
        d["solver"]["critical_tol"] = tol
    scn = load_doc(tmp_path, d)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ConvergenceError) as exc:
            scenario.run(scn, out=str(tmp_path / "out"))
    lo, hi = (float(x) for x in re.search(r"between load factors ([0-9.]+) and ([0-9.]+)", str(exc.value)).groups())
    width = (hi - lo) / hi
    want = tol or 1e-3
    assert lo < 0.6203 < hi and want / 2 < width <= want * (1 + 1e-6), (lo, hi)


@pytest.mark.parametrize("control", ["arclength", "linear"])
def test_a_load_control_switch_under_another_control_warns(tmp_path, control):
    """[solver] switches that only load control reads (max_cutbacks, inertia_check, ...) given
    with control = "arclength" or "linear" are not used: a warning names the key, and --strict
    refuses the file.  Before, `inertia_check = true` on an arc-length path (which counts its own
    pivots) or `max_cutbacks = 20` were accepted without a word."""
    d = base()
    d["solver"] = {"control": control, "max_cutbacks": 20, "inertia_check": True}
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        scn = load_doc(tmp_path, d)
    text = [str(w.message) for w in said]
    for key in ("solver.max_cutbacks", "solver.inertia_check"):
        assert any(f"[{key}]: a switch of load control" in t and f'control = "{control}"' in t for t in text), text
    assert sum("switch of load control" in str(w) for w in scn.warnings) == 2      # Scenario.warnings lists them
    with pytest.raises(ScenarioError, match=r"\[solver\.max_cutbacks\]"):
        scenario.from_dict(d, file="s.toml", strict=True)
    d["solver"] = {"control": "load", "max_cutbacks": 20, "inertia_check": True}
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        load_doc(tmp_path, d)
    assert not [w for w in said if "switch of load control" in str(w.message)]


def test_a_byte_order_mark_is_read_past(tmp_path):
    """Windows editors save a scenario, and spreadsheets a UTF-8 CSV, with a byte order mark
    (EF BB BF) first.  A scenario with one was refused ('not valid TOML: Invalid statement (at
    line 1, column 1)') and a Br_file table with one read its header as '\\ufeffelement' ('expected
    the header element,Brx,Bry,Brz ... its first row has 4 fields').  Both now read as without it:
    the same fingerprint, the same magnetisation."""
    d = base()
    d.update(units="SI", fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}},
             magnets=[{"Br_file": "br.csv"}])
    table = "element,Brx,Bry,Brz\n" + "".join(f"{e},0.{e + 1},0,0\n" for e in range(4))
    (tmp_path / "br.csv").write_bytes(table.encode())
    plain = load_doc(tmp_path, d)
    (tmp_path / "br.csv").write_bytes(b"\xef\xbb\xbf" + table.encode())
    marked = load_doc(tmp_path, d)
    mu = plain.problem.loads[-1].mag.mu
    assert np.ptp(mu[:, 0]) > 0 and np.array_equal(mu, marked.problem.loads[-1].mag.mu)
    src = (tmp_path / "s.toml").read_bytes()
    (tmp_path / "bom.toml").write_bytes(b"\xef\xbb\xbf" + src)
    assert scenario.load(tmp_path / "bom.toml").fingerprint == marked.fingerprint


def test_sweep_csv_writes_a_swept_vector_as_its_shortest_decimals(tmp_path):
    """sweep.csv wrote a swept vector [0, 0, 0.1] as '0;0;0.10000000000000001' (%.17g) while a
    swept number 0.1 read '0.1' (repr); both read back exactly, and now both are the shortest."""
    d = base()
    d["solver"] = {"steps": 1}
    d["output"] = {"plots": False}
    scenario.sweep(load_doc(tmp_path, d), {"loads[0].force": [[0.0, 0.0, 0.1]], "material.nu": [0.1]},
                   out=str(tmp_path / "sw"), plot=False)
    head, row = (tmp_path / "sw" / "sweep.csv").read_text().splitlines()[:2]
    cells = dict(zip(head.split(","), row.split(",")))
    assert cells["loads[0].force"] == "0.0;0.0;0.1" and cells["material.nu"] == "0.1", cells


@pytest.mark.parametrize("where,key", [("prescribed", "supports[1].rotate.angle"),
                                       ("motion", "obstacles[0].motion.angle"), ("box", "obstacles[0].rotation")])
def test_an_angle_in_degrees_warns_wherever_an_angle_is_given(tmp_path, where, key):
    """360 (degrees meant) as a prescribed support's rotate.angle or an obstacle's motion.angle is
    57.3 turns in radians, and [0, 0, 90] as a box's rotation vector 14.3 turns: each warns at its
    key, as a rotate support's angle and a field's rotate.angle did (docs/SCENARIOS.md); before,
    these three were accepted without a word.  The same keys at 3.0 rad say nothing."""
    def doc(angle):
        d = base()
        d["loads"] = [{"type": "pressure", "p": 0.001}]
        if where == "prescribed":
            d["supports"].append({"type": "prescribed", "edge": "x1",
                                  "rotate": {"axis": [1.0, 0.0, 0.0], "angle": angle}})
        else:
            ob = {"type": "box", "centre": [5.0, 0.0, -5.0], "half_sizes": [1.0, 1.0, 1.0]}
            ob.update({"motion": {"axis": [1.0, 0.0, 0.0], "angle": angle, "point": [5.0, 0.0, -5.0]}}
                      if where == "motion" else {"rotation": [0.0, 0.0, angle / 4]})
            d["obstacles"] = [ob]
        return d
    for angle, said in ((360.0, True), (3.0, False)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            load_doc(tmp_path, doc(angle))
        hits = [str(w.message) for w in caught if f"[{key}]" in str(w.message) and "radians" in str(w.message)]
        assert bool(hits) == said, (angle, [str(w.message)[:90] for w in caught])


@pytest.mark.parametrize("where,key,home", [
    ("top", "steps", "a key of [solver]"), ("top", "E", "a key of [material]"),
    ("solver", "units", "a top-level key: put it before the first [table] header"),
    ("solver", "vtu", "a key of [output]"), ("mesh", "rho", "a key of [material]"),
    ("material", "refine", "a key of [mesh]")])
def test_a_key_in_the_wrong_table_names_its_table(tmp_path, where, key, home):
    """A key written in another table -- most often a top-level key after a [table] header, which
    TOML makes part of that table -- is refused naming the table it belongs to.  Before, the
    suggestion was a near spelling of this table's keys or nothing: a top-level `steps = 4` read
    "unknown key 'steps'; did you mean 'sweep'?", `units = "SI"` after [solver] "unknown key
    'units'" alone."""
    d = base()
    value = {"steps": 4, "E": 1.0, "units": "SI", "vtu": False, "rho": 1.0, "refine": 1}[key]
    (d if where == "top" else d[where]).update({key: value})
    bad(tmp_path, d, key if where == "top" else f"{where}.{key}", f"unknown key {key!r}; it is {home}")
    d = base()
    d["material"]["shear_factr"] = 0.8                            # a misspelling still gets its near key
    bad(tmp_path, d, "material.shear_factr", "did you mean 'shear_factor'")


@pytest.mark.parametrize("E,h,key", [(1.2e6, 1e-300, "material.h"), (1.2e6, 1e-110, "material.h"),
                                     (1e-155, 0.1, "material.E"), (1e308, 100.0, "material.E")])
def test_a_stiffness_double_precision_cannot_hold_is_refused(tmp_path, E, h, key):
    """E and h whose membrane stiffness E h or bending stiffness E h^3/12 lies outside 1e-150 ..
    1e300 (units far off the problem's scale: it under- or overflows) are refused at their key,
    and by Material.  Before: h = 1e-300 and 1e-110 passed validation into a bare
    ZeroDivisionError (the load number's E h^3/12 = 0; in Python the solve called the shell
    unsupported, 'a rigid-body motion is not restrained'); E = 1e-155 loaded and failed with a
    singular tangent, E = 1e308 at h = 100 with a non-finite residual, after 12 cut-backs."""
    from core_se3 import Material
    from core_se3.errors import MaterialError
    d = base()
    d["material"].update(E=E, h=h)
    bad(tmp_path, d, key, "stiffness", "under- or overflows")
    with pytest.raises(MaterialError, match="stiffness"):
        Material(E, 0.0, h)


def test_a_load_or_rotation_that_the_run_never_reaches_warns(tmp_path):
    """A scale table whose ramp lies past lam_end ([[2, 0], [3, 1]] with lam_end = 1) is 0 at
    every step: the load does nothing -- the strip's tip stays at 0 -- and a field's rotate with
    start = 2 never turns it.  Each now warns at its key; before, both were accepted without a
    word.  The same keys within the run say nothing."""
    def said(d):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            scn = load_doc(tmp_path, d)
        return scn, [str(w.message) for w in caught]
    d = base()
    d["loads"][0]["scale"] = [[2.0, 0.0], [3.0, 1.0]]
    scn, text = said(d)
    assert any("[loads[0].scale]: the scale is 0 at every load factor of the run (0.5 .. 1)" in t for t in text)
    assert np.abs(scn.problem.solve().final.probes["tip"]["u"]).max() == 0.0       # it acts nowhere
    d["loads"][0]["scale"] = [[0.0, 0.0], [0.5, 1.0]]
    assert not [t for t in said(d)[1] if "scale is 0" in t]
    d = base()
    d.update(units="SI", fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.001],
                                       "rotate": {"axis": [0.0, 1.0, 0.0], "angle": 1.0, "start": 2.0, "end": 3.0}}},
             magnets=[{"Br": [0.1, 0.0, 0.0]}])
    assert any("[fields.c.rotate]: the field's rotation has not begun" in t for t in said(d)[1])
    d["fields"]["c"]["rotate"].update(start=0.5, end=1.0)
    assert not [t for t in said(d)[1] if "not begun" in t]

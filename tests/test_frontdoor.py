"""The user's front door (issue 18): one test per finding of the new user's day, and one test
per new kind of bad or implausible input (its own message, the key it names).

Findings: 1 Gmsh 4.1 files (also tests/test_gmsh_files.py), 2 units, 3 implausible values,
4 shapes and radial magnetisation, 5 physical loads in the outputs, 6 sweeps and extended or
refused resumes and interrupted runs, 7 suggestions for misspellings, 8 progress.
"""
import copy
import csv
import io
import json
import os
import warnings

import numpy as np
import pytest

from core_se3 import cli, mesh as M, scenario
from core_se3.errors import CheckpointError, MeshError, ScenarioError
from core_se3.scenario import runner

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLES = os.path.join(ROOT, "examples")
Br45 = 0.004808326112068524
STAR = {   # the four-arm star gripper of examples/star-gripper.toml on a coarse structured mesh
    "name": "star", "units": "N-mm-MPa",
    "mesh": {"generator": "star", "n_arms": 4, "arm_length": 20.0, "arm_width": 6.0, "size": 3.0,
             "backend": "structured"},
    "material": {"E": 0.4698783, "nu": 0.45, "h": 0.7},
    "supports": [{"type": "clamp", "region": "palm"}],
    "fields": {"coil": {"type": "uniform", "B": [0.0, 0.0, 0.06]}},
    "magnets": [{"region": "fingers", "direction": "radial", "Br": Br45, "Br_axial": -Br45}],
    "probes": [{"name": "tip_0", "edge": "tip_0"}],
    "solver": {"steps": 4},
    "output": {"vtu": False, "plots": False, "picture": False},
}
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
         "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 2},
         "output": {"vtu": False, "plots": False, "picture": False}}


MAGSTRIP = {**STRIP, "units": "N-mm-MPa", "material": {"E": 0.5, "nu": 0.45, "h": 0.5}, "loads": [],
            "fields": {"coil": {"type": "uniform", "B": [0.0, 0.0, 0.01]}}, "magnets": [{"Br": [0.01, 0.0, 0.0]}]}


def doc(base=STAR, **changes):
    d = copy.deepcopy(base)
    for k, v in changes.items():
        node = d
        parts = k.split("__")
        for p in parts[:-1]:
            node = node[int(p)] if isinstance(node, list) else node.setdefault(p, {})
        if v is None:
            node.pop(parts[-1], None)
        else:
            node[int(parts[-1]) if isinstance(node, list) else parts[-1]] = v
    return d


def load(d, tmp_path=None, strict=False, name="s.toml"):
    base_dir = str(tmp_path) if tmp_path is not None else "."
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kw = dict(strict=True) if strict else {}
        return scenario.from_dict(d, file=name, base_dir=base_dir, **kw)


def bad(d, key, *fragments, tmp_path=None):
    with pytest.raises(ScenarioError) as ei:
        load(d, tmp_path)
    assert ei.value.key == key, (ei.value.key, str(ei.value))
    for f in fragments:
        assert f in str(ei.value), (f, str(ei.value))
    return ei.value


def warns(d, key, *fragments, tmp_path=None):
    """The scenario loads with a warning at ``key`` (its message has every fragment), and
    strict=True makes it a ScenarioError at that key."""
    scn = load(d, tmp_path)
    hits = [w for w in scn.warnings if w.key == key]
    assert hits, [str(w) for w in scn.warnings]
    for f in fragments:
        assert f in str(hits[0]), (f, str(hits[0]))
    with pytest.raises(ScenarioError, match=r"an error with --strict") as ei:
        load(d, tmp_path, strict=True)
    assert ei.value.key == key
    return hits[0]


# ----------------------------------------------------------------------------- finding 1
def test_finding1_star_gripper_runs_from_its_gmsh_41_file(tmp_path):
    path = os.path.join(EXAMPLES, "star-gripper.msh")
    assert open(path).readline().strip() == "$MeshFormat" and open(path).readlines()[1].startswith("4.1")
    scn = scenario.load(os.path.join(EXAMPLES, "star-gripper.toml"))
    assert sorted(scn.regions)[:2] == ["finger_0", "finger_1"] and "tip_0" in scn.mesh.edges
    res = scn.with_overrides({"solver.steps": 3}).problem.solve()
    u0, u1 = res.final.probes["tip_0"]["u"], res.final.probes["tip_1"]["u"]
    assert u0[2] > 10 and abs(u0[2] - u1[2]) < 1e-3 * u0[2]         # the fingers close alike


# ----------------------------------------------------------------------------- finding 2
def test_finding2_a_magnetic_problem_without_units_is_an_error_naming_the_choices():
    e = bad(doc(MAGSTRIP, units=None), "units", "needs its unit system", 'units = "SI"', 'units = "N-mm-MPa"',
            'units = "consistent"')
    assert "magnets" in str(e)
    bad(doc(STRIP, units=None, loads=[{"type": "gravity", "rho": 1000.0}]), "units", "gravity")


def test_every_run_states_its_unit_system_first_and_its_load_numbers(tmp_path, capsys):
    path = tmp_path / "star.toml"
    path.write_text(scenario.dumps(STAR))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o"), "--check"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == ("star: units N-mm-MPa: length mm, force N, stress MPa, density t/mm^3, field T, "
                        "mu0 = 1.25664 (magnets)")
    assert lines[1].startswith("  load number magnets[0] (magnetic): 12 |Br| |Ba| L^2 / (mu0 E h^2) = ")


def test_magnetic_load_number_is_exact():
    """12 |Br| |Ba| L^2 / (mu0 E h^2) with L = the arm length (20 mm from the clamped palm)."""
    scn = load(STAR)
    n = scn.load_numbers()[0]
    Br = np.hypot(Br45, Br45)
    assert n["span"] == pytest.approx(20.0, rel=1e-12)
    assert n["value"] == pytest.approx(12 * Br * 0.06 * 400.0 / (4e-7 * np.pi * 1e6 * 0.4698783 * 0.49), rel=1e-12)


# ----------------------------------------------------------------------------- finding 3
def test_finding3_br_typed_in_mT_warns():
    warns(doc(MAGSTRIP, magnets=[{"Br": [100.0, 0.0, 0.0]}]), "magnets[0]", "|Br| = 100 T exceeds 2 T",
          "did you give mT?")


def test_finding3_modulus_in_Pa_in_a_mm_model_warns():
    warns(doc(MAGSTRIP, material__E=1e6), "material.E", "E = 1e+06 MPa = 1e+12 Pa is outside the range of real solids",
          "E is in MPa")


# ----------------------------------------------------------------------------- finding 4
def test_finding4_shapes_have_named_regions_and_exact_areas():
    def area(m):
        P = m.X[m.quads]
        return 0.5 * np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])[:, 2].sum()
    for backend in ["structured"] + (["gmsh"] if getattr(M, "gmsh_module", lambda: None)() else []):
        s = M.star(5, 20.0, 6.0, size=2.0, backend=backend)
        R = 3.0 / np.sin(np.pi / 5)
        assert area(s) == pytest.approx(5 * 20 * 6 + 2.5 * R ** 2 * np.sin(2 * np.pi / 5), rel=1e-12)
        assert sorted(s.regions) == ["finger_0", "finger_1", "finger_2", "finger_3", "finger_4", "fingers", "palm"]
        assert len(s.regions["fingers"]) == sum(len(s.regions[f"finger_{k}"]) for k in range(5))
        p = M.polygon(6, 10.0, size=2.0, backend=backend)
        assert area(p) == pytest.approx(3 * 100 * np.sin(np.pi / 3), rel=1e-12)
        a = M.annulus_sector(6.0, 12.0, 2.5, size=1.2, backend=backend)
        assert np.allclose(np.hypot(*a.X[a.edges["outer"], :2].T), 12.0, rtol=1e-12)
        r = M.rounded_rectangle(30.0, 16.0, 0.0, size=2.0, backend=backend)
        assert area(r) == pytest.approx(480.0, rel=1e-12) and sorted(r.edges) == ["boundary", "x0", "x1", "y0", "y1"]
        d = M.disk(10.0, size=2.0, backend=backend)
        assert np.allclose(np.linalg.norm(d.X[d.edges["rim"]], axis=1), 10.0, rtol=1e-12)


def test_finding4_radial_and_tangential_magnetisation_about_the_centre():
    """direction = "radial": each element carries Br e_r + Br_axial e_z, e_r from the centre to its
    centroid; the total moment int Br dV = h sum_e A_e Br_e exactly (and the tangential one,
    a x e_r, has the same magnitude per element)."""
    scn = load(STAR)
    m, el = scn.mesh, scn.regions["fingers"]
    P = m.X[m.quads[el]]
    A = 0.5 * np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])[:, 2]
    c = P.mean(1)
    er = c * [1, 1, 0] / np.linalg.norm(c[:, :2], axis=1)[:, None]
    expect = 0.7 * (A[:, None] * (Br45 * er + [0, 0, -Br45])).sum(0)
    total = sum(ld.mag.total_lab for ld in scn.problem.loads if hasattr(ld, "mag"))
    np.testing.assert_allclose(total, expect, rtol=0, atol=1e-15)
    tang = load(doc(magnets__0__direction="tangential"))
    et = np.cross([0, 0, 1.0], er)
    expect = 0.7 * (A[:, None] * (Br45 * et + [0, 0, -Br45])).sum(0)
    total = sum(ld.mag.total_lab for ld in tang.problem.loads if hasattr(ld, "mag"))
    np.testing.assert_allclose(total, expect, rtol=0, atol=1e-15)
    assert scn.problem.solve(steps=2).final.probes["tip_0"]["u"][2] > 5.0        # the fingers lift


def test_magnetisation_tables_per_element_and_per_node(tmp_path):
    scn = load(STAR)
    m = scn.mesh
    el = scn.regions["fingers"]
    c = m.X[m.quads[el]].mean(1)
    er = c / np.linalg.norm(c[:, :2], axis=1)[:, None] * [1, 1, 0]
    Br = Br45 * er + [0, 0, -Br45]
    with open(tmp_path / "el.csv", "w") as fh:
        fh.write("element,Brx,Bry,Brz\n" + "".join(f"{i},{float(b[0])!r},{float(b[1])!r},{float(b[2])!r}\n" for i, b in zip(el, Br)))
    table = load(doc(magnets=[{"region": "fingers", "Br_file": "el.csv"}]), tmp_path).problem.solve(steps=2).final.g
    np.testing.assert_allclose(table, scn.problem.solve(steps=2).final.g, rtol=0, atol=1e-12 * 20)
    nodes = np.unique(m.quads[el])
    with open(tmp_path / "nodes.csv", "w") as fh:
        fh.write("node,Brx,Bry,Brz\n" + "".join(f"{i},0.0,0.0,0.001\n" for i in nodes))
    s = load(doc(magnets=[{"region": "fingers", "Br_file": "nodes.csv"}]), tmp_path)
    total = sum(ld.mag.total_lab for ld in s.problem.loads if hasattr(ld, "mag"))
    np.testing.assert_allclose(total, [0, 0, 0.001 * 0.7 * 4 * 120], rtol=1e-12, atol=1e-18)


# ----------------------------------------------------------------------------- finding 5
def test_finding5_physical_loads_beside_lambda_everywhere(tmp_path):
    from core_se3.io import read_field_data
    d = doc(output={"vtu": True, "plots": True, "picture": False})
    res = runner.run(load(d), out=str(tmp_path / "o"))
    for st in res.doc["steps"]:
        assert st["physical"] == {"fields.coil.B": {"value": pytest.approx(0.06 * st["load_factor"], abs=1e-15),
                                                    "unit": "T"}}
    assert res.doc["unit_system"]["length"] == "mm" and res.doc["load_numbers"][0]["name"] == "magnets[0]"
    fd = read_field_data(os.path.join(res.out, "vtu", "step_0002.vtu"))
    assert fd == {"load_factor": 0.5, "fields.coil.B [T]": 0.03}
    assert os.path.getsize(res.files["probes"]) > 0
    out = io.StringIO()
    import contextlib
    with contextlib.redirect_stdout(out):
        cli._step_table(res.doc)
    head = out.getvalue().splitlines()[0]
    assert "fields.coil.B [T]" in head and "tip_0.uz" in head


# ----------------------------------------------------------------------------- finding 6
def test_finding6_sweep_of_the_star_gripper_over_five_fields(tmp_path):
    """Five field values: one CSV and one plot; the warm-started runs equal cold runs."""
    grid = {"fields.coil.B[2]": [0.02, 0.03, 0.04, 0.05, 0.06]}
    res = scenario.sweep(load(STAR), grid, out=str(tmp_path / "sw"))
    rows = list(csv.DictReader(open(res.files["csv"])))
    assert [float(r["fields.coil.B[2]"]) for r in rows] == grid["fields.coil.B[2]"]
    assert [r["status"] for r in rows] == ["complete"] * 5 and [r["warm"] for r in rows] == ["False"] + ["True"] * 4
    assert open(res.files["plot"], "rb").read(4)[1:] == b"PNG"
    cold = load(doc(fields__coil__B=[0.0, 0.0, 0.06])).problem.solve().final.probes["tip_0"]["u"]
    np.testing.assert_allclose([float(rows[-1][f"tip_0.u{c}"]) for c in "xyz"], cold, rtol=0, atol=1e-8)


def test_sweep_from_the_command_line_and_the_sweep_section(tmp_path, capsys):
    path = tmp_path / "star.toml"
    path.write_text(scenario.dumps(doc(sweep={"material.E": [0.4698783, 0.6]})))
    assert cli.main(["sweep", str(path), "--out", str(tmp_path / "a"), "-q"]) == 0
    assert len(list(csv.DictReader(open(tmp_path / "a" / "sweep.csv")))) == 2
    assert cli.main(["sweep", str(path), "--set", "material.E=0.5,0.6,0.7", "--out", str(tmp_path / "b"),
                     "--cold"]) == 0
    assert "3 runs (0 failed, 0 warm-started)" in capsys.readouterr().out


def test_finding6_extended_resume_equals_one_run_to_the_higher_load(tmp_path):
    short = load(doc(STRIP, solver={"steps": 2, "lam_end": 1.0}))
    runner.run(short, out=str(tmp_path / "ext"))
    longer = load(doc(STRIP, solver={"steps": 4, "lam_end": 2.0}))
    ext = runner.run(longer, out=str(tmp_path / "ext"), resume=True)
    one = runner.run(longer, out=str(tmp_path / "one"))
    assert ext.status == "complete" and [s["load_factor"] for s in ext.doc["steps"]] == [0.0, 0.5, 1.0, 1.5, 2.0]
    assert np.abs(ext.g - one.g).max() <= 1e-12 * 10.0
    assert ext.doc["steps"][-1]["probes"] == one.doc["steps"][-1]["probes"]


def test_finding6_refused_resume_names_the_key_that_changed(tmp_path):
    runner.run(load(STRIP), out=str(tmp_path / "o"))
    with pytest.raises(CheckpointError, match=r"different scenario: material.E changed from 1200000.0 to 1300000.0"):
        runner.run(load(doc(STRIP, material__E=1.3e6)), out=str(tmp_path / "o"), resume=True)
    with pytest.raises(CheckpointError, match=r"solver.steps \(or solver.lam_end\) changed: step 1 was done at "
                                              r"load factor 0.5, the scenario now puts it at 0.333333"):
        runner.run(load(doc(STRIP, solver={"steps": 3})), out=str(tmp_path / "o"), resume=True)
    with pytest.raises(CheckpointError, match="cannot shorten it"):
        runner.run(load(doc(STRIP, solver={"steps": 1, "lam_end": 0.5})), out=str(tmp_path / "o"), resume=True)


def test_finding6_a_ctrl_c_run_says_interrupted(tmp_path, monkeypatch):
    from core_se3.scenario import sinks

    class Stop(sinks.Progress):
        def update(self, *a, **k):
            raise KeyboardInterrupt
    monkeypatch.setattr(sinks, "Progress", Stop)
    with pytest.raises(KeyboardInterrupt):
        runner.run(load(STRIP), out=str(tmp_path / "o"))
    doc_ = json.load(open(tmp_path / "o" / "results.json"))
    assert doc_["status"] == "interrupted" and "continue with --resume" in doc_["error"]
    monkeypatch.undo()
    assert runner.run(load(STRIP), out=str(tmp_path / "o"), resume=True).status == "complete"


# ----------------------------------------------------------------------------- finding 7
def test_finding7_suggestions_for_swept_sections_and_elements(tmp_path, capsys):
    with pytest.raises(ScenarioError, match=r"refers to 'fields.coli'.*did you mean 'coil'\?"):
        scenario.sweep(load(STAR), {"fields.coli.B[2]": [0.02]}, out=str(tmp_path / "s"))
    bad(doc(sweep={"magnet[0].Br": [0.1]}), "sweep.magnet[0].Br", "did you mean 'magnets'?")
    bad(doc(units="N-mm-Mpa"), "units", "did you mean 'N-mm-MPa'?")
    assert cli.main(["bench", "run", "cantilever-shear", "--element", "defualt"]) == 2
    assert "did you mean 'default'?" in capsys.readouterr().err


# ----------------------------------------------------------------------------- finding 8
def test_finding8_progress_for_bench_run_and_sweeps(tmp_path, capsys):
    assert cli.main(["bench", "run", "cantilever-shear", "--mesh", "4x1", "--steps", "3", "--progress"]) == 0
    out = capsys.readouterr().out
    assert "\r[" in out and "step 3" in out and " s" in out
    assert cli.main(["bench", "run", "cantilever-shear", "--mesh", "4x1", "--steps", "3"]) == 0
    assert "\r[" not in capsys.readouterr().out                     # not a terminal: silent
    path = tmp_path / "s.toml"
    path.write_text(scenario.dumps(STRIP))
    assert cli.main(["sweep", str(path), "--set", "material.E=1.2e6,2.4e6", "--out", str(tmp_path / "w"),
                     "--progress"]) == 0
    out = capsys.readouterr().out
    assert "run 1/2" in out and "left" in out
    assert cli.main(["sweep", str(path), "--set", "material.E=1.2e6,2.4e6", "--out", str(tmp_path / "w"), "-q",
                     "--force"]) == 0
    assert capsys.readouterr().out == ""                              # --quiet: silent


# ----------------------------------------------------------------------------- new kinds of bad input
def test_unknown_unit_system():
    bad(doc(units="mm"), "units", "unknown value 'mm'", "'SI', 'N-mm-MPa', 'consistent'")


def test_consistent_units_need_mu0():
    bad(doc(units="consistent"), "magnets[0].mu0", 'with units = "consistent" every magnet needs mu0')


def test_a_density_in_g_per_cm3_written_in_si_units_warns():
    """Silicone's 1.07 g/cm^3 written as rho = 1.07 with units = "SI" is 1.07 kg/m^3 -- air's density,
    a thousandth of the gravity load; it passed the old range (1 .. 25 000 kg/m^3) silently."""
    grav = doc(STRIP, units="SI", loads=[{"type": "gravity", "rho": 1.07, "g": [0.0, 0.0, -9.81]}], material__E=1e6)
    warns(grav, "loads[0].rho", "rho = 1.07 kg/m^3 is outside the densities of real solids (10 to 25 000",
          "a density in g/cm^3 is 1000 times too small: 1.07 g/cm^3 is 1070 kg/m^3")
    grav["loads"][0]["rho"] = 1070.0                                  # silicone in kg/m^3: no warning
    assert not [w for w in load(grav).warnings if "rho" in w.key]


def test_implausible_density_gravity_mu0_dipole_field_thickness_first_step():
    grav = doc(STRIP, units="N-mm-MPa", loads=[{"type": "gravity", "rho": 1000.0, "g": [0.0, 0.0, -9.81]}],
               material__E=1.0)
    warns(grav, "loads[0].rho", "rho = 1000 t/mm^3 = 1e+15 kg/m^3 is outside the densities of real solids")
    grav["loads"][0]["rho"] = 1e-9
    warns(grav, "loads[0].g", "|g| = 9.81 mm/s^2 is 0.001 times Earth's gravity (9810 mm/s^2 in N-mm-MPa)")
    warns(doc(magnets__0__mu0=4e-7 * np.pi), "magnets[0].mu0", "differs from mu0 in N-mm-MPa (1.25664")
    dip = doc(fields={"coil": {"type": "dipole", "m": [0.0, 0.0, 1.0], "x0": [0.0, 0.0, -50.0], "mu0": 4e-7 * np.pi}})
    warns(dip, "fields.coil.mu0", "differs from mu0 of a dipole in N-mm-MPa (0.00125664", "leave it out")
    warns(doc(fields__coil__B=[0.0, 0.0, 60.0]), "fields.coil", "the applied field reaches |B| = 60 T")
    warns(doc(material__h=7.0), "material.h", "h / L = 7 / 20 = 0.35 > 0.3")
    warns(doc(solver={"steps": 1}, fields__coil__B=[0.0, 0.0, 1.9], magnets__0__Br=1.0, magnets__0__Br_axial=0.0),
          "magnets[0]",
          "the load number 12 |Br| |Ba| L^2 / (mu0 E h^2) = ", "in the first step", "above 1000")


def test_radial_magnet_errors(tmp_path):
    bad(doc(magnets__0__Br=[0.1, 0.0, 0.0]), "magnets[0].Br", 'with direction = "radial" Br is the magnitude')
    centred = doc(STRIP, units="SI", mesh__x0=-5.0, mesh__nx=3, fields={"f": {"type": "uniform", "B": [0, 0, 0.01]}},
                  magnets=[{"direction": "radial", "Br": 0.01}])
    bad(centred, "magnets[0].centre",
        "has its centroid on the axis", "radial direction is undefined")
    bad(doc(magnets=[{"region": "fingers", "Br": [0.01, 0, 0], "centre": [0.0, 0.0, 0.0]}]), "magnets[0].centre",
        "belongs to a radial or tangential magnetisation")


def test_magnetisation_table_errors(tmp_path):
    def table(text):
        (tmp_path / "t.csv").write_text(text)
        return doc(magnets=[{"region": "palm", "Br_file": "t.csv"}])
    bad(doc(magnets=[{"region": "palm", "Br_file": "none.csv"}]), "magnets[0].Br_file", "does not exist",
        tmp_path=tmp_path)
    bad(table("id,x,y,z\n0,0,0,1\n"), "magnets[0].Br_file", "expected the header element,Brx,Bry,Brz",
        tmp_path=tmp_path)
    bad(table("element,Brx,Bry,Brz\n0,a,0,1\n"), "magnets[0].Br_file", "row 2 is not four numbers",
        tmp_path=tmp_path)
    bad(table("element,Brx,Bry,Brz\n99999,0,0,1\n"), "magnets[0].Br_file", "element ids [99999] do not exist",
        tmp_path=tmp_path)
    bad(table("element,Brx,Bry,Brz\n0,0,0,1\n"), "magnets[0].Br_file", "the table misses 3 of the magnet's 4",
        tmp_path=tmp_path)
    palm = load(STAR).regions["palm"]
    rows = "".join(f"{i},0,0,0.001\n" for i in list(palm) + [palm[0]])
    bad(table("element,Brx,Bry,Brz\n" + rows), "magnets[0].Br_file", f"element {palm[0]} is listed 2 times",
        tmp_path=tmp_path)


def test_sweep_input_errors(tmp_path):
    from core_se3.scenario.sweep import parse_values
    with pytest.raises(ScenarioError, match=r"cannot read the value '\{x\}' of --set material.E"):
        parse_values("1,{x}", "--set material.E")
    bad(doc(sweep={"material.E": []}), "sweep.material.E", "expected a non-empty array of values")
    with pytest.raises(ScenarioError, match=r"refers to loads\[3\], but the scenario has 1 entries"):
        scenario.sweep(load(STRIP), {"loads[3].force": [[0.0, 0.0, 1.0]]}, out=str(tmp_path / "s"))


def test_shape_generator_errors():
    bad(doc(mesh__n_arms=2), "mesh.n_arms", "expected an integer >= 3, got 2")
    bad(doc(mesh__palm=1.0), "mesh.palm", "palm circumradius 1 is too small for 4 arms of width 6")   # at its key
    bad(doc(mesh__size=1e-4), "mesh.size", "over the limit of 1000000")
    bad(doc(mesh__backend="gmesh"), "mesh.backend", "did you mean 'gmsh'?")
    with pytest.raises(MeshError, match="0 <= radius <= min"):
        M.rounded_rectangle(10.0, 4.0, 3.0)

"""The front door of core_se3.design (issue 15 item 3): a [design] section in a scenario file,
``core-se3 design FILE.toml --out DIR`` and its outputs; the optimised scenario reproduces the
design's state under ``core-se3 run``; bad input is refused with the file and the key."""
import json
import os

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.cli import main
from core_se3.errors import ScenarioError

pytestmark = pytest.mark.core

BASE = """
units = "N-mm-MPa"
[mesh]
generator = "rectangle"
L = 17.2
width = 5.0
nx = 12
ny = 1
[material]
E = 0.8969
nu = 0.0
h = 0.42
[regions.root]
box = { x = [0.0, 8.6] }
[regions.free]
box = { x = [8.6, 17.2] }
[[supports]]
type = "clamp"
edge = "x0"
[fields.coil]
type = "uniform"
B = [0.0, 0.0, 0.002]
[[magnets]]
Br = [0.143, 0.0, 0.0]
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = 4
[design]
tolerance = 1e-6
[[design.variables]]
type = "field"
field = "coil"
form = "polar"
free = ["magnitude"]
B_max = 0.05
[[design.variables]]
type = "magnetisation"
regions = ["root", "free"]
form = "polar"
free = ["angle"]
[[design.targets]]
type = "position"
probe = "tip"
value = [12.0, 0.0, 10.0]
components = [0, 2]
"""


def test_design_command_writes_and_the_optimised_scenario_reproduces(tmp_path):
    path = tmp_path / "strip.toml"
    path.write_text(BASE)
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out), "-q"]) == 0
    doc = json.loads((out / "design.json").read_text())
    assert doc["result"]["reached"] and doc["result"]["max_misfit"] < 1e-6
    assert doc["result"]["history"] and doc["poses"][0]["targets"][0]["max_misfit"] < 1e-6
    for f in ("optimised.toml", "convergence.png", "target_design.png", os.path.join("vtu", "design", "series.pvd")):
        assert (out / f).exists(), f
    scn = scenario.load(out / "optimised.toml")
    assert "design" not in scn.spec and len(scn.spec["magnets"]) == 2
    tip = scn.problem.solve().final.probes["tip"]["u"] + np.array([17.2, 0.0, 0.0])
    assert abs(tip[0] - 12.0) < 1e-5 and abs(tip[2] - 10.0) < 1e-5
    # the components' units: the polar angles are the optimiser's radians (before, unmarked next to
    # targets in degrees: 1.910 read as degrees is 107.5 deg off), also given in degrees, and those
    # are the angles of the optimised scenario's B^r (what `core-se3 run` reads back)
    res = doc["result"]
    assert res["units"] == {"coil.B": "T", "magnetisation1[0].angle": "rad", "magnetisation1[1].angle": "rad"}
    for j, m in enumerate(scn.spec["magnets"]):
        lab = f"magnetisation1[{j}].angle"
        assert res["angles_deg"][lab] == pytest.approx(np.degrees(res["components"][lab]), rel=1e-14)
        assert res["angles_deg"][lab] == pytest.approx(np.degrees(np.arctan2(m["Br"][2], m["Br"][0])), abs=1e-9)


def test_a_magnetisation_in_two_fields_is_designed_and_written_in_both(tmp_path):
    """One material in two fields, a magnet per field (examples/walker.toml's spelling).  Before,
    the magnetisation variable (``field = "coil"``; without it a DesignError asked for one) dropped
    the magnets of the other field and started from the sum of the two B^r (0.286 T), and the
    optimised scenario had the material in the coil only.  Now the design acts in both fields
    and the optimised scenario writes a magnet per region and field, which `run` reproduces."""
    spec = BASE.replace('[[magnets]]\nBr = [0.143, 0.0, 0.0]\n',
                        '[fields.side]\ntype = "uniform"\nB = [0.0005, 0.0, 0.0]\n'
                        '[[magnets]]\nBr = [0.143, 0.0, 0.0]\nfield = "coil"\n'
                        '[[magnets]]\nBr = [0.143, 0.0, 0.0]\nfield = "side"\n')
    spec = spec.replace('regions = ["root", "free"]\n', 'regions = ["root", "free"]\nfield = "coil"\n')
    assert spec.count("[[magnets]]") == 2 and 'field = "coil"\n' in spec.split("[design]")[1]
    path = tmp_path / "two.toml"
    path.write_text(spec)
    scn = scenario.load(path)
    design = scn.design()
    mv = design.variables[1]
    assert [np.linalg.norm(b) for b in mv.Br()] == pytest.approx([0.143, 0.143], rel=1e-12)
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out), "-q"]) == 0
    doc = json.loads((out / "design.json").read_text())
    assert doc["result"]["reached"] and doc["result"]["max_misfit"] < 1e-6
    opt = scenario.load(out / "optimised.toml")
    mags = opt.spec["magnets"]
    assert sorted((m["region"], m["field"]) for m in mags) == [("free", "coil"), ("free", "side"),
                                                               ("root", "coil"), ("root", "side")]
    tip = opt.problem.solve().final.probes["tip"]["u"] + np.array([17.2, 0.0, 0.0])
    assert abs(tip[0] - 12.0) < 1e-5 and abs(tip[2] - 10.0) < 1e-5


@pytest.mark.parametrize("old,new,key", [
    ('probe = "tip"\nvalue', 'probe = "tpi"\nvalue', "design.targets[0].probe"),
    ('regions = ["root", "free"]', 'regions = ["root", "fre"]', "design.variables[1].regions"),
    ('field = "coil"\nform = "polar"\nfree', 'field = "cool"\nform = "polar"\nfree', "design.variables[0].field"),
    ("B_max = 0.05", "B_max = 0.001", "design"),
    ('type = "field"', 'type = "feild"', "design.variables[0].type"),
    ("components = [0, 2]", "components = [0, 3]", "design.targets[0].components"),
])
def test_bad_design_input_names_the_key(tmp_path, old, new, key):
    assert old in BASE
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace(old, new, 1))
    with pytest.raises(ScenarioError) as exc:
        scenario.load(path).design()
    assert exc.value.key == key and str(path) in str(exc.value)


@pytest.mark.parametrize("old,new,match", [
    ('free = ["magnitude"]\nB_max = 0.05', 'free = ["angle"]\nB_max = 0.001',
     "variable 'coil': the start field has magnitude 0.002 above B_max = 0.001"),
    ('form = "polar"\nfree = ["angle"]', 'form = "polar"\nfree = ["angle"]\nBr_max = 0.1',
     "variable 'magnetisation1': the start B\\^r of region 'root' has magnitude 0.143 above Br_max = 0.1"),
])
def test_a_bound_that_excludes_a_fixed_start_is_refused(tmp_path, old, new, match):
    # a polar form whose magnitude is not free, started above its bound (B_max, Br_max): before,
    # the design kept the magnitude there (0.002 T with B_max = 0.001, 0.143 T with Br_max = 0.1),
    # "reached the target" and wrote it to optimised.toml -- the bound silently dropped, where a
    # free magnitude or a vector form is refused ("outside its bounds", "norm ... above the bound")
    assert old in BASE
    path = tmp_path / "bad.toml"
    path.write_text(BASE.replace(old, new, 1))
    with pytest.raises(ScenarioError, match=match) as exc:
        scenario.load(path).design()
    assert exc.value.key == "design" and str(path) in str(exc.value)


@pytest.mark.parametrize("where,components,held", [
    ("node = 0", "components = [0, 2]", "[0, 2]"),          # node 0 of the clamped edge (x0)
    ('probe = "tip"', "components = [0, 2]", None),         # the tip: free
])
def test_a_target_on_held_nodes_is_refused(tmp_path, where, components, held):
    # a position target on a clamped node (a node id taken for the tip's): before, the design ran
    # and said only "did not reach the target: misfit 1.000e+00 > tolerance 1.000e-06".  (A target
    # with some free components, a whole shape with its clamped nodes, is the user's: the twin
    # experiment of test_design_cases targets every node.)
    text = BASE.replace('probe = "tip"\nvalue = [12.0, 0.0, 10.0]\ncomponents = [0, 2]', f"{where}\nvalue = [1.0, 0.0, 1.0]"
                        f"\n{components}")
    path = tmp_path / "held.toml"
    path.write_text(text)
    if held is None:
        scenario.load(path).design()
        return
    with pytest.raises(ScenarioError, match=rf"target 'targets\[0\]' of pose 'design': its component\(s\) "
                                            rf"\{held[:-1]}\] are held by the supports") as exc:
        scenario.load(path).design()
    assert exc.value.key == "design"


def test_poses_of_one_file_name_are_refused(tmp_path):
    """Pose names are made safe for file names ('grip é' and 'grip ü' both 'grip__'): the second
    pose's optimised_grip__.toml and vtu/grip__/ overwrote the first's, and design.json listed one.
    Distinct names of one file name are now refused at the second pose's name."""
    poses = '[[design.poses]]\nname = "grip é"\n[[design.poses]]\nname = "grip ü"\n'
    path = tmp_path / "poses.toml"
    path.write_text(BASE.replace("[[design.variables]]", poses + "[[design.variables]]", 1).replace(
        'components = [0, 2]', 'components = [0, 2]\npose = "grip é"'))
    with pytest.raises(ScenarioError, match=r"poses 'grip é' and 'grip ü' have one file name, 'grip__'") as exc:
        scenario.load(path)
    assert exc.value.key == "design.poses[1].name"
    path.write_text(path.read_text().replace("grip ü", "grip-u"))
    assert [p["name"] for p in scenario.load(path).spec["design"]["poses"]] == ["grip é", "grip-u"]


def test_unreachable_target_is_reported(tmp_path, capsys):
    path = tmp_path / "far.toml"
    path.write_text(BASE.replace("value = [12.0, 0.0, 10.0]", "value = [40.0, 0.0, 10.0]").replace(
        "[design]\n", "[design]\nmax_iter = 8\n"))
    assert main(["design", str(path), "--out", str(tmp_path / "o"), "-q"]) == 4
    doc = json.loads((tmp_path / "o" / "design.json").read_text())
    assert doc["result"]["reached"] is False and "did not reach the target: misfit" in doc["result"]["message"]


def test_gripper_design_example():
    # examples/gripper-design.toml (docs/DESIGN.md): two poses, 14 variables; bar: misfit below
    # 1e-3 of the finger length (0.02 mm) within 60 s (the issue's).  Wall time is not asserted
    # here (a loaded CI machine would make it flaky); the work is: measured 7 iterations, 24
    # equilibrium solves (each a ramp of the field from zero: equilibria = "ramp"), 1345 Newton
    # iterations -- the bounds below are 1.5 times that, a regression of the optimiser or of the
    # equilibrium path fails.
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    scn = scenario.load(os.path.join(root, "examples", "gripper-design.toml"))
    d = scn.design()
    r = d.optimise(max_iter=40, tolerance=0.02, stop_at_tolerance=True)
    assert r.reached and r.max_misfit < 0.02
    assert r.iterations <= 11 and r.equilibrium_solves <= 36 and r.newton_iterations <= 2000
    assert r.misfit["flat"]["targets[0]"] < 1e-9          # no field: the gripper stays flat
    # the grasp is the equilibrium the optimised scenario runs to (the field ramped from zero):
    # before (equilibria followed along the optimiser's path), that run closed the fingers
    # downward, the tips at z = -12.57 mm, 0.379 of the length scale from the design's
    assert r.branch == {}
    d.assign_pose(1, r.x)
    tips = scn.problem.solve().final.probes
    for name, ref, target in (("tip_px", (23, 0, 0), (5, 0, 12)), ("tip_mx", (-23, 0, 0), (-5, 0, 12)),
                              ("tip_py", (0, 23, 0), (0, 5, 12)), ("tip_my", (0, -23, 0), (0, -5, 12))):
        assert np.abs(np.add(ref, tips[name]["u"]) - target).max() < 0.02, name


GRAVITY = """
units = "N-mm-MPa"
[mesh]
generator = "rectangle"
L = 100.0
width = 10.0
nx = 8
ny = 1
[material]
E = 1000.0
nu = 0.0
h = 1.0
rho = 7.85e-9
[[supports]]
type = "clamp"
edge = "x0"
[[loads]]
type = "gravity"
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = 2
[design]
tolerance = 1e-6
[[design.variables]]
type = "load"
load = 0
[[design.targets]]
type = "position"
probe = "tip"
value = [0.0, 0.0, -5.0]
components = [2]
"""


def test_optimised_scenario_holds_a_load_magnitude_at_its_default(tmp_path):
    # a load variable on a gravity with the default g (-9810 mm/s^2 in N-mm-MPa): before, the
    # optimised scenario left g out, so `core-se3 run` solved the original load (tip z -11.4
    # for the design's -5.0); now g is written scaled, in the scenario's units
    path = tmp_path / "sag.toml"
    path.write_text(GRAVITY)
    assert main(["design", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
    scn = scenario.load(tmp_path / "o" / "optimised.toml")
    assert scn.spec["loads"][0]["g"][2] != -9810.0
    assert abs(scn.problem.solve().final.probes["tip"]["u"][2] + 5.0) < 1e-5


def test_a_second_design_of_one_scenario_starts_from_the_file_and_writes_it_right(tmp_path):
    # run_design twice on one Scenario (a notebook re-running its design cell, a script writing
    # two output directories): the first design leaves the problem at its values (the gravity
    # scaled by 0.4337).  Before, the second design was built on that problem: its load variable
    # started at 1 relative to the scaled gravity ("reached" at once) and optimised.toml wrote
    # 1 x the file's g = -9810, which `core-se3 run` sags 11.43 for the design's 5.0.  Now each
    # design is built on the problem as the file gives it: the same result, the same file.
    from core_se3.scenario.design_runner import run_design
    path = tmp_path / "sag.toml"
    path.write_text(GRAVITY)
    scn = scenario.load(path)
    docs = []
    for k in (1, 2):
        r, files = run_design(scn, out=tmp_path / f"o{k}", vtu=False, plots=False)
        assert r.reached and abs(r.x[0] - 0.4337) < 1e-4
        opt = scenario.load(files["scenario"])
        assert abs(opt.problem.solve().final.probes["tip"]["u"][2] + 5.0) < 1e-5
        docs.append(opt.spec["loads"][0]["g"])
    assert docs[0] == docs[1]


def test_a_pose_holds_the_field_of_a_shared_field_variable(tmp_path):
    # [[design.poses]] fields = { coil = [0, 0, 0] } beside a field variable of every pose (no
    # pose key): the flat pose must see no field.  Before, the shared variable was assigned
    # after the pose's hold: the "flat" pose was bent like the other (tip z 12.32 mm at the
    # start) and had a derivative in the field; optimised_flat.toml held the optimised field.
    text = BASE.replace("[design]\ntolerance = 1e-6\n", "[design]\ntolerance = 1e-6\n[[design.poses]]\nname = \"flat\"\n"
                        "fields = { coil = [0.0, 0.0, 0.0] }\n[[design.targets]]\ntype = \"position\"\npose = \"flat\"\n"
                        "probe = \"tip\"\nvalue = [17.2, 0.0, 0.0]\n[[design.poses]]\nname = \"bent\"\n")
    text = text.replace('[[design.targets]]\ntype = "position"\nprobe = "tip"\nvalue = [12.0',
                        '[[design.targets]]\ntype = "position"\npose = "bent"\nprobe = "tip"\nvalue = [12.0')
    path = tmp_path / "poses.toml"
    path.write_text(text)
    scn = scenario.load(path)
    d = scn.design()
    x = d.x_start()
    flat = scn.problem.probes["tip"].state(d.solve(x)[0].g)[0]
    assert np.abs(flat - [17.2, 0.0, 0.0]).max() < 1e-12
    assert np.all(d.jacobian(x)[:3] == 0.0)                 # the flat pose's rows: no variable moves it
    assert main(["design", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
    held = scenario.load(tmp_path / "o" / "optimised_flat.toml")
    assert held.spec["fields"]["coil"]["B"] == [0.0, 0.0, 0.0]


def test_design_of_a_scenario_traced_by_arc_length(tmp_path):
    # [solver] control = "arclength": the design's solves from the flat state step the load
    # with the scenario's Newton options.  Before, its path-following keys went along and
    # `core-se3 design` stopped with exit 2, "newton_solve() got an unknown option 'method'".
    path = tmp_path / "arc.toml"
    path.write_text(BASE.replace("[solver]\nsteps = 4", '[solver]\ncontrol = "arclength"\ndlam0 = 0.25'))
    assert main(["design", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
    scn = scenario.load(tmp_path / "o" / "optimised.toml")
    assert scn.problem.solve_defaults["control"] == "arclength"
    tip = scn.problem.solve().final.probes["tip"]["u"] + np.array([17.2, 0.0, 0.0])
    assert abs(tip[0] - 12.0) < 1e-5 and abs(tip[2] - 10.0) < 1e-5


FLOOR = """
[mesh]
generator = "rectangle"
L = 10.0
width = 1.0
nx = 8
ny = 1
[material]
E = 1.2e6
nu = 0.0
h = 0.1
[[supports]]
type = "clamp"
edge = "x0"
[[loads]]
type = "edge_force"
edge = "x1"
force = [0.0, 0.0, -0.4]
[[obstacles]]
type = "half_space"
name = "floor"
point = [0.0, 0.0, -0.3]
normal = [0.0, 0.0, 1.0]
[[probes]]
name = "mid"
nodes = [4]
[solver]
steps = 4
[output]
plots = false
picture = false
[design]
tolerance = 1e-6
[[design.variables]]
type = "load"
load = 0
[[design.targets]]
type = "position"
probe = "mid"
value = [0.0, 0.0, -0.07794]
components = [2]
"""


def test_a_designs_vtu_has_each_steps_contact_forces_and_a_runs_fields(tmp_path):
    """The design's VTU series evaluated the contact fields of every step with the last step's
    multipliers: contact_force summed to 0.4303 at step 1 of 4 where the step carries 0.0510
    (0.4302, 0.4302 for 0.1774, 0.3038 at steps 2, 3).  Now each step's multipliers are set first, and the files are
    written by the run's writer (``scenario.sinks.step_files``): stress resultants, FieldData
    load_factor and the obstacles' series too."""
    import meshio
    from core_se3.io.vtk import read_field_data
    path = tmp_path / "floor.toml"
    path.write_text(FLOOR)
    out = tmp_path / "d"
    assert main(["design", str(path), "--out", str(out), "-q"]) == 0
    res = scenario.load(out / "optimised.toml").problem.solve()
    vdir = out / "vtu" / "design"
    files = [meshio.read(str(vdir / f"step_{k:04d}.vtu")) for k in range(len(res.steps))]
    forces = [v.point_data["contact_force"][:, 2].sum() for v in files]
    np.testing.assert_allclose(forces, [s.contact["floor"]["force"][2] for s in res.steps], rtol=1e-6, atol=1e-12)
    assert 0.0 < forces[1] < 0.2 * forces[-1]                  # the push grows the contact force fourfold
    for k, (v, s) in enumerate(zip(files, res.steps)):
        assert "M1" in v.cell_data and read_field_data(str(vdir / f"step_{k:04d}.vtu"))["load_factor"] == \
            pytest.approx(s.load_factor, abs=1e-12)
    assert (vdir / "obstacles.pvd").exists() and (vdir / "step_0004_obstacles.vtu").exists()


def test_a_design_error_names_the_region_as_the_scenario_does(tmp_path):
    """B^r not uniform over the design region 'root' (0.143 on x < 4.3, 0.1 beyond): the error
    said 'region 0' (its index in the variable's list), a name the scenario never uses."""
    two = BASE.replace("[[magnets]]\nBr = [0.143, 0.0, 0.0]",
                       '[regions.a]\nbox = { x = [0.0, 4.3] }\n[regions.b]\nbox = { x = [4.3, 17.2] }\n'
                       '[[magnets]]\nBr = [0.143, 0.0, 0.0]\nregion = "a"\n[[magnets]]\nBr = [0.1, 0.0, 0.0]\nregion = "b"')
    assert two != BASE
    path = tmp_path / "two.toml"
    path.write_text(two)
    with pytest.raises(ScenarioError, match=r"B\^r varies over region 'root' .* on region 'root''s own nodes"):
        scenario.load(path).design()


def test_a_designs_vtu_field_data_holds_the_designed_loads(tmp_path):
    """A design's VTU FieldData held only load_factor, not the physical record a run writes beside
    it (a run of the scenario before the design would show the coil's 0.002 T).  Now each step's
    record at the design's values: the optimised scenario's record, read back from its file."""
    from core_se3.io.vtk import read_field_data
    from core_se3.scenario.outputs import physical_record
    path = tmp_path / "strip.toml"
    path.write_text(BASE)
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out), "-q"]) == 0
    opt = scenario.load(out / "optimised.toml")
    steps = sorted((out / "vtu" / "design").glob("step_*.vtu"))
    assert len(steps) == 5
    for f in steps:
        data = read_field_data(str(f))
        want = physical_record(opt, data["load_factor"])
        assert {k.split(" [")[0] for k in data} - {"load_factor"} == set(want)
        assert data["fields.coil.B [T]"] == pytest.approx(want["fields.coil.B"]["value"], rel=1e-12, abs=1e-15)
    assert abs(data["fields.coil.B [T]"] - 0.002) > 5e-5     # the designed coil (1.925e-3 T), not the 0.002 T before


UNION = GRAVITY.replace('''[[loads]]
type = "gravity"''', '''[[loads]]
type = "edge_force"
edge = ["x1", "y1"]
force = [0.0, 0.0, -0.01]''').replace("ny = 1", "ny = 2")


def test_a_load_variable_scales_an_edge_load_on_a_union_of_lines(tmp_path):
    # an edge force on the union of the lines x1 and y1 builds one load per line; a load variable
    # on it was refused ("a load variable needs a single load") although the optimised scenario
    # scales the entry as a whole.  Now it is one multiplier of both lines' loads: the design
    # reaches its tip target and `core-se3 run` of optimised.toml gives the design's tip
    path = tmp_path / "union.toml"
    path.write_text(UNION)
    assert main(["design", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
    scn = scenario.load(tmp_path / "o" / "optimised.toml")
    P = scn.spec["loads"][0]["force"][2] / -0.01
    assert abs(P - 1.0) > 0.05                                       # the design moved it
    assert abs(scn.problem.solve().final.probes["tip"]["u"][2] + 5.0) < 1e-5


def test_targets_all_of_weight_zero_are_refused(tmp_path):
    from core_se3.scenario.design_runner import run_design
    # every target of weight 0: Phi = 0 for every design.  Before, the design ran its equilibria
    # and said only "did not reach the target"; now a ScenarioError names the weight
    path = tmp_path / "w0.toml"
    path.write_text(GRAVITY + "weight = 0.0\n")
    with pytest.raises(ScenarioError, match="weight is 0"):
        run_design(scenario.load(path), out=tmp_path / "o", vtu=False, plots=False)


def test_a_design_leaves_the_users_matplotlib_backend_alone(tmp_path):
    # a notebook or GUI session that runs a design keeps its backend (before: the design's plots
    # called matplotlib.use("Agg"), so the user's next plt.show() showed nothing); a subprocess,
    # since the backend is global to the interpreter
    import subprocess
    import sys
    path = tmp_path / "strip.toml"
    path.write_text(BASE)
    code = ("import matplotlib; matplotlib.use('svg'); import matplotlib.pyplot as plt\n"
            "from core_se3.cli import main\n"
            f"assert main(['design', {str(path)!r}, '--out', {str(tmp_path / 'out')!r}, '-q']) == 0\n"
            "print(matplotlib.get_backend())\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert run.stdout.split()[-1] == "svg"
    assert (tmp_path / "out" / "convergence.png").read_bytes()[1:4] == b"PNG"
    assert (tmp_path / "out" / "target_design.png").read_bytes()[1:4] == b"PNG"

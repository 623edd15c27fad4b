"""New kinds of bad input of issue 34, one line each: every one is a specific error naming the file
and the key (ScenarioError), the checkpoint or the directory (CheckpointError), or a documented
behaviour (docs/SCENARIOS.md).  Together with the findings of tests/test_front_door_findings.py
they are the issue's stress battery kept as tests.
"""
import copy
import os
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, mesh as M, scenario
from core_se3.errors import CheckpointError, CoreSE3Error, ScenarioError
from core_se3.io import Checkpoint
from core_se3.io.rundir import RunDirectory, RunDirectoryError
from core_se3.scenario import runner

BASE = {"name": "adv", "units": "SI", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
        "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1, "rho": 1000.0},
        "supports": [{"type": "clamp", "edge": "x0"}],
        "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
        "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 2},
        "output": {"vtu": False, "plots": False, "picture": False}}
TURN = {"type": "rotate", "edge": "x1", "axis": [1.0, 0.0, 0.0], "angle": 0.1}
LIFT = {"type": "prescribed", "edge": "x1", "translate": [0.0, 0.0, 1.0]}
NODAL = {"type": "nodal", "force": [0.0, 0.0, 1.0]}


def with_(**sections):
    d = copy.deepcopy(BASE)
    for k, v in sections.items():
        if v is None:
            d.pop(k, None)
        else:
            d[k] = copy.deepcopy(v)
    return d


def load(d, base_dir="."):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file="adv.toml", base_dir=base_dir)


# (id, document, the key the error names, a fragment of its message)
CASES = [
    ("node repeated in a nodal load", with_(loads=[dict(NODAL, nodes=[4, 4])]), "loads[0].nodes", "node 4 is listed 2 times"),
    ("node repeated in a support", with_(supports=[{"type": "clamp", "nodes": [0, 5, 0]}]), "supports[0].nodes",
     "node 0 is listed 2 times"),
    ("node repeated in a probe", with_(probes=[{"name": "p", "nodes": [9, 9]}]), "probes[0].nodes", "listed 2 times"),
    ("node repeated in a node set", with_(edges={"e": {"nodes": [3, 3]}}), "edges.e.nodes", "node 3 is listed 2 times"),
    ("element repeated in a region", with_(regions={"r": {"elements": [1, 1]}}), "regions.r.elements",
     "element 1 is listed 2 times"),
    ("clamp and rotation of one edge", with_(supports=[{"type": "clamp", "edge": "x0"}, dict(TURN, edge="x0")]),
     "supports[1]", "supports[1] (a prescribed motion) and supports[0] (a clamp)"),
    ("two rotations of one edge", with_(supports=[BASE["supports"][0], TURN, dict(TURN, angle=0.2)]), "supports[2]",
     "supports[2] (a prescribed motion) and supports[1] (a prescribed motion)"),
    ("fix and rotation of one node", with_(supports=[BASE["supports"][0], TURN, {"type": "fix", "nodes": [9], "dofs": [2]}]),
     "supports[2]", "supports[2] (a fix) and supports[1] (a prescribed motion) both hold node 9 (translation along d3)"),
    ("prescribed motion on a clamped node", with_(supports=[BASE["supports"][0], dict(LIFT, edge="x0")]), "supports[1]",
     "supports[0] (a clamp)"),
    ("rotation and prescribed motion of one edge", with_(supports=[BASE["supports"][0], TURN, LIFT]), "supports[2]",
     "both hold nodes [4, 9]"),
    ("support repeated", with_(supports=[BASE["supports"][0]] * 2), "supports[1]", "repeats supports[0] exactly"),
    ("load repeated", with_(loads=BASE["loads"] * 2), "loads[1]", "repeats loads[0] exactly: the load would act twice"),
    ("gravity repeated", with_(loads=[{"type": "gravity"}] * 2), "loads[1]", "repeats loads[0]"),
    ("empty box of a node set", with_(edges={"e": {"box": {}}}), "edges.e.box", "an empty box selects every node"),
    ("empty box with a tolerance only", with_(edges={"e": {"box": {"tol": 0.1}}}), "edges.e.box", "an empty box"),
    ("empty box of a region", with_(regions={"r": {"box": {}}}), "regions.r.box", "an empty box"),
    ("probe on a block of nodes", with_(edges={"e": {"box": {"x": [5.0, 10.0]}}}, probes=[{"name": "p", "edge": "e"}]),
     "probes[0].edge", "node set 'e' is not a line of element edges, so it has no midpoint"),
    ("edge force on a block of nodes", with_(edges={"e": {"box": {"x": [5.0, 10.0]}}},
                                             loads=[{"type": "edge_force", "edge": "e", "force": [0.0, 0.0, 1.0]}]),
     "loads[0].edge", "node set 'e': an edge load (a total along a line) on a set that is not a line of element edges"),
    ("probe on a zig-zag node set", with_(edges={"e": {"nodes": [0, 6, 2]}}, probes=[{"name": "p", "edge": "e"}]),
     "probes[0].edge", "is not a line of element edges"),
    ("rtol of one", with_(solver={"rtol": 1.0}), "solver.rtol", "expected a number < 1"),
    ("dtol above one", with_(solver={"dtol": 2.0}), "solver.dtol", "expected a number < 1"),
    ("gravity without g in consistent units", with_(units="consistent", loads=[{"type": "gravity"}]), "loads[0].g",
     'with units = "consistent" gravity needs \'g\''),
    ("dipole without mu0 in consistent units",
     with_(units="consistent", loads=[], fields={"d": {"type": "dipole", "m": [0.0, 0.0, 1.0], "x0": [5.0, 0.0, -5.0]}},
           magnets=[{"Br": [0.1, 0.0, 0.0], "mu0": 1.0}]), "fields.d.mu0", "needs 'mu0' in your units"),
    ("a point with no node", with_(loads=[dict(NODAL, nodes={"near": [5.0, 5.0, 0.0]})]), "loads[0].nodes.near",
     "no node at [5.0, 5.0, 0.0]"),
    ("a point between two nodes", with_(loads=[dict(NODAL, nodes={"near": [8.75, 0.5, 0.0]})]), "loads[0].nodes.near",
     "the nearest is node 8 at [7.5, 0.5, 0.0], at distance 1.25 > 0.25"),
    ("two points at one node", with_(loads=[dict(NODAL, nodes={"near": [[10.0, 0.5, 0.0], [10.0, 0.49, 0.0]]})]),
     "loads[0].nodes.near", "two points find the same node ([9, 9])"),
    ("a point of two coordinates", with_(loads=[dict(NODAL, nodes={"near": [10.0, 0.5]})]), "loads[0].nodes.near",
     "expected an array of 3 numbers"),
    ("a point with an unknown key", with_(loads=[dict(NODAL, nodes={"near": [10.0, 0.5, 0.0], "within": 1.0})]),
     "loads[0].nodes.within", "unknown key 'within'"),
    ("a point tolerance of zero", with_(loads=[dict(NODAL, nodes={"near": [10.0, 0.5, 0.0], "tol": 0.0})]),
     "loads[0].nodes.tol", "expected a number > 0"),
    ("prescribed support without a motion", with_(supports=[BASE["supports"][0], {"type": "prescribed", "edge": "x1"}]),
     "supports[1]", "needs 'translate'"),
    ("prescribed rotation without an angle",
     with_(supports=[BASE["supports"][0], dict(LIFT, rotate={"axis": [0.0, 1.0, 0.0]})]), "supports[1].rotate.angle",
     "missing required key"),
    ("prescribed rotation about a zero axis",
     with_(supports=[BASE["supports"][0], dict(LIFT, rotate={"axis": [0.0, 0.0, 0.0], "angle": 0.1})]),
     "supports[1].rotate.axis", "expected a non-zero vector"),
    ("prescribed translation that is not finite", with_(supports=[BASE["supports"][0], dict(LIFT, translate=[0.0, 0.0, float("nan")])]),
     "supports[1].translate", "expected finite numbers"),
    ("prescribed motion with a free axis twice", with_(supports=[BASE["supports"][0], dict(LIFT, free=["x", "x"])]),
     "supports[1].free", "distinct lab axes"),
    ("prescribed motion with an arc length", with_(supports=[BASE["supports"][0], LIFT], solver={"control": "arclength"}),
     "supports[1].type", "a prescribed motion is not supported"),
    ("prescribed motion with an unknown key", with_(supports=[BASE["supports"][0], dict(LIFT, angle=0.1)]),
     "supports[1].angle", "unknown key 'angle'"),
    ("an edge force on the clamped edge", with_(loads=[{"type": "edge_force", "edge": "x0", "force": [0.0, 0.0, 1.0]}]),
     "loads[0]", "it acts only on dofs that supports[0] hold (nodes [0, 5])"),
    ("a moment on nodes whose rotations are fixed",
     with_(supports=[BASE["supports"][0], {"type": "fix", "nodes": [9], "dofs": [3, 4, 5]}],
           loads=[dict(NODAL, nodes=[9], force=[0.0, 0.0, 0.0], moment=[0.0, 1.0, 0.0])]), "loads[0]",
     "it acts only on dofs that supports[1] hold (nodes [9])"),
    ("a load on a node a prescribed motion moves", with_(supports=[BASE["supports"][0], LIFT],
                                                         loads=[dict(NODAL, nodes=[4])]), "loads[0]", "supports[1] hold"),
    ("magnet repeated", with_(loads=[], regions={"tip": {"box": {"x": [7.5, 10.0]}}},
                              fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}},
                              magnets=[{"Br": [0.1, 0.0, 0.0], "region": "tip"}] * 2), "magnets[1]", "repeats magnets[0]"),
    ("a magnet on clamped elements only", with_(loads=[], regions={"root": {"box": {"x": [0.0, 2.5]}},
                                                                    "tip": {"box": {"x": [7.5, 10.0]}}},
                                                supports=[{"type": "clamp", "region": "root"}],
                                                fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}},
                                                magnets=[{"Br": [0.1, 0.0, 0.0], "region": "root"},
                                                         {"Br": [0.1, 0.0, 0.0], "region": "tip"}]),
     "magnets[0]", "it acts only on dofs that supports[0] hold"),
    # an element has one remanent magnetisation: two magnets of one field on it would add
    ("two magnetisations of one region", with_(loads=[], regions={"tip": {"box": {"x": [7.5, 10.0]}}},
                                               fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}},
                                               magnets=[{"Br": [0.1, 0.0, 0.0], "region": "tip"},
                                                        {"Br": [-0.1, 0.0, 0.0], "region": "tip"}]),
     "magnets[1]", "magnets[0] and magnets[1] have common elements: 1, for field 'c'"),
    ("a whole-shell magnet beside a region's", with_(loads=[], regions={"tip": {"box": {"x": [7.5, 10.0]}}},
                                                     fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}},
                                                     magnets=[{"Br": [0.1, 0.0, 0.0]},
                                                              {"Br": [0.0, 0.1, 0.0], "region": "tip"}]),
     "magnets[1]", "common elements: 1 (a magnet without 'region' magnetises the whole shell)"),
]


@pytest.mark.parametrize("name,d,key,fragment", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_refused_by_name(name, d, key, fragment):
    with pytest.raises(ScenarioError) as ei:
        load(d)
    assert ei.value.key == key, (ei.value.key, str(ei.value))
    assert fragment in str(ei.value), str(ei.value)
    assert str(ei.value).startswith("adv.toml: ")


def test_the_battery_holds_forty_new_kinds():
    assert len(CASES) + len(FILE_CASES) + len(CHECKPOINT_CASES) + 6 >= 40


def test_command_line_contradictions_are_one_error_line(tmp_path, capsys):
    from core_se3 import cli
    path = tmp_path / "s.toml"
    path.write_text(scenario.dumps(with_(units=None)))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "o"), "--resume", "--force"]) == 2
    assert "give one of them" in capsys.readouterr().err
    assert cli.main(["sweep", str(path), "--set", "material.E=1e6", "--set", "material.E=2e6",
                     "--out", str(tmp_path / "w")]) == 2
    assert "--set material.E is given twice" in capsys.readouterr().err


# ----------------------------------------------------------------------------- input files
def _files(tmp_path):
    (tmp_path / "big.msh").write_bytes(b"")
    os.truncate(tmp_path / "big.msh", 2 ** 30 + 1)            # sparse: 1 GiB and a byte
    (tmp_path / "garbage.msh").write_text("$MeshFormat\nPRIVATE-KEY-LINE 4.1\n")
    (tmp_path / "garbage.vtu").write_text("<VTKFile type='PRIVATE-KEY-LINE'></VTKFile>\n")
    (tmp_path / "header.csv").write_text("PRIVATE-KEY-LINE,a,b,c\n")
    os.mkfifo(tmp_path / "pipe.csv")
    (tmp_path / "dir.msh").mkdir()


MAG = dict(fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}}, loads=[])
FILE_CASES = [
    ("mesh file of more than 1 GiB", with_(mesh={"file": "big.msh"}), "mesh.file", "more than the 1024 MiB"),
    ("mesh file that is a directory", with_(mesh={"file": "dir.msh"}), "mesh.file", "is not a regular file"),
    ("mesh file with garbage after its first line", with_(mesh={"file": "garbage.msh"}), "mesh.file", "cannot read mesh file"),
    ("vtu file with a foreign root", with_(mesh={"file": "garbage.vtu"}), "mesh.file", "cannot read mesh file"),
    ("magnetisation table with a foreign header", with_(magnets=[{"Br_file": "header.csv"}], **MAG), "magnets[0].Br_file",
     "its first row has 4 fields"),
    ("magnetisation table that is a pipe", with_(magnets=[{"Br_file": "pipe.csv"}], **MAG), "magnets[0].Br_file",
     "is not a regular file"),
]


@pytest.mark.parametrize("name,d,key,fragment", FILE_CASES, ids=[c[0] for c in FILE_CASES])
def test_bad_input_files_are_refused_without_their_contents(tmp_path, name, d, key, fragment):
    _files(tmp_path)
    with pytest.raises(ScenarioError) as ei:
        load(d, base_dir=str(tmp_path))
    assert ei.value.key == key and fragment in str(ei.value), str(ei.value)
    assert "PRIVATE" not in str(ei.value)


def test_a_scenario_file_of_more_than_16_MiB_is_refused(tmp_path):
    p = tmp_path / "huge.toml"
    p.write_bytes(b"")
    os.truncate(p, 16 * 2 ** 20 + 1)
    with pytest.raises(ScenarioError, match="more than the 16 MiB a scenario file may have"):
        scenario.load(p)


# ----------------------------------------------------------------------------- checkpoints
def _edit(st, **kw):
    return {**st, **kw}


CHECKPOINT_CASES = [
    ("frames of another node count", lambda st: _edit(st, g=st["g"][:-2]), "its frames g have shape (8, 4, 4)"),
    ("frames with a NaN", lambda st: _edit(st, g=np.where(np.arange(160).reshape(10, 4, 4) == 7, np.nan, st["g"])),
     "not finite proper rigid motions"),
    ("frames of a reflection", lambda st: _edit(st, g=st["g"] * np.diag([1.0, 1.0, -1.0, 1.0])),
     "not finite proper rigid motions"),
    ("a load factor that is not the last record's", lambda st: _edit(st, lam=0.25), "its load factor 0.25"),
    ("a step that is not the last record's", lambda st: _edit(st, step=1), "its step 1 is not that of its last record (2)"),
    ("records that skip a step", lambda st: _edit(st, records=[st["records"][0], st["records"][2]]),
     "its records are numbered [0, 2]"),
    ("no records", lambda st: _edit(st, records=[]), "it holds no step records"),
    ("a record without its load factor",
     lambda st: _edit(st, records=st["records"][:-1] + [{k: v for k, v in st["records"][-1].items() if k != "load_factor"}]),
     "lacks its step number or load factor"),
    ("probes of another scenario", lambda st: _edit(st, unwrap={"elsewhere": np.zeros(3)}), "its probe rotations"),
    ("timings that are not numbers", lambda st: _edit(st, timings={"solve": "fast"}), "its timings are not numbers"),
    ("a solver state at another load factor",
     lambda st: _edit(st, extra=dict(st["extra"], newton=dict(st["extra"]["newton"], lam=0.5))),
     "its solver state is at load factor 0.5, its frames at 1.0"),
]


@pytest.mark.parametrize("name,edit,fragment", CHECKPOINT_CASES, ids=[c[0] for c in CHECKPOINT_CASES])
def test_an_edited_checkpoint_is_refused(tmp_path, name, edit, fragment):
    scn = load(with_(units=None))
    out = str(tmp_path / "o")
    runner.run(scn, out=out)
    st = edit(Checkpoint(out).load())
    Checkpoint(out).save(st["fingerprint"], st)
    with pytest.raises(CheckpointError) as ei:
        runner.run(scn, out=out, resume=True)
    assert fragment in str(ei.value) and out in str(ei.value), str(ei.value)


# ----------------------------------------------------------------------------- output directories
def test_a_damaged_manifest_is_refused(tmp_path):
    (tmp_path / ".core-se3-manifest.json").write_text("{not json")
    with pytest.raises(RunDirectoryError, match="is damaged"):
        RunDirectory(tmp_path).claim(force=True)


def test_a_manifest_that_lists_files_outside_is_refused(tmp_path):
    (tmp_path / ".core-se3-manifest.json").write_text('{"tool": "core-se3", "files": ["../../etc/passwd"]}')
    with pytest.raises(RunDirectoryError, match="is damaged"):
        RunDirectory(tmp_path).claim(force=True)


def test_a_sweep_neither_continues_nor_deletes_a_runs_directory(tmp_path):
    """A sweep given a run's --out was refused as holding 'the files of an earlier sweep
    (checkpoint.npz, results.json, ...)' and advised --force, which deleted the run's results.json,
    checkpoint and VTU files.  Now a directory of another kind's files is refused naming that kind,
    with --resume and --force too; the same kind goes on as before."""
    scn = load(with_(units=None, solver={"steps": 1}))
    out = str(tmp_path / "o")
    scenario.run(scn, out=out)
    before = sorted(os.listdir(out))
    for kw in ({}, {"force": True}, {"resume": True}):
        with pytest.raises(RunDirectoryError, match=r"holds the files of a run \(checkpoint.npz, results.json.*not of a "
                                                   r"sweep: a sweep neither continues \(--resume\) nor deletes"):
            scenario.sweep(scn, {"material.E": [1e6]}, out=out, plot=False, **kw)
    assert sorted(os.listdir(out)) == before and os.path.exists(os.path.join(out, "results.json"))
    with RunDirectory(str(tmp_path / "sw"), "sweep").claim() as rd:
        open(rd.file("sweep.csv"), "w").close()
    with pytest.raises(RunDirectoryError, match=r"holds the files of a sweep \(sweep.csv\), not of a run"):
        RunDirectory(str(tmp_path / "sw"), "run").claim(resume=True)
    RunDirectory(out, "run").claim(force=True).release()          # the same kind starts over


def test_output_dir_gives_a_sweep_a_directory_of_its_own(tmp_path):
    """With [output] dir a run, a sweep and a design of the scenario all took that directory (out/NAME
    gets -sweep, -design): the sweep met the run's files (and its --force deleted them).  Now the
    sweep's and the design's are DIR-sweep and DIR-design, as out/NAME-sweep."""
    scn = load(with_(units=None, solver={"steps": 1}, output={"dir": str(tmp_path / "res"), "plots": False,
                                                                 "picture": False}))
    assert [runner.output_directory(scn, suffix=x) for x in ("", "-sweep", "-design")] == \
        [str(tmp_path / "res"), str(tmp_path / "res-sweep"), str(tmp_path / "res-design")]
    scenario.run(scn)
    res = scenario.sweep(scn, {"material.E": [1e6]}, plot=False)
    assert os.path.dirname(res.files["csv"]) == str(tmp_path / "res-sweep")
    assert os.path.exists(tmp_path / "res" / "results.json")
    here = load(with_(units=None, output={"dir": "."}))
    assert runner.output_directory(here) == "." and runner.output_directory(here, suffix="-sweep") == os.path.join(".", "sweep")


def test_a_directory_in_use_is_refused_naming_the_process(tmp_path):
    with RunDirectory(tmp_path, "run").claim():
        with pytest.raises(RunDirectoryError, match=rf"in use by another live run \(a run of process {os.getpid()}"):
            RunDirectory(tmp_path, "run").claim(force=True)
    RunDirectory(tmp_path, "run").claim(resume=True).release()       # the lock went with its holder


def test_a_sweep_resumed_with_other_values_is_refused(tmp_path):
    scn = load(with_(units=None, loads=[{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]))
    scenario.sweep(scn, {"material.E": [1e6, 2e6]}, out=str(tmp_path / "s"), plot=False)
    with pytest.raises(CheckpointError, match="belongs to another sweep"):
        scenario.sweep(scn, {"material.E": [1e6, 3e6]}, out=str(tmp_path / "s"), plot=False, resume=True)


def test_a_sweep_resumed_with_other_load_steps_is_refused(tmp_path):
    """The sweep's checkpoint took the scenario's fingerprint, which leaves out steps, lam_end and
    load_factors (a run may be extended on --resume): a sweep resumed with lam_end = 2 kept its
    rows at lam_end = 1 as complete (test_cli_run's strip: tip.uz 5.419 at E = 1e6 reported, 7.030
    the answer at lam_end = 2).  Now the load factors are part of the sweep's checkpoint."""
    scn = load(with_(units=None, solver={"steps": 2}))
    out = str(tmp_path / "s")
    first = scenario.sweep(scn, {"material.E": [1e6]}, out=out, plot=False).rows
    assert scenario.sweep(scn, {"material.E": [1e6]}, out=out, plot=False, resume=True).rows == first
    for solver in ({"steps": 4, "lam_end": 2.0}, {"steps": 3}, {"load_factors": [0.5, 1.5]}):
        other = load(with_(units=None, solver=solver))
        with pytest.raises(CheckpointError, match="belongs to another sweep .*its load steps"):
            scenario.sweep(other, {"material.E": [1e6]}, out=out, plot=False, resume=True)


def test_documented_behaviours():
    """Names that would leave out/ stay under it; unit defaults; Python selections refuse repeats."""
    assert runner.output_directory(load(with_(name="/tmp/x"))) == os.path.join("out", "_tmp_x")
    assert load(with_(units="N-mm-MPa", material={"E": 1.0, "nu": 0.3, "h": 0.5, "rho": 1e-9},
                      loads=[{"type": "gravity"}])).spec["loads"][0]["g"] == [0.0, 0.0, -9810.0]
    p = Problem(M.rectangle(1.0, 1.0, 2, 1), Material(1e3, 0.0, 0.01))
    with pytest.raises(CoreSE3Error, match="lists node 2 2 times"):
        p.clamp([2, 2])

"""The scenario front door's leftovers of the last review: ``run --check`` of a [sweep], ``sweep
--resume`` where there is nothing to resume, and the findings of an adversarial pass over the
TOML front door; each test fails on the code before its fix.  (A magnet in a zero applied field:
tests/test_magnetics.py; the residual's force and moment parts: tests/test_result_outputs.py.)
"""
import copy
import csv
import json
import os
import warnings

import pytest

from core_se3 import cli, scenario
from core_se3.errors import CheckpointError, ScenarioError

QUIET = {"vtu": False, "plots": False, "picture": False}
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "edges": {"mid": {"box": {"x": [5.0, 5.0]}}},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}],
         "probes": [{"name": "mid", "edge": "mid"}], "solver": {"steps": 1}, "output": dict(QUIET)}


def doc(**sections):
    d = copy.deepcopy(STRIP)
    d.update(copy.deepcopy(sections))
    return d


def write(tmp_path, d, name="s.toml"):
    p = tmp_path / name
    p.write_text(scenario.dumps(d))
    return str(p)


def load(d):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file="s.toml")


# ================================================================== (a) run --check of a [sweep]
def test_run_check_validates_every_sweep_value(tmp_path, capsys):
    """``run --check`` passed (exit 0, 'valid') a [sweep] whose second value of material.nu is 0.7,
    which ``core-se3 sweep`` then refused; now --check refuses it with the sweep's message."""
    path = write(tmp_path, doc(sweep={"material.nu": [0.3, 0.7]}))
    assert cli.main(["run", path, "--check", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == (f"error: {path}: [sweep.material.nu]: the swept value 0.7 of material.nu: expected a "
                           "number < 0.5, got 0.7")
    assert cli.main(["sweep", path, "--out", str(tmp_path / "sw"), "-q"]) == 2      # the sweep's own verdict
    assert capsys.readouterr().err == err and not os.path.exists(tmp_path / "sw")


def test_run_check_and_sweep_validate_every_point_of_the_grid(tmp_path, capsys):
    """Values valid one by one may not be together: nx = 2 has no node at x = 2.5.  --check passed
    it, and the sweep ran three of its four points, then stopped with '[edges.mid]: selects no
    nodes' (no point named), sweep.json left 'running' with 'rows': 0 beside a CSV of 3 rows.
    Now both refuse the point before anything runs, naming it."""
    path = write(tmp_path, doc(sweep={"mesh.nx": [4, 2], "edges.mid.box.x": [[5.0, 5.0], [2.5, 2.5]]}))
    msg = (f"error: {path}: [sweep]: the swept point mesh.nx = 2, edges.mid.box.x = [2.5, 2.5]: [edges.mid]: "
           "selects no nodes")
    assert cli.main(["run", path, "--check", "-q"]) == 2
    assert capsys.readouterr().err.strip() == msg
    assert cli.main(["sweep", path, "--out", str(tmp_path / "sw"), "-q"]) == 2
    assert capsys.readouterr().err.strip() == msg and not os.path.exists(tmp_path / "sw")
    with pytest.raises(ScenarioError, match=r"\[--set\]: the swept point mesh.nx = 2, edges.mid.box.x"):
        scenario.check_sweep(load(doc()), {"mesh.nx": [4, 2], "edges.mid.box.x": [[5.0, 5.0], [2.5, 2.5]]})


def test_run_check_of_a_valid_sweep_says_its_points(tmp_path, capsys):
    path = write(tmp_path, doc(sweep={"mesh.nx": [4, 8], "material.E": [1e6, 2e6, 3e6]}))
    assert cli.main(["run", path, "--check"]) == 0
    assert "sweep: 6 point(s) of mesh.nx, material.E valid" in capsys.readouterr().out
    grid, points = scenario.check_sweep(load(doc(sweep={"mesh.nx": [4, 8], "material.E": [1e6, 2e6, 3e6]})))
    assert list(grid) == ["mesh.nx", "material.E"] and len(points) == 6 and points[1] == (4, 2e6)


# ================================================================== (b) --resume with nothing to resume
def test_sweep_resume_where_there_is_no_sweep_is_refused(tmp_path, capsys):
    """``sweep --resume`` into a directory that does not exist, or holds no sweep, started a fresh
    sweep silently (exit 0: a misspelt --out ran the whole grid again, elsewhere); ``run --resume``
    refused, but created the directory (and, in a user's directory, left its manifest there).  Now
    both refuse, naming the directory, and create nothing."""
    path = write(tmp_path, doc())
    for cmd, extra in (("run", []), ("sweep", ["--set", "material.E=1e6,2e6"])):
        new = tmp_path / f"new-{cmd}"
        assert cli.main([cmd, path, "--resume", "--out", str(new), "-q", *extra]) == 2
        err = capsys.readouterr().err
        assert f"nothing to resume: --out '{new}' does not exist (no earlier {cmd} there)" in err, err
        assert not os.path.exists(new)
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cli.main(["sweep", path, "--resume", "--out", str(empty), "-q", "--set", "material.E=1e6,2e6"]) == 2
    assert f"nothing to resume: {empty} holds no sweep" in capsys.readouterr().err
    assert not os.path.exists(empty / "sweep.csv")
    mine = tmp_path / "mine"                   # a user's directory: --resume by mistake left a manifest there
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    for cmd, extra in (("run", []), ("sweep", ["--set", "material.E=1e6"])):
        assert cli.main([cmd, path, "--resume", "--out", str(mine), "-q", *extra]) == 2
        assert f"nothing to resume: {mine} holds no {cmd} (no file core-se3 wrote)" in capsys.readouterr().err
        assert os.listdir(mine) == ["notes.txt"]
    with pytest.raises(CheckpointError, match="nothing to resume"):
        scenario.sweep(load(doc()), {"material.E": [1e6]}, out=str(tmp_path / "py"), plot=False, resume=True)


def test_sweep_resume_of_a_sweep_stopped_before_its_first_row_starts_over(tmp_path):
    """As a run stopped before its first checkpoint: the earlier sweep's files are there, no
    sweep.npz yet; the resume runs the grid from its first point."""
    from core_se3.io.rundir import RunDirectory
    from core_se3.scenario.sweep_files import SWEEP_FILES
    out = str(tmp_path / "sw")
    with RunDirectory(out, "sweep", SWEEP_FILES).claim() as rd:      # what a sweep killed in its first run left
        with open(rd.file("sweep.json"), "w") as fh:
            json.dump({"status": "running", "rows": 0}, fh)
    res = scenario.sweep(load(doc()), {"material.E": [1e6, 2e6]}, out=out, plot=False, resume=True)
    assert [r["status"] for r in res.rows] == ["complete", "complete"]
    assert len(list(csv.DictReader(open(os.path.join(out, "sweep.csv"))))) == 2


# ================================================================== (e) adversarial pass
def test_a_generators_orientation_in_degrees_warns():
    """A star's ``angle0 = 45`` meant as degrees was read as 45 rad: arm 0 silently at 58.31
    degrees (45 rad modulo a turn).  An orientation needs no more than a turn: now a warning at
    mesh.angle0 (theta0 likewise) saying the radians and where the mesh lands; 0.785 rad says
    nothing and puts the arm at 45 degrees."""
    import numpy as np
    star = {"generator": "star", "n_arms": 4, "arm_length": 10.0, "arm_width": 2.0, "size": 1.0,
            "backend": "structured"}
    said = {}
    for a, where in ((45.0, 58.31), (np.radians(45.0), 45.0)):
        scn = load(doc(mesh=dict(star, angle0=a), edges={}, probes=[], loads=[],
                       supports=[{"type": "clamp", "region": "palm"}]))
        tip = scn.mesh.X[scn.mesh.node_set("tip_0")].mean(0)
        assert np.degrees(np.arctan2(tip[1], tip[0])) == pytest.approx(where, abs=0.01)
        said[a] = [str(w) for w in scn.warnings if "[mesh.angle0]" in str(w)]
    assert said[np.radians(45.0)] == [] and len(said[45.0]) == 1
    assert ("angle0 = 45 rad is more than a turn: it is in radians (45 degrees is 0.785398 rad; 45 rad places the "
            "mesh at 58.31 degrees)") in said[45.0][0]
    sector = {"generator": "annulus_sector", "r_in": 1.0, "r_out": 2.0, "angle": 1.0, "size": 0.5, "theta0": 30.0,
              "backend": "structured"}
    assert any("[mesh.theta0]" in str(w) for w in load(doc(mesh=sector, edges={}, probes=[], loads=[],
                                                             supports=[{"type": "clamp", "edge": "start"}])).warnings)


def test_a_generators_refused_value_is_named_at_its_key():
    """An arch of angle = 90 (degrees meant) was refused at [mesh] with 'cylinder_arch: cylinder_arch:
    angle must be ...' (the generator said twice, the key not named); now at mesh.angle, once."""
    arch = {"generator": "cylinder_arch", "R": 5.0, "angle": 90.0, "width": 1.0, "nx": 8, "ny": 1}
    with pytest.raises(ScenarioError) as ei:
        load(doc(mesh=arch, edges={}, probes=[]))
    assert ei.value.key == "mesh.angle" and str(ei.value).count("cylinder_arch") == 1
    assert "got 90 (1.5708 if 90 is in degrees)" in str(ei.value)


def test_an_empty_input_file_is_refused_as_empty(tmp_path):
    """An empty mesh file (a Gmsh export not yet saved) failed with meshio's bare NumPy message
    'cannot read mesh file 'empty.msh': ValueError: need at least one array to concatenate'; now
    each input file (mesh, magnetisation table, scenario) that is empty says so, at its key."""
    (tmp_path / "empty.msh").write_bytes(b"")
    (tmp_path / "empty.csv").write_bytes(b"")
    (tmp_path / "empty.toml").write_bytes(b"")
    cases = [(doc(mesh={"file": "empty.msh"}, edges={}, probes=[], loads=[]), "mesh.file"),
             (doc(units="SI", fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}},
                  magnets=[{"Br_file": "empty.csv"}]), "magnets[0].Br_file")]
    for d, key in cases:
        with pytest.raises(ScenarioError) as ei:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                scenario.from_dict(d, file=str(tmp_path / "s.toml"), base_dir=str(tmp_path))
        assert ei.value.key == key and "is empty (0 bytes)" in str(ei.value), str(ei.value)
        assert "concatenate" not in str(ei.value)
    with pytest.raises(ScenarioError, match=r"is empty \(0 bytes\)"):
        scenario.load(tmp_path / "empty.toml")


def test_a_resume_whose_checkpoint_was_deleted_keeps_the_runs_results(tmp_path, capsys):
    """A finished run whose checkpoint.npz was deleted (it is the large file: to save space) was
    started over by --resume without a word (exit 0): every step solved again, its results.json
    and VTU files replaced -- and, the scenario's check being the checkpoint's, by those of an
    edited scenario too (E doubled: tip uz 2.975 replaced by 1.597, no --force asked).  Now
    refused, naming the steps that would be lost; --force starts over as asked; a run stopped
    before its first checkpoint (no step recorded) still starts over."""
    path = write(tmp_path, doc(solver={"steps": 2}))
    out = tmp_path / "o"
    assert cli.main(["run", path, "--out", str(out), "-q"]) == 0
    (out / "checkpoint.npz").unlink()
    before = (out / "results.json").read_bytes()
    assert cli.main(["run", path, "--out", str(out), "--resume", "-q"]) == 2
    err = capsys.readouterr().err
    assert "checkpoint.npz is missing, but" in err and "records 2 converged step(s) to load factor 1 (status " \
                                                     "'complete')" in err, err
    assert (out / "results.json").read_bytes() == before
    assert cli.main(["run", path, "--out", str(out), "--force", "-q"]) == 0
    assert json.loads((out / "results.json").read_text())["status"] == "complete"


def test_a_sweep_resume_whose_checkpoint_was_deleted_keeps_its_rows(tmp_path):
    """As a run's: sweep.csv with 2 finished rows, sweep.npz deleted: the resume started over
    silently, ran every point again and rewrote sweep.csv (whatever the scenario had become: the
    checkpoint holds the check); now refused, the CSV kept."""
    out = str(tmp_path / "sw")
    scenario.sweep(load(doc()), {"material.E": [1e6, 2e6]}, out=out, plot=False)
    os.unlink(os.path.join(out, "sweep.npz"))
    before = open(os.path.join(out, "sweep.csv")).read()
    with pytest.raises(CheckpointError, match=r"sweep.npz is missing, but sweep.csv holds 2 finished row\(s\)"):
        scenario.sweep(load(doc()), {"material.E": [1e6, 2e6]}, out=out, plot=False, resume=True)
    assert open(os.path.join(out, "sweep.csv")).read() == before


@pytest.mark.parametrize("angle,said", [(45.0, True), (30.0, True), (60.0, True), (2 * 3.141592653589793, False),
                                        (4 * 3.141592653589793, False)])
def test_a_rotation_angle_in_degrees_warns_below_ten_turns(angle, said):
    """A support's ``angle = 45`` meant as degrees is 7.2 turns in radians (30: 4.8, 60: 9.5): the
    warning began at ten turns, so these common degree values turned the edge silently.  Now at
    three turns; one or two turns (a roll-up) say nothing."""
    d = doc(supports=[{"type": "clamp", "edge": "x0"},
                      {"type": "rotate", "edge": "x1", "axis": [1.0, 0.0, 0.0], "angle": angle, "free": ["x"]}],
            loads=[], edges={}, probes=[])
    hits = [str(w) for w in load(d).warnings if "[supports[1].angle]" in str(w) and "radians" in str(w)]
    assert bool(hits) == said, hits


def test_a_sweep_interrupted_before_its_first_row_does_not_advise_resume(tmp_path, capsys, monkeypatch):
    """Ctrl-C while a sweep validated its grid (many points of a large mesh take a while) said
    'the finished runs are in sweep.csv (sweep.json says where it stopped): continue with
    --resume' -- there was no sweep.csv, and --resume finds nothing to continue.  Now it says so;
    after a finished row the advice is --resume, as before."""
    import sys
    sw = sys.modules["core_se3.scenario.sweep"]        # (scenario.sweep is the function)
    path = write(tmp_path, doc())
    real = sw._check_values

    def stop(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr(sw, "_check_values", stop)
    assert cli.main(["sweep", path, "--set", "material.E=1e6,2e6", "--out", str(tmp_path / "sw"), "-q"]) == 130
    err = capsys.readouterr().err
    assert "stopped before its first finished run: nothing to continue" in err and "--resume" not in \
        err.replace("without --resume", ""), err
    monkeypatch.setattr(sw, "_check_values", real)
    calls = []

    def second(*a, **k):
        if calls:
            raise KeyboardInterrupt
        calls.append(1)
        return sw_point_row(*a, **k)
    sw_point_row = sw.point_row
    monkeypatch.setattr(sw, "point_row", second)
    assert cli.main(["sweep", path, "--set", "material.E=1e6,2e6", "--out", str(tmp_path / "sw2"), "-q"]) == 130
    assert "continue with --resume" in capsys.readouterr().err
    monkeypatch.setattr(sw, "point_row", sw_point_row)
    assert cli.main(["sweep", path, "--set", "material.E=1e6,2e6", "--out", str(tmp_path / "sw2"), "-q",
                     "--resume"]) == 0


def test_an_integer_beyond_64_bits_is_refused_naming_its_key(tmp_path, capsys):
    """TOML's integers are 64-bit, Python's reader keeps any length: ``E = 1`` and 400 zeros (a
    stuck key) stopped ``run --check`` with a traceback, 'OverflowError: int too large to convert
    to float'.  Now an error at material.E (exit 2); a vector's entry, a --set value too."""
    text = scenario.dumps(doc()).replace("E = 1200000.0", "E = 1" + "0" * 400)
    assert "E = 1000" in text
    (tmp_path / "big.toml").write_text(text)
    assert cli.main(["run", str(tmp_path / "big.toml"), "--check"]) == 2
    assert "[material.E]: an integer of 401 digits, beyond TOML's 64-bit integers" in capsys.readouterr().err
    with pytest.raises(ScenarioError) as ei:
        load(doc(loads=[{"type": "edge_force", "edge": "x1", "force": [0, 0, 10 ** 30]}]))
    assert ei.value.key == "loads[0].force[2]"
    assert cli.main(["sweep", write(tmp_path, doc()), "--set", "material.E=1" + "0" * 30, "--out",
                     str(tmp_path / "sw"), "-q"]) == 2
    assert "beyond TOML's 64-bit integers" in capsys.readouterr().err


def test_a_refused_sweep_resume_leaves_the_earlier_status_alone(tmp_path):
    """``sweep --resume`` with other values is refused (its checkpoint belongs to another
    sweep), but it had first rewritten the earlier sweep's sweep.json: 'complete', 2 rows became
    'running', 0 rows, with no process running.  Now the checkpoint is read first."""
    out = str(tmp_path / "sw")
    scenario.sweep(load(doc()), {"material.E": [1e6, 2e6]}, out=out, plot=False)
    before = open(os.path.join(out, "sweep.json")).read()
    with pytest.raises(CheckpointError, match="belongs to another sweep"):
        scenario.sweep(load(doc()), {"material.E": [1e6, 3e6]}, out=out, plot=False, resume=True)
    assert open(os.path.join(out, "sweep.json")).read() == before


def test_a_sweep_stopped_by_an_error_says_failed_not_running(tmp_path, monkeypatch):
    """An error no point catches (a full disk writing sweep.csv, a MemoryError) left sweep.json
    'running' with 0 rows for ever; now 'failed', the error named, the finished row counted."""
    import sys
    sw = sys.modules["core_se3.scenario.sweep"]
    real, calls = sw.point_row, []

    def second(*a, **k):
        if calls:
            raise MemoryError("no room")
        calls.append(1)
        return real(*a, **k)
    monkeypatch.setattr(sw, "point_row", second)
    out = str(tmp_path / "sw")
    with pytest.raises(MemoryError):
        scenario.sweep(load(doc()), {"material.E": [1e6, 2e6]}, out=out, plot=False)
    status = json.load(open(os.path.join(out, "sweep.json")))
    assert status["status"] == "failed" and status["rows"] == 1
    assert "failed after 1 of 2 runs: MemoryError: no room" in status["error"]


def test_a_hemisphere_hole_in_radians_warns():
    """``hole_deg`` is the one generator angle in degrees: 0.314 (the benchmark's 18 degrees given
    in radians) made a 0.3-degree hole, its elements 190 times longer than wide, silently.  Now a
    warning at mesh.hole_deg below a degree; the benchmark's 18 says nothing."""
    import numpy as np
    hits = {}
    for hole, aspect in ((0.3, 190.36), (18.0, 2.595)):
        scn = load(doc(mesh={"generator": "hemisphere_quarter", "R": 10.0, "hole_deg": hole, "nt": 4, "nf": 4},
                       edges={}, probes=[], loads=[]))
        X = scn.mesh.X[scn.mesh.quads]
        a, b = (np.linalg.norm(X[:, k] - X[:, 0], axis=1) for k in (1, 3))
        assert (np.maximum(a, b) / np.minimum(a, b)).max() == pytest.approx(aspect, rel=1e-3)
        hits[hole] = [str(w) for w in scn.warnings if "[mesh.hole_deg]" in str(w)]
    assert hits[18.0] == [] and len(hits[0.3]) == 1 and "0.3 rad is 17.19 degrees" in hits[0.3][0]


@pytest.mark.parametrize("cmd", ["run", "sweep", "check-mesh"])
def test_ctrl_c_while_a_scenario_is_read_is_one_line(tmp_path, capsys, monkeypatch, cmd):
    """Ctrl-C while a scenario was read and validated (a large mesh file, a refinement, a sweep's
    grid) ended ``run``, ``sweep`` and ``check-mesh`` with a Python traceback; now one line and
    exit status 130, as an interrupted run's, saying that nothing was written."""
    from core_se3.cli import scenario as cs

    def stop(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr(cs, "_load_quietly", stop)
    path = write(tmp_path, doc())
    extra = {"run": [], "sweep": ["--set", "material.E=1e6"], "check-mesh": []}[cmd]
    assert cli.main([cmd, path, *extra]) == 130
    err = capsys.readouterr().err
    said = "the check stopped after 0 mesh(es)" if cmd == "check-mesh" else \
        "it stopped while reading and checking the scenario: nothing was written"
    assert f"interrupted (SIGINT): {said}" in err and "Traceback" not in err


def test_a_users_files_in_a_linked_folder_are_never_overwritten(tmp_path):
    """``vtu`` a link to a user's folder holding step_0001.vtu ('MY DATA'): the directory's walk
    did not enter linked folders, so the claim saw no foreign file and the run -- even with
    --force, which promises never to overwrite one -- replaced the user's file by its VTU.  Now
    the walk enters linked folders (each real folder once: a link back to an ancestor does not
    loop), the run is refused, and a file this tool did not write found at a name it is about to
    write (one put there during the run) is refused too."""
    from core_se3.errors import CheckpointError as RunDirError
    from core_se3.io.rundir import RunDirectory
    user = tmp_path / "user"
    user.mkdir()
    (user / "step_0001.vtu").write_text("MY DATA")
    out = tmp_path / "o"
    out.mkdir()
    os.symlink(user, out / "vtu")
    os.symlink(out, user / "back")                   # a loop through the link
    path = write(tmp_path, doc(output={"vtu": True, "plots": False, "picture": False}, solver={"steps": 2}))
    for extra in ([], ["--force"]):
        assert cli.main(["run", path, "--out", str(out), "-q", *extra]) == 2
        assert (user / "step_0001.vtu").read_text() == "MY DATA"
    with RunDirectory(str(tmp_path / "r"), "run").claim() as rd:
        (tmp_path / "r" / "results.json").write_text("the user's, put there during the run")
        with pytest.raises(RunDirError, match="holds results.json, which core-se3 did not write"):
            rd.file("results.json")
    assert (tmp_path / "r" / "results.json").read_text() == "the user's, put there during the run"


def test_the_walk_enters_only_the_linked_folders_a_run_writes(tmp_path):
    """The walk that finds the user's files follows a link only into a folder the run writes
    (vtu), not into a linked data set beside the run (it would list every file of it)."""
    from core_se3.io.rundir import RunDirectory
    from core_se3.scenario.sinks import RUN_FILES
    data = tmp_path / "data"
    (data / "deep").mkdir(parents=True)
    (data / "deep" / "x.bin").write_text("")
    out = tmp_path / "o"
    out.mkdir()
    os.symlink(data, out / "dataset")
    os.symlink(data, out / "vtu")
    rd = RunDirectory(str(out), "run", RUN_FILES)
    assert rd._walk() == [os.path.join("vtu", "deep", "x.bin")]
    assert rd._written_in("vtu") and not rd._written_in("dataset") and not rd._written_in("vtu/deep")


@pytest.mark.parametrize("solver,said", [({"control": "linear"}, "a linear analysis at load factor 1)"),
                                         ({"load_factors": [0.25, 0.5, 1.5]}, "3 steps to load factor 1.5)"),
                                         ({"steps": 4, "lam_end": 2.0}, "4 steps to load factor 2)")])
def test_run_check_states_the_solve_it_validated(tmp_path, capsys, solver, said):
    """--check's summary gave '[solver] steps' whatever the solve: '10 steps' (the default of an
    unused key) for a linear analysis, and for explicit load_factors; now the solve itself."""
    path = write(tmp_path, doc(solver=solver))
    assert cli.main(["run", path, "--check", "-q"]) == 0
    assert said in capsys.readouterr().out

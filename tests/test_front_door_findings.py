"""The front door loses nothing and misapplies nothing (issue 34): one test per finding of the
adversarial battery behind the issue -- the wrong answers and lost data (W), the crashes (C) and
the unclear messages (U) -- each failing on the code before the issue.  The new kinds of bad
input are in tests/test_adversarial_inputs.py, the run directory and the lifecycle in
tests/test_run_lifecycle.py.
"""
import copy
import csv
import json
import os
import signal
import subprocess
import sys
import time
import warnings

import numpy as np
import pytest

from core_se3 import Material, Problem, cli, mesh as M, scenario
from core_se3.errors import CheckpointError, CoreSE3Error, ScenarioError
from core_se3.io import Checkpoint
from core_se3.scenario import runner

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
QUIET = {"vtu": False, "plots": False, "picture": False}
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
         "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 2}, "output": dict(QUIET)}


def doc(base=STRIP, **sections):
    d = copy.deepcopy(base)
    d.update(copy.deepcopy(sections))
    return d


def load(d, name="s.toml", base_dir="."):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file=name, base_dir=base_dir)


def refused(d, key, *fragments, base_dir="."):
    with pytest.raises(ScenarioError) as ei:
        load(d, base_dir=base_dir)
    assert ei.value.key == key, (ei.value.key, str(ei.value))
    for f in fragments:
        assert f in str(ei.value), (f, str(ei.value))
    return ei.value


def write(tmp_path, d, name="s.toml"):
    p = tmp_path / name
    p.write_text(scenario.dumps(d))
    return str(p)


def env(**extra):
    e = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    e.setdefault("CORE_SE3_BACKEND", "numpy")
    e.update(extra)
    return e


# ================================================================== wrong answers and lost data
def test_W1_a_node_listed_three_times_is_refused_not_loaded_three_times():
    refused(doc(loads=[{"type": "nodal", "nodes": [9, 9, 9], "force": [0.0, 0.0, 1.0]}]), "loads[0].nodes",
            "node 9 is listed 3 times")
    p = Problem(M.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    with pytest.raises(CoreSE3Error, match="lists node 9 3 times"):
        p.add_nodal_load([9, 9, 9], force=(0.0, 0.0, 1.0))


def test_W2_a_clamp_and_a_rotation_of_one_edge_are_refused():
    e = refused(doc(supports=[{"type": "clamp", "edge": "x0"},
                              {"type": "rotate", "edge": "x0", "axis": [1.0, 0.0, 0.0], "angle": 0.1}]),
                "supports[1]", "supports[1] (a prescribed motion) and supports[0] (a clamp) both hold nodes [0, 5]")
    assert "the later one would silently win" in str(e)


def test_W3_two_rotations_of_one_edge_are_refused():
    turn = {"type": "rotate", "edge": "x1", "axis": [1.0, 0.0, 0.0], "angle": 0.1}
    refused(doc(supports=[{"type": "clamp", "edge": "x0"}, turn, dict(turn, angle=0.2)]), "supports[2]",
            "supports[2] (a prescribed motion) and supports[1] (a prescribed motion)")


def test_W4_default_gravity_is_in_the_scenarios_units():
    grav = doc(units="N-mm-MPa", material={"E": 1.0, "nu": 0.45, "h": 0.5, "rho": 1.1e-9},
               loads=[{"type": "gravity"}])
    scn = load(grav)
    assert scn.spec["loads"][0]["g"] == [0.0, 0.0, -9810.0] and not scn.warnings
    explicit = load(doc(grav, loads=[{"type": "gravity", "g": [0.0, 0.0, -9810.0]}]))
    np.testing.assert_array_equal(scn.problem.solve().final.g, explicit.problem.solve().final.g)
    si = load(doc(grav, units="SI", material={"E": 1e6, "nu": 0.45, "h": 0.0005, "rho": 1100.0}))
    assert si.spec["loads"][0]["g"] == [0.0, 0.0, -9.81]
    refused(doc(grav, units="consistent"), "loads[0].g", 'with units = "consistent" gravity needs')


def test_W5_a_new_run_never_deletes_the_users_vtu_files(tmp_path):
    out = tmp_path / "o"
    (out / "vtu").mkdir(parents=True)
    (out / "vtu" / "step_0001.vtu").write_text("the user's own")
    path = write(tmp_path, doc(output={"vtu": True, "plots": False, "picture": False}))
    assert cli.main(["run", path, "--out", str(out), "-q"]) == 2              # foreign files: refused
    assert cli.main(["run", path, "--out", str(out), "-q", "--force"]) == 2   # --force never overwrites them
    assert (out / "vtu" / "step_0001.vtu").read_text() == "the user's own"


def test_W6_the_users_dot_files_with_tmp_in_their_name_are_kept(tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    (out / ".draft.tmp.txt").write_text("keep")
    (out / ".results.json.tmp").write_text("keep too")
    path = write(tmp_path, doc())
    assert cli.main(["run", path, "--out", str(out), "-q", "--force"]) == 0      # beside foreign files
    assert cli.main(["run", path, "--out", str(out), "-q", "--force"]) == 0      # over its own earlier run
    assert (out / ".draft.tmp.txt").read_text() == "keep" and (out / ".results.json.tmp").read_text() == "keep too"


def test_W7_two_runs_on_one_directory_do_not_mix(tmp_path):
    path = write(tmp_path, doc(solver={"steps": 40}))
    out = str(tmp_path / "o")
    cmd = [sys.executable, "-m", "core_se3", "run", path, "--out", out, "-q"]
    procs = [subprocess.Popen(cmd, env=env(), stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    codes = sorted(c for c, _ in results)
    assert codes == [0, 2], results
    loser = next(err for c, err in results if c == 2)
    assert "in use by another live run" in loser or "holds the files of an earlier run" in loser, loser
    final = json.load(open(os.path.join(out, "results.json")))
    assert final["status"] == "complete" and len(final["steps"]) == 41
    assert Checkpoint(out).load(final["fingerprint"])["step"] == 40


def test_W8_a_name_of_dot_dots_stays_under_out(tmp_path):
    path = write(tmp_path, doc(name="../../escaped"))
    work = tmp_path / "work" / "deeper"
    work.mkdir(parents=True)
    r = subprocess.run([sys.executable, "-m", "core_se3", "run", path, "-q"], cwd=work, env=env(),
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(work / "out")) == ["___escaped"]
    assert not (tmp_path / "escaped").exists() and not (tmp_path / "work" / "escaped").exists()
    assert runner.output_directory(load(doc(name="/etc"))) == os.path.join("out", "_etc")


def test_W9_errors_about_input_files_never_show_their_contents(tmp_path):
    secret = "SECRET-LINE-123 do not print"
    for name in ("secret.msh", "secret.vtu", "secret.csv"):
        (tmp_path / name).write_text(secret + "\n$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n" + secret + "\n")
    for f in ("secret.msh", "secret.vtu"):
        e = refused(doc(mesh={"file": f}), "mesh.file", "cannot read mesh file", base_dir=str(tmp_path))
        assert "SECRET" not in str(e)
    mag = doc(units="SI", fields={"c": {"type": "uniform", "B": [0.0, 0.0, 0.01]}}, magnets=[{"Br_file": "secret.csv"}])
    e = refused(mag, "magnets[0].Br_file", "expected the header", base_dir=str(tmp_path))
    assert "SECRET" not in str(e)
    (tmp_path / "rows.csv").write_text("element,Brx,Bry,Brz\n0,SECRET-ROW,0,0\n")
    e = refused(doc(mag, magnets=[{"Br_file": "rows.csv"}]), "magnets[0].Br_file", "row 2 is not four numbers",
                base_dir=str(tmp_path))
    assert "SECRET" not in str(e)


def test_W10_a_sweep_of_an_integer_key(tmp_path, capsys):
    path = write(tmp_path, doc(loads=[{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]))
    assert cli.main(["sweep", path, "--set", "mesh.nx=4,8", "--out", str(tmp_path / "w"), "-q"]) == 0
    rows = list(csv.DictReader(open(tmp_path / "w" / "sweep.csv")))
    assert [r["mesh.nx"] for r in rows] == ["4", "8"] and [r["status"] for r in rows] == ["complete"] * 2
    assert cli.main(["sweep", path, "--set", "mesh.nx=4,8.5", "--out", str(tmp_path / "x"), "-q"]) == 2
    assert "[mesh.nx]: the swept value 8.5 of mesh.nx: expected an integer" in capsys.readouterr().err
    assert not (tmp_path / "x" / "sweep.csv").exists()                  # refused before the first run


def _interrupt_after(monkeypatch, n, exc):
    """Raise ``exc`` in the sweep after its n-th finished run (as a signal would); returns the
    function that undoes it."""
    import importlib
    sw = importlib.import_module("core_se3.scenario.sweep")
    real, count = sw.point_row, [0]

    def point_row(*a, **k):
        if count[0] == n:
            raise exc
        count[0] += 1
        return real(*a, **k)
    monkeypatch.setattr(sw, "point_row", point_row)
    return lambda: monkeypatch.setattr(sw, "point_row", real)


def test_W11_an_interrupted_sweep_keeps_its_finished_rows_and_resumes(tmp_path, monkeypatch, pinned_backend):
    from core_se3.io.lifecycle import Terminated
    scn = load(doc(loads=[{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1e-3]}]))
    grid = {"material.E": [1.0e6, 1.2e6, 1.4e6, 1.6e6]}
    ref = scenario.sweep(scn, grid, out=str(tmp_path / "ref"), plot=False)
    undo = _interrupt_after(monkeypatch, 2, Terminated("SIGTERM"))
    with pytest.raises(Terminated):
        scenario.sweep(scn, grid, out=str(tmp_path / "cut"), plot=False)
    rows = list(csv.DictReader(open(tmp_path / "cut" / "sweep.csv")))
    assert len(rows) == 2
    status = json.load(open(tmp_path / "cut" / "sweep.json"))
    assert status["status"] == "interrupted" and "after 2 of 4 runs" in status["error"]
    undo()
    res = scenario.sweep(scn, grid, out=str(tmp_path / "cut"), plot=False, resume=True)
    assert res.rows == ref.rows                                          # bit for bit
    assert json.load(open(tmp_path / "cut" / "sweep.json"))["status"] == "complete"


def _start(path, out, steps_done, throttled_cli, extra=()):
    args = ["run", path, "--out", out, "-q", *extra]
    cmd = [sys.executable, "-m", "core_se3", *args]
    proc = subprocess.Popen(throttled_cli(args), env=env(),          # the signal lands mid-run
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    ck, t0 = Checkpoint(out), time.time()
    while time.time() - t0 < 120 and proc.poll() is None:
        try:
            if ck.exists() and ck.load()["step"] >= steps_done:
                break
        except CheckpointError:
            pass
        time.sleep(0.005)
    return proc, cmd


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_W12_sigterm_and_ctrl_c_end_a_run_as_interrupted_and_it_resumes_bit_for_bit(tmp_path, sig, pinned_backend,
                                                                                     throttled_cli):
    path = write(tmp_path, doc(solver={"steps": 30}))
    ref = runner.run(load(doc(solver={"steps": 30})), out=str(tmp_path / "ref"))
    out = str(tmp_path / "o")
    proc, cmd = _start(path, out, 3, throttled_cli)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == {signal.SIGTERM: 143, signal.SIGINT: 130}[sig], err
    name = signal.Signals(sig).name
    assert f"interrupted ({name})" in err
    d = json.load(open(os.path.join(out, "results.json")))
    assert d["status"] == "interrupted" and name in d["error"] and "continue with --resume" in d["error"]
    assert Checkpoint(out).load()["step"] == d["steps"][-1]["step"]
    r = subprocess.run(cmd + ["--resume"], env=env(), capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    np.testing.assert_array_equal(Checkpoint(out).load()["g"], ref.g)


def test_W13_the_design_report_describes_the_best_point_not_a_rejected_trial():
    from core_se3.design import Design, LoadMagnitude, Pose, ProbePosition, Target

    def design():
        p = Problem(M.rectangle(10.0, 1.0, 8, 1), Material(1.2e6, 0.0, 0.1))
        p.clamp("x0")
        p.add_edge_force("x1", (0.0, 0.0, 0.1))
        p.add_probe("tip", "x1")
        return Design(p, [LoadMagnitude(p, p.loads[0], lower=0.0)],
                      [Pose("bent", [Target(ProbePosition(p, "tip"), components=[2], value=[1.0])])])
    d = design()
    x1, x2 = np.array([2.0]), np.array([9.0])
    best = d.objective(x1)
    assert d.objective(x2) > best                      # x2: a trial the optimiser rejects
    assert abs(d.misfits(x1)["bent"]["tip"] - design().misfits(x1)["bent"]["tip"]) < 1e-12   # 1.75 before


# ================================================================== crashes
def test_C1_a_checkpoint_of_another_node_count_is_an_error_not_a_traceback(tmp_path):
    out = str(tmp_path / "o")
    scn = load(doc())
    runner.run(scn, out=out)
    st = Checkpoint(out).load()
    Checkpoint(out).save(st["fingerprint"], dict(st, g=st["g"][:-1]))
    with pytest.raises(CheckpointError, match=r"is inconsistent: its frames g have shape \(9, 4, 4\), the mesh has 10"):
        runner.run(scn, out=out, resume=True)


def test_C2_a_scenario_path_of_dev_zero_is_refused_at_once():
    r = subprocess.run([sys.executable, "-m", "core_se3", "run", "/dev/zero", "--check"], env=env(),
                       capture_output=True, text=True, timeout=60)       # read without limit before
    assert r.returncode == 2 and "error: /dev/zero: '/dev/zero' is not a regular file" in r.stderr, r.stderr


def test_C3_a_mesh_file_that_is_a_device_or_a_pipe_is_refused(tmp_path):
    path = write(tmp_path, doc(mesh={"file": "/dev/zero"}))
    r = subprocess.run([sys.executable, "-m", "core_se3", "run", path, "--check"], env=env(),
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "[mesh.file]: '/dev/zero' is not a regular file" in r.stderr, r.stderr
    os.mkfifo(tmp_path / "pipe.msh")
    refused(doc(mesh={"file": "pipe.msh"}), "mesh.file", "is not a regular file", base_dir=str(tmp_path))


# (C4, garbage [solver.petsc] options under mpirun: tests/test_run_lifecycle.py, with the other mpirun runs)


# ================================================================== unclear made clear
def test_U1_a_mesh_of_disconnected_parts_names_the_unsupported_part(tmp_path):
    import meshio
    a = M.rectangle(10.0, 1.0, 4, 1)
    X = np.concatenate([a.X, a.X + [0.0, 3.0, 0.0]])
    meshio.write(tmp_path / "two.vtu", meshio.Mesh(X, [("quad", np.concatenate([a.quads, a.quads + 10]))]))
    two = doc(mesh={"file": "two.vtu"}, edges={"end": {"box": {"x": [0.0, 0.0], "y": [-1.0, 1.0]}}},
              supports=[{"type": "clamp", "edge": "end"}], loads=[], probes=[])
    refused(two, "supports", "the mesh has 2 disconnected parts", "part 2 (4 elements, ids 4..7",
            "between [0.0, 2.5, 0.0] and [10.0, 3.5, 0.0]", base_dir=str(tmp_path))
    both = doc(two, edges={"end": {"box": {"x": [0.0, 0.0]}}})
    assert load(both, base_dir=str(tmp_path)).mesh.n_elements == 8          # each part held: valid


def test_U2_an_empty_box_is_refused():
    refused(doc(edges={"e": {"box": {}}}), "edges.e.box", "an empty box selects every node")
    refused(doc(regions={"r": {"box": {}}}), "regions.r.box", "an empty box")


def test_U3_a_tolerance_of_one_names_the_file_and_the_key():
    refused(doc(solver={"rtol": 1.0}), "solver.rtol", "expected a number < 1")
    refused(doc(solver={"dtol": 1.0}), "solver.dtol", "expected a number < 1")


@pytest.mark.parametrize("edit,message", [
    (lambda st: dict(st, lam=0.7), "its load factor 0.7 is not that of its last record"),
    (lambda st: dict(st, step=5), "its step 5 is not that of its last record (2)"),
    (lambda st: dict(st, records=st["records"][:1] + st["records"][2:]), "its records are numbered [0, 2]"),
    (lambda st: dict(st, unwrap={"tp": np.zeros(3)}), "its probe rotations (['tp']) are not 3-vectors"),
    (lambda st: dict(st, g=st["g"] * 1.5), "its frames g are not finite proper rigid motions"),
])
def test_U4_a_hand_edited_checkpoint_is_checked(tmp_path, edit, message):
    out = str(tmp_path / "o")
    scn = load(doc())
    runner.run(scn, out=out)
    st = edit(Checkpoint(out).load())
    Checkpoint(out).save(st["fingerprint"], st)
    with pytest.raises(CheckpointError) as ei:
        runner.run(scn, out=out, resume=True)
    assert message in str(ei.value) and "edited or damaged" in str(ei.value)


def test_U5_check_estimates_the_memory_and_warns_past_the_machines(tmp_path, capsys, monkeypatch):
    from core_se3.scenario import memory
    path = write(tmp_path, doc(mesh={"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 160, "ny": 160}))
    assert cli.main(["run", path, "--check", "-q"]) == 0
    out = capsys.readouterr()
    assert "memory: about 1.94 GiB" in out.out and "154560 free unknowns" in out.out and "warning" not in out.err
    monkeypatch.setattr(memory, "machine_memory", lambda: 1.0 * 2 ** 30)
    assert cli.main(["run", path, "--check", "-q"]) == 0
    assert "needs about 1.94 GiB, more than this machine's 1 GiB" in capsys.readouterr().err
    # the 1000 x 1000 plate of the finding: ~87 GiB estimated, past this 23 GiB machine
    assert memory.estimate(load(doc(mesh={"generator": "rectangle", "L": 1.0, "width": 1.0, "nx": 300, "ny": 300}),
                                )).bytes > 6e9


CONTACT = doc(mesh={"generator": "rectangle", "L": 1.0, "width": 0.2, "nx": 8, "ny": 1},
              material={"E": 1e4, "nu": 0.0, "h": 0.02},
              loads=[{"type": "pressure", "p": -0.004}],
              obstacles=[{"type": "half_space", "name": "floor", "point": [0.0, 0.0, -0.05], "normal": [0.0, 0.0, 1.0]}],
              solver={"load_factors": [0.7, 1.0]})


def test_U6_the_step_table_and_the_sweep_rows_show_the_contact_forces(tmp_path, capsys):
    path = write(tmp_path, CONTACT)
    assert cli.main(["run", path, "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    head = next(ln for ln in text.splitlines() if ln.lstrip().startswith("step"))
    assert "|F floor|" in head and "contact floor: force (" in text
    final = json.load(open(tmp_path / "o" / "results.json"))["steps"][-1]["contact"]["floor"]
    rows = scenario.sweep(load(CONTACT), {"loads[0].p": [-0.004, -0.005]}, out=str(tmp_path / "w"), plot=False).rows
    assert rows[0]["contact.floor.Fz"] == final["force"][2] > 0 and "contact.floor.nodes_in_contact" in rows[0]


def test_U7_probe_keys_are_the_same_in_python_and_in_results_json(tmp_path):
    scn = load(doc())
    res = runner.run(scn, out=str(tmp_path / "o"))
    py = scn.problem.solve().final.probes["tip"]
    js = json.load(open(tmp_path / "o" / "results.json"))["steps"][-1]["probes"]["tip"]
    assert sorted(py) == sorted(js) == ["rotation", "rotation_angle", "rotation_vector", "u"]
    np.testing.assert_allclose(py["rotation_vector"], js["rotation_vector"], rtol=0, atol=1e-12)
    assert py["w"] is py["rotation_vector"] and py["R"] is py["rotation"]         # the old names still read
    assert res.doc["steps"][-1]["probes"]["tip"]["rotation_angle"] == js["rotation_angle"]


def test_U8_a_prescribed_translation_in_a_scenario_file_moves_rigidly(pinned_backend):
    # two solves compared bit for bit: one backend for both (the "auto" switch could fall between
    # them, depending on the work the process did before: 4.4e-16 after test_adversarial_inputs)
    lift = doc(supports=[{"type": "prescribed", "edge": "x0", "translate": [0.0, 0.0, 2.0]},
                         {"type": "prescribed", "edge": "x1", "translate": [0.0, 0.0, 2.0]}], loads=[])
    res = load(lift).problem.solve()
    np.testing.assert_allclose(res.final.g[:, :3, 3] - load(lift).mesh.X, [[0.0, 0.0, 2.0]] * 10, rtol=0, atol=1e-12)
    turn = doc(supports=[{"type": "clamp", "edge": "x0"},
                         {"type": "prescribed", "edge": "x1", "translate": [0.0, 0.0, 1.0],
                          "rotate": {"axis": [0.0, -1.0, 0.0], "angle": 0.3}}], loads=[])
    scn = load(turn)
    p = Problem(M.rectangle(10.0, 1.0, 4, 1), Material(1.2e6, 0.0, 0.1))
    p.clamp("x0")
    p.move_edge("x1", (0.0, 0.0, 1.0), axis=(0.0, -1.0, 0.0), angle=0.3)
    np.testing.assert_array_equal(scn.problem.solve().final.g, p.solve(steps=2).final.g)
    assert scenario.run(scn, out=None if False else _tmp(), force=True).doc["steps"][-1]["physical"] == {
        "supports[1].translate": {"value": 1.0, "unit": ""}, "supports[1].rotate.angle": {"value": 0.3, "unit": "rad"}}


def _tmp():
    import tempfile
    return tempfile.mkdtemp()


def test_U9_a_node_at_a_point():
    scn = load(doc(loads=[{"type": "nodal", "nodes": {"near": [10.0, 0.5, 0.0]}, "force": [0.0, 0.0, 1.0]}],
                   probes=[{"name": "corner", "nodes": {"near": [[10.0, 0.5, 0.0]]}}]))
    assert scn.spec["loads"][0]["nodes"] == [9] == scn.spec["probes"][0]["nodes"]
    assert scn.problem.node_at((10.0, 0.5, 0.0)) == 9 and scn.problem.node_at((9.9, 0.45, 0.0)) == 9
    refused(doc(loads=[{"type": "nodal", "nodes": {"near": [5.0, 5.0, 0.0]}, "force": [0.0, 0.0, 1.0]}]),
            "loads[0].nodes.near", "no node at [5.0, 5.0, 0.0]: the nearest is node 7")


def test_U10_angle_targets_are_in_degrees_in_and_out(tmp_path):
    sys.path.insert(0, os.path.dirname(__file__))
    from test_design_scenario import BASE
    text = BASE.replace('''type = "position"
probe = "tip"
value = [12.0, 0.0, 10.0]
components = [0, 2]''', '''type = "angle"
probe = "tip"
value = 60.0''').replace("tolerance = 1e-6", "tolerance = 1e-3")
    path = tmp_path / "d.toml"
    path.write_text(text)
    assert cli.main(["design", str(path), "--out", str(tmp_path / "o"), "-q"]) == 0
    d = json.load(open(tmp_path / "o" / "design.json"))
    row = d["poses"][0]["targets"][0]
    assert row["unit"] == "deg" and row["target"] == 60.0 and abs(row["achieved"][0] - 60.0) < 1e-3
    assert row["max_misfit"] < 1e-3                                     # misfit in degrees
    opt = scenario.load(tmp_path / "o" / "optimised.toml")
    res = opt.problem.solve()
    tip = opt.problem.probes["tip"]
    angle = np.degrees(np.linalg.norm(res.final.probes["tip"]["rotation_vector"]))
    assert abs(angle - 60.0) < 1e-3 and tip is not None


def test_U11_a_cold_kernel_cache_makes_auto_wait_and_say_so(monkeypatch, capsys):
    from core_se3 import backend
    monkeypatch.setattr(backend._Rent, "saved", 0.0)
    monkeypatch.setattr(backend._Rent, "switched", False)
    monkeypatch.setattr(backend._Rent, "cold", None)
    monkeypatch.setattr(backend, "kernel_cache_warm", lambda: False)
    monkeypatch.setattr(backend, "numba_available", lambda: True)
    n = 0
    while not backend._Rent.switched:
        backend.charge(16)
        n += 1
    assert abs(n * backend.iteration_saving(16) - backend.NUMBA_COLD_START_COST) < backend.iteration_saving(16)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "compiles its kernels first, once (about 22 s; `core-se3 warmup`" in err[0]
    assert backend.rent_state()["cold"] is True                  # kept in a checkpoint: a resume waits alike


def test_U12_results_record_how_they_ran(tmp_path, capsys):
    res = runner.run(load(doc()), out=str(tmp_path / "o"))
    prov = res.doc["provenance"]
    assert prov["package"] == "core_se3" and prov["version"] and prov["ranks"] == 1 and prov["partition"] is None
    assert prov["linear_solver"] == {"setting": "auto", "used": "banded"} and prov["peak_memory"][0] > 1e7
    assert prov["backend"]["used"] == sorted({s["backend"] for s in res.doc["steps"] if s["backend"]})
    assert cli.main(["bench", "run", "cantilever-shear", "--mesh", "4x1", "--steps", "2", "-q",
                     "--json", str(tmp_path / "b.json")]) == 0
    bench = json.load(open(tmp_path / "b.json"))["provenance"]
    assert bench["ranks"] == 1 and bench["linear_solver"]["used"] in ("banded", "superlu", "mumps")


def test_U13_the_design_section_is_documented_with_a_running_example():
    text = open(os.path.join(ROOT, "docs", "SCENARIOS.md")).read()
    assert "### `[design]`" in text
    for key in ("method", "max_iter", "tolerance", "stop_at_tolerance", "[[design.poses]]", "[[design.variables]]",
                "[[design.targets]]", "degrees"):
        assert key in text.split("### `[design]`")[1].split("\n## ")[0], key


def test_U13_the_documented_design_fragment_reaches_its_target():
    sys.path.insert(0, os.path.dirname(__file__))
    from test_scenario_docs import fragments, merged
    frag = dict(fragments())["design"]
    scn = load(merged(frag))
    r = scn.design().optimise("least_squares", max_iter=20, tolerance=0.01)
    assert r.reached and r.max_misfit < 0.01                            # degrees


def test_U11_warmup_fills_the_kernel_cache_once():
    from core_se3.backend import kernel_cache_warm, numba_available
    if not numba_available():
        pytest.skip("needs numba")
    r = subprocess.run([sys.executable, "-m", "core_se3", "warmup"], env=env(), capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0 and r.stdout.strip().splitlines()[-1].startswith("numba kernels "), r.stderr[-2000:]
    assert kernel_cache_warm()
    again = subprocess.run([sys.executable, "-m", "core_se3", "warmup"], env=env(), capture_output=True, text=True,
                           timeout=900)
    assert "were already compiled" in again.stdout

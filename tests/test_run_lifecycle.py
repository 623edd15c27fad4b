"""The life of a run (issue 34): its directory (manifest, lock, force), its sinks each alone, its
results document from the start, its end by a signal, and what a distributed run records
(mpirun, skipped without mpi4py, petsc4py or mpirun).  The kill storm is tests/test_kill_storm.py.
"""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.io import Checkpoint
from core_se3.io.lifecycle import Terminated, held_signals, termination_as_interrupt
from core_se3.io.rundir import MANIFEST, RunDirectory, RunDirectoryError
from core_se3.scenario import runner, sinks
from core_se3.scenario.context import RunContext

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
STRIP = {"name": "strip", "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
         "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
         "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
         "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 3}}


def load(d=STRIP, **output):
    d = dict(d, output=dict({"vtu": False, "plots": False, "picture": False}, **output))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return scenario.from_dict(d, file="s.toml")


def manifest(out):
    return json.load(open(os.path.join(out, MANIFEST)))["files"]


# ----------------------------------------------------------------------------- the directory
def test_the_manifest_lists_every_file_the_run_wrote(tmp_path):
    out = str(tmp_path / "o")
    runner.run(load(vtu=True, plots=True, picture=True), out=out)
    on_disk = sorted(os.path.relpath(os.path.join(r, f), out) for r, _, fs in os.walk(out) for f in fs
                     if not f.startswith(".core-se3"))
    assert on_disk == sorted(manifest(out)) and "vtu/step_0003.vtu" in on_disk and "shell.png" in on_disk


def test_force_deletes_only_the_files_of_the_earlier_run(tmp_path):
    out = tmp_path / "o"
    runner.run(load(STRIP, vtu=True), out=str(out))
    (out / "notes.txt").write_text("mine")
    (out / "vtu" / "extra.vtu").write_text("mine too")
    fewer = load(dict(STRIP, solver={"steps": 1}), vtu=True)
    with pytest.raises(RunDirectoryError, match=r"did not write \(notes.txt, vtu/extra.vtu\)"):
        runner.run(fewer, out=str(out))
    runner.run(fewer, out=str(out), force=True)
    assert (out / "notes.txt").read_text() == "mine" and (out / "vtu" / "extra.vtu").read_text() == "mine too"
    assert not (out / "vtu" / "step_0003.vtu").exists()                 # the earlier run's, gone
    assert sorted(manifest(str(out))) == ["checkpoint.npz", "results.json", "vtu/series.pvd", "vtu/step_0000.vtu",
                                          "vtu/step_0001.vtu"]


def test_force_leaves_no_empty_folder_of_the_earlier_run(tmp_path):
    """A design run again with fewer poses (--force): the earlier run's vtu/<pose> files went but
    their folders stayed, empty (vtu/second read as a pose of this run).  Now the folders that
    held only its files go too; one holding a user's file stays, with the file."""
    d = str(tmp_path / "out")
    with RunDirectory(d, "design").claim() as rd:
        for f in ("vtu/first/step_0000.vtu", "vtu/second/step_0000.vtu", "vtu/third/step_0000.vtu", "design.json"):
            path = rd.file(f)
            os.makedirs(os.path.dirname(path), exist_ok=True)
            open(path, "w").close()
    open(os.path.join(d, "vtu", "third", "notes.txt"), "w").close()       # the user's
    with RunDirectory(d, "design").claim(force=True) as rd:
        assert sorted(os.listdir(d)) == [MANIFEST, ".core-se3.lock", "vtu"]
        assert os.listdir(os.path.join(d, "vtu")) == ["third"]
        assert os.listdir(os.path.join(d, "vtu", "third")) == ["notes.txt"]


def test_a_resume_keeps_the_files_added_beside_the_run(tmp_path):
    out = tmp_path / "o"
    scn = load()
    with pytest.raises(sinks.RunInterrupted):
        runner.run(scn, out=str(out), stop_after=1)
    (out / "notes.txt").write_text("mine")
    assert runner.run(scn, out=str(out), resume=True).status == "complete"
    assert (out / "notes.txt").read_text() == "mine" and "notes.txt" not in manifest(str(out))


def test_a_resume_adopts_the_run_directory_of_an_older_version(tmp_path):
    out = str(tmp_path / "o")
    scn = load()
    with pytest.raises(sinks.RunInterrupted):
        runner.run(scn, out=out, stop_after=1)
    os.unlink(os.path.join(out, MANIFEST))                          # as written before issue 34
    res = runner.run(scn, out=out, resume=True)
    assert res.status == "complete" and "checkpoint.npz" in manifest(out)


def test_a_resume_of_a_run_stopped_before_its_first_checkpoint_starts_over(tmp_path):
    out = str(tmp_path / "o")
    scn = load()
    with RunDirectory(out, "run", sinks.RUN_FILES).claim() as rd:     # what a run killed in its set-up left
        with open(rd.file("results.json"), "w") as fh:
            json.dump({"status": "running", "steps": []}, fh)
    with pytest.raises(RunDirectoryError, match="holds the files of an earlier run"):
        runner.run(scn, out=out)
    assert runner.run(scn, out=out, resume=True).status == "complete"


def test_a_directory_in_use_by_a_live_run_is_refused_and_free_after_it(tmp_path):
    out = str(tmp_path / "o")
    holder = subprocess.Popen([sys.executable, "-c", f"""
import sys, time
from core_se3.io.rundir import RunDirectory
rd = RunDirectory({out!r}, "run").claim()
print("locked", flush=True)
sys.stdin.read()
"""], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                              env=dict(os.environ, PYTHONPATH=ROOT))
    assert holder.stdout.readline().strip() == "locked"
    with pytest.raises(RunDirectoryError, match=rf"in use by another live run \(a run of process {holder.pid}"):
        runner.run(load(), out=out, force=True)
    holder.kill()                                   # the kernel drops the lock of a killed process
    holder.wait()
    assert runner.run(load(), out=out, force=True).status == "complete"


def test_a_lock_file_is_there_only_while_a_run_lives(tmp_path):
    """A completed run left .core-se3.lock (with its dead pid) in the output directory, as did a
    failed one.  Now a run that ends, complete or failed, deletes it; a stale file of a killed run
    (no process holds it) does not block the next run, which takes it and deletes it at its end."""
    import json as _json
    from core_se3.errors import ConvergenceError
    from core_se3.io import rundir
    out = tmp_path / "o"
    assert runner.run(load(), out=str(out)).status == "complete"
    assert not (out / rundir.LOCK).exists()
    (out / rundir.LOCK).write_text(_json.dumps({"pid": 999999999, "kind": "run", "started": "then"}))
    assert runner.run(load(), out=str(out), force=True).status == "complete"
    assert not (out / rundir.LOCK).exists()
    failing = load(dict(STRIP, solver={"steps": 1, "max_iter": 1, "max_cutbacks": 0}))
    with pytest.raises(ConvergenceError):
        runner.run(failing, out=str(out), force=True)
    assert json.load(open(out / "results.json"))["status"] == "failed" and not (out / rundir.LOCK).exists()


def test_a_refused_run_leaves_no_lock_file_in_the_users_directory(tmp_path, monkeypatch):
    """A run refused by a directory of the user's files (notes.txt) left .core-se3.lock in it.
    The refusing process deletes the lock file it created (still holding it); one that opened
    that file just before and locks it after finds it gone and locks the name's new file (here
    simulated: the file deleted between the open and the flock), so two runs never both hold one."""
    from core_se3.io import rundir
    d = tmp_path / "mine"
    d.mkdir()
    (d / "notes.txt").write_text("mine")
    with pytest.raises(RunDirectoryError, match=r"did not write \(notes.txt\)"):
        runner.run(load(), out=str(d))
    assert sorted(os.listdir(d)) == ["notes.txt"]
    real, calls = os.open, []

    def open_then_deleted(path, flags, *mode):
        fd = real(path, flags, *mode)
        if path.endswith(rundir.LOCK) and not calls:
            calls.append(path)
            os.unlink(path)                  # a refusing run deletes the file this one opened
        return fd
    monkeypatch.setattr(rundir.os, "open", open_then_deleted)
    with RunDirectory(str(tmp_path / "o"), "run").claim() as rd:
        monkeypatch.setattr(rundir.os, "open", real)
        assert calls and os.path.exists(os.path.join(rd.path, rundir.LOCK))
        with pytest.raises(RunDirectoryError, match="in use by another live run"):
            RunDirectory(rd.path, "run").claim()
    with RunDirectory(str(tmp_path / "o"), "run").claim(force=True):
        pass
    assert not os.path.exists(tmp_path / "o" / rundir.LOCK)          # a run that ended leaves none


# ----------------------------------------------------------------------------- each sink alone
@pytest.fixture
def state(tmp_path):
    scn = load()
    rd = RunDirectory(str(tmp_path / "o"), "run").claim()
    yield sinks.RunState(scn, rd, RunContext(scn.problem), result=None)
    rd.release()


def _event(scn, k, lam, finished=False):
    g = scn.problem.mesh.g0.copy()
    g[:, 2, 3] += lam
    return sinks.StepEvent(k, {"step": k, "load_factor": lam, "probes": {}, "iterations": 1, "residual": 0.0}, g, lam,
                           finished, {}, None, {"tip": np.zeros(3)})


def test_the_vtu_sink_writes_every_kth_step_and_the_last(state):
    sink = sinks.VtuSink(every=2)
    for k in range(4):
        sink.step(state, _event(state.scn, k, k / 3, finished=k == 3))
    assert sorted(os.listdir(os.path.join(state.rd.path, "vtu"))) == ["step_0000.vtu", "step_0002.vtu", "step_0003.vtu"]


def test_the_checkpoint_sink_saves_the_records_and_what_a_resume_needs(state):
    ev = _event(state.scn, 0, 0.0)
    state.records.append(ev.record)
    sinks.CheckpointSink().step(state, ev)
    st = Checkpoint(state.rd.path).load()
    assert st["step"] == 0 and st["records"] == [ev.record] and state.saved == 1
    np.testing.assert_array_equal(st["g"], ev.g)


def test_the_document_sink_writes_from_the_start_and_the_end_status(state):
    sink = sinks.DocumentSink()
    sink.start(state)
    path = os.path.join(state.rd.path, "results.json")
    assert json.load(open(path))["status"] == "running" and json.load(open(path))["steps"] == []
    state.records.append(_event(state.scn, 0, 0.0).record)
    sink.end(state, "interrupted", "interrupted by SIGTERM")
    d = json.load(open(path))
    assert d["status"] == "interrupted" and d["error"] == "interrupted by SIGTERM" and len(d["steps"]) == 1


def test_the_provenance_sink_measures_the_peak_memory(state):
    sinks.ProvenanceSink().step(state, _event(state.scn, 0, 0.0))
    assert len(state.provenance["peak_memory"]) == 1 and state.provenance["peak_memory"][0] > 1e7


def test_stop_after_counts_only_the_new_steps(state):
    state.done = 2
    sink = sinks.StopAfter(1)
    sink.step(state, _event(state.scn, 2, 0.5))               # a step of the checkpoint: not counted
    with pytest.raises(sinks.RunInterrupted, match="stopped after step 3"):
        sink.step(state, _event(state.scn, 3, 0.75))


# ----------------------------------------------------------------------------- signals
def test_signals_held_while_the_last_files_are_written_come_afterwards():
    import signal
    seen = []
    with termination_as_interrupt():
        with pytest.raises(Terminated) as ei:
            with held_signals():
                os.kill(os.getpid(), signal.SIGTERM)
                seen.append("wrote")
    assert seen == ["wrote"] and ei.value.signal_name == "SIGTERM"


# ----------------------------------------------------------------------------- mpirun
HAVE_MPI = (importlib.util.find_spec("mpi4py") is not None and importlib.util.find_spec("petsc4py") is not None
            and shutil.which("mpirun") is not None)


def _mpirun(tmp_path, doc, *args, command=("run",)):
    if not HAVE_MPI:
        pytest.skip("needs mpi4py, petsc4py and mpirun")
    path = tmp_path / "s.toml"
    path.write_text(scenario.dumps(doc))
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1", CORE_SE3_BACKEND="numpy",
               PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    what = list(command) + ([path.name] if command == ("run",) else [])
    cmd = ["mpirun", "-n", "2", "-x", "PYTHONPATH", "-x", "CORE_SE3_BACKEND", "-x", "OMP_NUM_THREADS",
           sys.executable, "-m", "core_se3", *what, "-q", *args]
    return subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600, cwd=str(tmp_path))


def test_a_run_on_two_ranks_records_how_it_ran(tmp_path):
    doc = dict(STRIP, mesh={"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 8, "ny": 2},
               solver={"steps": 2, "linear": "mumps"}, output={"vtu": False, "plots": False, "picture": False})
    r = _mpirun(tmp_path, doc, "--out", "o")
    assert r.returncode == 0, r.stderr[-3000:]
    prov = json.load(open(tmp_path / "o" / "results.json"))["provenance"]
    assert prov["ranks"] == 2 and prov["linear_solver"]["used"] == "mumps" and prov["solve"] == "distributed"
    assert prov["partition"]["method"] == "auto" and sum(prov["partition"]["elements_per_rank"]) == 16
    assert len(prov["peak_memory"]) == 2 and min(prov["peak_memory"]) > 1e7
    r = _mpirun(tmp_path, doc, "--json", "b.json", command=("bench", "run", "cantilever-shear", "--mesh", "8x2",
                                                             "--steps", "2"))
    assert r.returncode == 0, r.stderr[-3000:]
    bench = json.load(open(tmp_path / "b.json"))["provenance"]
    assert bench["ranks"] == 2 and bench["linear_solver"]["used"] == "mumps" and len(bench["peak_memory"]) == 2
    assert sum(bench["partition"]["elements_per_rank"]) == 16


def test_a_linear_run_on_two_ranks_records_that_every_rank_solved_it(tmp_path):
    """A linear analysis under mpirun -n 2 runs serially on every rank (docs/PARALLEL.md); its
    results.json said ranks = 1, as if launched alone.  Now ranks = 2 (the job's size) and solve
    = 'serial on every rank' (a load-control run: 'distributed'; serially: 'serial'), with no
    partition; the answer is the serial one to round-off."""
    doc = dict(STRIP, solver={"control": "linear"}, output={"vtu": False, "plots": False, "picture": False})
    r = _mpirun(tmp_path, doc, "--out", "o")
    assert r.returncode == 0, r.stderr[-3000:]
    res = json.load(open(tmp_path / "o" / "results.json"))
    prov = res["provenance"]
    assert prov["ranks"] == 2 and prov["solve"] == "serial on every rank" and prov["partition"] is None
    serial = runner.run(load(dict(STRIP, solver={"control": "linear"})), out=str(tmp_path / "serial"))
    assert serial.doc["provenance"]["ranks"] == 1 and serial.doc["provenance"]["solve"] == "serial"
    assert res["steps"][-1]["probes"]["tip"]["u"] == pytest.approx(serial.doc["steps"][-1]["probes"]["tip"]["u"],
                                                                   rel=1e-10, abs=1e-14)


def test_a_failed_run_on_two_ranks_writes_its_last_steps_contact_forces(tmp_path):
    """A run on 2 ranks whose step 4 (1.5 -> 1e5) fails after converging sub-steps: the VTU file of
    step 3 written at the failure showed the sub-steps' contact forces, 512.8 for the step's 0.675
    in results.json (the serial run's was restored, the distributed one's not).  Now it is 0.675."""
    import meshio
    doc = dict(STRIP, mesh={"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 8, "ny": 1},
               loads=[{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, -0.5]}],
               obstacles=[{"type": "half_space", "name": "floor", "point": [0.0, 0.0, -0.3], "normal": [0.0, 0.0, 1.0]}],
               solver={"load_factors": [0.5, 1.0, 1.5, 1e5], "max_cutbacks": 0, "max_iter": 8},
               output={"vtu_every": 10, "plots": False, "picture": False})
    r = _mpirun(tmp_path, doc, "--out", "o")
    assert r.returncode != 0 and "step 4 (load factor 1.5 -> 100000) failed" in r.stderr, r.stderr[-3000:]
    res = json.load(open(tmp_path / "o" / "results.json"))
    last = res["steps"][-1]
    assert res["provenance"]["ranks"] == 2 and last["step"] == 3 and last["contact"]["floor"]["force"][2] > 0.5
    v = meshio.read(str(tmp_path / "o" / "vtu" / "step_0003.vtu"))
    assert v.point_data["contact_force"][:, 2].sum() == pytest.approx(last["contact"]["floor"]["force"][2], rel=1e-12)


def test_C4_petsc_options_it_refuses_are_one_error_line_naming_the_key(tmp_path):
    doc = dict(STRIP, mesh={"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 8, "ny": 2},
               solver={"steps": 1, "linear": "gamg", "petsc": {"ksp_rtol": 1e-9, "pc_gamg_threshold": "abc"}},
               output={"vtu": False, "plots": False, "picture": False})
    r = _mpirun(tmp_path, doc, "--out", "o")
    assert r.returncode != 0 and "Traceback" not in r.stderr and "petsc4py.PETSc.Error" not in r.stderr, r.stderr[-3000:]
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("error:")]
    assert lines == ["error: s.toml: [solver.petsc.pc_gamg_threshold]: PETSc refused the option pc_gamg_threshold = "
                     "'abc' (Input string abc has no numeric value); see the PETSc manual for the option's values "
                     "(docs/PARALLEL.md)"], r.stderr[-3000:]

"""Resumable arc-length runs: the follower restarts from a saved ArcState, the runner
checkpoints every converged path point and ``--resume`` continues the path.

The reference is the uninterrupted run of the same scenario: a resumed path repeats the same
computations from the same saved bits, so its frames g, step count, load factors, records and
critical points equal those of the uninterrupted run exactly (measured: max |g - g_ref| = 0.0
for every restart point below, the snapping arch of tests/test_cli_run.py resumed across
both of its limit points).
"""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from core_se3 import scenario, solvers as C
from core_se3.scenario import runner
from core_se3.io import Checkpoint
from core_se3.errors import CheckpointError, ConvergenceError

from test_cli_run import ARCH, assert_outputs_intact, pvd_files, with_, write
from test_continuation import cubic, pitchfork


def _snapshots(sysm_factory, **kw):
    snaps = []
    pts, crit, _, _ = C.path_follow(sysm_factory(), on_step=snaps.append, **kw)
    return pts, crit, snaps


@pytest.fixture(autouse=True)
def _one_backend(pinned_backend):
    """Every run here on one backend (the runs are compared bit for bit)."""
    return pinned_backend


@pytest.mark.parametrize("case", ["pitchfork-switch", "cubic-riks"])
def test_path_follow_restarts_from_every_point_bit_for_bit(case):
    """Restarting path_follow from the ArcState of any converged point (through pack/unpack,
    as a checkpoint stores it) ends in the uninterrupted final state, with the same number of
    points and the same critical points; this covers the pending branch switch of the
    pitchfork and the Riks normal plane with a landing on control_end of the cubic."""
    if case == "pitchfork-switch":
        make = pitchfork
        kw = dict(method="crisfield", lam_end=1.6, dlam0=0.15, branch_switch=True)
    else:
        make = lambda: cubic()[0]
        kw = dict(method="riks", lam_end=None, dlam0=0.02, psi=1.0,
                  control=(lambda u: u[0], lambda u: np.array([1.0])), control_end=3.0)
    pts, crit, snaps = _snapshots(make, **kw)
    assert len(snaps) == len(pts) and [s.step for s in snaps] == list(range(len(pts)))
    assert snaps[-1].finished and not any(s.finished for s in snaps[:-1])
    if case == "pitchfork-switch":
        assert any(s.switch_mode is not None for s in snaps)
    for k, snap in enumerate(snaps):
        sc, arrays = snap.pack()
        sc = json.loads(json.dumps(sc))
        start = C.ArcState.unpack(np.array(snap.state), sc, arrays)
        tail, crit2, _, _ = C.path_follow(make(), start=start, **kw)
        assert len(tail) == (len(pts) - k if k < len(pts) - 1 else 0)
        if tail:
            np.testing.assert_array_equal(tail[-1].state, pts[-1].state)
            assert [p.lam for p in tail[1:]] == [p.lam for p in pts[k + 1:]]
        assert [(c.kind, c.step, c.lam) for c in crit2] == [(c.kind, c.step, c.lam) for c in crit]


def test_interrupted_arclength_run_resumes_to_the_same_state(tmp_path):
    """The snapping arch (two limit points, 18 path steps) stopped after 4 points, resumed and
    stopped again after 7 more (past the first limit point, step 10), then resumed to the end:
    the same frames bit for bit, the same records and critical points as the uninterrupted
    run; every file written on the way parses.  Resuming a complete run changes nothing; a
    changed scenario is refused."""
    scn = scenario.load(write(tmp_path, ARCH))
    ref = runner.run(scn, out=str(tmp_path / "ref"))
    out = str(tmp_path / "cut")
    with pytest.raises(runner.RunInterrupted):
        runner.run(scn, out=out, stop_after=4)
    doc, st = assert_outputs_intact(out)
    assert st["step"] == 4 and doc["status"] == "running" and len(doc["steps"]) == 5
    assert doc["steps"] == ref.doc["steps"][:5]
    with pytest.raises(runner.RunInterrupted):
        runner.run(scn, out=out, resume=True, stop_after=7)
    doc, st = assert_outputs_intact(out)
    assert st["step"] == 11 and doc["critical_points"] == ref.doc["critical_points"][:1]
    res = runner.run(scn, out=out, resume=True)
    np.testing.assert_array_equal(res.g, ref.g)
    assert res.status == "complete" and len(res.doc["steps"]) == len(ref.doc["steps"])
    assert res.doc["steps"] == ref.doc["steps"]                 # load factors, probes, iterations
    assert res.doc["critical_points"] == ref.doc["critical_points"]
    assert [c["kind"] for c in res.doc["critical_points"]] == ["limit", "limit"]
    assert pvd_files(os.path.join(out, "vtu", "series.pvd")) == \
        pvd_files(os.path.join(ref.out, "vtu", "series.pvd"))
    again = runner.run(scn, out=out, resume=True)
    np.testing.assert_array_equal(again.g, ref.g)
    assert again.doc["steps"] == ref.doc["steps"]
    changed = scenario.load(write(tmp_path, with_(ARCH, material={"E": 2e6}), "changed.toml"))
    with pytest.raises(CheckpointError, match="different scenario"):
        runner.run(changed, out=out, resume=True)


def test_arclength_results_carry_each_points_stability_and_each_critical_points_accuracy(tmp_path):
    """The snapping arch's results.json: every path point has its stability (det K's sign and the
    count of negative eigenvalues of sym K), so that a reader sees where the counts change, and
    each critical point its accuracy (<= critical_tol 1e-3) and the counts at its bracket's ends.
    Found: neither was written (the accuracy only inside the description's text)."""
    res = runner.run(scenario.load(write(tmp_path, ARCH)), out=str(tmp_path / "run"))
    counts = [s["stability"]["negative_eigenvalues"] for s in res.doc["steps"]]
    assert counts[0] == 0 and max(counts) == 1 and counts[-1] == 0
    assert all(s["stability"]["det_sign"] == (-1) ** n for s, n in zip(res.doc["steps"], counts))
    first, second = res.doc["critical_points"]
    assert first["negative_eigenvalues"] == [0, 1] and second["negative_eigenvalues"] == [1, 0]
    assert 0 < first["accuracy"] <= 1e-3 and 0 < second["accuracy"] <= 1e-3
    assert counts[first["step"] - 1] == 0 and counts[first["step"]] == 1


def test_checkpoint_without_path_state_is_refused(tmp_path):
    """An arc-length checkpoint without the follower state (as written before resume existed)
    is refused with a message naming the cause, not resumed from the wrong state."""
    scn = scenario.load(write(tmp_path, with_(ARCH, output={"vtu": False})))
    out = str(tmp_path / "old")
    with pytest.raises(runner.RunInterrupted):
        runner.run(scn, out=out, stop_after=1)
    st = Checkpoint(out).load()
    Checkpoint(out).save(st["fingerprint"], dict(st, extra=dict(control="arclength"), arrays=None))
    with pytest.raises(CheckpointError, match="no arc-length path state"):
        runner.run(scn, out=out, resume=True)


def test_killed_arclength_process_resumes_to_the_same_state(tmp_path, throttled_cli):
    """SIGKILL a real ``core-se3 run`` of the arch after 3 path points; ``--resume`` finishes it
    with the uninterrupted frames bit for bit and keeps everything written before the kill."""
    path = write(tmp_path, ARCH)
    ref = runner.run(scenario.load(path), out=str(tmp_path / "ref"))
    n = len(ref.doc["steps"]) - 1
    out = str(tmp_path / "run")
    args = ["run", path, "--out", out, "--quiet"]
    cmd = [sys.executable, "-m", "core_se3"] + args
    proc = subprocess.Popen(throttled_cli(args),             # the kill lands mid-run
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    ck = Checkpoint(out)
    t0 = time.time()
    while time.time() - t0 < 60 and proc.poll() is None:
        if ck.exists() and ck.load()["step"] >= 3:
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    doc_cut, st = assert_outputs_intact(out)
    assert 3 <= st["step"] < n
    open(os.path.join(out, ".results.json.x1y2z3w4.tmp.json"), "w").close()   # as a kill mid-write leaves
    r = subprocess.run(cmd + ["--resume"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    final = Checkpoint(out).load()
    assert final["step"] == n
    np.testing.assert_array_equal(final["g"], ref.g)
    done = json.load(open(os.path.join(out, "results.json")))
    assert done["status"] == "complete"
    assert done["steps"][:len(doc_cut["steps"])] == doc_cut["steps"]      # nothing written was lost
    assert done["steps"] == ref.doc["steps"] and done["critical_points"] == ref.doc["critical_points"]
    assert len(pvd_files(os.path.join(out, "vtu", "series.pvd"))) == n + 1
    assert not [f for f in os.listdir(os.path.join(out, "vtu")) if f.startswith(".")]


def test_path_stopped_by_max_steps_resumes_with_a_larger_budget(tmp_path):
    """An arc-length run that stops at [solver] max_steps (a failed run that keeps its converged
    points) continues with ``--resume`` once max_steps is raised, and ends in the uninterrupted
    run's frames bit for bit: max_steps is left out of the scenario fingerprint because it only
    decides where the path stops."""
    ref = runner.run(scenario.load(write(tmp_path, ARCH)), out=str(tmp_path / "ref"))
    n = len(ref.doc["steps"]) - 1
    out = str(tmp_path / "short")
    short = scenario.load(write(tmp_path, with_(ARCH, solver={"max_steps": 6}), "short.toml"))
    with pytest.raises(ConvergenceError, match="max_steps"):
        runner.run(short, out=out)
    assert Checkpoint(out).load()["step"] == 6 < n
    res = runner.run(scenario.load(write(tmp_path, with_(ARCH, solver={"max_steps": 200}), "long.toml")),
                     out=out, resume=True)
    np.testing.assert_array_equal(res.g, ref.g)
    assert res.doc["steps"] == ref.doc["steps"] and res.status == "complete"

"""``core-se3 run SCENARIO.toml [--out DIR] [--resume]``: outputs, progress, checkpoints, resume.

The resumed runs must end in exactly the state of an uninterrupted run (the same per-step
Newton solves from the same saved bits), and nothing written before an interruption may be
lost or left half-written (atomic writes).
"""
import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from core_se3 import cli, io, scenario
from core_se3.backend import numba_available
from core_se3.scenario import runner
from core_se3.io import Checkpoint
from core_se3.errors import CheckpointError, ConvergenceError

EXAMPLES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "examples")

STRIP = {
    "name": "strip",
    "mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 6, "ny": 1},
    "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1},
    "supports": [{"type": "clamp", "edge": "x0"}],
    "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 2.0]}],
    "probes": [{"name": "tip", "edge": "x1"}],
    "solver": {"steps": 3},
}


def write(tmp_path, doc, name="s.toml"):
    p = tmp_path / name
    p.write_text(scenario.dumps(doc))
    return str(p)


def with_(doc, **sections):
    import copy
    d = copy.deepcopy(doc)
    for k, v in sections.items():
        if isinstance(v, dict) and isinstance(d.get(k), dict):
            d[k].update(v)
        else:
            d[k] = v
    return d


def pvd_files(pvd):
    root = ET.parse(pvd).getroot()
    return [(float(e.get("timestep")), e.get("file")) for e in root.iter("DataSet")]


def assert_outputs_intact(out):
    """Every file a run has written so far parses: results JSON, checkpoint, each VTU of the pvd."""
    doc = json.load(open(os.path.join(out, "results.json")))
    st = Checkpoint(out).load(doc["fingerprint"])
    assert [s["step"] for s in doc["steps"]] == list(range(len(doc["steps"])))
    assert st["step"] >= doc["steps"][-1]["step"]
    for t, f in pvd_files(os.path.join(out, "vtu", "series.pvd")):
        m = meshio.read(os.path.join(out, "vtu", f))
        assert m.point_data["displacement"].shape == (len(m.points), 3)
    return doc, st


def test_run_writes_results_vtu_series_and_plots(tmp_path, capsys):
    path = write(tmp_path, STRIP)
    out = str(tmp_path / "out")
    assert cli.main(["run", path, "--out", out]) == 0
    text = capsys.readouterr().out
    assert "strip: 3 steps to load factor 1" in text and "probe tip" in text
    doc = json.load(open(os.path.join(out, "results.json")))
    assert (doc["schema"], doc["version"], doc["status"], doc["case"]) == ("core-se3-result", 1, "complete", "strip")
    assert [s["load_factor"] for s in doc["steps"]] == [0.0, 1 / 3, 2 / 3, 1.0]
    assert doc["mesh"] == dict(nx=6, ny=1, n_nodes=14, n_elements=6, n_dofs=84)
    assert all(s["balance_error"] < 1e-8 for s in doc["steps"])
    series = pvd_files(os.path.join(out, "vtu", "series.pvd"))
    assert [t for t, _ in series] == [0.0, 1 / 3, 2 / 3, 1.0]
    m = meshio.read(os.path.join(out, "vtu", series[-1][1]))
    for f in ("displacement", "d1", "d2", "d3", "rotation_angle"):
        assert f in m.point_data
    for f in ("N1", "N2", "M1", "M2", "N1_local", "M1_local"):
        assert m.cell_data[f][0].shape == (6, 3)
    # the VTU displacement at the tip nodes is the results' tip probe (symmetric tip: both nodes alike)
    tip = scenario.load(path).mesh.edges["x1"]
    np.testing.assert_allclose(m.point_data["displacement"][tip].mean(0), doc["steps"][-1]["probes"]["tip"]["u"],
                               atol=1e-12)
    # equilibrium of the part beyond each element centre c (dead tip force P e_z, width 1):
    # moment on the cut M1 = (phi_tip - phi_c) x P e_z, force N1 = P e_z; second-order
    # discretisation error, measured 0.28 % (M1) and 0.27 % (N1) at worst on 6 elements
    g = Checkpoint(out).load()["g"]
    qs = scenario.load(path).mesh.quads
    c = g[qs, :3, 3].mean(1)
    phi_tip = g[tip, :3, 3].mean(0)
    P = np.array([0.0, 0.0, 2.0])
    exact = np.cross(phi_tip - c, P)
    assert np.abs(m.cell_data["M1"][0] - exact).max() < 5e-3 * np.abs(exact).max()
    assert np.abs(m.cell_data["N1"][0] - P).max() < 5e-3 * 2.0
    assert os.stat(os.path.join(out, "results.json")).st_mode & 0o644 == 0o644    # not mkstemp's 0600
    for png in ("probes.png", "shell.png"):
        with open(os.path.join(out, png), "rb") as fh:
            assert fh.read(8) == b"\x89PNG\r\n\x1a\n"


def test_the_run_summary_names_a_critical_point_it_passed_as_not_located(tmp_path, capsys):
    """The strip compressed past Euler's load (~0.617 of 4 N) in 2 steps, limit_check = false:
    the printed summary names the bifurcation passed between steps 1 and 2 as not located (only
    its bracket, load factors 0.5 .. 1, is known).  Before, the summary said nothing of it (the
    warning shows only with -v) and results.json read 'bifurcation point at lam ~ 0.75'."""
    doc = with_(STRIP, mesh={"nx": 10}, loads=[{"type": "edge_force", "edge": "x1", "force": [-4.0, 0.0, 0.0]}],
                solver={"steps": 2, "limit_check": False}, output={"vtu": False, "plots": False, "picture": False})
    assert cli.main(["run", write(tmp_path, doc), "--out", str(tmp_path / "out")]) == 0
    (line,) = [x for x in capsys.readouterr().out.splitlines() if "critical point" in x]
    assert line.startswith("  critical point between steps 1 and 2: bifurcation point not located: lam between 0.5 and 1")


def test_progress_bar_only_when_asked_or_on_a_terminal(tmp_path, capsys):
    scn = scenario.load(write(tmp_path, with_(STRIP, solver={"steps": 2}, output={"vtu": False, "plots": False,
                                                                                  "picture": False})))
    runner.run(scn, out=str(tmp_path / "a"), progress=True)
    text = capsys.readouterr().out
    assert "step 1/2" in text and "step 2/2" in text and "it " in text and "res " in text and "dlam 0.5" in text
    runner.run(scn, out=str(tmp_path / "b"))            # stdout is not a terminal under pytest
    assert capsys.readouterr().out == ""


def test_interrupted_run_resumes_to_the_same_state(tmp_path, pinned_backend):
    scn = scenario.load(write(tmp_path, with_(STRIP, solver={"steps": 4}, output={"plots": False,
                                                                                  "picture": False})))
    ref = runner.run(scn, out=str(tmp_path / "ref"))
    out = str(tmp_path / "cut")
    with pytest.raises(runner.RunInterrupted):
        runner.run(scn, out=out, stop_after=2)
    doc, st = assert_outputs_intact(out)
    assert st["step"] == 2 and doc["status"] == "running" and len(doc["steps"]) == 3
    res = runner.run(scn, out=out, resume=True)
    np.testing.assert_array_equal(res.g, ref.g)          # bit for bit
    strip_t = lambda d: [dict(s) for s in d["steps"]]
    assert strip_t(res.doc) == strip_t(ref.doc)
    assert len(pvd_files(os.path.join(out, "vtu", "series.pvd"))) == 5


@pytest.mark.skipif(not numba_available(), reason="the switch to numba needs numba")
def test_a_resumed_run_switches_backend_where_the_uninterrupted_one_did(tmp_path, fresh_backend_count,
                                                                         monkeypatch):
    """The 'auto' backend's count is in the checkpoint: a run interrupted before its switch to
    numba and resumed in a new process (a fresh count) switches at the same Newton iteration
    and ends on the uninterrupted frames bit for bit (without the count it would switch later
    and differ by round-off)."""
    from core_se3 import backend
    monkeypatch.delenv("CORE_SE3_BACKEND", raising=False)
    scn = scenario.load(write(tmp_path, with_(STRIP, solver={"steps": 6}, output={"plots": False,
                                                                                  "picture": False})))
    m = scn.problem.mesh.n_elements
    # a start cost that the uninterrupted run passes during its 4th step (4 iterations a step)
    monkeypatch.setattr(backend, "NUMBA_START_COST", 14.5 * backend.iteration_saving(m))
    ref = runner.run(scn, out=str(tmp_path / "ref"))
    assert fresh_backend_count.switched and ref.doc["steps"][4]["iterations"] == 4
    out = str(tmp_path / "cut")
    backend.restore_rent({"saved": 0.0, "switched": False, "cold": False})         # a new process
    with pytest.raises(runner.RunInterrupted):
        runner.run(scn, out=out, stop_after=2)
    assert not fresh_backend_count.switched                         # stopped before the switch
    backend.restore_rent({"saved": 0.0, "switched": False, "cold": False})         # another new process
    res = runner.run(scn, out=out, resume=True)
    assert fresh_backend_count.switched
    np.testing.assert_array_equal(res.g, ref.g)            # bit for bit


def test_killed_process_resumes_to_the_same_state(tmp_path, pinned_backend, throttled_cli):
    """SIGKILL a real ``core-se3 run`` after a few steps; --resume finishes it identically."""
    doc = with_(STRIP, solver={"steps": 12}, output={"plots": False, "picture": False})
    path = write(tmp_path, doc)
    scn = scenario.load(path)
    ref = runner.run(scn, out=str(tmp_path / "ref"))
    out = str(tmp_path / "run")
    args = ["run", path, "--out", out, "--quiet"]
    cmd = [sys.executable, "-m", "core_se3"] + args
    proc = subprocess.Popen(throttled_cli(args),             # the kill lands mid-run
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    ck = Checkpoint(out)
    t0 = time.time()
    step = -1
    while time.time() - t0 < 60 and proc.poll() is None:
        if ck.exists():
            step = ck.load()["step"]
            if step >= 3:
                break
        time.sleep(0.01)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    doc_cut, st = assert_outputs_intact(out)
    assert 3 <= st["step"] < 12
    open(os.path.join(out, ".results.json.x1y2z3w4.tmp.json"), "w").close()   # as a kill mid-write leaves
    r = subprocess.run(cmd + ["--resume"], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    final = Checkpoint(out).load()
    assert final["step"] == 12
    np.testing.assert_array_equal(final["g"], ref.g)
    done = json.load(open(os.path.join(out, "results.json")))
    assert done["status"] == "complete"
    assert done["steps"][:len(doc_cut["steps"])] == doc_cut["steps"]      # nothing written was lost
    assert [s["probes"] for s in done["steps"]] == [s["probes"] for s in ref.doc["steps"]]
    assert len(pvd_files(os.path.join(out, "vtu", "series.pvd"))) == 13
    assert not [f for f in os.listdir(os.path.join(out, "vtu")) if f.startswith(".")]
    assert not [f for f in os.listdir(out) if ".tmp" in f]


def test_failed_run_keeps_converged_steps_and_resumes_with_other_controls(tmp_path, pinned_backend):
    """Steps 1-2 are small, 3 jumps: with the plain displacement Newton, max_iter = 5 and no
    cut-backs step 3 fails; the checkpoint keeps step 2 and --resume with the default max_iter
    and cut-backs finishes the run exactly as an uninterrupted run with those controls (solver
    controls are not part of the fingerprint)."""
    base = with_(STRIP, solver={"steps": 4, "iteration": "displacement"}, output={"plots": False, "picture": False})
    base["loads"][0]["scale"] = [[0.0, 0.0], [0.5, 0.02], [1.0, 1.0]]
    strict = with_(base, solver={"max_iter": 5, "max_cutbacks": 0})
    out = str(tmp_path / "out")
    rc = cli.main(["run", write(tmp_path, strict), "--out", out, "--quiet"])
    assert rc == 3
    doc = json.load(open(os.path.join(out, "results.json")))
    assert doc["status"] == "failed" and "step 3" in doc["error"] and len(doc["steps"]) == 3
    assert Checkpoint(out).load()["step"] == 2
    path = write(tmp_path, base)
    assert cli.main(["run", path, "--out", out, "--resume", "--quiet"]) == 0
    ref = runner.run(scenario.load(path), out=str(tmp_path / "ref"))
    np.testing.assert_array_equal(Checkpoint(out).load()["g"], ref.g)


def test_convergence_error_from_the_api_keeps_the_steps(tmp_path):
    base = with_(STRIP, solver={"steps": 4, "max_iter": 5, "max_cutbacks": 0, "iteration": "displacement"},
                 output={"vtu": False})
    base["loads"][0]["scale"] = [[0.0, 0.0], [0.5, 0.02], [1.0, 1.0]]
    with pytest.raises(ConvergenceError, match="step 3 .* failed.*checkpoint keeps step 2") as ei:
        runner.run(scenario.load(write(tmp_path, base)), out=str(tmp_path / "o"))
    assert ei.value.result is not None


def test_resume_refuses_a_changed_scenario(tmp_path, capsys):
    out = str(tmp_path / "out")
    quiet = {"vtu": False, "plots": False, "picture": False}
    assert cli.main(["run", write(tmp_path, with_(STRIP, output=quiet)), "--out", out, "-q"]) == 0
    changed = with_(STRIP, material={"E": 2e6}, output=quiet)
    assert cli.main(["run", write(tmp_path, changed), "--out", out, "--resume"]) == 2
    assert "belongs to a different scenario" in capsys.readouterr().err
    with pytest.raises(CheckpointError, match="does not exist"):
        runner.run(scenario.load(write(tmp_path, changed)), out=str(tmp_path / "empty"), resume=True)


def test_a_renamed_scenario_resumes_its_run(tmp_path, pinned_backend):
    """``name`` labels a run (results' name, titles, the default out/NAME) and changes no
    mechanics, but it was in the fingerprint: a run renamed from 'strip' and extended from 2 to 4
    steps was refused ("name changed from 'strip' to 'strip-2'").  Now the fingerprint leaves it
    out: the renamed run resumes from step 2 and ends in the state of the uninterrupted run to the
    bit; a checkpoint of the version that hashed the name (same name) still resumes."""
    out = str(tmp_path / "o")
    quiet = {"vtu": False, "plots": False, "picture": False}
    first = with_(STRIP, solver={"steps": 2}, output=quiet)
    runner.run(scenario.load(write(tmp_path, first)), out=out)
    renamed = with_(STRIP, name="strip-2", solver={"steps": 4, "lam_end": 2.0}, output=quiet)
    scn = scenario.load(write(tmp_path, renamed))
    assert scn.fingerprint == scenario.load(write(tmp_path, with_(renamed, name="other"))).fingerprint
    res = runner.run(scn, out=out, resume=True)
    whole = runner.run(scenario.load(write(tmp_path, renamed)), out=str(tmp_path / "whole"))
    assert res.status == "complete" and len(res.doc["steps"]) == 5 and res.doc["case"] == "strip-2"
    np.testing.assert_array_equal(res.g, whole.g)             # bit for bit
    ck = Checkpoint(out)
    st = ck.load()
    st["fingerprint"], st["extra"]["physical"]["name"] = scn.named_fingerprint, "strip-2"
    from core_se3.scenario.resume import check_same_scenario
    check_same_scenario(ck.path, st, scn)                # an older version's checkpoint


def test_existing_run_needs_resume_or_force(tmp_path, capsys):
    out = str(tmp_path / "out")
    path = write(tmp_path, with_(STRIP, output={"vtu": False, "plots": False, "picture": False}))
    assert cli.main(["run", path, "--out", out, "-q"]) == 0
    assert cli.main(["run", path, "--out", out, "-q"]) == 2
    assert "holds the files of an earlier run" in capsys.readouterr().err
    assert cli.main(["run", path, "--out", out, "-q", "--force"]) == 0


def test_bad_scenario_is_one_line_on_stderr(tmp_path, capsys):
    path = write(tmp_path, with_(STRIP, material={"nu": 0.7}))
    assert cli.main(["run", path, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"error: {path}: [material.nu]: expected a number < 0.5, got 0.7"
    assert not os.path.exists(tmp_path / "o")            # nothing ran, nothing written
    assert cli.main(["run", write(tmp_path, STRIP), "--check"]) == 0
    assert "valid (6 elements, 14 nodes" in capsys.readouterr().out


ARCH = {
    "name": "shallow-arch",
    "mesh": {"generator": "cylinder_arch", "R": 10.0, "angle": 0.4, "width": 1.0, "nx": 12, "ny": 1},
    "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1},
    "edges": {"crown": {"box": {"x": [10 * np.sin(0.2)] * 2, "tol": 1e-6}}},
    "supports": [{"type": "clamp", "edge": "x0"}, {"type": "clamp", "edge": "x1"}],
    "loads": [{"type": "nodal", "edge": "crown", "force": [0.0, 0.0, 40.0]}],
    "probes": [{"name": "crown", "edge": "crown"}],
    "solver": {"control": "arclength", "steps": 20},
    "output": {"plots": False, "picture": False},
}


def test_arclength_run_passes_the_limit_points_of_a_snapping_arch(tmp_path, pinned_backend):
    """A clamped shallow arch pushed at its crown toward its centre snaps through: the
    arc-length run goes over the maximum, back down to the minimum and up to lam = 1, and
    records both limit points (change in the number of negative tangent eigenvalues)."""
    res = runner.run(scenario.load(write(tmp_path, ARCH)), out=str(tmp_path / "arch"))
    doc = res.doc
    assert doc["status"] == "complete" and doc["control"] == "arclength"
    lam = np.array([s["load_factor"] for s in doc["steps"]])
    assert lam[-1] == pytest.approx(1.0, abs=1e-12)
    kinds = [c["kind"] for c in doc["critical_points"]]
    assert kinds == ["limit", "limit"]
    lmax, lmin = (c["load_factor"] for c in doc["critical_points"])
    assert lmin < lmax < 1.0 and lam.max() == pytest.approx(1.0)
    i1, i2 = (c["step"] for c in doc["critical_points"])    # first steps past each limit point
    assert lam[i2] < lam[i1 - 1] and np.any(np.diff(lam) < 0)  # the path turns back down
    uz = [s["probes"]["crown"]["u"][2] for s in doc["steps"]]
    assert np.all(np.diff(uz) > 0)                            # while the crown keeps moving
    assert_outputs_intact(res.out)
    series = pvd_files(os.path.join(res.out, "vtu", "series.pvd"))      # ParaView sorts by time: the
    assert [t for t, _ in series] == [float(s["step"]) for s in doc["steps"]]   # path's order, not lam's
    assert [io.read_field_data(os.path.join(res.out, "vtu", f))["load_factor"] for _, f in series] == lam.tolist()
    again = runner.run(scenario.load(write(tmp_path, ARCH)), out=res.out, resume=True)  # nothing left to do
    np.testing.assert_array_equal(again.g, res.g)
    assert again.doc["steps"] == doc["steps"] and again.doc["critical_points"] == doc["critical_points"]


def test_pvd_of_negative_load_factors_plays_in_step_order(tmp_path):
    """load_factors towards negative values: the .pvd's times were the load factors 0, -0.2,
    -0.5, -1, which ParaView sorts, playing the run backwards from its end; now they are the
    step numbers, with each file's load factor in its FieldData."""
    doc = with_(STRIP, solver={"load_factors": [-0.2, -0.5, -1.0]}, output={"plots": False, "picture": False})
    del doc["solver"]["steps"]
    out = runner.run(scenario.load(write(tmp_path, doc)), out=str(tmp_path / "o")).out
    series = pvd_files(os.path.join(out, "vtu", "series.pvd"))
    assert series == [(float(k), f"step_{k:04d}.vtu") for k in range(4)]
    assert [io.read_field_data(os.path.join(out, "vtu", f))["load_factor"] for _, f in series] == [0.0, -0.2, -0.5, -1.0]


def test_sweep_prints_each_scenario_warning_once(tmp_path, capsys):
    """A sweep validates every value and then runs it: each point's scenario warnings came twice,
    as raw Python warnings with an internal line of code ('return from_dict(doc, ...)'), and the
    base scenario's again after the first lines.  Now each text once, as a 'warning:' line."""
    doc = with_(STRIP, material={"h": 3.5}, output={"plots": False, "picture": False})
    path = write(tmp_path, doc)
    assert cli.main(["sweep", path, "--set", "material.h=3.5,4.0", "--out", str(tmp_path / "sw"), "-q"]) == 0
    err = capsys.readouterr().err.splitlines()
    thick = [ln for ln in err if "is thick for its span" in ln]
    assert len(thick) == 2 and all(ln.startswith("warning: ") for ln in thick)
    assert {"h / L = 3.5 / 10" in thick[0], "h / L = 4 / 10" in thick[1]} == {True}
    assert not [ln for ln in err if "from_dict" in ln or "Warning:" in ln]


def test_arclength_on_a_monotone_path_lands_on_the_load_control_state(tmp_path):
    arc = with_(STRIP, solver={"control": "arclength", "steps": 4}, output={"vtu": False, "plots": False,
                                                                            "picture": False})
    a = runner.run(scenario.load(write(tmp_path, arc)), out=str(tmp_path / "a"))
    b = runner.run(scenario.load(write(tmp_path, with_(arc, solver={"control": "load"}))), out=str(tmp_path / "b"))
    assert a.doc["steps"][-1]["load_factor"] == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(a.doc["steps"][-1]["probes"]["tip"]["u"], b.doc["steps"][-1]["probes"]["tip"]["u"],
                               rtol=0, atol=1e-8)


def test_bench_run_vtu_includes_the_problem_output_fields(tmp_path, capsys):
    """``core-se3 bench run --vtu`` writes prob.output_fields (magnetisation) next to the frames."""
    out = str(tmp_path / "vtu")
    assert cli.main(["bench", "run", "magnetic-cantilever", "--mesh", "4x1", "--steps", "2", "--vtu", out]) == 0
    files = pvd_files(os.path.join(out, "series.pvd"))
    m = meshio.read(os.path.join(out, files[-1][1]))
    Br = m.point_data["magnetisation_Br"]
    assert np.abs(Br).max() > 0 and "magnetic_couple" in m.point_data


def test_run_with_explicit_load_factors(tmp_path):
    """A load-controlled run through [solver] load_factors records exactly those load factors
    and ends in the state of the uniform 3-step run (conservative load: path independent)."""
    uni = runner.run(scenario.load(write(tmp_path, with_(STRIP, output={"vtu": False, "plots": False,
                                                                        "picture": False}))),
                     out=str(tmp_path / "uni"))
    doc = with_(STRIP, solver={"load_factors": [0.1, 0.45, 1.0]},
                output={"vtu": False, "plots": False, "picture": False})
    doc["solver"].pop("steps")
    res = runner.run(scenario.load(write(tmp_path, doc, "lf.toml")), out=str(tmp_path / "lf"))
    assert [s["load_factor"] for s in res.doc["steps"]] == [0.0, 0.1, 0.45, 1.0]
    assert np.abs(res.g[:, :3, 3] - uni.g[:, :3, 3]).max() < 1e-8 * 10.0


@pytest.mark.parametrize("args, message", [
    (["design-tip-angle", "--set", "theta_deg=120"], "turns its tip by 0 .. 90 deg"),
    (["sze-semicylinder", "--mesh", "15x16"], "even number of elements around"),
    (["cantilever-shear", "--set", "nu=0.5"], "nu must lie in (-1, 0.5)"),
    (["cantilever-shear", "--mesh", "0x1"], "two whole numbers >= 1"),
    (["magnetic-cantilever", "--mesh", "0x1"], "two whole numbers >= 1"),      # was: 0 read as "auto"
])
def test_bench_run_bad_parameters_are_one_error_line_not_a_traceback(args, message, capsys):
    """A case parameter, mesh or option outside what the case admits: exit status 2 and one
    'error: ...' line naming the cause (found: an out-of-range design target and an odd
    semicylinder mesh ended in a Python traceback)."""
    assert cli.main(["bench", "run", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("error: ") and message in err[-1] and "Traceback" not in "\n".join(err)


def test_steps_below_one_are_refused_not_replaced_by_the_default(capsys):
    """--steps 0 used to run the case's default 10 steps silently, and design --max-iter 0 the
    section's iterations."""
    from core_se3.catalogue.run import run_case
    from core_se3.errors import DesignError, OptionError
    from core_se3.scenario.design_runner import run_design
    for argv, what in ((["bench", "run", "cantilever-shear", "--steps", "0"], "steps"),
                       (["design", os.path.join(EXAMPLES, "gripper-design.toml"), "--max-iter", "0"], "max-iter")):
        with pytest.raises(SystemExit) as exc:
            cli.main(argv)
        assert exc.value.code == 2 and f"{what} must be at least 1" in capsys.readouterr().err
    with pytest.raises(DesignError, match="max_iter must be a whole number"):
        run_design(scenario.load(os.path.join(EXAMPLES, "gripper-design.toml")), max_iter=0)
    for bad in (0, -3, 2.5, True):
        with pytest.raises(OptionError, match="load steps must be a whole number"):
            run_case("cantilever-shear", steps=bad)


def test_an_unwritable_output_path_is_one_error_line(tmp_path, capsys):
    """An output under a regular file (so no directory can be made there): exit status 2 and
    one 'error: cannot write the outputs' line, for bench run (its --vtu directory claimed before
    it solves) and for a scenario run, instead of an OSError traceback."""
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert cli.main(["bench", "run", "cantilever-shear", "--mesh", "4x1", "--steps", "2",
                     "--vtu", str(blocker / "vtu")]) == 2
    out, err = capsys.readouterr()           # its --vtu directory is claimed before the solve, as a run's
    assert "reactions balance" not in out and err.strip().startswith("error: cannot write the outputs")
    assert err.strip().endswith("nothing was solved")
    assert cli.main(["run", write(tmp_path, STRIP), "--out", str(blocker / "run"), "-q"]) == 2
    assert capsys.readouterr().err.strip().startswith("error: cannot write the outputs")


def test_bench_run_vtu_follows_the_run_directory_rules_and_writes_a_runs_files(tmp_path, capsys):
    """``bench run --vtu DIR`` wrote over any file in DIR (a user's series.pvd replaced) and its
    files had neither stress resultants nor FieldData.  Now DIR is a run directory (``io.rundir``):
    files core-se3 did not write are refused (kept beside with --force, never overwritten), a
    second bench replaces its own files, and the files are core-se3 run's (``step_files``)."""
    from core_se3.io.vtk import read_field_data
    out = tmp_path / "vtu"
    out.mkdir()
    (out / "series.pvd").write_text("mine")
    args = ["bench", "run", "cantilever-shear", "--mesh", "4x1", "--steps", "2", "-q", "--vtu", str(out)]
    assert cli.main(args) == 2
    assert "did not write (series.pvd)" in capsys.readouterr().err and (out / "series.pvd").read_text() == "mine"
    assert cli.main(args + ["--force"]) == 2                      # never over it
    assert "--force does not overwrite them" in capsys.readouterr().err and (out / "series.pvd").read_text() == "mine"
    (out / "series.pvd").rename(out / "notes.txt")
    assert cli.main(args + ["--force"]) == 0 and cli.main(args + ["--force"]) == 0    # beside; its own replaced
    assert (out / "notes.txt").read_text() == "mine"
    m = meshio.read(str(out / "step_0002.vtu"))
    assert "M1" in m.cell_data and "N1" in m.cell_data
    assert read_field_data(str(out / "step_0002.vtu"))["load_factor"] == pytest.approx(1.0, abs=1e-12)
    assert [f for _, f in pvd_files(str(out / "series.pvd"))] == [f"step_{k:04d}.vtu" for k in range(3)]


@pytest.mark.parametrize("cmd", [["run", "S"], ["sweep", "S", "--set", "material.E=1e6"],
                                 ["bench", "run", "cantilever-shear"]])
def test_progress_and_quiet_together_are_a_usage_error(tmp_path, capsys, cmd):
    """--progress (draw the line) and -q (no line, no summary) contradict each other (the usage
    line reads [--progress | -q]): both is a usage error, exit status 2, before anything runs.
    Before, `run --progress -q` ran and drew the progress line that -q was to silence."""
    path = write(tmp_path, with_(STRIP, solver={"steps": 1}))
    args = [path if a == "S" else a for a in cmd] + ["--out" if cmd[0] != "bench" else "--vtu", str(tmp_path / "o"),
                                                     "--progress", "-q"]
    with pytest.raises(SystemExit) as exc:
        cli.main(args)
    assert exc.value.code == 2 and "not allowed with argument --progress" in capsys.readouterr().err
    assert not os.path.exists(tmp_path / "o")


def test_sweep_set_says_it_replaces_the_files_sweep_section(tmp_path, capsys):
    """`core-se3 sweep FILE --set KEY=...` on a file with a [sweep] section runs the --set grid
    alone; a note on stderr names the section's keys that are not run.  Before, the file's
    [sweep] (here material.nu = [0.0, 0.3]) was dropped without a word: 2 rows, not 4 or 2 x 2."""
    doc = with_(STRIP, solver={"steps": 1}, output={"vtu": False, "plots": False, "picture": False})
    doc["sweep"] = {"material.nu": [0.0, 0.3]}
    path = write(tmp_path, doc)
    assert cli.main(["sweep", path, "--set", "material.E=1e6,2e6", "--out", str(tmp_path / "sw"), "-q"]) == 0
    err = capsys.readouterr().err
    assert "--set replaces the scenario's [sweep] section (material.nu)" in err, err
    rows = (tmp_path / "sw" / "sweep.csv").read_text().splitlines()
    assert rows[0].startswith("material.E,") and len(rows) == 3
    assert cli.main(["sweep", path, "--out", str(tmp_path / "sw2"), "-q"]) == 0      # the section alone: no note
    assert "replaces" not in capsys.readouterr().err


def test_check_mesh_json_never_overwrites_a_file_that_is_not_a_check(tmp_path, capsys):
    """check-mesh --json PATH replaces an earlier check's JSON, and refuses (exit 2, the file
    intact) any other existing file: another scenario's mesh, a run's results.json, notes.
    Before, only the scenario's own inputs were protected: `--json other.vtu` wrote the JSON over
    a mesh file of another scenario."""
    path = write(tmp_path, with_(STRIP, solver={"steps": 1}))
    mesh = tmp_path / "other.vtu"
    meshio.write(mesh, meshio.Mesh(np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
                                   [("quad", [[0, 1, 2, 3]])]))
    before = mesh.read_bytes()
    assert cli.main(["check-mesh", path, "--json", str(mesh)]) == 2
    assert mesh.read_bytes() == before and "not an earlier check's JSON" in capsys.readouterr().err
    out = tmp_path / "check.json"
    assert cli.main(["check-mesh", path, "--json", str(out)]) == 0           # new, then replaced
    assert cli.main(["check-mesh", path, "--json", str(out)]) == 0
    assert json.loads(out.read_text())["status"] == "complete"


def test_bench_plot_of_an_unknown_image_format_is_refused_before_the_solve(tmp_path, capsys):
    """`bench run CASE --plot notes.toml`: matplotlib has no '.toml' writer.  Before, the case
    solved and printed its table, then the plot worker raised a bare ValueError ("Format 'toml' is
    not supported") with a traceback, exit status 1.  Now: exit 2 at once, naming the formats, the
    file untouched."""
    notes = tmp_path / "notes.toml"
    notes.write_text("mine\n")
    assert cli.main(["bench", "run", "cantilever-shear", "--plot", str(notes), "-q"]) == 2
    out = capsys.readouterr()
    assert "writes no '.toml' images" in out.err and "png" in out.err and "load" not in out.out
    assert notes.read_text() == "mine\n"


def test_bench_json_never_overwrites_a_file_that_is_not_a_bench_json(tmp_path, capsys):
    """`bench run CASE --json PATH` replaces an earlier bench JSON and refuses (exit 2, before the
    solve, the file intact) anything else: a scenario file, a run's results.json.  Before, it
    wrote the case's document over them (a scenario file became JSON)."""
    path = write(tmp_path, with_(STRIP, solver={"steps": 1}, output={"vtu": False, "plots": False, "picture": False}))
    scenario_text = open(path).read()
    run = runner.run(scenario.load(path), out=str(tmp_path / "run"))
    results = open(run.files["results"]).read()
    for target in (path, run.files["results"]):
        assert cli.main(["bench", "run", "cantilever-shear", "--json", target, "-q"]) == 2
        assert "not an earlier bench run's JSON" in capsys.readouterr().err
    assert open(path).read() == scenario_text and open(run.files["results"]).read() == results
    out = str(tmp_path / "case.json")
    assert cli.main(["bench", "run", "cantilever-shear", "--json", out, "-q"]) == 0
    assert cli.main(["bench", "run", "cantilever-shear", "--json", out, "-q"]) == 0      # its own: replaced

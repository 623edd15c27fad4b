"""A resumed run's sessions (docs/SCENARIOS.md, 'Checkpoints and --resume'): a checkpoint keeps
what each session of the run computed with beyond the scenario's fingerprint (package version,
Python, NumPy, ranks, backend, the solver controls a resume may change), a resume under another
package version is refused naming both, another difference is said, and results.json's
provenance lists the sessions.  Before, a run started under one version (or rtol, or number of
ranks) and resumed under another reported the last session's alone, as if it had run whole."""
import json

import numpy as np
import pytest

import core_se3
from core_se3 import scenario
from core_se3.errors import CheckpointError, ScenarioWarning
from core_se3.scenario import runner

DOC = {"mesh": {"generator": "rectangle", "L": 10.0, "width": 1.0, "nx": 4, "ny": 1},
       "material": {"E": 1.2e6, "nu": 0.0, "h": 0.1}, "supports": [{"type": "clamp", "edge": "x0"}],
       "loads": [{"type": "edge_force", "edge": "x1", "force": [0.0, 0.0, 1.0]}],
       "probes": [{"name": "tip", "edge": "x1"}], "solver": {"steps": 4},
       "output": {"vtu": False, "plots": False, "picture": False}}


def _scn(**solver):
    base = {} if "load_factors" in solver else DOC["solver"]
    return scenario.from_dict(dict(DOC, solver=dict(base, **solver)))


def _cut(out, n=2, **solver):
    with pytest.raises(runner.RunInterrupted):
        runner.run(_scn(**solver), out=out, stop_after=n)


def test_a_resume_under_another_package_version_is_refused_naming_both(tmp_path, monkeypatch):
    out = str(tmp_path / "run")
    with monkeypatch.context() as m:
        m.setattr(core_se3, "__version__", "0.0.1")
        _cut(out)
    before = (tmp_path / "run" / "results.json").read_text()
    with pytest.raises(CheckpointError, match=rf"written by core_se3 0\.0\.1, this is {core_se3.__version__}"):
        runner.run(_scn(), out=out, resume=True)
    assert (tmp_path / "run" / "results.json").read_text() == before        # nothing written


def test_a_resume_with_other_controls_says_so_and_lists_both_sessions(tmp_path):
    out = str(tmp_path / "run")
    _cut(out)
    with pytest.warns(ScenarioWarning, match=r"controls\.rtol 1e-10 -> 1e-08.*not bit for bit"):
        res = runner.run(_scn(rtol=1e-8), out=out, resume=True)
    doc = json.loads((tmp_path / "run" / "results.json").read_text())
    sessions = doc["provenance"]["sessions"]
    assert [s["first_step"] for s in sessions] == [0, 3]
    assert [s["controls"]["rtol"] for s in sessions] == [1e-10, 1e-8]
    assert sessions[1]["version"] == core_se3.__version__ and res.status == "complete"


def test_an_unbroken_run_lists_no_sessions_and_a_plain_resume_warns_nothing(tmp_path, recwarn):
    ref = runner.run(_scn(), out=str(tmp_path / "ref"))
    out = str(tmp_path / "run")
    _cut(out)
    res = runner.run(_scn(), out=out, resume=True)
    assert not [w for w in recwarn if issubclass(w.category, ScenarioWarning)]
    np.testing.assert_array_equal(res.g, ref.g)
    assert "sessions" not in ref.doc["provenance"] and len(res.doc["provenance"]["sessions"]) == 2


def test_a_resume_with_other_steps_names_the_load_factors_to_keep(tmp_path):
    """After a failure the message says 'change the solver controls or the steps and rerun with
    --resume'; finer steps (steps = 8 for 4) were refused naming only 'raise lam_end and steps in
    proportion'.  The refusal now names the way that works: load_factors beginning with the
    steps done -- and that resume runs."""
    out = str(tmp_path / "run")
    _cut(out)
    with pytest.raises(CheckpointError, match=r"give solver\.load_factors that begin with them \(0\.25, 0\.5\)"):
        runner.run(_scn(steps=8), out=out, resume=True)
    res = runner.run(_scn(load_factors=[0.25, 0.5, 0.625, 0.75, 0.875, 1.0]), out=out, resume=True)
    assert [s["load_factor"] for s in res.doc["steps"]] == [0.0, 0.25, 0.5, 0.625, 0.75, 0.875, 1.0]


def test_a_run_whose_manifest_is_damaged_resumes_taking_its_files_by_name(tmp_path):
    """A damaged .core-se3-manifest.json (a disk fault, a hand edit) stopped the resume with
    'choose another --out': the run's steps could only be computed again elsewhere.  A resume now
    takes the run's files by their names, as an older version's (with a warning), and ends in the
    unbroken run's state; a new run or --force there is still refused (which files to delete?)."""
    ref = runner.run(_scn(), out=str(tmp_path / "ref"))
    out = tmp_path / "run"
    _cut(str(out))
    (out / ".core-se3-manifest.json").write_text("{not json")
    with pytest.raises(Exception, match=r"is damaged.*continue it with --resume"):
        runner.run(_scn(), out=str(out), force=True)
    with pytest.warns(ScenarioWarning, match=r"manifest\.json is damaged .*taken by their names"):
        res = runner.run(_scn(), out=str(out), resume=True)
    np.testing.assert_array_equal(res.g, ref.g)
    assert json.loads((out / ".core-se3-manifest.json").read_text())["files"] == ["checkpoint.npz", "results.json"]


def test_a_resumed_sweep_refuses_another_version_and_lists_its_sessions(tmp_path, monkeypatch):
    """A sweep interrupted after its first row and resumed with another rtol lists both sessions
    in sweep.json (first_row 0 and 1) and says so; one started under another package version is
    refused (before: both continued silently, sweep.json naming the last session alone)."""
    import importlib
    from core_se3.io.lifecycle import Terminated
    sweep_mod = importlib.import_module("core_se3.scenario.sweep")
    grid = {"material.E": [1.2e6, 1.4e6, 1.6e6]}
    orig, calls = sweep_mod.point_row, []

    def cut_second(*a, **k):
        calls.append(1)
        if len(calls) == 2:
            raise Terminated("SIGTERM")
        return orig(*a, **k)
    for name, version in (("other", "0.0.1"), ("same", core_se3.__version__)):
        out = str(tmp_path / name)
        calls.clear()
        with monkeypatch.context() as m:
            m.setattr(core_se3, "__version__", version)
            m.setattr(sweep_mod, "point_row", cut_second)
            with pytest.raises(Terminated):
                sweep_mod.sweep(_scn(), grid, out=out, plot=False)
    with pytest.raises(CheckpointError, match=r"written by core_se3 0\.0\.1"):
        sweep_mod.sweep(_scn(), grid, out=str(tmp_path / "other"), plot=False, resume=True)
    with pytest.warns(ScenarioWarning, match=r"controls\.rtol 1e-10 -> 1e-09"):
        res = sweep_mod.sweep(_scn(rtol=1e-9), grid, out=str(tmp_path / "same"), plot=False, resume=True)
    doc = json.loads((tmp_path / "same" / "sweep.json").read_text())
    assert [s["first_row"] for s in doc["provenance"]["sessions"]] == [0, 1] and len(res.rows) == 3

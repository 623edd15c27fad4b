"""A resumed load-control run takes the uninterrupted run's step checks (docs/SCENARIOS.md,
'Checkpoints and --resume'; docs/STEPS.md).

The snap roof of examples/snap-roof.toml loaded to 0.735 P_max (99 % of its limit load) and back
to 0 in 2 steps, stopped after step 1 and resumed, skipped the midpoint probe of step 2 that the
uninterrupted run made: the probe's current-stiffness record (and det K's sign) were not in the
checkpoint.  The roof's crown is at z = 2540 and the solver iterates relative to an origin: the
checkpoint keeps those frames too (``held_frames``), so the resumed run ends on the unbroken
run's bits; from the frames in the problem's coordinates alone (eps |x| = 5.6e-13) it ended
1.4e-14 off, under load control and arc length alike."""
import json
import re
import pathlib

import numpy as np
import pytest

from core_se3 import scenario
from core_se3.scenario import runner

ROOF = pathlib.Path(__file__).resolve().parents[1] / "examples" / "snap-roof.toml"


def _cycle():
    text = ROOF.read_text()
    head = text[:text.index("[solver]")].replace(
        "force = [0.0, 0.0, -750.0]", "force = [0.0, 0.0, -750.0]\nscale = [[0.0, 0.0], [0.5, 0.735], [1.0, 0.0]]")
    return scenario.loads(head + '[solver]\ncontrol = "load"\nsteps = 2\n\n[output]\npicture = false\nvtu = false\n',
                          file="cycle.toml", base_dir=str(ROOF.parent))


def test_a_resumed_run_repeats_the_uninterrupted_runs_checks_and_state(tmp_path, pinned_backend):
    ref = runner.run(_cycle(), out=str(tmp_path / "ref"))
    with pytest.raises(runner.RunInterrupted):
        runner.run(_cycle(), out=str(tmp_path / "cut"), stop_after=1)
    res = runner.run(_cycle(), out=str(tmp_path / "cut"), resume=True)
    np.testing.assert_array_equal(res.g, ref.g)           # was 1.4e-14 off: the frames came back from z = 2540
    steps = [json.load(open(r.files["results"]))["steps"] for r in (ref, res)]
    assert [s["probes"]["crown"]["u"] for s in steps[1]] == [s["probes"]["crown"]["u"] for s in steps[0]]
    assert steps[0][2]["checks"]["midpoint_probes"] == 1            # the probe of step 2 (a limit point ahead)
    count = ("path_rejections", "det_sign", "midpoint_probes", "refinements")
    assert [[(s.get("checks") or {}).get(k) for k in count] for s in steps[1]] == \
        [[(s.get("checks") or {}).get(k) for k in count] for s in steps[0]]
    assert [s["iterations"] for s in steps[1]] == [s["iterations"] for s in steps[0]]


def _roof_arc():
    text = ROOF.read_text().replace("picture = false", "picture = false\nplots = false\nvtu = false")
    return scenario.loads(text, file="snap-roof.toml", base_dir=str(ROOF.parent))


def test_a_resumed_arc_length_path_far_from_the_origin_ends_on_the_unbroken_paths_bits(tmp_path, pinned_backend):
    """examples/snap-roof.toml (crown at z = 2540) by arc length, stopped at step 5 and again at
    step 12 (beside its limit point, 0.7427 at step 12), resumed: the frames, the
    load factors, the crown's displacements and the critical points equal the unbroken path's
    to the bit.  From the frames in the problem's coordinates the path continued 4.6e-13 off in
    g, its reactions' moments 3.4e-6 off (moments about the origin, at 2540)."""
    ref = runner.run(_roof_arc(), out=str(tmp_path / "ref"))
    out = str(tmp_path / "cut")
    for k, n in enumerate((5, 7)):
        with pytest.raises(runner.RunInterrupted):
            runner.run(_roof_arc(), out=out, stop_after=n, resume=k > 0)
    res = runner.run(_roof_arc(), out=out, resume=True)
    np.testing.assert_array_equal(res.g, ref.g)
    docs = [json.load(open(r.files["results"])) for r in (ref, res)]
    for key in ("load_factor", "reactions"):
        assert [s[key] for s in docs[1]["steps"]] == [s[key] for s in docs[0]["steps"]], key
    assert [s["probes"]["crown"]["u"] for s in docs[1]["steps"]] == [s["probes"]["crown"]["u"] for s in docs[0]["steps"]]
    assert [(c["kind"], c["load_factor"]) for c in docs[1]["critical_points"]] == \
        [(c["kind"], c["load_factor"]) for c in docs[0]["critical_points"]]


ROUGH = """name = "rough"
[mesh]
generator = "rectangle"
L = 10.0
width = 1.0
nx = 10
ny = 2
x0 = 10000.0
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
force = [0.0, 0.0, -6.0]
[[obstacles]]
type = "half_space"
name = "floor"
point = [10000.0, 0.0, -1.5]
normal = [0.0, 0.0, 1.0]
friction = 0.3
motion = { translate = [0.0, 0.5, 0.0] }
[[probes]]
name = "tip"
edge = "x1"
[solver]
steps = 6
[output]
picture = false
plots = false
vtu = false
"""


def test_a_resumed_rough_contact_far_from_the_origin_keeps_its_friction_anchors_to_the_bit(tmp_path, pinned_backend):
    """A cantilever 1e4 from the origin pushed onto a rough floor that slides sideways (mu = 0.3),
    stopped after step 3, resumed: the frames and the contact records equal the unbroken run's.
    The restart point's friction anchors came back from the problem's coordinates (anchor + c -
    c): the resumed run ended 9.3e-14 off in g (stopped after step 5), its contact forces 3.5e-7
    off; the checkpoint now keeps the relocated load's own anchors too (``held_multipliers``)."""
    ref = runner.run(scenario.loads(ROUGH, file="rough.toml"), out=str(tmp_path / "ref"))
    out = str(tmp_path / "cut")
    for stop in (1, 2):                               # after steps 1 and 3
        with pytest.raises(runner.RunInterrupted):
            runner.run(scenario.loads(ROUGH, file="rough.toml"), out=out, stop_after=stop, resume=stop > 1)
    res = runner.run(scenario.loads(ROUGH, file="rough.toml"), out=out, resume=True)
    np.testing.assert_array_equal(res.g, ref.g)
    docs = [json.load(open(r.files["results"]))["steps"] for r in (ref, res)]
    assert docs[0][-1]["contact"]["floor"]["slipping"] > 0                   # the history matters
    assert [s["contact"] for s in docs[1]] == [s["contact"] for s in docs[0]]


def test_held_frames_that_are_not_the_checkpoints_frames_are_refused(tmp_path):
    """A checkpoint whose frames relative to the solver's origin are not its frames g (edited,
    or mixed from two files) is refused as inconsistent, naming them; a checkpoint without them
    (written before they were kept) still resumes, from g."""
    from core_se3.errors import CheckpointError
    from core_se3.io import Checkpoint
    out = str(tmp_path / "cut")
    with pytest.raises(runner.RunInterrupted):
        runner.run(_cycle(), out=out, stop_after=1)
    ck = Checkpoint(out)
    st = ck.load()
    assert st["extra"]["newton"]["origin"] == [0.0, 0.0, 2540.0 * np.cos(0.1)]
    held = st["arrays"]["held_frames"]
    bad = dict(st, arrays=dict(st["arrays"], held_frames=held + np.where(np.arange(4) == 3, 1e-9, 0.0)))
    ck.save(st["fingerprint"], bad)
    with pytest.raises(CheckpointError, match="held_frames, origin"):
        runner.run(_cycle(), out=out, resume=True)
    newton = {k: v for k, v in st["extra"]["newton"].items() if k != "origin"}
    old = dict(st, arrays={k: v for k, v in st["arrays"].items() if k != "held_frames"},
               extra=dict(st["extra"], newton=newton))
    ck.save(st["fingerprint"], old)
    assert runner.run(_cycle(), out=out, resume=True).status == "complete"


def test_two_ranks_name_the_limit_point_as_the_serial_run_does(tmp_path):
    """The 8x8 snap roof under 1.0003 times its limit load in one step: the serial run fails
    after 12 cut-backs at 0.999268 with 'Probable cause: ... S_p = 0.0136 ... load control has
    met a limit point'; on 2 ranks the same failure said no cause (the hint factorised the whole
    tangent on one process and was skipped).  Now the ranks take S_p from the last try's first
    iterate: the same message."""
    import importlib.util
    import os
    import shutil
    import subprocess
    import sys
    if importlib.util.find_spec("mpi4py") is None or shutil.which("mpirun") is None:
        pytest.skip("needs mpi4py and mpirun")
    text = ROOF.read_text()
    head = text[:text.index("[solver]")].replace("force = [0.0, 0.0, -750.0]", "force = [0.0, 0.0, -558.0]")
    toml = tmp_path / "roof.toml"
    toml.write_text(head +
                    '[solver]\ncontrol = "load"\nsteps = 1\n\n[output]\npicture = false\nvtu = false\nplots = false\n')
    root = str(ROOF.parents[1])
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1", OMPI_MCA_rmaps_base_oversubscribe="1",
               PYTHONPATH=root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = ["mpirun", "-n", "2", "-x", "PYTHONPATH", "-x", "OMP_NUM_THREADS", "-x", "NUMBA_NUM_THREADS",
           sys.executable, "-m", "core_se3", "run", str(toml), "--out", str(tmp_path / "two")]
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=600, cwd=root)
    assert p.returncode == 3, p.stdout[-3000:] + p.stderr[-3000:]
    two = json.loads((tmp_path / "two" / "results.json").read_text())
    assert two["provenance"]["ranks"] == 2
    with pytest.raises(Exception):
        runner.run(scenario.load(str(toml)), out=str(tmp_path / "one"))
    one = json.loads((tmp_path / "one" / "results.json").read_text())
    hint = r"last converged load factor is 0\.999268 .*S_p = 0\.0136 of its initial value: load control has met a limit point"
    for doc in (one, two):
        assert re.search(hint, doc["error"]), doc["error"]

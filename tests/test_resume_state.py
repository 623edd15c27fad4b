"""A resumed load-control run takes the uninterrupted run's step checks (docs/SCENARIOS.md,
'Checkpoints and --resume'; docs/STEPS.md).

The snap roof of examples/snap-roof.toml loaded to 0.735 P_max (99 % of its limit load) and back
to 0 in 2 steps, stopped after step 1 and resumed, skipped the midpoint probe of step 2 that the
uninterrupted run made: the probe's current-stiffness record (and det K's sign) were not in the
checkpoint.  Its state agrees to the round-off of the stored frames: the roof's crown is at
z = 2540, the solver iterates relative to an origin, and the checkpoint holds the frames in the
problem's coordinates, to eps |x| = 5.6e-13 (the part far from the origin of
tests/test_step_checks.py keeps its precision by not going through them between steps)."""
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
    assert np.abs(res.g - ref.g).max() <= 4 * np.finfo(float).eps * np.abs(ref.g).max()
    steps = [json.load(open(r.files["results"]))["steps"] for r in (ref, res)]
    assert steps[0][2]["checks"]["midpoint_probes"] == 1            # the probe of step 2 (a limit point ahead)
    count = ("path_rejections", "det_sign", "midpoint_probes", "refinements")
    assert [[(s.get("checks") or {}).get(k) for k in count] for s in steps[1]] == \
        [[(s.get("checks") or {}).get(k) for k in count] for s in steps[0]]
    assert [s["iterations"] for s in steps[1]] == [s["iterations"] for s in steps[0]]


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

"""A resumed load-control run repeats the uninterrupted run's computations bit for bit, checks
included (docs/SCENARIOS.md: '--resume continues bit for bit'; docs/STEPS.md).

The snap roof of examples/snap-roof.toml (its crown at z = 2540: the solver works relative to an
origin) loaded to 0.735 P_max (99 % of its limit load) and back to 0 in 2 steps, stopped after
step 1 and resumed, ended 1.4e-14 off the uninterrupted run (its first residual of step 2
1.4e-12 relative: the resume starts from the stored whole frames moved to the origin, the
uninterrupted run from its iterate), and it skipped the midpoint probe of step 2 that the
uninterrupted run made (the probe's current-stiffness record was not in the checkpoint)."""
import json
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
    np.testing.assert_array_equal(res.g, ref.g)
    steps = [json.load(open(r.files["results"]))["steps"] for r in (ref, res)]
    assert steps[0][2]["checks"]["midpoint_probes"] == 1            # the probe of step 2 (a limit point ahead)
    assert [s.get("checks") for s in steps[1]] == [s.get("checks") for s in steps[0]]
    assert [s.get("residual_history") for s in steps[1]] == [s.get("residual_history") for s in steps[0]]

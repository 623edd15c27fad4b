"""The control example (examples/gripper_control.py, issue 32) is a literate script whose asserts
are its checks: the planned field trajectory reaches every sample of the fingertip's figure
eight within 1e-4 mm and replays exactly, the closed loop (Jacobian feedback, one warm update
per cycle) tracks the figure within its stated bound, and with a model error (E x 1.1) the
feedback keeps the tip within a tenth of the open loop's miss.  Run here with --quick (fewer
samples, looser bound: 80 cycles, 1e-2 mm)."""
import os
import runpy
import sys

EXAMPLE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "examples", "gripper_control.py")


def test_gripper_control_example(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", [EXAMPLE, str(tmp_path), "--quick"])
    runpy.run_path(EXAMPLE, run_name="__main__")
    out = capsys.readouterr().out
    assert "all 13 samples within 0.0001" in out
    assert "closed loop: 80 cycles" in out and "cycles/s" in out

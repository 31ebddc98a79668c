"""The ``pendulab swingup`` command, run briefly."""

import json

from pendulab.cli import main


def test_cli_writes_results_and_reports_success(tmp_path):
    status = main(["swingup", "--task", "acrobot", "--N", "50", "--out", str(tmp_path), "--no-gif"])
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert status == 0 and summary["success"]
    assert summary["max_torque_Nm"] <= 6.0 and summary["swing_up_time_s"] < summary["horizon_s"]
    for name in ("closed_loop.csv", "optimal.csv", "states_torques.png", "phase.png", "height.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_cli_bad_input_exits_2(tmp_path, capsys):
    assert main(["swingup", "--task", "nope", "--out", str(tmp_path)]) == 2
    assert "unknown task" in capsys.readouterr().err

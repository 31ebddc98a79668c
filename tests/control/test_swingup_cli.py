"""The ``pendulab swingup`` command, run briefly."""

import json

from pendulab.cli import main


def test_cli_writes_results_and_reports_success(tmp_path, capsys):
    status = main(["swingup", "--task", "acrobot", "--N", "50", "--out", str(tmp_path), "--no-gif", "--tolerance", "2e-3"])
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert status == 0 and summary["success"]
    assert summary["max_torque_Nm"] <= 6.0 and summary["swing_up_time_s"] < summary["horizon_s"]
    for name in ("closed_loop.csv", "optimal.csv", "states_torques.png", "phase.png", "height.png", "error.png"):
        assert (tmp_path / name).stat().st_size > 0
    # The error estimate: per interval on the final mesh, its worst, the tolerance asked for, pass/fail.
    assert summary["error_tolerance"] == 2e-3 and summary["error_passed"]
    assert len(summary["error_interval_worst"]) == summary["N"] == len(summary["mesh_t_s"]) - 1
    assert max(summary["error_interval_worst"]) == summary["error_worst"] <= 2e-3
    assert summary["planning_model"] == "rigid" and summary["build_time_s"] >= 0.0
    assert "error estimate" in capsys.readouterr().out


def test_cli_no_refine_reports_the_estimate_of_the_first_mesh(tmp_path):
    main(["swingup", "--task", "acrobot", "--N", "50", "--out", str(tmp_path), "--no-gif", "--no-refine"])
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["N"] == 50 and summary["refinements"] == 0 and "error_worst" in summary


def test_cli_bad_input_exits_2(tmp_path, capsys):
    assert main(["swingup", "--task", "nope", "--out", str(tmp_path)]) == 2
    assert "unknown task" in capsys.readouterr().err
    assert main(["swingup", "--task", "acrobot", "--tolerance", "0", "--out", str(tmp_path)]) == 2
    assert "--tolerance" in capsys.readouterr().err

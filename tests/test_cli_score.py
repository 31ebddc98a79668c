"""The ``pendulab score`` command: scorecard files and JSON, bad input, Ctrl-C, --realai wiring."""

from __future__ import annotations

import json

import pytest

from pendulab.cli import main
from pendulab.control.realai.spec import PLAN_VELOCITY_LIMIT_HW


def test_score_writes_json_markdown_png(tmp_path, capsys):
    argv = ["score", "--controller", "lqr", "--task", "pendubot", "--runs", "2", "--categories", "delay,torque_noise"]
    status = main([*argv, "--json", "--out", str(tmp_path), "--no-progress", "--workers", "1"])
    assert status == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads((tmp_path / "scorecard.json").read_text())
    assert printed["categories"] == written["categories"]
    assert [c["name"] for c in written["categories"]] == ["delay", "torque_noise"]
    # delay is deterministic (one run per level), torque noise stochastic (--runs per level).
    assert written["categories"][0]["runs"] == [1] * 5 and written["categories"][1]["runs"] == [2] * 5
    # LQR balance started hanging never swings up: every run fails, and says why.
    assert written["overall"] == 0.0 and written["n_runs"] == 15 and len(written["failures"]) == 15
    assert all("end effector below" in f["reason"] for f in written["failures"])
    assert "| delay |" in (tmp_path / "scorecard.md").read_text()
    assert (tmp_path / "scorecard.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--controller", "pid", "--task", "pendubot"], "--controller 'pid'"),
        (["--controller", "lqr", "--task", "nope"], "unknown task"),
        (["--controller", "lqr", "--task", "pendubot", "--categories", "gravity"], "unknown ['gravity']"),
        (["--controller", "lqr", "--task", "pendubot", "--runs", "0"], "--runs = '0': out of range; expected an integer in [1, "),
        (["--controller", "lqr", "--task", "pendubot", "--categories", "stiffness"], "does not apply"),
        (["--task", "pendubot"], "--controller and --task are required"),
        (["--realai", "--controller", "best", "--task", "pendubot_elastic"], "pendubot or acrobot"),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, message, capsys):
    assert main(["score", *argv, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_ctrl_c_exits_130(monkeypatch, capsys, tmp_path):
    import pendulab.evaluate as sc

    monkeypatch.chdir(tmp_path)  # the default output directory is ./pendulab-out/score/...

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(sc, "score", interrupted)
    assert main(["score", "--controller", "lqr", "--task", "pendubot", "--no-progress"]) == 130
    assert "interrupted" in capsys.readouterr().err


def test_realai_calls_realai_score(monkeypatch, tmp_path, capsys):
    realai = pytest.importorskip("pendulab.evaluate.realai")
    calls = {}

    class Result:
        def to_dict(self):
            return {"task": "acrobot", "controller": "best", "success": True, "score": 0.5, "criteria": {"swingup_time": 1.0}}

    def fake(task, controller="best", *, csv_path=None, progress=None, plant=None):
        calls.update(task=task, controller=controller, csv_path=csv_path, plant=plant)
        return Result()

    monkeypatch.setattr(realai, "realai_score", fake, raising=False)
    status = main(["score", "--realai", "--task", "acrobot", "--controller", "best", "--out", str(tmp_path), "--json"])
    assert status == 0
    # the command writes realai.csv itself; no --plant: the nominal plant
    assert calls == {"task": "acrobot", "controller": "best", "csv_path": None, "plant": None}
    assert json.loads(capsys.readouterr().out)["score"] == 0.5
    assert json.loads((tmp_path / "realai.json").read_text())["success"] is True


def test_score_help_names_every_controller_each_mode_accepts():
    from pendulab.commands import score as cmd
    from pendulab.control.controllers import TASK_CONTROLLERS
    from pendulab.evaluate.realai.controllers import CONTROLLERS

    assert cmd._SCORECARD_CONTROLLERS == tuple(TASK_CONTROLLERS)
    assert cmd._REALAI_CONTROLLERS == tuple(CONTROLLERS)


def test_v3_hardware_protocol_is_a_cli_protocol_and_refuses_options_it_does_not_take(capsys, monkeypatch, tmp_path):
    import pendulab.evaluate.realai.v3_hardware as hw

    monkeypatch.chdir(tmp_path)
    assert main(["score", "--protocol", "v3-hardware", "--controller", "best", "--task", "pendubot", "--workers", "2"]) == 2
    err = capsys.readouterr().err
    assert "--protocol v3-hardware" in err and "--workers" in err and err.count("\n") == 1
    # The command runs the hardware protocol (not the simulation one) with the seed and controller given.
    seen = {}

    def fake(task, controller, **kw):
        seen.update(task=task, controller=controller, **kw)
        raise ValueError("stop here")

    monkeypatch.setattr(hw, "v3_hardware_score", fake)
    argv = ["score", "--protocol", "v3-hardware", "--controller", "best", "--task", "acrobot", "--seed", "777", "--no-progress"]
    assert main(argv) == 2
    assert seen["task"] == "acrobot" and seen["controller"] == "best" and seen["seed"] == 777
    assert "--protocol v3-hardware (--controller 'best'): stop here" in capsys.readouterr().err


def test_v3_hardware_passive_allowance_is_passed_recorded_and_refused_elsewhere(capsys, monkeypatch, tmp_path):
    import functools

    import pendulab.evaluate.realai.v3_hardware as hw

    monkeypatch.chdir(tmp_path)
    base = ["score", "--controller", "lqr", "--task", "pendubot", "--no-progress"]
    # Only the hardware protocol takes it; out of its declared range it is refused before any work.
    for other in (["--protocol", "v3"], ["--protocol", "robustness-v2"], ["--realai"], []):
        assert main([*base, *other, "--passive-allowance", "0.5"]) == 2
        assert "--passive-allowance applies to --protocol v3-hardware and to --leaderboard" in capsys.readouterr().err
    assert main([*base, "--protocol", "v3-hardware", "--passive-allowance", "0.7"]) == 2
    assert "--passive-allowance = '0.7': out of range; expected a finite number in [0, 0.5] N.m" in capsys.readouterr().err
    # The real runner, on a 0.2 s episode instead of 60 s (the CLI's wiring is under test, not the score).
    monkeypatch.setattr(hw, "run_v3_hardware", functools.partial(hw.run_v3_hardware, duration=0.2))
    assert main([*base, "--protocol", "v3-hardware", "--passive-allowance", "0.5", "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads((tmp_path / "pendulab-out/score/v3-hardware-lqr-pendubot-allowance0.5/v3_hardware.json").read_text())
    assert printed["passive_allowance"] == written["passive_allowance"] == 0.5
    assert written["simulation"]["entry_torque_limit"] == [6.0, 0.5]
    assert written["entry"] == {"velocity_limit": None, "friction_compensated": True}  # lqr plans nothing to bound
    # Without the option: no allowance, no compensation, its own default directory.
    assert main([*base, "--protocol", "v3-hardware"]) == 0
    plain = json.loads((tmp_path / "pendulab-out/score/v3-hardware-lqr-pendubot/v3_hardware.json").read_text())
    assert plain["passive_allowance"] == 0.0 and plain["simulation"]["entry_torque_limit"] == [6.0, 0.0]
    assert plain["entry"]["friction_compensated"] is False
    assert "max measured joint rate" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("controller", "protocol", "bound"),
    [
        ("library", "v3", None),
        ("library", "v3-hardware", PLAN_VELOCITY_LIMIT_HW),
        ("mpc_library", "v3", PLAN_VELOCITY_LIMIT_HW),
        ("mpc_library", "v3-hardware", PLAN_VELOCITY_LIMIT_HW),
    ],
)
def test_plan_library_players_build_their_library_first_with_the_bound_they_play(
    capsys, monkeypatch, tmp_path, controller, protocol, bound
):
    # Every controller that plays the cached plan library gets it built (minutes at first use) before the run, with
    # the rate bound it will play with, so the run itself never plans silently.
    import pendulab.control.plan_library as pl_lib
    import pendulab.evaluate.realai.v3 as v3
    import pendulab.evaluate.realai.v3_hardware as hw

    monkeypatch.chdir(tmp_path)
    built = []

    def fake_library(task, *, progress=None, velocity_limit=None, **_):
        built.append((task, velocity_limit))
        progress(1, 1)

    def stop(task, controller, **kw):
        raise ValueError("stop here")

    monkeypatch.setattr(pl_lib, "library_controller", fake_library)
    monkeypatch.setattr(hw, "v3_hardware_score", stop)
    monkeypatch.setattr(v3, "v3_score", stop)
    argv = ["score", "--protocol", protocol, "--controller", controller, "--task", "acrobot", "--no-progress"]
    assert main(argv) == 2
    assert built == [("acrobot", bound)]
    assert "stop here" in capsys.readouterr().err


def test_library_bound_refuses_a_controller_without_a_library():
    from pendulab.evaluate.realai.controllers import library_bound

    with pytest.raises(ValueError, match="plays no plan library"):
        library_bound("mpc", True)

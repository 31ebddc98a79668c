"""`pendulab cosim` and `pendulab cosim sweep` end to end, and the example."""

from __future__ import annotations

import csv
import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from pendulab.cli import main

ROOT = Path(__file__).resolve().parents[2]


def test_cosim_cli_writes_csv_plot_gif(cosim_fmu, tmp_path, capsys):
    out = tmp_path / "run"
    fmu = cosim_fmu("rigid", 2)
    assert (
        main(
            [
                "cosim",
                "--fmu",
                str(fmu),
                "--controller",
                "swingup",
                "--comm-step",
                "0.02",
                "--t-final",
                "6",
                "--gif-fps",
                "5",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    rows = list(csv.reader((out / "cosim.csv").open()))
    assert rows[0][:5] == ["t", "theta1", "theta2", "omega1", "omega2"]
    data = np.array(rows[1:], dtype=float)
    assert len(data) == 301 and data[-1, 0] == 6.0
    # Swung up and balanced: both angles within 0.05 rad of upright (+-pi) at the end.
    assert np.all(np.abs(np.abs(data[-1, 1:3]) - np.pi) < 0.05)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["caught_at"] is not None and summary["max_abs_torque"] <= 20.0
    gif = Image.open(out / "cosim.gif")
    assert gif.n_frames == 31  # 5 frames per simulated second over 6 s
    assert (out / "cosim.png").stat().st_size > 20_000
    assert "co-simulated" in capsys.readouterr().out


@pytest.mark.parametrize(("task", "solver", "tol"), [("pendubot", "dopri5", "1e-8"), ("acrobot", "dopri5", "1e-10")])
def test_cosim_cli_energy_swingup_on_a_task_succeeds(task, solver, tol, tmp_path):
    """`pendulab cosim --controller swingup --task ...`: the path that used to fail (the sampled pumping loop's chatter
    made the outcome depend on the solver and tolerance: both of these failed; docs/leaderboard.md has the whole grid)."""
    out = tmp_path / task
    argv = ["cosim", "--controller", "swingup", "--task", task, "--solver", solver, "--tolerance", tol]
    assert main([*argv, "--no-gif", "--no-progress", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["success"] is True and summary["caught_at"] is not None, summary


def test_cosim_cli_tracks_a_reference_csv(cosim_fmu, tmp_path):
    import pendulab as pl
    from pendulab.control.feedback import as_feedback, energy_swingup

    model = pl.rigid()
    ref = pl.simulate(model, model.state(theta1=0.2), 5.0, dt=0.01, u=as_feedback(energy_swingup(model, 0.01), model))
    csv_path = ref.to_csv(tmp_path / "ref.csv")
    out = tmp_path / "track"
    argv = ["cosim", "--fmu", str(cosim_fmu("rigid", 2)), "--controller", "tvlqr", "--reference", str(csv_path)]
    assert main([*argv, "--t-final", "7", "--no-gif", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["x0"]["theta1"] == 0.2  # starts where the reference starts
    # Tracked and handed over to balance: upright (+-pi) within 1e-2 rad at 7 s.
    assert abs(abs(summary["x_final"]["theta1"]) - np.pi) < 1e-2
    assert main(["cosim", "--fmu", str(cosim_fmu("rigid", 2)), "--reference", str(csv_path), "--out", str(out)]) == 2


def test_cosim_cli_bad_input(cosim_fmu, tmp_path, capsys):
    fmu = str(cosim_fmu("rigid", 2))
    assert main(["cosim", "--fmu", fmu, "--comm-step", "-0.01", "--out", str(tmp_path)]) == 2
    assert "--comm-step = '-0.01': out of range; expected a finite number in [1e-06, 10] s" in capsys.readouterr().err
    assert main(["cosim", "--fmu", fmu, "--init", "phi=1", "--out", str(tmp_path)]) == 2
    assert "--init: expected NAME=VALUE" in capsys.readouterr().err
    assert main(["cosim", "--fmu", str(tmp_path / "nope.fmu"), "--out", str(tmp_path)]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["cosim", "sweep", "--steps", "0.1:0.05:0.01", "--out", str(tmp_path)]) == 2
    assert "--steps" in capsys.readouterr().err


def test_cosim_sweep_cli(cosim_fmu, tmp_path, capsys):
    out = tmp_path / "sweep"
    args = ["cosim", "sweep", "--kinds", "rigid", "--fmu-rigid", str(cosim_fmu("rigid", 2)), "--steps", "0.17,0.18"]
    assert main([*args, "--out", str(out), "--json"]) == 0
    crit = json.loads((out / "sweep.json").read_text())[0]
    assert json.loads(capsys.readouterr().out)["critical_steps"] == [crit]  # --json prints what sweep.json holds
    assert 0.17 < crit["h_crit_pred"] < 0.18  # predicted crossing (175.2 ms)
    assert abs(crit["h_crit_meas"] - crit["h_crit_pred"]) < 1e-3
    assert "| 0.17 |" in (out / "sweep.md").read_text()


def test_example_runs(cosim_fmu, tmp_path):
    spec = importlib.util.spec_from_file_location("cosimulate_fmu", ROOT / "examples" / "cosimulate_fmu.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.run(t_final=1.0, fmus=(cosim_fmu("rigid", 2), cosim_fmu("elastic", 2)), out_dir=tmp_path)
    assert out["max_state_diff_native"] < 1e-6  # the equivalence bound of test_cosim
    assert out["n_rejected"] > 0 and out["retry_vs_plain"] < 1e-7
    assert 0 < out["rigid_vs_elastic"] < 0.01  # k = 5e4 N/m: 5.7e-3 rad over 1 s
    assert (tmp_path / "side_by_side.png").stat().st_size > 20_000


def test_cosim_cli_json_and_torque_limit_figure(cosim_fmu, tmp_path, capsys):
    out = tmp_path / "json"
    fmu = str(cosim_fmu("rigid", 2))
    # Energy swing-up at a 2 N.m limit: the torque saturates while pumping, so the limit lines are drawn.
    argv = ["cosim", "--fmu", fmu, "--controller", "swingup", "--u-max", "2", "--t-final", "3", "--no-gif", "--json"]
    assert main([*argv, "--out", str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)  # the whole of stdout is one JSON object
    assert summary == json.loads((out / "summary.json").read_text())
    assert summary["torque_limit"] == 2.0 and summary["max_abs_torque"] == pytest.approx(2.0)  # saturated at the limit
    with Image.open(out / "cosim.png") as im:
        assert im.size[1] > 700  # three panels and the title
    # Options that do not apply are errors, not ignored.
    assert main(["cosim", "--fmu", fmu, "--kind", "elastic", "--out", str(out)]) == 2
    assert "--kind" in capsys.readouterr().err


def test_plot_cosim_marks_binding_limit_and_solve_times(tmp_path):
    from dataclasses import replace

    import pendulab as pl
    from pendulab.cosim.plots import plot_cosim

    model = pl.rigid()
    traj = pl.simulate(model, model.state(theta1=0.3), 2.0, dt=0.01)
    u = np.zeros((traj.t.size, 2))
    u[:50, 0] = 1.5  # on the limit for the first half second
    held = replace(traj, u=u)
    plain = plot_cosim(held, tmp_path / "plain.png", "t")
    path = plot_cosim(held, tmp_path / "c.png", "t", torque_limit=1.5, solve_times=[0.002] * 100, sample_time=0.02)
    with Image.open(path) as im, Image.open(plain) as im0:
        assert im.size[1] > im0.size[1]  # one more panel: the solve times

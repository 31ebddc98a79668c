"""Control surface under bad input and budgets: one task-name rule, checked sizes, inapplicable options, resumable scorecards."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulab.cli import main
from pendulab.control.controllers import controller_for_task
from pendulab.control.nmpc import NMPCOptions, nmpc_controller, nmpc_for_task
from pendulab.control.swingup.iterations import iteration_hook
from pendulab.control.swingup.solve import solve_transcription as swing_up
from pendulab.control.swingup.tasks import load_task, resolve_task
from pendulab.evaluate.scorecard import score


@pytest.fixture(scope="module")
def pendubot():
    return load_task("pendubot")


# -- one task-name rule --------------------------------------------------------------


def test_task_names_short_with_long_aliases(pendubot):
    assert pendubot.name == "pendubot"
    assert load_task("swingup_pendubot").name == "pendubot"  # the long form is an alias of the same task
    assert resolve_task("swingup_acrobot").problem.actuation == "acrobot"
    assert resolve_task(pendubot) is pendubot


@pytest.mark.parametrize("bad", [None, 3, ["pendubot"]])
def test_non_task_is_a_type_error_naming_the_argument(bad):
    with pytest.raises(TypeError, match="task must be a swing-up Task or a task name"):
        controller_for_task("lqr", bad)
    with pytest.raises(TypeError, match="task must be"):
        score("lqr", bad)
    with pytest.raises(TypeError, match="task must be"):
        nmpc_for_task(bad)


def test_every_entry_point_accepts_the_task_name():
    ctrl, x0 = controller_for_task("lqr", "pendubot")
    assert ctrl.input_names == ("tau1",) and np.allclose(x0, 0.0)  # pendubot drives tau1, starts hanging at rest
    card = score("lqr", "swingup_pendubot", runs=1, categories=["delay"], workers=1)
    assert card.task == "pendubot" and card.overall == 0.0  # balance-only LQR never swings up from hanging


# -- NMPC ------------------------------------------------------------------------------


def test_nmpc_sizes_are_bounded_before_planning(pendubot):
    # The bound fails at once: no swing-up is planned, no NLP of 10^7 intervals is built.
    with pytest.raises(ValueError, match=r"horizon = 10000000: out of range; expected an integer in \[1, 500\]"):
        nmpc_for_task(pendubot, horizon=10**7)
    with pytest.raises(ValueError, match="r = 'x': a str, not a number"):
        nmpc_for_task(pendubot, r="x")
    with pytest.raises(TypeError, match="unknown NMPC option"):
        nmpc_for_task(pendubot, horizn=10)
    # Only the CLI parses text: a numeric string is refused; a whole float is the count it spells.
    with pytest.raises(ValueError, match="r = '1': a str, not a number"):
        NMPCOptions(r="1")
    assert isinstance(NMPCOptions(horizon=20.0).horizon, int) and NMPCOptions(r=1).r == 1.0


def test_plan_lengths_are_bounded_and_named():
    import pendulab as pl
    from pendulab.control.controllers import make_controller
    from pendulab.control.nmpc import nmpc_swingup

    # Both fail at once, naming the argument and the limit, instead of building a plan of 10^7 intervals.
    with pytest.raises(ValueError, match=r"horizon = 1000000.0: out of range; expected a finite number in \(0, 30\] s"):
        nmpc_swingup(pl.rigid(), horizon=1e6)
    with pytest.raises(ValueError, match=r"t_ref must be at most 1000000 samples"):
        make_controller("tvlqr", pl.rigid(), 0.01, t_ref=1e9)
    with pytest.raises(TypeError, match="model must be a pendulab Model"):
        make_controller("lqr", "rigid", 0.01)


def test_nmpc_before_time_zero_is_a_value_error(pendubot):
    ctrl = nmpc_controller(pendubot.model, actuation="pendubot", u_max=6.0, horizon=5)
    x = np.array([np.pi, np.pi, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"t must be a finite time >= 0 \[s\].*got -0.02"):
        ctrl(-0.02, x)
    with pytest.raises(ValueError, match="t must be"):
        ctrl("soon", x)
    assert ctrl(0.0, x).shape == (1,)  # still usable after the refused calls


def test_nmpc_solve_time_budget_falls_back(pendubot):
    x = np.array([np.pi - 0.1, np.pi, 0.0, 0.0])
    capped = nmpc_controller(pendubot.model, actuation="pendubot", u_max=6.0, horizon=10, solver="ipopt", max_solve_time=1e-6)
    u = capped(0.0, x)
    # IPOPT stopped by the budget: a counted failure, and the LQR fallback torque within the limit instead.
    assert capped.last_status == "Maximum_WallTime_Exceeded" and capped.failures == 1
    assert np.all(np.isfinite(u)) and abs(u[0]) <= 6.0
    with pytest.raises(ValueError, match=r"max_solve_time = 0.0: out of range; expected a finite number in \(0, 60\] s"):
        NMPCOptions(max_solve_time=0.0)


# -- scorecard ---------------------------------------------------------------------------


def test_score_arguments_name_themselves(pendubot):
    with pytest.raises(ValueError, match="seed = 'x': a str, not a number"):
        score("lqr", pendubot, seed="x")
    with pytest.raises(ValueError, match=r"runs = 100000000: out of range; expected an integer in \[1, 5000\]"):
        score("lqr", pendubot, runs=100_000_000, categories=["measurement_noise"])
    with pytest.raises(TypeError, match="categories must be a sequence"):
        score("lqr", pendubot, categories="delay")


def test_scorecard_records_batches_and_resumes(pendubot):
    seen = []
    kw = dict(runs=2, categories=["delay", "torque_noise"], workers=1)
    full = score("lqr", pendubot, on_records=lambda recs: seen.append(len(recs)), **kw)
    # Records arrive batch by batch, whole levels at a time, ending with every run.
    assert seen == sorted(seen) and seen[-1] == len(full.records) == 15 and len(seen) >= 2
    calls = []
    resumed = score("lqr", pendubot, completed=full.records[:9], progress=lambda d, t: calls.append(d), **kw)
    same = [(r.category, r.level_index, r.run, r.seed, r.success, r.reason) for r in full.records]
    # Seeded runs: resuming gives the same card (t_up is nan on failures, so it is compared apart).
    assert [(r.category, r.level_index, r.run, r.seed, r.success, r.reason) for r in resumed.records] == same
    assert np.array_equal([r.t_up for r in resumed.records], [r.t_up for r in full.records], equal_nan=True)
    assert calls[0] == 9  # the completed runs are not run again
    other = score("lqr", pendubot, runs=1, categories=["delay"], workers=1).records
    with pytest.raises(ValueError, match="not a run of this scorecard"):
        score("lqr", pendubot, completed=other[:1], runs=2, categories=["torque_noise"], workers=1)


def test_scorecard_wall_time_budget_keeps_finished_batches(pendubot):
    seen = []
    with pytest.raises(TimeoutError, match="wall-time budget"):
        # A budget far below one batch: the first batch runs (it is not cut), the next one is not started.
        score("lqr", pendubot, runs=2, categories=["delay", "torque_noise"], workers=1, max_wall_time=1e-9,
              on_records=lambda recs: seen.append(len(recs)))  # fmt: skip
    assert seen == []  # the budget was spent before the first batch (controller design included)


# -- swing-up: bounded, budgeted, observable ----------------------------------------------


def test_swingup_size_and_wall_time_budget(pendubot):
    with pytest.raises(ValueError, match=r"N = 1000000: out of range; expected an integer in \[2, 1000\]"):
        swing_up(pendubot.problem, "radau", 10**6)
    res = swing_up(pendubot.problem, "radau", 40, max_wall_time=1e-3)
    assert not res.success and "wall-time budget" in res.message


def test_iteration_hook_sees_every_ipopt_iteration_and_can_stop(pendubot):
    count = []
    with iteration_hook(lambda: count.append(1)):
        res = swing_up(pendubot.problem, "radau", 30, tolerance=None)
    # One call per IPOPT iteration plus the initial point (the solve's own count is per stage, summed).
    assert res.success and len(count) == res.iterations + len(res.stages)
    with iteration_hook(lambda: True):
        stopped = swing_up(pendubot.problem, "radau", 30, tolerance=None, guess="linear")
    assert not stopped.success and stopped.status == "User_Requested_Stop"


# -- CLI: inapplicable options and sizes are errors -------------------------------------


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["score", "--realai", "--controller", "lqr", "--task", "pendubot", "--categories", "mass"],
            "--categories does not apply",
        ),
        (["score", "--realai", "--controller", "lqr", "--task", "pendubot", "--seed", "1"], "--seed does not apply"),
        (["score", "--realai", "--controller", "lqr", "--task", "pendubot", "--workers", "2"], "--workers does not apply"),
        (["score", "--leaderboard", "--seed", "3"], "--seed does not apply to --leaderboard"),
        (
            ["score", "--controller", "lqr", "--task", "pendubot", "--runs", "100000000"],
            "--runs = '100000000': out of range; expected an integer in [1, 5000]",
        ),
        (["score", "--realai", "--controller", "lqr", "--task", "pendubot_elastic"], "pendubot or acrobot"),
        (["cosim", "--task", "pendubot", "--u-max", "3"], "--u-max cannot be combined"),
        (["cosim", "--task", "pendubot", "--actuation", "full"], "--actuation cannot be combined"),
        (["cosim", "--task", "pendubot", "--kind", "elastic"], "--kind cannot be combined"),
        (["cosim", "--task", "pendubot", "--controller", "nmpc", "--t-final", "1e9"], "at most 1000000"),
        (
            ["cosim", "--task", "pendubot", "--tolerance", "1"],
            "--tolerance = '1': out of range; expected a finite number in [2.22e-16, 1)",
        ),
        (["swingup", "--task", "pendubot", "--N", "1000000"], "--N = '1000000': out of range; expected an integer in [2, 1000]"),
        (["swingup", "--task", "pendubot", "--planning", "elastic"], "applies to elastic tasks only"),
    ],
)
def test_cli_refuses_with_one_line(argv, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # nothing may be written anyway
    assert main([*argv, "--no-progress"] if argv[0] == "score" else argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "pendulab-out").exists()  # refused before anything is written (not even a directory)


def test_score_default_output_and_resume(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    argv = ["score", "--controller", "lqr", "--task", "swingup_pendubot", "--runs", "1", "--categories", "delay",
            "--workers", "1", "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    out = tmp_path / "pendulab-out" / "score" / "lqr-pendubot"  # default, short task name
    records = json.loads((out / "records.json").read_text())
    assert records["meta"]["complete"] is True and len(records["records"]) == 5
    capsys.readouterr()
    assert main([*argv, "--resume", "--json"]) == 0
    card = json.loads(capsys.readouterr().out)
    assert card["task"] == "pendubot" and card["n_runs"] == 5
    # Other settings cannot resume these records.
    assert main([*argv[:5], "--runs", "1", "--categories", "delay", "--seed", "4", "--resume", "--no-progress"]) == 2
    assert "other settings" in capsys.readouterr().err


def test_leaderboard_default_is_not_the_shipped_docs_page():
    from pendulab.commands.leaderboard import DEFAULT_PATH

    assert DEFAULT_PATH.parts[:2] == ("pendulab-out", "leaderboard") and "docs" not in DEFAULT_PATH.parts


def test_swingup_json_is_one_object_on_stdout(tmp_path, capsys):
    argv = ["swingup", "--task", "pendubot", "--N", "30", "--no-refine", "--no-gif", "--json", "--no-progress"]
    status = main([*argv, "--out", str(tmp_path)])
    out = capsys.readouterr().out
    summary = json.loads(out)  # the whole of stdout is one JSON object
    assert summary["task"] == "pendubot" and summary["N"] == 30 and status == (0 if summary["success"] else 1)
    assert json.loads((tmp_path / "summary.json").read_text())["N"] == 30

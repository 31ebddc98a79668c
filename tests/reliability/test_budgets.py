"""Issue 15 (reliability): integrations end in a SimulationError within a budget, never hang,
report the time they reached, and leave Ctrl-C a KeyboardInterrupt.

Each run is bounded to well under a second by its budget (or by the interrupt).
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

import pendulab as pl
from pendulab import SimulationError

CHAOTIC = np.array([2.0, 2.0, 0.0, 0.0])
#: Ceiling [s] on how long a budgeted or interrupted run may take to stop: a hang guard, not a speed test (stops
#: take well under a second on an idle machine; a loaded 2-core CI host can be 10x slower).
HANG_GUARD_S = 60.0


def _stiff() -> tuple[pl.Model, np.ndarray]:
    model = pl.elastic(k1=1e8, k2=1e8)
    return model, model.state(theta1=0.3, theta2=0.3)


# -- 4. the time actually reached, no SUNDIALS output --------------------------------------
def test_cvodes_failure_reports_the_time_reached_and_prints_nothing(capfd):
    model = pl.rigid()
    with pytest.raises(SimulationError) as exc:
        pl.simulate(model, model.state(theta1=1.0), 1e9, dt=1e8, method="cvodes")
    # 100 000 steps of a 1e-8-tolerance pendulum cover a few hundred seconds, far from 0 and from 1e8.
    assert 10.0 < exc.value.t_reached < 1e5
    assert f"failed at t = {exc.value.t_reached:.6g} s" in str(exc.value)
    assert "CV_TOO_MUCH_WORK" in str(exc.value) and ".cpp" not in str(exc.value)
    out = capfd.readouterr()
    assert "mxstep" not in out.err and "mxstep" not in out.out


# -- 5. Ctrl-C is a KeyboardInterrupt, not a solver failure ---------------------------------
@pytest.mark.parametrize("method", ["cvodes", "collocation", "RK45"])
def test_sigint_during_integration_is_a_keyboard_interrupt(method):
    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals are delivered to the main thread")
    timer = threading.Timer(0.3, lambda: os.kill(os.getpid(), signal.SIGINT))
    start = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            # Long enough to be interrupted (seconds of work), within a budget large enough not to end first.
            pl.simulate(
                pl.rigid(), CHAOTIC, 300.0, dt=1.0 if method == "collocation" else 300.0, method=method,
                rtol=1e-12, atol=1e-12, options={"max_steps": 10**8},
            )  # fmt: skip
    finally:
        timer.cancel()
    assert time.perf_counter() - start < HANG_GUARD_S
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # the front end restored the handler


# -- 8. budgets ------------------------------------------------------------------------------
def test_scipy_step_budget_names_steps_time_and_hint():
    with pytest.raises(SimulationError, match=r"step budget exhausted: 200 steps taken, options max_steps = 200") as exc:
        pl.simulate(pl.rigid(), CHAOTIC, 10.0, method="RK45", rtol=1e-10, atol=1e-10, options={"max_steps": 200})
    assert exc.value.n_steps == 200 and 0.0 < exc.value.t_reached < 10.0
    assert "stiff springs need an implicit method" in str(exc.value)


def test_stiff_rk45_ends_at_its_wall_time_budget():
    model, x0 = _stiff()
    start = time.perf_counter()
    with pytest.raises(SimulationError, match="wall-time budget exhausted") as exc:
        pl.simulate(model, x0, 1.0, method="RK45", max_step=1e-6, options={"max_wall_time": 0.3})
    assert time.perf_counter() - start < HANG_GUARD_S  # checked at every RHS evaluation (0.3 s + a few ms when idle)
    assert exc.value.n_steps > 0 and 0.0 < exc.value.t_reached < 1.0
    assert "stiff springs" in str(exc.value)


def test_scipy_stats_count_steps():
    tr = pl.simulate(pl.rigid(), [0.5, 0, 0, 0], 1.0, method="DOP853")
    assert tr.stats["n_steps"] > 0 and tr.stats["n_rhs"] >= tr.stats["n_steps"]


def test_casadi_step_and_wall_budgets():
    with pytest.raises(SimulationError, match=r"step budget exhausted: \d+ steps taken, options max_steps = 300") as exc:
        pl.simulate(pl.rigid(), CHAOTIC, 10.0, dt=0.1, method="cvodes", rtol=1e-12, atol=1e-12, options={"max_steps": 300})
    assert exc.value.n_steps > 300 and 0.0 < exc.value.t_reached < 10.0
    start = time.perf_counter()
    with pytest.raises(SimulationError, match="wall-time budget exhausted"):
        pl.simulate(pl.rigid(), CHAOTIC, 1e4, dt=1.0, method="cvodes", rtol=1e-12, atol=1e-12, options={"max_wall_time": 0.2})
    assert time.perf_counter() - start < HANG_GUARD_S


@pytest.mark.parametrize("method", ["rk4", "collocation"])
def test_fixed_step_run_above_the_budget_is_refused_before_starting(method):
    with pytest.raises(SimulationError, match=r"needs 100000 fixed steps .* max_steps = 1000; refused before starting") as exc:
        pl.simulate(pl.rigid(), CHAOTIC, 10.0, method=method, max_step=1e-4, options={"max_steps": 1000})
    assert exc.value.t_reached == 0.0  # refused at t = 0: no step was taken


def test_wall_budget_holds_between_feedback_intervals():
    def slow(t, x):
        time.sleep(0.02)
        return np.zeros(2)

    with pytest.raises(SimulationError, match="wall-time budget exhausted") as exc:
        pl.simulate(pl.rigid(), CHAOTIC, 10.0, dt=0.01, method="rk4", u=slow, options={"max_wall_time": 0.1})
    assert 0.0 < exc.value.t_reached < 1.0


@pytest.mark.parametrize("bad", [0, -5, 2.5, True, "10"])
def test_bad_step_budget_is_a_value_error(bad):
    with pytest.raises(ValueError, match="max_steps must be an integer"):
        pl.simulate(pl.rigid(), CHAOTIC, 0.1, method="cvodes", options={"max_steps": bad})


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), "1", True])
def test_bad_wall_budget_is_a_value_error(bad):
    with pytest.raises(ValueError, match="max_wall_time"):
        pl.simulate(pl.rigid(), CHAOTIC, 0.1, method="RK45", options={"max_wall_time": bad})


def test_budget_options_do_not_reach_families_without_them():
    """rk4 accepts no options; the budget options are the front end's, so they pass."""
    tr = pl.simulate(pl.rigid(), CHAOTIC, 0.1, method="rk4", options={"max_steps": 1000, "max_wall_time": 10.0})
    assert tr.stats["n_steps"] == 100


@pytest.mark.parametrize(
    "argv",
    [
        # In their declared ranges (pendulab._inputs), each alone; together beyond the output-points budget.
        ["simulate", "--model", "rigid", "--t-final", "86400", "--dt", "1e-3"],
        ["simulate", "--model", "rigid", "--t-final", "1", "--dt", "1e-9"],
    ],
)
def test_output_grids_beyond_the_budget_are_refused_before_allocation(argv, capsys):
    from pendulab.cli import main

    assert main(argv) == 2  # not a MemoryError of 7 PiB: refused before any array exists
    err = capsys.readouterr().err
    assert "beyond the budget of 5e+06" in err and "PENDULAB_MAX_OUTPUT_POINTS" in err


def test_the_output_budget_is_named_and_overridable(monkeypatch):
    import pendulab as pl
    from pendulab._checks import BudgetError

    model = pl.rigid()
    with pytest.raises(BudgetError, match="PENDULAB_MAX_OUTPUT_POINTS"):
        pl.simulate(model, model.state(), 1.0, 1e-7)  # 1e7 + 1 points
    monkeypatch.setenv("PENDULAB_MAX_OUTPUT_POINTS", "100")
    with pytest.raises(BudgetError, match="budget of 100"):
        pl.simulate(model, model.state(), 1.0, 0.001)  # 1001 points: within the default, beyond 100
    assert len(pl.simulate(model, model.state(), 1.0, 0.02).t) == 51  # 51 points fit the raised-and-lowered budget
    monkeypatch.setenv("PENDULAB_MAX_OUTPUT_POINTS", "-3")
    with pytest.raises(BudgetError, match="must be a positive integer"):
        pl.simulate(model, model.state(), 1.0, 0.02)


# -- issue 31, item 3: one table of resource budgets, checked before any work ------------------
def _never(*args, **kwargs):
    raise AssertionError("work started: the budget must be checked before it")


def test_every_budget_is_in_the_one_table_with_its_variable_and_cost():
    from pendulab._checks import BUDGETS

    assert set(BUDGETS) == {"output_points", "repeats", "runs", "sweep_points", "frames", "image_pixels"}
    for b in BUDGETS.values():
        assert b.env.startswith("PENDULAB_MAX_") and b.default >= 1 and b.counts and b.cost


def test_a_budget_names_the_input_value_budget_and_variable_and_is_overridable(monkeypatch):
    from pendulab._checks import BudgetError, check_budget

    with pytest.raises(BudgetError, match=r"--repeats = 1000000000: .* beyond the budget of 100 .*PENDULAB_MAX_REPEATS"):
        check_budget("repeats", "--repeats", 10**9)
    monkeypatch.setenv("PENDULAB_MAX_REPEATS", "2000")
    assert check_budget("repeats", "--repeats", 1000) == 1000
    monkeypatch.setenv("PENDULAB_MAX_REPEATS", "many")
    with pytest.raises(BudgetError, match="PENDULAB_MAX_REPEATS must be a positive integer"):
        check_budget("repeats", "--repeats", 3)


@pytest.mark.parametrize(("t_final", "dt"), [("86400", "1e-3"), ("1.0", "1e-9")])
def test_scene_output_grid_beyond_the_budget_is_refused_when_read(tmp_path, capsys, t_final, dt):
    from pendulab._checks import BudgetError
    from pendulab.cli import main
    from pendulab.scene import load_scene

    path = tmp_path / "big.toml"
    path.write_text(f'[model]\nkind = "rigid"\n[simulation]\nt_final = {t_final}\ndt = {dt}\n')
    with pytest.raises(BudgetError, match=r"\[simulation\] t_final / dt = .* PENDULAB_MAX_OUTPUT_POINTS"):
        load_scene(path)  # no run, no grid: refused at reading
    assert main(["scene", "check", str(path)]) == 2
    assert "t_final / dt" in capsys.readouterr().err


def test_bench_repeats_beyond_the_budget_are_refused_before_any_run(monkeypatch, tmp_path, capsys):
    from pendulab._checks import BudgetError
    from pendulab.bench import hierarchy, workprecision
    from pendulab.cli import main
    from pendulab.scene import load_scene

    monkeypatch.setattr(workprecision, "run_work_precision", _never)
    assert main(["bench", "work-precision", "--repeats", "1000000000", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "--repeats = 1000000000" in err and "PENDULAB_MAX_REPEATS" in err
    assert not any(tmp_path.iterdir())  # no journal, no CSV
    monkeypatch.undo()
    monkeypatch.setattr(workprecision, "get_cases", _never)
    with pytest.raises(BudgetError, match="repeats = 1000000000"):
        workprecision.run_work_precision(repeats=10**9)
    monkeypatch.setattr(hierarchy, "_run_levels", _never)
    with pytest.raises(BudgetError, match="repeats = 1000000000"):
        hierarchy.check_scene(load_scene("rigid_regular"), repeats=10**9)


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--grid", "4000"], "--grid = 4000"),  # the largest declared grid: 1.6e7 runs
        (["--runs", "100000000"], "--runs = 100000000"),
        (["--repeats", "500"], "--repeats = 500"),
    ],
)
def test_bench_ensemble_sizes_beyond_the_budget_are_refused_before_any_run(monkeypatch, capsys, argv, option):
    from pendulab.bench import ensemble as eb
    from pendulab.cli import main

    monkeypatch.setattr(eb, "run_ensemble_bench", _never)
    assert main(["bench", "ensemble", *argv]) == 2
    err = capsys.readouterr().err
    assert option in err and "PENDULAB_MAX_" in err


def test_bench_ensemble_api_checks_its_budgets_before_importing_or_running(monkeypatch):
    from pendulab._checks import BudgetError
    from pendulab.bench import ensemble as eb

    monkeypatch.setattr(eb, "require_extra", _never)
    monkeypatch.setattr(eb, "flipmap_workload", _never)
    with pytest.raises(BudgetError, match=r"grid = 100000: runs .* 1e\+10 .*PENDULAB_MAX_RUNS"):
        eb.run_ensemble_bench(grid=100_000)
    with pytest.raises(BudgetError, match="repeats = 500"):
        eb.run_ensemble_bench(grid=10, repeats=500)


def test_cosim_sweep_steps_beyond_the_budget_are_refused_before_allocation(capsys):
    from pendulab.cli import main

    assert main(["cosim", "sweep", "--steps", "0.01:1e12:0.001"]) == 2  # 1e15 steps: np.arange never runs
    err = capsys.readouterr().err
    assert "--steps = 0.01:1e12:0.001" in err and "PENDULAB_MAX_SWEEP_POINTS" in err


def test_animation_frames_and_pixels_beyond_the_budget_are_refused_before_drawing(monkeypatch, tmp_path):
    from pendulab._checks import BudgetError
    from pendulab.cosim.plots import animate_cosim
    from pendulab.viz import animate as anim

    model = pl.rigid()
    runs = {"a": (model, pl.simulate(model, model.state(theta1=1.0), 2.0, 0.01))}
    monkeypatch.setattr(anim.plt, "subplots", _never)
    with pytest.raises(BudgetError, match=r"duration x fps = 2 s x 1000000000.0: .*PENDULAB_MAX_FRAMES"):
        anim.animate(runs, tmp_path / "a.gif", fps=1e9)
    with pytest.raises(BudgetError, match=r"width, dpi = 9.6, 100000: .*PENDULAB_MAX_IMAGE_PIXELS"):
        anim.animate(runs, tmp_path / "a.gif", dpi=100_000)
    with pytest.raises(BudgetError, match="max_frames = 1000000000"):
        animate_cosim(runs["a"][1], tmp_path / "c.gif", max_frames=10**9)
    assert not any(tmp_path.iterdir())


def test_figure_pixels_beyond_the_budget_are_refused_before_rendering(tmp_path):
    import matplotlib.pyplot as plt

    from pendulab._checks import BudgetError
    from pendulab.viz.save import save_figure

    fig = plt.figure(figsize=(6, 4))
    with pytest.raises(BudgetError, match=r"dpi = 100000: pixels .*PENDULAB_MAX_IMAGE_PIXELS"):
        save_figure(fig, tmp_path / "f.png", dpi=100_000)  # 2.4e11 px: never rendered
    assert not plt.fignum_exists(fig.number) and not any(tmp_path.iterdir())
    assert save_figure(plt.figure(figsize=(2, 2)), tmp_path / "g.png", dpi=50).exists()

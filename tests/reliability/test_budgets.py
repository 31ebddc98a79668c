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
        ["simulate", "--model", "rigid", "--t-final", "1e12", "--dt", "1e-3"],
        ["simulate", "--model", "rigid", "--t-final", "1", "--dt", "1e-12"],
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

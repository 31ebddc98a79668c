"""The v3-hardware protocol (pendulab.evaluate.realai.v3_hardware): resets, sensing, timing, limits, options."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.evaluate.realai.v3_definition import reset_schedule
from pendulab.evaluate.realai.v3_hardware import (
    N_RESETS_HW,
    RESET_LENGTH_HW,
    FrictionCompensated,
    run_v3_hardware,
)
from pendulab.identify.sensing import c1_sensing
from pendulab.model.plant_file import load_plant


class _Const:
    """Entry that commands constant torques (tau1, tau2), upstream style (relative state in)."""

    def __init__(self, u: tuple[float, float] = (0.0, 0.0)) -> None:
        self.u = np.asarray(u, dtype=float)
        self.call_times: list[float] = []

    def get_control_output_(self, x: np.ndarray, t: float) -> np.ndarray:
        return self.u.copy()


class _Both:
    """A sampled pendulab controller driving both inputs with constant torques."""

    sample_time = 0.002
    input_names = ("tau1", "tau2")

    def __init__(self, u: tuple[float, float]) -> None:
        self.u = np.asarray(u, dtype=float)

    def reset(self) -> None:
        pass

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        return self.u.copy()


@pytest.fixture(scope="module")
def zero_run():
    # seed 2: no reset target from which the free fall exceeds 20 rad/s (no limit reset shifts the schedule)
    return run_v3_hardware("pendubot", _Const(), "zero", seed=2)


def test_schedule_is_upstreams_hardware_draw(zero_run) -> None:
    states, times = reset_schedule(2, N_RESETS_HW, 60.0)
    assert len(zero_run.intervals) == N_RESETS_HW and zero_run.limit_resets == 0 and zero_run.stopped_at is None
    for (a, b), t_sched in zip(zero_run.intervals, times[:N_RESETS_HW], strict=True):
        assert t_sched <= a < t_sched + 0.004  # the first loop sample at or after the scheduled time
        assert RESET_LENGTH_HW < b - a < RESET_LENGTH_HW + 0.01  # "timer > 1.0 s", counted in loop intervals


def test_pid_reset_reaches_the_target(zero_run) -> None:
    states, _ = reset_schedule(2, N_RESETS_HW, 60.0)
    finals = []
    for (a, b), goal in zip(zero_run.intervals, states, strict=False):
        i0, i1 = np.searchsorted(zero_run.t, [a, b])
        x0, x1 = zero_run.x[i0], zero_run.x[i1 - 1]
        err0 = np.abs(goal[:2] - [x0[0], x0[1] - x0[0]])
        err1 = np.abs(goal[:2] - [x1[0], x1[1] - x1[0]])
        if np.all(err0 < np.pi):  # (angles are not wrapped: from several turns away 1 s is too short)
            # kp = 2 N.m/rad (proportional part capped at 3 N.m) against Coulomb friction of 0.16 / 0.12 N.m and
            # model 1.0's gravity compensation on the identified robot: the hardware reset is not exact
            assert np.all(err1 < 0.35) and np.linalg.norm(err1) < np.linalg.norm(err0), (a, err0, err1)
            assert np.all(np.abs(x1[2:]) < 1.0)  # and nearly at rest
            finals.append(err1)
    assert len(finals) >= 8 and np.mean(finals) < 0.2


def test_zero_entry_scores_nothing_before_the_first_reset() -> None:
    # seed 333: the first reset at 6.16 s; hanging at rest with zero torque the end effector stays at -0.5 m
    res = run_v3_hardware("pendubot", _Const(), "zero", seed=333, duration=6.0)
    assert res.score == 0.0 and res.uptime == 0.0 and res.n_swingups == 0 and not res.intervals
    assert np.all(res.height < -0.49)
    # the time stamps: 2 ms steps with the records' rare overruns, summing to the episode
    iv = np.diff(res.t)
    assert np.median(iv) == pytest.approx(0.002, abs=2e-6) and iv.max() < 0.0038
    assert res.t[-1] < 6.0 <= res.t[-1] + 0.0038
    # what the controller saw: angles on the encoder grid, rates with the measured noise (joint 1: absolute)
    step = c1_sensing().position_step
    q_rel = np.column_stack([res.measured[:, 0], res.measured[:, 1] - res.measured[:, 0]])
    assert np.allclose(q_rel / step, np.round(q_rel / step), atol=1e-6)
    noise = res.measured[:, 2] - res.x[:, 2]
    assert noise.std() == pytest.approx(c1_sensing().velocity_noise[0], rel=0.1)
    assert np.corrcoef(noise[1:], noise[:-1])[0, 1] == pytest.approx(c1_sensing().velocity_correlation[0], abs=0.1)


def test_seeded_runs_are_identical() -> None:
    a = run_v3_hardware("acrobot", _Const((0.0, 0.3)), "c", seed=7, duration=2.0)
    b = run_v3_hardware("acrobot", _Const((0.0, 0.3)), "c", seed=7, duration=2.0)
    c = run_v3_hardware("acrobot", _Const((0.0, 0.3)), "c", seed=8, duration=2.0)
    assert np.array_equal(a.t, b.t) and np.array_equal(a.x, b.x) and np.array_equal(a.measured, b.measured)
    assert not np.array_equal(a.t, c.t)


def test_passive_allowance_clips_the_passive_joint() -> None:
    sigma = c1_sensing().torque_noise
    strict = run_v3_hardware("pendubot", _Both((0.0, 1.0)), "both", seed=1, duration=1.0)
    allowed = run_v3_hardware("pendubot", _Both((0.0, 1.0)), "both", seed=1, duration=1.0, passive_allowance=0.5)
    assert np.all(np.abs(strict.u[:, 1]) < 6 * sigma[1])  # the passive joint gets nothing but the torque noise
    assert np.mean(allowed.u[:, 1]) == pytest.approx(0.5, abs=0.01)


def test_limit_violation_starts_a_reset() -> None:
    # full torque on the driven joint spins the pendubot past 20 rad/s: a reset starts before the schedule's first
    res = run_v3_hardware("pendubot", _Const((6.0, 0.0)), "spin", seed=333, duration=5.0)
    assert res.limit_resets >= 1 and res.intervals and res.intervals[0][0] < 5.0


def test_friction_compensation_matches_the_plant() -> None:
    plant = load_plant("c1")
    fc = FrictionCompensated(_Both((0.0, 0.0)), plant, deadband=0.0)
    x = np.array([0.1, 0.3, 2.0, 1.0])  # joint rates 2.0 and -1.0 rad/s
    u = fc(0.0, x)
    p = plant.params
    assert u[0] == pytest.approx(p["b1"] * 2.0 + p["cf1"] * np.arctan(200.0))
    assert u[1] == pytest.approx(-p["b2"] * 1.0 - p["cf2"] * np.arctan(100.0))


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"passive_allowance": 0.6}, ValueError, r"passive_allowance = 0.6: out of range; .* \[0, 0.5\] N.m"),
        ({"passive_allowance": -0.1}, ValueError, r"passive_allowance = -0.1: out of range"),
        ({"passive_allowance": True}, ValueError, r"passive_allowance = True: a bool, not a number"),
        ({"duration": 0.0}, ValueError, "duration"),
        ({"duration": 61.0}, ValueError, "duration"),
        ({"seed": -1}, ValueError, r"seed = -1: out of range"),
        ({"seed": 2**32}, ValueError, r"seed = 4294967296: out of range; expected an integer in \[0, 4294967295\]"),
        ({"sensing": "c1"}, TypeError, "sensing"),
    ],
)
def test_bad_options_name_the_option(kwargs, exc, match) -> None:
    with pytest.raises(exc, match=match):
        run_v3_hardware("pendubot", _Const(), "zero", **kwargs)


def test_leaderboard_runs_and_journals_v3_hardware(tmp_path) -> None:
    from pendulab.evaluate.realai.leaderboard import run_protocols

    kw = {"tasks": ["pendubot"], "protocols": ["v3-hardware"], "quick": True, "root": tmp_path}
    run = run_protocols({"v3-hardware": ["lqr"]}, passive_allowance=0.5, **kw)
    case = run.case("v3-hardware", "pendubot", "lqr")
    assert case.status == "done" and case.executed == 1
    seed = case.summary["seeds"][0]
    assert seed["protocol"] == "v3-hardware" and seed["simulation"]["entry_torque_limit"] == [6.0, 0.5]
    again = run_protocols({"v3-hardware": ["lqr"]}, passive_allowance=0.5, resume=True, **kw)
    assert again.case("v3-hardware", "pendubot", "lqr").reused == 1
    with pytest.raises(ValueError, match="journal"):  # a record of another allowance is not read back
        run_protocols({"v3-hardware": ["lqr"]}, passive_allowance=0.0, resume=True, **kw)
    with pytest.raises(ValueError, match="passive_allowance"):
        run_protocols({"v3-hardware": ["lqr"]}, passive_allowance=0.7, **kw)


def test_score_bounds_the_plans_of_planning_controllers_and_compensates_friction(monkeypatch) -> None:
    import functools

    import pendulab.evaluate.realai.v3_hardware as hw
    from pendulab.evaluate.realai.controllers import CONTROLLERS

    seen: dict[str, object] = {}

    def planner(task: str, velocity_limit: float | None = None) -> _Both:
        seen["velocity_limit"] = velocity_limit
        return _Both((0.0, 0.0))

    monkeypatch.setitem(CONTROLLERS, "replan", planner)
    short = functools.partial(hw.run_v3_hardware, duration=0.1)  # the wiring is under test, not the score

    def run(task, entry, name, **kw):
        seen["entry"] = entry
        return short(task, entry, name, **kw)

    monkeypatch.setattr(hw, "run_v3_hardware", run)
    res = hw.v3_hardware_score("pendubot", "replan", seed=1)
    assert seen["velocity_limit"] == hw.PLAN_VELOCITY_LIMIT_HW and res.velocity_limit == hw.PLAN_VELOCITY_LIMIT_HW
    assert res.to_dict()["entry"] == {"velocity_limit": hw.PLAN_VELOCITY_LIMIT_HW, "friction_compensated": False}
    assert isinstance(seen["entry"], _Both)  # no allowance: nothing to compensate with
    res = hw.v3_hardware_score("pendubot", "replan", seed=1, velocity_limit=None, passive_allowance=0.5)
    assert seen["velocity_limit"] is None and res.velocity_limit is None and res.friction_compensated
    assert isinstance(seen["entry"], hw.FrictionCompensated) and seen["entry"].cf[1] == load_plant("c1").params["cf2"]
    hw.v3_hardware_score("pendubot", "replan", seed=1, passive_allowance=0.5, friction_compensation=False)
    assert isinstance(seen["entry"], _Both)
    with pytest.raises(ValueError, match=r"velocity_limit = -1.0: out of range"):
        hw.v3_hardware_score("pendubot", "replan", velocity_limit=-1.0)


def test_goal_mpc_swings_the_simulated_robot_up_within_the_hardware_limits() -> None:
    # The goal-regulating RTI (``mpc``) on the identified C.1 with the measured sensing, from the hanging start:
    # it swings up and balances before the first reset, with its joint rates under the 20 rad/s limit reset.
    from pendulab.evaluate.realai.v3_hardware import hardware_entry

    name, ctrl, _, compensated = hardware_entry("pendubot", "mpc", 0.5)
    predicted, robot = ctrl.controller.model.params, load_plant("c1")
    assert compensated and predicted.cf1 == predicted.b1 == 0.0  # frictionless prediction, friction compensated
    # designed on the identified robot (its links, rotor inertia and gear ratio), not on the leaderboard's model 1.0
    ident = robot.rigid_kwargs()
    assert (predicted.m2, predicted.I2, predicted.Ir, predicted.gr) == (ident["m2"], ident["I2"], ident["Ir"], ident["gr"])
    res = run_v3_hardware("pendubot", ctrl, name, seed=0, passive_allowance=0.5, duration=6.0)
    assert float(reset_schedule(0, N_RESETS_HW, 60.0)[1][0]) > 6.0  # seed 0: no reset inside the 6 s run
    assert res.limit_resets == 0 and res.stopped_at is None
    assert res.n_swingups >= 1
    # up for most of the run: the swing-up from hanging takes ~0.6 s here (0.9 s of margin on top)
    assert res.uptime >= 6.0 - 1.5
    assert np.abs(np.column_stack([res.measured[:, 2], res.measured[:, 3] - res.measured[:, 2]])).max() < 20.0

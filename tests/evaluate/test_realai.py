"""RealAIGym leaderboard v2: criteria against hand values, the RK4 run against pendulab.simulate, the shipped best swing-up."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.feedback import balance_controller
from pendulab.control.realai.spec import DT, N_STEPS, leaderboard_model
from pendulab.evaluate.realai import PUBLISHED, realai_score, rk4_rollout, run_leaderboard, to_relative
from pendulab.evaluate.realai import criteria as crit
from pendulab.evaluate.realai.criteria import criteria, score_v2

L1, L2 = 0.2, 0.3


def _grid(n: int = 501, dt: float = 0.01) -> np.ndarray:
    return np.arange(n) * dt


def test_constant_torque_cost_is_u_squared_times_duration() -> None:
    T = _grid()
    U = np.column_stack([np.full(len(T), 2.0), np.zeros(len(T))])
    # Sum over N - 1 intervals of u^2 dt = 4 * (T[-1] - T[0]); float round-off only.
    assert crit.torque_cost(T, U) == pytest.approx(4.0 * T[-1], rel=1e-12)


def test_linear_ramp_is_perfectly_smooth_and_steps_are_not() -> None:
    T = _grid()
    ramp = np.column_stack([0.01 * np.arange(len(T)), np.zeros(len(T))])
    # Constant increments: the std of the differences is zero up to round-off.
    assert crit.torque_smoothness(ramp) == pytest.approx(0.0, abs=1e-12)
    square = np.column_stack([np.where(np.arange(len(T)) % 2 == 0, 1.0, -1.0), np.zeros(len(T))])
    # Alternating +-2 increments: population std 2 exactly.
    assert crit.torque_smoothness(square) == pytest.approx(2.0, rel=1e-12)


def test_energy_and_velocity_cost_of_a_uniform_rotation() -> None:
    T = _grid()
    w1, w2_rel, tau = 2.0, -1.0, 1.5
    X = np.column_stack([w1 * T, w2_rel * T, np.full(len(T), w1), np.full(len(T), w2_rel)])
    U = np.column_stack([np.full(len(T), tau), np.full(len(T), -tau)])
    # |dq1 tau| + |dq2 tau| summed: tau (|w1| + |w2|) T_end; round-off only.
    assert crit.energy(X, U) == pytest.approx(tau * (abs(w1) + abs(w2_rel)) * T[-1], rel=1e-12)
    assert crit.velocity_cost(T, X) == pytest.approx((w1**2 + w2_rel**2) * T[-1], rel=1e-12)


def test_relative_angles_from_absolute() -> None:
    x_abs = np.array([[0.3, 1.0, 2.0, -1.0], [np.pi, np.pi, 0.0, 0.0]])
    rel = to_relative(x_abs)
    np.testing.assert_allclose(rel, [[0.3, 0.7, 2.0, -3.0], [np.pi, 0.0, 0.0, 0.0]], rtol=0, atol=1e-15)
    # Input untouched (a copy is converted).
    assert x_abs[0, 1] == 1.0
    with pytest.raises(ValueError, match="x_abs"):
        to_relative(np.zeros((3, 3)))


def _hang_then_up(n: int, k_up: int) -> np.ndarray:
    X = np.zeros((n, 4))
    X[k_up:, 0] = np.pi  # q1 = pi, q2 = 0 (relative): end effector at +0.5 m
    return X


def test_swingup_time_is_start_of_the_final_stay_above_the_line() -> None:
    T = _grid(101)
    assert crit.swingup_time(T, _hang_then_up(101, 40), L1, L2) == pytest.approx(T[40])
    # A dip below the line after 40 restarts the clock.
    X = _hang_then_up(101, 40)
    X[60, 0] = 0.0
    assert crit.swingup_time(T, X, L1, L2) == pytest.approx(T[61])


def test_success_rule_ignores_the_last_sample_as_the_leaderboard_does() -> None:
    T = _grid(101)
    # Only the last sample up: the scan starts at the second-to-last one, so no swing-up.
    assert crit.swingup_time(T, _hang_then_up(101, 100), L1, L2) == T[-1]
    # Up from the second-to-last sample: a (late) success.
    assert crit.swingup_time(T, _hang_then_up(101, 99), L1, L2) == pytest.approx(T[99])
    # Height threshold: 0.9 (L1 + L2) = 0.45 m; link 2 horizontal up to 0.2 m is below.
    X = np.zeros((101, 4))
    X[50:, 0] = np.pi
    X[50:, 1] = -np.pi / 2
    assert crit.swingup_time(T, X, L1, L2) == T[-1]


def test_score_formula() -> None:
    zero = dict.fromkeys(crit.CRITERIA, 0.0)
    assert score_v2(zero, True) == 1.0
    assert score_v2(zero, False) == 0.0
    vals = {"swingup_time": 2.0, "energy": 6.0, "torque_cost": 2.0, "torque_smoothness": 0.01, "velocity_cost": 40.0}
    # Every term is tanh(pi/10) by construction.
    assert score_v2(vals, True) == pytest.approx(1.0 - math.tanh(math.pi / 10), rel=1e-14)
    with pytest.raises(ValueError, match="criteria"):
        score_v2({"energy": 1.0}, True)


def test_bad_trajectories_raise() -> None:
    T = _grid(11)
    with pytest.raises(ValueError, match="X must have shape"):
        crit.velocity_cost(T, np.zeros((10, 4)))
    X = np.zeros((11, 4))
    X[3, 2] = np.nan
    with pytest.raises(ValueError, match="finite"):
        crit.velocity_cost(T, X)


def test_rk4_matches_pendulab_simulate() -> None:
    model = leaderboard_model("pendubot")
    x0 = np.array([0.4, -0.3, 1.0, 0.5])
    n = 250  # 0.5 s
    u_seq = np.column_stack([2.0 * np.sin(np.arange(n) * DT * 7.0), np.zeros(n)])
    t, x, u = rk4_rollout(model, x0, lambda k, t, x: u_seq[k], n)
    ref = pl.simulate(model, x0, n * DT, dt=DT, method="cvodes", rtol=1e-12, atol=1e-12, u=u_seq)
    np.testing.assert_allclose(u, u_seq)
    # RK4 at 2 ms has global error ~ h^4 ~ 1e-10 per unit of the dynamics' scale; 1e-7 leaves room for growth.
    np.testing.assert_allclose(x, ref.x, rtol=0, atol=1e-7)
    assert t[-1] == pytest.approx(n * DT, rel=1e-12)


def test_run_clips_the_actuated_joint_and_zeroes_the_passive_one() -> None:
    model = leaderboard_model("acrobot")
    # Full-actuation LQR sampled at 2 ms asks for large torques on both joints from hanging.
    ctrl = balance_controller(model, DT, design="discrete")
    res = run_leaderboard("acrobot", ctrl, "lqr-full")
    assert len(res.t) == N_STEPS == len(res.u)
    assert np.all(res.u[:, 0] == 0.0)
    assert np.max(np.abs(res.u[:, 1])) <= 6.0
    assert np.max(np.abs(res.u[:, 1])) == 6.0  # it saturates
    assert res.criteria == criteria(res.t, to_relative(res.x), res.u, 0.2, 0.3)


def test_bad_names_and_controllers() -> None:
    with pytest.raises(ValueError, match="task"):
        realai_score("cartpole")
    with pytest.raises(ValueError, match="controller"):
        realai_score("pendubot", "nope")
    with pytest.raises(TypeError, match="controller"):
        realai_score("pendubot", 3.0)  # type: ignore[arg-type]
    ctrl = balance_controller(leaderboard_model("pendubot"), 0.003, actuation="pendubot")
    with pytest.raises(ValueError, match="sample_time"):
        run_leaderboard("pendubot", ctrl)


@pytest.mark.parametrize("task", ["pendubot", "acrobot"])
def test_best_swingup_beats_the_published_best(task: str, tmp_path) -> None:
    res = realai_score(task, "best", csv_path=tmp_path / "realai.csv")
    best_published = max(PUBLISHED[task].values())
    assert res.success
    assert res.score > best_published
    d = res.to_dict()
    assert d["beats_published"] and d["score"] == res.score
    # The CSV holds the scored run: recomputing the criteria from it gives the same numbers.
    data = np.loadtxt(tmp_path / "realai.csv", delimiter=",", skiprows=1)
    assert data.shape == (N_STEPS, 7)
    again = criteria(data[:, 0], to_relative(data[:, 1:5]), data[:, 5:7], 0.2, 0.3)
    for k, v in again.items():
        # repr() round-trips floats exactly.
        assert v == pytest.approx(res.criteria[k], rel=1e-12, abs=1e-12)

"""Swing-up trajectory optimization: dynamics, bounds, agreement between transcriptions, failures."""

import numpy as np
import pytest

import pendulab as pl
from pendulab.control import SwingUpProblem, solve_transcription, swing_up
from pendulab.control.swingup.check import replay
from pendulab.control.swingup.tasks import load_task
from pendulab.model.robot import joint_rates


@pytest.fixture(scope="module")
def pendubot():
    return load_task("pendubot").problem


@pytest.fixture(scope="module")
def solved(pendubot):
    # Fixed meshes (no estimate, no refinement): the convergence test needs N = 40 and 80 as given.
    return {N: swing_up(pendubot, "radau", N, tolerance=None) for N in (40, 80)}


def test_optimum_satisfies_dynamics_and_converges(solved):
    d40, d80 = (replay(solved[N]).interval_defect for N in (40, 80))
    assert solved[40].success and solved[80].success
    # Per-interval defect vs CVODES at 1e-10 from each grid state: small at N=80 (measured 1.5e-3 rad/s) ...
    assert d80 < 1e-2
    # ... and shrinking like a high-order method: Radau(3) local error ~h^4 or better -> >= 8x per halving of h.
    assert d40 / d80 > 8.0


def test_optimum_respects_all_bounds(solved, pendubot):
    r = solved[80]
    # Torque bounds are hard IPOPT bounds, relaxed by at most bound_relax_factor (1e-8) times the limit.
    assert np.max(np.abs(r.u[:, 0])) <= pendubot.torque_limit * (1 + 1e-7)
    assert np.all(r.u[:, 1] == 0.0)  # passive elbow: bound fixed at exactly zero
    np.testing.assert_array_equal(r.x[0], pendubot.start)
    np.testing.assert_array_equal(r.x[-1], pendubot.target)
    # Interpolant reproduces the grid (Hermite through the knots) and holds u on each interval.
    np.testing.assert_allclose(r.x_at(r.t), r.x, atol=1e-12)
    np.testing.assert_array_equal(r.u_at(r.t[:-1] + 1e-9), r.u)


@pytest.mark.parametrize("method", ["radau", "shooting"])
def test_velocity_limit_bounds_the_joint_rates(pendubot, method):
    # The bound is on the robot's joints (omega1, omega2 - omega1), as the RTI's and the hardware's limits.
    free = swing_up(pendubot, method, 40)
    vmax = 0.8 * np.max(np.abs(joint_rates(free.x)))
    r = swing_up(pendubot.replace(velocity_limit=vmax), method, 40)
    assert r.success, r.message
    w = np.abs(joint_rates(r.x))
    # Shoulder: a state bound, hard (bound_relax_factor 1e-8); elbow: a constraint row, kept to IPOPT's tol 1e-8.
    assert w[:, 0].max() <= vmax * (1 + 1e-7)
    assert w[:, 1].max() <= vmax + 1e-6
    assert w.max() > 0.95 * vmax  # the bound is active: a time-optimal-ish plan runs into it


def test_collocation_and_shooting_agree_on_cost(pendubot):
    costs = {m: swing_up(pendubot, m, 40, tolerance=None).cost for m in ("legendre", "shooting")}
    # Same ZOH problem, different O(h^k) discretisations at N = 40: measured 0.5 % apart; 1.5 % allows for that.
    assert costs["shooting"] == pytest.approx(costs["legendre"], rel=1.5e-2)


def test_infeasible_problem_is_a_failed_result(pendubot):
    pb = pendubot.replace(torque_limit=0.05, horizon=1.0)
    r = swing_up(pb, "radau", 20)
    assert not r.success
    assert r.status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    assert r.status in r.message and "failed" in r.message
    assert r.iterations > 0 and len(r.stages) > 1  # auto tried the homotopy before giving up


def test_bad_problem_definitions_raise():
    model = pl.rigid()
    with pytest.raises(ValueError, match="torque_limit"):
        SwingUpProblem(model, torque_limit=-1.0)
    with pytest.raises(ValueError, match="actuation"):
        SwingUpProblem(model, actuation="elbow")
    with pytest.raises(ValueError, match="goal"):
        SwingUpProblem(model, goal=[np.pi, np.pi, 0.0])
    with pytest.raises(ValueError, match="free_horizon"):
        SwingUpProblem(model, objective="time")
    with pytest.raises(ValueError, match="stretch_limits"):
        SwingUpProblem(model, stretch_limits=(-0.1, 0.1))
    with pytest.raises(ValueError, match="method"):
        swing_up(SwingUpProblem(model), "euler", 10)
    with pytest.raises(ValueError, match="N"):
        swing_up(SwingUpProblem(model), "radau", 1)


def test_free_horizon_mix_beats_fixed_horizon(pendubot):
    fixed = swing_up(pendubot, "radau", 40)
    pb = pendubot.replace(free_horizon=True, objective="mix", time_weight=1.0, horizon_bounds=(0.5, 3.0))
    r = swing_up(pb, "radau", 40)
    assert r.success, r.message
    # The fixed-horizon optimum (T = 3 s) is feasible for the free problem, so the free optimum costs
    # no more than it (effort + 1 N^2.m^2 * 3 s), and with a price on time T leaves its upper bound.
    assert r.cost <= fixed.cost + 3.0
    assert r.horizon < 3.0 - 1e-3


def test_elastic_solve_starts_from_rigid_counterpart():
    pb = load_task("pendubot_elastic_soft").problem
    r = solve_transcription(pb, "radau", 30, tolerance=None)  # expert path's guess; the estimate is tested elsewhere
    assert r.success, r.message
    assert r.stages[0]["label"].startswith("rigid:")  # auto guess: rigid point-mass solve, lifted
    smin, smax = pb.stretch_limits
    stretch = r.x[:, 2:4] - np.array([pb.model.params.L1, pb.model.params.L2])
    # Stretch bounds are hard variable bounds (bound_relax_factor 1e-8 m).
    assert stretch.min() >= smin - 1e-7 and stretch.max() <= smax + 1e-7
    # Springs visibly matter: dynamic stretch well beyond the static compression at the goal.
    assert np.ptp(stretch[:, 0]) > 0.01


def test_joint_rates_read_the_link_rates_of_either_model():
    # Rigid (theta1, theta2, omega1, omega2) and elastic (theta1, theta2, r1, r2, omega1, omega2, v1, v2) states:
    # the spring lengths and their rates are not joint rates.
    rigid_x = np.array([0.1, 0.2, 3.0, -2.0])
    elastic_x = np.array([0.1, 0.2, 0.3, 0.4, 3.0, -2.0, 7.0, 9.0])
    for x in (rigid_x, elastic_x, np.stack([elastic_x, 2.0 * elastic_x])):
        w = joint_rates(x)
        np.testing.assert_array_equal(w.reshape(-1, 2)[0], [3.0, -5.0])
    assert pl.make_model("elastic").state_names[4:6] == ("omega1", "omega2")  # where joint_rates reads them

"""The estimator-wrapped controllers (pendulab.control.robust) and the ``estimator=`` of the controller factories.

The disturbed runs use a small harness of RealAIGym robustness-v2's disturbances on the leaderboard's RK4 loop
(2 ms, 10 s): velocity-measurement noise and whole-state measurement delay, as upstream's ``Simulator`` applies
them; success = final state within (0.35, 0.35, 1, 1) of upright (relative angles), as the benchmark checks it.
"""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.controllers import controller_for_task, make_controller
from pendulab.control.estimation import ExtendedKalmanFilter
from pendulab.control.feedback import full_input
from pendulab.control.realai.design import best_controller
from pendulab.control.realai.spec import DT, N_STEPS, TASKS, TORQUE_LIMIT, leaderboard_model
from pendulab.control.robust import EstimatedController, build_estimator, robust_controller
from pendulab.evaluate.realai.simulate import rk4_rollout


def _run(task: str, controller, *, noise: float = 0.0, delay: float = 0.0, seed: int = 0) -> bool:
    """One 10 s leaderboard run with velocity noise or a measurement delay; True on success."""
    model = leaderboard_model(task)
    rng = np.random.default_rng(seed)
    limit = np.zeros(2)
    limit[TASKS[task]] = TORQUE_LIMIT
    n = int(delay / DT + 1e-9)
    hist: list[np.ndarray] = []
    controller.reset()

    def policy(k, t, x):
        hist.append(x.copy())
        xm = hist[max(len(hist) - 1 - n, 0)].copy()
        xm[2:] += rng.normal(0.0, noise, 2) if noise > 0 else 0.0
        return np.clip(full_input(controller, controller(t, xm)), -limit, limit)

    _, x, _ = rk4_rollout(model, model.state(), policy, N_STEPS)
    q = np.array([x[-1, 0] - np.pi, x[-1, 1] - x[-1, 0], x[-1, 2], x[-1, 3] - x[-1, 2]])
    q[:2] = (q[:2] + np.pi) % (2 * np.pi) - np.pi
    return bool(np.all(np.abs(q) < [0.35, 0.35, 1.0, 1.0]))


# Seeded cases where the tracker fed the raw measurement fails (checked once per case below) and the robust one must not.
CASES = [("pendubot", {"delay": 0.04}), ("acrobot", {"delay": 0.03}), ("acrobot", {"noise": 0.5, "seed": 3})]


@pytest.mark.parametrize(("task", "kw"), CASES)
def test_robust_succeeds_where_tvlqr_fails(task, kw):
    ctrl = robust_controller(task)
    assert not _run(task, ctrl.controller, **kw)  # its own 2 ms TVLQR tracker on the raw measurement fails
    assert _run(task, ctrl, **kw)
    if "delay" in kw:
        assert ctrl.estimator.hypothesis[0] == pytest.approx(kw["delay"])  # the bank found the delay


def test_robust_nominal_matches_best():
    """Without disturbances the bank finds no delay and the EKF follows the state: the swing-up of ``best`` succeeds."""
    ctrl = robust_controller("pendubot", inner="best")
    assert _run("pendubot", ctrl)
    assert _run("pendubot", best_controller("pendubot"))
    assert ctrl.estimator.hypothesis == (0.0, 1.0)


def test_estimated_controller_passes_the_estimate():
    model = pl.rigid()
    inner, x0 = make_controller("lqr", model, 0.01, actuation="full")
    wrapped, x0w = make_controller("lqr", model, 0.01, actuation="full", estimator="ekf")
    assert isinstance(wrapped, EstimatedController)
    np.testing.assert_array_equal(x0, x0w)
    wrapped.reset()
    inner.reset()
    # The filter's prior is the start state: on an exact first measurement the estimate is that state (its update
    # moves it by less than the 1e-4 measurement sigma), so the two controllers agree to the gain times 1e-4.
    u_in = inner(0.0, x0)
    u_w = wrapped(0.0, x0)
    np.testing.assert_allclose(u_w, u_in, atol=1e-2)
    np.testing.assert_allclose(wrapped.x_hat, x0, atol=1e-4)


def test_ekf_balances_under_velocity_noise():
    """LQR balance at 10 ms on a rigid pendulum, rates measured with 0.5 rad/s noise: the EKF-fed loop stays closer."""
    model = pl.rigid()
    rng = np.random.default_rng(0)
    results = {}
    for est in (None, "ekf"):
        ctrl, x0 = make_controller("lqr", model, 0.01, actuation="full", estimator=est)
        ctrl.reset()
        x = x0.copy()
        dev = []
        for k in range(300):
            y = x.copy()
            y[2:] += rng.normal(0.0, 0.5, 2)
            u = full_input(ctrl, ctrl(k * 0.01, y))
            x = pl.simulate(model, x, 0.01, dt=0.01, method="rk4", u=u).x[-1]
            dev.append(np.abs(x[2:]).max())
        results[est] = float(np.sqrt(np.mean(np.square(dev[100:]))))
    # The raw loop turns the rate noise into torque noise through the LQR gain; the filter averages it out.
    assert results["ekf"] < 0.5 * results[None]


def test_factories_accept_estimators_and_robust():
    ctrl, x0 = controller_for_task("robust", "swingup_pendubot")
    assert isinstance(ctrl, EstimatedController) and ctrl.sample_time == DT
    np.testing.assert_allclose(x0, 0.0)
    ctrl2, _ = controller_for_task("robust", "swingup_acrobot", estimator="ekf")
    assert isinstance(ctrl2.estimator, ExtendedKalmanFilter)
    ctrl3, _ = controller_for_task("lqr", "swingup_pendubot", estimator="mmae")
    assert isinstance(ctrl3, EstimatedController)


def test_bad_estimator_and_robust_arguments():
    model = pl.rigid()
    with pytest.raises(ValueError, match="estimator must be one of"):
        make_controller("lqr", model, 0.01, estimator="kalman")
    with pytest.raises(TypeError, match="estimator must be one of"):
        make_controller("lqr", model, 0.01, estimator=3)
    with pytest.raises(ValueError, match="robust is designed for the leaderboard tasks"):
        controller_for_task("robust", "swingup_pendubot_pointmass")
    with pytest.raises(ValueError, match="sample_time must be"):
        controller_for_task("robust", "swingup_pendubot", sample_time=0.01)
    with pytest.raises(ValueError, match="task must be one of"):
        robust_controller("cartpole")
    with pytest.raises(ValueError, match="inner must be"):
        robust_controller("pendubot", inner="nmpc")
    with pytest.raises(TypeError, match="controller must be a SampledController"):
        EstimatedController(object(), build_estimator("ekf", model, 0.01))
    with pytest.raises(TypeError, match="estimator must have reset"):
        EstimatedController(make_controller("lqr", model, 0.01)[0], object())

"""Numerics that cannot lie (issue 31): an estimator never returns, nor keeps, a non-finite or absurd estimate.

The class of the cases found: inputs whose squares leave the doubles (sigmas of 1e200 or 1e-200), inputs
beyond any pendulum (a rate or a torque of 1e300), a sample time beyond the prediction's stability, and a
step that diverges anyway. Each is refused where it enters, naming the input, or the step raises and the
filter is left as it was.
"""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.estimation import EstimationError, ExtendedKalmanFilter
from pendulab.control.estimation.ekf import MAX_MAGNITUDE, STD_RANGE


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"measurement_std": 1e200}, "measurement_std must be standard deviations in"),
        ({"measurement_std": 1e-200}, "measurement_std must be standard deviations in"),
        ({"process_std": 1e200}, "process_std must be standard deviations in"),
        ({"process_std": 1e-300}, "process_std must be standard deviations in"),
        ({"x0_std": 1e150}, "x0_std must be standard deviations in"),
        ({"disturbance": True, "disturbance_std": 1e101}, "disturbance_std must be standard deviations in"),
        ({"sample_time": 1e6}, r"sample_time = 1000000.0: out of range; expected a finite number in \[1e-05, 10\] s"),
        ({"sample_time": 0.5}, "too long for the filter's RK4 prediction"),  # 0.5 s x 5.8 1/s > 2.5
    ],
)
def test_inputs_whose_squares_or_steps_leave_the_doubles_are_refused(kwargs, message):
    kwargs = {"sample_time": 0.002, **kwargs}
    with pytest.raises(ValueError, match=message):
        ExtendedKalmanFilter(pl.rigid(), kwargs.pop("sample_time"), **kwargs)


def test_the_admissible_range_is_usable_at_both_ends():
    lo, hi = STD_RANGE
    model = pl.rigid()
    for sigma in (lo, hi):
        ekf = ExtendedKalmanFilter(model, 0.002, measurement_std=sigma, process_std=sigma)
        x = model.state(theta1=0.1)
        ekf.update(0.0, x)
        est = ekf.update(0.002, x, np.zeros(2))
        assert np.all(np.isfinite(est)) and np.all(np.isfinite(ekf.P))
    # the longest admissible step on the rigid default (fastest rate 5.79 1/s) still predicts a finite state
    ExtendedKalmanFilter(model, 2.5 / 5.79)


@pytest.mark.parametrize(
    ("y", "u", "message"),
    [
        ([0.1, 0.0, 1e300, 0.0], [0.0, 0.0], "y must be finite measurements"),
        ([0.1, 0.0, 2 * MAX_MAGNITUDE, 0.0], [0.0, 0.0], "at most 1e\\+06"),
        ([0.1, 0.0, 0.0, 0.0], [1e300, 0.0], "u must be finite torques"),
        ([0.1, 0.0, np.nan, 0.0], [0.0, 0.0], "y must be finite measurements"),
    ],
)
def test_absurd_measurements_and_torques_are_refused_and_change_nothing(y, u, message):
    model = pl.rigid()
    ekf = ExtendedKalmanFilter(model, 0.002)
    x = model.state(theta1=0.1)
    ekf.update(0.0, x)
    before = (ekf.z.copy(), ekf.P.copy(), ekf.k)
    with pytest.raises(ValueError, match=message):
        ekf.update(0.002, y, u)
    assert np.array_equal(ekf.z, before[0]) and np.array_equal(ekf.P, before[1]) and ekf.k == before[2]
    assert np.all(np.isfinite(ekf.update(0.002, x, np.zeros(2))))  # and it goes on filtering


def test_a_diverging_step_raises_and_restores_the_filter(monkeypatch):
    model = pl.rigid()
    ekf = ExtendedKalmanFilter(model, 0.002)
    x = model.state(theta1=0.1)
    ekf.update(0.0, x)
    before = (ekf.z.copy(), ekf.P.copy(), ekf.k, ekf.x_hat.copy())
    good_step = ekf._step_jac

    def exploding(z, u):  # a prediction that overflows (what a stiffer plant at a long step does)
        zn, A = good_step(z, u)
        return np.asarray(zn) * np.inf, A

    monkeypatch.setattr(ekf, "_step_jac", exploding)
    with pytest.raises(EstimationError, match="non-finite estimate or covariance"):
        ekf.update(0.002, x, np.zeros(2))
    assert np.array_equal(ekf.z, before[0]) and np.array_equal(ekf.P, before[1]) and ekf.k == before[2]
    assert np.array_equal(ekf.x_hat, before[3])
    monkeypatch.setattr(ekf, "_step_jac", good_step)
    assert np.all(np.isfinite(ekf.update(0.002, x, np.zeros(2))))

"""State estimation in the pipelines: the measurement model, the scorecard's episodes, ``pendulab score --estimator``.

(The co-simulation pipeline: tests/fmu/test_cosim_estimation.py; the Gymnasium env: tests/gym/test_env_estimation.py.)
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from pendulab.control.controllers import controller_for_task
from pendulab.control.robust import EstimatedController, build_estimator
from pendulab.control.swingup.tasks import load_task
from pendulab.evaluate import Perturbation, run_perturbed_episode, score
from pendulab.evaluate.measurement import MeasurementModel

# -- the measurement model ----------------------------------------------------------------------------------------------


def test_measurement_model_delays_by_whole_samples_from_the_start_state():
    m = MeasurementModel(0.0, 3)
    x0 = np.array([0.1, 0.2, 0.0, 0.0])
    m.reset(x0)
    xs = [x0 + k * np.array([1.0, 0.0, 0.5, 0.0]) for k in range(8)]
    ys = [m(x) for x in xs]
    # y_k = x_{k-3}, and the start state while k < 3 (the protocol's convention: at rest before t = 0).
    for k, y in enumerate(ys):
        np.testing.assert_array_equal(y, xs[max(k - 3, 0)])
    assert MeasurementModel().is_exact and not m.is_exact


def test_measurement_noise_is_on_the_link_rates_only_with_the_given_sigma():
    x = np.array([0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0])  # elastic: theta1, theta2, r1, r2, omega1, omega2, v1, v2
    m = MeasurementModel(0.3, seed=1)
    m.reset(x)
    Y = np.array([m(x) for _ in range(20000)])
    np.testing.assert_array_equal(Y[:, [0, 1, 2, 3, 6, 7]], np.tile(x[[0, 1, 2, 3, 6, 7]], (20000, 1)))
    # Sample std of 20000 Gaussian draws: relative standard error 1/sqrt(2 N) = 0.5 %, so 3 % is > 5 sigma.
    np.testing.assert_allclose((Y[:, 4:6] - x[4:6]).std(axis=0), 0.3, rtol=0.03)
    # Same seed, same noise (reset restarts the generator).
    m.reset(x)
    np.testing.assert_array_equal(m(x), Y[0])


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"velocity_noise": -0.1}, "velocity_noise"),
        ({"velocity_noise": float("nan")}, "velocity_noise"),
        ({"velocity_noise": "loud"}, "velocity_noise"),
        ({"delay": 1.5}, "delay"),
        ({"delay": -1}, "delay"),
        ({"delay": 10**9}, "delay"),
    ],
)
def test_measurement_model_rejects_bad_settings_by_name(kwargs, match):
    with pytest.raises(ValueError, match=match):
        MeasurementModel(**kwargs)


# -- the scorecard's episodes -----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def pendubot():
    task = load_task("pendubot")
    ctrl, x0 = controller_for_task("tvlqr", task)
    return task, ctrl, x0


def _ekf_fed(task, inner, x0):
    limit = task.problem.torque_limit
    est = build_estimator("ekf", task.model, task.dt, x0=x0, torque_limit=(limit, 0.0))
    return EstimatedController(inner, est, u_max=limit)


def test_scorecard_episode_ekf_estimate_beats_the_noisy_measurement(pendubot, recorder):
    task, ctrl, x0 = pendubot
    raw, inner = recorder(ctrl), recorder(ctrl)
    pert = Perturbation(meas_noise=0.3, seed=(0, 6, 3, 0))
    res_raw = run_perturbed_episode(raw, task, x0, pert)
    res_ekf = run_perturbed_episode(_ekf_fed(task, inner, x0), task, x0, pert)
    rms_raw = np.sqrt(np.mean((np.array(raw.seen)[:, 2:4] - res_raw.x[:-1, 2:4]) ** 2))
    rms_ekf = np.sqrt(np.mean((np.array(inner.seen)[:, 2:4] - res_ekf.x[:-1, 2:4]) ** 2))
    assert rms_raw == pytest.approx(0.3, rel=0.05)  # 2 x 1000 draws: the sample RMS is within 5 % (> 3 sigma)
    # The angles are measured to 1e-4 rad, so the filter's rates follow the angles' increments, not the rate noise:
    # measured 0.015 rad/s against 0.30; a factor 5 leaves room for another seed or plant.
    assert rms_ekf < rms_raw / 5
    assert res_ekf.success


def test_scorecard_episode_without_noise_or_delay_reproduces_the_plain_run(pendubot, recorder):
    task, ctrl, x0 = pendubot
    plain = run_perturbed_episode(ctrl, task, x0)
    inner = recorder(ctrl)
    fed = run_perturbed_episode(_ekf_fed(task, inner, x0), task, x0)
    # The estimate is the exact measurement blended with a 10 ms RK4 prediction (the plant takes substeps): it stays
    # within 1e-3 of the state (measured 3e-4 at the swing-up's fastest), and the closed loop lands where the plain one does.
    assert np.max(np.abs(np.array(inner.seen) - fed.x[:-1])) < 1e-3
    assert plain.success and fed.success
    np.testing.assert_allclose(fed.x[-1], plain.x[-1], atol=1e-6)  # both balanced upright at rest to round-off


def test_score_with_estimator_runs_every_controller_on_the_estimate(pendubot):
    task, ctrl, x0 = pendubot
    levels = {"measurement_noise": (0.0, 0.5), "delay": (0.0, 0.02)}
    card = score("tvlqr", task, runs=2, categories=list(levels), levels=levels, workers=1, estimator="ekf")
    assert card.estimator == "ekf" and card.to_dict()["estimator"] == "ekf"
    assert "fed by `ekf`" in card.table()
    # At these levels the filtered tvlqr swings up (benchmarks: the plain one does too; the point is that the runs are
    # made on the estimate and still pass the RealAIGym criterion).
    assert card.category("measurement_noise").success_rates == (1.0, 1.0)
    assert card.category("delay").success_rates[0] == 1.0
    # A factory gets the same wrapper.
    card2 = score(lambda tk: controller_for_task("tvlqr", tk), task, runs=1, categories=["measurement_noise"],
                  levels={"measurement_noise": (0.5,)}, workers=1, estimator="ekf")  # fmt: skip
    assert card2.estimator == "ekf" and card2.category("measurement_noise").success_rates == (1.0,)


@pytest.mark.parametrize(("estimator", "exc"), [("kalman", ValueError), (3, TypeError)])
def test_score_rejects_a_bad_estimator_before_designing(estimator, exc):
    with pytest.raises(exc, match="estimator must be one of"):
        score("nmpc", "pendubot", runs=1, estimator=estimator)


def test_cli_score_estimator_errors_name_the_option():
    def run(*args):
        return subprocess.run([sys.executable, "-m", "pendulab", "score", *args], capture_output=True, text=True)

    bad = run("--controller", "tvlqr", "--task", "pendubot", "--estimator", "kalman")
    assert bad.returncode == 2 and "--estimator 'kalman'" in bad.stderr and "ekf" in bad.stderr
    other = run("--controller", "best", "--task", "pendubot", "--realai", "--estimator", "ekf")
    assert other.returncode == 2 and "--estimator does not apply" in other.stderr

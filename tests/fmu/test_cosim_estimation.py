"""Co-simulation with a measurement model and a state estimator between the FMU plant and the controller."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.feedback import balance_controller, upright_state
from pendulab.cosim import cosim
from pendulab.evaluate.measurement import MeasurementModel


def _start(model):
    x0 = upright_state(model)
    x0[0] += 0.1
    return x0


def _rms_rates(rec, traj, nq):
    seen = np.array(rec.seen)
    return float(np.sqrt(np.mean((seen[:, nq : nq + 2] - traj.x[: len(seen), nq : nq + 2]) ** 2)))


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_cosim_ekf_estimate_beats_the_noisy_measurement(cosim_fmu, kind, recorder):
    model = pl.make_model(kind)
    ctrl, x0, nq = balance_controller(model, 0.01), _start(model), model.nq
    raw, inner = recorder(ctrl), recorder(ctrl)
    t_raw = cosim(cosim_fmu(kind), raw, 0.01, 3.0, x0=x0, measurement=MeasurementModel(0.2, seed=3))
    t_ekf = cosim(cosim_fmu(kind), inner, 0.01, 3.0, x0=x0, measurement=MeasurementModel(0.2, seed=3), estimator="ekf")
    rms_raw, rms_ekf = _rms_rates(raw, t_raw, nq), _rms_rates(inner, t_ekf, nq)
    assert rms_raw == pytest.approx(0.2, rel=0.1)  # 2 x 300 draws: the sample RMS is within 10 % (> 3 sigma)
    # Angles measured to 1e-4 rad carry the rates (their increments over 10 ms): measured 0.01 rad/s rigid against
    # 0.2; a factor 4 leaves room for the elastic plant's spring modes, which the filter also predicts.
    assert rms_ekf < rms_raw / 4
    # And the filtered loop balances (the raw one feeds the noise through the gains).
    assert np.max(np.abs(t_ekf.x[-1, :2] - upright_state(model)[:2])) < 0.02


def test_cosim_exact_measurement_and_ekf_reproduce_the_plain_run(cosim_fmu):
    model = pl.rigid()
    ctrl, x0 = balance_controller(model, 0.01), _start(model)
    plain = cosim(cosim_fmu("rigid"), ctrl, 0.01, 3.0, x0=x0, tolerance=1e-10)
    exact = cosim(cosim_fmu("rigid"), ctrl, 0.01, 3.0, x0=x0, tolerance=1e-10, measurement=MeasurementModel())
    np.testing.assert_array_equal(exact.x, plain.x)  # the exact measurement is the state itself: same run bit for bit
    fed = cosim(cosim_fmu("rigid"), ctrl, 0.01, 3.0, x0=x0, tolerance=1e-10, estimator="ekf")
    # The EKF blends the exact state with its 10 ms RK4 prediction (error ~1e-7 near upright): the loops agree to 1e-5.
    assert np.max(np.abs(fed.x - plain.x)) < 1e-5


def test_cosim_mmae_identifies_a_delay(cosim_fmu, recorder):
    model = pl.rigid()
    ctrl, x0 = balance_controller(model, 0.01), _start(model)
    inner = recorder(ctrl)
    traj = cosim(cosim_fmu("rigid"), inner, 0.01, 3.0, x0=x0, measurement=MeasurementModel(0.0, 3), estimator="mmae")
    # The bank's delay hypotheses (0 ... 40 ms) include the 3 samples; once identified the rolled-forward estimate is
    # the current state (3e-3: the 10 ms RK4 rollout over 3 samples, measured 1e-4).
    late = np.array(inner.seen[50:])
    assert np.max(np.abs(late - traj.x[50 : 50 + len(late)])) < 3e-3


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"estimator": "kalman"}, ValueError, "estimator must be one of"),
        ({"estimator": 3}, TypeError, "estimator must be one of"),
        ({"measurement": 0.2}, TypeError, "measurement must be"),
    ],
)
def test_cosim_rejects_bad_estimator_or_measurement(cosim_fmu, kwargs, exc, match):
    model = pl.rigid()
    with pytest.raises(exc, match=match):
        cosim(cosim_fmu("rigid"), balance_controller(model, 0.01), 0.01, 1.0, **kwargs)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--measurement-noise", "-0.1"], "--measurement-noise = '-0.1': out of range"),
        (["--measurement-noise", "loud"], "--measurement-noise = 'loud': not a number"),
        (["--measurement-delay", "1.5"], "--measurement-delay = '1.5': not an integer"),
        (["--measurement-delay", "-2"], "--measurement-delay = '-2': out of range"),
        (["--measurement-seed", "3"], "--measurement-seed applies with --measurement-noise only"),
        (["--estimator", "kalman"], "--estimator"),
    ],
)
def test_cli_cosim_measurement_errors_name_the_option(tmp_path, args, match):
    res = subprocess.run(
        [sys.executable, "-m", "pendulab", "cosim", "--out", str(tmp_path), *args], capture_output=True, text=True
    )
    assert res.returncode == 2 and match in res.stderr
    assert not any(tmp_path.iterdir())  # rejected before the FMU export


def test_cli_cosim_reports_what_the_controller_saw(cosim_fmu, tmp_path):
    import json

    base = [sys.executable, "-m", "pendulab", "cosim", "--fmu", str(cosim_fmu("rigid")), "--no-gif", "--json"]
    out = {}
    for name, extra in (("raw", []), ("ekf", ["--estimator", "ekf"])):
        res = subprocess.run(
            [*base, "--out", str(tmp_path / name), "--measurement-noise", "0.2", "--t-final", "2", *extra],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        out[name] = json.loads(res.stdout)
    assert out["ekf"]["estimator"] == "ekf" and out["raw"]["measurement"]["velocity_noise"] == 0.2
    # As in the API test: raw ~ the noise sigma, the EKF's estimate a factor > 4 closer to the plant's rates.
    assert out["raw"]["controller_rate_rms_error"] == pytest.approx(0.2, rel=0.15)  # 2 x 200 draws: 15 % > 3 sigma
    assert out["ekf"]["controller_rate_rms_error"] < out["raw"]["controller_rate_rms_error"] / 4


class Diverging:
    """An estimator that passes the measurement through, then returns NaN from its 4th update on."""

    def reset(self):
        self.k = 0

    def update(self, t, y, u=None):
        self.k += 1
        return np.asarray(y, dtype=float) * (np.nan if self.k > 3 else 1.0)


def test_cosim_names_a_diverged_estimator(cosim_fmu):
    model = pl.rigid()
    with pytest.raises(ValueError, match=r"state estimate is not finite at t = 0.03 s: the estimator diverged"):
        cosim(cosim_fmu("rigid"), balance_controller(model, 0.01), 0.01, 1.0, x0=_start(model), estimator=Diverging())

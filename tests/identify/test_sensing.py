"""The sensing and timing measured from the C.1 records (pendulab.identify.sensing): physics, not shapes."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.identify.datasets import C1_BLIND, C1_EXCITATION
from pendulab.identify.records import make_record
from pendulab.identify.sensing import c1_sensing, ma1_coefficients, measure_sensing

#: The T-motor AK80-6's CAN reply: position 16 bits over +-12.5 rad, torque 12 bits over +-12 N.m.
ENCODER_STEP = 25.0 / 65536
TORQUE_STEP = 24.0 / 4095


def test_c1_quantization_is_the_motor_protocol_step() -> None:
    s = c1_sensing()
    assert s.records == C1_EXCITATION  # the excitation records only, never the blind test
    assert s.position_step == pytest.approx(ENCODER_STEP, rel=1e-4)
    assert s.position_multiple_error < 0.01  # every position change is a whole number of steps
    assert s.torque_step == pytest.approx(TORQUE_STEP, rel=1e-4)


def test_c1_velocity_noise_and_timing() -> None:
    s = c1_sensing()
    # a difference of quantized positions over 2 ms alone has std step / 2 ms * sqrt(1/6) = 0.078 rad/s and lag-1
    # correlation -0.5; the reply is a little noisier and a little less anti-correlated
    for std, rho in zip(s.velocity_noise, s.velocity_correlation, strict=True):
        assert 0.078 < std < 0.15 and -0.5 <= rho < -0.3
    st = s.interval_stats()
    assert st["median"] == pytest.approx(0.002, abs=2e-6)
    assert 0.0019 < st["min"] and st["max"] < 0.0038 and st["overrun_fraction"] < 0.01
    assert all(0.005 < v < 0.05 for v in s.torque_noise)


def _synthetic(name: str, noise: float, seed: int = 0) -> object:
    rng = np.random.default_rng(seed)
    t = np.arange(3000) * 0.002
    q = np.column_stack([0.2 * np.sin(t), 0.1 * np.cos(0.7 * t)])  # slow: below the 0.5 rad/s the noise is measured at
    qd = np.column_stack([0.2 * np.cos(t), -0.07 * np.sin(0.7 * t)]) + noise * rng.standard_normal((t.size, 2))
    qq = ENCODER_STEP * np.round(q / ENCODER_STEP)
    tau = TORQUE_STEP * np.round(0.3 * np.sin(3 * t)[:, None] * np.ones(2) / TORQUE_STEP)
    return make_record(name, t, qq, tau, qd)


def test_measure_sensing_recovers_known_noise() -> None:
    s = measure_sensing([_synthetic("a", 0.1), _synthetic("b", 0.1, seed=1)])
    assert s.position_step == pytest.approx(ENCODER_STEP, rel=1e-9)
    assert s.velocity_noise == pytest.approx((0.1, 0.1), rel=0.05)
    assert all(abs(r) < 0.05 for r in s.velocity_correlation)  # white noise
    assert s.torque_step == pytest.approx(TORQUE_STEP, rel=1e-9)
    assert np.allclose(s.intervals, 0.002)


def test_ma1_coefficients_give_the_std_and_correlation() -> None:
    c0, c1 = ma1_coefficients(0.1, -0.42)
    assert c0**2 + c1**2 == pytest.approx(0.01)
    assert c0 * c1 / (c0**2 + c1**2) == pytest.approx(-0.42)
    e = np.random.default_rng(3).standard_normal(400_000)
    n = c0 * e[1:] + c1 * e[:-1]
    assert n.std() == pytest.approx(0.1, rel=0.01) and np.corrcoef(n[1:], n[:-1])[0, 1] == pytest.approx(-0.42, abs=0.01)


def test_blind_records_are_refused() -> None:
    # a stand-in carrying a blind stamp: the blind data themselves are not even loaded
    fake = _synthetic(C1_BLIND[0], 0.1)
    with pytest.raises(ValueError, match="blind test"):
        measure_sensing([_synthetic("ok", 0.1), fake])
    with pytest.raises(ValueError, match="at least one record"):
        measure_sensing([])

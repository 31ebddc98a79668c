"""The swing-up summary's account of the tracking torque: its RMS departure from the plan, frequency and cause."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from pendulab.control.swingup.episode import tracking_torque


def _loop(ripple_hz: float, amplitude: float, horizon: float = 2.0):
    t = np.arange(0.0, 4.0 + 1e-12, 0.002)
    plan = SimpleNamespace(horizon=horizon, u_at=lambda ts: np.column_stack([np.sin(ts), np.zeros_like(ts)]))
    u = np.column_stack([np.sin(t) + np.where(t <= horizon, amplitude * np.sin(2 * np.pi * ripple_hz * t), 5.0), 0 * t])
    return SimpleNamespace(t=t, u=u), plan


def test_ripple_at_the_spring_frequency_is_named_as_spring_ringing():
    cl, plan = _loop(20.0, 0.3)
    out = tracking_torque(cl, plan, spring_frequency=2 * np.pi * 20.1)
    # 40 whole periods of a sine on the horizon: RMS = amplitude / sqrt(2) to sampling round-off.
    assert out["tracking_torque_rms_Nm"] == pytest.approx(0.3 / np.sqrt(2), rel=1e-2)
    assert out["tracking_torque_frequency_Hz"] == pytest.approx(20.0, abs=0.5)  # bin width 1/horizon = 0.5 Hz
    assert "spring modes (20.1 Hz)" in out["tracking_torque_note"]


def test_slow_departure_is_not_blamed_on_springs_and_only_the_horizon_counts():
    cl, plan = _loop(2.0, 0.1)  # after the horizon the torque is off by 5 N.m: LQR balance, not tracking
    out = tracking_torque(cl, plan, spring_frequency=2 * np.pi * 20.1)
    assert out["tracking_torque_rms_Nm"] == pytest.approx(0.1 / np.sqrt(2), rel=1e-2)
    assert "spring" not in out["tracking_torque_note"] and "2.0 Hz" in out["tracking_torque_note"]
    assert "spring" not in tracking_torque(cl, plan, spring_frequency=None)["tracking_torque_note"]


def test_alternation_near_the_nyquist_frequency_is_named_as_such():
    cl, plan = _loop(240.0, 0.2)  # output step 2 ms: Nyquist 250 Hz
    out = tracking_torque(cl, plan, spring_frequency=2 * np.pi * 20.1)
    assert "Nyquist frequency 250 Hz" in out["tracking_torque_note"] and "spring" not in out["tracking_torque_note"]

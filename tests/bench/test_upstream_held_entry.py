"""The benchmark of the ICRA 2025 entries calls an entry declared at 5 ms as the robot's loop did, on any step grid."""

from __future__ import annotations

import numpy as np
import pytest

BENCHMARK = "bench_upstream_entries"  # the script the `bench` fixture imports (tests/bench/conftest.py)


class _Counter:
    """An entry whose torque is the number of its calls (so a held output is visible)."""

    def __init__(self) -> None:
        self.times: list[float] = []

    def get_control_output_(self, x, t=None):
        self.times.append(t)
        return np.array([len(self.times), -1.0])


@pytest.mark.parametrize("seed", [None, 0, 1])
def test_an_entry_is_called_once_per_period_and_held_in_between(bench, seed):
    # 2 ms steps (v3), or 2.0-3.7 ms jittered steps (v3-hardware's measured loop intervals)
    steps = np.full(3000, 0.002) if seed is None else np.random.default_rng(seed).uniform(0.002, 0.0037, 3000)
    t = np.concatenate([[0.0], np.cumsum(steps)])
    inner = _Counter()
    held = bench.HeldEntry(inner, 0.005)
    out = [held.get_control_output_(np.zeros(4), float(ti))[0] for ti in t]
    called = np.asarray(inner.times)
    # one call at the first step at or after each multiple of 5 ms: as many calls as 5 ms boundaries passed
    assert len(called) == int(np.floor(t[-1] / 0.005 + 1e-9)) + 1
    assert np.all(np.floor(called[1:] / 0.005 + 1e-9) - np.floor(called[:-1] / 0.005 + 1e-9) >= 1)
    assert np.all(np.diff(called) <= 0.005 + 0.0037 + 1e-12)  # never a period skipped beyond one step's lateness
    assert out == [float(np.searchsorted(called, ti, side="right")) for ti in t]  # the last call's torque is held
    assert len(held.call_times) == len(called)


def test_with_a_latency_each_output_takes_effect_that_much_later(bench):
    t = np.arange(0, 1.0, 0.002)
    inner, plain = _Counter(), _Counter()
    late = bench.HeldEntry(inner, 0.005, latency=0.004)
    now = bench.HeldEntry(plain, 0.005)
    u_late = np.array([late.get_control_output_(np.zeros(4), float(ti))[0] for ti in t])
    u_now = np.array([now.get_control_output_(np.zeros(4), float(ti))[0] for ti in t])
    assert inner.times == plain.times  # the same calls of the entry, at the same states
    assert np.all(u_late[t < 0.004 - 1e-9] == 0.0)  # nothing before the first output is ready
    for ti, u in zip(t, u_late, strict=True):  # the latest call at least 4 ms old
        ready = [c for c in inner.times if c + 0.004 <= ti + 1e-9]
        assert u == len(ready)
    assert np.any(u_late != u_now)


@pytest.mark.parametrize("period", [0.0, -0.005, float("nan"), float("inf")])
def test_a_bad_period_or_missing_time_is_refused(bench, period):
    with pytest.raises(ValueError, match="period must be"):
        bench.HeldEntry(_Counter(), period)
    for latency in (-0.001, 0.006, float("nan")):  # negative, longer than the period, not a number
        with pytest.raises(ValueError, match="latency must be"):
            bench.HeldEntry(_Counter(), 0.005, latency=latency)
    with pytest.raises(ValueError, match="needs the time"):
        bench.HeldEntry(_Counter(), 0.005).get_control_output_(np.zeros(4), None)

"""The streaming phase of a chunk (lanes refilled inside event callbacks) against the stepped loop."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

import pendulab as pl
from pendulab.ensemble import Event
from pendulab.ensemble.stream import CLOCK_MAX, SWITCH_FRACTION, clock_settings, elapsed

pytest.importorskip("heyoka")


def _releases(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x0 = np.zeros((n, 4))
    x0[:, :2] = rng.uniform(-3.0, 3.0, (n, 2))
    return x0


def test_streaming_equals_the_stepped_loop() -> None:
    # No output grid: the runs stream through the lanes. An output grid forces the stepped loop (a stop per
    # finished run, every run timed from t = 0): the flip times must be the same doubles.
    model, x0, t_final = pl.rigid(), _releases(48, 5), 3.0
    streamed = pl.ensemble(model, x0, t_final, events=["flip"], threads=1, batch_size=4)
    stepped = pl.ensemble(model, x0, t_final, events=["flip"], threads=1, batch_size=4, t_eval=[0.0, t_final])
    assert streamed.status.tolist() == stepped.status.tolist()
    assert 5 < np.sum(streamed.status == "event") < 43  # both kinds of ending are exercised
    np.testing.assert_array_equal(streamed.event_times["flip"], stepped.event_times["flip"])
    ok = streamed.status == "ok"
    assert np.all(streamed.t_final[ok] == t_final)  # finished exactly at the horizon, not at the clock's end
    # Runs that reach the horizon leave the stream at t (1 - 2^-8) and are finished by fresh steps: the last
    # 12 ms differ from one unbroken step sequence at the rounding level (tolerance 1e-9 > 1e-12 tolerance grown).
    np.testing.assert_allclose(streamed.x_final[ok], stepped.x_final[ok], rtol=0, atol=1e-9)
    flipped = ~ok
    np.testing.assert_array_equal(streamed.x_final[flipped], stepped.x_final[flipped])


def test_streaming_elastic_with_a_user_event() -> None:
    model = pl.elastic(k1=500.0, k2=500.0)
    x0 = np.array([[a, b, 1.02, 1.02, 0.0, 0.0, 0.0, 0.0] for a, b in _releases(12, 7)[:, :2]])
    low = Event("low", "y2", value=-1.9, terminal=True)
    streamed = pl.ensemble(model, x0, 2.0, events=["flip", low], threads=1, batch_size=4)
    stepped = pl.ensemble(model, x0, 2.0, events=["flip", low], threads=1, batch_size=4, t_eval=[0.0, 2.0])
    assert streamed.status.tolist() == stepped.status.tolist()
    for name in ("flip", "low"):
        np.testing.assert_array_equal(streamed.event_times[name], stepped.event_times[name])
    assert np.isfinite(streamed.event_times["low"]).any() and np.isfinite(streamed.event_times["flip"]).any()


def test_chunking_does_not_change_streamed_results() -> None:
    # A run's lane and its time offset there depend on the chunking; its results must not.
    model, x0 = pl.rigid(), _releases(40, 11)
    a = pl.ensemble(model, x0, 4.0, events=["flip"], threads=1, batch_size=8)
    b = pl.ensemble(model, x0[::-1], 4.0, events=["flip"], threads=1, batch_size=2, chunk_size=7)
    np.testing.assert_array_equal(a.event_times["flip"], b.event_times["flip"][::-1])
    np.testing.assert_array_equal(a.x_final, b.x_final[::-1])


@pytest.mark.parametrize("t_final", [1e-6, 0.3, 1.0, 10.0, 1024.0, 1e12])
def test_clock_stays_far_below_the_states(t_final: float) -> None:
    rate, end = clock_settings(t_final)
    assert 0 < rate * t_final < CLOCK_MAX  # never near a pendulum state: heyoka's steps are unchanged
    assert math.log2(rate) == int(math.log2(rate))  # a power of two: the clock's increments are exact
    assert end == pytest.approx(rate * t_final * (1 - SWITCH_FRACTION), rel=1e-15)


def test_elapsed_is_the_nearest_double_to_the_exact_difference() -> None:
    rng = np.random.default_rng(2)
    for _ in range(2000):
        hi0 = float(rng.uniform(0, 5000))
        lo0 = float(rng.uniform(-0.5, 0.5)) * math.ulp(hi0)
        dt = float(rng.uniform(0, 20))
        hi = hi0 + dt
        lo = float(rng.uniform(-0.5, 0.5)) * math.ulp(hi)
        exact = (Fraction(hi) + Fraction(lo)) - (Fraction(hi0) + Fraction(lo0))
        t, t_lo = elapsed(hi, lo, hi0, lo0)
        assert t == float(exact)
        assert Fraction(t) + Fraction(t_lo) == pytest.approx(exact, abs=1e-28)

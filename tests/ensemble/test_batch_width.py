"""The ensemble on every SIMD batch width: 2, 4 and 8 lanes, whatever heyoka recommends on this host.

Hosts differ (``heyoka.recommended_simd_size()`` is 2, 4 or 8), so the width is an explicit setting
(``batch_size=`` or ``PENDULAB_SIMD_SIZE``). What holds: the same width gives bitwise-identical
results for any chunking; another width may change them at the rounding level only.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import pendulab as pl
from pendulab.ensemble.batch import SIMD_ENV, default_batch_size
from pendulab.ensemble.engine import local_chunk_size

hy = pytest.importorskip("heyoka")

WIDTHS = (2, 4, 8)
TOL = 1e-12


def _starts(n: int = 20, seed: int = 11) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x0 = np.zeros((n, 4))
    x0[:, :2] = rng.uniform(-3.0, 3.0, (n, 2))
    return x0


@pytest.fixture(scope="module")
def model() -> pl.Model:
    return pl.rigid()


@pytest.fixture(scope="module")
def by_width(model: pl.Model) -> dict:
    return {w: pl.ensemble(model, _starts(), 2.0, events=["flip"], threads=1, batch_size=w) for w in WIDTHS}


@pytest.mark.parametrize("width", WIDTHS)
def test_core_checks_hold_at_every_width(model: pl.Model, width: int, by_width: dict) -> None:
    res = by_width[width]
    assert res.stats["batch_size"] == width
    # The chunking is a pure function of (n, chunk_size, width, threads), never of the host.
    assert res.stats["chunk_size"] == local_chunk_size(20, 2000, width, 1)
    x0 = _starts()
    flipped = res.status == "event"
    assert np.all(res.status[~flipped] == "ok") and flipped.any() and (~flipped).any()
    np.testing.assert_array_equal(res.t_final[flipped], res.event_times["flip"][flipped])
    # At its terminal event a link is exactly up: |theta| = pi to the event root accuracy.
    np.testing.assert_allclose(np.max(np.abs(res.x_final[flipped, :2]), axis=1), math.pi, rtol=0, atol=1e-12)
    # Runs that did not flip agree with independent scalar-mode simulate runs.
    for i in np.flatnonzero(~flipped)[:3]:
        traj = pl.simulate(model, x0[i], 2.0, method="taylor", rtol=TOL, atol=TOL)
        # Same translated ODE, scalar vs SIMD lanes: rounding differences amplified over 2 s of chaos.
        np.testing.assert_allclose(res.x_final[i], traj.x[-1], rtol=0, atol=1e-9)
    # Energy is conserved along each free run (not amplified by chaos): the physics check per lane.
    e0, e1 = model.energy(x0[~flipped]), model.energy(res.x_final[~flipped])
    np.testing.assert_allclose(e1, e0, rtol=0, atol=1e-10)  # tolerance 1e-12 per step over ~1e3 steps


@pytest.mark.parametrize("width", WIDTHS)
def test_same_width_and_chunking_is_bitwise_identical(model: pl.Model, width: int, by_width: dict) -> None:
    again = pl.ensemble(model, _starts(), 2.0, events=["flip"], threads=1, batch_size=width)
    np.testing.assert_array_equal(again.x_final, by_width[width].x_final)
    np.testing.assert_array_equal(again.event_times["flip"], by_width[width].event_times["flip"])
    # Threads change where a chunk runs, not what it computes: same chunking -> same bits.
    threaded = pl.ensemble(model, _starts(), 2.0, events=["flip"], threads=2, chunk_size=2, batch_size=width)
    serial = pl.ensemble(model, _starts(), 2.0, events=["flip"], threads=1, chunk_size=2, batch_size=width)
    assert threaded.stats["chunk_size"] == serial.stats["chunk_size"] == 2
    np.testing.assert_array_equal(threaded.x_final, serial.x_final)
    # Nor does the chunking: each lane's arithmetic and double-length time are its own.
    assert serial.stats["chunk_size"] != by_width[width].stats["chunk_size"]
    np.testing.assert_array_equal(serial.x_final, by_width[width].x_final)


def test_widths_agree_to_rounding(by_width: dict) -> None:
    ref = by_width[WIDTHS[0]]
    for w in WIDTHS[1:]:
        res = by_width[w]
        # Another vector width may compile to other instructions: rounding-level differences, amplified over <= 2 s.
        np.testing.assert_array_equal(res.status, ref.status)
        np.testing.assert_allclose(res.x_final, ref.x_final, rtol=0, atol=1e-9)
        np.testing.assert_allclose(res.event_times["flip"], ref.event_times["flip"], rtol=0, atol=1e-9)


def test_env_variable_sets_the_default_width(monkeypatch: pytest.MonkeyPatch, model: pl.Model) -> None:
    monkeypatch.setenv(SIMD_ENV, "2")
    assert default_batch_size() == 2
    assert pl.ensemble(model, _starts(3), 0.5, threads=1).stats["batch_size"] == 2
    monkeypatch.setenv(SIMD_ENV, "65")
    with pytest.raises(ValueError, match=r"PENDULAB_SIMD_SIZE must be at most 64"):
        default_batch_size()
    monkeypatch.delenv(SIMD_ENV)
    assert default_batch_size() == int(hy.recommended_simd_size())


@pytest.mark.parametrize("bad", [0, 65, 2.5, "four", True])
def test_bad_batch_size_names_the_argument(model: pl.Model, bad: object) -> None:
    with pytest.raises(ValueError, match="batch_size"):
        pl.ensemble(model, _starts(2), 0.5, batch_size=bad)

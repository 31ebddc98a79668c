"""The hand-over benchmark reads a reset's hand-over height and time to the band off a figure and off a simulated run."""

from __future__ import annotations

import io
from types import SimpleNamespace

import numpy as np
import pytest

BENCHMARK = "bench_handover"  # the script the `bench` fixture imports (tests/bench/conftest.py)


def _row(bench, angle: float) -> int:
    return int(round(bench.ROW_ZERO - angle * bench.PX_PER_RAD))


def _figure(bench, bars: list[tuple[float, float]], up_at: list[float]) -> bytes:
    """A white figure of upstream's size with grey reset bars [s] and the two curves: upright, hanging from each bar
    until its ``up_at`` time [s] (NaN: never), then upright again."""
    from PIL import Image

    im = np.full((802, 1795, 3), 255, dtype=np.uint8)
    px = (bench.X1 - bench.X0) / bench.T_SPAN
    x_of = lambda t: int(round(bench.X0 + t * px))  # noqa: E731
    for a, b in bars:
        im[20:210, x_of(a) : x_of(b) + 1] = bench.BAR_RGB
    for x in range(bench.X0, bench.X1):
        t = (x - bench.X0) / px
        hanging = any(b < t < up for (_, b), up in zip(bars, up_at, strict=True)) or any(a <= t <= b for a, b in bars)
        q1 = 0.0 if hanging else np.pi
        for angle, rgb in ((q1, bench.Q1_RGB), (0.0, bench.Q2_RGB)):
            r = _row(bench, angle)
            im[r - 1 : r + 2, x] = rgb
    buf = io.BytesIO()
    Image.fromarray(im).save(buf, format="PNG")
    return buf.getvalue()


def test_figure_hand_over_and_time_to_band(bench):
    png = _figure(bench, [(10.0, 11.0), (30.0, 31.0)], [11.8, np.inf])
    rows = bench.read_figure(png)
    assert len(rows) == 2
    (h1, rise1), (h2, rise2) = rows
    # hanging with the elbow straight: the end effector at -(L1 + L2); the drawn curve is 3 px thick
    assert h1 == pytest.approx(-(bench.L1 + bench.L2), abs=0.01)
    assert h2 == pytest.approx(-(bench.L1 + bench.L2), abs=0.01)
    # 0.8 s from the bar's end to upright, to within the figure's resolution (2 px of the bar edge, 1 px a step)
    assert rise1 == pytest.approx(0.8, abs=4 / ((bench.X1 - bench.X0) / bench.T_SPAN))
    assert np.isnan(rise2)  # never up before the figure ends


def test_figure_of_another_size_is_refused(bench):
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.full((400, 900, 3), 255, dtype=np.uint8)).save(buf, format="PNG")
    with pytest.raises(ValueError, match="1795"):
        bench.read_figure(buf.getvalue())


def test_simulated_hand_overs(bench):
    t = np.arange(0.0, 10.0, 0.002)
    q1 = np.full_like(t, np.pi)
    q1[(t >= 1.0) & (t < 2.5)] = 0.0  # reset 1.0-2.0 s leaves it hanging; up again at 2.5 s
    q1[(t >= 5.0) & (t < 9.0)] = np.pi / 2  # reset 5.0-6.0 s leaves it horizontal; up at 9.0 s
    measured = np.column_stack([q1, q1])  # absolute angles: elbow straight
    run = SimpleNamespace(t=t, measured=measured, link_lengths=(0.2, 0.3), threshold=0.45, intervals=[(1.0, 2.0), (5.0, 6.0)])
    (h1, rise1), (h2, rise2) = bench._sim_handovers(run)
    assert h1 == pytest.approx(-0.5)
    assert rise1 == pytest.approx(0.5, abs=0.003)  # one 2 ms sample
    assert h2 == pytest.approx(0.0, abs=1e-12)  # horizontal: the end effector at the pivot's height
    assert rise2 == pytest.approx(3.0, abs=0.003)

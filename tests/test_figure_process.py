"""The CLI's figure process: figures drawn in a forked process that imported matplotlib in advance."""

from __future__ import annotations

import multiprocessing

import matplotlib.pyplot as plt
import numpy as np
import pytest

from pendulab.commands.figure_process import FigureProcess


def _square(path, value: float):
    fig = plt.figure(figsize=(2, 2))
    fig.add_subplot().imshow(np.full((4, 4), value), vmin=0, vmax=1, cmap="gray")
    fig.savefig(path, dpi=50)
    return fig


def _boom(path):
    raise ValueError(f"cannot draw {path.name}")


def test_figures_are_written_by_the_process(tmp_path) -> None:
    with FigureProcess() as figures:
        assert figures._proc is not None and figures._proc.is_alive()
        figures.start(_square, tmp_path / "a.png", 1.0)
        figures.start(_square, tmp_path / "b.png", 0.0)
        figures.finish()
        proc = figures._proc
    assert not proc.is_alive()  # ended with the block
    # The files hold what was asked for: a white and a black square (centre pixel).
    a, b = plt.imread(tmp_path / "a.png"), plt.imread(tmp_path / "b.png")
    assert a[a.shape[0] // 2, a.shape[1] // 2, :3].min() > 0.99 and b[b.shape[0] // 2, b.shape[1] // 2, :3].max() < 0.01


def test_a_failing_figure_is_drawn_here_and_raises_its_own_error(tmp_path) -> None:
    with FigureProcess() as figures:
        figures.start(_boom, tmp_path / "c.png")
        with pytest.raises(ValueError, match="cannot draw c.png"):
            figures.finish()
        assert figures._proc is None  # the process is not trusted any more: later figures are drawn here
        figures.start(_square, tmp_path / "d.png", 1.0)
        figures.finish()
    assert (tmp_path / "d.png").stat().st_size > 0


def test_without_fork_figures_are_drawn_in_this_process(tmp_path, monkeypatch) -> None:
    monkeypatch.setattr(multiprocessing, "get_all_start_methods", lambda: ["spawn"])
    with FigureProcess() as figures:
        assert figures._proc is None
        figures.start(_square, tmp_path / "e.png", 1.0)  # drawn at once
        assert (tmp_path / "e.png").stat().st_size > 0
        figures.finish()


def test_an_error_in_the_block_ends_the_process_at_once() -> None:
    with pytest.raises(KeyboardInterrupt), FigureProcess() as figures:
        proc = figures._proc
        raise KeyboardInterrupt
    assert not proc.is_alive() and proc.exitcode is not None

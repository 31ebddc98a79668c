"""Animated GIF of one or more pendulums side by side, with fading traces of the bobs."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402
from PIL import Image  # noqa: E402

from .._checks import check_budget  # noqa: E402
from .._io import atomic_path  # noqa: E402
from .drawing import as_runs, link_polylines, run_colors, view_limits  # noqa: E402

__all__ = ["animate"]


def _frame_indices(t: np.ndarray, fps: float, duration: float | None) -> np.ndarray:
    """Output-grid indices shown at ``fps`` frames per second of simulated time (real-time playback)."""
    t_end = t[-1] if duration is None else min(duration, t[-1])
    frames = np.arange(0.0, t_end + 1e-9, 1.0 / fps)
    return np.unique(np.clip(np.searchsorted(t, frames - 1e-9), 0, len(t) - 1))


def animate(
    runs: Any,
    path: str | Path,
    *,
    fps: float = 20.0,
    duration: float | None = None,
    trail: float = 1.5,
    width: float = 9.6,
    dpi: int = 100,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Write an animated GIF of the runs side by side (frames blitted with matplotlib, written by Pillow).

    Parameters
    ----------
    runs : mapping label -> (Model, Trajectory), or list of Run
        All runs must share the same output times.
    path : str or Path
        GIF file to write.
    fps : float, default 20.0
        Frames per second; playback is real time (one frame per ``1/fps`` s simulated).
    duration : float, optional
        Simulated time shown [s] (default: the whole trajectory).
    trail : float, default 1.5
        Length of the fading trace of each bob [s].
    width : float, default 9.6
        Figure width [in]; the height follows the motion's aspect ratio. With
        ``dpi`` it sets the GIF size in pixels (default 960 px wide: labels of
        10-13 px a person can read).
    dpi : int, default 100
        Resolution [dots per inch].
    progress : callable(done, total), optional
        Called after each rendered frame (the CLI prints progress with it).

    Returns
    -------
    Path
        The written file (parent directories created).

    Raises
    ------
    ValueError
        The runs do not share the same output times, ``fps <= 0`` or
        ``trail < 0``, or ``runs`` is empty or malformed.
    BudgetError
        More frames (shown duration x ``fps``) than ``PENDULAB_MAX_FRAMES``, or a frame (``width`` x ``dpi``)
        of more pixels than ``PENDULAB_MAX_IMAGE_PIXELS``; checked before any frame is drawn.
    """
    runs = as_runs(runs)
    t = runs[0].traj.t
    if any(r.traj.t.shape != t.shape or not np.allclose(r.traj.t, t) for r in runs):
        raise ValueError("animate: all runs must share the same output times")
    if fps <= 0 or trail < 0:
        raise ValueError(f"animate: fps must be > 0 and trail >= 0, got fps={fps!r}, trail={trail!r}")
    shown = float(t[-1] if duration is None else min(duration, t[-1]))
    check_budget("frames", "duration x fps", f"{shown:g} s x {fps!r}", shown * fps + 1.0)  # before the frame times are allocated
    frames = _frame_indices(t, fps, duration)
    n_trail = max(1, int(round(trail / max(t[1] - t[0], 1e-12)))) if len(t) > 1 else 1
    xlim, ylim = view_limits(runs)

    ratio = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    size = (width, width / len(runs) * ratio + 0.55)
    check_budget("image_pixels", "width, dpi", f"{width!r}, {dpi!r}", float(size[0] * dpi) * float(size[1] * dpi))
    fig, axes = plt.subplots(1, len(runs), figsize=size, dpi=dpi, squeeze=False)
    artists = []
    for ax, run, color in zip(axes[0], runs, run_colors(len(runs)), strict=True):
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        ax.set_xlabel("$x$ [m]", fontsize=10)
        ax.set_ylabel("$y$ [m]", fontsize=10)
        ax.tick_params(labelsize=9)
        ax.set_title(run.label, fontsize=12)
        ax.grid(alpha=0.25)
        ax.plot([0], [0], "k^", ms=6)
        traces = [LineCollection([], lw=1.4, animated=True) for _ in range(2)]
        for tr in traces:
            ax.add_collection(tr)
        links = [ax.plot([], [], color="0.15", lw=1.3, animated=True)[0] for _ in range(2)]
        (bobs,) = ax.plot([], [], "o", color=color, ms=7, animated=True)
        artists.append((ax, run, color, traces, links, bobs))
    label = fig.text(0.5, 0.02, "", ha="center", fontsize=11, animated=True)
    fig.tight_layout(rect=(0, 0.05, 1, 1))

    # Blitting: axes, ticks and labels are rendered once; each frame redraws only the moving artists
    # (re-rendering the text of every frame costs ~10x more).
    canvas = fig.canvas
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    images = []
    try:
        for n, k in enumerate(frames):
            canvas.restore_region(background)
            lo = max(0, k - n_trail)
            for ax, run, color, traces, links, bobs in artists:
                pos = run.positions
                for tr, (cx, cy), base in zip(traces, ((2, 3), (0, 1)), (color, "0.45"), strict=True):
                    pts = pos[lo : k + 1][:, [cx, cy]]
                    segs = np.stack([pts[:-1], pts[1:]], axis=1) if len(pts) > 1 else np.empty((0, 2, 2))
                    rgba = np.tile(to_rgba(base), (len(segs), 1))
                    # Older points fade out: alpha rises from 0 at the tail to 0.9 at the bob.
                    rgba[:, 3] = np.linspace(0.0, 0.9, len(segs)) ** 1.5
                    tr.set_segments(segs)
                    tr.set_color(rgba)
                    ax.draw_artist(tr)
                for line, poly in zip(links, link_polylines(run.model, pos[k]), strict=True):
                    line.set_data(poly[:, 0], poly[:, 1])
                    ax.draw_artist(line)
                bobs.set_data(pos[k, [0, 2]], pos[k, [1, 3]])
                ax.draw_artist(bobs)
            label.set_text(f"t = {t[k]:5.2f} s")
            fig.draw_artist(label)
            images.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy()))
            if progress is not None:
                progress(n + 1, len(frames))
    finally:
        plt.close(fig)
    # One shared adaptive palette keeps colours stable between frames and the file small.
    # (method 0 = median cut, dither 0 = none: integer codes valid across Pillow versions.)
    palette = images[len(images) // 2].quantize(colors=64, method=0)
    frames_p = [im.quantize(palette=palette, dither=0) for im in images]
    path = Path(path)
    with atomic_path(path) as tmp:  # an interrupted run never leaves a truncated GIF
        frames_p[0].save(tmp, format="GIF", save_all=True, append_images=frames_p[1:], duration=int(round(1000 / fps)), loop=0)
    return path

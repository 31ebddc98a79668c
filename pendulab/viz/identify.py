"""Figures of system identification: measured against predicted motion, and error against horizon."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..identify.preprocess import Prepared
from ..identify.simulate import HORIZONS, open_loop_segments
from ..identify.validation import RecordScore
from .save import save_figure

__all__ = ["identification_figure"]


def identification_figure(
    preps: Sequence[Prepared],
    models: Mapping[str, Sequence[np.ndarray]],
    scores: Mapping[str, Sequence[RecordScore]],
    fixed: Mapping[str, float],
    path: str | os.PathLike[str],
    *,
    title: str = "",
) -> Path:
    """Measured against predicted angles per record, and the prediction error against horizon per model.

    Parameters
    ----------
    preps : sequence of Prepared
        The records shown (one row each).
    models : mapping of str to sequence of numpy.ndarray
        Per model name, its standard parameters for each record (shape (13,) each; leave-one-out
        fits differ per record). At most three models are drawn in the record panels.
    scores : mapping of str to sequence of RecordScore
        By record, the scores of every model (the error-against-horizon panels).
    fixed : mapping of str to float
        Known geometry.
    path : path-like
        The PNG file.
    title : str, default ""
        Figure title.

    Returns
    -------
    Path
        The file written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(preps)
    fig = plt.figure(figsize=(15, 2.1 * n + 3.2))
    grid = fig.add_gridspec(n + 1, 2, height_ratios=[1.5] + [1.0] * n, hspace=0.55, wspace=0.12)
    names = sorted({s.model for v in scores.values() for s in v}, key=lambda m: (m != "pendulab", m))
    for j in range(2):
        ax = fig.add_subplot(grid[0, j])
        for name in names:
            errs = np.concatenate([s.prediction for v in scores.values() for s in v if s.model == name], axis=1)
            rms = np.sqrt((errs[:, :, j] ** 2).mean(axis=1))
            ax.plot(HORIZONS, rms, "o-", lw=2.5 if name == "pendulab" else 1.2, label=name)
        ax.set_xlabel("prediction horizon [s]")
        ax.set_ylabel(f"RMS error of q{j + 1} [rad]")
        ax.set_title(f"open-loop prediction error, joint {j + 1} (held-out records)")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    colors = {"measured": "k"}
    palette = ["tab:blue", "tab:orange", "tab:red"]
    for i, prep in enumerate(preps):
        for j in range(2):
            ax = fig.add_subplot(grid[i + 1, j])
            ax.plot(prep.t, prep.q_measured[:, j], color=colors["measured"], lw=1.0, label="measured")
            for c, (name, per_record) in enumerate(list(models.items())[:3]):
                for k, (t, q) in enumerate(open_loop_segments(prep, per_record[i], fixed, every=1.0, length=1.0)):
                    ax.plot(t, q[j], color=palette[c], lw=1.0, alpha=0.9, label=f"{name} (1 s open loop)" if k == 0 else None)
            ax.set_ylabel(f"q{j + 1} [rad]")
            ax.set_title(f"{prep.name}, joint {j + 1}", fontsize=9)
            if i == n - 1:
                ax.set_xlabel("time [s]")
            if i == 0 and j == 1:
                ax.legend(fontsize=7, loc="upper right")
    if title:
        fig.suptitle(title)
    out = Path(path)
    save_figure(fig, out)
    return out

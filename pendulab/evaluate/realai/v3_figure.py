"""Figure of a v3 run: end-effector height with the 0.9 (L1 + L2) line and the reset intervals, and the torques.

Kept beside the protocol (not in :mod:`pendulab.viz`, a layer above) because :func:`~.v3.v3_score` writes it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..._io import atomic_path

__all__ = ["plot_v3"]


def plot_v3(result: Any, path: str | Path) -> Path:
    """Two panels over the 60 s: end-effector height [m] (the line, reset intervals shaded) and torques [N.m].

    Parameters
    ----------
    result : V3Result
        A finished v3 run.
    path : str or Path
        Output image (format from the suffix).

    Returns
    -------
    Path
        The file written (atomically).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, h = result.t, result.height
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(12, 6), sharex=True, layout="constrained")
    for i, (a, b) in enumerate(result.intervals):
        for ax in (ax1, ax2):
            ax.axvspan(a, b, color="tab:red", alpha=0.25, lw=0, label="reset (PID)" if (i == 0 and ax is ax1) else None)
    ax1.plot(t, h, lw=0.7, color="tab:blue", label="end effector")
    ax1.axhline(result.threshold, color="k", ls="--", lw=1, label=f"0.9 (L1 + L2) = {result.threshold:.2f} m")
    ax1.set_ylabel("height [m]")
    ax1.set_title(
        f"RealAIGym v3, {result.task}, {result.controller}, seed {result.seed}: "
        f"score {result.score:.3f} (uptime {result.uptime:.1f} s of 60 s, {result.n_swingups} swing-ups)"
    )
    ax1.legend(loc="lower right", fontsize=8, ncols=3)
    ax2.plot(t, result.u[:, 0], lw=0.6, label="tau1")
    ax2.plot(t, result.u[:, 1], lw=0.6, label="tau2")
    ax2.set_ylabel("applied torque [N.m]")
    ax2.set_xlabel("time [s]")
    ax2.set_ylim(-6.5, 6.5)
    ax2.set_xlim(0.0, float(np.max(t)) + 0.002)
    ax2.legend(loc="lower right", fontsize=8, ncols=2)
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    try:
        with atomic_path(p) as tmp:
            fig.savefig(tmp, dpi=110, format=p.suffix.lstrip(".").lower() or "png")
    finally:
        plt.close(fig)
    return p

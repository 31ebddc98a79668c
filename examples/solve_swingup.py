"""Swing-up trajectory optimization
================================

Swing up the RealAIGym pendubot (or any shipped task), check it against CVODES, hold it with TVLQR + LQR.

The plan is a direct collocation (Radau, N intervals) solved by IPOPT, its error estimated by re-integrating
every interval (the mesh is refined until it meets the task's tolerance), then replayed open loop and tracked
in closed loop by TVLQR with an LQR hand-over at the top. Prints the episode's key numbers and writes the
figures of ``pendulab swingup --out DIR``: states and torques, phase portraits, tip height, error estimate.

Run: ``python examples/solve_swingup.py [OUT_DIR]`` (default ``swingup_figures``; about 10 s, progress on stderr)
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

from pendulab.control.swingup.episode import run_episode
from pendulab.control.swingup.tasks import load_task
from pendulab.viz.swingup import plot_episode

#: The summary entries printed by main() (``Episode.summary()`` has many more).
SHOWN = (
    "task", "method", "N", "solve_success", "iterations", "solve_time_s", "cost", "error_worst", "error_tolerance",
    "refinements", "replay_open_loop_max_deviation", "success", "swing_up_time_s",
)  # fmt: skip


def run(
    *,
    task: str = "pendubot",
    N: int | None = None,
    method: str = "radau",
    out_dir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Solve, replay and track one task; return its summary (SI units).

    Parameters
    ----------
    task : str
        Shipped task name (``pendulab swingup --list``).
    N : int, optional
        Initial number of collocation intervals, refined until the plan meets the task's tolerance
        (default: the task's, the same as ``pendulab swingup``).
    method : str
        Transcription (``radau``, ``legendre``, ``shooting``).
    out_dir : str or Path, optional
        Where to write the episode's PNG figures; none if None.
    progress : callable(str), optional
        Called with a one-line status before each step (planning, replay, closed loop, figures).

    Returns
    -------
    dict
        ``Episode.summary()``, plus ``figures`` (list of written paths).
    """
    say = progress or (lambda message: None)
    spec = load_task(task)
    say(f"planning the {task} swing-up: {method}, N = {N or spec.N}, IPOPT, error estimate ...")
    episode = run_episode(spec, method=method, N=N, stage=say)
    figures = []
    if out_dir is not None:
        say("drawing the figures ...")
        figures = plot_episode(episode, out_dir)
    return {**episode.summary(), "figures": figures}


def main() -> None:
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("swingup_figures")
    summary = run(out_dir=out_dir, progress=lambda message: print(message, file=sys.stderr))
    for key in SHOWN:
        print(f"{key:32s} {summary.get(key)}")
    print(f"wrote {len(summary['figures'])} figures to {out_dir}/")


if __name__ == "__main__":
    main()

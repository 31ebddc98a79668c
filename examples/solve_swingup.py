"""Swing-up trajectory optimization
================================

Swing up the RealAIGym pendubot (or any shipped task), check it against CVODES, hold it with TVLQR + LQR.

Run:  PYTHONPATH=$PWD python examples/solve_swingup.py
"""

# Gallery thumbnail (this example is shown as code; the figure is the one its command writes).
# sphinx_gallery_thumbnail_path = "figures/swingup_pendubot.png"

from __future__ import annotations

from pendulab.control.swingup.episode import run_episode
from pendulab.control.swingup.tasks import load_task

#: Keyword arguments of the brief run in the test suite.
TEST_KWARGS = {"N": 40}


def run(*, task: str = "pendubot", N: int = 100, method: str = "radau") -> dict:
    """Solve, replay and track one task; return its summary (SI units)."""
    episode = run_episode(load_task(task), method=method, N=N)
    return episode.summary()


def main() -> None:
    summary = run()
    for key, value in summary.items():
        print(f"{key:32s} {value}")


if __name__ == "__main__":
    main()

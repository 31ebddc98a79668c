"""The seed paper's experiment
===========================

Simulate the seed paper's experiment: rigid vs elastic double pendulum from identical initial conditions.

Loads the shipped ``seed_paper`` scene (elastic, k = 500 N/m, theta1 = theta2 =
1.2 rad, springs at rest length), builds the rigid counterpart (same masses,
lengths, gravity), simulates both and reports how far the elastic pendulum
departs from the rigid one. ``pendulab demo`` does the same (and an animation);
here the paper's figures go to ``OUT_DIR``.

Run: ``python examples/simulate_seed_paper.py [OUT_DIR]`` (default ``seed_paper_figures``)
"""

# The gallery's thumbnail: the third figure written (rigid against elastic angles, the paper's Fig. 4).
# sphinx_gallery_thumbnail_number = 3

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import pendulab as pl
from pendulab.model.counterpart import rigid_counterpart, rigid_state
from pendulab.scene import load_scene


def run(*, t_final: float = 10.0, out_dir: str | Path | None = None) -> dict:
    """Simulate both models; return trajectories, models and the angle gap.

    Parameters
    ----------
    t_final : float
        Horizon [s].
    out_dir : str or Path, optional
        When given, write the seed paper's figures (PNG) there.

    Returns
    -------
    dict
        ``rigid`` and ``elastic``: (Model, Trajectory); ``max_angle_gap``: largest
        |theta2 elastic - theta2 rigid| [rad]; ``energy_drift``: largest
        relative energy drift of the two runs.
    """
    scene = load_scene("seed_paper")
    rigid = rigid_counterpart(scene.model)
    elastic_traj = scene.simulate(t_final=t_final)
    rigid_traj = pl.simulate(
        rigid, rigid_state(scene.model, scene.x0), t_final, dt=scene.dt, method=scene.method, rtol=scene.rtol, atol=scene.atol
    )
    runs = {"rigid": (rigid, rigid_traj), "elastic": (scene.model, elastic_traj)}
    if out_dir is not None:
        from pendulab.viz import save_figures

        save_figures(runs, out_dir)
    drift = max(float(np.max(np.abs(tr["energy"] - tr["energy"][0])) / abs(tr["energy"][0])) for _, tr in runs.values())
    return {
        **runs,
        "max_angle_gap": float(np.max(np.abs(elastic_traj["theta2"] - rigid_traj["theta2"]))),
        "energy_drift": drift,
    }


def main() -> None:
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("seed_paper_figures")
    result = run(out_dir=out_dir)
    for label in ("rigid", "elastic"):
        model, traj = result[label]
        print(f"{label:8s} theta1(T) = {traj['theta1'][-1]:+.4f} rad, theta2(T) = {traj['theta2'][-1]:+.4f} rad")
    print(f"largest theta2 gap elastic - rigid: {result['max_angle_gap']:.3f} rad")
    print(f"largest relative energy drift: {result['energy_drift']:.1e}")
    print(f"wrote the paper's figures to {out_dir}/")


if __name__ == "__main__":
    main()

"""The seed paper's experiment
===========================

Simulate the seed paper's experiment: rigid vs elastic double pendulum from identical initial conditions.

Loads the shipped ``seed_paper`` scene (elastic, k = 500 N/m, theta1 = theta2 =
1.2 rad, springs at rest length), builds the rigid counterpart (same masses,
lengths, gravity), simulates both and reports how far the elastic pendulum
departs from the rigid one. ``pendulab demo`` does the same and also writes the
paper's figures; pass ``out_dir`` to write them here too.

Run: ``python examples/simulate_seed_paper.py``
"""

# Gallery thumbnail (this example is shown as code; the figure is the one its command writes).
# sphinx_gallery_thumbnail_path = "figures/demo_fig4_angles_compare.png"

from __future__ import annotations

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
    result = run()
    for label in ("rigid", "elastic"):
        model, traj = result[label]
        print(f"{label:8s} theta1(T) = {traj['theta1'][-1]:+.4f} rad, theta2(T) = {traj['theta2'][-1]:+.4f} rad")
    print(f"largest theta2 gap elastic - rigid: {result['max_angle_gap']:.3f} rad")
    print(f"largest relative energy drift: {result['energy_drift']:.1e}")


if __name__ == "__main__":
    main()

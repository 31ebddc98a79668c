"""Elastic pendulums approach the rigid one
========================================

Compare elastic pendulums of increasing stiffness with the rigid one (the rigid limit).

From the same release (theta1 = theta2 = 0.3 rad, at rest), the elastic
trajectory approaches the rigid one as the spring stiffness k grows. The
springs start at their static hanging length, so the fast spring mode is only
weakly excited; an implicit method (CVODES BDF) steps over it for stiff springs.

Run: ``python examples/compare_stiffness.py``
"""

# Gallery thumbnail (this example is shown as code; the figure is the one its command writes).
# sphinx_gallery_thumbnail_path = "figures/modes_frequency_vs_stiffness.png"

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

import pendulab as pl
from pendulab.model.counterpart import rigid_counterpart, rigid_state


def run(*, stiffnesses: Sequence[float] = (1e2, 1e3, 1e4, 1e5), t_final: float = 3.0, theta0: float = 0.3) -> dict:
    """Largest bob-2 position error against the rigid pendulum for each stiffness.

    Parameters
    ----------
    stiffnesses : sequence of float
        Spring stiffnesses k1 = k2 [N/m].
    t_final : float
        Horizon [s].
    theta0 : float
        Release angle of both links [rad].

    Returns
    -------
    dict
        ``k`` (array of stiffnesses [N/m]) and ``error`` (largest distance
        between the rigid and elastic bob 2 over the horizon [m]), same order.
    """
    errors = []
    for k in stiffnesses:
        elastic = pl.elastic(k1=float(k), k2=float(k))
        x0 = elastic.state(theta1=theta0, theta2=theta0)
        rigid = rigid_counterpart(elastic)
        opts = {"dt": 0.01, "method": "cvodes", "rtol": 1e-10, "atol": 1e-10}
        te = pl.simulate(elastic, x0, t_final, **opts)
        tr = pl.simulate(rigid, rigid_state(elastic, x0), t_final, **opts)
        gap = np.hypot(te["x2"] - tr["x2"], te["y2"] - tr["y2"])
        errors.append(float(np.max(gap)))
    return {"k": np.asarray(stiffnesses, dtype=float), "error": np.asarray(errors)}


def main() -> None:
    result = run()
    print("k [N/m]      max |bob 2 elastic - rigid| [m]")
    for k, e in zip(result["k"], result["error"], strict=True):
        print(f"{k:10.0e}   {e:.3e}")


if __name__ == "__main__":
    main()

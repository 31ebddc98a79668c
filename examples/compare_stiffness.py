"""Elastic pendulums approach the rigid one
========================================

Compare elastic pendulums of increasing stiffness with the rigid one (the rigid limit).

From the same release (theta1 = theta2 = 0.3 rad, at rest), the elastic
trajectory approaches the rigid one as the spring stiffness k grows. The
springs start at their static hanging length, so the fast spring mode is only
weakly excited; an implicit method (CVODES BDF) steps over it for stiff springs.
The error falls as 1/k (the static stretch of a spring is m g / k).

Run: ``python examples/compare_stiffness.py [OUT_DIR]`` (default ``stiffness_figures``)
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pendulab as pl  # noqa: E402
from pendulab.model.counterpart import rigid_counterpart, rigid_state  # noqa: E402


def run(
    *,
    stiffnesses: Sequence[float] = (1e2, 1e3, 1e4, 1e5),
    t_final: float = 3.0,
    theta0: float = 0.3,
    out_dir: str | Path | None = None,
) -> dict:
    """Largest bob-2 position error against the rigid pendulum for each stiffness.

    Parameters
    ----------
    stiffnesses : sequence of float
        Spring stiffnesses k1 = k2 [N/m].
    t_final : float
        Horizon [s].
    theta0 : float
        Release angle of both links [rad].
    out_dir : str or Path, optional
        Where to write ``rigid_limit.png`` (error against k, log-log); no figure if None.

    Returns
    -------
    dict
        ``k`` (array of stiffnesses [N/m]) and ``error`` (largest distance
        between the rigid and elastic bob 2 over the horizon [m]), same order;
        ``figure`` (path or None).
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
    result = {"k": np.asarray(stiffnesses, dtype=float), "error": np.asarray(errors), "figure": None}
    if out_dir is not None:
        result["figure"] = _figure(result, t_final, theta0, Path(out_dir))
    return result


def _figure(result: dict, t_final: float, theta0: float, out_dir: Path) -> Path:
    k, err = result["k"], result["error"]
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    ax.loglog(k, err, "o-", label="elastic vs rigid (CVODES, rtol 1e-10)")
    ax.loglog(k, err[0] * k[0] / k, "k--", lw=0.8, label="slope 1/k")
    ax.set_xlabel("spring stiffness k1 = k2 [N/m]")
    ax.set_ylabel("max |bob 2 elastic - rigid| [m]")
    ax.set_title(f"the rigid limit: release at {theta0:g} rad, {t_final:g} s", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "rigid_limit.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    result = run(out_dir=Path(sys.argv[1]) if len(sys.argv) > 1 else Path("stiffness_figures"))
    print("k [N/m]      max |bob 2 elastic - rigid| [m]")
    for k, e in zip(result["k"], result["error"], strict=True):
        print(f"{k:10.0e}   {e:.3e}")
    print(f"wrote {result['figure']}")


if __name__ == "__main__":
    main()

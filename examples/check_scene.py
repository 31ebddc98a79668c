"""Which model does a scene need?
==============================

Which model does a scene need? Run the model hierarchy on a shipped scene.

Linearized, rigid, rigid with quasi-static spring stretch and the full elastic
model are run on the scene's outputs and horizon; the cheapest one within the
scene's tolerance is chosen, and its trajectory is computed with that level.
Prints the table of the levels and writes a figure: each level's error against
the tolerance, and the chosen level's bob-2 path over the reference's.

Usage: ``python examples/check_scene.py [SCENE]`` (default ``stiff_moderate_amplitude``;
the figure goes to ``scene_figures/``).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pendulab.bench.hierarchy import measure_model_choice  # noqa: E402
from pendulab.scene import load_scene  # noqa: E402


def run(
    *,
    scene: str = "stiff_moderate_amplitude",
    repeats: int = 3,
    out_dir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Check ``scene``; return the report, the chosen level and its trajectory.

    Parameters
    ----------
    scene : str
        Shipped scene name or TOML file.
    repeats : int
        Timed runs per level (the wall times are medians).
    out_dir : str or Path, optional
        Where to write ``model_choice.png``; no figure if None.
    progress : callable(str), optional
        Called with a one-line status before the check.

    Returns
    -------
    dict
        ``report`` (HierarchyReport), ``level`` (the chosen ModelLevel), ``trajectory`` (its run of
        the scene) and ``figure`` (path or None).
    """
    sc = load_scene(scene)
    if progress is not None:
        progress(f"running every model level and the reference on {sc.name} ({repeats} timed runs each) ...")
    level, report = measure_model_choice(sc, repeats=repeats)
    traj = level.simulate(sc)
    figure = _figure(sc, report, traj, Path(out_dir)) if out_dir is not None else None
    return {"report": report, "level": level, "trajectory": traj, "figure": figure}


def _figure(scene: Any, report: Any, traj: Any, out_dir: Path) -> Path:
    reference = scene.simulate()  # the scene's own model and settings: the reference level
    levels = [lv for lv in report.levels if lv.note != "reference"]
    fig, (ax_err, ax_path) = plt.subplots(1, 2, figsize=(10.5, 4.2))
    colors = ["C2" if lv.within else "C3" for lv in levels]
    ax_err.bar([lv.name for lv in levels], [max(lv.error, 1e-16) for lv in levels], color=colors)
    ax_err.axhline(report.tolerance, color="k", ls="--", lw=1, label=f"tolerance {report.tolerance:g}")
    ax_err.set_yscale("log")
    ax_err.set_ylabel(f"max error on {', '.join(report.outputs)}")
    ax_err.set_title(f"{report.scene}: chosen {report.chosen} (green: within)", fontsize=10)
    ax_err.legend(fontsize=8)
    ax_path.plot(reference["x2"], reference["y2"], color="0.6", lw=3, label=f"reference ({report.reference})")
    ax_path.plot(traj["x2"], traj["y2"], color="C0", lw=1, label=f"chosen: {report.chosen}")
    ax_path.plot(traj["x2"][0], traj["y2"][0], "ko", ms=4)
    ax_path.set_xlabel("x2 [m]")
    ax_path.set_ylabel("y2 [m]")
    ax_path.set_aspect("equal", adjustable="datalim")
    gap = np.max(np.hypot(traj["x2"] - reference["x2"], traj["y2"] - reference["y2"]))
    ax_path.set_title(f"bob 2 over {traj.t[-1]:g} s, largest gap {gap:.1e} m", fontsize=10)
    ax_path.legend(fontsize=8)
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "model_choice.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    scene = sys.argv[1] if len(sys.argv) > 1 else "stiff_moderate_amplitude"
    result = run(scene=scene, out_dir="scene_figures", progress=lambda message: print(message, file=sys.stderr))
    print(result["report"].table())
    traj = result["trajectory"]
    print(f"final bob-2 position with the {result['level'].name} model: x2 = {traj['x2'][-1]:.4f} m, y2 = {traj['y2'][-1]:.4f} m")
    print(f"wrote {result['figure']}")


if __name__ == "__main__":
    main()

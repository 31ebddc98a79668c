"""Which model does a scene need?
==============================

Which model does a scene need? Run the model hierarchy on a shipped scene.

Linearized, rigid, rigid with quasi-static spring stretch and the full elastic
model are run on the scene's outputs and horizon; the cheapest one within the
scene's tolerance is chosen, and its trajectory is computed with that level.

Usage: ``python examples/check_scene.py [SCENE]`` (default ``stiff_moderate_amplitude``).
"""

from __future__ import annotations

import sys
from typing import Any

from pendulab.bench.hierarchy import measure_model_choice
from pendulab.scene import load_scene

TEST_KWARGS = {"repeats": 1}


def run(*, scene: str = "stiff_moderate_amplitude", repeats: int = 3) -> dict[str, Any]:
    """Check ``scene``; return the report, the chosen level and its trajectory."""
    sc = load_scene(scene)
    level, report = measure_model_choice(sc, repeats=repeats)
    return {"report": report, "level": level, "trajectory": level.simulate(sc)}


def main() -> None:
    result = run(scene=sys.argv[1] if len(sys.argv) > 1 else "stiff_moderate_amplitude")
    print(result["report"].table())
    traj = result["trajectory"]
    print(f"final bob-2 position with the {result['level'].name} model: x2 = {traj['x2'][-1]:.4f} m, y2 = {traj['y2'][-1]:.4f} m")


if __name__ == "__main__":
    main()

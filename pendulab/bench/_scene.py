"""Scene loading for the bench tools: ``pendulab.scenes.load_scene`` when present.

The minimal fallback below reads the shared scene format (see the common
brief) until the scene loader lands; delete it then.
"""

from __future__ import annotations

import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..model.model import make_model

_SCENE_DIR = Path(__file__).resolve().parent.parent / "scenes"


def load(path_or_name: str | Path) -> Any:
    """Load a scene by file path or shipped name."""
    try:
        from ..scenes import load_scene  # type: ignore[attr-defined]
    except ImportError:
        return _load_minimal(path_or_name)
    return load_scene(path_or_name)


def _load_minimal(path_or_name: str | Path) -> Any:
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib
    path = Path(path_or_name)
    if not path.is_file():
        path = _SCENE_DIR / f"{str(path_or_name).removesuffix('.toml')}.toml"
    if not path.is_file():
        raise FileNotFoundError(f"scene {str(path_or_name)!r}: no such file and no shipped scene of that name")
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    model = make_model(data["model"]["kind"], **data["model"].get("params", {}))
    sim = {"t_final": 10.0, "dt": 0.01, "method": "cvodes", "rtol": 1e-8, "atol": 1e-8, **data.get("simulation", {})}
    out = data.get("outputs", {})
    u = data.get("input")
    return SimpleNamespace(
        name=data.get("scene", {}).get("name", path.stem),
        model=model,
        x0=model.state(**data.get("initial", {})),
        outputs=tuple(out.get("names", ("theta1", "theta2"))),
        tolerance=out.get("tolerance"),
        u=None if u is None else np.array([u.get("tau1", 0.0), u.get("tau2", 0.0)]),
        path=path,
        **sim,
    )

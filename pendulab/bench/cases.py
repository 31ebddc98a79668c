"""Benchmark cases of the work-precision study: the shipped scenes of the ``bench`` group.

Each case is a :class:`~pendulab.scene.Scene` (``pendulab/scenes/bench/*.toml``):
a model, an initial state, a horizon and an output grid. All are undamped and
unforced, so the exact energy is constant and energy drift is a check that
chaos does not amplify. Their stored reference solutions are keyed by scene name.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from ..scene import Scene, list_scenes, load_scene

__all__ = ["CASES", "get_cases", "is_stiff"]

#: Stiffness [N/m] from which a case counts as stiff (spring modes >= 0.618 sqrt(k) = 62 rad/s).
STIFF_K = 1e4


def _load() -> Mapping[str, Scene]:
    order = (
        "rigid_regular",
        "rigid_chaotic_2s",
        "rigid_chaotic_10s",
        "elastic_soft",
        "elastic_stiff_1e4_rest",
        "elastic_stiff_1e4_qs",
        "elastic_stiff_1e6_rest",
        "elastic_stiff_1e6_qs",
    )
    shipped = {name.split("/", 1)[1] for name in list_scenes("bench")}
    names = [n for n in order if n in shipped] + sorted(shipped - set(order))
    return MappingProxyType({n: load_scene(f"bench/{n}") for n in names})


#: The cases by name (legend order).
CASES: Mapping[str, Scene] = _load()


def is_stiff(case: Scene) -> bool:
    """True for an elastic case whose softer spring has k >= :data:`STIFF_K`.

    Parameters
    ----------
    case : Scene
        A case.

    Returns
    -------
    bool
    """
    p = case.model.params
    return case.kind == "elastic" and min(p.k1, p.k2) >= STIFF_K


def get_cases(names: list[str] | tuple[str, ...] | None = None) -> list[Scene]:
    """Cases by name (all when None).

    Parameters
    ----------
    names : sequence of str, optional
        Case names (keys of :data:`CASES`).

    Returns
    -------
    list of Scene

    Raises
    ------
    ValueError
        An unknown name.
    """
    if names is None:
        return list(CASES.values())
    unknown = [n for n in names if n not in CASES]
    if unknown:
        raise ValueError(f"unknown case(s) {unknown}; expected some of {list(CASES)}")
    return [CASES[n] for n in names]

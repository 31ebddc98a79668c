"""Benchmark cases of the work-precision study (issue 7).

Each case is a model, an initial state, a horizon and an output grid. All are
undamped and unforced, so the exact energy is constant and energy drift is a
check that chaos does not amplify.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..model.model import Model, make_model
from ..model.quasistatic import quasi_static_state

__all__ = ["Case", "CASES", "get_cases"]


@dataclass(frozen=True)
class Case:
    """One work-precision case.

    Attributes
    ----------
    name : str
    kind : {"rigid", "elastic"}
    params : mapping
        Model parameters by name (others at their defaults: m = 1 kg, L = 1 m, g = 9.81 m/s2).
    theta : tuple of float
        Initial angles [rad], at rest.
    start : {"static", "rest-length", "quasi-static"}
        Spring lengths at t = 0 (elastic only): static hanging length, rest length
        L (excites the spring mode), or quasi-static (zero radial acceleration).
    t_final, dt : float
        Horizon and output-grid step [s].
    """

    name: str
    kind: str
    theta: tuple[float, float]
    t_final: float
    description: str
    params: Mapping[str, float] = field(default_factory=dict)
    start: str = "static"
    dt: float = 0.05

    def model(self) -> Model:
        return make_model(self.kind, **dict(self.params))

    def initial_state(self) -> np.ndarray:
        m = self.model()
        if self.kind == "rigid":
            return m.state(theta1=self.theta[0], theta2=self.theta[1])
        if self.start == "rest-length":
            return m.state(theta1=self.theta[0], theta2=self.theta[1], r1=m.params.L1, r2=m.params.L2)
        if self.start == "quasi-static":
            return quasi_static_state(m, self.theta)
        return m.state(theta1=self.theta[0], theta2=self.theta[1])

    @property
    def stiff(self) -> bool:
        return self.kind == "elastic" and min(self.params.get("k1", 500.0), self.params.get("k2", 500.0)) >= 1e4


def _stiff(k: float, start: str) -> Case:
    tag = {"rest-length": "rest", "quasi-static": "qs"}[start]
    return Case(
        f"elastic_stiff_{k:.0e}_{tag}".replace("+0", ""),
        "elastic",
        (0.3, 0.3),
        2.0,
        f"elastic, k = {k:.0e} N/m, theta = 0.3 rad, springs at {start} length, 2 s",
        {"k1": k, "k2": k},
        start,
    )


CASES: Mapping[str, Case] = {
    c.name: c
    for c in (
        Case("rigid_regular", "rigid", (0.3, 0.3), 10.0, "rigid, theta = 0.3 rad, 10 s (regular)"),
        Case("rigid_chaotic_2s", "rigid", (2.0, 2.0), 2.0, "rigid, theta = 2 rad, 2 s (chaotic)"),
        Case("rigid_chaotic_10s", "rigid", (2.0, 2.0), 10.0, "rigid, theta = 2 rad, 10 s (chaotic)"),
        Case(
            "elastic_soft",
            "elastic",
            (0.5, 0.5),
            5.0,
            "elastic, k = 100 N/m, theta = 0.5 rad, static lengths, 5 s",
            {"k1": 100.0, "k2": 100.0},
        ),
        _stiff(1e4, "rest-length"),
        _stiff(1e4, "quasi-static"),
        _stiff(1e6, "rest-length"),
        _stiff(1e6, "quasi-static"),
    )
}


def get_cases(names: list[str] | tuple[str, ...] | None = None) -> list[Case]:
    """Cases by name (all when None); raises ValueError naming unknown ones."""
    if names is None:
        return list(CASES.values())
    unknown = [n for n in names if n not in CASES]
    if unknown:
        raise ValueError(f"unknown case(s) {unknown}; expected some of {list(CASES)}")
    return [CASES[n] for n in names]

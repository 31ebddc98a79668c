"""The record of a stability run (``pendulab bench stability``): the map classes and :class:`StabilityResult`.

Shared by the study (:mod:`pendulab.bench.stability`) and its CSVs and charts
(:mod:`pendulab.bench.stability_report`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["StabilityResult", "POSITION_TOL", "UNSTABLE", "INACCURATE", "ACCURATE", "FAILED"]

POSITION_TOL = 1e-3  # [m] bob-position error that counts as accurate
UNSTABLE, INACCURATE, ACCURATE = 0, 1, 2
FAILED = -1  # a map cell whose run raised (recorded with its reason in StabilityResult.failures)
_HORIZON = 1.0


@dataclass
class StabilityResult:
    """Everything ``pendulab bench stability`` measured.

    Attributes
    ----------
    ks : ndarray, shape (nk,)
        Spring stiffnesses [N/m] of the map.
    n_steps : ndarray, shape (nh,)
        Steps over the 1 s horizon; h = 1 / n_steps [s] (see ``hs``).
    omega_max : ndarray, shape (nk,)
        Fastest linearized mode per k [rad/s].
    maps : dict of str to ndarray
        Method -> classes, shape (nk, nh) (``UNSTABLE``, ``INACCURATE``, ``ACCURATE``).
    errors : dict of str to ndarray
        Method -> bob-position errors [m], shape (nk, nh).
    blowup : list of (float, float, float)
        (k [N/m], measured, predicted RK4 blow-up step [s]).
    step_counts : list of dict
        ``k``, ``start``, ``method`` and accepted ``steps`` over 1 s.
    energy : dict of str to (ndarray, ndarray)
        Label -> (t [s], E(t) - E(0) [J]) of the energy study.
    failures : list of dict
        Units that raised: ``unit`` (journal key) and ``reason``.
    """

    ks: np.ndarray
    n_steps: np.ndarray  # steps over the 1 s horizon; h = 1 / n_steps
    omega_max: np.ndarray  # per k [rad/s]
    maps: dict[str, np.ndarray] = field(default_factory=dict)  # method -> (len(ks), len(n_steps)) classes
    errors: dict[str, np.ndarray] = field(default_factory=dict)
    blowup: list[tuple[float, float, float]] = field(default_factory=list)  # (k, h_measured, h_predicted)
    step_counts: list[dict[str, Any]] = field(default_factory=list)
    energy: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)  # label -> (t, E - E0)
    failures: list[dict[str, str]] = field(default_factory=list)  # {"unit": key, "reason": ...}

    @property
    def hs(self) -> np.ndarray:
        return _HORIZON / self.n_steps

    def summary(self) -> dict[str, Any]:
        """JSON-friendly summary of the blow-up, step-count and energy studies.

        Returns
        -------
        dict
            ``rk4_blowup`` (k, measured and predicted step [s], relative
            difference), ``step_counts``, and ``energy_change_J``: the final
            energy change [J] per run, and ``failures`` (units that raised, with the reason).
        """
        return {
            "rk4_blowup": [
                {"k": k, "h_measured": hm, "h_predicted": hp, "relative_difference": hm / hp - 1} for k, hm, hp in self.blowup
            ],
            "step_counts": self.step_counts,
            "energy_change_J": {lab: float(dE[-1]) for lab, (_, dE) in self.energy.items()},
            "failures": self.failures,
        }

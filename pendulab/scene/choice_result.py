"""What the a priori model rule (:func:`pendulab.scene.choice.choose_model`) returns.

The per-level predictions, the choice and its verification, with their JSON and table forms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..integrate.trajectory import Trajectory
from .core import Scene
from .cost import LevelCost
from .levels import LinearSolution, ModelLevel, level_trajectory, levels_for

__all__ = ["LevelPrediction", "Verification", "ModelChoice"]


@dataclass(frozen=True)
class LevelPrediction:
    """The rule's prediction for one level.

    Attributes
    ----------
    name : str
        Level (one of :data:`pendulab.scene.levels.LEVELS`).
    error : float
        Predicted max abs error over the horizon and the outputs, against the
        scene's own model, in the outputs' units (0 for the reference; inf when the
        level cannot run the scene, e.g. no equilibrium to linearize about).
    horizon : float
        Time [s] up to which the predicted error stays within the tolerance
        (``t_final`` when throughout, 0 when never).
    within : bool
        ``error <= tolerance``.
    note : str
        Why (one line).
    cost : LevelCost or None
        Estimated cost of its run in this process, compilation still owed included
        (levels within tolerance only: the rule picks the cheapest of those).
    """

    name: str
    error: float
    horizon: float
    within: bool
    note: str = ""
    cost: LevelCost | None = None


@dataclass(frozen=True)
class Verification:
    """Predicted against measured: the chosen level and the reference, both run.

    Attributes
    ----------
    level : str
        The chosen level.
    predicted_error, measured_error : float
        Max abs error over the horizon and the outputs against the reference, in the outputs' units.
    predicted_horizon, measured_horizon : float
        Time [s] up to which the chosen level's error stays within the tolerance.
    within : bool
        ``measured_error <= tolerance``.
    level_time, reference_time : float
        Wall time [s] of the chosen level's run and of the reference's run.
    reference_error : float or None
        Max abs error of the reference at the scene's rtol against a run at ``rtol * 1e-3``
        (chaotic scenes only, else None), in the outputs' units.
    reference_horizon : float or None
        Measured time [s] up to which the reference stays within the tolerance of that tighter run.
    """

    level: str
    predicted_error: float
    measured_error: float
    predicted_horizon: float
    measured_horizon: float
    within: bool
    level_time: float
    reference_time: float
    reference_error: float | None = None
    reference_horizon: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (seconds in keys ending ``_s``).

        Returns
        -------
        dict
        """
        return {
            "level": self.level,
            "predicted_error": _finite(self.predicted_error),
            "measured_error": _finite(self.measured_error),
            "predicted_horizon_s": self.predicted_horizon,
            "measured_horizon_s": self.measured_horizon,
            "within_tolerance": self.within,
            "level_time_s": self.level_time,
            "reference_time_s": self.reference_time,
            "reference_error": _finite(self.reference_error),
            "reference_horizon_s": self.reference_horizon,
        }


@dataclass(frozen=True)
class ModelChoice:
    """Outcome of :func:`choose_model`.

    Attributes
    ----------
    scene : str
        Scene name.
    outputs : tuple of str
        Signals judged.
    tolerance : float
        Accepted max abs error of the outputs, in their units.
    t_final : float
        Scene horizon [s].
    chosen : str
        Level of least estimated cost (:mod:`pendulab.scene.cost`: compilation still owed in
        this process included) among those predicted within tolerance; the reference qualifies always.
    levels : tuple of LevelPrediction
        One per level in the hierarchy's order (fewest states first); the reference last.
    lyapunov : float
        Predicted largest Lyapunov exponent [1/s] (0: regular motion).
    energy_fraction : float
        Energy above the hanging rest over the potential energy from hanging to upright.
    frequency_ratio : float
        Lowest spring over highest pendular frequency w_s / w_p (inf for rigid links).
    reference_horizon : float
        Time [s] up to which the reference at the scene's rtol keeps the outputs within
        tolerance (predictability horizon; ``t_final`` when throughout).
    needed_rtol : float
        Integrator tolerance with which the reference would hold the whole horizon.
    trusted_until : float
        ``min`` of the chosen level's horizon and the reference's [s]: no model at this
        rtol and tolerance gives the outputs beyond it.
    verdict : str
        One line for the user.
    rule_time : float
        Wall time of the rule [s].
    verification : Verification or None
        With ``verify=True``.
    _linear : LinearSolution or None
        The linear solution the rule computed (reused by :meth:`simulate` when ``linearized`` is chosen).

    Examples
    --------
    >>> from pendulab.scene import choose_model, load_scene
    >>> scene = load_scene("stiff_moderate_amplitude")
    >>> choice = choose_model(scene)
    >>> for level in choice.levels:  # cheapest first, the reference (the scene's own model) last
    ...     print(level.name, level.within)
    linearized False
    rigid True
    rigid+quasi-static True
    elastic True
    >>> choice.chosen, choice.reference_horizon, choice.tolerance
    ('rigid', 5.0, 0.001)
    >>> traj = choice.simulate(scene)  # the scene run with the chosen level, in the elastic model's signals
    >>> traj.method, traj.x.shape
    ('rigid (cvodes)', (501, 8))
    """

    scene: str
    outputs: tuple[str, ...]
    tolerance: float
    t_final: float
    chosen: str
    levels: tuple[LevelPrediction, ...]
    lyapunov: float
    energy_fraction: float
    frequency_ratio: float
    reference_horizon: float
    needed_rtol: float
    trusted_until: float
    verdict: str
    rule_time: float
    verification: Verification | None = None
    _linear: LinearSolution | None = field(default=None, repr=False, compare=False)

    @property
    def level(self) -> str:
        """Alias of :attr:`chosen`."""
        return self.chosen

    def model_level(self, scene: Scene) -> ModelLevel:
        """The chosen :class:`~pendulab.scene.levels.ModelLevel` of ``scene``.

        Parameters
        ----------
        scene : Scene
            The scene the choice was made for.

        Returns
        -------
        ModelLevel
        """
        return next(lv for lv in levels_for(scene.model) if lv.name == self.chosen)

    def simulate(self, scene: Scene) -> Trajectory:
        """The scene's trajectory with the chosen level (the linear solution of the rule is reused).

        Parameters
        ----------
        scene : Scene
            The scene the choice was made for.

        Returns
        -------
        Trajectory
            In the scene model's signals (see :meth:`ModelLevel.simulate`).
        """
        if self.chosen == "linearized" and self._linear is not None:
            return level_trajectory(scene, self._linear.x, "linearized")
        return self.model_level(scene).simulate(scene)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form of the choice.

        Returns
        -------
        dict
            ``scene``, ``outputs``, ``tolerance``, ``t_final_s``, ``chosen``, ``levels`` (list of
            ``name``, ``predicted_error``, ``horizon_s``, ``within_tolerance``, ``note``),
            ``lyapunov_per_s``, ``energy_fraction``, ``frequency_ratio``, ``reference_horizon_s``,
            ``needed_rtol``, ``trusted_until_s``, ``verdict``, ``rule_time_s`` and ``verification``
            (None without ``verify``).
        """
        return {
            "scene": self.scene,
            "outputs": list(self.outputs),
            "tolerance": self.tolerance,
            "t_final_s": self.t_final,
            "chosen": self.chosen,
            "a_priori": True,
            "levels": [
                {
                    "name": lv.name,
                    "predicted_error": _finite(lv.error),
                    "horizon_s": lv.horizon,
                    "within_tolerance": lv.within,
                    "note": lv.note,
                    "estimated_cost": None
                    if lv.cost is None
                    else {
                        "method": lv.cost.method,
                        "preparation_s": lv.cost.preparation,
                        "integration_s": lv.cost.integration,
                        "note": lv.cost.note,
                    },
                }
                for lv in self.levels
            ],
            "lyapunov_per_s": _finite(self.lyapunov),
            "energy_fraction": self.energy_fraction,
            "frequency_ratio": self.frequency_ratio if math.isfinite(self.frequency_ratio) else None,
            "reference_horizon_s": self.reference_horizon,
            "needed_rtol": _finite(self.needed_rtol),
            "trusted_until_s": self.trusted_until,
            "verdict": self.verdict,
            "rule_time_s": self.rule_time,
            "verification": None if self.verification is None else self.verification.to_dict(),
            "missed": self.misses(),
        }

    def misses(self) -> list[str]:
        """The predictions the verification measured worse than predicted, one plain line each.

        Returns
        -------
        list of str
            Empty when nothing was verified or every prediction held; else what missed and by how much
            (the chosen level's error or horizon, the reference's horizon).
        """
        return [] if self.verification is None else _missed(self, self.verification)

    def table(self) -> str:
        """Plain-text table of the predictions (and the verification, if any).

        Returns
        -------
        str
        """
        v = self.verification
        ran = (
            "a priori prediction, then verified: the chosen level and the reference were run"
            if v is not None
            else "a priori prediction: no level and no reference were run"
        )
        lines = [
            f"scene {self.scene}: outputs {', '.join(self.outputs)}; tolerance {self.tolerance:g}; horizon {self.t_final:g} s"
            f" ({ran})",
            f"{'model':<20} {'predicted error':>15} {'valid until [s]':>16}  within  {'est. cost [s]':>13}",
        ]
        for lv in self.levels:
            cost = "" if lv.cost is None else f"{lv.cost.total:13.3g}"
            why = "; ".join(x for x in (lv.note, "" if lv.cost is None else _cost_note(lv.cost)) if x)
            lines.append(
                f"{lv.name:<20} {lv.error:>15.2e} {lv.horizon:>16.3g}  {'yes' if lv.within else 'no ':<6}  {cost:>13}"
                + (f"  ({why})" if why else "")
            )
        lines.append(
            f"chosen: {self.chosen} (least estimated cost within tolerance, compilation still owed included; "
            f"rule {self.rule_time * 1e3:.1f} ms)"
        )
        lines.append(self.verdict)
        if v is not None:
            lines.append(
                f"verify: {v.level} measured error {v.measured_error:.2e} (predicted {v.predicted_error:.2e}), "
                f"valid until {v.measured_horizon:.3g} s (predicted {v.predicted_horizon:.3g} s); "
                f"{'within' if v.within else 'NOT within'} tolerance; "
                f"one run {v.level_time:.3g} s vs reference {v.reference_time:.3g} s (a first run includes any compilation)"
            )
            if v.reference_horizon is not None:
                lines.append(
                    f"verify: the reference at its rtol is off a 1000x tighter run by {v.reference_error:.2e}, "
                    f"valid until {v.reference_horizon:.3g} s (predicted {self.reference_horizon:.3g} s)"
                )
            lines += _misses(self, v)
        return "\n".join(lines)


def _cost_note(cost: LevelCost) -> str:
    prep = f" + {cost.preparation:.2g} s {cost.note}" if cost.preparation > 0 else ""
    return f"{cost.method}: {cost.integration:.2g} s{prep}"


def _misses(choice: ModelChoice, v: Verification) -> list[str]:
    """Plain lines for every prediction the verification measured worse than predicted."""
    return choice.misses() or ["verify: every prediction held (measured error and horizons at least as good as predicted)"]


def _missed(choice: ModelChoice, v: Verification) -> list[str]:
    out = []
    if v.measured_error > v.predicted_error:
        out.append(
            f"verify: prediction MISSED: {v.level}'s measured error {v.measured_error:.2e} exceeds the predicted "
            f"{v.predicted_error:.2e}" + (f" ({v.measured_error / v.predicted_error:.3g}x)" if v.predicted_error > 0 else "")
        )
    if v.measured_horizon < v.predicted_horizon:
        out.append(
            f"verify: prediction MISSED: {v.level} holds the tolerance until {v.measured_horizon:.3g} s, not the predicted "
            f"{v.predicted_horizon:.3g} s ({v.predicted_horizon - v.measured_horizon:.3g} s short)"
        )
    if v.reference_horizon is not None and v.reference_horizon < choice.reference_horizon:
        out.append(
            f"verify: prediction MISSED: the reference holds until {v.reference_horizon:.3g} s, not the predicted "
            f"{choice.reference_horizon:.3g} s ({choice.reference_horizon - v.reference_horizon:.3g} s short)"
        )
    return out


def _finite(x: float | None) -> float | None:
    """``x``, or None when it is not finite (strict JSON has no NaN / Infinity)."""
    return None if x is None or not math.isfinite(x) else float(x)

"""Which model to plan an elastic swing-up on, and a plan proven on the full elastic dynamics.

Model no more than the task needs (DESIGN.md, principle 4) - the rule of the
scene hierarchy (:mod:`pendulab.bench.hierarchy`), restated here because
``control`` may not import ``bench``: *the cheapest model whose error is within
the tolerance wins; the full elastic model is the reference and always
qualifies.* Levels, cheapest first:

``rigid``
    Plan on the rigid point-mass counterpart; the springs are taken as rigid
    links (r = L, v = 0).
``rigid+quasi-static``
    Plan on the rigid counterpart; the springs follow at their quasi-static
    lengths r*(theta, omega, u) (:func:`pendulab.model.quasistatic.quasi_static_lengths`:
    gravity, centrifugal and torque load, zero radial acceleration), v = dr*/dt.
``elastic``
    Plan on the full elastic model, warm-started from the quasi-static lift of
    the rigid plan. p-refinement first: the lowest collocation degree (from the
    task's up to :data:`ELASTIC_DEGREE`) that resolves the fastest spring mode
    on the task's N intervals, else :data:`ELASTIC_DEGREE` on a uniform mesh
    fine enough for it (:func:`pendulab.control.swingup.mesh.oscillation_mesh`:
    Radau of degree d follows an undamped mode within 1e-3 per interval up to
    ``h w`` = 1.41, 2.54, 3.83, 5.2, 6.7 for d = 3 ... 7), then h-refinement
    where the estimate still misses the tolerance. The warm start is the rigid plan
    re-solved on that mesh and degree (a coarse plan interpolated onto it cost
    the elastic NLP ~200 IPOPT iterations instead of ~20).

The error of a level is *predicted* from the modes (screening) and then
*measured* (the proof): the lifted plan is checked interval by interval on the
full elastic dynamics (:func:`pendulab.control.swingup.errors.estimate_error_arrays`).
A level that fails its proof hands over to the next one, so the decision never
rests on the prediction alone.

Prediction, with ``w_p`` the highest pendular and ``w_s`` the lowest spring
frequency (modes at hanging and upright, :func:`pendulab.analysis.modes.modes`)
and ``eps = w_p / w_s``:

* rigid: a spring not at its loaded length oscillates about it; the spring force
  of that oscillation is set by the load (not by k), and its effect on the
  angular rates over one interval averages out as ``1 / w_s``:
  error ~ ``C_RIGID * eps``;
* rigid+quasi-static: the lengths carry the load; what remains is the next
  order of the slow-manifold expansion: error ~ ``C_QUASI_STATIC * eps**2``.

The rigid plan is refined to half the tolerance, leaving the other half to
the modelling error of the lift. The constants bound the measured ratios on
``swingup_pendubot_elastic`` with springs of 1e3 ... 1e9 N/m (one rigid plan lifted;
benchmarks/results/swingup.md, "Planning rule"): rigid 1.1 ... 4.2, quasi-static
5 ... 14. They order the attempts; the proof decides.

Proofs use the error estimate's default normalisation (each state's largest
magnitude over the plan, the issue's metric); ``error_scale="bob-speed"``
judges the spring rates against the bobs' speed instead (the one definition is
in :mod:`.errors`). The constants above were fitted with the bob-speed scale:
under the default scale a quasi-statically lifted plan of very stiff springs
can fail its proof (each step of the held torque rings the springs with rates
far above the quasi-static ones) and the elastic level takes over.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._inputs import checked
from ...analysis.model_error import C_QUASI_STATIC, C_RIGID, mode_ratio_errors
from ...analysis.modes import modes
from ...model.model import Model
from .errors import ErrorEstimate, estimate_error_arrays

__all__ = [
    "PLANNING",
    "LEVELS",
    "C_RIGID",
    "C_QUASI_STATIC",
    "ELASTIC_DEGREE",
    "PlanningDecision",
    "planning_rule",
    "elastic_error",
    "fastest_spring_frequency",
]

#: Planning choices accepted in task files and by :func:`plan` (``quasi-static`` = ``rigid+quasi-static``).
PLANNING: tuple[str, ...] = ("auto", "rigid", "quasi-static", "elastic")
#: Planning levels, cheapest first.
LEVELS: tuple[str, ...] = ("rigid", "rigid+quasi-static", "elastic")
#: Highest collocation degree of the elastic level's p-refinement (beyond it, more intervals).
ELASTIC_DEGREE = 7
_LEVEL_OF = {"rigid": "rigid", "quasi-static": "rigid+quasi-static", "elastic": "elastic"}


@dataclass(frozen=True)
class PlanningDecision:
    """The planning-model rule applied to one elastic model.

    Attributes
    ----------
    requested : str
        What was asked (one of :data:`PLANNING`).
    chosen : str
        Level the rule starts from (one of :data:`LEVELS`; always ``rigid`` for a rigid model).
    pendular_frequency : float
        Highest pendular abs(lambda) at hanging and upright [rad/s].
    spring_frequency : float
        Lowest spring-mode frequency at hanging and upright [rad/s] (inf for a rigid model).
    predicted : dict of str to float
        Predicted relative error of each level on the elastic dynamics (dimensionless).
    tolerance : float
        Relative tolerance (dimensionless).
    reason : str
        One line: why this level.

    Examples
    --------
    >>> from pendulab.control import planning_rule
    >>> from pendulab.control.swingup.tasks import load_task
    >>> d = planning_rule(load_task("pendubot_elastic").model)  # a PlanningDecision; springs of 25 kN/m
    >>> round(d.pendular_frequency, 1), round(d.spring_frequency, 1), round(d.separation, 1)  # [rad/s], ratio
    (12.6, 126.4, 10.0)
    >>> {level: round(err, 2) for level, err in d.predicted.items()}  # predicted relative error of each level
    {'rigid': 0.4, 'rigid+quasi-static': 0.15, 'elastic': 0.0}
    >>> d.chosen
    'elastic'
    >>> print(d.reason)
    springs 10x faster than the pendulum (w_s = 126.4, w_p = 12.64 rad/s): no cheaper model predicted
    within tolerance 1.0e-03 (rigid 0.4, rigid+quasi-static 0.15)
    """

    requested: str
    chosen: str
    pendular_frequency: float
    spring_frequency: float
    predicted: dict[str, float]
    tolerance: float
    reason: str

    @property
    def separation(self) -> float:
        """Frequency ratio ``spring_frequency / pendular_frequency`` (inf for a rigid model)."""
        return self.spring_frequency / self.pendular_frequency


def _frequencies(model: Model) -> tuple[float, float]:
    """Highest pendular abs(lambda) and lowest spring frequency [rad/s] at hanging and upright."""
    pend, spring = 0.0, math.inf
    for at in ("down-down", "up-up"):
        for md in modes(model, at):
            if md.spring_share >= 0.5 and md.kind == "oscillatory":
                spring = min(spring, md.omega_n)
            elif md.spring_share < 0.5:
                pend = max(pend, md.omega_n)
    return pend, spring


def fastest_spring_frequency(model: Model) -> float:
    """Highest spring-mode frequency at hanging and upright (0 without springs).

    Parameters
    ----------
    model : Model
        Rigid or elastic model.

    Returns
    -------
    float
        [rad/s].
    """
    return max(
        (md.omega_n for at in ("down-down", "up-up") for md in modes(model, at) if md.spring_share >= 0.5),
        default=0.0,
    )


def _check_tolerance(tolerance: Any) -> float:
    try:
        tol = float(tolerance)
    except (TypeError, ValueError):
        raise TypeError(f"tolerance must be a number (relative defect), got {type(tolerance).__name__}") from None
    if not (math.isfinite(tol) and tol > 0.0):
        raise ValueError(f"tolerance must be a positive finite relative defect, got {tolerance!r}")
    return tol


@checked()
def planning_rule(model: Model, tolerance: float = 1e-3, planning: str = "auto") -> PlanningDecision:
    """Pick the cheapest planning model predicted to meet ``tolerance`` on the elastic dynamics.

    Parameters
    ----------
    model : Model
        The task's model (elastic; a rigid model is planned on as it is).
    tolerance : float
        Relative defect the plan must meet on the full dynamics (dimensionless, > 0).
    planning : {"auto", "rigid", "quasi-static", "elastic"}
        ``auto`` applies the rule; the others force a starting level (the proof
        still runs, and a failed level still hands over to the next one).

    Returns
    -------
    PlanningDecision
        The starting level, the frequencies and the predicted errors.

    Raises
    ------
    TypeError
        ``model`` is not a Model or ``tolerance`` is not a number.
    ValueError
        Unknown ``planning`` name or a non-positive tolerance.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import planning_rule
    >>> d = planning_rule(pl.elastic(k1=1e7, k2=1e7), tolerance=1e-3)
    >>> d.chosen, f"{d.spring_frequency:.0f} rad/s"
    ('rigid+quasi-static', '1954 rad/s')
    >>> planning_rule(pl.elastic(), tolerance=1e-3).chosen  # soft 500 N/m springs: plan on the full model
    'elastic'
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    if planning not in PLANNING:
        raise ValueError(f"planning must be one of {list(PLANNING)}, got {planning!r}")
    tol = _check_tolerance(tolerance)
    if model.kind != "elastic":
        pend, _ = _frequencies(model)
        return PlanningDecision(planning, "rigid", pend, math.inf, {}, tol, "rigid model: planned on as it is")
    pend, spring = _frequencies(model)
    predicted = mode_ratio_errors(pend, spring)  # the one definition, shared with the scenes' a priori rule
    if planning != "auto":
        chosen = _LEVEL_OF[planning]
        reason = f"requested {planning!r}"
    else:
        chosen = next(level for level in LEVELS if predicted[level] <= tol)
        head = f"springs {spring / pend:.3g}x faster than the pendulum (w_s = {spring:.4g}, w_p = {pend:.4g} rad/s): "
        cheaper = ", ".join(f"{k} {predicted[k]:.2g}" for k in LEVELS[: LEVELS.index(chosen)])
        if chosen == "elastic":
            reason = head + f"no cheaper model predicted within tolerance {tol:.1e} ({cheaper})"
        else:
            reason = head + f"{chosen} predicted {predicted[chosen]:.2g} <= tolerance {tol:.1e}"
            reason += f" ({cheaper})" if cheaper else ""
    return PlanningDecision(planning, chosen, pend, spring, predicted, tol, reason)


def elastic_error(model: Model, t: np.ndarray, x: np.ndarray, u: np.ndarray, tolerance: float = 1e-3) -> ErrorEstimate:
    """Error estimate of a plan on ``model`` with spring rates judged against the bob speed.

    Parameters
    ----------
    model : Model
        Model the plan must satisfy (rigid models: the plain estimate).
    t : ndarray, shape (N + 1,)
        Grid [s].
    x : ndarray, shape (N + 1, nx)
        States on the grid.
    u : ndarray, shape (N, 2)
        Held torques [N.m].
    tolerance : float
        Relative tolerance of the verdict.

    Returns
    -------
    ErrorEstimate
        :func:`estimate_error_arrays` with ``scale="bob-speed"`` (the definition lives there).

    Raises
    ------
    ValueError
        Bad shapes or values (from :func:`estimate_error_arrays`).
    """
    return estimate_error_arrays(model, t, x, u, tolerance=tolerance, scale="bob-speed")

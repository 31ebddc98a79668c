"""The a priori model rule of a scene: the cheapest level predicted within tolerance, and its horizon of validity.

:func:`choose_model` predicts, *without running the reference*, the error of
every level of the hierarchy (:mod:`pendulab.scene.levels`) on the scene's
outputs over its horizon, and picks the cheapest level predicted within the
scene's tolerance (the scene's own model always qualifies). Predictions
(constants in :mod:`pendulab.scene.prediction`, calibrated by ``benchmarks/bench_model_choice.py``;
``docs/model_choice.md``):

``linearized``
    Amplitude screen first (a pendulum of amplitude A runs slow by A^2 / 16:
    ``A^2 sum_j A_j w_j T / 16``); past ``SCREEN`` x tolerance it is hopeless.
    Else the linear solution is computed (it is the level's run, kept for
    reuse) and the neglected nonlinear terms along it,
    ``r(t) = f(x_lin, u) - A (x_lin - x_eq) - b``, are propagated through the
    linear dynamics (first-order perturbation, exact zero-order hold in the
    modal basis on at most ``RESIDUAL_POINTS`` times) and mapped to the
    outputs through the output Jacobian: ``C_LINEAR * |C| |e(t)|``.
``rigid``, ``rigid+quasi-static``
    From the spring-to-pendulum frequency ratio and the load, as the swing-up
    planning rule (:mod:`pendulab.analysis.model_error`): each spring stretches by
    ``delta_i = T_i / k_i`` under gravity and, growing over the first quarter
    period, the centrifugal load of the energy above rest; a start off the
    quasi-static lengths rings the spring by ``dR_i``. The relative length error
    ``nu = sum (delta_i + dR_i eps) / L_i`` (``eps = w_p / w_s``) makes a phase
    error that grows secularly and, over chaotic motion, like ``e^(lambda_1 t)``:
    angle error ``nu (sum_j C_j A_j w_j t / 2 + C_CHAOS expm1(lambda_1 t))`` with
    the start's modal amplitudes ``A_j`` (``C_SLOW`` for the in-phase, ``C_FAST``
    for the anti-phase mode). Position outputs add the spring-length error
    itself: ``delta_i + dR_i`` for rigid links, ``dR_i + delta_i eps^2`` with
    quasi-static lengths.
reference
    The scene's own model at its ``rtol``: ``C_REFERENCE * max(rtol, atol) *
    (1 + w_p t + expm1(lambda_1 t))``.

``lambda_1`` comes from the energy above the hanging rest and the stiffness
(:func:`pendulab.analysis.model_error.lyapunov_exponent`). The horizon of
validity of a level is the first time its predicted error exceeds the tolerance;
for the reference it is the predictability horizon at the scene's ``rtol``, and
``needed_rtol`` is the integrator tolerance that would hold the whole horizon.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._checks import positive_float
from ..analysis.model_error import validity_horizon
from ..integrate import time_grid
from ..integrate.trajectory import Trajectory
from .core import Scene
from .levels import LinearSolution, ModelLevel, level_trajectory, levels_for, linear_solution, scene_signals
from .prediction import (
    DOUBLE_PRECISION_RTOL,
    SCREEN,
    _features,
    _linear_curve,
    _output_gains,
    _reduced_curve,
    _reference_curve,
)

__all__ = [
    "LevelPrediction",
    "Verification",
    "ModelChoice",
    "choose_model",
    "error_curve",
]


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
        level cannot run the scene, e.g. a sine input for ``linearized``).
    horizon : float
        Time [s] up to which the predicted error stays within the tolerance
        (``t_final`` when throughout, 0 when never).
    within : bool
        ``error <= tolerance``.
    note : str
        Why (one line).
    """

    name: str
    error: float
    horizon: float
    within: bool
    note: str = ""


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
        Cheapest level predicted within tolerance (the reference when none is).
    levels : tuple of LevelPrediction
        One per level, cheapest first; the reference last.
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
        }

    def table(self) -> str:
        """Plain-text table of the predictions (and the verification, if any).

        Returns
        -------
        str
        """
        lines = [
            f"scene {self.scene}: outputs {', '.join(self.outputs)}; tolerance {self.tolerance:g}; horizon {self.t_final:g} s"
            f" (a priori, reference not run)",
            f"{'model':<20} {'predicted error':>15} {'valid until [s]':>16}  within",
        ]
        for lv in self.levels:
            lines.append(
                f"{lv.name:<20} {lv.error:>15.2e} {lv.horizon:>16.3g}  {'yes' if lv.within else 'no '}"
                + (f"  ({lv.note})" if lv.note else "")
            )
        lines.append(f"chosen: {self.chosen} (cheapest predicted within tolerance; rule {self.rule_time * 1e3:.1f} ms)")
        lines.append(self.verdict)
        v = self.verification
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
        return "\n".join(lines)


def choose_model(
    scene: Scene,
    *,
    tolerance: float | None = None,
    verify: bool = False,
) -> ModelChoice:
    """Pick the cheapest model level predicted to keep the scene's outputs within tolerance, without running the reference.

    Parameters
    ----------
    scene : Scene
        A loaded scene (:func:`pendulab.scene.load_scene`).
    tolerance : float, optional
        Accepted max abs error of the outputs, in their units; default the scene's
        ``[outputs] tolerance``.
    verify : bool
        Also run the chosen level and the reference (and, on a chaotic scene, the
        reference at ``rtol * 1e-3``) and report predicted against measured error
        (:attr:`ModelChoice.verification`).

    Returns
    -------
    ModelChoice
        The chosen level, every level's predicted error and horizon of validity, the
        reference's predictability horizon and the tolerance it would need.

    Raises
    ------
    TypeError
        ``scene`` is not a :class:`Scene`.
    ValueError
        No tolerance (neither given nor in the scene), or not a positive number.
    SimulationError
        With ``verify``: the reference or the chosen level failed to integrate.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a pendulab Scene (pendulab.scene.load_scene), got {type(scene).__name__}")
    tol = scene.tolerance if tolerance is None else tolerance
    if tol is None:
        raise ValueError(f"scene {scene.name!r}: tolerance is missing: state [outputs] tolerance in the scene or pass tolerance=")
    tol = positive_float("tolerance", tol, "(max abs error of the outputs, in their units)")
    if not isinstance(verify, bool):
        raise TypeError(f"verify must be True or False, got {verify!r}")
    start = time.perf_counter()
    f = _features(scene)
    t_grid = time_grid(scene.t_final, scene.dt)
    t_pred = np.linspace(0.0, scene.t_final, 201)
    preds: list[LevelPrediction] = []
    lin = None
    gain = max((g for g, _ in _output_gains(scene, f).values()), default=1.0)
    # Screen: a pendulum of amplitude A runs slow by A^2 / 16 of its frequency; past SCREEN x tolerance
    # the linearization is hopeless and its residual is not worth computing.
    screen = max(gain, 1.0) * f.amplitude**2 * f.phase_sum * t_pred / 16
    if getattr(scene, "u_amplitude", None) is not None:
        preds.append(LevelPrediction("linearized", math.inf, 0.0, False, "cannot run: sine input (constant torques only)"))
    elif screen[-1] > SCREEN * tol:
        note = f"screened: amplitude {f.amplitude:.2g} rad, A^2 sum(A_j w_j) T / 16 = {screen[-1]:.2g} > {SCREEN:g} x tolerance"
        preds.append(_prediction("linearized", t_pred, screen, tol, note))
    else:
        try:
            lin = linear_solution(scene)
            t_lin, e_lin = _linear_curve(scene, lin, t_grid)
            if not np.all(np.isfinite(lin.x)):
                e_lin = np.full_like(t_lin, np.inf)
            preds.append(_prediction("linearized", t_lin, e_lin, tol, "neglected nonlinear terms along the linear solution"))
        except RuntimeError as exc:
            preds.append(LevelPrediction("linearized", math.inf, 0.0, False, f"cannot run: {str(exc).splitlines()[0]}"))
    if scene.model.kind == "elastic":
        eps = f.w_p / f.w_s
        for name, qs in (("rigid", False), ("rigid+quasi-static", True)):
            e = _reduced_curve(scene, f, t_pred, qs)
            note = f"w_s/w_p = {1 / eps:.3g}, stretch {np.sum(f.stretch):.2g} m, ring {np.sum(f.ring):.2g} m"
            preds.append(_prediction(name, t_pred, e, tol, note))
    rtol = max(scene.rtol, scene.atol)
    e_ref = _reference_curve(scene, f, t_pred, rtol)
    ref_h = validity_horizon(t_pred, e_ref, tol)
    needed = rtol * tol / float(e_ref[-1])
    ref_name = "elastic" if scene.model.kind == "elastic" else "rigid"
    preds.append(LevelPrediction(ref_name, 0.0, scene.t_final, True, "reference (the scene's own model)"))
    chosen = next(p for p in preds if p.within)
    trusted = min(chosen.horizon if chosen.name != ref_name else scene.t_final, ref_h)
    if ref_h >= scene.t_final:
        verdict = f"the reference at rtol {rtol:g} holds the whole horizon ({scene.t_final:g} s)"
    elif needed >= DOUBLE_PRECISION_RTOL:
        verdict = (
            f"chaotic (lambda_1 ~ {f.lam:.2g} /s): at rtol {rtol:g} no model keeps the outputs within {tol:g} past "
            f"~{ref_h:.3g} s; the whole {scene.t_final:g} s needs rtol <= {needed:.1e}"
        )
    else:
        verdict = (
            f"chaotic (lambda_1 ~ {f.lam:.2g} /s): no model keeps the outputs within {tol:g} past ~{ref_h:.3g} s at rtol "
            f"{rtol:g}; the whole {scene.t_final:g} s would need rtol {needed:.1e}, beyond double precision"
        )
    rule_time = time.perf_counter() - start
    choice = ModelChoice(
        scene.name,
        tuple(scene.outputs),
        tol,
        float(scene.t_final),
        chosen.name,
        tuple(preds),
        f.lam,
        f.energy_fraction,
        f.w_s / f.w_p,
        ref_h,
        needed,
        trusted,
        verdict,
        rule_time,
        None,
        lin,
    )
    if not verify:
        return choice
    return _verified(scene, choice)


def _finite(x: float | None) -> float | None:
    """``x``, or None when it is not finite (strict JSON has no NaN / Infinity)."""
    return None if x is None or not math.isfinite(x) else float(x)


def _prediction(name: str, t: np.ndarray, e: np.ndarray, tol: float, note: str) -> LevelPrediction:
    err = float(np.max(e)) if len(e) else math.inf
    if not math.isfinite(err):
        err = math.inf
    return LevelPrediction(name, err, validity_horizon(t, e, tol), err <= tol, note)


def error_curve(scene: Scene, X: np.ndarray, ref: dict[str, np.ndarray]) -> np.ndarray:
    """Max abs error over the scene's outputs at each grid time, of states ``X`` against the reference signals ``ref``.

    Parameters
    ----------
    scene : Scene
        The scene (its outputs).
    X : ndarray, shape (N, nx)
        States of a level on the scene's grid.
    ref : dict of str to ndarray, shape (N,)
        The reference's outputs (:func:`pendulab.scene.levels.scene_signals`).

    Returns
    -------
    ndarray, shape (N,)
        In the outputs' units; inf everywhere when ``X`` is not finite.
    """
    if not np.all(np.isfinite(X)):
        return np.full(X.shape[0], np.inf)
    sig = scene_signals(scene, X)
    return np.max(np.vstack([np.abs(sig[n] - ref[n]) for n in scene.outputs]), axis=0)


def _verified(scene: Scene, choice: ModelChoice) -> ModelChoice:
    import dataclasses

    t = time_grid(scene.t_final, scene.dt)
    levels = {lv.name: lv for lv in levels_for(scene.model)}
    ref_level = list(levels.values())[-1]
    t0 = time.perf_counter()
    X_ref = ref_level.run(scene)
    t_ref = time.perf_counter() - t0
    ref = scene_signals(scene, X_ref)
    t0 = time.perf_counter()
    X = X_ref if choice.chosen == ref_level.name else levels[choice.chosen].run(scene)
    t_level = time.perf_counter() - t0 if choice.chosen != ref_level.name else t_ref
    e = error_curve(scene, X, ref)
    pred = next(p for p in choice.levels if p.name == choice.chosen)
    ref_err = ref_h = None
    if choice.reference_horizon < scene.t_final or choice.lyapunov > 0.1:
        from ..integrate import simulate

        tight = max(scene.rtol * 1e-3, DOUBLE_PRECISION_RTOL)
        X_t = simulate(
            scene.model, scene.x0, scene.t_final, scene.dt, scene.method, tight, max(scene.atol * 1e-3, 1e-16), scene.input_spec()
        ).x
        e_ref = error_curve(scene, X_ref, scene_signals(scene, X_t))
        ref_err, ref_h = float(np.max(e_ref)), validity_horizon(t, e_ref, choice.tolerance)
    v = Verification(
        choice.chosen,
        pred.error,
        float(np.max(e)),
        pred.horizon,
        validity_horizon(t, e, choice.tolerance),
        bool(np.max(e) <= choice.tolerance),
        t_level,
        t_ref,
        ref_err,
        ref_h,
    )
    return dataclasses.replace(choice, verification=v)

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
    reuse; a sine input is held exactly as the reference holds it) and the neglected nonlinear terms along it,
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
    for the anti-phase mode), seen through the envelope ``min(1, s0 + w_slow t)``
    of a mode started at rest (``s0``: kinetic share of the start). The stretch
    grows from the start's own load to the largest over a quarter of the slow
    period, lengthened by ``2 K(sin^2(A / 2)) / pi`` for the amplitude. Position outputs add the spring-length error
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

import dataclasses
import math
import time

import numpy as np

from .._checks import positive_float
from .._inputs import checked
from ..analysis.model_error import validity_horizon
from ..integrate import time_grid
from .choice_result import LevelPrediction, ModelChoice, Verification
from .choice_verify import _verified, error_curve
from .core import Scene
from .cost import level_cost
from .levels import linear_solution
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


#: Fastest spring mode the a priori rule models [rad/s]: beyond, the modal analysis and the spring terms of
#: the error bounds lose every digit in double precision (k / m = 1e12 1/s^2).
MAX_SPRING_RATE: float = 1e6


def check_rule_domain(scene: Scene) -> None:
    """Refuse a scene the a priori rule was not built for, before any work.

    The rule predicts errors from the linear modes about the hanging equilibrium: it needs gravity
    (``g > 0``: without it there is no restoring pendular mode, and the energy scale of a swing is
    zero) and springs whose modes double precision still resolves (``sqrt(k / m)`` at most
    :data:`MAX_SPRING_RATE`).

    Parameters
    ----------
    scene : Scene
        The scene.

    Raises
    ------
    ValueError
        Outside that domain; the message names the parameter and says what to run instead.
    """
    p = scene.model.params
    where = f"scene {scene.name!r}"
    if not p.g > 0.0:
        raise ValueError(
            f"{where}: g = {p.g!r}; the a priori rule predicts from the pendular modes about hanging and needs g > 0 "
            "(use `scene check --measure`, which runs every level)"
        )
    if scene.model.kind == "elastic":
        rate = max(math.sqrt(p.k1 / p.m1), math.sqrt(p.k2 / p.m2))
        if not rate <= MAX_SPRING_RATE:
            raise ValueError(
                f"{where}: springs k1 = {p.k1!r}, k2 = {p.k2!r} N/m ring at {rate:.3g} rad/s, beyond the {MAX_SPRING_RATE:g} "
                "rad/s the rule resolves in double precision (and beyond what an elastic model of a pendulum means: "
                "use the rigid model)"
            )


@checked()
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
        No tolerance (neither given nor in the scene), or not a positive number; a scene outside
        the rule's domain (:func:`check_rule_domain`).
    SimulationError
        With ``verify``: the reference or the chosen level failed to integrate.

    Examples
    --------
    >>> from pendulab.scene import choose_model, load_scene
    >>> scene = load_scene("stiff_moderate_amplitude")  # k = 1e6 N/m, 1 rad release, 5 s, tolerance 1e-3
    >>> choice = choose_model(scene)  # decided a priori: nothing is integrated
    >>> choice.chosen, choice.trusted_until
    ('rigid', 5.0)
    >>> proof = choose_model(scene, verify=True).verification  # runs the rigid level and the elastic reference
    >>> proof.level, proof.within, bool(proof.measured_error < 1e-3)
    ('rigid', True, True)
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a pendulab Scene (pendulab.scene.load_scene), got {type(scene).__name__}")
    tol = scene.tolerance if tolerance is None else tolerance
    if tol is None:
        raise ValueError(f"scene {scene.name!r}: tolerance is missing: state [outputs] tolerance in the scene or pass tolerance=")
    tol = positive_float("tolerance", tol, "(max abs error of the outputs, in their units)")
    if not isinstance(verify, bool):
        raise TypeError(f"verify must be True or False, got {verify!r}")
    check_rule_domain(scene)
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
    if screen[-1] > SCREEN * tol:
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
    # Cheapest by the estimated cost in this process (compilation still owed included), not by the hierarchy's
    # order: the first level within tolerance wins a tie (stable sort).
    preds = [dataclasses.replace(p, cost=level_cost(scene, p.name)) if p.within else p for p in preds]
    chosen = min((p for p in preds if p.within), key=lambda p: p.cost.total)
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


def _prediction(name: str, t: np.ndarray, e: np.ndarray, tol: float, note: str) -> LevelPrediction:
    err = float(np.max(e)) if len(e) else math.inf
    if not math.isfinite(err):
        err = math.inf
    return LevelPrediction(name, err, validity_horizon(t, e, tol), err <= tol, note)

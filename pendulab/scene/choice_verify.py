"""Verification of the a priori model rule: run the chosen level and the reference, and measure the error the rule predicted."""

from __future__ import annotations

import time

import numpy as np

from ..analysis.model_error import validity_horizon
from ..integrate import time_grid
from .choice_result import ModelChoice, Verification
from .core import Scene
from .levels import levels_for, scene_signals
from .prediction import DOUBLE_PRECISION_RTOL

__all__ = ["error_curve"]


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

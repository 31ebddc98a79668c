"""Equal-energy initial states for Lyapunov studies: :func:`energy_matched_state` and :func:`energy_matched_states`.

See the section "Equal-energy initial states" of :mod:`pendulab.ensemble.lyapunov`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.optimize import brentq

from .._checks import bounded_int, check_model
from .._inputs import checked
from ..model.model import Model
from ..model.quasistatic import quasi_static_lengths
from ..model.statics import static_spring_lengths

__all__ = ["SPRING_STARTS", "energy_matched_state", "energy_matched_states"]

#: Spring-length choices of the energy-matched initial states.
SPRING_STARTS: tuple[str, ...] = ("quasi-static", "static")


# -- energy-matched initial states ------------------------------------------------------
def _springs_at(model: Model, theta: np.ndarray, omega: np.ndarray, springs: str) -> np.ndarray:
    if springs == "static":
        return static_spring_lengths(model.params, theta)
    return quasi_static_lengths(model, theta, omega)


def _state_at(model: Model, theta: np.ndarray, omega: np.ndarray, springs: str) -> np.ndarray:
    if model.kind == "rigid":
        return np.concatenate([theta, omega])
    r = _springs_at(model, theta, omega, springs)
    return np.concatenate([theta, r, omega, np.zeros(2)])


@checked()
def energy_matched_state(model: Model, energy: float, theta: Any, direction: Any, *, springs: str = "quasi-static") -> np.ndarray:
    """A state at the angles ``theta`` whose total mechanical energy is ``energy``.

    The angular rates are ``s * direction / |direction|`` with the one ``s >= 0`` that
    gives ``model.energy(x) == energy``; for the elastic model the spring rates are zero
    and the spring lengths follow ``springs``.

    Parameters
    ----------
    model : Model
        Rigid or elastic model.
    energy : float
        Requested total energy [J] (kinetic + gravity + springs; zero at the pivot
        height with unstretched springs, as :meth:`Model.energy`).
    theta : array_like, shape (2,)
        Absolute link angles [rad].
    direction : array_like, shape (2,)
        Direction of the angular rates (omega1, omega2); its length does not matter.
    springs : {"quasi-static", "static"}
        Elastic model only: lengths with zero radial acceleration at the final rates
        (:func:`pendulab.model.quasistatic.quasi_static_lengths`; no fast spring
        oscillation is excited), or lengths carrying the along-link gravity load only
        (:func:`pendulab.model.statics.static_spring_lengths`).

    Returns
    -------
    ndarray, shape (nx,)
        State with ``|model.energy(x) - energy| <= 1e-12 max(1, |energy|)``.

    Raises
    ------
    ValueError
        Bad shapes or non-finite values, a zero ``direction``, an unknown ``springs``,
        or ``energy`` below the potential energy at ``theta`` (not reachable).
    RuntimeError
        No quasi-static spring lengths (springs too soft for the motion), or the energy
        could not be matched to the tolerance.
    """
    model = check_model(model)
    th = _pair("theta", theta)
    dv = _pair("direction", direction)
    nd = float(np.linalg.norm(dv))
    if nd == 0.0:
        raise ValueError("direction must be a non-zero (omega1, omega2) direction, got (0, 0)")
    dv = dv / nd
    if springs not in SPRING_STARTS:
        raise ValueError(f"springs must be one of {list(SPRING_STARTS)}, got {springs!r}")
    try:
        E = float(energy)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"energy must be a finite number [J], got {energy!r}") from exc
    if not math.isfinite(E):
        raise ValueError(f"energy must be a finite number [J], got {energy!r}")

    def excess(s: float) -> float:
        return float(model.energy(_state_at(model, th, s * dv, springs))) - E

    e0 = excess(0.0)
    if e0 > 0.0:
        raise ValueError(
            f"energy = {E!r} J is below the energy at rest at theta = {th.tolist()} rad ({e0 + E!r} J); "
            "choose angles with a lower potential energy"
        )
    tol = 1e-12 * max(1.0, abs(E))
    if model.kind == "rigid" or springs == "static":
        # Spring lengths independent of the rates: E(s) = E(0) + s**2 T(unit direction).
        t1 = excess(1.0) - e0
        s = math.sqrt(-e0 / t1)
    else:
        s_hi = math.sqrt(-e0 / max(excess(1.0) - e0, 1e-300))
        for _ in range(60):
            if excess(s_hi) > 0.0:
                break
            s_hi *= 2.0
        s = brentq(excess, 0.0, s_hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    x = _state_at(model, th, s * dv, springs)
    # One Newton polish along the rates (the kinetic energy is quadratic in them).
    err = float(model.energy(x)) - E
    if abs(err) > tol / 4 and s > 0.0:
        h = 1e-6 * s
        slope = (excess(s + h) - excess(s - h)) / (2 * h)
        s -= err / slope
        x = _state_at(model, th, s * dv, springs)
        err = float(model.energy(x)) - E
    if abs(err) > tol:
        raise RuntimeError(f"energy_matched_state: energy matched only to {err:.3g} J (tolerance {tol:.3g} J)")
    return model.check_state(x)


def _pair(name: str, value: Any) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be two numbers, got {value!r}") from exc
    if a.shape != (2,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be two finite numbers, got {value!r}")
    return a


@checked()
def energy_matched_states(
    models: Sequence[Model], energy: float, n: int, *, seed: int = 0, springs: str = "quasi-static"
) -> list[np.ndarray]:
    """Random states of equal energy, the same angles and rate directions for every model.

    Angles are drawn uniformly in [-pi, pi)^2 and rate directions uniformly on the
    circle (``numpy.random.default_rng(seed)``); a draw is kept when ``energy`` is above
    the rest energy at those angles for every model, so every model gets a state.

    Parameters
    ----------
    models : sequence of Model
        Models to start (rigid and/or elastic).
    energy : float
        Total energy [J] of every state (see :func:`energy_matched_state`).
    n : int
        Number of states per model, >= 1.
    seed : int, default 0
        Random seed.
    springs : {"quasi-static", "static"}
        Spring lengths of the elastic models (see :func:`energy_matched_state`).

    Returns
    -------
    list of ndarray, shape (n, nx) each
        ``out[j][i]`` is the i-th state of ``models[j]``.

    Raises
    ------
    ValueError
        ``n`` not a positive integer, an empty ``models``, or an ``energy`` below the
        potential energy of every angle tried (1000 n draws).
    """
    n = bounded_int("n", n, high=1_000_000, why="each state is found by a root search in Python")
    models = [check_model(m) for m in models]
    if not models:
        raise ValueError("models must contain at least one Model, got none")
    rng = np.random.default_rng(seed)
    out: list[list[np.ndarray]] = [[] for _ in models]
    tries = 0
    while len(out[0]) < n:
        tries += 1
        if tries > 1000 * n:
            raise ValueError(f"energy = {energy!r} J: found only {len(out[0])} of {n} reachable angle pairs in {tries - 1} draws")
        th = rng.uniform(-np.pi, np.pi, 2)
        phi = rng.uniform(0.0, 2 * np.pi)
        dv = np.array([np.cos(phi), np.sin(phi)])
        try:
            states = [energy_matched_state(m, energy, th, dv, springs=springs) for m in models]
        except ValueError:
            continue
        for j, x in enumerate(states):
            out[j].append(x)
    return [np.array(o) for o in out]

"""One robustness-v2 run: measurement (delay, noise), controller, applied torque (response, noise, clip, pulse), RK4 step."""

from __future__ import annotations

import math
import statistics
import time
from typing import Any

import numpy as np

from ...control.feedback import SampledController, full_input
from ...control.realai.spec import DT, TORQUE_LIMIT
from ...model.plant_file import IdentifiedPlant
from ...model.robot import robot_params_vector
from .plant import actuated_joint, protocol_params, protocol_rhs_python, vary
from .robustness_grid import CATEGORIES, DRAWS_PER_STEP, EPSILON, GOAL, RunSpec, _n_steps, _pert_kwargs, random_gauss_perturbation

__all__ = [
    "run_protocol_episode",
]

# -- one run --------------------------------------------------------------------------------------------------------


def _hold_ratio(controller: SampledController) -> int:
    h = float(controller.sample_time)
    ratio = round(h / DT) if math.isfinite(h) else 0
    if ratio < 1 or abs(ratio * DT - h) > 1e-9:
        raise ValueError(f"controller.sample_time must be a positive multiple of {DT} s, got {h!r}")
    return ratio


def _to_joint(x: np.ndarray) -> np.ndarray:
    """pendulab absolute state -> upstream joint coordinates (q2, dq2 relative)."""
    return np.array([x[0], x[1] - x[0], x[2], x[3] - x[2]])


def _to_absolute(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], q[0] + q[1], q[2], q[2] + q[3]])


def _wrap_top(q: np.ndarray) -> np.ndarray:
    y = np.copy(q)
    y[0] = q[0] % (2 * np.pi)
    y[1] = (q[1] + np.pi) % (2 * np.pi) - np.pi
    return y


def _is_success(q_final: np.ndarray) -> bool:
    lp = _wrap_top(q_final)
    return bool(all(abs(lp[i] - GOAL[i]) < EPSILON[i] for i in range(4)))


def run_protocol_episode(
    task: str,
    controller: SampledController,
    spec: RunSpec,
    rng_state: tuple | None = None,
    *,
    seed: int = 0,
    record: bool = False,
    every_step: bool = False,
    plant: IdentifiedPlant | None = None,
) -> dict[str, Any]:
    """One run of the protocol: upstream's ``Simulator.simulate`` loop with the run's perturbation.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    controller : SampledController
        Reset first; called with ``(t, x)`` (pendulab absolute state, measured) every
        ``sample_time`` (a multiple of 2 ms) and held in between.
    spec : RunSpec
        What to perturb.
    rng_state : tuple, optional
        ``RandomState.get_state()`` at the start of the run; default ``RandomState(seed)``.
    seed : int
        Seed when ``rng_state`` is None.
    record : bool
        Also return the trajectory (``t``, ``x`` joint coordinates, ``u`` applied torques).
    every_step : bool
        Call the controller every 2 ms step, as upstream's simulator calls its controllers, whatever
        its ``sample_time`` (default: on its own sample grid, the output held in between).
    plant : IdentifiedPlant, optional
        Simulate an identified robot (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.

    Returns
    -------
    dict
        ``index, category, param, level_index, level, rep, success``, ``final`` (joint
        coordinates (q1, q2, dq1, dq2), unwrapped), ``ctrl_median``, ``ctrl_max`` [s] per
        controller call, ``calls``, ``wall`` [s]; perturbation runs also ``mu``, ``sigma``,
        ``amplitude``; with ``record``: ``t``, ``x``, ``u`` arrays.

    Raises
    ------
    ValueError
        A sample time that is not a multiple of 2 ms, or a non-finite state.
    """
    w0 = time.perf_counter()
    act = actuated_joint(task)
    rng = np.random.RandomState(seed)
    if rng_state is not None:
        rng.set_state(rng_state)
    params = protocol_params(task, plant)
    meas_sigma = np.zeros(4)
    u_sigma = np.zeros(2)
    k_resp = 1.0
    delay = 0.0
    pert = np.zeros((2, 0))
    extra: dict[str, Any] = {}
    if spec.category == "model":
        params = vary(params, spec.param, spec.level)
    elif spec.category == "measurement_noise":
        meas_sigma = np.array([0.0, 0.0, spec.level, spec.level])
    elif spec.category == "u_noise":
        u_sigma[act] = spec.level
    elif spec.category == "u_responsiveness":
        k_resp = spec.level
    elif spec.category == "delay":
        delay = spec.level
    elif spec.category == "perturbation":
        pert, mu, sig, amp = random_gauss_perturbation(rng, **_pert_kwargs())
        extra = {"mu": mu.tolist(), "sigma": sig.tolist(), "amplitude": amp.tolist()}
    else:
        raise ValueError(f"spec.category must be one of {list(CATEGORIES)}, got {spec.category!r}")
    n_steps = _n_steps()
    Z = rng.standard_normal((n_steps, DRAWS_PER_STEP))
    f = protocol_rhs_python()
    p = robot_params_vector(params, validate=False).tolist()  # upstream's grid leaves the physical range (cf < 0)
    limit = np.zeros(2)
    limit[act] = TORQUE_LIMIT
    drive = np.zeros(2)
    drive[act] = 1.0  # the plant's input matrix: the passive joint's torque (a perturbation there) does nothing
    ratio = 1 if every_step else _hold_ratio(controller)
    n_delay = int(delay / DT) + 1
    dt = DT
    x = np.zeros(4)
    hist = [x]
    last = np.zeros(2)
    held = np.zeros(2)
    t = 0.0
    times = []
    us = [] if record else None
    controller.reset()
    for k in range(n_steps):
        xm = hist[max(-n_delay, -len(hist))] if n_delay > 1 else x
        q_meas = _to_joint(xm) + meas_sigma * Z[k, 0:4]
        if k % ratio == 0:
            c0 = time.perf_counter()
            out = controller(t, _to_absolute(q_meas))
            times.append(time.perf_counter() - c0)
            held = full_input(controller, out, t)
        nu = last + k_resp * (held - last)
        nu = nu + u_sigma * Z[k, 4:6]
        nu[0] = np.clip(nu[0], -limit[0], limit[0])
        nu[1] = np.clip(nu[1], -limit[1], limit[1])
        idx = int(t / dt)
        if idx < pert.shape[1]:
            nu[0] += pert[0][idx]
            nu[1] += pert[1][idx]
        u = nu * drive
        k1 = f(x, u, p)
        k2 = f(x + 0.5 * dt * k1, u, p)
        k3 = f(x + 0.5 * dt * k2, u, p)
        k4 = f(x + dt * k3, u, p)
        x = x + dt * ((k1 + 2.0 * (k2 + k3) + k4) / 6.0)
        t += dt
        hist.append(x)
        last = nu
        if us is not None:
            us.append(nu)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"run {spec.index} ({spec.category} {spec.param} level {spec.level}) produced a non-finite state")
    q_final = _to_joint(x)
    res: dict[str, Any] = {
        "index": spec.index,
        "category": spec.category,
        "param": spec.param,
        "level_index": spec.level_index,
        "level": None if math.isnan(spec.level) else spec.level,
        "rep": spec.rep,
        "success": _is_success(q_final),
        "final": [float(v) for v in q_final],
        "ctrl_median": float(statistics.median(times)) if times else 0.0,
        "ctrl_max": float(max(times)) if times else 0.0,
        "calls": len(times),
        "wall": time.perf_counter() - w0,
        **extra,
    }
    if record:
        res["t"] = np.arange(n_steps + 1) * dt
        res["x"] = np.array([_to_joint(h) for h in hist])
        res["u"] = np.array(us)
    return res

"""The RealAIGym simulation leaderboard v2 run: fixed-step RK4 at 2 ms, the controller called every step, 10 s.

What the leaderboard does (verified in github.com/dfki-ric-underactuated-lab/double_pendulum,
stored copies): ``leaderboard/{pendubot,acrobot}/simulation_v2/sim_parameters.py``
(commit 699c934) loads design C.1, model 1.0, sets the torque limit to
``[6, 0]`` (pendubot) or ``[0, 6]`` (acrobot), motor inertia, damping and
Coulomb friction to zero, ``integrator = "runge_kutta"``, ``dt = 0.002``,
``t_final = 10``, ``x0 = 0``. ``Simulator.simulate_and_animate``
(``src/python/double_pendulum/simulation/simulation.py``, commit d9084c6)
runs ``int(10 / 0.02) = 500`` frames of ``int(0.02 / 0.002) = 10`` steps; each
step measures the exact state, calls ``controller.get_control_output(x, t)``,
clips the torque to the limits (so the passive joint gets 0), takes one
classic RK4 step with the torque held, and records ``(t + dt, x, tau)`` with
``t`` accumulated in floating point. ``save_trajectory`` keeps the shortest
column, so the scored CSV holds 5000 rows ``(t_k, x_k, tau_k)``, t = 0 ... 9.998 s,
``tau_k`` held over ``[t_k, t_k + dt]``.

pendulab's rigid model (absolute angles) with the task's parameters and
``b1 = b2 = 0`` supplies the right-hand side (its CasADi graph translated to
plain Python, :func:`pendulab.model.pycode.to_python`). A
:class:`~pendulab.control.feedback.SampledController` whose sample time is a
multiple of 2 ms is called on its own grid and its output held in between
(its zero-order-hold contract); a 2 ms controller is called every step, as
the leaderboard calls its controllers.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..._inputs import checked
from ...control.feedback import SampledController, full_input
from ...control.realai.spec import DT, N_STEPS, T_FINAL, TASKS, TORQUE_LIMIT, check_task
from ...model.model import INPUT_NAMES, Model
from ...model.plant_file import IdentifiedPlant
from ...model.pycode import to_python
from .criteria import CRITERIA, PUBLISHED, criteria, score_v2, to_relative
from .plant import plant_label, protocol_model

__all__ = ["RealAIResult", "rk4_rollout", "run_leaderboard"]


@dataclass
class RealAIResult:
    """One leaderboard run: the trajectory, the five criteria and the v2 score.

    Attributes
    ----------
    task : str
        "pendubot" or "acrobot".
    controller : str
        Controller name.
    t : ndarray, shape (N,)
        Times [s] (N = 5000, t = 0 ... 9.998).
    x : ndarray, shape (N, 4)
        pendulab state (theta1, theta2, omega1, omega2), absolute angles from hanging [rad, rad/s].
    u : ndarray, shape (N, 2)
        Applied torques (tau1, tau2) [N.m], held over [t_k, t_k + 2 ms].
    criteria : dict of str to float
        The five criteria (:data:`~pendulab.evaluate.realai.criteria.CRITERIA`).
    score : float
        RealAI score v2.
    success : bool
        The end effector stays above 0.9 (L1 + L2) before the last sample.
    plant : str
        The simulated plant (:func:`~pendulab.evaluate.realai.plant.plant_label`).

    Examples
    --------
    >>> from pendulab.evaluate import realai_score
    >>> res = realai_score("pendubot", "best")
    >>> res.task, res.controller, res.plant, res.t.shape, res.x.shape  # 5000 samples of 2 ms
    ('pendubot', 'best', 'nominal', (5000,), (5000, 4))
    >>> {name: round(value, 3) for name, value in res.criteria.items()}
    {'swingup_time': 1.558, 'energy': 7.675, 'torque_cost': 2.917, 'torque_smoothness': 0.005, 'velocity_cost': 40.415}
    >>> res.write_csv("leaderboard_run.csv").name
    'leaderboard_run.csv'
    """

    task: str
    controller: str
    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    criteria: dict[str, float]
    score: float
    success: bool
    plant: str = "nominal"

    @property
    def swingup_time(self) -> float:
        """Swing-up time [s] (the last time stamp when there is none)."""
        return self.criteria["swingup_time"]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary.

        Returns
        -------
        dict
            task, controller, success, score, the criteria, and the best
            published entry of the task (name, score) with ``beats_published``.
        """
        name, best = max(PUBLISHED[self.task].items(), key=lambda kv: kv[1])
        return {
            "task": self.task,
            "controller": self.controller,
            "success": bool(self.success),
            "score": float(self.score),
            "swingup_time": float(self.swingup_time),
            "criteria": {k: float(self.criteria[k]) for k in CRITERIA},
            "published_best": {"name": name, "score": best},
            "beats_published": bool(self.score > best),
            "simulation": {"integrator": "rk4", "dt": DT, "t_final": T_FINAL, "torque_limit": TORQUE_LIMIT, "plant": self.plant},
        }

    def write_csv(self, path: str | Path) -> Path:
        """Write ``t, theta1, theta2, omega1, omega2, tau1, tau2`` (absolute angles), one row per 2 ms step.

        Parameters
        ----------
        path : str or Path
            CSV file (parent directories are created).

        Returns
        -------
        Path
            The file written.
        """
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        with p.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t", "theta1", "theta2", "omega1", "omega2", "tau1", "tau2"])
            for tk, xk, uk in zip(self.t, self.x, self.u, strict=True):
                w.writerow([repr(float(tk)), *(repr(float(v)) for v in xk), *(repr(float(v)) for v in uk)])
        return p


def _hold_ratio(controller: SampledController) -> int:
    """Steps per controller sample: its sample time must be a whole number of 2 ms steps."""
    h = float(controller.sample_time)
    ratio = round(h / DT)
    if not math.isfinite(h) or ratio < 1 or abs(ratio * DT - h) > 1e-9:
        raise ValueError(f"controller.sample_time must be a positive multiple of {DT} s, got {h!r}")
    return ratio


@checked()
def rk4_rollout(model: Model, x0: np.ndarray, policy: Any, n_steps: int, dt: float = DT) -> tuple:
    """Fixed-step classic RK4 with the torque held over each step, as the leaderboard's ``Simulator.step``.

    Parameters
    ----------
    model : Model
        Rigid plant (absolute angles).
    x0 : array_like, shape (4,)
        Start state.
    policy : callable
        ``policy(k, t, x) -> (tau1, tau2)`` [N.m], applied as returned (clip it yourself).
    n_steps : int
        Number of steps.
    dt : float
        Step [s].

    Returns
    -------
    t : ndarray, shape (n_steps + 1,)
        Times accumulated in floating point, as the leaderboard does [s].
    x : ndarray, shape (n_steps + 1, 4)
        States.
    u : ndarray, shape (n_steps, 2)
        Torques held over each step [N.m].
    """
    f = to_python(model.functions["rhs"])
    p = [float(v) for v in model.p]
    x = np.array(model.check_state(x0, "x0"), dtype=float)
    ts, xs, us = [0.0], [x.copy()], []
    t = 0.0
    for k in range(n_steps):
        u = [float(v) for v in policy(k, t, x)]
        k1 = f(x, u, p)
        k2 = f(x + 0.5 * dt * k1, u, p)
        k3 = f(x + 0.5 * dt * k2, u, p)
        k4 = f(x + dt * k3, u, p)
        x = x + dt * (k1 + 2.0 * (k2 + k3) + k4) / 6.0
        t += dt
        ts.append(t)
        xs.append(x.copy())
        us.append(u)
    return np.array(ts), np.array(xs), np.array(us, dtype=float).reshape(n_steps, len(INPUT_NAMES))


def run_leaderboard(
    task: str,
    controller: SampledController,
    name: str = "custom",
    *,
    progress: Callable[[int, int], None] | None = None,
    plant: IdentifiedPlant | None = None,
) -> RealAIResult:
    """Run ``controller`` through the leaderboard simulation of ``task`` and score it.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    controller : SampledController
        Called with ``(t, x)`` (pendulab absolute state) on its own sample grid
        (a multiple of 2 ms); its torques are scattered to (tau1, tau2) and
        clipped to +-6 N.m on the actuated joint, 0 on the passive one.
    name : str
        Controller name for the result.
    progress : callable, optional
        ``progress(done, total)`` in 2 ms steps, every 100 steps and at the end.
    plant : IdentifiedPlant, optional
        Simulate an identified robot (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.

    Returns
    -------
    RealAIResult
        Trajectory, criteria and score.

    Raises
    ------
    ValueError
        Unknown ``task``, a sample time that is not a multiple of 2 ms, or a
        non-finite state (the run blew up).
    TypeError
        ``controller`` lacks ``sample_time``/``input_names`` or is not callable.
    """
    check_task(task)
    if not (callable(controller) and hasattr(controller, "sample_time") and hasattr(controller, "input_names")):
        raise TypeError(
            f"controller must be a SampledController (callable with sample_time, input_names), got {type(controller)}"
        )
    model = protocol_model(task, plant)
    ratio = _hold_ratio(controller)
    limit = np.zeros(len(INPUT_NAMES))
    limit[TASKS[task]] = TORQUE_LIMIT
    held = np.zeros(len(INPUT_NAMES))
    controller.reset()

    def policy(k: int, t: float, x: np.ndarray) -> np.ndarray:
        nonlocal held
        if k % ratio == 0:
            held = np.clip(full_input(controller, controller(t, x), t), -limit, limit)
        if progress is not None and k % 100 == 0:
            progress(k, N_STEPS)
        return held

    t, x, u = rk4_rollout(model, model.state(), policy, N_STEPS)
    if progress is not None:
        progress(N_STEPS, N_STEPS)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"the leaderboard run of {name!r} on {task} produced a non-finite state")
    # The scored CSV keeps the shortest column: N_STEPS rows (t_k, x_k, u_k).
    t, x = t[:N_STEPS], x[:N_STEPS]
    prm = model.params
    values = criteria(t, to_relative(x), u, prm.L1, prm.L2)
    success = values["swingup_time"] < t[-1]
    return RealAIResult(task, name, t, x, u, values, score_v2(values, success), bool(success), plant_label(plant))

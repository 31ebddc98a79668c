"""The RealAIGym v3 protocol as the ICRA 2025 hardware final ran it, on a hardware-faithful simulated robot.

Upstream (github.com/dfki-ric-underactuated-lab/double_pendulum, ``experiments/icra_2025/``): the entry is
wrapped in ``GlobalPolicyTestingControllerV2(controller, n_disturbances=10, t_max=60, reset_length=1.0, kp=2.0,
ki=0.0, kd=0.3, pos_limit=3.5 pi, vel_limit=20, pid_pos_contribution_limit=[3, 3], mpar=mpar_nolim)``
(``leaderboard_score_run.py``, ``parameters.py``) and run by ``hardware_control_loop_tmotors.run_experiment``
(``tau_limit=[6, 6]``, ``safety_velocity_limit=25``, ``safety_position_limit=4 pi``, ``dt`` the entry's, at
most 500 Hz). What this module keeps of it:

* the schedule of :func:`~.v3_definition.reset_schedule` with 10 resets over 60 s; each reset is a
  ``PointPIDController`` (kp 2, ki 0, kd 0.3, its ``dt`` left at the wrapper's default 0.001 s although the loop
  runs at 2 ms, so the D term is ``0.3 (e_k - e_{k-1}) / 0.001``; angles not wrapped; proportional part clipped to
  3 N.m; error history kept over all resets; 6 N.m per joint) plus gravity compensation of model 1.0, for more
  than 1.0 s;
* a **limit reset**: a measured angle beyond 3.5 pi or a rate beyond 20 rad/s starts a reset at once (the later
  reset times move by the delay), and a reset ends only after 10 calls without such a violation;
* the **safety stop**: a measured angle beyond 4 pi or rate beyond 25 rad/s ends the experiment; the rest of the
  60 s scores nothing;
* the entry's torque limit: 6 N.m on the driven joint, 0 on the passive one, or the passive allowance the
  hardware rules grant to compensate motor friction (0.5 N.m, ``passive_allowance``); the loop clips to 6 N.m;
* the score: ``uptime / 60`` over the *measured* angles at the loop's time stamps, as upstream scores the
  recorded CSV.

:func:`v3_hardware_score` runs pendulab's planning controllers with their plans' rates bounded
(:data:`PLAN_VELOCITY_LIMIT_HW`, below the limit reset) and, with an allowance, compensating the identified friction
(:class:`FrictionCompensated`).

The simulated robot (:func:`run_v3_hardware`): the identified design C.1 (``pendulab/model/plants/c1.json``:
links, viscous and Coulomb friction, rotor inertia) and the sensing and timing measured on its excitation
records (:func:`pendulab.identify.sensing.c1_sensing`, ``docs/realai_v3.md``):

* loop intervals drawn (bootstrap) from the records' time-stamp differences: 2.000 ms with rare overruns up
  to 3.7 ms; the controller sees the measurement at each loop instant and its torque is held until the next one;
* angles quantized to the encoder step; joint rates plus MA(1) noise of the measured standard deviation and
  lag-1 correlation;
* the commanded torque quantized to the reading's step, plus white noise of the reading's measured standard
  deviation (the identified plant was fitted with the *reading* as its input, so the plant is driven by what
  the reading would show).

The plant is integrated by classic RK4 in sub-steps of at most 1 ms inside each loop interval. Every random
draw (schedule, intervals, noise) comes from ``seed``: a run is reproducible. Not modelled: the command-to-
reading lag of the motors (fitted time constants 3-49 ms across the records, no consistent value), and the
~1 ms by which the hardware loop's measurement precedes its command.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..._inputs import checked
from ..._io import atomic_write_text
from ...control.feedback import SampledController, full_input
from ...control.realai.spec import DT, HEIGHT_FRACTION, TASKS, TORQUE_LIMIT, check_task, leaderboard_model
from ...identify.sensing import SensingModel, c1_sensing, ma1_coefficients
from ...model.model import INPUT_NAMES
from ...model.plant_file import IdentifiedPlant, load_plant
from ...model.pycode import to_python
from ...model.robot import COULOMB_SHARPNESS
from .controllers import PLAN_VELOCITY_LIMIT_HW, RATE_BOUNDED, resolve_controller
from .leaderboard_published import PUBLISHED_HARDWARE
from .plant import plant_label, protocol_model
from .v3 import _entry_limits, _entry_torque, _gravity_compensation, protocol_entry, v3_score
from .v3_definition import count_swingups, reset_schedule, uptime
from .v3_result import V3Result

__all__ = [
    "T_FINAL_HW",
    "N_RESETS_HW",
    "RESET_LENGTH_HW",
    "PID_GAINS_HW",
    "PASSIVE_ALLOWANCE",
    "PLAN_VELOCITY_LIMIT_HW",
    "PUBLISHED_HARDWARE",
    "V3HardwareResult",
    "FrictionCompensated",
    "run_v3_hardware",
    "v3_hardware_score",
    "V3_RUNNERS",
]

#: Episode length [s] (``t_final``).
T_FINAL_HW: float = 60.0
#: Resets per episode (``n_disturbances``).
N_RESETS_HW: int = 10
#: A reset lasts until its timer exceeds this [s] (``reset_length``).
RESET_LENGTH_HW: float = 1.0
#: Reset PID (kp [N.m/rad], ki [N.m/(rad s)], kd [N.m s/rad]).
PID_GAINS_HW: tuple[float, float, float] = (2.0, 0.0, 0.3)
#: The PID's own step [s]: the wrapper's default, not the loop's period (upstream does not pass it).
PID_DT_HW: float = 0.001
#: Limit of the PID's proportional part per joint [N.m] (``pid_pos_contribution_limit``).
PID_POS_LIMIT: float = 3.0
#: Torque limit of the loop (and of the PID) on both joints [N.m] (``tau_limit``, ``mpar_nolim``).
LOOP_LIMIT: float = 6.0
#: A measured joint angle [rad] or rate [rad/s] beyond these starts a reset (``pos_limit``, ``vel_limit``).
RESET_POS_LIMIT: float = 3.5 * math.pi
RESET_VEL_LIMIT: float = 20.0
#: A measured joint angle [rad] or rate [rad/s] beyond these stops the experiment (``safety_*_limit``).
SAFETY_POS_LIMIT: float = 4.0 * math.pi
SAFETY_VEL_LIMIT: float = 25.0
#: The passive joint's allowance under the hardware rules (motor friction compensation) [N.m].
PASSIVE_ALLOWANCE: float = 0.5
#: Longest RK4 sub-step inside a loop interval [s].
SUBSTEP: float = 0.001


@dataclass
class V3HardwareResult(V3Result):
    """One v3-hardware run (:class:`~.v3_result.V3Result`, ``t`` the loop's irregular time stamps, ``x`` the true
    states there, ``u`` the torques applied over each interval).

    Attributes
    ----------
    task, controller, seed, t, x, u, score, uptime, n_swingups, threshold, reset_states, reset_times : see V3Result
        Inherited from :class:`~.v3_result.V3Result`, with ``t``, ``x`` and ``u`` as above.
    call_times, wall_time, plant, intervals, link_lengths : see V3Result
        Inherited from :class:`~.v3_result.V3Result`.
    passive_limit, schedule : see V3Result
        Inherited; ``passive_limit`` equals ``passive_allowance``; ``schedule`` is ``"current"`` (10 resets).
    measured : ndarray, shape (N, 4)
        What the controller saw: quantized angles, noisy rates (pendulab's absolute state) [rad, rad/s].
    stopped_at : float or None
        Time of the safety stop [s] (the score counts nothing after it), None if the run went the 60 s.
    limit_resets : int
        Resets started by a limit violation (angle beyond 3.5 pi or rate beyond 20 rad/s).
    passive_allowance : float
        The passive joint's torque limit of this run [N.m].
    velocity_limit : float or None
        Bound on the joint rates of the controller's plans [rad/s] (None: unbounded, or a controller without plans).
    friction_compensated : bool
        The controller ran wrapped in :class:`FrictionCompensated` (what the passive allowance is used for).
    sensing : dict
        :meth:`~pendulab.identify.sensing.SensingModel.to_dict` of the sensing simulated.
    """

    measured: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)), repr=False)
    stopped_at: float | None = None
    limit_resets: int = 0
    passive_allowance: float = 0.0
    velocity_limit: float | None = None
    friction_compensated: bool = False
    sensing: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def height(self) -> np.ndarray:
        """End-effector height [m] of the *measured* angles at each sample (what upstream scores)."""
        L1, L2 = self.link_lengths if self.link_lengths is not None else (0.2, 0.3)
        return -L1 * np.cos(self.measured[:, 0]) - L2 * np.cos(self.measured[:, 1])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: :meth:`V3Result.to_dict` with the hardware protocol's settings and published rows.

        Returns
        -------
        dict
            As :meth:`V3Result.to_dict`; ``protocol`` ``"v3-hardware"``, ``published_best`` the hardware winner,
            ``simulation`` the loop, sensing and reset settings, plus ``stopped_at``, ``limit_resets``,
            ``passive_allowance`` [N.m],
            ``max_joint_rate`` (largest measured joint rate of the run [rad/s]; the limit reset acts at 20) and
            ``entry`` (the controller's plan ``velocity_limit`` [rad/s] and ``friction_compensated``).
        """
        d = super().to_dict()
        name, best = max(PUBLISHED_HARDWARE[self.task].items(), key=lambda kv: kv[1])
        iv = np.diff(self.t)
        m = self.measured
        rates = np.column_stack([m[:, 2], m[:, 3] - m[:, 2]]) if len(m) else np.zeros((0, 2))  # joint coordinates
        d.update(
            protocol="v3-hardware",
            published_best={"name": name, "score": best},
            beats_published=bool(self.score > best),
            stopped_at=self.stopped_at,
            limit_resets=int(self.limit_resets),
            passive_allowance=float(self.passive_allowance),
            max_joint_rate=float(np.abs(rates).max()) if len(rates) else None,
            entry={"velocity_limit": self.velocity_limit, "friction_compensated": bool(self.friction_compensated)},
        )
        d["controller_time"]["period_s"] = DT
        d["simulation"] = {
            "integrator": f"rk4, sub-steps <= {SUBSTEP} s",
            "loop_period": DT,
            "loop_intervals": {"mean": float(iv.mean()) if iv.size else None, "max": float(iv.max()) if iv.size else None},
            "t_final": T_FINAL_HW,
            "loop_torque_limit": [LOOP_LIMIT, LOOP_LIMIT],
            "entry_torque_limit": [TORQUE_LIMIT if i == TASKS[self.task] else self.passive_limit for i in range(2)],
            "n_resets": N_RESETS_HW,
            "reset_length": RESET_LENGTH_HW,
            "pid": {"gains": list(PID_GAINS_HW), "dt": PID_DT_HW, "pos_contribution_limit": PID_POS_LIMIT},
            "reset_limits": [RESET_POS_LIMIT, RESET_VEL_LIMIT],
            "safety_limits": [SAFETY_POS_LIMIT, SAFETY_VEL_LIMIT],
            "sensing": self.sensing,
            "upstream": "dfki-ric-underactuated-lab/double_pendulum experiments/icra_2025 (hardware final)",
            "plant": self.plant,
        }
        return d


class FrictionCompensated:
    """A pendulab controller plus the identified joint friction, on both joints: what the passive allowance is for.

    The output is the controller's torque scattered to (tau1, tau2) plus ``b_i q_i' + cf_i atan(100 q_i')`` of an
    identified robot on each joint (``q2'`` relative), evaluated on the measured rates; the protocol clips the
    passive joint's share to its allowance. At rest the rate noise (~0.1 rad/s, times the atan's slope 100) flips the
    Coulomb term's sign from sample to sample: ``deadband`` [rad/s] scales it down linearly below that speed.

    Parameters
    ----------
    controller : SampledController
        The controller (pendulab's absolute state in, its ``input_names`` out).
    plant : IdentifiedPlant
        Gives ``b1, b2, cf1, cf2``.
    deadband : float
        Speed below which the Coulomb term is scaled down [rad/s], >= 0.

    Raises
    ------
    TypeError
        ``plant`` is not an IdentifiedPlant.
    ValueError
        A negative or non-finite ``deadband``.
    """

    input_names: tuple[str, ...] = INPUT_NAMES

    def __init__(self, controller: SampledController, plant: IdentifiedPlant, deadband: float = 0.3) -> None:
        if not isinstance(plant, IdentifiedPlant):
            raise TypeError(f"plant must be an IdentifiedPlant, got {type(plant).__name__}")
        db = float(deadband)
        if not (math.isfinite(db) and db >= 0.0):
            raise ValueError(f"deadband must be a speed >= 0 [rad/s], got {deadband!r}")
        self.controller = controller
        self.sample_time = float(controller.sample_time)
        self.b = np.array([plant.params["b1"], plant.params["b2"]], dtype=float)
        self.cf = np.array([plant.params["cf1"], plant.params["cf2"]], dtype=float)
        self.deadband = db

    def reset(self) -> None:
        """Reset the wrapped controller."""
        self.controller.reset()

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """(tau1, tau2) [N.m]: the controller's torque plus the friction compensation, at the state ``x`` (absolute)."""
        u = full_input(self.controller, self.controller(t, x), t)
        qd = np.array([x[2], x[3] - x[2]])
        scale = np.clip(np.abs(qd) / self.deadband, 0.0, 1.0) if self.deadband > 0.0 else 1.0
        return u + self.b * qd + scale * self.cf * np.arctan(COULOMB_SHARPNESS * qd)


def _check_duration(value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    if isinstance(value, bool) or not (0.0 < v <= T_FINAL_HW):
        raise ValueError(f"duration must be in (0, {T_FINAL_HW}] s (the protocol's episode), got {value!r}")
    return v


class _Sensor:
    """Encoder quantization and MA(1) rate noise in joint coordinates, returned as pendulab's absolute state."""

    def __init__(self, sensing: SensingModel, rng: np.random.Generator) -> None:
        self.step = float(sensing.position_step)
        self.coef = [ma1_coefficients(s, r) for s, r in zip(sensing.velocity_noise, sensing.velocity_correlation, strict=True)]
        self.rng = rng
        self.prev = rng.standard_normal(2)

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(joint-coordinate measurement (q1, q2, qd1, qd2), the same as pendulab's absolute state)."""
        q = np.array([x[0], x[1] - x[0]])
        qd = np.array([x[2], x[3] - x[2]])
        e = self.rng.standard_normal(2)
        noise = np.array([c0 * e[j] + c1 * self.prev[j] for j, (c0, c1) in enumerate(self.coef)])
        self.prev = e
        qm = self.step * np.round(q / self.step)
        vm = qd + noise
        rel = np.array([qm[0], qm[1], vm[0], vm[1]])
        return rel, np.array([qm[0], qm[0] + qm[1], vm[0], vm[0] + vm[1]])


@checked(seed="legacy_seed")
def run_v3_hardware(
    task: str,
    entry: Any,
    name: str = "custom",
    *,
    seed: int = 0,
    passive_allowance: float = 0.0,
    duration: float = T_FINAL_HW,
    plant: IdentifiedPlant | None = None,
    sensing: SensingModel | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> V3HardwareResult:
    """Run an entry through the v3-hardware protocol on the simulated robot and score it.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    entry : SampledController or object with ``get_control_output_(x_rel, t)``
        As :func:`~.v3.run_v3`; a pendulab controller is called on its own sample grid (a multiple of 2 ms) of the
        loop's calls, with the measured state.
    name : str
        Controller name for the result.
    seed : int
        Seeds the reset schedule (:func:`~.v3_definition.reset_schedule`, upstream's draws) and, separately, the
        loop intervals and the noise.
    passive_allowance : float
        Torque the entry may put on the passive joint [N.m], in [0, 0.5] (the hardware rules' friction allowance).
    duration : float
        Episode length [s] (default the protocol's 60; shorter for a check, score = uptime / duration).
    plant : IdentifiedPlant, optional
        The simulated robot (default the shipped identified C.1, ``load_plant("c1")``).
    sensing : SensingModel, optional
        Sensing and timing (default :func:`~pendulab.identify.sensing.c1_sensing`).
    progress : callable, optional
        ``progress(done, total)`` in loop samples (total estimated at 2 ms each), every 500 samples and at the end.

    Returns
    -------
    V3HardwareResult
        The scored run.

    Raises
    ------
    InputError
        ``seed`` or ``passive_allowance`` outside its declaration (:data:`pendulab._inputs.INPUTS`; a ValueError).
    ValueError
        Unknown task, bad ``duration``, or a non-finite state.
    TypeError
        ``entry`` is neither a sampled controller nor an upstream-style entry, or ``plant``/``sensing`` of the
        wrong type.
    """
    check_task(task)
    seed = int(seed)  # seed and allowance: checked where they entered (@checked)
    allowance = float(passive_allowance)
    t_final = _check_duration(duration)
    if plant is None:
        plant = load_plant("c1")
    if sensing is None:
        sensing = c1_sensing()
    if not isinstance(sensing, SensingModel):
        raise TypeError(f"sensing must be a SensingModel (pendulab.identify.sensing), got {type(sensing).__name__}")
    states, times = reset_schedule(seed, N_RESETS_HW, T_FINAL_HW)
    times = times.copy()
    # a reset interrupts the entry for at least 1 s; an overrun of the loop (<= 3.7 ms) does not
    proto = protocol_entry(task, entry, passive_limit=allowance, gap=0.5 * RESET_LENGTH_HW)
    limit = _entry_limits(task, allowance)
    model = protocol_model(task, plant)
    f = to_python(model.functions["rhs"])
    p = [float(v) for v in model.p]
    grav = _gravity_compensation(leaderboard_model(task))  # the wrapper's mpar_nolim: model 1.0, not the robot
    rng = np.random.default_rng([seed, 30])  # loop and noise draws, apart from upstream's schedule stream
    sensor = _Sensor(sensing, rng)
    pool = np.asarray(sensing.intervals, dtype=float)
    tau_step = float(sensing.torque_step)
    tau_sigma = np.asarray(sensing.torque_noise, dtype=float)
    kp, ki, kd = PID_GAINS_HW
    err1: list[float] = []
    err2: list[float] = []
    goal = states[0]
    violations: list[bool] = []
    mode, timer, last_t, start, counter, limit_resets = False, 0.0, 0.0, 0.0, 0, 0
    intervals: list[tuple[float, float]] = []
    total = int(round(t_final / DT))
    ts: list[float] = []
    xs: list[np.ndarray] = []
    ys: list[np.ndarray] = []
    us: list[np.ndarray] = []
    stopped_at: float | None = None
    x = model.state().astype(float)
    t = 0.0
    k = 0
    t_wall = time.perf_counter()
    while t < t_final:
        if progress is not None and k % 500 == 0:
            progress(min(k, total), total)
        xr, y = sensor(x)
        ts.append(t)
        xs.append(x.copy())
        ys.append(y)
        # GlobalPolicyTestingControllerV2.get_control_output_, on the measured relative state
        violation = bool(np.any(np.abs(xr[:2]) > RESET_POS_LIMIT) or np.any(np.abs(xr[2:]) > RESET_VEL_LIMIT))
        violations.append(violation)
        if (violation or t >= times[counter]) and not mode:
            mode, timer, start = True, 0.0, t
            goal = states[counter]
            if violation:
                limit_resets += 1
                times = np.insert(times, counter, [t])
                delay = t if counter == 0 else t - times[counter - 1]
                times[counter + 1 :] += delay
            counter += 1
        if not any(violations[-10:]) and timer > RESET_LENGTH_HW and mode:
            mode = False
            intervals.append((float(start), float(t)))
        if mode:
            e1, e2 = goal[0] - xr[0], goal[1] - xr[1]
            err1.append(e1)
            err2.append(e2)
            d1 = kd * (err1[-1] - err1[-2]) / PID_DT_HW if len(err1) > 2 else 0.0
            d2 = kd * (err2[-1] - err2[-2]) / PID_DT_HW if len(err2) > 2 else 0.0
            u1 = np.clip(kp * e1, -PID_POS_LIMIT, PID_POS_LIMIT) + ki * sum(err1) * PID_DT_HW + d1
            u2 = np.clip(kp * e2, -PID_POS_LIMIT, PID_POS_LIMIT) + ki * sum(err2) * PID_DT_HW + d2
            u = np.clip([u1, u2], -LOOP_LIMIT, LOOP_LIMIT) + grav(xr)
            timer += t - last_t
        else:
            u = _entry_torque(proto, xr, t, limit)
        last_t = t
        cmd = np.clip(u, -LOOP_LIMIT, LOOP_LIMIT)
        # the motor's 12-bit torque and the reading's noise: the identified plant's input was the reading
        applied = tau_step * np.round(cmd / tau_step) + tau_sigma * rng.standard_normal(2)
        h = float(pool[rng.integers(pool.size)])
        n_sub = max(1, math.ceil(h / SUBSTEP - 1e-9))
        dt = h / n_sub
        ua = [float(applied[0]), float(applied[1])]
        for _ in range(n_sub):
            k1 = f(x, ua, p)
            k2 = f(x + 0.5 * dt * k1, ua, p)
            k3 = f(x + 0.5 * dt * k2, ua, p)
            k4 = f(x + dt * k3, ua, p)
            x = x + dt * (k1 + 2.0 * (k2 + k3) + k4) / 6.0
        us.append(applied)
        if not np.all(np.isfinite(x)):
            raise ValueError(f"the v3-hardware run of {name!r} on {task} produced a non-finite state at t = {t:.4g} s")
        t += h
        k += 1
        # run_experiment's safety check on the reply (the next measurement's angles and rates)
        q_next = np.array([x[0], x[1] - x[0], x[2], x[3] - x[2]])
        if np.any(np.abs(q_next[:2]) > SAFETY_POS_LIMIT) or np.any(np.abs(q_next[2:]) > SAFETY_VEL_LIMIT):
            stopped_at = t
            break
    if progress is not None:
        progress(total, total)
    t_arr, x_arr, y_arr = np.array(ts), np.array(xs), np.array(ys)
    prm = model.params
    threshold = HEIGHT_FRACTION * (prm.L1 + prm.L2)
    h_meas = -prm.L1 * np.cos(y_arr[:, 0]) - prm.L2 * np.cos(y_arr[:, 1])
    up = uptime(t_arr, h_meas, threshold)
    calls = np.asarray(proto.call_times, dtype=float)
    n_sched = N_RESETS_HW + limit_resets
    return V3HardwareResult(
        task=task,
        controller=name,
        seed=int(seed),
        t=t_arr,
        x=x_arr,
        u=np.array(us, dtype=float).reshape(-1, len(INPUT_NAMES)),
        reset_times=times[:n_sched].copy(),
        reset_states=states[:n_sched].copy(),
        intervals=intervals,
        uptime=up,
        score=up / t_final,
        n_swingups=count_swingups(t_arr, h_meas, threshold),
        threshold=threshold,
        call_times=calls,
        wall_time=time.perf_counter() - t_wall,
        plant=plant_label(plant),
        link_lengths=(prm.L1, prm.L2),
        measured=y_arr,
        stopped_at=stopped_at,
        limit_resets=limit_resets,
        passive_allowance=allowance,
        passive_limit=allowance,
        sensing=sensing.to_dict(),
    )


def hardware_entry(
    task: str,
    controller: Any,
    passive_allowance: float,
    plant: Any = None,
    *,
    velocity_limit: float | None = PLAN_VELOCITY_LIMIT_HW,
    friction_compensation: bool = True,
) -> tuple[str, SampledController, float | None, bool]:
    """A controller as the hardware protocol runs it (:func:`v3_hardware_score` and the leaderboard alike).

    A named controller whose plans can be bounded (:data:`~.controllers.RATE_BOUNDED`) plans within
    ``velocity_limit``; one that designs on the robot (:data:`~.controllers.PLANT_DESIGNED`) designs on ``plant``;
    with a positive ``passive_allowance`` a named controller is wrapped in
    :class:`FrictionCompensated` (the friction of ``plant``, or of the identified C.1).

    Parameters
    ----------
    task : str
        Leaderboard task (checked).
    controller : str or SampledController or callable
        As :func:`~.controllers.resolve_controller`.
    passive_allowance : float
        Torque the entry may put on the passive joint [N.m].
    plant : IdentifiedPlant, optional
        The simulated robot (default the identified C.1).
    velocity_limit : float or None
        Bound on both joint rates of the plans [rad/s].
    friction_compensation : bool
        Wrap a named controller in :class:`FrictionCompensated` when the allowance is positive.

    Returns
    -------
    tuple
        ``(name, controller, velocity bound used or None, compensated)``.
    """
    bounded = velocity_limit if isinstance(controller, str) and controller in RATE_BOUNDED else None
    robot = plant if isinstance(plant, IdentifiedPlant) else load_plant("c1")
    name, ctrl = resolve_controller(task, controller, velocity_limit=bounded, plant=robot)
    compensated = bool(friction_compensation) and isinstance(controller, str) and passive_allowance > 0.0
    if compensated:
        ctrl = FrictionCompensated(ctrl, robot)
    return name, ctrl, None if bounded is None else float(bounded), compensated


@checked(seed="legacy_seed")
def v3_hardware_score(
    task: str,
    controller: str | SampledController = "global",
    *,
    seed: int = 0,
    passive_allowance: float = 0.0,
    velocity_limit: float | None = PLAN_VELOCITY_LIMIT_HW,
    friction_compensation: bool = True,
    progress: Callable[[int, int], None] | None = None,
    out: str | Path | None = None,
    plant: IdentifiedPlant | None = None,
) -> V3HardwareResult:
    """Score a controller on the v3-hardware protocol (60 s, 10 PID resets of 1 s, the simulated C.1 robot).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (``swingup_pendubot``/``swingup_acrobot`` are aliases).
    controller : str, SampledController or callable
        A name of :data:`~.controllers.CONTROLLERS`, a controller or a factory (:func:`~.controllers.resolve_controller`).
    seed : int
        Seed of the schedule, the loop intervals and the noise.
    passive_allowance : float
        Torque the entry may put on the passive joint [N.m], in [0, 0.5].
    velocity_limit : float or None
        Bound on both joint rates of the plans of a named planning controller (:data:`~.controllers.RATE_BOUNDED`:
        ``library``, ``replan``, ``replan_delayed``) [rad/s]; default :data:`PLAN_VELOCITY_LIMIT_HW`, below the
        protocol's 20 rad/s limit reset. None: the simulation protocols' unbounded plans. The plan library caches
        bounded plans apart (the bound is part of every entry's key).
    friction_compensation : bool
        With a positive ``passive_allowance``, run a named controller wrapped in :class:`FrictionCompensated`
        (the friction of ``plant``, or of the identified C.1 when ``plant`` is not an identified one): the use the
        hardware rules grant the allowance for. Objects and factories run as given.
    progress : callable, optional
        ``progress(done, total)`` in loop samples.
    out : str or Path, optional
        Directory: writes ``v3_hardware.csv``, ``v3_hardware.png`` and, last, ``v3_hardware.json``.
    plant : IdentifiedPlant, optional
        The simulated robot (default the shipped identified C.1).

    Returns
    -------
    V3HardwareResult
        Score, uptime, schedule and trajectory.

    Raises
    ------
    InputError
        ``seed``, ``passive_allowance`` or ``velocity_limit`` outside its declaration (:data:`pendulab._inputs.INPUTS`;
        a ValueError whose message names the option).
    ValueError
        Unknown task or controller name, or a run that blew up.
    TypeError
        ``task`` not a string or ``controller`` neither a name nor a sampled controller.
    """
    from ...control.swingup.tasks import short_name

    if not isinstance(task, str):
        raise TypeError(f"task must be a leaderboard task name (one of {list(TASKS)}), got {type(task).__name__}")
    task = check_task(short_name(task))
    name, ctrl, bounded, compensated = hardware_entry(
        task, controller, passive_allowance, plant, velocity_limit=velocity_limit, friction_compensation=friction_compensation
    )
    result = run_v3_hardware(task, ctrl, name, seed=seed, passive_allowance=passive_allowance, progress=progress, plant=plant)
    result.velocity_limit = bounded
    result.friction_compensated = compensated
    if out is not None:
        from .v3_figure import plot_v3

        d = Path(out)
        d.mkdir(parents=True, exist_ok=True)
        result.write_csv(d / "v3_hardware.csv")
        plot_v3(result, d / "v3_hardware.png")
        atomic_write_text(d / "v3_hardware.json", json.dumps(result.to_dict(), indent=2) + "\n")
    return result


#: ``pendulab score --protocol P``'s runner of each v3 protocol: ``runner(task, controller, *, seed, progress, out, plant,
#: **options)`` (``v3-hardware`` also takes ``passive_allowance``).
V3_RUNNERS: dict[str, Callable[..., V3Result]] = {"v3": v3_score, "v3-hardware": v3_hardware_score}

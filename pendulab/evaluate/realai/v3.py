"""The RealAIGym v3 (ICRA 2025 competition) simulation protocol: 60 s, 15 resets to random configurations, uptime score.

What upstream does (github.com/dfki-ric-underactuated-lab/double_pendulum, commit 1e8544e; restated
independently, not copied, as the test oracle ``tests/evaluate/v3_reference.py``):

* ``leaderboard/{pendubot,acrobot}/simulation_v3/sim_parameters.py``: design C.1, **model 1.1** (model 1.0
  with rotor inertia, damping and Coulomb friction zero), torque limit ``[6, 0]`` / ``[0, 6]`` for scoring,
  but the *simulated* plant is ``mpar_nolim`` with ``[6, 6]`` (the reset PID drives both joints);
  RK4 at ``dt = 0.002``, 60 s, ``x0 = 0``.
* ``calculate_leaderboard_score.py`` wraps the entry in ``GlobalPolicyTestingControllerV2(controller,
  n_disturbances=15, t_max=60, reset_length=0.2, mpar=mpar_nolim)``
  (``src/python/double_pendulum/controller/global_policy_testing_controller.py``). Its constructor draws,
  from the global ``np.random``, first ``uniform(0, 2 pi, (151, 4)) - pi`` (velocities then zeroed: random
  configurations at rest, relative angles), then the reset times ``linspace(60/16, 60 - 60/16, 15) +
  2 (rand(15) - 0.5)``. From a reset time on, for more than ``reset_length`` (its timer accumulates
  ``t - t_last`` per call), a ``PointPIDController`` (kp 10, ki 0.1, kd 1, its own ``dt = 0.001``, angles not
  wrapped, error history and integral kept over *all* resets, each joint clipped to 6 N.m) plus gravity
  compensation ``-G(q)`` drives toward the next random configuration; otherwise the entry's
  ``get_control_output_`` (no filter, no compensation) is called. The simulator clips the sum to the
  plant's ``[6, 6]``.
* ``Simulator.simulate_and_animate`` runs ``3000`` frames of ``10`` steps (30000 steps, ``t`` accumulated in
  floating point); ``save_trajectory`` keeps the shortest column (30000 rows, the state at 60 s dropped).
* ``analysis/leaderboard.py``: ``uptime = sum(diff(T, prepend=0)[y_ee > 0.9 (l1 + l2)])``,
  ``score = uptime / 60`` (``score_version="v3"``).

pendulab runs the same loop on its own rigid model (absolute angles; the protocol's PID and gravity
compensation act on upstream's relative ``q2 = theta2 - theta1``), with the schedule drawn from
``np.random.RandomState(seed)`` in upstream's call order, so ``seed`` reproduces an upstream run
after ``np.random.seed(seed)``. An entry is a :class:`~pendulab.control.feedback.SampledController`
called with pendulab's absolute state on its own sample grid (restarted after each reset); it is *not*
told about resets, as upstream entries are not.
"""

from __future__ import annotations

import csv
import json
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..._checks import bounded_int
from ..._io import atomic_open, atomic_write_text
from ...control.feedback import SampledController, full_input
from ...control.realai.spec import DT, HEIGHT_FRACTION, TASKS, TORQUE_LIMIT, check_task, leaderboard_model
from ...model.model import INPUT_NAMES, Model
from .controllers import resolve_controller
from .simulate import rk4_rollout

__all__ = [
    "T_FINAL_V3",
    "N_STEPS_V3",
    "N_RESETS",
    "RESET_LENGTH",
    "PID_GAINS",
    "PUBLISHED_V3",
    "V3Result",
    "ProtocolController",
    "reset_schedule",
    "uptime",
    "count_swingups",
    "run_v3",
    "v3_score",
]

#: Episode length [s].
T_FINAL_V3: float = 60.0
#: RK4 steps: ``int(60 / 0.02)`` animation frames of ``int(0.02 / 0.002)`` steps.
N_STEPS_V3: int = int(T_FINAL_V3 / 0.02) * int(0.02 / DT)
#: Resets per episode (``n_disturbances``).
N_RESETS: int = 15
#: A reset lasts until its timer exceeds this [s].
RESET_LENGTH: float = 0.2
#: Reset PID (kp [N.m/rad], ki [N.m/(rad s)], kd [N.m s/rad]) and its own step [s] (``dt=0.001`` default).
PID_GAINS: tuple[float, float, float] = (10.0, 0.1, 1.0)
PID_DT: float = 0.001
#: Torque limit of the simulated plant on both joints during the whole run [N.m] (``mpar_nolim``).
PLANT_LIMIT: float = 6.0
#: Best published v3 simulation scores (ICRA 2025 competition leaderboard, as quoted in issue 21).
PUBLISHED_V3: dict[str, dict[str, float]] = {"pendubot": {"vimppi": 0.799}, "acrobot": {"ar_eapo": 0.658}}
#: A swing-up counts again only after this dead time [s] (``get_number_of_swingups``).
SWINGUP_DEADTIME: float = 1.0


def reset_schedule(seed: int, n_resets: int = N_RESETS, t_max: float = T_FINAL_V3) -> tuple[np.ndarray, np.ndarray]:
    """The random reset configurations and times, drawn as ``GlobalPolicyTestingControllerV2.__init__`` draws them.

    Parameters
    ----------
    seed : int
        Seed of ``np.random.RandomState`` (upstream: the global state after ``np.random.seed(seed)``).
    n_resets : int
        ``n_disturbances``.
    t_max : float
        Episode length [s].

    Returns
    -------
    states : ndarray, shape (10 n_resets + 1, 4)
        Upstream's relative configurations ``(q1, q2, 0, 0)``, ``q`` uniform in ``[-pi, pi)`` [rad];
        reset ``i`` drives toward ``states[i]``.
    times : ndarray, shape (n_resets + 1,)
        Reset times [s], the last ``inf``.

    Raises
    ------
    ValueError
        ``seed`` outside ``[0, 2**32 - 1]`` or ``n_resets`` outside ``[1, 1000]``.
    TypeError
        ``seed`` or ``n_resets`` not an integer.
    """
    seed = bounded_int("seed", seed, low=0, high=2**32 - 1, why="a numpy RandomState seed")
    n = bounded_int("n_resets", n_resets, low=1, high=1000, why="upstream draws 10 n + 1 states")
    rs = np.random.RandomState(seed)
    states = rs.uniform(0.0, 2 * np.pi, (10 * n + 1, 4))
    states -= np.pi
    states.T[2:] *= 0.0
    avg = t_max / float(n + 1)
    times = np.linspace(avg, t_max - avg, n) + 2.0 * (rs.rand(n) - 0.5)
    return states, np.append(times, [np.inf], axis=0)


def _to_absolute(x_rel: np.ndarray) -> np.ndarray:
    """Upstream's (q1, q2, dq1, dq2), q2 relative -> pendulab's (theta1, theta2, omega1, omega2)."""
    return np.array([x_rel[0], x_rel[0] + x_rel[1], x_rel[2], x_rel[2] + x_rel[3]], dtype=float)


def _end_height(model: Model, x: np.ndarray) -> np.ndarray:
    """End-effector height above the pivot [m] of absolute states ``x`` (N, 4)."""
    p = model.params
    return -p.L1 * np.cos(x[:, 0]) - p.L2 * np.cos(x[:, 1])


def uptime(t: np.ndarray, height: np.ndarray, threshold: float) -> float:
    """``get_uptime``: the sum of ``diff(t, prepend=0)`` over the samples whose end effector is above ``threshold``.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Sample times [s] (the scored CSV's, starting at 0).
    height : ndarray, shape (N,)
        End-effector height [m].
    threshold : float
        ``0.9 (l1 + l2)`` [m].

    Returns
    -------
    float
        Uptime [s].
    """
    dt = np.diff(np.asarray(t, dtype=float), prepend=0.0)
    return float(np.sum(dt[np.asarray(height) > threshold]))


def count_swingups(t: np.ndarray, height: np.ndarray, threshold: float, deadtime: float = SWINGUP_DEADTIME) -> int:
    """``get_number_of_swingups`` (method "height"): rising edges above ``threshold``, at least ``deadtime`` apart.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Sample times [s].
    height : ndarray, shape (N,)
        End-effector height [m].
    threshold : float
        [m].
    deadtime : float
        [s].

    Returns
    -------
    int
        Number of swing-ups.
    """
    last_up_time, last_up, n = -deadtime, False, 0
    for tk, up in zip(t, np.asarray(height) > threshold, strict=True):
        if up and not last_up and (tk - last_up_time) > deadtime:
            n += 1
            last_up_time = tk
        last_up = bool(up)
    return n


class ProtocolController:
    """A pendulab sampled controller as an upstream entry: ``get_control_output_(x_rel, t) -> (tau1, tau2)``.

    The state is converted from upstream's relative angles to pendulab's absolute ones; the controller is
    called on its own sample grid (a multiple of 2 ms), restarted whenever a call follows a gap (a reset),
    its output scattered to (tau1, tau2) and clipped to the task's limit (6 N.m on the actuated joint,
    0 on the passive one). The wall time of every real call is recorded in :attr:`call_times`.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (which joint is driven).
    controller : SampledController
        Reset once, now.

    Raises
    ------
    ValueError
        Unknown task, or a sample time that is not a positive multiple of 2 ms.
    TypeError
        ``controller`` is not a sampled controller.
    """

    def __init__(self, task: str, controller: SampledController) -> None:
        check_task(task)
        if not (callable(controller) and hasattr(controller, "sample_time") and hasattr(controller, "input_names")):
            raise TypeError(
                f"controller must be a SampledController (callable with sample_time, input_names), got {type(controller)}"
            )
        h = float(controller.sample_time)
        ratio = round(h / DT) if math.isfinite(h) else 0
        if ratio < 1 or abs(ratio * DT - h) > 1e-9:
            raise ValueError(f"controller.sample_time must be a positive multiple of {DT} s, got {h!r}")
        self.controller = controller
        self.ratio = ratio
        self.limit = np.zeros(len(INPUT_NAMES))
        self.limit[TASKS[task]] = TORQUE_LIMIT
        self.call_times: list[float] = []
        self._held = np.zeros(len(INPUT_NAMES))
        self._last_t: float | None = None
        self._k = 0
        controller.reset()

    def get_control_output_(self, x: np.ndarray, t: float) -> np.ndarray:
        """Torques of the entry, upstream's call.

        Parameters
        ----------
        x : ndarray, shape (4,)
            Upstream state ``(q1, q2, dq1, dq2)``, ``q2`` relative [rad, rad/s].
        t : float
            Time [s].

        Returns
        -------
        ndarray, shape (2,)
            (tau1, tau2) [N.m], held on the controller's sample grid.
        """
        if self._last_t is None or t - self._last_t > 1.5 * DT:
            self._k = 0  # first call, or the first after a reset: sample now
        if self._k % self.ratio == 0:
            t0 = time.perf_counter()
            u = self.controller(t, _to_absolute(x))
            self.call_times.append(time.perf_counter() - t0)
            self._held = np.clip(full_input(self.controller, u), -self.limit, self.limit)
        self._k += 1
        self._last_t = t
        return self._held.copy()


@dataclass
class V3Result:
    """One v3 run: trajectory, reset schedule, uptime and score.

    Attributes
    ----------
    task, controller : str
        Task and controller name.
    seed : int
        Schedule seed.
    t : ndarray, shape (N,)
        Scored sample times [s] (N = 30000: 0 ... 59.998).
    x : ndarray, shape (N, 4)
        pendulab states (absolute angles) [rad, rad/s].
    u : ndarray, shape (N, 2)
        Applied torques (tau1, tau2) [N.m], held over [t_k, t_k + 2 ms].
    reset_times : ndarray, shape (n_resets,)
        Scheduled reset times [s].
    reset_states : ndarray, shape (n_resets, 4)
        The configurations the resets drive toward (upstream's relative angles, zero rates).
    intervals : list of (float, float)
        Actual reset intervals (PID active) [s].
    uptime : float
        [s].
    score : float
        ``uptime / 60``.
    n_swingups : int
        Swing-ups counted as upstream counts them.
    threshold : float
        Height line ``0.9 (L1 + L2)`` [m].
    call_times : ndarray
        Wall time of each controller call [s].
    wall_time : float
        Wall time of the run [s].
    """

    task: str
    controller: str
    seed: int
    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    reset_times: np.ndarray = field(repr=False)
    reset_states: np.ndarray = field(repr=False)
    intervals: list[tuple[float, float]] = field(repr=False)
    uptime: float
    score: float
    n_swingups: int
    threshold: float
    call_times: np.ndarray = field(repr=False)
    wall_time: float = 0.0

    @property
    def height(self) -> np.ndarray:
        """End-effector height [m] at each sample."""
        return _end_height(leaderboard_model(self.task), self.x)

    def interval_uptimes(self) -> list[dict[str, float]]:
        """Uptime per segment between resets (before the first reset, then from each reset's start).

        Returns
        -------
        list of dict
            ``start``, ``end`` [s], ``reset_end`` (end of the reset PID phase, None for the first segment),
            ``uptime`` [s] and ``fraction`` (uptime / segment length).
        """
        starts = [0.0, *(a for a, _ in self.intervals)]
        ends = [*(a for a, _ in self.intervals), float(self.t[-1]) + DT]
        dt = np.diff(self.t, prepend=0.0)
        up = self.height > self.threshold
        out = []
        for i, (a, b) in enumerate(zip(starts, ends, strict=True)):
            sel = (self.t >= a) & (self.t < b) & up
            value = float(np.sum(dt[sel]))
            out.append(
                {
                    "start": a,
                    "end": b,
                    "reset_end": None if i == 0 else float(self.intervals[i - 1][1]),
                    "uptime": value,
                    "fraction": value / (b - a) if b > a else 0.0,
                }
            )
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary.

        Returns
        -------
        dict
            protocol, task, controller, seed, score, uptime [s], n_swingups, per-interval uptimes, controller
            per-call time (median, max, count, against the 2 ms period), the best published entry and
            ``beats_published``, the reset schedule and the run's wall time.
        """
        name, best = max(PUBLISHED_V3[self.task].items(), key=lambda kv: kv[1])
        ct = np.asarray(self.call_times, dtype=float)
        return {
            "protocol": "v3",
            "task": self.task,
            "controller": self.controller,
            "seed": int(self.seed),
            "score": float(self.score),
            "uptime": float(self.uptime),
            "n_swingups": int(self.n_swingups),
            "intervals": self.interval_uptimes(),
            "controller_time": {
                "median_s": float(np.median(ct)) if ct.size else None,
                "max_s": float(np.max(ct)) if ct.size else None,
                "calls": int(ct.size),
                "period_s": DT,
                "median_fits_period": bool(ct.size and np.median(ct) <= DT),
            },
            "published_best": {"name": name, "score": best},
            "beats_published": bool(self.score > best),
            "reset_times": [float(v) for v in self.reset_times],
            "reset_states_relative": [[float(v) for v in row[:2]] for row in self.reset_states],
            "simulation": {
                "integrator": "rk4",
                "dt": DT,
                "t_final": T_FINAL_V3,
                "plant_torque_limit": [PLANT_LIMIT, PLANT_LIMIT],
                "entry_torque_limit": [TORQUE_LIMIT if i == TASKS[self.task] else 0.0 for i in range(2)],
                "n_resets": N_RESETS,
                "reset_length": RESET_LENGTH,
                "upstream": "dfki-ric-underactuated-lab/double_pendulum@1e8544e leaderboard/*/simulation_v3",
            },
            "wall_time_s": float(self.wall_time),
        }

    def write_csv(self, path: str | Path) -> Path:
        """Write ``t, theta1, theta2, omega1, omega2, tau1, tau2, height, reset`` (one row per 2 ms step), atomically.

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
        in_reset = np.zeros(len(self.t), dtype=bool)
        for a, b in self.intervals:
            in_reset |= (self.t >= a) & (self.t < b)
        h = self.height
        with atomic_open(p, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t", "theta1", "theta2", "omega1", "omega2", "tau1", "tau2", "height", "reset"])
            for k in range(len(self.t)):
                w.writerow(
                    [repr(float(self.t[k])), *(repr(float(v)) for v in self.x[k]), *(repr(float(v)) for v in self.u[k])]
                    + [repr(float(h[k])), int(in_reset[k])]
                )
        return p


def _gravity_compensation(model: Model) -> Callable[[np.ndarray], np.ndarray]:
    """``-G(q)`` of upstream's plant (joint torques holding the configuration), from pendulab's parameters."""
    p = model.params
    a1 = p.m1 * p.g * p.lc1 + p.m2 * p.g * p.L1
    a2 = p.m2 * p.g * p.lc2

    def comp(xr: np.ndarray) -> np.ndarray:
        s12 = math.sin(xr[0] + xr[1])
        return np.array([a1 * math.sin(xr[0]) + a2 * s12, a2 * s12])

    return comp


def run_v3(
    task: str,
    entry: Any,
    name: str = "custom",
    *,
    seed: int = 0,
    n_steps: int = N_STEPS_V3,
    progress: Callable[[int, int], None] | None = None,
) -> V3Result:
    """Run an entry through the v3 protocol on pendulab's model and score it.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    entry : SampledController or object with ``get_control_output_(x_rel, t)``
        A pendulab controller (wrapped in :class:`ProtocolController`) or an upstream-style entry
        (relative angles, returns (tau1, tau2)).
    name : str
        Controller name for the result.
    seed : int
        Schedule seed (:func:`reset_schedule`).
    n_steps : int
        RK4 steps (default the protocol's 30000; fewer for a shortened check).
    progress : callable, optional
        ``progress(done, total)`` in 2 ms steps, every 500 steps and at the end.

    Returns
    -------
    V3Result
        The scored run (the last state dropped, as upstream's CSV does).

    Raises
    ------
    ValueError
        Unknown task, bad ``seed``/``n_steps``, or a non-finite state.
    TypeError
        ``entry`` is neither.
    """
    check_task(task)
    n_steps = bounded_int("n_steps", n_steps, low=1, high=N_STEPS_V3, why="the protocol runs 30000 steps of 2 ms")
    states, times = reset_schedule(seed)
    if hasattr(entry, "get_control_output_"):
        proto = entry
    else:
        proto = ProtocolController(task, entry)
    model = leaderboard_model(task)
    grav = _gravity_compensation(model)
    kp, ki, kd = PID_GAINS
    errors1: list[float] = []
    errors2: list[float] = []
    goal = states[0]
    st: dict[str, Any] = {"mode": False, "timer": 0.0, "counter": 0, "last_t": 0.0, "start": 0.0}
    intervals: list[tuple[float, float]] = []
    last_u = np.zeros(len(INPUT_NAMES))
    t_wall = time.perf_counter()

    def pid(xr: np.ndarray) -> np.ndarray:
        e1, e2 = goal[0] - xr[0], goal[1] - xr[1]
        errors1.append(e1)
        errors2.append(e2)
        i1 = ki * np.sum(np.asarray(errors1)) * PID_DT
        i2 = ki * np.sum(np.asarray(errors2)) * PID_DT
        if len(errors1) > 2:
            d1 = kd * (errors1[-1] - errors1[-2]) / PID_DT
            d2 = kd * (errors2[-1] - errors2[-2]) / PID_DT
        else:
            d1 = d2 = 0.0
        u1 = np.clip(kp * e1 + i1 + d1, -PLANT_LIMIT, PLANT_LIMIT)
        u2 = np.clip(kp * e2 + i2 + d2, -PLANT_LIMIT, PLANT_LIMIT)
        return np.array([u1, u2], dtype=float)

    def policy(k: int, t: float, x: np.ndarray) -> np.ndarray:
        nonlocal goal, last_u
        if progress is not None and k % 500 == 0:
            progress(k, n_steps)
        xr = np.array([x[0], x[1] - x[0], x[2], x[3] - x[2]])
        if t >= times[st["counter"]] and not st["mode"]:
            st["mode"], st["timer"], st["start"] = True, 0.0, t
            goal = states[st["counter"]]
            st["counter"] += 1
        if st["timer"] > RESET_LENGTH and st["mode"]:
            st["mode"] = False
            intervals.append((float(st["start"]), float(t)))
        if st["mode"]:
            u = pid(xr) + grav(xr)
            st["timer"] += t - st["last_t"]
        else:
            u = np.asarray(proto.get_control_output_(xr, t), dtype=float)
        st["last_t"] = t
        # Simulator.get_real_applied_u: responsiveness 1 (last + 1 (u - last)), then the plant's [6, 6] clip.
        nu = np.clip(last_u + 1.0 * (u - last_u), -PLANT_LIMIT, PLANT_LIMIT)
        last_u = nu
        return nu

    t, x, u = rk4_rollout(model, model.state(), policy, n_steps)
    if progress is not None:
        progress(n_steps, n_steps)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"the v3 run of {name!r} on {task} produced a non-finite state")
    t, x = t[:n_steps], x[:n_steps]
    prm = model.params
    threshold = HEIGHT_FRACTION * (prm.L1 + prm.L2)
    h = _end_height(model, x)
    up = uptime(t, h, threshold)
    calls = np.asarray(getattr(proto, "call_times", []), dtype=float)
    return V3Result(
        task=task,
        controller=name,
        seed=int(seed),
        t=t,
        x=x,
        u=u,
        reset_times=times[:N_RESETS].copy(),
        reset_states=states[:N_RESETS].copy(),
        intervals=intervals,
        uptime=up,
        score=up / T_FINAL_V3,
        n_swingups=count_swingups(t, h, threshold),
        threshold=threshold,
        call_times=calls,
        wall_time=time.perf_counter() - t_wall,
    )


def v3_score(
    task: str,
    controller: str | SampledController = "global",
    *,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    out: str | Path | None = None,
) -> V3Result:
    """Score a controller on the RealAIGym v3 simulation protocol (60 s, 15 random resets, uptime / 60).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (``swingup_pendubot``/``swingup_acrobot`` are aliases).
    controller : str, SampledController or callable
        A name of :data:`pendulab.evaluate.realai.controllers.CONTROLLERS` (``"global"``: energy pumping and a
        verified LQR catch; ``"replan"``: online re-planning, not real time; ``"best"``, ``"robust"``, the task
        controllers), a controller object or a factory (:func:`~.controllers.resolve_controller`).
    seed : int
        Seed of the reset schedule (:func:`reset_schedule`).
    progress : callable, optional
        ``progress(done, total)`` in 2 ms steps.
    out : str or Path, optional
        Directory: writes ``v3.csv``, ``v3.png`` (height, resets, torques) and, last, ``v3.json``.

    Returns
    -------
    V3Result
        Score, uptime, schedule and trajectory.

    Raises
    ------
    ValueError
        Unknown task or controller name, bad seed, or a run that blew up.
    TypeError
        ``task`` not a string or ``controller`` neither a name nor a sampled controller.
    """
    from ...control.swingup.tasks import short_name

    if not isinstance(task, str):
        raise TypeError(f"task must be a leaderboard task name (one of {list(TASKS)}), got {type(task).__name__}")
    task = check_task(short_name(task))
    name, ctrl = resolve_controller(task, controller)
    result = run_v3(task, ctrl, name, seed=seed, progress=progress)
    if out is not None:
        from .v3_figure import plot_v3

        d = Path(out)
        d.mkdir(parents=True, exist_ok=True)
        result.write_csv(d / "v3.csv")
        plot_v3(result, d / "v3.png")
        atomic_write_text(d / "v3.json", json.dumps(result.to_dict(), indent=2) + "\n")
    return result

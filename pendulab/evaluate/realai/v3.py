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

import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..._checks import bounded_int
from ..._inputs import checked
from ..._io import atomic_write_text
from ...control.feedback import SampledController, full_input
from ...control.realai.adapter import from_realai, is_realai_controller
from ...control.realai.spec import DT, HEIGHT_FRACTION, TASKS, TORQUE_LIMIT, check_task
from ...model.model import INPUT_NAMES, Model
from ...model.plant_file import IdentifiedPlant
from .controllers import resolve_controller
from .plant import plant_label, protocol_model
from .simulate import rk4_rollout
from .v3_definition import (
    N_RESETS,
    N_STEPS_V3,
    PID_DT,
    PID_GAINS,
    PLANT_LIMIT,
    PUBLISHED_V3,
    PUBLISHED_V3_RUNS,
    RESET_LENGTH,
    T_FINAL_V3,
    _end_height,
    _to_absolute,
    count_swingups,
    reset_schedule,
    uptime,
)
from .v3_result import V3Result

__all__ = [
    "T_FINAL_V3",
    "N_STEPS_V3",
    "N_RESETS",
    "RESET_LENGTH",
    "PID_GAINS",
    "PUBLISHED_V3",
    "PUBLISHED_V3_RUNS",
    "V3Result",
    "ProtocolController",
    "RawEntry",
    "protocol_entry",
    "reset_schedule",
    "uptime",
    "count_swingups",
    "run_v3",
    "v3_score",
]


@checked()
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
    passive_limit : float
        Torque the passive joint may get [N.m] (0: the simulation rules; the ICRA 2025 hardware rules allow 0.5 N.m
        to compensate motor friction, :mod:`.v3_hardware`; upstream's simulator enforced only the plant's 6 N.m).
    gap : float
        A call more than this after the previous one follows a reset: the controller samples at once [s] (the
        hardware loop's intervals reach 3.7 ms, so it widens this).

    Raises
    ------
    ValueError
        Unknown task, or a sample time that is not a positive multiple of 2 ms.
    TypeError
        ``controller`` is not a sampled controller.
    """

    def __init__(self, task: str, controller: SampledController, *, passive_limit: float = 0.0, gap: float = 1.5 * DT) -> None:
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
        self.limit = _entry_limits(task, passive_limit)
        self.gap = float(gap)
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
        if self._last_t is None or t - self._last_t > self.gap:
            self._k = 0  # first call, or the first after a reset: sample now
        if self._k % self.ratio == 0:
            t0 = time.perf_counter()
            u = self.controller(t, _to_absolute(x))
            self.call_times.append(time.perf_counter() - t0)
            self._held = np.clip(full_input(self.controller, u, t), -self.limit, self.limit)
        self._k += 1
        self._last_t = t
        return self._held.copy()


def _entry_limits(task: str, passive_limit: float) -> np.ndarray:
    """(tau1, tau2) bounds of an entry's output [N.m]: the task's 6 N.m on the driven joint, ``passive_limit`` on the other."""
    limit = np.zeros(len(INPUT_NAMES))
    limit[TASKS[task]] = TORQUE_LIMIT
    limit[1 - TASKS[task]] = float(passive_limit)
    return limit


@checked()
class RawEntry:
    """An upstream-style entry called raw, as upstream's ``GlobalPolicyTestingControllerV2`` calls it, under the rules.

    ``get_control_output_(x_rel, t)`` is called on every loop step (upstream's wrapper neither filters nor calls
    ``init``/``reset``); its wall time is recorded in :attr:`call_times` and its output clipped to the protocol's
    limits, as a pendulab controller's is (:class:`ProtocolController`).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (which joint is driven).
    entry : object
        Has ``get_control_output_(x_rel, t) -> (tau1, tau2)``.
    passive_limit : float
        Torque the passive joint may get [N.m].

    Raises
    ------
    ValueError
        Unknown task.
    TypeError
        ``entry`` has no ``get_control_output_``.
    """

    #: An upstream entry commands both joints, (tau1, tau2), for :func:`~pendulab.control.feedback.full_input`.
    input_names: tuple[str, ...] = tuple(INPUT_NAMES)

    def __init__(self, task: str, entry: Any, *, passive_limit: float = 0.0) -> None:
        check_task(task)
        if not callable(getattr(entry, "get_control_output_", None)):
            raise TypeError(f"entry must have get_control_output_(x_rel, t), got {type(entry).__name__}")
        self.entry = entry
        self.limit = _entry_limits(task, passive_limit)
        self.call_times: list[float] = []

    def get_control_output_(self, x: np.ndarray, t: float) -> np.ndarray:
        """The entry's torques, clipped to the limits, upstream's call.

        Parameters
        ----------
        x : ndarray, shape (4,)
            Upstream state ``(q1, q2, dq1, dq2)``, ``q2`` relative [rad, rad/s].
        t : float
            Time [s].

        Returns
        -------
        ndarray, shape (2,)
            (tau1, tau2) [N.m].

        Raises
        ------
        ControllerOutputError
            The entry returned something other than two finite torques (a ``ValueError``).
        """
        t0 = time.perf_counter()
        u = self.entry.get_control_output_(x, t)
        self.call_times.append(time.perf_counter() - t0)
        return np.clip(full_input(self, u, t, who=type(self.entry).__name__), -self.limit, self.limit)


@checked()
def protocol_entry(task: str, entry: Any, *, passive_limit: float = 0.0, gap: float = 1.5 * DT) -> ProtocolController | RawEntry:
    """The one way an entry enters a v3 protocol: timed, and its torques clipped to the rules.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    entry : ProtocolController, RawEntry, SampledController or upstream controller
        A protocol wrapper (kept: it is one); an object with ``get_control_output_`` (every upstream
        ``AbstractController`` has it) -> :class:`RawEntry`, called raw as upstream's wrapper does; an object with
        only upstream's public interface (``init``, ``get_control_output``, ``reset``) -> through
        :func:`~pendulab.control.realai.adapter.from_realai` at 2 ms; a pendulab controller -> :class:`ProtocolController`.
    passive_limit : float
        Torque the passive joint may get [N.m] (the rules: 0 in simulation, up to 0.5 on hardware).
    gap : float
        A call this long after the previous one follows a reset [s] (:class:`ProtocolController`).

    Returns
    -------
    ProtocolController or RawEntry
        Records ``call_times``. The runners clip its output to the same limits again
        (``_entry_torque``), so a wrapper built elsewhere with wider limits cannot break the rules either.

    Raises
    ------
    ValueError
        Unknown task, or a controller sample time that is not a multiple of 2 ms.
    TypeError
        ``entry`` is none of these.
    """
    if isinstance(entry, (ProtocolController, RawEntry)):
        return entry
    if hasattr(entry, "get_control_output_"):
        return RawEntry(task, entry, passive_limit=passive_limit)
    ctrl = from_realai(entry, task=task) if is_realai_controller(entry) else entry
    return ProtocolController(task, ctrl, passive_limit=passive_limit, gap=gap)


def _entry_torque(proto: ProtocolController | RawEntry, x_rel: np.ndarray, t: float, limit: np.ndarray) -> np.ndarray:
    """The entry's torques at upstream state ``x_rel``, clipped to the protocol's ``limit`` (2,) [N.m].

    Raises
    ------
    ValueError
        The state is not finite (the run diverged: the entry is not called, so it is not blamed for the NaN
        torques such a state gives), or the entry returned something other than two finite torques (both
        wrappers check their output with :func:`~pendulab.control.feedback.full_input`).
    """
    if not np.all(np.isfinite(x_rel)):
        raise ValueError(f"the v3 run produced a non-finite state at t = {t:.6g} s (before the entry was called)")
    return np.clip(proto.get_control_output_(x_rel, t), -limit, limit)


def _gravity_compensation(model: Model) -> Callable[[np.ndarray], np.ndarray]:
    """``-G(q)`` of upstream's plant (joint torques holding the configuration), from pendulab's parameters."""
    p = model.params
    a1 = p.m1 * p.g * p.lc1 + p.m2 * p.g * p.L1
    a2 = p.m2 * p.g * p.lc2

    def comp(xr: np.ndarray) -> np.ndarray:
        s12 = math.sin(xr[0] + xr[1])
        return np.array([a1 * math.sin(xr[0]) + a2 * s12, a2 * s12])

    return comp


@checked(seed="legacy_seed")
def run_v3(
    task: str,
    entry: Any,
    name: str = "custom",
    *,
    seed: int = 0,
    n_steps: int = N_STEPS_V3,
    progress: Callable[[int, int], None] | None = None,
    plant: IdentifiedPlant | None = None,
    passive_limit: float = 0.0,
    schedule: str = "current",
) -> V3Result:
    """Run an entry through the v3 protocol on pendulab's model and score it.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    entry : SampledController or object with ``get_control_output_(x_rel, t)``
        A pendulab controller (wrapped in :class:`ProtocolController`) or an upstream-style entry
        (relative angles, returns (tau1, tau2)), called raw as upstream's v3 calls its entry (:class:`RawEntry`);
        an object with only upstream's public interface (``init``, ``get_control_output``, ``reset``) runs
        through :func:`~pendulab.control.realai.adapter.from_realai` at 2 ms (:func:`protocol_entry`). Whatever
        the kind, its torques are clipped to the rules and its calls timed.
    name : str
        Controller name for the result.
    seed : int
        Schedule seed (:func:`reset_schedule`).
    n_steps : int
        RK4 steps (default the protocol's 30000; fewer for a shortened check).
    progress : callable, optional
        ``progress(done, total)`` in 2 ms steps, every 500 steps and at the end.
    plant : IdentifiedPlant, optional
        Simulate an identified robot (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.
    passive_limit : float
        Torque the entry may put on the passive joint [N.m]. The rules: 0 (default). Upstream's simulator enforced
        only the plant's 6 N.m, so its published runs are reproduced with 6.
    schedule : {"current", "published"}
        How the resets are drawn from ``seed`` (:func:`reset_schedule`): upstream's current code, or as the
        published ICRA 2025 simulation runs drew them (seed 777 pendubot, 333 acrobot reproduce those runs).

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
    states, times = reset_schedule(seed, schedule=schedule)
    proto = protocol_entry(task, entry, passive_limit=passive_limit)
    limit = _entry_limits(task, passive_limit)
    model = protocol_model(task, plant)
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
            u = _entry_torque(proto, xr, t, limit)
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
    calls = np.asarray(proto.call_times, dtype=float)
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
        plant=plant_label(plant),
        link_lengths=(prm.L1, prm.L2),
        passive_limit=float(passive_limit),
        schedule=schedule,
    )


@checked(seed="legacy_seed")
def v3_score(
    task: str,
    controller: str | SampledController = "global",
    *,
    seed: int = 0,
    progress: Callable[[int, int], None] | None = None,
    out: str | Path | None = None,
    plant: IdentifiedPlant | None = None,
    schedule: str = "current",
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
    plant : IdentifiedPlant, optional
        Simulate an identified robot (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.
    schedule : {"current", "published"}
        Reset draw (:func:`reset_schedule`); ``"published"`` with seed 333 / 777 is the published runs' schedule.

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
    result = run_v3(task, ctrl, name, seed=seed, progress=progress, plant=plant, schedule=schedule)
    if out is not None:
        from .v3_figure import plot_v3

        d = Path(out)
        d.mkdir(parents=True, exist_ok=True)
        result.write_csv(d / "v3.csv")
        plot_v3(result, d / "v3.png")
        atomic_write_text(d / "v3.json", json.dumps(result.to_dict(), indent=2) + "\n")
    return result

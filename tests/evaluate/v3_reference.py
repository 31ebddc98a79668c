"""RealAIGym's v3 simulation run restated independently, in upstream's conventions, as a test oracle.

Written for pendulab from the behaviour of github.com/dfki-ric-underactuated-lab/double_pendulum
at commit 1e8544e67f3da72a51ee52fbbb278e131ce2a43f (BSD-3-Clause; copyright the DFKI
Underactuated Lab): ``leaderboard/{pendubot,acrobot}/simulation_v3`` (model 1.1 of design C.1 with
Ir, b, cf = 0, the simulated plant limited at [6, 6], ``GlobalPolicyTestingControllerV2(controller,
n_disturbances=15, t_max=60, reset_length=0.2, mpar=mpar_nolim)``),
``controller/global_policy_testing_controller.py`` (the reset schedule and the switch between the entry
and the reset PID), ``controller/pid/point_pid_controller.py`` and ``controller/abstract_controller.py``
(PID, gravity compensation), ``simulation/simulation.py`` (measurement, applied torque, RK4 step, process
noise, 30000 steps with ``t`` accumulated in floats), ``utils/csv_trajectory.py`` (the shortest column is
kept) and ``analysis/leaderboard.py`` (uptime above 0.9 (l1 + l2), score = uptime / 60).

It is a restatement, not a copy of that code (the project does not carry upstream's source): plain
functions and small dataclasses, written from what upstream computes, keeping what the numbers depend on
(the order of floating-point operations where it changes round-off, NumPy's *global* generator called
where and as often as upstream calls it) and differing from pendulab's ``pendulab.evaluate.realai.v3``
where an independent check needs it:

* joint coordinates throughout (``q2`` relative to link 1), not pendulab's absolute angles;
* the equations of motion typed as the lecture formulas (mass, Coriolis, gravity matrices, friction
  vector, ``inv(M)``), not derived by CasADi from a Lagrangian;
* the schedule drawn from ``np.random.uniform`` / ``np.random.rand`` after ``np.random.seed(seed)``
  (upstream leaves the global generator unseeded; the seed stands for its state), and the zero-width
  ``np.random.normal`` draws of measurement, torque and process noise made every step as upstream makes them.

``real_upstream_run()`` runs upstream's own package instead when ``PENDULAB_UPSTREAM_DOUBLE_PENDULUM``
names its ``src/python`` directory (a local checkout), so the same comparison can run the original.
"""

from __future__ import annotations

import math
import os
import sys
import types
from dataclasses import dataclass, field

import numpy as np

# design_C.1/model_1.1: the v3 scripts also set Ir, b and cf to zero.
MASS = (0.5234602302310271, 0.6255677234174437)
LENGTH = (0.2, 0.3)
COM = (0.2, 0.25569305436052964)
INERTIA = (0.031887199591513114, 0.05086984812807257)
GRAVITY = 9.81
ROTOR_INERTIA, GEAR_RATIO = 0.0, 6.0
DAMPING, COULOMB = (0.0, 0.0), (0.0, 0.0)
PLANT_LIMIT = (6.0, 6.0)  # mpar_nolim: what the simulator clips to and the reset PID is limited by
HEIGHT_FRACTION = 0.9
N_RESETS, T_MAX, RESET_LENGTH = 15, 60.0, 0.2
PID_GAINS, PID_DT = (10.0, 0.1, 1.0), 0.001

# The plant's input matrix: upstream builds it from the constructor's default (inf, inf) limit, i.e. both
# joints actuated, also for the gravity compensation's plant.
_INPUT = np.eye(2)


def lecture_matrices(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mass matrix, Coriolis matrix, gravity vector and friction vector at state ``x`` (joint coordinates)."""
    m1, m2 = MASS
    l1 = LENGTH[0]
    r1, r2 = COM
    j1, j2 = INERTIA
    jr, n = ROTOR_INERTIA, GEAR_RATIO
    cq2, sq2 = np.cos(x[1]), np.sin(x[1])
    coupling = m2 * l1 * r2  # every off-diagonal term is a multiple of it (factors of 2 are exact)
    off = j2 + coupling * cq2 - n * jr
    mass = np.array([[j1 + j2 + m2 * l1**2.0 + 2 * coupling * cq2 + n**2.0 * jr + jr, off], [off, j2 + n**2.0 * jr]])
    coriolis = np.array([[-2 * coupling * sq2 * x[3], -coupling * sq2 * x[3]], [coupling * sq2 * x[2], 0.0]])
    s1, s12 = np.sin(x[0]), np.sin(x[0] + x[1])
    grav = np.array([-m1 * GRAVITY * r1 * s1 - m2 * GRAVITY * (l1 * s1 + r2 * s12), -m2 * GRAVITY * r2 * s12])
    fric = np.array([DAMPING[k] * x[2 + k] + COULOMB[k] * np.arctan(100 * x[2 + k]) for k in range(2)])
    return mass, coriolis, grav, fric


def state_derivative(x: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``d/dt (q1, q2, dq1, dq2)`` under joint torques ``tau``: ``inv(M) (G + B tau - C dq - F)``."""
    mass, coriolis, grav, fric = lecture_matrices(x)
    ddq = np.linalg.inv(mass) @ ((grav + _INPUT @ tau - coriolis @ x[2:]) - fric)
    return np.array([x[2], x[3], ddq[0], ddq[1]])


def rk4_increment(x: np.ndarray, tau: np.ndarray, dt: float) -> np.ndarray:
    """The classical Runge-Kutta slope over one step of ``dt`` with ``tau`` held (to be multiplied by ``dt``)."""
    k1 = state_derivative(x, tau)
    k2 = state_derivative(x + 0.5 * dt * k1, tau)
    k3 = state_derivative(x + 0.5 * dt * k2, tau)
    k4 = state_derivative(x + dt * k3, tau)
    return (k1 + 2.0 * (k2 + k3) + k4) / 6.0


def draw_schedule(n_resets: int = N_RESETS, t_max: float = T_MAX) -> tuple[np.ndarray, np.ndarray]:
    """Reset targets ``(10 n + 1, 4)`` (configurations at rest) and times ``(n + 1,)`` (last ``inf``), global generator."""
    targets = np.random.uniform(0.0, 2 * np.pi, (10 * n_resets + 1, 4))
    targets -= np.pi
    targets[:, 2:] *= 0.0
    spacing = t_max / float(n_resets + 1)
    times = np.linspace(spacing, t_max - spacing, n_resets) + 2.0 * (np.random.rand(n_resets) - 0.5)
    return targets, np.concatenate([times, [math.inf]])


@dataclass
class ResetPID:
    """The reset phase's PID on joint angles: error history kept over every reset, angles not wrapped."""

    goal: np.ndarray = field(default_factory=lambda: np.array([np.pi, 0.0, 0.0, 0.0]))
    history: tuple[list, list] = field(default_factory=lambda: ([], []))

    def torque(self, x: np.ndarray) -> np.ndarray:
        kp, ki, kd = PID_GAINS
        out = []
        for j in range(2):
            errs = self.history[j]
            errs.append(self.goal[j] - x[j])
            integral = ki * np.sum(np.asarray(errs)) * PID_DT
            rate = kd * (errs[-1] - errs[-2]) / PID_DT if len(errs) > 2 else 0.0
            out.append(np.clip(kp * errs[-1] + integral + rate, -PLANT_LIMIT[j], PLANT_LIMIT[j]))
        return np.asarray(out)


@dataclass
class ResetProtocol:
    """State of the v3 wrapper around an entry: schedule, PID, and which of the two is in charge."""

    targets: np.ndarray
    times: np.ndarray
    pid: ResetPID = field(default_factory=ResetPID)
    resetting: bool = False
    done: int = 0
    timer: float = 0.0
    start: float = 0.0
    previous_t: float = 0.0
    intervals: list[tuple[float, float]] = field(default_factory=list)


def protocol_torque(p: ResetProtocol, entry, x: np.ndarray, t: float) -> np.ndarray:
    """The torque the wrapped entry asks for at ``(x, t)``, with the reset PID and ``-G(q)`` while resetting.

    ``entry.get_control_output_(x, t)`` gets the (unfiltered) measured joint-coordinate state. Upstream's
    position and velocity limits are infinite in v3, so a limit never triggers a reset here.
    """
    if not p.resetting and t >= p.times[p.done]:
        p.resetting, p.timer, p.start = True, 0.0, t
        p.pid.goal = p.targets[p.done]
        p.done += 1
    if p.resetting and p.timer > RESET_LENGTH:
        p.resetting = False
        p.intervals.append((p.start, t))
    if p.resetting:
        u = p.pid.torque(x)
        p.timer += t - p.previous_t
    else:
        u = np.asarray(entry.get_control_output_(x, t))
    p.previous_t = t
    _, _, grav, _ = lecture_matrices(x)
    compensation = -(_INPUT @ grav) if p.resetting else np.zeros(2)
    return u + np.zeros(2) + compensation  # the zero is upstream's friction compensation (no friction terms)


@dataclass
class V3Run:
    """One v3 run as upstream records it: ``t`` (n,), joint-coordinate ``x`` (n, 4), applied ``u`` (n, 2)."""

    reset_times: np.ndarray
    reset_states: np.ndarray
    intervals: list[tuple[float, float]]
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    uptime: float


def end_effector_height(x: np.ndarray) -> np.ndarray:
    """Height of the tip above the shoulder for joint-coordinate states ``x`` (n, 4), m."""
    return -LENGTH[0] * np.cos(x[:, 0]) - LENGTH[1] * np.cos(x[:, 0] + x[:, 1])


def uptime_of(t: np.ndarray, x: np.ndarray) -> float:
    """Seconds above ``0.9 (l1 + l2)``: each sample above the line counts the time since the previous one."""
    above = end_effector_height(x) > HEIGHT_FRACTION * (LENGTH[0] + LENGTH[1])
    return float(np.sum(np.diff(t, prepend=0.0)[above]))


def run_v3(entry, task: str, seed: int, n_steps: int = 30000, dt: float = 0.002) -> V3Run:
    """Upstream's v3 run of ``entry`` after ``np.random.seed(seed)``, from rest hanging down.

    ``task`` only names the scoring limit in upstream; the simulated plant is the same for both tasks.
    Rows are cut to the shortest column as ``save_trajectory`` does (the state after the last step is dropped).
    """
    if task not in ("pendubot", "acrobot"):
        raise ValueError(f"task must be 'pendubot' or 'acrobot', got {task!r}")
    np.random.seed(seed)
    protocol = ResetProtocol(*draw_schedule())
    x, t = np.zeros(4), 0.0
    ts, xs, us = [t], [x.copy()], []
    for _ in range(n_steps):
        last = np.asarray(us[-1]) if us else np.zeros(2)
        fed_through = np.asarray(us[-1]) if len(us) > 1 else np.zeros(2)  # upstream's D-term input, times D = 0
        measured = np.random.normal(np.eye(4) @ x + np.zeros((4, 2)) @ fed_through, [0.0] * 4, (4,))
        wanted = protocol_torque(protocol, entry, measured, t)
        applied = np.random.normal(last + 1.0 * (np.copy(wanted) - last), [0.0] * 2, (2,))
        applied[0] = np.clip(applied[0], -PLANT_LIMIT[0], PLANT_LIMIT[0])
        applied[1] = np.clip(applied[1], -PLANT_LIMIT[1], PLANT_LIMIT[1])
        x = np.add(x, dt * rk4_increment(x, applied, dt), casting="unsafe")
        x = np.random.normal(x, [0.0] * 4, (4,))
        t += dt
        ts.append(t)
        xs.append(x.copy())
        us.append(list(applied))
    n = min(len(ts), len(xs), len(us))
    t_arr, x_arr, u_arr = np.asarray(ts)[:n], np.asarray(xs)[:n], np.asarray(us)[:n]
    return V3Run(protocol.times, protocol.targets, protocol.intervals, t_arr, x_arr, u_arr, uptime_of(t_arr, x_arr))


def real_upstream() -> types.ModuleType | None:
    """Upstream's own ``double_pendulum`` package from ``$PENDULAB_UPSTREAM_DOUBLE_PENDULUM`` (its ``src/python``), or None."""
    path = os.environ.get("PENDULAB_UPSTREAM_DOUBLE_PENDULUM")
    if not path or not os.path.isdir(os.path.join(path, "double_pendulum")):
        return None
    if path not in sys.path:
        sys.path.insert(0, path)
    sys.modules.setdefault("pandas", types.ModuleType("pandas"))  # imported by a CSV helper the run never calls
    import double_pendulum

    return double_pendulum


def real_upstream_run(entry, task: str, seed: int, n_steps: int = 30000, dt: float = 0.002) -> V3Run | None:
    """The same run with upstream's own classes (``None`` without a checkout): its wrapper, plant and simulator."""
    if real_upstream() is None:
        return None
    from double_pendulum.analysis.leaderboard import get_uptime
    from double_pendulum.controller.global_policy_testing_controller import GlobalPolicyTestingControllerV2
    from double_pendulum.model.model_parameters import model_parameters
    from double_pendulum.model.plant import DoublePendulumPlant
    from double_pendulum.simulation.simulation import Simulator

    def pars(limit):
        return model_parameters(
            mass=list(MASS),
            length=list(LENGTH),
            com=list(COM),
            damping=list(DAMPING),
            cfric=list(COULOMB),
            gravity=GRAVITY,
            inertia=list(INERTIA),
            motor_inertia=ROTOR_INERTIA,
            gear_ratio=GEAR_RATIO,
            torque_limit=list(limit),
        )

    class Entry:  # upstream calls get_control_output_ only; give it upstream's abstract hooks too
        def get_control_output_(self, x, t):
            return entry.get_control_output_(x, t)

        def init_(self):
            pass

    score_pars = pars([6.0, 0.0] if task == "pendubot" else [0.0, 6.0])
    np.random.seed(seed)
    wrapper = GlobalPolicyTestingControllerV2(
        Entry(), n_disturbances=N_RESETS, t_max=T_MAX, reset_length=RESET_LENGTH, mpar=pars(PLANT_LIMIT)
    )
    sim = Simulator(plant=DoublePendulumPlant(model_pars=pars(PLANT_LIMIT)))
    x0 = np.zeros(4)
    sim.set_state(0.0, x0)
    sim.reset_data_recorder()
    sim.record_data(0.0, np.copy(x0), None)
    for _ in range(n_steps):
        sim.controller_step(dt, wrapper, integrator="runge_kutta")
    n = min(len(sim.t_values), len(sim.x_values), len(sim.tau_values))
    t_arr, x_arr, u_arr = (np.asarray(v)[:n] for v in (sim.t_values, sim.x_values, sim.tau_values))
    intervals = [tuple(iv) for iv in wrapper.disturbance_intervals]
    uptime = float(get_uptime(t_arr, x_arr, mpar=score_pars, method="height", height=HEIGHT_FRACTION))
    return V3Run(wrapper.reset_times, wrapper.random_states, intervals, t_arr, x_arr, u_arr, uptime)

"""One closed-loop episode under perturbations: the plant and controller wrappers of the robustness scorecard.

The plant advances one controller sample at a time with a fixed-step RK4
(``n_sub`` equal substeps per sample, chosen from the fastest mode of the plant,
see :func:`substeps`) on the model's own ``rhs`` CasADi Function. The whole
sample (all substeps and the end-effector height) is one JIT-compiled CasADi
Function evaluated in place through its buffer interface (~2 us per sample), so
the episode's cost is the controller's and the loop's.

Perturbations (:class:`Perturbation`), in the order they act within a sample:

1. time delay: the controller sees the state of ``delay`` seconds ago
   (rounded to whole samples; before t = 0 it sees the start state);
2. measurement noise: Gaussian noise on the measured link rates ``omega1, omega2``;
3. the controller's torque command is checked (finite, right size, within the
   task's torque limit, no torque on a passive joint), else the run fails;
4. torque response: the applied torque follows the command with a
   responsiveness factor ``r`` (``u_a <- u_a + r (u - u_a)`` per sample; 1 = ideal);
5. torque noise: Gaussian noise on the driven torques, then the actuator
   saturates at the torque limit;
6. pushes: Gaussian-shaped torque pulses on both joints at random times;
7. model errors: the plant's parameters differ from the design model's, and an
   optional Coulomb friction ``-cf tanh(rate / 0.05 rad/s)`` per joint (the model
   has viscous joint damping ``b1, b2`` but no Coulomb friction, so it lives
   here as an external torque).
"""

from __future__ import annotations

import atexit
import math
import os
import shutil
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from .._inputs import checked
from ..analysis.equilibria import equilibrium
from ..control.feedback import SampledController
from ..model.model import INPUT_NAMES, Model, model_functions
from .measurement import MeasurementModel

if TYPE_CHECKING:
    from ..control.swingup.tasks import Task

__all__ = ["Perturbation", "EpisodeResult", "run_perturbed_episode", "substeps", "FRICTION_SMOOTHING", "MAX_SUBSTEP"]

#: Rate scale [rad/s] of the smooth Coulomb friction ``-cf tanh(rate / FRICTION_SMOOTHING)``.
FRICTION_SMOOTHING = 0.05
#: Largest RK4 substep [s] (RealAIGym simulates with RK4 at 2 ms).
MAX_SUBSTEP = 0.002
# RK4 is stable up to h w = 2.83 on an undamped oscillator; h w <= 0.5 keeps the fastest mode's
# amplitude error per step below (0.5)^6 / 144 ~ 1e-4.
_H_OMEGA = 0.5


@dataclass(frozen=True)
class Perturbation:
    """What differs from the nominal closed loop in one episode.

    Attributes
    ----------
    params : Mapping[str, float]
        Plant parameters that differ from the design model (SI units), e.g. ``{"m1": 0.6}``.
    friction : (float, float)
        Coulomb friction torque of joints 1 and 2 [N.m] (>= 0).
    meas_noise : float
        Standard deviation of the Gaussian noise on the measured ``omega1, omega2`` [rad/s].
    torque_noise : float
        Standard deviation of the Gaussian noise on the driven torques [N.m].
    response : float
        Torque responsiveness factor per sample (1 = the torque follows the command at once).
    delay : float
        Measurement delay [s] (rounded to whole controller samples).
    push_amplitude : float
        Largest push amplitude [N.m]; each push has a random amplitude in
        ``[push_amplitude / 2, push_amplitude]`` and a random sign. 0: no pushes.
    pushes_per_joint : int
        Number of pushes per joint (at random times at least 1 s apart).
    seed : int or tuple of int
        Seed of the episode's random generator (noise and pushes).

    Examples
    --------
    >>> from pendulab.control import controller_for_task
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("pendubot")  # RealAIGym's C.1 robot, shoulder driven, 6 N.m, 10 s
    >>> controller, x0 = controller_for_task("swingup", task)  # energy pumping, then LQR balance
    >>> from pendulab.evaluate import Perturbation, run_perturbed_episode
    >>> sticky = Perturbation(friction=(0.1, 0.1))  # Coulomb friction the design model lacks [N.m]
    >>> run_perturbed_episode(controller, task, x0, sticky).success
    True
    >>> heavier = Perturbation(params={"m2": 1.25 * task.model.params.m2})  # plant link 2 heavier than designed
    >>> result = run_perturbed_episode(controller, task, x0, heavier)
    >>> result.success, result.reason
    (False, 'end effector below 0.45 m in the last second (min -0.425 m)')
    """

    params: Mapping[str, float] = field(default_factory=dict)
    friction: tuple[float, float] = (0.0, 0.0)
    meas_noise: float = 0.0
    torque_noise: float = 0.0
    response: float = 1.0
    delay: float = 0.0
    push_amplitude: float = 0.0
    pushes_per_joint: int = 3
    seed: int | tuple[int, ...] = 0

    def __post_init__(self) -> None:
        for name in ("meas_noise", "torque_noise", "delay", "push_amplitude"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        if not (isinstance(self.response, int | float) and math.isfinite(self.response) and self.response > 0):
            raise ValueError(f"response must be a finite number > 0, got {self.response!r}")
        if len(self.friction) != 2 or not all(math.isfinite(c) and c >= 0 for c in self.friction):
            raise ValueError(f"friction must be two finite torques >= 0 [N.m], got {self.friction!r}")


@dataclass(frozen=True)
class EpisodeResult:
    """Outcome of one closed-loop episode.

    Attributes
    ----------
    success : bool
        RealAIGym criterion: end effector at or above ``threshold`` over the last
        second, every torque command finite and within the limit, plant finite.
    reason : str
        Why it failed ("" on success).
    t_up : float
        Start of the final stretch above the threshold [s] (nan if not above at the end).
    threshold : float
        ``fraction * (L1 + L2)`` of the plant [m].
    t : ndarray, shape (K + 1,)
        Sample times [s].
    x : ndarray, shape (K + 1, nx)
        True plant states at the samples (rows after a failure are nan).
    u : ndarray, shape (K, 2)
        Applied torques (tau1, tau2) per sample, pushes excluded [N.m].
    height : ndarray, shape (K + 1,)
        End-effector height y2 [m].

    Examples
    --------
    >>> from pendulab.control import controller_for_task
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("pendubot")  # RealAIGym's C.1 robot, shoulder driven, 6 N.m, 10 s
    >>> controller, x0 = controller_for_task("swingup", task)  # energy pumping, then LQR balance
    >>> from pendulab.evaluate import run_perturbed_episode
    >>> episode = run_perturbed_episode(controller, task, x0)
    >>> episode.success, episode.t_up, episode.threshold  # up from 5.13 s on; the line is 0.9 (L1 + L2) [m]
    (True, 5.13, 0.45)
    >>> episode.t.shape, episode.x.shape, episode.u.shape  # 1000 samples of 10 ms
    ((1001,), (1001, 4), (1000, 2))
    >>> bool(episode.height[-100:].min() >= episode.threshold)  # above the line over the last second
    True
    """

    success: bool
    reason: str
    t_up: float
    threshold: float
    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    height: np.ndarray = field(repr=False)


def substeps(model: Model, sample_time: float, x0: np.ndarray | None = None) -> int:
    """Number of RK4 substeps per controller sample for ``model``.

    The substep is at most :data:`MAX_SUBSTEP` and at most ``0.5 / w_max``, where
    ``w_max`` is the largest eigenvalue modulus of the Jacobian at the upright
    equilibrium and at ``x0`` (the springs of an elastic model).

    Parameters
    ----------
    model : Model
        Plant.
    sample_time : float
        Controller sample time [s], > 0.
    x0 : ndarray, shape (nx,), optional
        A second state at which to measure the fastest mode (the start).

    Returns
    -------
    int
        ``n_sub >= 1`` with ``sample_time / n_sub`` within both bounds.

    Raises
    ------
    ValueError
        Non-positive ``sample_time``.
    """
    if not (math.isfinite(sample_time) and sample_time > 0):
        raise ValueError(f"sample_time must be a finite number > 0 [s], got {sample_time!r}")
    states = [equilibrium(model, "up-up").x] + ([] if x0 is None else [np.asarray(x0, dtype=float)])
    jac = model.functions["jac_rhs"]
    w_max = max(float(np.max(np.abs(np.linalg.eigvals(np.asarray(jac(x, np.zeros(2), model.p)[0]))))) for x in states)
    h = min(MAX_SUBSTEP, _H_OMEGA / w_max) if w_max > 0 else MAX_SUBSTEP
    return max(1, math.ceil(sample_time / h - 1e-9))


@cache
def _jit_directory() -> str:
    """A private temporary directory (one per process) for the generated sources and libraries, removed at exit."""
    folder = tempfile.mkdtemp(prefix="pendulab-jit-")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    return folder


@cache
def _sample_map(kind: str, n_sub: int) -> ca.Function:
    """``F([x; u; p; cf; h]) -> [x+; y2+]``: ``n_sub`` RK4 steps of ``h`` with held ``u`` and smooth Coulomb friction ``cf``.

    One packed input and output (evaluated through ``Function.buffer``) and a JIT-compiled body keep a call at
    ~2 us (the SX virtual machine needs ~40 us for the 20 right-hand sides of a rigid sample); without a C
    compiler the SX Function is used as is.
    """
    fns = model_functions(kind)
    rhs, pos = fns["rhs"], fns["positions"]
    nx, npar = rhs.size1_in(0), rhs.size1_in(2)
    nq = nx // 2
    x, u, p = ca.SX.sym("x", nx), ca.SX.sym("u", 2), ca.SX.sym("p", npar)
    cf, h = ca.SX.sym("cf", 2), ca.SX.sym("h")

    def f(z: ca.SX) -> ca.SX:
        w1, w2 = z[nq], z[nq + 1]
        # Joint torques: tau1 acts on omega1 (ground-link 1), tau2 on omega2 - omega1 (link 1-link 2).
        fric = ca.vertcat(-cf[0] * ca.tanh(w1 / FRICTION_SMOOTHING), -cf[1] * ca.tanh((w2 - w1) / FRICTION_SMOOTHING))
        return rhs(z, u + fric, p)

    z = x
    for _ in range(n_sub):
        k1 = f(z)
        k2 = f(z + h / 2 * k1)
        k3 = f(z + h / 2 * k2)
        k4 = f(z + h * k3)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    name = f"sample_rk4_{kind}_{n_sub}"
    fn = ca.Function(name, [ca.vertcat(x, u, p, cf, h)], [ca.vertcat(z, pos(z, p)[3])])
    try:
        return _compiled(fn)
    except RuntimeError:  # no C compiler (or it failed): same function, interpreted
        return fn


def _compiled(fn: ca.Function) -> ca.Function:
    """``fn`` generated as C, compiled by the project's compiler runner and loaded (``casadi.external``).

    Not CasADi's own JIT: its shell compiler runs ``cc`` through ``system()``, which ignores SIGINT in
    this process while the compiler runs, so a Ctrl-C then killed the compiler, was lost here, and the
    scorecard went on with the interpreted function. :func:`pendulab.native.build.compile_shared` runs
    the compiler in its own process group, so Ctrl-C raises ``KeyboardInterrupt`` here and kills it.
    The sources go to a private temporary directory, never the user's current directory.
    """
    from ..native.build import compile_shared, shared_library_suffix

    folder = Path(_jit_directory())
    source = f"{fn.name()}.c"
    _generate(fn, folder, source)
    lib = folder / f"{fn.name()}{shared_library_suffix()}"
    # -O1: a sample map of a few hundred RHS evaluations compiles in about a second (-O2 takes several).
    compile_shared(folder, [source], lib, extra_flags=("-O1", "-fvisibility=default", "-w"))
    return ca.external(fn.name(), str(lib))


def _generate(fn: ca.Function, folder: Path, source: str) -> None:
    """Write the C source of ``fn`` to ``folder / source``."""
    gen = ca.CodeGenerator(source)
    gen.add(fn)
    gen.generate(str(folder) + os.sep)


def _pushes(rng: np.random.Generator, pert: Perturbation, t_final: float) -> list[tuple[int, float, float, float]]:
    """Random pushes (joint, time [s], amplitude [N.m], width [s]) at least 1 s apart on each joint."""
    out: list[tuple[int, float, float, float]] = []
    if pert.push_amplitude <= 0 or pert.pushes_per_joint <= 0:
        return out
    for joint in (0, 1):
        times: list[float] = []
        for _ in range(1000):  # rejection sampling; a 10 s episode fits 3 pushes 1 s apart easily
            if len(times) == pert.pushes_per_joint:
                break
            tp = float(rng.uniform(0.5, max(t_final - 1.5, 0.5)))
            if all(abs(tp - s) >= 1.0 for s in times):
                times.append(tp)
        for tp in sorted(times):
            amp = float(rng.uniform(0.5, 1.0) * pert.push_amplitude * rng.choice((-1.0, 1.0)))
            out.append((joint, tp, amp, float(rng.uniform(0.05, 0.1))))
    return out


def _push_torque(pushes: list[tuple[int, float, float, float]], t: float) -> np.ndarray:
    tau = np.zeros(2)
    for joint, tp, amp, width in pushes:
        tau[joint] += amp * math.exp(-0.5 * ((t - tp) / width) ** 2)
    return tau


@checked()
def run_perturbed_episode(
    controller: SampledController,
    task: Task,
    x0: Any,
    perturbation: Perturbation | None = None,
    *,
    t_final: float | None = None,
    n_sub: int | None = None,
) -> EpisodeResult:
    """Run ``controller`` on the task's plant (perturbed) and apply the RealAIGym success criterion.

    Parameters
    ----------
    controller : SampledController
        Reset before the run; its sample time is the episode's sample time.
    task : Task
        Nominal plant, actuation, torque limit, episode length, success fraction.
    x0 : array_like, shape (nx,)
        Start state.
    perturbation : Perturbation, optional
        Default: none (the nominal closed loop).
    t_final : float, optional
        Episode length [s]; default the task's.
    n_sub : int, optional
        RK4 substeps per sample; default :func:`substeps` of the perturbed plant.

    Returns
    -------
    EpisodeResult
        A controller that raises, returns a non-finite, wrongly sized or
        out-of-limit torque, or drives a passive joint ends the run as failed
        with the reason; so does a plant state that stops being finite.

    Raises
    ------
    ValueError
        Bad ``x0``, unknown parameter names in the perturbation, or a
        non-positive ``t_final`` or ``n_sub``.

    Examples
    --------
    >>> from pendulab.control import controller_for_task
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("pendubot")  # RealAIGym's C.1 robot, shoulder driven, 6 N.m, 10 s
    >>> controller, x0 = controller_for_task("swingup", task)  # energy pumping, then LQR balance
    >>> from pendulab.evaluate import Perturbation, run_perturbed_episode
    >>> nominal = run_perturbed_episode(controller, task, x0)
    >>> nominal.success, nominal.t_up  # above 0.9 (L1 + L2) from t_up [s] to the end
    (True, 5.13)
    >>> noisy = run_perturbed_episode(controller, task, x0, Perturbation(meas_noise=0.5, seed=1))
    >>> noisy.success, noisy.reason  # noise of 0.5 rad/s on the measured rates
    (False, 'end effector below 0.45 m in the last second (min -0.338 m)')
    """
    pert = Perturbation() if perturbation is None else perturbation
    plant = task.model.with_params(**dict(pert.params)) if pert.params else task.model
    x = plant.check_state(x0, "x0")
    if x.ndim != 1:
        raise ValueError(f"x0 must have shape ({plant.nx},), got {x.shape}")
    dt = float(controller.sample_time)
    T = task.t_final if t_final is None else float(t_final)
    if not (math.isfinite(T) and T > 0):
        raise ValueError(f"t_final must be a finite number > 0 [s], got {t_final!r}")
    n = substeps(plant, dt, x) if n_sub is None else int(n_sub)
    if n < 1:
        raise ValueError(f"n_sub must be >= 1, got {n_sub!r}")
    F = _sample_map(plant.kind, n)
    K = max(1, round(T / dt))
    limit = float(task.problem.torque_limit)
    driven = {INPUT_NAMES[i] for i in task.problem.actuated}
    lengths = plant.params.L1 + plant.params.L2
    threshold = task.success_fraction * lengths
    rng = np.random.default_rng(pert.seed)
    pushes = _pushes(rng, pert, K * dt)
    # Delay and rate noise: the one measurement model (also cosim's and the gym env's), drawing from this run's rng.
    measure = MeasurementModel(pert.meas_noise, round(pert.delay / dt))
    measure.reset(x, rng=rng)
    p = plant.p

    t = np.arange(K + 1) * dt
    X = np.full((K + 1, plant.nx), np.nan)
    U = np.full((K, 2), np.nan)
    y2 = np.full(K + 1, np.nan)
    X[0] = x
    y2[0] = float(plant.outputs(x)[3])
    applied = np.zeros(2)
    mask = np.array([name in driven for name in INPUT_NAMES])
    slots = [INPUT_NAMES.index(name) for name in controller.input_names]
    nx = plant.nx
    packed = np.concatenate([x, np.zeros(2), p, np.asarray(pert.friction, dtype=float), [dt / n]])
    result = np.zeros(nx + 1)
    # CasADi's buffer interface evaluates F on these two arrays in place: ~2 us per call instead of ~30 us for a
    # regular call, which converts every argument to a DM.
    buffer, evaluate = F.buffer()
    buffer.set_arg(0, memoryview(packed))
    buffer.set_res(0, memoryview(result))
    reason = ""
    controller.reset()
    for k in range(K):
        tk = float(t[k])
        xm = measure(X[k])
        try:
            cmd = np.asarray(controller(tk, xm), dtype=float).reshape(-1)
        except Exception as exc:  # noqa: BLE001 - any controller error ends this run, recorded, not the scorecard
            reason = f"controller raised {type(exc).__name__}: {exc} at t = {tk:.3f} s"
            break
        reason = _check_command(controller, cmd, driven, limit, tk)
        if reason:
            break
        full = np.zeros(2)
        full[slots] = cmd
        applied = applied + pert.response * (full - applied)
        tau = applied + pert.torque_noise * rng.standard_normal(2) if pert.torque_noise > 0 else applied
        # The actuator saturates; a passive joint has no motor (no torque, no torque noise).
        tau = np.where(mask, np.clip(tau, -limit, limit), 0.0)
        U[k] = tau
        packed[:nx] = X[k]
        packed[nx : nx + 2] = tau + _push_torque(pushes, tk + dt / 2) if pushes else tau
        evaluate()
        if not np.isfinite(result).all():
            reason = f"plant state not finite (diverged) at t = {t[k + 1]:.3f} s"
            break
        X[k + 1] = result[:nx]
        y2[k + 1] = result[nx]
    last = t >= t[-1] - 1.0 - 1e-9
    above = y2 >= threshold
    if not reason and not np.all(above[last]):
        reason = f"end effector below {threshold:.3g} m in the last second (min {np.nanmin(y2[last]):.3g} m)"
    t_up = float("nan")
    if not reason:
        below = np.flatnonzero(~above)
        t_up = float(t[0 if below.size == 0 else int(below[-1]) + 1])
    return EpisodeResult(not reason, reason, t_up, threshold, t, X, U, y2)


def _check_command(controller: SampledController, cmd: np.ndarray, driven: set[str], limit: float, t: float) -> str:
    """Why a torque command is not acceptable ("" if it is)."""
    names = tuple(controller.input_names)
    if cmd.shape != (len(names),):
        return f"controller returned {cmd.size} torque(s) for inputs {list(names)} at t = {t:.3f} s"
    if not np.all(np.isfinite(cmd)):
        return f"controller returned a non-finite torque {cmd.tolist()} at t = {t:.3f} s"
    for name, value in zip(names, cmd, strict=True):
        if name not in driven and value != 0.0:
            return f"controller drives {name} = {value:.3g} N.m, a passive joint of this task, at t = {t:.3f} s"
        # A relative slack of 1e-9 lets a command clipped exactly at the limit pass.
        if abs(value) > limit * (1 + 1e-9):
            return f"torque {name} = {value:.3g} N.m above the limit {limit:g} N.m at t = {t:.3f} s"
    return ""

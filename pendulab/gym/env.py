"""``DoublePendulumEnv``: the rigid or elastic double pendulum as a Gymnasium environment.

Action: ``Box(-1, 1, (n_act,), float32)``, one entry per actuated torque (pendubot: tau1,
acrobot: tau2, full: both), clipped to [-1, 1] and multiplied by ``action_scale`` (the torque
limit [N.m]); the torque is held over the sample ``dt`` (zero-order hold).

Observation (float32): ``cos th1, sin th1, cos th2, sin th2, w1 / ws, w2 / ws`` for the rigid
model (absolute angles from the downward vertical, ``ws = velocity_scale`` [rad/s]); the
elastic model appends ``(r1 - L1) / L1, (r2 - L2) / L2, v1 / (ws L1), v2 / (ws L2)``. The
full-precision model state is ``env.unwrapped.state``. With ``measurement=`` and/or ``estimator=``
the observation is made from the delayed, noisy measurement of the state or from a state estimate
of it (:mod:`pendulab.gym.observation`; ``env.unwrapped.estimate``); reward and termination stay
on the true state.

Episode: reset near hanging at rest (uniform noise of ``reset_noise`` on angles [rad] and
angular rates [rad/s]) or at ``options={"state": x0}``; truncated after ``max_episode_steps``
steps (``round(episode_length / dt)``, or the ``max_episode_steps`` argument), the value
``env.spec.max_episode_steps`` reports; terminated when the integrator fails (non-finite state;
the state then stays at the last good one) or a spring length reaches 0.

Copies: ``pickle``, ``copy.deepcopy`` and cloudpickle (Dask, joblib, Ray) copy an environment
with its plant's full state; the copy steps bit for bit like the original (see
:class:`~pendulab.gym.backends.NativePlant` and :class:`~pendulab.gym.backends.FmuBackend`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.envs.registration import EnvSpec

from .._checks import bounded_int, positive_float
from .._inputs import checked
from ..model.model import ACTUATIONS, Model, make_model
from .backends import INTEGRATORS, FmuBackend, NativePlant
from .observation import make_pipeline
from .render import FrameRenderer
from .rewards import RewardFn, make_reward

__all__ = [
    "DoublePendulumEnv",
    "BACKENDS",
    "ENV_ID",
    "OBS_LIMIT",
    "DEFAULT_EPISODE_LENGTH",
    "DEFAULT_RENDER_FPS",
    "MAX_EPISODE_STEPS",
    "horizon",
]

#: The id registered by ``import pendulab.gym``.
ENV_ID = "pendulab/DoublePendulum-v0"
#: Bound of the scaled rates and stretches in the observation (they are clipped to it; never reached in practice:
#: 10^4 rad/s at the default velocity scale), so that the observation space is finite.
OBS_LIMIT = 1000.0
#: Plant backends.
BACKENDS: tuple[str, ...] = ("native", "fmu")
#: Episode duration [s] when neither ``episode_length`` nor ``max_episode_steps`` is given.
DEFAULT_EPISODE_LENGTH = 10.0
#: Largest ``max_episode_steps``: 10^9 steps of 10 ms is 115 days of simulated time per episode.
MAX_EPISODE_STEPS = 10**9
#: ``metadata["render_fps"]`` of the class: one frame per sample at the default ``dt = 0.01`` s;
#: an instance reports ``round(1 / dt)`` (Gymnasium's convention: frames advance by the env's own time step).
DEFAULT_RENDER_FPS = 100


def horizon(dt: float, episode_length: Any = None, max_episode_steps: Any = None) -> int:
    """Steps of an episode: ``max_episode_steps``, else ``round(episode_length / dt)`` (default 10 s).

    Parameters
    ----------
    dt : float
        Sample time [s] (already checked).
    episode_length : float, optional
        Episode duration [s].
    max_episode_steps : int, optional
        Steps of an episode (what ``gym.make_vec(..., max_episode_steps=N)`` passes).

    Returns
    -------
    int
        Steps before truncation (>= 1).

    Raises
    ------
    ValueError
        A bad value, an ``episode_length`` shorter than ``dt``, or both given and in disagreement.
    """
    steps = None
    if max_episode_steps is not None:
        steps = bounded_int("max_episode_steps", max_episode_steps, low=1, high=MAX_EPISODE_STEPS, why="steps of one episode")
    if episode_length is None:
        if steps is not None:
            return steps
        episode_length = DEFAULT_EPISODE_LENGTH
    length = positive_float("episode_length", episode_length, "s")
    if length < dt * (1 - 1e-9):
        raise ValueError(f"episode_length must be at least one sample dt = {dt} s, got {episode_length!r}")
    ratio = length / dt
    if not ratio <= MAX_EPISODE_STEPS + 0.5:  # also catches inf (dt = 5e-324)
        raise ValueError(
            f"episode_length / dt = {length:g} s / {dt:g} s is {ratio:.3g} steps; "
            f"at most {MAX_EPISODE_STEPS} steps of one episode"
        )
    from_length = max(int(round(ratio)), 1)
    if steps is not None and steps != from_length:
        raise ValueError(
            f"max_episode_steps={max_episode_steps!r} and episode_length={episode_length!r} s disagree at dt = {dt} s "
            f"({from_length} steps); give one of them"
        )
    return from_length


class DoublePendulumEnv(gymnasium.Env):
    """Swing-up and balance of the rigid or elastic double pendulum (see the module docstring).

    Parameters
    ----------
    model : {"rigid", "elastic"} or Model
        Model kind (with ``params``), or a model.
    actuation : {"pendubot", "acrobot", "full"}
        Actuated torques.
    backend : {"native", "fmu"}
        ``"native"``: a persistent compiled integrator (:class:`~pendulab.gym.backends.NativePlant`);
        ``"fmu"``: the exported FMU through fmpy (needs a C compiler once).
    dt : float
        Sample time [s].
    torque_limit : float
        ``action_scale``: torque [N.m] of an action of 1.
    episode_length : float, optional
        Episode duration [s] before truncation (default 10 s, or ``max_episode_steps * dt``).
    max_episode_steps : int, optional
        Steps before truncation instead of ``episode_length`` (both given: they must agree).
        ``gym.make_vec(..., max_episode_steps=N)`` passes it; ``gym.make(..., max_episode_steps=N)``
        adds Gymnasium's ``TimeLimit`` instead, which can only end episodes earlier (see ``docs/gym.md``).
    reward : {"realai", "quadratic", "height"} or callable
        See :func:`~pendulab.gym.rewards.make_reward`; a callable is ``reward(x, tau) -> float``.
    params : mapping, optional
        Parameter values by name when ``model`` is a kind (e.g. ``{"k1": 1e4}``).
    integrator : {"auto", "taylor", "compiled-dopri5", "compiled-rodas4"}
        Native backend's integrator (``"auto"``: Taylor when heyoka is installed).
    tol : float
        Integrator tolerance in (0, 1) (heyoka ``tol``; ``rtol = atol`` of the C solvers and of the FMU).
    fmu_solver : {"dopri5", "rodas4"}
        Embedded solver of the FMU backend.
    velocity_scale : float
        ``ws`` [rad/s] dividing the rates in the observation.
    reset_noise : float
        Half-width of the uniform noise of a reset on angles [rad] and angular rates [rad/s], in [0, 100].
    render_mode : {"rgb_array"} or None
        ``"rgb_array"``: :meth:`render` returns an RGB frame.
    render_size : int
        Frame width and height [pixel].
    measurement : MeasurementModel, optional
        :class:`~pendulab.evaluate.measurement.MeasurementModel`: delay [samples of ``dt``] and Gaussian noise
        [rad/s] on ``omega1, omega2`` of the state the observation is made from; the noise is drawn from the
        environment's generator (``reset(seed=)`` seeds it). The environment keeps its own copy.
    estimator : {"ekf", "mmae"} or StateEstimator, optional
        The observation is made from this estimator's state, updated every step with the measurement and the
        held torques and reset (at the start state) by :meth:`reset`; a name is built by
        :func:`~pendulab.control.robust.build_estimator` on the model at ``dt`` with the torque limit.

    Attributes
    ----------
    model : Model
    actuation : str
    dt : float
        Sample time [s].
    action_scale : float
        Torque limit [N.m].
    max_episode_steps : int
        Steps before truncation (also ``spec.max_episode_steps`` once ``gym.make`` has set the spec).
    state : ndarray, shape (nx,)
        Current model state (a copy).
    t : float
        Time since reset [s].
    estimate : ndarray, shape (nx,)
        The state the last observation was made from (the plant's state without measurement and estimator).

    Raises
    ------
    ValueError
        An unknown name or an invalid value of any argument (the message names it).
    TypeError
        ``model`` or ``reward`` of the wrong type.

    Examples
    --------
    >>> import gymnasium as gym
    >>> import numpy as np
    >>> import pendulab.gym  # registers "pendulab/DoublePendulum-v0"
    >>> env = gym.make("pendulab/DoublePendulum-v0", model="rigid", actuation="pendubot", dt=0.01)
    >>> obs, info = env.reset(seed=0)
    >>> env.observation_space.shape, env.action_space.shape  # cos/sin of both angles, scaled rates; tau1
    ((6,), (1,))
    >>> obs, reward, terminated, truncated, info = env.step(np.array([0.5], dtype=np.float32))
    >>> info["t"], info["tau"]  # half the 10 N.m torque limit, held on the shoulder for 10 ms
    (0.01, array([5., 0.]))
    >>> env.unwrapped.max_episode_steps, terminated, truncated  # 10 s episodes
    (1000, False, False)
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": DEFAULT_RENDER_FPS}

    @checked(episode_length="t_final", tol="tolerance", torque_limit="u_max")
    def __init__(
        self,
        model: str | Model = "rigid",
        actuation: str = "pendubot",
        backend: str = "native",
        *,
        dt: float = 0.01,
        torque_limit: float = 10.0,
        episode_length: float | None = None,
        max_episode_steps: int | None = None,
        reward: str | RewardFn = "realai",
        params: Mapping[str, float] | None = None,
        integrator: str = "auto",
        tol: float = 1e-10,
        fmu_solver: str = "dopri5",
        velocity_scale: float = 10.0,
        reset_noise: float = 0.05,
        render_mode: str | None = None,
        render_size: int = 400,
        measurement: Any = None,
        estimator: Any = None,
    ) -> None:
        self.model = _model(model, params)
        if actuation not in ACTUATIONS:
            raise ValueError(f"actuation must be one of {list(ACTUATIONS)}, got {actuation!r}")
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {list(BACKENDS)}, got {backend!r}")
        if integrator not in INTEGRATORS:
            raise ValueError(f"integrator must be one of {list(INTEGRATORS)}, got {integrator!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        self.actuation = actuation
        self.backend = backend
        # dt, torque_limit (as u_max), velocity_scale, reset_noise and tol were checked against their
        # declarations (pendulab._inputs) where they entered: @checked on this constructor.
        self.dt = float(dt)
        self.action_scale = float(torque_limit)
        self.max_episode_steps = horizon(self.dt, episode_length, max_episode_steps)
        self.velocity_scale = float(velocity_scale)
        self.reset_noise = float(reset_noise) + 0.0  # + 0.0: -0.0 becomes 0.0 (NumPy's uniform(0.0, -0.0) raises)
        tol = float(tol)
        self.tol = tol
        self.reward_fn = make_reward(reward, self.model)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": max(int(round(1.0 / self.dt)), 1)}

        self._actuated = ACTUATIONS[actuation]
        self.action_space = spaces.Box(-1.0, 1.0, shape=(len(self._actuated),), dtype=np.float32)
        n_obs = 6 if self.model.kind == "rigid" else 10
        high = np.full(n_obs, OBS_LIMIT, dtype=np.float32)
        high[:4] = 1.0
        self.observation_space = spaces.Box(-high, high, dtype=np.float32)
        values = self.model.params.resolved()
        self._lengths = (float(values["L1"]), float(values["L2"]))
        if backend == "native":
            self.plant: NativePlant | FmuBackend = NativePlant(self.model, actuation, integrator=integrator, tol=tol)
        else:
            self.plant = FmuBackend(self.model, solver=fmu_solver, tol=tol)
        self._renderer: FrameRenderer | None = None
        self._render_size = render_size
        if render_mode is not None:
            self._renderer = FrameRenderer(self.model, size=render_size)
        self._pipeline = make_pipeline(self.model, self.dt, self._actuated, self.action_scale, estimator, measurement)
        self._tau = np.zeros(2)
        self._x = self.model.rest_state()
        self._seen = self._x
        self._steps = 0
        self._needs_reset = True

    # -- properties ---------------------------------------------------------------------------
    @property
    def spec(self) -> EnvSpec | None:
        """The spec ``gym.make`` sets, with ``max_episode_steps`` = this environment's own horizon."""
        return self.__dict__.get("_spec")

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        # gym.make sets a spec with max_episode_steps=None (the id registers none: the horizon depends on dt and
        # episode_length); report the steps after which this environment truncates itself instead.
        if value is not None and value.max_episode_steps != self.max_episode_steps:
            value = dataclasses.replace(value, max_episode_steps=self.max_episode_steps)
        self.__dict__["_spec"] = value

    @property
    def state(self) -> np.ndarray:
        """The model state, shape (nx,), in ``model.state_names`` order (a copy)."""
        return self._x.copy()

    @property
    def estimate(self) -> np.ndarray:
        """The state the last observation was made from, shape (nx,) (a copy)."""
        return np.array(self._seen, dtype=float)

    @property
    def t(self) -> float:
        """Time since the last reset [s]."""
        return self._steps * self.dt

    @property
    def integrator(self) -> str:
        """The integrator stepping the plant (e.g. ``"taylor"``, ``"fmu-dopri5"``)."""
        return self.plant.integrator

    # -- gymnasium API ------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode near hanging at rest, or at ``options["state"]``.

        Parameters
        ----------
        seed : int, optional
            Seeds the environment's random generator (same seed, same episode).
        options : dict, optional
            ``{"state": x0}`` (shape (nx,)) starts there exactly.

        Returns
        -------
        observation : ndarray, shape (6,) or (10,), float32
        info : dict
            ``{"t": 0.0, "tau": zeros(2)}``.

        Raises
        ------
        ValueError
            ``options`` has unknown keys or a bad state (wrong shape, not finite, a spring length <= 0).
        """
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = sorted(set(options) - {"state"})
        if unknown:
            raise ValueError(f"options: unknown key(s) {unknown}; expected 'state'")
        if "state" in options:
            x0 = self.model.check_start(options["state"], "options['state']")
            if x0.ndim != 1:
                raise ValueError(f"options['state'] must have shape ({self.model.nx},), got {x0.shape}")
            x0 = x0.copy()
        else:
            x0 = self.model.rest_state()
            names = self.model.state_names
            idx = [i for i, n in enumerate(names) if n.startswith(("theta", "omega"))]
            x0[idx] += self.np_random.uniform(-self.reset_noise, self.reset_noise, size=len(idx))
        self.plant.reset(x0)
        self._x = x0
        self._tau = np.zeros(2)
        self._steps = 0
        self._needs_reset = False
        self._seen = x0 if self._pipeline is None else self._pipeline.reset(x0, self.np_random)
        return self._observe(self._seen), {"t": 0.0, "tau": self._tau.copy()}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Hold the torque of ``action`` for ``dt`` and advance the plant.

        Parameters
        ----------
        action : array_like, shape (n_act,)
            In [-1, 1] (clipped), scaled by ``action_scale`` [N.m].

        Returns
        -------
        observation : ndarray, float32
        reward : float
        terminated : bool
            Integrator failure, a spring length <= 0, or a diverged estimator (``estimator=``).
        truncated : bool
            ``max_episode_steps`` reached.
        info : dict
            ``t`` [s], ``tau`` (tau1, tau2) [N.m] held; ``failure`` (str) when the integrator stopped.

        Raises
        ------
        RuntimeError
            ``step`` before ``reset``.
        ValueError
            Wrong number of action entries or a NaN entry.
        """
        if self._needs_reset:
            raise RuntimeError("call reset() before step()")
        tau = np.zeros(2)
        act = np.ravel(action) if not isinstance(action, np.ndarray) or action.ndim != 1 else action
        if act.shape[0] != len(self._actuated):
            raise ValueError(f"action must have {len(self._actuated)} entries ({self.actuation}), got shape {np.shape(action)}")
        scale = self.action_scale
        for k, i in enumerate(self._actuated):
            a = float(act[k])
            if a != a:
                raise ValueError(f"action must not be NaN, got {action!r}")
            tau[i] = scale * (1.0 if a > 1.0 else (-1.0 if a < -1.0 else a))
        x, failure = self.plant.step(tau, self.dt)
        self._x = x
        self._tau = tau
        self._steps += 1
        terminated = failure is not None
        if self.model.kind == "elastic" and (x[2] <= 0.0 or x[3] <= 0.0):
            terminated = True
        truncated = self._steps >= self.max_episode_steps
        info: dict[str, Any] = {"t": self._steps * self.dt, "tau": tau}
        if failure is not None:
            info["failure"] = failure
        self._seen = x if self._pipeline is None else self._pipeline.step(self._steps * self.dt, x, tau)
        if self._pipeline is not None and self._pipeline.diverged:
            terminated = True
            info.setdefault("failure", "the state estimate is not finite (the estimator diverged); observed the measurement")
        return self._observe(self._seen), float(self.reward_fn(x, tau)), terminated, truncated, info

    def render(self) -> np.ndarray | None:
        """The current frame.

        Returns
        -------
        ndarray, shape (render_size, render_size, 3), uint8, or None
            RGB frame when ``render_mode == "rgb_array"``, else None.
        """
        if self._renderer is None:
            return None
        return self._renderer.render(self._x)

    def close(self) -> None:
        """Free the plant (the FMU instance); idempotent."""
        self.plant.close()

    # -- helpers ------------------------------------------------------------------------------
    def _observe(self, x: np.ndarray) -> np.ndarray:
        ws = self.velocity_scale
        t1, t2 = float(x[0]), float(x[1])
        if self.model.kind == "rigid":
            rest = (x[2] / ws, x[3] / ws)
        else:
            l1, l2 = self._lengths
            rest = (x[4] / ws, x[5] / ws, (x[2] - l1) / l1, (x[3] - l2) / l2, x[6] / (ws * l1), x[7] / (ws * l2))
        lim = OBS_LIMIT
        obs = [math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)]
        obs += [lim if v > lim else (-lim if v < -lim else float(v)) for v in rest]
        return np.array(obs, dtype=np.float32)


def _model(model: Any, params: Mapping[str, float] | None) -> Model:
    if isinstance(model, Model):
        return model.with_params(**params) if params else model
    if not isinstance(model, str):
        raise TypeError(f"model must be 'rigid', 'elastic' or a pendulab Model, got {type(model).__name__}")
    if model not in ("rigid", "elastic"):
        raise ValueError(f"model must be 'rigid', 'elastic' or a pendulab Model, got {model!r}")
    if params is not None and not isinstance(params, Mapping):
        raise TypeError(f"params must be a mapping name -> value, got {type(params).__name__}")
    return make_model(model, **dict(params or {}))

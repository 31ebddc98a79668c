"""``DoublePendulumVectorEnv``: many pendulums stepped at once by one heyoka batch integrator.

``gym.make_vec("pendulab/DoublePendulum-v0", num_envs=N)`` builds it (the id's vector entry
point); every keyword of :class:`~pendulab.gym.env.DoublePendulumEnv` applies, with
``backend="native"`` and the Taylor integrator (heyoka's ``taylor_adaptive_batch``: one
``propagate_for(dt)`` advances every lane, each with its own adaptive steps and its torques as
per-lane runtime parameters). Lanes are independent episodes: same spaces (batched), same
observations, rewards (evaluated with NumPy over the lanes for the named rewards), termination
and truncation as the single environment. Autoreset mode ``NEXT_STEP``: the step after a lane's
episode ended resets that lane (its action is ignored, reward 0, both flags False).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import threading
from typing import Any

import casadi as ca
import numpy as np
from gymnasium.envs.registration import EnvSpec
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .._inputs import checked
from ..integrate.taylor import structure_key, translate
from ..integrate.taylor.availability import heyoka_module
from ..model.pycode import to_python
from .env import DEFAULT_RENDER_FPS, OBS_LIMIT, DoublePendulumEnv
from .rewards import HeightReward, QuadraticReward

__all__ = ["DoublePendulumVectorEnv"]

_BATCH_CACHE: dict[tuple, Any] = {}
_BATCH_LOCK = threading.Lock()


class DoublePendulumVectorEnv(VectorEnv):
    """``num_envs`` independent double pendulums in one heyoka batch integrator (see the module docstring).

    Parameters
    ----------
    num_envs : int
        Number of lanes (parallel episodes), >= 1.
    **kwargs
        Keyword arguments of :class:`~pendulab.gym.env.DoublePendulumEnv` (``backend`` must be
        ``"native"``, ``integrator`` ``"auto"`` or ``"taylor"``).

    Attributes
    ----------
    num_envs : int
    max_episode_steps : int
        Steps of every lane's episode (``gym.make_vec(..., max_episode_steps=N)`` sets it; also ``spec.max_episode_steps``).
    single_env : DoublePendulumEnv
        A single environment with the same settings (model, spaces, reward, renderer).
    states : ndarray, shape (num_envs, nx)
        Current model states (a copy).

    Raises
    ------
    ValueError
        ``num_envs`` < 1, an FMU backend or a C integrator, or any bad keyword of the single environment.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.gym import DoublePendulumVectorEnv
    >>> venv = DoublePendulumVectorEnv(num_envs=4, actuation="full", reset_noise=0.0)  # one heyoka batch, 4 lanes
    >>> obs, infos = venv.reset(seed=0)
    >>> actions = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0], [0.3, 0.0]], dtype=np.float32)
    >>> for _ in range(50):  # 0.5 s of constant shoulder torques 0, 1, 2, 3 N.m
    ...     obs, rewards, terminated, truncated, infos = venv.step(actions)
    >>> obs.shape, venv.states.shape
    ((4, 6), (4, 4))
    >>> np.round(venv.states[:, 0], 3)  # theta1 [rad]: the lane at rest stays at rest
    array([0.   , 0.066, 0.133, 0.198])
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": ["rgb_array"], "render_fps": DEFAULT_RENDER_FPS}

    @checked(DoublePendulumEnv)
    def __init__(self, num_envs: int = 8, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if kwargs.get("backend", "native") != "native":
            raise ValueError(
                "the vector environment steps the native Taylor integrator only; for backend='fmu' use "
                "gym.make_vec(..., vectorization_mode='sync')"
            )
        if kwargs.get("integrator", "auto") not in ("auto", "taylor"):
            raise ValueError(f"the vector environment uses integrator 'taylor', got integrator={kwargs['integrator']!r}")
        # make_vec forwards max_episode_steps: it sets the horizon of every lane (checked against episode_length).
        env = DoublePendulumEnv(**{**kwargs, "integrator": "taylor"})
        self.single_env = env
        self.num_envs = int(num_envs)
        self.render_mode = env.render_mode
        self.metadata = {**self.metadata, "render_fps": env.metadata["render_fps"]}
        self.single_observation_space = env.observation_space
        self.single_action_space = env.action_space
        self.observation_space = batch_space(env.observation_space, self.num_envs)
        self.action_space = batch_space(env.action_space, self.num_envs)
        model = env.model
        self._model = model
        self._actuated = list(env._actuated)
        self._dt = env.dt
        self._lanes = _Lanes(model, tuple(self._actuated), env.tol, self.num_envs)
        self._reward = _batch_reward(env.reward_fn, model)
        self._X = np.tile(model.rest_state(), (self.num_envs, 1))
        # One measurement model and estimator per lane (copies of the single environment's), or None.
        pipe = env._pipeline
        self._pipes = None if pipe is None else [pipe.copy() for _ in range(self.num_envs)]
        self._seen = self._X.copy()
        self._steps = np.zeros(self.num_envs, dtype=int)
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._needs_reset = True

    @property
    def max_episode_steps(self) -> int:
        """Steps of every lane's episode (``spec.max_episode_steps``)."""
        return self.single_env.max_episode_steps

    @property
    def spec(self) -> EnvSpec | None:
        """The spec ``gym.make_vec`` sets, with ``max_episode_steps`` = the lanes' own horizon."""
        return self.__dict__.get("_spec")

    @spec.setter
    def spec(self, value: EnvSpec | None) -> None:
        if value is not None and value.max_episode_steps != self.max_episode_steps:
            value = dataclasses.replace(value, max_episode_steps=self.max_episode_steps)
        self.__dict__["_spec"] = value

    @property
    def states(self) -> np.ndarray:
        """Model states of the lanes, shape (num_envs, nx) (a copy)."""
        return self._X.copy()

    @property
    def estimates(self) -> np.ndarray:
        """The states the lanes' last observations were made from, shape (num_envs, nx) (a copy; see the single env)."""
        return np.array(self._seen, dtype=float)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every lane near hanging at rest, or at ``options["state"]``.

        Parameters
        ----------
        seed : int, optional
            Seeds the vector environment's generator (same seed, same episodes).
        options : dict, optional
            ``{"state": x0}`` with shape (nx,) (every lane) or (num_envs, nx).

        Returns
        -------
        observations : ndarray, shape (num_envs, n_obs), float32
        infos : dict
            Empty.

        Raises
        ------
        ValueError
            Unknown option keys or bad states (wrong shape, not finite, a spring length <= 0).
        """
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = sorted(set(options) - {"state"})
        if unknown:
            raise ValueError(f"options: unknown key(s) {unknown}; expected 'state'")
        if "state" in options:
            X0 = self._model.check_start(options["state"], "options['state']")
            X0 = np.array(np.broadcast_to(X0, (self.num_envs, self._model.nx)))
        else:
            X0 = np.array([self._initial_state() for _ in range(self.num_envs)])
        self._lanes.set_states(X0, np.arange(self.num_envs))
        self._X = X0
        self._steps[:] = 0
        self._autoreset[:] = False
        self._needs_reset = False
        self._seen = X0 if self._pipes is None else self._pipe_step(X0, None, None)
        return self._observe(self._seen), {}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Advance every lane by ``dt`` (lanes whose episode ended are reset instead).

        Parameters
        ----------
        actions : array_like, shape (num_envs, n_act)
            In [-1, 1] (clipped), scaled by ``action_scale`` [N.m].

        Returns
        -------
        observations : ndarray, shape (num_envs, n_obs), float32
        rewards : ndarray, shape (num_envs,)
        terminations, truncations : ndarray of bool, shape (num_envs,)
        infos : dict
            ``tau``: torques (num_envs, 2) [N.m] held; ``_tau``: all True.

        Raises
        ------
        RuntimeError
            ``step`` before ``reset``.
        ValueError
            Actions of the wrong shape or with NaN entries.
        """
        if self._needs_reset:
            raise RuntimeError("call reset() before step()")
        n_act = len(self._actuated)
        A = np.asarray(actions, dtype=float).reshape(self.num_envs, -1) if np.size(actions) == self.num_envs * n_act else None
        if A is None:
            raise ValueError(f"actions must have shape ({self.num_envs}, {n_act}), got {np.shape(actions)}")
        if np.isnan(A).any():
            raise ValueError("actions must not be NaN")
        restart = self._autoreset.copy()
        tau = np.zeros((self.num_envs, 2))
        tau[:, self._actuated] = np.clip(A, -1.0, 1.0) * self.single_env.action_scale
        tau[restart] = 0.0
        X, failed = self._lanes.propagate(tau, self._dt)
        self._steps += 1
        terminated = failed.copy()
        if self._model.kind == "elastic":
            terminated |= (X[:, 2] <= 0.0) | (X[:, 3] <= 0.0)
        truncated = self._steps >= self.single_env.max_episode_steps
        rewards = self._reward(X, tau)
        if restart.any():
            lanes = np.flatnonzero(restart)
            for i in lanes:
                X[i] = self._initial_state()
            self._lanes.set_states(X[lanes], lanes)
            self._steps[restart] = 0
            rewards[restart] = 0.0
            terminated[restart] = False
            truncated[restart] = False
        self._X = X
        self._seen = X if self._pipes is None else self._pipe_step(X, tau, restart)
        if self._pipes is not None:  # a lane whose estimator diverged ends its episode (as the single env does)
            terminated |= np.array([p.diverged for p in self._pipes])
        self._autoreset = terminated | truncated
        info = {"tau": tau, "_tau": np.ones(self.num_envs, dtype=bool)}
        return self._observe(self._seen), rewards, terminated, truncated, info

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Frames of every lane.

        Returns
        -------
        tuple of ndarray, each (render_size, render_size, 3) uint8, or None
            None unless ``render_mode == "rgb_array"``.
        """
        renderer = self.single_env._renderer
        if renderer is None:
            return None
        return tuple(renderer.render(x) for x in self._X)

    # -- copies -------------------------------------------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        """Everything but the vectorised reward (generated code, rebuilt from the single env's reward)."""
        state = dict(self.__dict__)
        state.pop("_reward", None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Restore the attributes and rebuild the vectorised reward."""
        self.__dict__.update(state)
        self._reward = _batch_reward(self.single_env.reward_fn, self._model)

    # -- helpers ------------------------------------------------------------------------------
    def _pipe_step(self, X: np.ndarray, tau: np.ndarray | None, restart: np.ndarray | None) -> np.ndarray:
        """Each lane's measurement and estimate; a lane (re)started now (``tau`` None: all) restarts its pipeline."""
        rows = []
        for i, pipe in enumerate(self._pipes or ()):
            if tau is None or restart is None or restart[i]:
                rows.append(pipe.reset(X[i], self.np_random))
            else:
                rows.append(pipe.step(self._steps[i] * self._dt, X[i], tau[i]))
        return np.array(rows)

    def _initial_state(self) -> np.ndarray:
        model, noise = self._model, self.single_env.reset_noise
        x0 = model.rest_state()
        idx = [i for i, n in enumerate(model.state_names) if n.startswith(("theta", "omega"))]
        x0[idx] += self.np_random.uniform(-noise, noise, size=len(idx))
        return x0

    def _observe(self, X: np.ndarray) -> np.ndarray:
        ws = self.single_env.velocity_scale
        if self._model.kind == "rigid":
            rest = X[:, 2:4] / ws
        else:
            l1, l2 = self.single_env._lengths
            scale = np.array([ws, ws, l1, l2, ws * l1, ws * l2])
            rest = (X[:, [4, 5, 2, 3, 6, 7]] - np.array([0.0, 0.0, l1, l2, 0.0, 0.0])) / scale
        angles = X[:, :2]
        obs = np.column_stack([np.cos(angles[:, 0]), np.sin(angles[:, 0]), np.cos(angles[:, 1]), np.sin(angles[:, 1])])
        return np.hstack([obs, np.clip(rest, -OBS_LIMIT, OBS_LIMIT)]).astype(np.float32)


class _Lanes:
    """The lanes in chunks of ``2 x heyoka.recommended_simd_size()`` lanes, one batch integrator per chunk.

    One batch of 64 lanes costs ~4x more per lane than batches of 16 here (wide vectors spill
    registers), so lanes are split; the last chunk is padded with idle lanes (zero torque).
    """

    def __init__(self, model: Any, actuated: tuple[int, ...], tol: float, n: int) -> None:
        b = min(n, 2 * int(heyoka_module().recommended_simd_size()))
        self.n, self.b = n, b
        self.model, self.tol = model, tol
        self.actuated = list(actuated)
        self.chunks = [_batch_integrator(model, actuated, tol, b) for _ in range(-(-n // b))]
        self.X = np.tile(model.rest_state(), (len(self.chunks) * b, 1))  # last good states, padded
        self.tau = np.zeros((len(self.chunks) * b, 2))

    def __getstate__(self) -> dict[str, Any]:
        # The batch integrators are compiled code: keep their settings, states and times, rebuild them on unpickling.
        times = [tuple(np.array(a) for a in ta.dtime) for ta in self.chunks]
        return {
            "model": self.model,
            "actuated": tuple(self.actuated),
            "tol": self.tol,
            "n": self.n,
            "b": self.b,
            "X": self.X.copy(),
            "tau": self.tau.copy(),
            "states": [np.array(ta.state) for ta in self.chunks],
            "times": times,
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.model, self.tol, self.n, self.b = state["model"], state["tol"], state["n"], state["b"]
        self.actuated = list(state["actuated"])
        self.chunks = [_batch_integrator(self.model, state["actuated"], self.tol, self.b) for _ in state["states"]]
        for ta, x, (hi, lo) in zip(self.chunks, state["states"], state["times"], strict=True):
            ta.state[:] = x
            ta.set_dtime(hi, lo)  # double-length time: the last step of propagate_for depends on it
        self.X, self.tau = state["X"].copy(), state["tau"].copy()

    def set_states(self, X: np.ndarray, lanes: np.ndarray) -> None:
        self.X[lanes] = X
        b = self.b
        for c, ta in enumerate(self.chunks):
            ta.state[:] = self.X[c * b : (c + 1) * b].T

    def propagate(self, tau: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """States after ``dt`` (N, nx) and the lanes that failed (their state is the last good one)."""
        b, act = self.b, self.actuated
        self.tau[: self.n] = tau
        failed = np.zeros(len(self.X), dtype=bool)
        for c, ta in enumerate(self.chunks):
            rows = slice(c * b, (c + 1) * b)
            ta.pars[act, :] = self.tau[rows, act].T
            target = ta.time + dt
            ta.propagate_for(dt)
            state = ta.state
            # A lane that stopped early (non-finite state: heyoka does not update it) has not reached the target;
            # heyoka keeps time in double-length arithmetic, hence the margin.
            bad = (ta.time < target - 1e-6 * dt) | ~np.isfinite(state).all(axis=0)
            if bad.any():
                state[:, bad] = self.X[rows][bad].T
                failed[rows] = bad
            self.X[rows] = state.T
        return self.X[: self.n].copy(), failed[: self.n]


def _batch_integrator(model: Any, actuated: tuple[int, ...], tol: float, n: int) -> Any:
    """A heyoka batch integrator of ``n`` lanes, compiled once per (structure, n) and process, copied per env."""
    hy = heyoka_module()
    zero_u = tuple(i for i in range(model.nu) if i not in actuated)
    key = structure_key(model.kind, model.p, zero_u, tol)
    with _BATCH_LOCK:
        entry = _BATCH_CACHE.get((key, n))
        if entry is None:
            system = translate(
                model.functions["rhs"], zero_params=key.zero_params, zero_inputs=key.zero_inputs, state_names=model.state_names
            )
            ta = hy.taylor_adaptive_batch(system.sys, np.zeros((model.nx, n)), pars=np.zeros((system.n_pars, n)), tol=key.tol)
            entry = _BATCH_CACHE[key, n] = (system, ta)
    system, template = entry
    ta = copy.copy(template)
    pars = system.pars(np.zeros(model.nu), model.p)
    ta.pars[:] = np.asarray(pars)[:, None]
    return ta


def _batch_reward(reward: Any, model: Any) -> Any:
    """``reward(X, TAU) -> (N,)`` over the lanes: NumPy for the named rewards, a loop for a user callable."""
    if isinstance(reward, (QuadraticReward, HeightReward)):
        f = model.functions["positions"]
        xs, ps = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("p", f.size1_in(1))
        positions = to_python(ca.Function("tip_height", [xs, ps], [f(xs, ps)[3]]), vectorized=True)
        p = [float(v) for v in model.p]

        def tip(X: np.ndarray) -> np.ndarray:
            return np.asarray(positions(X.T, p))[0]

    if isinstance(reward, HeightReward):
        return lambda X, TAU: tip(X) / reward.reach
    if isinstance(reward, QuadraticReward):
        q, goal = np.array(reward.q), np.array(reward.goal)
        angles = list(reward.angle_index)
        r = np.array(reward.r)

        def quadratic(X: np.ndarray, TAU: np.ndarray) -> np.ndarray:
            E = X - goal
            E[:, angles] = (E[:, angles] + math.pi) % (2 * math.pi) - math.pi
            out = -(E**2 @ q + TAU**2 @ r)
            if reward.bonus and reward.tip_height is not None:
                out += reward.bonus * (tip(X) > reward.height_fraction * reward.reach)
            return out

        return quadratic
    return lambda X, TAU: np.array([float(reward(x, t)) for x, t in zip(X, TAU, strict=True)])

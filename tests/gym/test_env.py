"""The Gymnasium environment: API conformance, seeding, plant physics against simulate, rewards, rendering, errors."""

from __future__ import annotations

import math
import subprocess
import sys
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pendulab as pl
import pendulab.gym  # noqa: F401 - registers the id
from pendulab.gym import ENV_ID, DoublePendulumEnv, make_reward
from pendulab.gym.render import COLORS

KINDS = ("rigid", "elastic")
ACTUATIONS = ("pendubot", "acrobot", "full")


def _combos():
    for backend in ("native", "fmu"):
        marks = [pytest.mark.needs_cc] if backend == "fmu" else []
        for kind in KINDS:
            for act in ACTUATIONS:
                yield pytest.param(kind, act, backend, marks=marks, id=f"{kind}-{act}-{backend}")


def _episode(env, n, seed, action_seed):
    """States, held torques, observations and rewards of ``n`` random-action steps."""
    env.action_space.seed(action_seed)
    obs, _ = env.reset(seed=seed)
    X, U, O, R = [env.unwrapped.state], [], [obs], []
    for _ in range(n):
        obs, r, _, _, info = env.step(env.action_space.sample())
        X.append(env.unwrapped.state)
        U.append(info["tau"])
        O.append(obs)
        R.append(r)
    return np.array(X), np.array(U), np.array(O), np.array(R)


@pytest.mark.parametrize(("kind", "actuation", "backend"), list(_combos()))
def test_check_env_passes(kind, actuation, backend):
    env = gym.make(ENV_ID, model=kind, actuation=actuation, backend=backend, render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)  # gymnasium's checker warns on doubtful spaces
        check_env(env.unwrapped)
    env.close()


@pytest.mark.parametrize("kind", KINDS)
def test_same_seed_same_episode(kind):
    env = gym.make(ENV_ID, model=kind, actuation="full")
    X1, U1, O1, R1 = _episode(env, 30, seed=7, action_seed=1)
    X2, U2, O2, R2 = _episode(env, 30, seed=7, action_seed=1)
    # Bit-identical: same seed, same actions, and the integrator keeps no state between episodes.
    np.testing.assert_array_equal(X1, X2)
    np.testing.assert_array_equal(R1, R2)
    np.testing.assert_array_equal(O1, O2)
    X3, *_ = _episode(env, 1, seed=8, action_seed=1)
    assert np.abs(X3[0] - X1[0]).max() > 1e-4  # another seed starts elsewhere (noise of 0.05 rad)


@pytest.mark.parametrize("kind", KINDS)
def test_native_plant_equals_simulate_under_zoh(kind):
    env = gym.make(ENV_ID, model=kind, actuation="full", torque_limit=5.0)
    X, U, _, _ = _episode(env, 60, seed=3, action_seed=0)
    model, dt = env.unwrapped.model, env.unwrapped.dt
    assert np.ptp(U[:, 0]) > 5.0 and np.ptp(U[:, 1]) > 5.0  # the torques really change every sample
    ref = pl.simulate(model, X[0], 60 * dt, dt=dt, method="taylor", rtol=1e-15, atol=1e-15, u=U)
    # Same integrator family at tol 1e-10 vs 1e-15 over 0.6 s near the hanging state (no chaotic growth).
    np.testing.assert_allclose(X, ref.x, rtol=0, atol=1e-9)
    ref = pl.simulate(model, X[0], 60 * dt, dt=dt, method="cvodes", rtol=1e-12, atol=1e-12, u=U)
    # An independent integrator (CVODES BDF): its own achieved error at 1e-12 is ~1e-9 here.
    np.testing.assert_allclose(X, ref.x, rtol=0, atol=1e-7)


@pytest.mark.needs_cc
@pytest.mark.parametrize("kind", KINDS)
def test_fmu_backend_equals_native_backend(kind):
    runs = {}
    for backend in ("native", "fmu"):
        env = gym.make(ENV_ID, model=kind, actuation="full", backend=backend)
        runs[backend] = _episode(env, 40, seed=5, action_seed=2)
        env.close()
    np.testing.assert_array_equal(runs["native"][1], runs["fmu"][1])  # same held torques
    # FMU's embedded DOPRI5 at rtol = atol = 1e-10 against Taylor at 1e-10, 0.4 s from near rest.
    np.testing.assert_allclose(runs["native"][0], runs["fmu"][0], rtol=0, atol=1e-7)


@pytest.mark.needs_cc
def test_compiled_integrator_equals_taylor():
    X = {}
    for integrator in ("taylor", "compiled-dopri5", "compiled-rodas4"):
        env = gym.make(ENV_ID, model="elastic", actuation="full", integrator=integrator)
        assert env.unwrapped.integrator == integrator
        X[integrator] = _episode(env, 30, seed=1, action_seed=1)[0]
    # The C solvers at rtol = atol = 1e-10 against Taylor at 1e-10, 0.3 s from near rest.
    np.testing.assert_allclose(X["compiled-dopri5"], X["taylor"], rtol=0, atol=1e-7)
    np.testing.assert_allclose(X["compiled-rodas4"], X["taylor"], rtol=0, atol=1e-7)


@pytest.mark.parametrize(("actuation", "index"), [("pendubot", (0,)), ("acrobot", (1,)), ("full", (0, 1))])
def test_action_scaling_and_clipping(actuation, index):
    env = gym.make(ENV_ID, actuation=actuation, torque_limit=3.0).unwrapped
    n = len(index)
    assert env.action_space.shape == (n,) and env.action_scale == 3.0
    start = {"state": env.model.state(theta1=0.3)}
    env.reset(options=start)
    _, _, _, _, info = env.step(np.full(n, 0.5))
    expected = np.zeros(2)
    expected[list(index)] = 1.5
    np.testing.assert_array_equal(info["tau"], expected)
    env.reset(options=start)
    x_clip = env.step(np.full(n, 7.0))[4]["tau"], env.state
    env.reset(options=start)
    x_one = env.step(np.full(n, 1.0))[4]["tau"], env.state
    np.testing.assert_array_equal(x_clip[0], x_one[0])  # clipped to the limit
    np.testing.assert_array_equal(x_clip[1], x_one[1])
    env.reset(options=start)
    assert np.all(env.step(np.full(n, -9.0))[4]["tau"][list(index)] == -3.0)


def test_torque_moves_the_driven_link():
    # From rest hanging, a positive tau1 accelerates link 1 positively (generalized force tau1 - tau2 on theta1).
    env = gym.make(ENV_ID, actuation="pendubot").unwrapped
    env.reset(options={"state": env.model.rest_state()})
    env.step(np.array([1.0]))
    assert env.state[2] > 0.0


def test_observation_is_the_documented_function_of_the_state():
    for kind in KINDS:
        env = gym.make(ENV_ID, model=kind, velocity_scale=4.0).unwrapped
        x = env.model.state(theta1=0.7, theta2=-2.0, omega1=3.0, omega2=-1.0)
        if kind == "elastic":
            x[2:4] += (0.01, -0.02)
            x[6:8] = (0.5, -0.25)
        obs, _ = env.reset(options={"state": x})
        expect = [math.cos(0.7), math.sin(0.7), math.cos(-2.0), math.sin(-2.0), 3.0 / 4.0, -1.0 / 4.0]
        if kind == "elastic":
            expect += [x[2] - 1.0, x[3] - 1.0, 0.5 / 4.0, -0.25 / 4.0]
        np.testing.assert_allclose(obs, expect, rtol=2e-7, atol=1e-7)  # float32 rounding
        np.testing.assert_array_equal(env.state, x)


def test_truncation_at_episode_length():
    env = gym.make(ENV_ID, dt=0.02, episode_length=0.1)
    env.reset(seed=0)
    flags = [env.step(np.zeros(1))[3] for _ in range(5)]
    assert flags == [False, False, False, False, True]
    assert env.unwrapped.t == pytest.approx(0.1, abs=1e-12)  # 5 steps of 20 ms


def test_termination_when_a_spring_collapses():
    env = gym.make(ENV_ID, model="elastic").unwrapped
    x = env.model.state(r1=0.02, v1=-20.0)  # 20 m/s inward, 2 cm from the pivot: r1 reaches 0 within a step
    env.reset(options={"state": x})
    _, _, terminated, truncated, info = env.step(np.zeros(1))
    assert terminated and not truncated
    assert np.all(np.isfinite(env.state))
    assert env.state[2] <= 0.0 or "failure" in info


def test_rewards_at_known_states():
    model = pl.rigid()
    realai, quad, height = (make_reward(n, model) for n in ("realai", "quadratic", "height"))
    up, down, zero = model.state(theta1=np.pi, theta2=np.pi), model.rest_state(), np.zeros(2)
    assert realai(up, zero) == 100.0  # zero cost at the goal, plus the bonus above 0.9 (L1 + L2)
    assert quad(up, zero) == 0.0
    # Wrapped angle errors: pi away on both angles, Q = 10 on each.
    assert quad(down, zero) == pytest.approx(-2 * 10 * np.pi**2, rel=1e-14)
    assert realai(model.state(theta1=3 * np.pi, theta2=-np.pi), zero) == pytest.approx(100.0, abs=1e-12)
    assert quad(up, np.array([10.0, 0.0])) == pytest.approx(-1e-4 * 100, rel=1e-14)  # R = 1e-4 on tau [N.m]
    assert height(up, zero) == pytest.approx(1.0, abs=1e-15) and height(down, zero) == pytest.approx(-1.0, abs=1e-15)
    # Just below the line: no bonus (tip at 0.89 of the reach).
    a = np.arccos(0.89)
    assert realai(model.state(theta1=np.pi - a, theta2=np.pi + a), zero) < 0.0


def test_user_reward_callable_is_used():
    calls = []

    def reward(x, tau):
        calls.append((x.copy(), tau.copy()))
        return float(tau[0])

    env = gym.make(ENV_ID, reward=reward, torque_limit=2.0).unwrapped
    env.reset(seed=0)
    _, r, *_ = env.step(np.array([0.25]))
    assert r == 0.5 and len(calls) == 1
    np.testing.assert_array_equal(calls[0][0], env.state)


@pytest.mark.parametrize("kind", KINDS)
def test_render_draws_the_bobs_where_kinematics_puts_them(kind):
    env = gym.make(ENV_ID, model=kind, render_mode="rgb_array", render_size=200).unwrapped
    x = env.model.state(theta1=2.4, theta2=1.0)
    env.reset(options={"state": x})
    frame = env.render()
    assert frame.shape == (200, 200, 3) and frame.dtype == np.uint8
    x1, y1, x2, y2 = env.model.positions(x)
    renderer = env._renderer
    for (px, py), color in (((x1, y1), "bob1"), ((x2, y2), "bob2"), ((0.0, 0.0), "pivot")):
        col, row = renderer.to_pixel(np.array([px, py]))
        assert tuple(frame[row, col]) == COLORS[color]
    assert tuple(frame[5, 5]) == COLORS["background"]  # a corner far from the pendulum
    assert gym.make(ENV_ID).unwrapped.render() is None  # no render_mode: nothing drawn


@pytest.mark.parametrize(
    ("kwargs", "exc", "words"),
    [
        ({"model": "floppy"}, ValueError, "model"),
        ({"model": 3}, TypeError, "model"),
        ({"actuation": "cartpole"}, ValueError, "actuation"),
        ({"backend": "mujoco"}, ValueError, "backend"),
        ({"dt": -0.01}, ValueError, "dt"),
        ({"dt": float("nan")}, ValueError, "dt"),
        ({"torque_limit": 0.0}, ValueError, "torque_limit"),
        ({"episode_length": 0.001}, ValueError, "episode_length"),
        ({"reward": "fun"}, ValueError, "reward"),
        ({"reward": 1.0}, TypeError, "reward"),
        ({"integrator": "euler"}, ValueError, "integrator"),
        ({"render_mode": "human"}, ValueError, "render_mode"),
        ({"params": {"k9": 1.0}}, ValueError, "k9"),
        ({"params": {"m1": -1.0}}, ValueError, "m1"),
        ({"reset_noise": -1.0}, ValueError, "reset_noise"),
        ({"velocity_scale": 0.0}, ValueError, "velocity_scale"),
    ],
)
def test_bad_kwargs_raise_naming_the_argument(kwargs, exc, words):
    with pytest.raises(exc, match=words):
        DoublePendulumEnv(**kwargs)


def test_bad_actions_and_options():
    env = DoublePendulumEnv(actuation="full")
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(2))
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.step(np.zeros(3))
    with pytest.raises(ValueError, match="NaN"):
        env.step(np.array([np.nan, 0.0]))
    with pytest.raises(ValueError, match="options"):
        env.reset(options={"theta": 1.0})
    with pytest.raises(ValueError, match="state"):
        env.reset(options={"state": [0.0, 0.0, np.inf, 0.0]})


def test_import_without_gymnasium_names_the_extra():
    code = "import sys; sys.modules['gymnasium'] = None\ntry:\n import pendulab.gym\nexcept ImportError as e: print(e)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert 'pip install "pendulab[gym]"' in out


# -- vector environment (heyoka batch mode) ----------------------------------------------------
@pytest.mark.parametrize("kind", KINDS)
def test_vector_lanes_equal_single_envs(kind):
    n, steps = 4, 25
    venv = gym.make_vec(ENV_ID, num_envs=n, model=kind, actuation="full")
    assert isinstance(venv, pendulab.gym.DoublePendulumVectorEnv)
    single = gym.make(ENV_ID, model=kind, actuation="full").unwrapped
    rng = np.random.default_rng(4)
    X0 = np.array([single.model.state(theta1=a, theta2=-a) for a in (0.1, 1.0, 2.0, 3.0)])
    A = rng.uniform(-1.2, 1.2, (steps, n, 2)).astype(np.float32)
    obs, _ = venv.reset(options={"state": X0})
    V_obs, V_rew, V_x = [obs], [], []
    for k in range(steps):
        obs, rew, *_ = venv.step(A[k])
        V_obs.append(obs)
        V_rew.append(rew)
        V_x.append(venv.states)
    for i in range(n):
        obs, _ = single.reset(options={"state": X0[i]})
        np.testing.assert_array_equal(obs, V_obs[0][i])
        for k in range(steps):
            obs, rew, *_ = single.step(A[k, i])
            # Batch and scalar Taylor integrators differ only by rounding (SIMD lanes), 0.25 s of motion.
            np.testing.assert_allclose(single.state, V_x[k][i], rtol=0, atol=1e-11)
            np.testing.assert_allclose(rew, V_rew[k][i], rtol=1e-10, atol=1e-9)  # vectorised reward, same formula
            np.testing.assert_allclose(obs, V_obs[k + 1][i], rtol=0, atol=1e-6)  # float32 observations


def test_vector_autoreset_next_step_and_seeding():
    kw = {"num_envs": 3, "actuation": "pendubot", "dt": 0.02, "episode_length": 0.06}
    runs = []
    for _ in range(2):
        venv = gym.make_vec(ENV_ID, **kw)
        obs0, _ = venv.reset(seed=11)
        out = [venv.step(np.full((3, 1), 0.5, dtype=np.float32)) for _ in range(4)]
        runs.append((obs0, out, venv.states))
    (obs0, out, states), (obs0b, outb, statesb) = runs
    np.testing.assert_array_equal(obs0, obs0b)  # same seed, same resets
    np.testing.assert_array_equal(states, statesb)
    assert [bool(o[3].all()) for o in out] == [False, False, True, False]  # truncated after 3 steps of 20 ms
    np.testing.assert_array_equal(out[3][1], 0.0)  # the next step resets: reward 0, flags False
    assert not out[3][2].any() and not out[3][3].any()
    assert np.abs(out[3][0] - obs0).max() > 1e-4  # fresh noise, not the first start again


def test_vector_env_rejects_what_it_cannot_run():
    with pytest.raises(ValueError, match="fmu"):
        pendulab.gym.DoublePendulumVectorEnv(num_envs=2, backend="fmu")
    with pytest.raises(ValueError, match="num_envs"):
        pendulab.gym.DoublePendulumVectorEnv(num_envs=0)
    venv = pendulab.gym.DoublePendulumVectorEnv(num_envs=2, actuation="full")
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="actions"):
        venv.step(np.zeros((3, 2)))

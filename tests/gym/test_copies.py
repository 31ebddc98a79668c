"""Copies of the environment (pickle, copy.deepcopy, cloudpickle as Dask/joblib/Ray use it) step exactly like the original.

Bitwise comparisons throughout: a copy rebuilds the same compiled code (Taylor integrator, C
library, FMU) and restores the full integrator state (state, double-length time, step-size
guess; the FMU replays its episode), so it performs the same floating-point operations.
"""

from __future__ import annotations

import copy
import os
import pickle
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import pendulab.gym  # noqa: F401 - registers the id
from pendulab.gym import ENV_ID, DoublePendulumEnv
from pendulab.gym import backends as gym_backends

ROOT = Path(__file__).resolve().parents[2]


def _cloudpickle_copy(obj):
    cloudpickle = pytest.importorskip("cloudpickle")  # installed with dask (pendulab[ensemble])
    return cloudpickle.loads(cloudpickle.dumps(obj))


COPIERS = {
    "pickle": lambda obj: pickle.loads(pickle.dumps(obj)),
    "deepcopy": copy.deepcopy,
    "cloudpickle": _cloudpickle_copy,
}
PLANTS = [
    pytest.param({"model": "rigid", "integrator": "taylor"}, id="rigid-taylor"),
    pytest.param({"model": "elastic", "integrator": "taylor"}, id="elastic-taylor"),
    pytest.param({"model": "rigid", "integrator": "compiled-dopri5"}, marks=pytest.mark.needs_cc, id="rigid-dopri5"),
    pytest.param({"model": "elastic", "integrator": "compiled-rodas4"}, marks=pytest.mark.needs_cc, id="elastic-rodas4"),
    pytest.param({"model": "rigid", "backend": "fmu"}, marks=pytest.mark.needs_cc, id="rigid-fmu"),
    pytest.param({"model": "elastic", "backend": "fmu", "fmu_solver": "rodas4"}, marks=pytest.mark.needs_cc, id="elastic-fmu"),
]


def _steps(env, actions):
    """Observations, rewards, flags, states and held torques of a run of ``actions``."""
    out = []
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append((obs, r, term, trunc, env.unwrapped.state, info["tau"]))
    return out


def _assert_same(run_a, run_b):
    for k, (a, b) in enumerate(zip(run_a, run_b, strict=True)):
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {k}")


@pytest.mark.parametrize("how", list(COPIERS))
@pytest.mark.parametrize("kwargs", PLANTS)
def test_a_copy_mid_episode_steps_bit_for_bit_like_the_original(kwargs, how):
    env = gym.make(ENV_ID, actuation="full", render_mode="rgb_array", **kwargs)
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1.2, 1.2, (90, 2)).astype(np.float32)  # some beyond the limit: clipping is exercised
    env.reset(seed=4)
    _steps(env, actions[:40])  # mid-episode: the integrator carries time and a step-size guess
    twin = COPIERS[how](env)
    assert twin.unwrapped.integrator == env.unwrapped.integrator and twin.unwrapped.t == env.unwrapped.t
    np.testing.assert_array_equal(twin.unwrapped.state, env.unwrapped.state)
    _assert_same(_steps(env, actions[40:]), _steps(twin, actions[40:]))
    # The copies are independent: stepping one leaves the other where it was.
    before = env.unwrapped.state
    twin.step(np.ones(2, dtype=np.float32))
    np.testing.assert_array_equal(env.unwrapped.state, before)
    # Seeded resets continue the same random stream in both.
    np.testing.assert_array_equal(env.reset()[0], twin.reset()[0])
    np.testing.assert_array_equal(twin.render(), env.render())  # the renderer is rebuilt too
    env.close()
    twin.close()


@pytest.mark.parametrize("kwargs", PLANTS)
def test_copies_before_reset_and_after_close(kwargs):
    env = DoublePendulumEnv(actuation="pendubot", **kwargs)
    twin = copy.deepcopy(env)
    with pytest.raises(RuntimeError, match="reset"):
        twin.step(np.zeros(1))
    a, b = env.reset(seed=1)[0], twin.reset(seed=1)[0]
    np.testing.assert_array_equal(a, b)
    env.close()
    after = pickle.loads(pickle.dumps(env))
    np.testing.assert_array_equal(after.reset(seed=1)[0], a)
    after.close()
    twin.close()


def test_a_pickled_env_steps_identically_in_another_process():
    env = gym.make(ENV_ID, model="elastic", actuation="full")
    actions = np.random.default_rng(8).uniform(-1, 1, (60, 2)).astype(np.float32)
    env.reset(seed=2)
    _steps(env, actions[:20])
    blob = pickle.dumps((env, actions[20:]))
    expected = np.array([s[0] for s in _steps(env, actions[20:])])
    code = (
        "import pickle, sys, numpy as np\n"
        "env, actions = pickle.loads(sys.stdin.buffer.read())\n"
        "obs = np.array([env.step(a)[0] for a in actions])\n"
        "sys.stdout.buffer.write(pickle.dumps(obs))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], input=blob, cwd=ROOT, capture_output=True, timeout=300, env=os.environ)
    assert proc.returncode == 0, proc.stderr.decode()[-2000:]
    # A fresh process compiles its own Taylor integrator: the same code from the same expressions, bit for bit.
    np.testing.assert_array_equal(pickle.loads(proc.stdout), expected)


@pytest.mark.needs_cc
def test_fmu_backend_refuses_to_copy_an_episode_too_long_to_replay(monkeypatch):
    monkeypatch.setattr(gym_backends, "MAX_REPLAY_STEPS", 5)
    env = DoublePendulumEnv(backend="fmu")
    env.reset(seed=0)
    for _ in range(6):
        env.step(np.zeros(1))
    with pytest.raises(ValueError, match=r"more than 5 steps since the last reset.*reset\(\)"):
        pickle.dumps(env)
    env.reset(seed=0)  # a reset makes it copyable again
    np.testing.assert_array_equal(copy.deepcopy(env).state, env.state)
    env.close()


@pytest.mark.parametrize("how", list(COPIERS))
def test_vector_env_copies_step_bit_for_bit_through_autoresets(how):
    n = 5
    venv = gym.make_vec(ENV_ID, num_envs=n, model="elastic", actuation="full", dt=0.02, episode_length=0.2)
    actions = np.random.default_rng(6).uniform(-1, 1, (40, n, 2)).astype(np.float32)
    venv.reset(seed=9)
    for a in actions[:13]:
        venv.step(a)
    twin = COPIERS[how](venv)
    for k, a in enumerate(actions[13:]):  # 27 more steps of a 10-step episode: autoresets draw from the copied generator
        for x, y in zip(venv.step(a)[:4], twin.step(a)[:4], strict=True):
            np.testing.assert_array_equal(x, y, err_msg=f"step {k}")
        np.testing.assert_array_equal(venv.states, twin.states)

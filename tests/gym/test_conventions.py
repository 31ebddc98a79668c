"""Gymnasium conventions (spec.max_episode_steps, render_fps) and the env's argument checks (tolerance, spring lengths, extra)."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import pendulab.gym  # noqa: F401 - registers the id
from pendulab.gym import ENV_ID, DoublePendulumEnv, DoublePendulumVectorEnv


def _truncation_step(env, limit=5000):
    """The step (1-based) at which the first episode is truncated, stepping zero torques."""
    env.reset(seed=0)
    n_act = env.action_space.shape[-1]
    for k in range(1, limit + 1):
        *_, truncated, _ = env.step(np.zeros(n_act, dtype=np.float32))
        if truncated:
            return k
    return None


@pytest.mark.parametrize(
    ("kwargs", "steps"),
    [({}, 1000), ({"dt": 0.02}, 500), ({"dt": 0.02, "episode_length": 0.1}, 5)],
)
def test_spec_max_episode_steps_is_the_envs_own_horizon(kwargs, steps):
    env = gym.make(ENV_ID, **kwargs)
    assert env.unwrapped.max_episode_steps == steps
    assert env.spec.max_episode_steps == steps and env.unwrapped.spec.max_episode_steps == steps
    if steps <= 500:  # the horizon the spec reports is where the episode really ends
        assert _truncation_step(env) == steps


def test_max_episode_steps_and_episode_length_must_agree():
    env = DoublePendulumEnv(dt=0.02, episode_length=0.2, max_episode_steps=10)  # both say 10 steps
    assert env.max_episode_steps == 10
    env = DoublePendulumEnv(max_episode_steps=7)  # alone: the horizon in steps (episode_length follows)
    assert env.max_episode_steps == 7 and _truncation_step(env) == 7
    with pytest.raises(ValueError, match=r"max_episode_steps=7 and episode_length=0.2 s disagree"):
        DoublePendulumEnv(dt=0.02, episode_length=0.2, max_episode_steps=7)
    for bad in (0, -3, 2.5, "ten", True, 10**12):
        with pytest.raises(ValueError, match="max_episode_steps"):
            DoublePendulumEnv(max_episode_steps=bad)


def test_gym_make_time_limit_shorter_than_the_horizon_ends_the_episode_there():
    env = gym.make(ENV_ID, max_episode_steps=12)  # Gymnasium's TimeLimit wrapper
    assert env.spec.max_episode_steps == 12 and _truncation_step(env) == 12


def test_make_vec_max_episode_steps_is_honoured():
    venv = gym.make_vec(ENV_ID, num_envs=3, max_episode_steps=4, dt=0.02)
    assert isinstance(venv, DoublePendulumVectorEnv)
    assert venv.spec.max_episode_steps == 4 and venv.max_episode_steps == 4
    venv.reset(seed=0)
    flags = [bool(venv.step(np.zeros((3, 1), dtype=np.float32))[3].all()) for _ in range(4)]
    assert flags == [False, False, False, True]  # every lane truncated after the 4 steps asked for (not 500)
    default = gym.make_vec(ENV_ID, num_envs=2)
    assert default.spec.max_episode_steps == default.max_episode_steps == 1000
    with pytest.raises(ValueError, match="disagree"):
        gym.make_vec(ENV_ID, num_envs=2, max_episode_steps=4, episode_length=10.0)


def test_render_fps_class_and_instance_agree():
    # Gymnasium's convention: render_fps = 1 / dt (frames advance by the env's own time step).
    for cls in (DoublePendulumEnv, DoublePendulumVectorEnv):
        assert cls.metadata["render_fps"] == 100  # the default dt = 0.01 s
    assert gym.make(ENV_ID).metadata["render_fps"] == DoublePendulumEnv.metadata["render_fps"]
    assert gym.make_vec(ENV_ID, num_envs=2).metadata["render_fps"] == DoublePendulumVectorEnv.metadata["render_fps"]
    assert gym.make(ENV_ID, dt=0.02).metadata["render_fps"] == 50  # an instance at another dt reports its own
    assert gym.make_vec(ENV_ID, num_envs=2, dt=0.04).metadata["render_fps"] == 25


@pytest.mark.parametrize("tol", [1.0, 10.0, 0.0, -1e-8, float("nan")])
def test_tolerance_outside_zero_one_is_refused(tol, monkeypatch, tmp_path):
    monkeypatch.setenv("PENDULAB_CACHE_DIR", str(tmp_path / "cache"))
    for kwargs in ({}, {"integrator": "compiled-dopri5"}, {"backend": "fmu"}):
        with pytest.raises(ValueError, match=r"tol = .*expected a finite number in \[2.22e-16, 1\)"):
            DoublePendulumEnv(tol=tol, **kwargs)
    with pytest.raises(ValueError, match="tol"):
        gym.make_vec(ENV_ID, num_envs=2, tol=tol)
    assert not (tmp_path / "cache").exists()  # refused before any library or FMU was built


@pytest.mark.parametrize("r1", [0.0, -1.0, float("-inf")])
def test_reset_states_with_a_spring_length_at_or_below_zero_are_refused(r1):
    env = DoublePendulumEnv(model="elastic")
    x = env.model.rest_state()
    x[2] = r1
    with pytest.raises(ValueError, match=r"options\['state'\]"):
        env.reset(options={"state": x})
    venv = DoublePendulumVectorEnv(num_envs=3, model="elastic")
    X = np.tile(env.model.rest_state(), (3, 1))
    X[1, 3] = r1
    with pytest.raises(ValueError, match=r"options\['state'\](\[1\])?"):
        venv.reset(options={"state": X})
    if np.isfinite(r1):
        with pytest.raises(ValueError, match=r"options\['state'\]\[1\]: spring lengths r1, r2 must be > 0 m"):
            venv.reset(options={"state": X})
    # The rigid state's third entry is a rate: any value is a state.
    rigid = DoublePendulumEnv(model="rigid")
    rigid.reset(options={"state": [0.0, 0.0, -1.0, 0.0]})


def test_missing_gymnasium_is_a_missing_extra_error_naming_the_extra():
    code = (
        "import sys; sys.modules['gymnasium'] = None\n"
        "from pendulab._checks import MissingExtraError\n"
        "try:\n    import pendulab.gym\n"
        "except MissingExtraError as e:\n    print(isinstance(e, ImportError), e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120).stdout
    assert out.startswith("True ") and "pendulab[gym]" in out and "gymnasium" in out

"""The environments' observation pipeline: measurement model (delay, rate noise) and a state estimator."""

from __future__ import annotations

import copy
import pickle
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pendulab.gym  # noqa: F401 - registers the id
from pendulab.evaluate.measurement import MeasurementModel
from pendulab.gym import ENV_ID, DoublePendulumEnv


def _actions(n, n_act=1):
    """A smooth pumping torque (a few N.m at the default limit): the links swing, the rates are not ~0."""
    return [np.full(n_act, 0.8 * np.sin(0.06 * k), dtype=np.float32) for k in range(n)]


def _rms_rate_error(env, n=300):
    env.reset(seed=4)
    errs = []
    for a in _actions(n):
        env.step(a)
        u = env.unwrapped
        errs.append(u.estimate[2:4] - u.state[2:4])
    return float(np.sqrt(np.mean(np.square(errs))))


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_check_env_passes_with_measurement_and_estimator(kind):
    env = gym.make(ENV_ID, model=kind, actuation="pendubot", measurement=MeasurementModel(0.2, 2), estimator="ekf")
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)  # gymnasium's checker warns on doubtful spaces
        check_env(env.unwrapped)  # includes: same seed, same first observation (noise from the env's generator)
    env.close()


def test_ekf_observation_beats_the_noisy_measurement():
    raw = gym.make(ENV_ID, actuation="pendubot", measurement=MeasurementModel(0.3))
    ekf = gym.make(ENV_ID, actuation="pendubot", measurement=MeasurementModel(0.3), estimator="ekf")
    rms_raw, rms_ekf = _rms_rate_error(raw), _rms_rate_error(ekf)
    assert rms_raw == pytest.approx(0.3, rel=0.1)  # 2 x 300 draws: the sample RMS is within 10 % (> 3 sigma)
    # The angles are exact (1e-4 rad assumed), so the filter's rates follow their increments over 10 ms, not the rate
    # noise: measured 0.014 rad/s against 0.29; a factor 5 leaves room for other seeds.
    assert rms_ekf < rms_raw / 5


def test_exact_measurement_and_ekf_reproduce_the_plain_observations():
    def episode(**kw):
        env = gym.make(ENV_ID, actuation="acrobot", **kw)
        obs = [env.reset(seed=7)[0]]
        obs += [env.step(a)[0] for a in _actions(200)]
        return np.array(obs)

    plain = episode()
    np.testing.assert_array_equal(episode(measurement=MeasurementModel()), plain)  # the measurement is the state
    # The EKF blends the exact state with its 10 ms RK4 prediction: measured 1.05e-5 on a rate scaled by 1/10 (1e-4
    # rad/s at 8 rad/s); 1e-4 bounds it with room, far below the 0.03 (0.3 rad/s) a noise of the test above makes.
    np.testing.assert_allclose(episode(estimator="ekf"), plain, atol=1e-4)


def test_reset_restarts_the_pipeline():
    env = gym.make(ENV_ID, actuation="pendubot", measurement=MeasurementModel(0.2, 3), estimator="ekf")

    def episode():
        obs = [env.reset(seed=11)[0]]
        return np.array(obs + [env.step(a)[0] for a in _actions(50)])

    first = episode()
    np.testing.assert_array_equal(episode(), first)  # same seed: same noise, same filter run from its prior
    # The start: delay line and prior at the start state; the noisy rate measurement (sigma 0.2, assumed 0.1) is
    # weighed against the prior's 1e-3 and moves the estimate by ~(1e-3 / 0.1)^2 x 0.2 = 2e-5: within 1e-3 of the state.
    env.reset(seed=11)
    np.testing.assert_allclose(env.unwrapped.estimate, env.unwrapped.state, atol=1e-3)


def test_vector_env_lanes_match_the_single_env():
    x0 = np.array([0.2, -0.1, 0.0, 0.0])
    kw = {"actuation": "pendubot", "measurement": MeasurementModel(0.0, 2), "estimator": "ekf"}
    single = DoublePendulumEnv(integrator="taylor", **kw)
    venv = gym.make_vec(ENV_ID, num_envs=2, **kw)
    o1 = [single.reset(options={"state": x0})[0]]
    ov = [venv.reset(options={"state": x0})[0]]
    for a in _actions(100):
        o1.append(single.step(a)[0])
        ov.append(venv.step(np.tile(a, (2, 1)))[0])
    o1, ov = np.array(o1), np.array(ov)
    # Same plant (heyoka single vs batch at tol 1e-10), same delay, same filter per lane: float32 round-off apart.
    np.testing.assert_allclose(ov[:, 0], o1, atol=1e-5)
    np.testing.assert_allclose(ov[:, 1], o1, atol=1e-5)


def test_vector_env_autoreset_restarts_a_lanes_pipeline():
    venv = gym.make_vec(ENV_ID, num_envs=2, max_episode_steps=5, actuation="pendubot",
                        measurement=MeasurementModel(0.0, 3), estimator="ekf")  # fmt: skip
    venv.reset(seed=2)
    for a in _actions(5):
        venv.step(np.tile(a, (2, 1)))
    obs, *_ = venv.step(np.zeros((2, 1), dtype=np.float32))  # the autoreset step: both lanes start anew
    # A restarted lane's delay line and prior hold its new start state: the observation is of that state.
    U = venv.unwrapped
    np.testing.assert_allclose(U.estimates, U.states, atol=1e-6)
    np.testing.assert_allclose(obs, U._observe(U.states), atol=1e-6)


def test_copies_of_an_env_with_an_estimator_step_alike():
    env = gym.make(ENV_ID, actuation="pendubot", measurement=MeasurementModel(0.2, 1), estimator="ekf").unwrapped
    env.reset(seed=3)
    for a in _actions(10):
        env.step(a)
    for twin in (copy.deepcopy(env), pickle.loads(pickle.dumps(env))):
        ref = copy.deepcopy(env)  # the original's continuation, kept apart from the next twin
        for a in _actions(10):
            np.testing.assert_array_equal(twin.step(a)[0], ref.step(a)[0])  # delay line, noise stream, filter copied


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"estimator": "kalman"}, ValueError, "estimator must be one of"),
        ({"estimator": 3}, TypeError, "estimator must be one of"),
        ({"measurement": 0.3}, TypeError, "measurement must be"),
    ],
)
@pytest.mark.parametrize("vector", [False, True])
def test_bad_estimator_or_measurement_is_named(kwargs, exc, match, vector):
    with pytest.raises(exc, match=match):
        gym.make_vec(ENV_ID, num_envs=2, **kwargs) if vector else gym.make(ENV_ID, **kwargs)


class Diverging:
    """An estimator that passes the measurement through, then returns NaN from its 4th update on."""

    def reset(self):
        self.k = 0

    def update(self, t, y, u=None):
        self.k += 1
        return np.asarray(y, dtype=float) * (np.nan if self.k > 3 else 1.0)


def test_a_diverged_estimator_ends_the_episode_with_an_observation_in_the_space():
    env = gym.make(ENV_ID, actuation="pendubot", estimator=Diverging())
    env.reset(seed=0)
    steps = [env.step(a) for a in _actions(3)]
    assert not any(s[2] for s in steps[:2])  # updates 2, 3: finite
    obs, _, terminated, _, info = steps[2]  # update 4: NaN
    assert terminated and "estimator diverged" in info["failure"]
    assert env.observation_space.contains(obs)  # the measurement is observed instead
    venv = gym.make_vec(ENV_ID, num_envs=2, actuation="pendubot", estimator=Diverging())
    venv.reset(seed=0)
    flags = [venv.step(np.tile(a, (2, 1)))[2] for a in _actions(3)]
    assert not flags[1].any() and flags[2].all()


def test_mmae_identifies_the_delay_from_each_episodes_random_start():
    env = gym.make(ENV_ID, actuation="pendubot", measurement=MeasurementModel(0.0, 3), estimator="mmae")
    for seed in (4, 5):
        env.reset(seed=seed)  # a random start near hanging: the bank's predictions must start there, not at rest
        errs = []
        for a in _actions(120):
            env.step(a)
            errs.append(np.abs(env.unwrapped.estimate - env.unwrapped.state).max())
        assert env.unwrapped._pipeline.estimator.hypothesis[0] == pytest.approx(0.03)  # 3 samples of 10 ms
        # Locked on the right delay, the rolled-forward estimate is the current state (measured 1.4e-5: the 10 ms RK4
        # rollout over 3 samples against the Taylor plant); a wrong delay is off by 0.1-0.8.
        assert max(errs[50:]) < 1e-3

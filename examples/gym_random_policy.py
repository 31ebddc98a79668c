"""Gymnasium environment: random and energy-pumping policies
=========================================================

Drive the Gymnasium environment with a random policy and a tiny energy-pumping policy; print their returns.

The energy-pumping policy (pendubot: only the shoulder torque tau1) pushes the shoulder with
its own angular velocity while the total energy is below that of the upright rest state,
``tau1 = limit * clip(gain * (E_up - E) * omega1)``: the torque's power ``tau1 * omega1`` is
then positive, so each swing gains energy and the tip climbs towards the top. It needs no
learning and no RL library; it shows the environment's API (``reset(seed=...)``, ``step``,
``env.unwrapped.state``, ``env.unwrapped.model``) and gives a baseline return to beat.

    python examples/gym_random_policy.py
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

import pendulab.gym  # noqa: F401 - registers "pendulab/DoublePendulum-v0"

#: Keyword arguments used by tests/test_examples.py (short episodes).
TEST_KWARGS = {"episode_length": 2.0, "episodes": 1}


def run_episode(env: gym.Env, policy, seed: int) -> dict[str, float]:
    """One episode; returns its return and the highest tip height reached [m]."""
    obs, _ = env.reset(seed=seed)
    model = env.unwrapped.model
    total, best = 0.0, -np.inf
    done = False
    while not done:
        obs, reward, terminated, truncated, _ = env.step(policy(env, obs))
        total += reward
        best = max(best, float(model.positions(env.unwrapped.state)[3]))
        done = terminated or truncated
    return {"return": total, "max_tip_height": best}


def energy_pumping(gain: float = 0.5):
    """The pendubot energy-pumping policy ``a = clip(gain (E_up - E) omega1, -1, 1)`` (E in J, omega1 in rad/s)."""

    def policy(env: gym.Env, obs: np.ndarray) -> np.ndarray:
        model = env.unwrapped.model
        x = env.unwrapped.state
        e_up = model.energy(model.state(theta1=np.pi, theta2=np.pi))
        a = gain * (e_up - model.energy(x)) * x[model.state_names.index("omega1")]
        return np.array([np.clip(a, -1.0, 1.0)], dtype=np.float32)

    return policy


def random_policy(env: gym.Env, obs: np.ndarray) -> np.ndarray:
    """Uniform random actions from the action space (seeded by the caller)."""
    return env.action_space.sample()


def run(*, episode_length: float = 10.0, episodes: int = 3, model: str = "rigid") -> dict[str, list[dict[str, float]]]:
    """Returns of both policies over a few seeded episodes.

    Parameters
    ----------
    episode_length : float
        Episode duration [s].
    episodes : int
        Episodes per policy (seeds 0, 1, ...).
    model : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    dict
        ``{"random": [...], "energy pumping": [...]}``, one ``{"return", "max_tip_height"}`` per episode.
    """
    env = gym.make("pendulab/DoublePendulum-v0", model=model, actuation="pendubot", episode_length=episode_length)
    env.action_space.seed(0)
    results = {
        name: [run_episode(env, policy, seed) for seed in range(episodes)]
        for name, policy in (("random", random_policy), ("energy pumping", energy_pumping()))
    }
    env.close()
    return results


def main() -> None:
    """Print the mean return and the highest tip reached by each policy."""
    for name, rows in run().items():
        ret = np.mean([r["return"] for r in rows])
        tip = max(r["max_tip_height"] for r in rows)
        print(f"{name:15s} mean return {ret:10.1f}   highest tip {tip:+.2f} m (top = +2.00 m)")


if __name__ == "__main__":
    main()

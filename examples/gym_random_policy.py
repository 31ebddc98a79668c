"""Gymnasium environment: random and energy-pumping policies
=========================================================

Drive the Gymnasium environment with a random policy and a tiny energy-pumping policy; print their returns.

The energy-pumping policy (pendubot: only the shoulder torque tau1) pushes the shoulder with
its own angular velocity while the total energy is below that of the upright rest state,
``tau1 = limit * clip(gain * (E_up - E) * omega1)``: the torque's power ``tau1 * omega1`` is
then positive, so each swing gains energy and the tip climbs towards the top. It needs no
learning and no RL library; it shows the environment's API (``reset(seed=...)``, ``step``,
``env.unwrapped.state``, ``env.unwrapped.model``) and gives a baseline return to beat.
The figure shows the tip height of each policy's first episode.

    python examples/gym_random_policy.py [OUT_DIR]     # default gym_figures; progress on stderr
"""

from __future__ import annotations

import sys
from pathlib import Path

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pendulab.gym  # noqa: F401, E402 - registers "pendulab/DoublePendulum-v0"


def run_episode(env: gym.Env, policy, seed: int) -> dict:
    """One episode; returns its return, the highest tip height reached [m] and the tip height per step [m]."""
    obs, _ = env.reset(seed=seed)
    model = env.unwrapped.model
    total, heights = 0.0, []
    done = False
    while not done:
        obs, reward, terminated, truncated, _ = env.step(policy(env, obs))
        total += reward
        heights.append(float(model.positions(env.unwrapped.state)[3]))
        done = terminated or truncated
    return {"return": total, "max_tip_height": max(heights), "tip_height": np.asarray(heights)}


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


def run(
    *,
    episode_length: float = 10.0,
    episodes: int = 3,
    model: str = "rigid",
    out_dir: str | Path | None = None,
    progress=None,
) -> dict[str, list[dict]]:
    """Returns of both policies over a few seeded episodes.

    Parameters
    ----------
    episode_length : float
        Episode duration [s].
    episodes : int
        Episodes per policy (seeds 0, 1, ...).
    model : {"rigid", "elastic"}
        Model kind.
    out_dir : str or Path, optional
        Where to write ``tip_height.png`` (first episode of each policy); no figure if None.
    progress : callable(str), optional
        Called with a one-line status before each policy's episodes.

    Returns
    -------
    dict
        ``{"random": [...], "energy pumping": [...]}``, one ``{"return", "max_tip_height", "tip_height"}``
        per episode.
    """
    env = gym.make("pendulab/DoublePendulum-v0", model=model, actuation="pendubot", episode_length=episode_length)
    env.action_space.seed(0)
    results = {}
    for name, policy in (("random", random_policy), ("energy pumping", energy_pumping())):
        if progress is not None:
            progress(f"{name} policy: {episodes} episodes of {episode_length:g} s ...")
        results[name] = [run_episode(env, policy, seed) for seed in range(episodes)]
    dt = env.unwrapped.dt
    env.close()
    if out_dir is not None:
        _figure(results, dt, Path(out_dir))
    return results


def _figure(results: dict[str, list[dict]], dt: float, out_dir: Path) -> Path:
    fig, ax = plt.subplots(figsize=(8.0, 3.8))
    for name, rows in results.items():
        h = rows[0]["tip_height"]
        ax.plot(dt * np.arange(1, len(h) + 1), h, lw=1.0, label=f"{name} (return {rows[0]['return']:.3g})")
    ax.axhline(2.0, color="k", lw=0.8, ls="--", label="top (tip at +2 m)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tip height [m]")
    ax.set_title("pendulab/DoublePendulum-v0, pendubot: first episode (seed 0) of each policy", fontsize=10)
    ax.set_ylim(-2.2, 2.9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left", ncols=3)
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "tip_height.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    """Print the mean return and the highest tip reached by each policy; write the figure."""
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("gym_figures")
    for name, rows in run(out_dir=out_dir, progress=lambda message: print(message, file=sys.stderr)).items():
        ret = np.mean([r["return"] for r in rows])
        tip = max(r["max_tip_height"] for r in rows)
        print(f"{name:15s} mean return {ret:10.1f}   highest tip {tip:+.2f} m (top = +2.00 m)")


if __name__ == "__main__":
    main()

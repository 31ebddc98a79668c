"""Gymnasium environment of the rigid and elastic double pendulum (needs ``pip install "pendulab[gym]"``).

Importing this package registers ``"pendulab/DoublePendulum-v0"``::

    import gymnasium as gym
    import pendulab.gym

    env = gym.make("pendulab/DoublePendulum-v0", model="rigid", actuation="pendubot", backend="native")

Keyword arguments are those of :class:`~pendulab.gym.env.DoublePendulumEnv`; truncation happens
inside the environment after ``episode_length`` seconds (``max_episode_steps`` steps), so no
``TimeLimit`` wrapper is added and ``env.spec.max_episode_steps`` reports that horizon.
``gym.make_vec(ENV_ID, num_envs=N, ...)`` builds :class:`~pendulab.gym.vector.DoublePendulumVectorEnv`
(N pendulums in one heyoka batch integrator); ``vectorization_mode="sync"`` gives Gymnasium's
``SyncVectorEnv`` of single environments instead (needed for ``backend="fmu"``).
"""

from __future__ import annotations

from .._checks import require_extra

#: How to install gymnasium with pendulab (the optional dependency group "gym").
EXTRA_HINT = 'pip install "pendulab[gym]"'

require_extra("gymnasium", "gym", "pendulab.gym (the Gymnasium environment)")  # MissingExtraError naming pendulab[gym]

import gymnasium  # noqa: E402 - after the check that names the extra

from .backends import INTEGRATORS, FmuBackend, NativePlant, cached_fmu  # noqa: E402
from .env import BACKENDS, ENV_ID, DoublePendulumEnv  # noqa: E402
from .render import FrameRenderer  # noqa: E402
from .rewards import REWARDS, HeightReward, QuadraticReward, make_reward  # noqa: E402
from .vector import DoublePendulumVectorEnv  # noqa: E402

if ENV_ID not in gymnasium.registry:
    gymnasium.register(
        id=ENV_ID,
        entry_point="pendulab.gym.env:DoublePendulumEnv",
        vector_entry_point="pendulab.gym.vector:DoublePendulumVectorEnv",
    )

__all__ = [
    "BACKENDS",
    "ENV_ID",
    "EXTRA_HINT",
    "INTEGRATORS",
    "REWARDS",
    "DoublePendulumEnv",
    "DoublePendulumVectorEnv",
    "FmuBackend",
    "FrameRenderer",
    "HeightReward",
    "NativePlant",
    "QuadraticReward",
    "cached_fmu",
    "make_reward",
]

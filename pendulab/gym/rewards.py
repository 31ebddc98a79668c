"""Rewards of the double-pendulum environment: RealAIGym-style quadratic cost, plain quadratic, tip height, or a callable.

A reward is called once per environment step as ``reward(x, tau) -> float`` with the state
*after* the step and the torques (tau1, tau2) [N.m] held during it. The built-in rewards are
plain-Python arithmetic on a few floats (a NumPy call costs about a microsecond; an
environment step has a budget of 50 us), and the tip height comes from the model's CasADi
``positions`` function translated to Python (:func:`pendulab.model.pycode.to_python`), so no
kinematics is typed here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .._inputs import checked
from ..model.model import Model
from ..model.pycode import to_python

__all__ = ["REWARDS", "RewardFn", "QuadraticReward", "HeightReward", "TipHeight", "make_reward", "tip_height_function"]

#: ``reward(x, tau) -> float``: state after the step (shape (nx,)) and held torques (tau1, tau2) [N.m].
RewardFn = Callable[[np.ndarray, np.ndarray], float]

#: Names accepted by :func:`make_reward`.
REWARDS: tuple[str, ...] = ("realai", "quadratic", "height")

_TWO_PI = 2.0 * math.pi


def tip_height_function(model: Model) -> Callable[[np.ndarray], float]:
    """A fast ``h(x) -> y2``: the end effector's (bob 2's) height above the pivot [m].

    Parameters
    ----------
    model : Model
        Rigid or elastic model; its parameters are bound into the returned function.

    Returns
    -------
    TipHeight
        ``h(x)`` with ``x`` of shape (nx,) (or a list), returning ``y2`` [m] (up positive), from the model's
        ``positions`` CasADi function translated to plain Python; picklable (rebuilt from the model).
    """
    return TipHeight(model)


class TipHeight:
    """``h(x) -> y2`` [m] of one model (see :func:`tip_height_function`); pickles as its model.

    Parameters
    ----------
    model : Model
        Rigid or elastic model; its parameters are bound in.
    """

    __slots__ = ("model", "_tip", "_p")

    def __init__(self, model: Model) -> None:
        f = model.functions["positions"]
        xs, ps = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("p", f.size1_in(1))
        # Only y2 of the model's positions (the same graph, its other outputs dropped): ~1 us faster per call.
        self.model = model
        self._tip = to_python(ca.Function("tip_height", [xs, ps], [f(xs, ps)[3]]))
        self._p = [float(v) for v in model.p]

    def __call__(self, x: np.ndarray) -> float:
        """Height of bob 2 above the pivot [m] at state ``x`` (shape (nx,) or a list)."""
        return float(self._tip(x, self._p)[0])

    def __reduce__(self) -> tuple[Any, tuple[Model]]:
        # The translated function is generated code: rebuild it from the model instead of pickling it.
        return (TipHeight, (self.model,))


@dataclass(frozen=True)
class QuadraticReward:
    """Negative quadratic cost about the upright goal, plus a bonus while the tip is high.

    ``r = -((x - goal)^T Q (x - goal) + tau^T R tau) + bonus * [y2 > height_fraction * (L1 + L2)]``,
    with the angle errors wrapped to [-pi, pi) (the goal is reached at every multiple of 2 pi),
    ``Q``, ``R`` diagonal.

    Attributes
    ----------
    q : tuple of float, length nx
        Diagonal of Q, in ``state_names`` order [1/unit^2 of each state].
    r : tuple of float, length 2
        Diagonal of R on (tau1, tau2) [1/(N.m)^2].
    goal : tuple of float, length nx
        Goal state (angles pi, rates 0; spring lengths carry zero weight by default).
    angle_index : tuple of int
        Entries of the state that are angles (wrapped).
    bonus : float
        Added while the tip is above the line (0 disables the line test).
    height_fraction : float
        The line is at ``height_fraction * (L1 + L2)`` above the pivot.
    tip_height : callable or None
        ``h(x) -> y2`` [m] (:func:`tip_height_function`); needed when ``bonus != 0``.
    reach : float
        ``L1 + L2`` [m] (rest lengths for the elastic model).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.gym import make_reward
    >>> model = pl.rigid()
    >>> cost = make_reward("quadratic", model, q=[1.0, 1.0, 0.0, 0.0], r=[0.1, 0.1])  # a QuadraticReward
    >>> cost.q, cost.r, np.round(cost.goal, 4)
    ((1.0, 1.0, 0.0, 0.0), (0.1, 0.1), array([3.1416, 3.1416, 0.    , 0.    ]))
    >>> x = model.state(theta1=np.pi + 0.1, theta2=np.pi - 0.2)  # near upright
    >>> round(cost(x, np.array([1.0, 0.0])), 6)  # -(0.1^2 + 0.2^2 + 0.1 * 1^2)
    -0.15
    """

    q: tuple[float, ...]
    r: tuple[float, float]
    goal: tuple[float, ...]
    angle_index: tuple[int, ...] = (0, 1)
    bonus: float = 0.0
    height_fraction: float = 0.9
    tip_height: Callable[[np.ndarray], float] | None = field(default=None, repr=False, compare=False)
    reach: float = 2.0

    _terms: tuple = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # (index, weight, goal, wrapped) of the weighted entries only: the call is on the env's hot path.
        terms = tuple((i, qi, gi, i in self.angle_index) for i, (qi, gi) in enumerate(zip(self.q, self.goal, strict=True)) if qi)
        object.__setattr__(self, "_terms", terms)

    def __call__(self, x: np.ndarray, tau: np.ndarray) -> float:
        """Reward of one step.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            State after the step.
        tau : ndarray, shape (2,)
            Torques held during the step [N.m].

        Returns
        -------
        float
            The reward (<= ``bonus``).
        """
        xs = x.tolist()  # Python floats: indexing an ndarray costs ~0.1 us per entry
        cost = 0.0
        for i, qi, gi, wrap in self._terms:
            e = xs[i] - gi
            if wrap:
                e = (e + math.pi) % _TWO_PI - math.pi
            cost += qi * e * e
        t1, t2 = float(tau[0]), float(tau[1])
        cost += self.r[0] * t1 * t1 + self.r[1] * t2 * t2
        if self.bonus and self.tip_height is not None and self.tip_height(xs) > self.height_fraction * self.reach:
            return self.bonus - cost
        return -cost


@dataclass(frozen=True)
class HeightReward:
    """The tip's height as a fraction of the reach: ``y2 / (L1 + L2)``, in [-1, 1] for the rigid model.

    Attributes
    ----------
    tip_height : callable
        ``h(x) -> y2`` [m] (:func:`tip_height_function`).
    reach : float
        ``L1 + L2`` [m].

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.gym import make_reward
    >>> model = pl.rigid()
    >>> height = make_reward("height", model)  # a HeightReward: y2 / (L1 + L2)
    >>> for theta in (0.0, np.pi / 3, 2 * np.pi / 3, np.pi):  # hanging to upright, links aligned
    ...     print(f"{height(model.state(theta1=theta, theta2=theta), np.zeros(2)):.3f}")
    -1.000
    -0.500
    0.500
    1.000
    """

    tip_height: Callable[[np.ndarray], float] = field(repr=False, compare=False)
    reach: float = 2.0

    def __call__(self, x: np.ndarray, tau: np.ndarray) -> float:
        """Reward of one step.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            State after the step.
        tau : ndarray, shape (2,)
            Torques [N.m] (unused).

        Returns
        -------
        float
            ``y2 / (L1 + L2)`` (dimensionless).
        """
        return self.tip_height(x) / self.reach


def _default_q(model: Model) -> tuple[float, ...]:
    # RealAIGym's weights (angles 10, rates 0.4 and 0.3); the elastic spring lengths and rates carry none.
    q = {"theta1": 10.0, "theta2": 10.0, "omega1": 0.4, "omega2": 0.3}
    return tuple(q.get(n, 0.0) for n in model.state_names)


@checked()
def make_reward(
    reward: str | RewardFn,
    model: Model,
    *,
    q: Sequence[float] | None = None,
    r: Sequence[float] = (1e-4, 1e-4),
    bonus: float = 100.0,
) -> RewardFn:
    """The reward of an environment by name, or a user callable passed through.

    ``"realai"`` (default of the env): negative quadratic cost about the upright state
    ``(pi, pi, 0, 0)`` with wrapped angle errors, Q = diag(10, 10, 0.4, 0.3), R = 1e-4 I on the
    torques [N.m], plus ``bonus`` while the tip is above 0.9 (L1 + L2). ``"quadratic"``: the same
    cost without the bonus. ``"height"``: the tip height over the reach, ``y2 / (L1 + L2)``.

    Parameters
    ----------
    reward : {"realai", "quadratic", "height"} or callable
        Name, or ``reward(x, tau) -> float`` (returned unchanged).
    model : Model
        The environment's model (state order, lengths, kinematics).
    q : sequence of float, length nx, optional
        Diagonal of Q in ``state_names`` order (default as above, zero on spring states).
    r : sequence of float, length 2
        Diagonal of R on (tau1, tau2) [1/(N.m)^2].
    bonus : float
        Bonus of ``"realai"`` per step above the line.

    Returns
    -------
    callable
        ``reward(x, tau) -> float``.

    Raises
    ------
    ValueError
        Unknown name, or weights of the wrong length or not finite and non-negative.
    TypeError
        ``reward`` is neither a string nor callable.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.gym import make_reward
    >>> model = pl.rigid()
    >>> reward = make_reward("realai", model)  # the environment's default
    >>> up, down = model.state(theta1=np.pi, theta2=np.pi), model.rest_state()
    >>> reward(up, np.zeros(2)), reward(up + 2 * np.pi * np.array([1, 0, 0, 0]), np.zeros(2))  # goal: bonus only, angles wrapped
    (100.0, 100.0)
    >>> round(reward(down, np.zeros(2)), 3)  # hanging: -(10 pi^2 + 10 pi^2), no bonus
    -197.392
    >>> effort = lambda x, tau: -float(abs(tau[0]))
    >>> make_reward(effort, model) is effort  # a callable passes through
    True
    """
    if callable(reward):
        return reward
    if not isinstance(reward, str):
        raise TypeError(f"reward must be one of {list(REWARDS)} or a callable reward(x, tau) -> float, got {reward!r}")
    if reward not in REWARDS:
        raise ValueError(f"reward must be one of {list(REWARDS)} or a callable reward(x, tau) -> float, got {reward!r}")
    params = model.params.resolved()
    reach = float(params["L1"] + params["L2"])
    height = tip_height_function(model)
    if reward == "height":
        return HeightReward(height, reach)
    qv = _weights("q", _default_q(model) if q is None else q, model.nx)
    rv = _weights("r", r, 2)
    if not (math.isfinite(bonus) and bonus >= 0):
        raise ValueError(f"bonus must be finite and >= 0, got {bonus!r}")
    goal = tuple(math.pi if n.startswith("theta") else 0.0 for n in model.state_names)
    angles = tuple(i for i, n in enumerate(model.state_names) if n.startswith("theta"))
    return QuadraticReward(
        qv, (rv[0], rv[1]), goal, angles, bonus if reward == "realai" else 0.0, 0.9, height if reward == "realai" else None, reach
    )


def _weights(name: str, values: Sequence[float], n: int) -> tuple[float, ...]:
    w = np.asarray(values, dtype=float)
    if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError(f"{name} must be {n} finite non-negative weights, got {list(np.ravel(values))!r}")
    return tuple(float(v) for v in w)

"""Run a RealAIGym controller (double_pendulum's ``AbstractController``) as a pendulab :class:`SampledController`.

The community's controllers (``dfki-ric-underactuated-lab/double_pendulum``) keep upstream's interface:
``init()`` before a run, ``reset()`` between runs, ``get_control_output(x, t)`` with the state in
*joint coordinates* ``x = (q1, q2, dq1, dq2)`` [rad, rad/s] (``q1`` from hanging down, ``q2`` the elbow
angle relative to link 1) returning the torques ``(u1, u2)`` [N.m] of both joints. :func:`from_realai`
wraps any object with these three methods (duck-typed: the upstream package is not needed) so it runs in
every pendulab protocol: :func:`pendulab.evaluate.realai.realai_score`,
:func:`pendulab.evaluate.realai.robustness.robustness_v2`, :func:`pendulab.evaluate.realai.v3.v3_score`,
:func:`pendulab.evaluate.scorecard.score` and :func:`pendulab.cosim.cosim`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..feedback import ControllerOutputError, actuated_inputs
from ..lqr import actuation_name

__all__ = ["REALAI_METHODS", "RealAIGymController", "check_realai_controller", "from_realai", "is_realai_controller", "to_joint"]

#: The methods an upstream controller must have (``AbstractController``'s public interface).
REALAI_METHODS: tuple[str, ...] = ("init", "get_control_output", "reset")


def is_realai_controller(obj: Any) -> bool:
    """Whether ``obj`` has RealAIGym's controller interface (``init``, ``get_control_output``, ``reset``, all callable).

    Parameters
    ----------
    obj : object
        Anything.

    Returns
    -------
    bool
        True for an upstream ``AbstractController`` or any object of its shape.
    """
    return all(callable(getattr(obj, m, None)) for m in REALAI_METHODS)


def check_realai_controller(obj: Any) -> None:
    """Raise unless ``obj`` has RealAIGym's controller interface, naming what it lacks.

    Parameters
    ----------
    obj : object
        Anything.

    Raises
    ------
    TypeError
        ``obj`` lacks one of ``init``, ``get_control_output``, ``reset`` (or it is not callable).
    """
    missing = [m for m in REALAI_METHODS if not callable(getattr(obj, m, None))]
    if missing:
        raise TypeError(
            f"{type(obj).__name__} is not a RealAIGym controller: it lacks {', '.join(missing)} "
            f"(needs {', '.join(REALAI_METHODS)})"
        )


def to_joint(x: np.ndarray) -> np.ndarray:
    """pendulab's state -> RealAIGym's joint coordinates ``(q1, q2, dq1, dq2)``, q2 relative to link 1.

    Parameters
    ----------
    x : array_like, shape (nx,)
        pendulab state: absolute link angles from hanging down ``theta1, theta2`` [rad] first, the link
        rates ``omega1, omega2`` [rad/s] at ``nx // 2`` (rigid: nx = 4; elastic: nx = 8, spring lengths
        and rates are dropped).

    Returns
    -------
    ndarray, shape (4,)
        ``(theta1, theta2 - theta1, omega1, omega2 - omega1)`` [rad, rad, rad/s, rad/s].

    Raises
    ------
    ValueError
        ``x`` is not a flat state of even size >= 4.

    Examples
    --------
    >>> from pendulab.control.realai.adapter import to_joint
    >>> to_joint([3.0, 3.5, 0.1, -0.2]).round(3).tolist()  # elbow bent by 0.5 rad, turning at -0.3 rad/s
    [3.0, 0.5, 0.1, -0.3]
    """
    x = np.asarray(x, dtype=float)
    if x.ndim != 1 or x.size < 4 or x.size % 2:
        raise ValueError(f"x must be a pendulab state of shape (nx,), nx even >= 4, got shape {x.shape}")
    h = x.size // 2
    return np.array([x[0], x[1] - x[0], x[h], x[h + 1] - x[h]])


class RealAIGymController:
    """A RealAIGym controller as a pendulab :class:`~pendulab.control.feedback.SampledController` (see :func:`from_realai`).

    Parameters
    ----------
    controller : object
        Has ``init()``, ``get_control_output(x, t)`` and ``reset()`` (upstream's ``AbstractController``).
    actuation : {"pendubot", "acrobot", "full"}
        The joint(s) driven; the other joint's torque is dropped.
    sample_time : float
        Sample period [s].
    torque_limit : float, optional
        Clip the driven torque(s) to +- this [N.m]; None: unclipped (the protocols apply their own limit).

    Attributes
    ----------
    controller : object
        The wrapped upstream controller.
    sample_time : float
        Sample period [s].
    input_names : tuple of str
        The driven inputs, ``("tau1",)`` (pendubot), ``("tau2",)`` (acrobot) or both.
    torque_limit : float or None
        Clip of the driven torque(s) [N.m].
    """

    def __init__(self, controller: Any, actuation: str, sample_time: float, torque_limit: float | None = None) -> None:
        self.controller = controller
        self.input_names = actuated_inputs(actuation)
        self.sample_time = float(sample_time)
        self.torque_limit = torque_limit
        self._joints = [int(n[-1]) - 1 for n in self.input_names]
        self._ready = False

    def __repr__(self) -> str:
        return f"RealAIGymController({type(self.controller).__name__}, inputs={self.input_names}, sample_time={self.sample_time})"

    def reset(self) -> None:
        """Call the upstream ``reset()``; its ``init()`` follows before the next output (upstream's benchmark order)."""
        self.controller.reset()
        self._ready = False

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """The driven torque(s) [N.m], shape (len(input_names),), at time ``t`` [s] and pendulab state ``x``, shape (nx,).

        Parameters
        ----------
        t : float
            Time since the start of the run [s], passed on as a float.
        x : ndarray, shape (nx,)
            pendulab state (absolute angles), converted by :func:`to_joint`.

        Returns
        -------
        ndarray, shape (len(input_names),)
            The upstream output's entries of the driven joints, clipped to ``torque_limit`` if set.

        Raises
        ------
        ControllerOutputError
            The upstream output is not two finite torques.
        """
        if not self._ready:
            self.controller.init()
            self._ready = True
        out = self.controller.get_control_output(x=to_joint(x), t=float(t))  # by keyword, as upstream's Simulator calls it
        try:
            u = np.asarray(out, dtype=float).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ControllerOutputError(
                f"{type(self.controller).__name__}.get_control_output returned {out!r} at t = {t:.6g} s: not torques"
            ) from exc
        if u.shape != (2,) or not np.isfinite(u).all():
            raise ControllerOutputError(
                f"{type(self.controller).__name__}.get_control_output returned {u.tolist()!r} at t = {t:.6g} s; "
                "expected 2 finite torques (u1, u2) [N.m]"
            )
        u = u[self._joints]
        if self.torque_limit is not None:
            u = np.clip(u, -self.torque_limit, self.torque_limit)
        return u


def from_realai(
    controller: Any, *, task: str = "pendubot", sample_time: float = 0.002, torque_limit: float | None = None
) -> RealAIGymController:
    """Wrap a RealAIGym controller (``AbstractController`` or any object of its shape) as a pendulab controller.

    Each sample the pendulab state (absolute angles from hanging down) is converted to upstream's joint
    coordinates ``(theta1, theta2 - theta1, omega1, omega2 - omega1)`` by :func:`to_joint` and passed as
    ``get_control_output(x, t)``; of the returned ``(u1, u2)`` only the driven joint's torque is kept
    (**the passive joint's value is dropped**, as on the real robot; both must still be finite). Upstream's
    ``reset()`` is called when the protocol resets the controller (before every run) and ``init()`` once
    before the first output of every run (as upstream's benchmark calls ``reset()`` then ``init()``).
    Upstream's extras (``get_init_trajectory``, ``get_forecast``, filters, friction/gravity compensation
    inside the controller) are left to the controller itself.

    Parameters
    ----------
    controller : object
        Has callable ``init()``, ``get_control_output(x, t)`` (called by keyword as upstream's simulator
        does: ``x`` shape (4,), ``t`` [s] float; returns shape (2,) [N.m]) and ``reset()``.
    task : {"pendubot", "acrobot", "full"}
        Which joint is driven: the shoulder (``tau1``), the elbow (``tau2``) or both.
    sample_time : float
        Sample period [s]; the RealAIGym protocols need a multiple of their 2 ms step.
    torque_limit : float, optional
        Clip the driven torque to +- this [N.m]; None (default): the protocol's limit applies.

    Returns
    -------
    RealAIGymController
        A :class:`~pendulab.control.feedback.SampledController`; commands that every runner applies pass
        through :func:`~pendulab.control.feedback.full_input`.

    Raises
    ------
    TypeError
        ``controller`` lacks one of ``init``, ``get_control_output``, ``reset``.
    ValueError
        Unknown task, a non-positive ``sample_time`` or ``torque_limit``.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control.realai.adapter import from_realai
    >>> class ElbowPD:  # upstream's shape: joint coordinates in, (u1, u2) out
    ...     def init(self): pass
    ...     def reset(self): pass
    ...     def get_control_output(self, x, t=None):
    ...         return np.array([-2.0 * x[1] - 0.5 * x[3], 99.0])  # u2 is dropped for the pendubot
    >>> ctrl = from_realai(ElbowPD(), task="pendubot")
    >>> ctrl.input_names, ctrl.sample_time
    (('tau1',), 0.002)
    >>> ctrl.reset()
    >>> ctrl(0.0, np.array([3.0, 3.5, 0.0, 1.0])).round(3)  # q2 = 0.5 rad, dq2 = 1 rad/s
    array([-1.5])
    """
    check_realai_controller(controller)
    actuation = actuation_name(task)
    h = float(sample_time)
    if not (np.isfinite(h) and h > 0):
        raise ValueError(f"sample_time must be a positive number of seconds, got {sample_time!r}")
    if torque_limit is not None and not (np.isfinite(torque_limit) and torque_limit > 0):
        raise ValueError(f"torque_limit must be positive [N.m] or None, got {torque_limit!r}")
    return RealAIGymController(controller, actuation, h, None if torque_limit is None else float(torque_limit))

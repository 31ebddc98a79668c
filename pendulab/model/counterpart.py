"""The rigid counterpart of an elastic pendulum: same masses, lengths, gravity and joint dampers.

The seed paper compares the elastic pendulum with the rigid one "from
identical initial conditions": the rigid links have the springs' rest lengths,
point masses at their ends (``lc = L``, ``I = 0``), the same joint dampers
``b1, b2``; the spring-only parameters ``k`` and ``c`` have no rigid analogue.
The rigid state keeps the angles and angular rates of the elastic one (the
bobs coincide when the springs are at rest length).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .builders import STATE_NAMES
from .model import Model, rigid

__all__ = ["rigid_counterpart", "rigid_state"]

_SHARED = ("m1", "m2", "L1", "L2", "g", "b1", "b2")


def rigid_counterpart(model: Model) -> Model:
    """Rigid pendulum with the same ``m1, m2, L1, L2, g, b1, b2`` as ``model``.

    Parameters
    ----------
    model : Model
        An elastic model (a rigid model is returned unchanged).

    Returns
    -------
    Model
        Rigid model with point masses at the link ends; link lengths equal the
        spring rest lengths.

    Raises
    ------
    TypeError
        ``model`` is not a :class:`~pendulab.model.model.Model`.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    if model.kind == "rigid":
        return model
    return rigid(**{name: getattr(model.params, name) for name in _SHARED})


def rigid_state(model: Model, x: Any) -> np.ndarray:
    """Project states of ``model`` onto the rigid state (theta1, theta2, omega1, omega2).

    Parameters
    ----------
    model : Model
        The model ``x`` belongs to.
    x : array_like, shape (nx,) or (N, nx)
        State(s) of ``model``.

    Returns
    -------
    ndarray, shape (4,) or (N, 4)
        Angles [rad] and angular rates [rad/s]; spring lengths and rates are dropped.
    """
    x = model.check_state(x)
    names = model.state_names
    cols = [names.index(n) for n in STATE_NAMES["rigid"]]
    return x[..., cols].copy()

"""Named controllers: the factory behind ``pendulab cosim --controller NAME``.

A new controller plugs in here: add its name to :data:`CONTROLLERS` and a
branch to :func:`make_controller` returning an object that keeps the
:class:`~pendulab.control.feedback.SampledController` protocol.
"""

from __future__ import annotations

import numpy as np

from .._checks import positive_float
from ..model.model import INPUT_NAMES, Model
from .feedback import SampledController, actuated_inputs, balance_controller, energy_swingup, upright_state
from .tracking import swingup_reference, tvlqr_tracker

__all__ = ["CONTROLLERS", "make_controller"]


#: Names accepted by :func:`make_controller`.
CONTROLLERS: tuple[str, ...] = ("lqr", "swingup", "tvlqr")


def make_controller(
    name: str,
    model: Model,
    sample_time: float,
    *,
    u_max: float = 20.0,
    t_ref: float = 6.0,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    actuation: str = "full",
) -> tuple[SampledController, np.ndarray]:
    """A named controller for ``model`` and its natural start state.

    Parameters
    ----------
    name : {"lqr", "swingup", "tvlqr"}
        ``lqr``: continuous LQR balance (start 0.1 rad off upright);
        ``swingup``: energy pumping + LQR catch (start hanging, theta1 = 0.1);
        ``tvlqr``: discrete TVLQR tracking of ``reference`` (default: the native
        energy swing-up, :func:`swingup_reference`, ``t_ref`` seconds) then
        discrete LQR balance; starts at the reference's first state.
    model : Model
        Design model (e.g. ``FmuInfo.model()`` for an FMU's parameters).
    sample_time : float
        [s].
    u_max : float
        Torque limit [N.m] (swing-up and tracking).
    t_ref : float
        Horizon [s] of the default ``tvlqr`` reference.
    reference : (t, x, u), optional
        Reference to track with ``tvlqr`` (any grid; e.g. an optimized swing-up or
        :func:`load_reference_csv`).
    actuation : {"full", "pendubot", "acrobot"}
        Driven torques of ``lqr`` and ``tvlqr`` (``swingup`` needs both).

    Returns
    -------
    controller : SampledController
        The sampled-data controller.
    x0 : ndarray, shape (nx,)
        Start state for ``model`` (see ``name``).

    Raises
    ------
    ValueError
        Unknown ``name``, non-positive ``sample_time`` (or ``t_ref``), or
        ``swingup`` with an actuation other than ``"full"``.
    """
    h = positive_float("sample_time", sample_time)
    if name == "lqr":
        x0 = upright_state(model)
        x0[0] += 0.1
        return balance_controller(model, h, actuation=actuation), x0
    if name == "swingup":
        if actuated_inputs(actuation) != INPUT_NAMES:
            raise ValueError(f"the energy swing-up drives both torques; actuation must be 'full', got {actuation!r}")
        return energy_swingup(model, h, u_max=u_max), model.state(theta1=0.1)
    if name == "tvlqr":
        if reference is None:
            reference = swingup_reference(model, h, round(positive_float("t_ref", t_ref) / h) * h, u_max=u_max)
        tracker = tvlqr_tracker(model, *reference, h, u_max=u_max, actuation=actuation)
        return tracker, tracker.x_ref[0].copy()
    raise ValueError(f"controller must be one of {list(CONTROLLERS)}, got {name!r}")

"""The control law of a designed pendulab controller as CasADi functions and constants (for C generation).

Part of the controller FMU export (:mod:`pendulab.fmu.controller_export`): :func:`controller_law` turns
a :class:`~pendulab.control.feedback.LinearStateFeedback` (``lqr``), an
:class:`~pendulab.control.feedback.EnergySwingUp` (``swingup``) or a
:class:`~pendulab.control.tracking.TVLQRTracker` (``tvlqr``) into a :class:`ControllerLaw`;
:func:`design_controller` designs a named controller to export.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .._inputs import checked
from ..control.feedback import EnergySwingUp, LinearStateFeedback
from ..control.tracking import TVLQRTracker
from ..model.model import Model

__all__ = ["EXPORTABLE", "NMPC_NOT_EXPORTABLE", "ControllerLaw", "controller_law", "design_controller"]

#: Controllers that can be exported as FMUs (the NMPC cannot: see :data:`NMPC_NOT_EXPORTABLE`).
EXPORTABLE: tuple[str, ...] = ("lqr", "tvlqr", "swingup")
#: Why ``nmpc`` is not exported (docs/fmu.md has the measurements).
NMPC_NOT_EXPORTABLE = (
    "the NMPC is not exported as an FMU: the C that CasADi generates for its solver (sqpmethod with the hpipm QP "
    "solver) calls HPIPM and BLASFEO (libraries of CasADi's wheel, BLASFEO built per CPU target), and ipopt and fatrop "
    "call their external libraries; only sqpmethod with CasADi's own dense QP solver qrqp generates self-contained C "
    "(see docs/fmu.md)"
)


@dataclass(frozen=True)
class ControllerLaw:
    """A controller as data for C: CasADi functions of the law and constants of the fixed core.

    Attributes
    ----------
    kind : {"lqr", "swingup", "tvlqr"}
        Control law.
    model : Model
        Design model (state names and units).
    state_names : tuple of str
        FMU inputs, in the model's state order.
    output_names : tuple of str
        FMU outputs: the driven torques.
    sample_time : float
        Default of the ``sample_time`` parameter [s].
    functions : tuple of casadi.Function
        ``balance(x) -> (u, cost)`` (when there is an LQR), ``pump(x) -> u`` (swing-up),
        ``track(x, x_ref, u_ref, K) -> u`` (TVLQR).
    constants : dict
        ``#define`` values of the generated header (limits, thresholds, sizes).
    arrays : dict of str to ndarray
        Constant arrays of the generated C (TVLQR plan: ``t_ref``, ``x_ref``, ``u_ref``, ``k_ref``).
    x_start : ndarray, shape (nx,)
        Start values of the inputs.
    """

    kind: str
    model: Model
    state_names: tuple[str, ...]
    output_names: tuple[str, ...]
    sample_time: float
    functions: tuple[ca.Function, ...]
    constants: dict[str, Any] = field(default_factory=dict)
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    x_start: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def identifier(self) -> str:
        """Model identifier: ``pendulab_<kind>_controller``."""
        return f"pendulab_{self.kind}_controller"


def _pymod(a: ca.SX, b: float) -> ca.SX:
    """Python's / NumPy's float ``a % b`` for ``b > 0``: C's fmod, moved into [0, b) (bit-identical to NumPy)."""
    m = ca.fmod(a, b)
    return ca.if_else(m < 0, m + b, m)


def _wrapped_error(x: ca.SX, ref: Any, names: tuple[str, ...]) -> ca.SX:
    """``pendulab.control.lqr.wrap_state_error(x - ref)``: angle differences into (-pi, pi]."""
    d = x - ref
    return ca.vertcat(
        *[-(_pymod(-d[i] + math.pi, 2 * math.pi) - math.pi) if n.startswith("theta") else d[i] for i, n in enumerate(names)]
    )


def _clip(u: ca.SX, limit: float | None) -> ca.SX:
    return u if limit is None else ca.fmin(ca.fmax(u, -float(limit)), float(limit))


def _affine(u0: Any, K: Any, e: ca.SX, m: int, nx: int) -> ca.SX:
    """``u0 - K e`` row by row (K given as a callable (i, j) -> entry)."""
    return ca.vertcat(*[u0[i] - sum((K(i, j) * e[j] for j in range(nx)), ca.SX(0)) for i in range(m)])


def _finite(name: str, value: Any) -> np.ndarray:
    """``value`` as a float array; ValueError when any entry is NaN or infinite (never exported as a broken law)."""
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"controller {name} must be finite to be exported, got non-finite entries in {np.ravel(arr)[:6]!r}")
    return arr


def _balance(ident: str, lsf: LinearStateFeedback, x: ca.SX) -> ca.Function:
    for name in ("K", "x_eq", "u_eq") + (("P",) if lsf.P is not None else ()) + (("u_max",) if lsf.u_max is not None else ()):
        _finite(name, getattr(lsf, name))
    names = lsf.model.state_names
    e = _wrapped_error(x, ca.DM(lsf.x_eq), names)
    K = np.asarray(lsf.K, dtype=float)
    u = _clip(_affine([float(v) for v in lsf.u_eq], lambda i, j: float(K[i, j]), e, K.shape[0], len(names)), lsf.u_max)
    cost = ca.mtimes([e.T, ca.DM(np.asarray(lsf.P, dtype=float)), e]) if lsf.P is not None else ca.dot(e, e)
    return ca.Function(f"{ident}_balance", [x], [u, cost], ["x"], ["u", "cost"])


def controller_law(controller: Any) -> ControllerLaw:
    """The control law of a designed pendulab controller, as CasADi functions and constants.

    Parameters
    ----------
    controller : LinearStateFeedback, EnergySwingUp or TVLQRTracker
        A designed sampled-data controller, e.g. from
        :func:`pendulab.control.controllers.controller_for_task` or ``make_controller``.

    Returns
    -------
    ControllerLaw

    Raises
    ------
    TypeError
        Another kind of controller (e.g. the NMPC, whose solver is not generated as C).
    ValueError
        A TVLQR tracker whose final controller is not a linear state feedback.
    """
    if isinstance(controller, LinearStateFeedback):
        kind = "lqr"
    elif isinstance(controller, EnergySwingUp):
        kind = "swingup"
    elif isinstance(controller, TVLQRTracker):
        kind = "tvlqr"
    else:
        raise TypeError(
            "controller must be a LinearStateFeedback (lqr), EnergySwingUp (swingup) or TVLQRTracker (tvlqr), got "
            f"{type(controller).__name__}"
        )
    model: Model = controller.model
    names = model.state_names
    ident = f"pendulab_{kind}_controller"
    x = ca.SX.sym("x", model.nx)
    outs = tuple(controller.input_names)
    consts: dict[str, Any] = {"CTRL_U_MAX": 0.0 if controller.u_max is None else float(controller.u_max)}
    arrays: dict[str, np.ndarray] = {}
    if kind == "lqr":
        funcs: tuple[ca.Function, ...] = (_balance(ident, controller, x),)
        x_start = np.asarray(controller.x_eq, dtype=float)
    elif kind == "swingup":
        sw: EnergySwingUp = controller
        for name in ("k_energy", "kp", "kd", "u_max", "catch_cost", "e_up"):
            _finite(name, getattr(sw, name))
        energy = model.functions["energy"](x, ca.DM(np.asarray(model.p, dtype=float)))
        deficit = sw.e_up - energy
        w1, w2 = x[model.nq], x[model.nq + 1]
        rate = w2 - w1 if sw.actuation == "acrobot" else w1
        # EnergySwingUp.pump_gain: k / (1 + k rate^2 h) at the design sample time (the sampled-data loop gain below 1)
        gain = sw.k_energy / (1.0 + sw.k_energy * rate * rate * float(sw.sample_time))
        pump = ca.if_else(ca.fabs(rate) > 1e-3, gain * deficit * rate, sw.u_max * ca.sign(deficit))
        if sw.actuation == "full":
            rel = _pymod(x[1] - x[0] + math.pi, 2 * math.pi) - math.pi
            u = ca.vertcat(pump, -sw.kp * rel - sw.kd * (w2 - w1))
        else:
            u = pump
        pump_f = ca.Function(f"{ident}_pump", [x], [_clip(u, sw.u_max)], ["x"], ["u"])
        funcs = (_balance(ident, sw.balance, x), pump_f)
        consts.update(
            CTRL_CATCH_COST=float(sw.catch_cost),
            CTRL_RELEASE_FACTOR=0.0 if sw.release_factor is None else float(sw.release_factor),
            CTRL_U_MAX=float(sw.u_max),
        )
        x_start = model.rest_state()
    else:
        tr: TVLQRTracker = controller
        for name in ("t_ref", "x_ref", "u_ref", "K") + (("u_max",) if tr.u_max is not None else ()):
            _finite(name, getattr(tr, name))
        m, nx = len(outs), model.nx
        xr, ur, kk = ca.SX.sym("x_ref", nx), ca.SX.sym("u_ref", m), ca.SX.sym("K", m * nx)
        u = _clip(_affine(ur, lambda i, j: kk[i * nx + j], _wrapped_error(x, xr, names), m, nx), tr.u_max)
        funcs = (ca.Function(f"{ident}_track", [x, xr, ur, kk], [u], ["x", "x_ref", "u_ref", "K"], ["u"]),)
        if tr.final is not None:
            if not isinstance(tr.final, LinearStateFeedback):
                raise ValueError(
                    f"a TVLQR tracker's final controller must be a LinearStateFeedback, got {type(tr.final).__name__}"
                )
            funcs = (_balance(ident, tr.final, x), *funcs)
        nk = min(len(tr.K), len(tr.u_ref), len(tr.t_ref) - 1)
        consts.update(
            CTRL_NT=len(tr.t_ref),
            CTRL_NK=nk,
            CTRL_NU_ROWS=len(tr.u_ref),
            CTRL_DESIGN_SAMPLE_TIME=float(tr.sample_time),
            CTRL_HAS_BALANCE=int(tr.final is not None),
        )
        arrays = {
            "t_ref": np.asarray(tr.t_ref, dtype=float),
            "x_ref": np.asarray(tr.x_ref, dtype=float).ravel(),
            "u_ref": np.asarray(tr.u_ref, dtype=float).ravel(),
            "k_ref": np.asarray(tr.K, dtype=float).ravel(),
        }
        x_start = np.asarray(tr.x_ref[0], dtype=float)
    return ControllerLaw(kind, model, names, outs, float(controller.sample_time), funcs, consts, arrays, x_start)


@checked()
def design_controller(
    name: str,
    task: Any = None,
    *,
    kind: str = "rigid",
    sample_time: float | None = None,
    u_max: float = 20.0,
) -> tuple[Any, np.ndarray, Model]:
    """Design a named controller to export, with its start state and plant model.

    With a task: :func:`pendulab.control.controllers.controller_for_task` (the task's model, actuation,
    torque limit; ``tvlqr`` tracks the task's optimized swing-up). Without: ``make_controller`` on the
    default ``kind`` model (``tvlqr`` tracks the native energy swing-up).

    Parameters
    ----------
    name : {"lqr", "tvlqr", "swingup"}
        Controller.
    task : Task or str, optional
        Swing-up task or its name.
    kind : {"rigid", "elastic"}
        Model without a task.
    sample_time : float, optional
        [s]; default the task's ``dt``, else 0.01.
    u_max : float
        Torque limit [N.m] without a task.

    Returns
    -------
    controller : SampledController
        The designed controller.
    x0 : ndarray, shape (nx,)
        Its natural start state.
    model : Model
        The plant model it was designed for.

    Raises
    ------
    ValueError
        ``nmpc`` (not exportable), an unknown name, a bad sample time, or a failed design.
    """
    from ..control.controllers import controller_for_task, make_controller
    from ..model.model import make_model

    if name == "nmpc":
        raise ValueError(NMPC_NOT_EXPORTABLE)
    if name not in EXPORTABLE:
        raise ValueError(f"controller must be one of {list(EXPORTABLE)}, got {name!r}")
    if task is not None:
        ctrl, x0 = controller_for_task(name, task, sample_time=sample_time)
    else:
        ctrl, x0 = make_controller(name, make_model(kind), 0.01 if sample_time is None else sample_time, u_max=u_max)
    return ctrl, np.asarray(x0, dtype=float), ctrl.model

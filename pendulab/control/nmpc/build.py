"""Build an NMPC controller: prediction model (by the planning rule's levels), weights, reference, the NLP.

:func:`nmpc_controller` picks the prediction model of an elastic plant
(:func:`pendulab.control.nmpc.prediction.choose_prediction`), maps the reference onto it
(rigid projection, or the quasi-static lift for an elastic prediction; the quasi-static
link lengths along it for the ``rigid+quasi-static`` level), builds the weights, the
terminal LQR cost-to-go and the multiple-shooting NLP (:func:`.ocp.build_ocp`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..._inputs import checked
from ...model.counterpart import rigid_state
from ...model.model import INPUT_NAMES, Model
from ..feedback import actuated_inputs, upright_state
from ..lqr import lqr_balance
from ..tracking import resample_reference
from .controller import NMPCController, NMPCOptions
from .ocp import build_ocp
from .prediction import LENGTH_PARAMS, SlowStateMap, choose_prediction, prediction_model, upright_lengths

__all__ = ["nmpc_controller"]


@checked(NMPCOptions)
def nmpc_controller(
    model: Model,
    *,
    actuation: str | Sequence[str] = "full",
    u_max: float = 20.0,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    goal: np.ndarray | None = None,
    options: NMPCOptions | None = None,
    **option_changes: Any,
) -> NMPCController:
    """Build an NMPC controller tracking ``reference`` (if any), then holding ``goal``.

    Parameters
    ----------
    model : Model
        Plant model (rigid or elastic; see ``NMPCOptions.planning``).
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        Driven torques.
    u_max : float
        Hard torque bound [N.m].
    reference : (t, x, u), optional
        Reference times [s] shape (K,), states shape (K, nx) of ``model`` or
        rigid states shape (K, 4) (lifted to quasi-static spring lengths for an
        elastic prediction model), torques (tau1, tau2) [N.m] shape (K, 2) or (K-1, 2).
        None: regulation about ``goal`` only.
    goal : ndarray, shape (nx_plan,), optional
        Planning-model state held after the reference; default upright at rest.
    options : NMPCOptions, optional
        Settings (default :class:`NMPCOptions`).
    **option_changes
        :class:`NMPCOptions` fields overriding ``options`` (e.g. ``solver="ipopt"``, ``horizon=30``).

    Returns
    -------
    NMPCController
        Ready to run (call :meth:`NMPCController.reset` between runs).

    Raises
    ------
    TypeError
        ``model`` is not a Model, or an unknown option name.
    ValueError
        Bad options, torque limit, actuation or reference shapes.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, nmpc_controller, upright_state
    >>> model = pl.rigid()
    >>> ctrl = nmpc_controller(model, actuation="pendubot", u_max=6.0, horizon=10)  # regulation about upright
    >>> x0 = upright_state(model) + [0.1, 0.0, 0.0, 0.0]
    >>> traj = pl.simulate(model, x0, 3.0, dt=ctrl.sample_time, u=as_feedback(ctrl, model))
    >>> bool(np.allclose(traj.x[-1], upright_state(model), atol=1e-2)), ctrl.stats()["failures"]
    (True, 0)
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    opts = options if options is not None else NMPCOptions()
    unknown = sorted(set(option_changes) - set(NMPCOptions.__dataclass_fields__))
    if unknown:
        raise TypeError(f"unknown NMPC option(s) {unknown}; expected some of {sorted(NMPCOptions.__dataclass_fields__)}")
    opts = NMPCOptions(**{**opts.__dict__, **option_changes})
    u_max = float(u_max)
    names = actuated_inputs(actuation)
    choice = choose_prediction(model, opts.planning, opts.prediction_tolerance)
    plan = prediction_model(model, choice.level)
    h = opts.sample_time
    goal = upright_state(plan) if goal is None else plan.check_state(goal, "goal")
    if goal.ndim != 1:
        raise ValueError(f"goal must be a single state of shape ({plan.nx},), got {goal.shape}")
    cols = [INPUT_NAMES.index(n) for n in names]
    if reference is None:
        x_ref, u_ref = goal[None, :], np.zeros((1, len(names)))
    else:
        t, x, u = reference
        x = np.asarray(x, dtype=float)
        u = np.asarray(u, dtype=float)
        if u.ndim != 2 or u.shape[1] != len(INPUT_NAMES):
            raise ValueError(f"reference torques must have shape (K, 2) (tau1, tau2), got {u.shape}")
        if x.ndim == 2 and x.shape[1] == model.nx and plan is not model:
            x = rigid_state(model, x)
        elif x.ndim == 2 and x.shape[1] == 4 and plan.kind == "elastic":
            x = _lift_quasi_static(plan, x, u)
        if x.ndim != 2 or x.shape[1] != plan.nx:
            raise ValueError(f"reference states must have shape (K, {model.nx}) or (K, 4), got {x.shape}")
        _, x_ref, u_full = resample_reference(t, x, u, h, plan)
        x_ref, u_ref = x_ref, u_full[:, cols]
    stage_params: tuple[str, ...] = ()
    stage_ref, stage_goal = np.zeros((1, 0)), np.zeros(0)
    if choice.level == "rigid+quasi-static":
        # Each stage predicts with the link lengths the springs take quasi-statically along the reference.
        stage_params = LENGTH_PARAMS
        ufull = np.zeros((len(x_ref), len(INPUT_NAMES)))
        ufull[: len(u_ref), cols] = u_ref
        r = _quasi_static_lengths(model, x_ref, ufull) if reference is not None else np.zeros((0, 2))
        stage_ref = np.column_stack([r, r])
        stage_goal = np.array(upright_lengths(model) * 2)
        if reference is None:
            stage_ref = stage_goal[None, :]
    n_ang = [i for i, n in enumerate(plan.state_names) if n.startswith("theta")]
    n_rate = [i for i, n in enumerate(plan.state_names) if n.startswith("omega")]
    Q = np.zeros((plan.nx, plan.nx))
    q_rate = opts.q_rate if opts.q_rate is not None else (0.1 if plan.kind != model.kind else 1.0)
    Q[n_ang, n_ang], Q[n_rate, n_rate] = opts.q_angle, q_rate
    n_len = [i for i, n in enumerate(plan.state_names) if n[0] in "rv"]
    Q[n_len, n_len] = [100.0 if plan.state_names[i][0] == "r" else 0.1 for i in n_len]  # springs: as default_weights
    R = np.eye(len(names)) * (opts.r if opts.r is not None else 1.0 / u_max**2)
    top = lqr_balance(plan, names, Q, R, h, at=goal)
    ocp = build_ocp(
        plan, names, N=opts.horizon, sample_time=h, substeps=_substeps(plan, h, opts.substeps), Q=Q, R=R, P=top.P, u_max=u_max,
        velocity_limit=opts.velocity_limit, slack_weight=opts.slack_weight, solver=opts.solver, max_iter=opts.iterations_cap,
        max_solve_time=opts.max_solve_time, stage_params=stage_params, rate_weight=opts.torque_rate,
    )  # fmt: skip
    smap = None
    if plan is not model and opts.state_map == "momentum":
        smap = SlowStateMap(model, quasi_static=choice.level == "rigid+quasi-static")
    elif plan is not model and opts.state_map == "average":
        smap = SlowStateMap(model, quasi_static=False, average=_spring_periods(model))
    return NMPCController(
        model, plan, opts, names, u_max, x_ref, u_ref, goal, ocp, top.K,
        prediction=choice, state_map=smap, stage_ref=stage_ref, stage_goal=stage_goal,
    )  # fmt: skip


def _substeps(plan: Model, h: float, substeps: int | None) -> int:
    """RK4 steps per interval: given, 2 for a rigid model, or ``h * omega_fast`` rounded up for an elastic one."""
    if substeps is not None:
        return int(substeps)
    if plan.kind == "rigid":
        return 2
    from ...analysis.equilibria import equilibrium
    from ...analysis.linearize import linearize

    fast = float(np.max(np.abs(linearize(plan, equilibrium(plan, "down-down")).eigenvalues)))
    return max(2, int(np.ceil(h * fast)))


def _spring_periods(model: Model) -> tuple[float, ...]:
    """Periods [s] of the spring modes at the hanging rest."""
    from ...analysis.modes import modes

    return tuple(sorted(2 * np.pi / md.omega_n for md in modes(model, "down-down") if md.spring_share >= 0.5))


def _quasi_static_lengths(model: Model, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Quasi-static spring lengths [m] of the elastic ``model`` along rigid states ``x`` (K, 4) under torques ``u`` (K, 2)."""
    from ...model.quasistatic import quasi_static_lengths

    return np.array([quasi_static_lengths(model, xk[:2], xk[2:], u[k]) for k, xk in enumerate(x)])


def _lift_quasi_static(plan: Model, x: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Elastic states of a rigid reference: same angles and rates, quasi-static spring lengths, v = 0."""
    from ...model.quasistatic import quasi_static_lengths

    r = np.array([quasi_static_lengths(plan, xk[:2], xk[2:], u[min(k, len(u) - 1)]) for k, xk in enumerate(x)])
    return np.column_stack([x[:, :2], r, x[:, 2:], np.zeros_like(r)])

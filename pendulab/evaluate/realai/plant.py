"""The RealAIGym robustness-v2 plant: pendulab's rigid model with upstream's parameters, rotor inertia and Coulomb friction.

RealAIGym's ``DoublePendulumPlant`` (``src/python/double_pendulum/model/plant.py`` of
github.com/dfki-ric-underactuated-lab/double_pendulum, commit 1e8544e, formulas
"UnderactuatedLecture") works in joint coordinates ``q = (q1, q2)`` with ``q2`` the angle of
link 2 *relative* to link 1, link inertias ``I1, I2`` about the *joints*, and two terms the
pendulab rigid model does not have:

* motor (rotor) inertia ``Ir`` with gear ratio ``gr``: the constant matrix
  ``[[gr^2 Ir + Ir, -gr Ir], [-gr Ir, gr^2 Ir]]`` added to the joint-coordinate mass matrix,
  i.e. the kinetic energy ``1/2 q'^T M_r q'``;
* joint friction ``b_i q_i' + cf_i atan(100 q_i')`` on the joint rates (viscous and smoothed
  Coulomb).

Here nothing is typed by hand: pendulab's own symbolic rigid model (:func:`pendulab.model.builders.build_rigid`,
absolute angles, inertias about the centres of mass) supplies ``T`` and ``V`` with
``I_com = I_joint - m r^2``; the rotor term is added to ``T`` as ``1/2 (J w)^T M_r (J w)`` with
``J = d(q1, theta2 - theta1)/d theta``, the friction enters as a Rayleigh function (viscous) and
the generalized force ``-J^T cf atan(100 J w)`` (Coulomb), and the joint torques as ``J^T tau``;
:func:`pendulab.model.lagrange.lagrange_equations` derives the equations of motion.

The parameter vector is upstream's (:data:`PARAM_NAMES`); :func:`nominal_params` gives design
C.1 / model 1.0 as ``leaderboard/{pendubot,acrobot}/robustness_v2/sim_parameters.py`` sets it
(motor inertia, damping and Coulomb friction zero, torque limit 6 N.m on the actuated joint),
:func:`vary` applies one of the ten model-parameter variations the benchmark sweeps.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import cache

import casadi as ca
import numpy as np

from ...control.realai.spec import TASKS, check_task
from ...model.builders import build_rigid
from ...model.lagrange import lagrange_equations
from ...model.pycode import to_python

__all__ = [
    "PARAM_NAMES",
    "MODEL_1_0",
    "MODEL_VARIATIONS",
    "nominal_params",
    "vary",
    "protocol_rhs",
    "protocol_rhs_python",
]

#: Upstream parameter vector: masses [kg], lengths [m], centres of mass [m], viscous [N.m.s/rad]
#: and Coulomb [N.m] joint friction, gravity [m/s^2], link inertias about the joints [kg.m^2],
#: rotor inertia [kg.m^2], gear ratio [-].
PARAM_NAMES: tuple[str, ...] = ("m1", "m2", "l1", "l2", "r1", "r2", "b1", "b2", "cf1", "cf2", "g", "I1", "I2", "Ir", "gr")

#: ``data/system_identification/identified_parameters/design_C.1/model_1.0/model_parameters.yml`` (commit 1e8544e).
MODEL_1_0: Mapping[str, float] = {
    "m1": 0.5234602302310271,
    "m2": 0.6255677234174437,
    "l1": 0.2,
    "l2": 0.3,
    "r1": 0.2,
    "r2": 0.25569305436052964,
    "b1": 0.001,
    "b2": 0.001,
    "cf1": 0.16,
    "cf2": 0.12,
    "g": 9.81,
    "I1": 0.031887199591513114,
    "I2": 0.05086984812807257,
    "Ir": 6.287203962819607e-05,
    "gr": 6.0,
}

#: The ten model parameters the benchmark varies, in its order (``mpar_vars``).
MODEL_VARIATIONS: tuple[str, ...] = ("Ir", "m1r1", "I1", "b1", "cf1", "m2r2", "m2", "I2", "b2", "cf2")


def nominal_params(task: str) -> dict[str, float]:
    """The robustness-v2 plant of a task: model 1.0 with ``Ir = b = cf = 0`` (``sim_parameters.py``).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (the torque limit [6, 0] or [0, 6] is the task's, not a parameter here).

    Returns
    -------
    dict of str to float
        Values of :data:`PARAM_NAMES`.

    Raises
    ------
    ValueError
        Unknown ``task``.
    """
    check_task(task)
    return {**MODEL_1_0, "Ir": 0.0, "b1": 0.0, "b2": 0.0, "cf1": 0.0, "cf2": 0.0}


def vary(params: Mapping[str, float], name: str, value: float) -> dict[str, float]:
    """One model-parameter variation as the benchmark applies it (``benchmarker.check_modelpar_robustness``).

    ``m1r1`` and ``m2r2`` change the centre of mass (``r_i = value / m_i``) and keep the mass
    and the joint inertia; ``m2`` changes the mass only (centre of mass and joint inertia
    kept); the others set the parameter of that name.

    Parameters
    ----------
    params : mapping of str to float
        Parameters (:data:`PARAM_NAMES`).
    name : str
        One of :data:`MODEL_VARIATIONS`.
    value : float
        The new value (``m1r1``, ``m2r2``: the product m r [kg.m]).

    Returns
    -------
    dict of str to float
        A new parameter dict.

    Raises
    ------
    ValueError
        Unknown ``name``.
    """
    out = dict(params)
    v = float(value)
    if name == "m1r1":
        out["r1"] = v / out["m1"]
    elif name == "m2r2":
        out["r2"] = v / out["m2"]
    elif name in MODEL_VARIATIONS:
        out[name] = v
    else:
        raise ValueError(f"name must be one of {list(MODEL_VARIATIONS)}, got {name!r}")
    return out


@cache
def protocol_rhs() -> ca.Function:
    """The plant's right-hand side as a CasADi Function, absolute angles.

    Returns
    -------
    casadi.Function
        ``rhs(x, tau, p) -> xdot``: ``x = (theta1, theta2, omega1, omega2)`` (absolute angles
        from hanging [rad, rad/s]), ``tau = (tau1, tau2)`` joint torques [N.m] (``tau2`` between
        the links), ``p`` the values of :data:`PARAM_NAMES`.
    """
    sm = build_rigid()
    theta, omega = sm.q, sm.qd
    p = ca.SX.sym("p", len(PARAM_NAMES))
    P = dict(zip(PARAM_NAMES, ca.vertsplit(p), strict=True))
    # pendulab's parameters (m1, m2, L1, L2, g, b1, b2, lc1, lc2, I1, I2) with inertias about the centres of mass.
    pendulab_p = ca.vertcat(
        P["m1"], P["m2"], P["l1"], P["l2"], P["g"], P["b1"], P["b2"], P["r1"], P["r2"],
        P["I1"] - P["m1"] * P["r1"] ** 2, P["I2"] - P["m2"] * P["r2"] ** 2,
    )  # fmt: skip
    T_links = ca.substitute(sm.kinetic, sm.p, pendulab_p)
    V = ca.substitute(sm.potential, sm.p, pendulab_p)
    D = ca.substitute(sm.dissipation, sm.p, pendulab_p) / 2  # pendulab: 2 D (joint viscous dampers)
    joint = ca.vertcat(theta[0], theta[1] - theta[0])
    J = ca.jacobian(joint, theta)
    rate = J @ omega
    Ir, gr = P["Ir"], P["gr"]
    M_rotor = ca.vertcat(ca.horzcat(gr**2 * Ir + Ir, -gr * Ir), ca.horzcat(-gr * Ir, gr**2 * Ir))
    T = T_links + 0.5 * ca.dot(rate, M_rotor @ rate)
    tau = ca.SX.sym("tau", 2)
    coulomb = ca.vertcat(P["cf1"] * ca.atan(100 * rate[0]), P["cf2"] * ca.atan(100 * rate[1]))
    Q = J.T @ (tau - coulomb)
    eom = lagrange_equations(theta, omega, T, V, D, Q)
    x = ca.vertcat(theta, omega)
    return ca.Function("protocol_rhs", [x, tau, p], [ca.vertcat(omega, eom.qdd)], ["x", "tau", "p"], ["xdot"])


@cache
def protocol_rhs_python() -> Callable[[np.ndarray, np.ndarray, list[float]], np.ndarray]:
    """:func:`protocol_rhs` translated to plain Python (:func:`pendulab.model.pycode.to_python`): ~10x faster per call.

    Returns
    -------
    callable
        ``f(x, tau, p) -> ndarray, shape (4,)`` with the arguments of :func:`protocol_rhs`.
    """
    return to_python(protocol_rhs())


def params_vector(params: Mapping[str, float]) -> list[float]:
    """The values of :data:`PARAM_NAMES` in order.

    Parameters
    ----------
    params : mapping of str to float
        Parameters by name.

    Returns
    -------
    list of float
        ``[params[n] for n in PARAM_NAMES]``.

    Raises
    ------
    KeyError
        A parameter is missing.
    """
    return [float(params[n]) for n in PARAM_NAMES]


def actuated_joint(task: str) -> int:
    """Index of the driven joint (0 pendubot, 1 acrobot).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.

    Returns
    -------
    int
        0 or 1.
    """
    return TASKS[check_task(task)]

"""The rigid double-pendulum *robot*: rigid links plus geared motors' rotor inertia and joint friction.

A real double-pendulum robot (RealAIGym's design C.1 and A.0) adds two things to the ideal rigid
links of :func:`pendulab.model.builders.build_rigid`: the rotor inertia ``Ir`` of the geared motors
(gear ratio ``gr``), and joint friction. Both act in *joint* coordinates ``q = (q1, q2)``, ``q2``
the angle of link 2 relative to link 1, which is also how the robot's records and RealAIGym's
``DoublePendulumPlant`` are written (``src/python/double_pendulum/model/plant.py`` of
github.com/dfki-ric-underactuated-lab/double_pendulum, commit 1e8544e):

* rotor kinetic energy ``1/2 q'^T M_r q'`` with ``M_r = [[gr^2 Ir + Ir, -gr Ir], [-gr Ir, gr^2 Ir]]``;
* viscous friction ``b_i q_i'`` (a Rayleigh function) and smoothed Coulomb friction
  ``cf_i atan(100 q_i')`` on the joint rates;
* link inertias ``I1, I2`` about the *joints* (``I_com = I_joint - m r^2``).

Nothing is typed by hand: the links' ``T`` and ``V`` are pendulab's own symbolic rigid model, the
rotor term is added to ``T`` as ``1/2 (J w)^T M_r (J w)`` with ``J = d(q1, theta2 - theta1)/d theta``,
the joint torques enter as ``J^T tau`` and :func:`pendulab.model.lagrange.lagrange_equations`
derives the equations of motion. The same symbols give the forward dynamics (:func:`robot_rhs`)
and the inverse dynamics (:func:`robot_inverse_dynamics`) that system identification regresses.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from .builders import build_rigid
from .lagrange import LagrangeSystem, lagrange_equations

__all__ = [
    "ROBOT_PARAM_NAMES",
    "ROBOT_PARAM_UNITS",
    "COULOMB_SHARPNESS",
    "RobotSymbols",
    "build_robot",
    "robot_rhs",
    "robot_inverse_dynamics",
    "check_robot_params",
    "robot_params_vector",
]

#: Parameter vector (RealAIGym's names): masses [kg], link lengths [m], joint-to-centre-of-mass
#: distances [m], viscous [N.m.s/rad] and Coulomb [N.m] joint friction, gravity [m/s^2], link
#: inertias about the joints [kg.m^2], rotor inertia [kg.m^2], gear ratio [-].
ROBOT_PARAM_NAMES: tuple[str, ...] = ("m1", "m2", "l1", "l2", "r1", "r2", "b1", "b2", "cf1", "cf2", "g", "I1", "I2", "Ir", "gr")

#: Units of :data:`ROBOT_PARAM_NAMES`.
ROBOT_PARAM_UNITS: Mapping[str, str] = {
    "m1": "kg", "m2": "kg", "l1": "m", "l2": "m", "r1": "m", "r2": "m", "b1": "N.m.s/rad", "b2": "N.m.s/rad",
    "cf1": "N.m", "cf2": "N.m", "g": "m/s2", "I1": "kg.m2", "I2": "kg.m2", "Ir": "kg.m2", "gr": "-",
}  # fmt: skip

#: Slope of the smoothed Coulomb friction ``cf atan(COULOMB_SHARPNESS q')`` at rest [s/rad] (upstream's 100).
COULOMB_SHARPNESS = 100.0


@dataclass(frozen=True)
class RobotSymbols:
    """The robot's symbolic equations of motion in absolute angles.

    Attributes
    ----------
    theta, omega : casadi.SX, shape (2, 1)
        Absolute angles from hanging [rad] and their rates [rad/s].
    tau : casadi.SX, shape (2, 1)
        Joint torques [N.m] (``tau2`` between the links).
    p : casadi.SX, shape (15, 1)
        The values of :data:`ROBOT_PARAM_NAMES`.
    eom : LagrangeSystem
        ``M(theta) theta'' = rhs(theta, omega, tau)``.
    joint_map : casadi.DM, shape (2, 2)
        ``J``: joint rates ``q' = J omega``.
    """

    theta: ca.SX
    omega: ca.SX
    tau: ca.SX
    p: ca.SX
    eom: LagrangeSystem
    joint_map: ca.DM


@cache
def build_robot() -> RobotSymbols:
    """Derive the robot's equations of motion (see the module docstring).

    Returns
    -------
    RobotSymbols
        Symbols and the Lagrange system.
    """
    sm = build_rigid()
    theta, omega = sm.q, sm.qd
    p = ca.SX.sym("p", len(ROBOT_PARAM_NAMES))
    P = dict(zip(ROBOT_PARAM_NAMES, ca.vertsplit(p), strict=True))
    # pendulab's rigid parameters (m1, m2, L1, L2, g, b1, b2, lc1, lc2, I1, I2) with inertias about the centres of mass.
    rigid_p = ca.vertcat(
        P["m1"], P["m2"], P["l1"], P["l2"], P["g"], P["b1"], P["b2"], P["r1"], P["r2"],
        P["I1"] - P["m1"] * P["r1"] ** 2, P["I2"] - P["m2"] * P["r2"] ** 2,
    )  # fmt: skip
    T_links = ca.substitute(sm.kinetic, sm.p, rigid_p)
    V = ca.substitute(sm.potential, sm.p, rigid_p)
    D = ca.substitute(sm.dissipation, sm.p, rigid_p) / 2  # pendulab's D is twice the Rayleigh function of joint dampers
    joint = ca.vertcat(theta[0], theta[1] - theta[0])
    J = ca.jacobian(joint, theta)
    rate = J @ omega
    Ir, gr = P["Ir"], P["gr"]
    M_rotor = ca.vertcat(ca.horzcat(gr**2 * Ir + Ir, -gr * Ir), ca.horzcat(-gr * Ir, gr**2 * Ir))
    T = T_links + 0.5 * ca.dot(rate, M_rotor @ rate)
    tau = ca.SX.sym("tau", 2)
    coulomb = ca.vertcat(P["cf1"] * ca.atan(COULOMB_SHARPNESS * rate[0]), P["cf2"] * ca.atan(COULOMB_SHARPNESS * rate[1]))
    Q = J.T @ (tau - coulomb)
    eom = lagrange_equations(theta, omega, T, V, D, Q)
    return RobotSymbols(theta=theta, omega=omega, tau=tau, p=p, eom=eom, joint_map=ca.DM(ca.evalf(J)))


@cache
def robot_rhs() -> ca.Function:
    """Forward dynamics in absolute angles.

    Returns
    -------
    casadi.Function
        ``rhs(x, tau, p) -> xdot``: ``x = (theta1, theta2, omega1, omega2)`` (absolute angles from
        hanging [rad, rad/s]), ``tau = (tau1, tau2)`` joint torques [N.m], ``p`` the values of
        :data:`ROBOT_PARAM_NAMES`.
    """
    s = build_robot()
    x = ca.vertcat(s.theta, s.omega)
    return ca.Function("robot_rhs", [x, s.tau, s.p], [ca.vertcat(s.omega, s.eom.qdd)], ["x", "tau", "p"], ["xdot"])


@cache
def robot_inverse_dynamics() -> ca.Function:
    """Inverse dynamics in joint coordinates (as the robot's records are written).

    From ``M theta'' = rhs(tau)`` and ``rhs = rhs(0) + J^T tau``: ``tau = J^-T (M theta'' - rhs(0))``.

    Returns
    -------
    casadi.Function
        ``tau(q, qd, qdd, p) -> tau``: ``q = (q1, q2)`` joint angles [rad] (``q2`` relative),
        their first and second derivatives, ``p`` the values of :data:`ROBOT_PARAM_NAMES`;
        the joint torques that produce that motion [N.m].
    """
    s = build_robot()
    q, qd, qdd = ca.SX.sym("q", 2), ca.SX.sym("qd", 2), ca.SX.sym("qdd", 2)
    J = s.joint_map
    Jinv = ca.DM(np.linalg.inv(np.asarray(J)))
    to_abs = {"theta": Jinv @ q, "omega": Jinv @ qd}
    residual = s.eom.M @ (Jinv @ qdd) - ca.substitute(s.eom.rhs, s.tau, ca.DM.zeros(2))
    residual = ca.substitute(residual, ca.vertcat(s.theta, s.omega), ca.vertcat(to_abs["theta"], to_abs["omega"]))
    tau = ca.solve(J.T, residual)
    return ca.Function("robot_inverse_dynamics", [q, qd, qdd, s.p], [tau], ["q", "qd", "qdd", "p"], ["tau"])


def check_robot_params(params: Mapping[str, float], name: str = "params") -> dict[str, float]:
    """Validate a robot parameter set: every name known and present, every value finite and physical.

    Parameters
    ----------
    params : mapping of str to float
        Values of :data:`ROBOT_PARAM_NAMES`.
    name : str, default "params"
        The argument's name in error messages.

    Returns
    -------
    dict of str to float
        The values as floats, in :data:`ROBOT_PARAM_NAMES` order.

    Raises
    ------
    KeyError
        A name missing or unknown.
    ValueError
        A value not finite, a mass, length or the gear ratio not positive, friction, gravity or an
        inertia negative, or a link inertia about its joint below ``m r^2`` (negative inertia about
        the centre of mass).
    """
    unknown = sorted(set(params) - set(ROBOT_PARAM_NAMES))
    missing = [n for n in ROBOT_PARAM_NAMES if n not in params]
    if unknown or missing:
        raise KeyError(f"{name}: unknown names {unknown}, missing names {missing}; expected exactly {list(ROBOT_PARAM_NAMES)}")
    out: dict[str, float] = {}
    for n in ROBOT_PARAM_NAMES:
        try:
            v = float(params[n])
        except (TypeError, ValueError):
            raise ValueError(f"{name}[{n!r}] must be a real number, got {params[n]!r}") from None
        if not np.isfinite(v):
            raise ValueError(f"{name}[{n!r}] must be finite, got {v!r}")
        out[n] = v
    for n in ("m1", "m2", "l1", "l2", "gr"):
        if out[n] <= 0.0:
            raise ValueError(f"{name}[{n!r}] must be > 0 [{ROBOT_PARAM_UNITS[n]}], got {out[n]!r}")
    for n in ("b1", "b2", "cf1", "cf2", "g", "Ir"):
        if out[n] < 0.0:
            raise ValueError(f"{name}[{n!r}] must be >= 0 [{ROBOT_PARAM_UNITS[n]}], got {out[n]!r}")
    for i in ("1", "2"):
        m, r, inertia = out["m" + i], out["r" + i], out["I" + i]
        # Relative slack: a set written with finite digits may sit on the bound (I = m r^2, a point mass).
        if inertia < m * r * r * (1.0 - 1e-9):
            raise ValueError(
                f"{name}: I{i} = {inertia!r} kg.m2 about joint {i} is below m{i} r{i}^2 = {m * r * r!r} kg.m2, "
                "a negative inertia about the centre of mass; expected I >= m r^2"
            )
    return out


def robot_params_vector(params: Mapping[str, float]) -> np.ndarray:
    """The values of :data:`ROBOT_PARAM_NAMES` in order, validated (:func:`check_robot_params`).

    Parameters
    ----------
    params : mapping of str to float
        Parameters by name.

    Returns
    -------
    numpy.ndarray, shape (15,)
        The parameter vector of :func:`robot_rhs` and :func:`robot_inverse_dynamics`.
    """
    return np.array(list(check_robot_params(params).values()))

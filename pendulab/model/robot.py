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

Nothing is typed by hand, and there is one Lagrangian: pendulab's rigid model carries the
drivetrain (:class:`~pendulab.model.params.RigidParams` ``Ir, gr, cf1, cf2``), so the robot is the
rigid model in RealAIGym's parametrization (inertias about the joints, ``I_com = I_joint - m r^2``),
substituted into its symbolic equations. The same symbols give the forward dynamics
(:func:`robot_rhs`) and the inverse dynamics (:func:`robot_inverse_dynamics`) that system
identification regresses; :func:`robot_to_rigid` turns a robot parameter set into
:func:`pendulab.rigid` arguments.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from .builders import COULOMB_SHARPNESS, build_rigid
from .lagrange import LagrangeSystem
from .params import RigidParams

__all__ = [
    "joint_rates",
    "ROBOT_PARAM_NAMES",
    "ROBOT_PARAM_UNITS",
    "COULOMB_SHARPNESS",
    "RobotSymbols",
    "build_robot",
    "robot_rhs",
    "robot_inverse_dynamics",
    "check_robot_params",
    "robot_params_vector",
    "robot_to_rigid",
]

#: Parameter vector (RealAIGym's names): masses [kg], link lengths [m], joint-to-centre-of-mass
#: distances [m], viscous [N.m.s/rad] and Coulomb [N.m] joint friction, gravity [m/s^2], link
#: inertias about the joints [kg.m^2], rotor inertia [kg.m^2], gear ratio [-].
ROBOT_PARAM_NAMES: tuple[str, ...] = ("m1", "m2", "l1", "l2", "r1", "r2", "b1", "b2", "cf1", "cf2", "g", "I1", "I2", "Ir", "gr")

#: Units of :data:`ROBOT_PARAM_NAMES`.
ROBOT_PARAM_UNITS: Mapping[str, str] = {
    "m1": "kg", "m2": "kg", "l1": "m", "l2": "m", "r1": "m", "r2": "m", "b1": "N.m.s/rad", "b2": "N.m.s/rad",
    "cf1": "N.m", "cf2": "N.m", "g": "m/s2", "I1": "kg.m2", "I2": "kg.m2", "Ir": "kg.m2", "gr": "1",
}  # fmt: skip


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
    """The rigid model's equations of motion in RealAIGym's parameters (see the module docstring).

    Returns
    -------
    RobotSymbols
        Symbols and the Lagrange system.
    """
    sm = build_rigid()
    theta, omega = sm.q, sm.qd
    p = ca.SX.sym("p", len(ROBOT_PARAM_NAMES))
    P = dict(zip(ROBOT_PARAM_NAMES, ca.vertsplit(p), strict=True))
    rigid_p = ca.vertcat(*(_rigid_expression(P, n) for n in RigidParams.names()))
    eom = LagrangeSystem(*(ca.substitute(e, sm.p, rigid_p) for e in (sm.eom.M, sm.eom.rhs, sm.eom.qdd, sm.eom.bias)))
    J = ca.jacobian(ca.vertcat(theta[0], theta[1] - theta[0]), theta)
    return RobotSymbols(theta=theta, omega=omega, tau=sm.u, p=p, eom=eom, joint_map=ca.DM(ca.evalf(J)))


def _rigid_expression(P: Mapping[str, ca.SX], name: str) -> ca.SX:
    """One :class:`RigidParams` value in RealAIGym's parameters (works on symbols and on floats)."""
    if name in _RIGID_FROM_ROBOT:
        return P[_RIGID_FROM_ROBOT[name]]
    i = name[-1]  # I1 or I2: about the centre of mass
    return P["I" + i] - P["m" + i] * P["r" + i] ** 2


#: RigidParams names taken over unchanged (renamed) from RealAIGym's; I1, I2 are shifted to the centres of mass.
_RIGID_FROM_ROBOT: Mapping[str, str] = {
    "m1": "m1", "m2": "m2", "L1": "l1", "L2": "l2", "g": "g", "b1": "b1", "b2": "b2", "lc1": "r1", "lc2": "r2",
    "Ir": "Ir", "gr": "gr", "cf1": "cf1", "cf2": "cf2",
}  # fmt: skip


def robot_to_rigid(params: Mapping[str, float]) -> dict[str, float]:
    """:func:`pendulab.rigid` arguments of a robot parameter set: the same robot as a pendulab model.

    Parameters
    ----------
    params : mapping of str to float
        Values of :data:`ROBOT_PARAM_NAMES` (validated, :func:`check_robot_params`).

    Returns
    -------
    dict of str to float
        Values of :class:`~pendulab.model.params.RigidParams` (inertias about the centres of
        mass, clipped at 0 where a point mass sits on the bound ``I = m r^2`` within rounding).
    """
    P = check_robot_params(params)
    return {
        n: max(0.0, float(_rigid_expression(P, n))) if n in ("I1", "I2") else P[_RIGID_FROM_ROBOT[n]] for n in RigidParams.names()
    }


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


def robot_params_vector(params: Mapping[str, float], *, validate: bool = True) -> np.ndarray:
    """The values of :data:`ROBOT_PARAM_NAMES` in order, validated (:func:`check_robot_params`).

    Parameters
    ----------
    params : mapping of str to float
        Parameters by name.
    validate : bool, default True
        Check them first. ``False`` only where a protocol deliberately simulates values outside
        the physical range (RealAIGym's robustness grid varies Coulomb friction down to -0.2 N.m).

    Returns
    -------
    numpy.ndarray, shape (15,)
        The parameter vector of :func:`robot_rhs` and :func:`robot_inverse_dynamics`.
    """
    if validate:
        return np.array(list(check_robot_params(params).values()))
    return np.array([float(params[n]) for n in ROBOT_PARAM_NAMES])


def joint_rates(x: np.ndarray) -> np.ndarray:
    """The joint rates ``(omega1, omega2 - omega1)`` of pendulab states (absolute angles): what a robot's limits bound.

    Parameters
    ----------
    x : array_like, shape (..., nx)
        States, the link rates ``omega1, omega2`` at ``nx // 2`` (rigid: nx = 4; elastic: nx = 8) [rad/s].

    Returns
    -------
    ndarray, shape (..., 2)
        Shoulder and elbow joint rates [rad/s].

    Examples
    --------
    >>> joint_rates([0.0, 0.0, 3.0, -2.0]).tolist()  # links turning apart: the elbow joint at -5 rad/s
    [3.0, -5.0]
    """
    x = np.asarray(x, dtype=float)
    nq = x.shape[-1] // 2
    return np.stack([x[..., nq], x[..., nq + 1] - x[..., nq]], axis=-1)

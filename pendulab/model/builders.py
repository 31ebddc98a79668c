"""Symbolic rigid and elastic double pendulum: energies in, equations out.

This is the only module that creates physics symbols. Each builder states the
geometry (positions of the masses as functions of q), from which velocities,
kinetic and potential energy, the Rayleigh dissipation function and the
generalized forces of the joint torques are formed; ``lagrange_equations``
turns them into M(q) q'' = rhs.

Conventions (see DESIGN.md): absolute angles from the downward vertical,
``tau1`` acts between ground and link 1, ``tau2`` between link 1 and link 2,
so the torques do virtual work tau1 d(theta1) + tau2 d(theta2 - theta1).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

import casadi as ca

from .lagrange import LagrangeSystem, lagrange_equations
from .params import ElasticParams, RigidParams

__all__ = ["SymbolicModel", "build_rigid", "build_elastic", "STATE_NAMES", "COULOMB_SHARPNESS"]

#: Slope of the smoothed Coulomb friction ``cf atan(COULOMB_SHARPNESS q')`` at rest [s/rad]
#: (RealAIGym's ``DoublePendulumPlant`` uses 100).
COULOMB_SHARPNESS = 100.0

#: State names of each model kind (the one place they are typed): angles, [spring lengths,] their rates.
STATE_NAMES: dict[str, tuple[str, ...]] = {
    "rigid": ("theta1", "theta2", "omega1", "omega2"),
    "elastic": ("theta1", "theta2", "r1", "r2", "omega1", "omega2", "v1", "v2"),
}


@dataclass(frozen=True)
class SymbolicModel:
    """All symbolic expressions of one pendulum model.

    Attributes
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    x, u, p : casadi.SX
        State (nx,), input (2,) = (tau1, tau2) and parameter (np,) symbols.
    q, qd : casadi.SX
        Generalized coordinates and velocities (views into ``x``).
    eom : LagrangeSystem
        Mass matrix, right-hand side and accelerations.
    xdot : casadi.SX, shape (nx, 1)
        State derivative.
    kinetic, potential, spring : casadi.SX
        Kinetic energy, total potential energy (gravity + springs) and the
        spring part of it [J].
    dissipation : casadi.SX
        Power dissipated by the dampers (2 D) and the Coulomb friction [W].
    power_in : casadi.SX
        Power delivered by the torques, tau1 w1 + tau2 (w2 - w1) [W].
    positions : casadi.SX, shape (4, 1)
        x1, y1, x2, y2 of the link ends / bobs [m], y up.
    stretch : casadi.SX, shape (2, 1)
        Spring extensions r - L [m] (zero for the rigid model).
    state_names : tuple of str
        Names of the entries of ``x`` (see ``STATE_NAMES``).
    """

    kind: str
    x: ca.SX
    u: ca.SX
    p: ca.SX
    q: ca.SX
    qd: ca.SX
    eom: LagrangeSystem
    xdot: ca.SX
    kinetic: ca.SX
    potential: ca.SX
    spring: ca.SX
    dissipation: ca.SX
    power_in: ca.SX
    positions: ca.SX
    stretch: ca.SX
    state_names: tuple[str, ...]


def _unit(theta: ca.SX) -> ca.SX:
    """Unit vector along a link at absolute angle theta from the downward vertical."""
    return ca.vertcat(ca.sin(theta), -ca.cos(theta))


def _joint_terms(theta: ca.SX, omega: ca.SX, u: ca.SX, b1: ca.SX, b2: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """Joint coordinates (theta1, theta2 - theta1): their torques' generalized
    forces on theta (by virtual work), joint Rayleigh dissipation and input power."""
    joint_angle = ca.vertcat(theta[0], theta[1] - theta[0])
    J = ca.jacobian(joint_angle, theta)
    joint_rate = J @ omega
    Q_theta = J.T @ u
    D = 0.5 * b1 * joint_rate[0] ** 2 + 0.5 * b2 * joint_rate[1] ** 2
    power = ca.dot(u, joint_rate)
    return Q_theta, D, power


def _drivetrain_terms(theta: ca.SX, omega: ca.SX, Ir: ca.SX, gr: ca.SX, cf1: ca.SX, cf2: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """A robot's geared motors: rotor kinetic energy, Coulomb friction's generalized forces and its power.

    The rotors turn at ``gr q'`` about the joints (RealAIGym's ``DoublePendulumPlant``): kinetic
    energy ``1/2 q'^T M_r q'`` with ``M_r = [[gr^2 Ir + Ir, -gr Ir], [-gr Ir, gr^2 Ir]]`` in joint
    rates ``q' = (omega1, omega2 - omega1)``; the friction ``cf atan(100 q')`` opposes each joint rate.
    """
    joint_angle = ca.vertcat(theta[0], theta[1] - theta[0])
    J = ca.jacobian(joint_angle, theta)
    rate = J @ omega
    M_rotor = ca.vertcat(ca.horzcat(gr**2 * Ir + Ir, -gr * Ir), ca.horzcat(-gr * Ir, gr**2 * Ir))
    T_rotor = 0.5 * ca.dot(rate, M_rotor @ rate)
    friction = ca.vertcat(cf1 * ca.atan(COULOMB_SHARPNESS * rate[0]), cf2 * ca.atan(COULOMB_SHARPNESS * rate[1]))
    return T_rotor, -J.T @ friction, ca.dot(friction, rate)


def _assemble(
    kind: str,
    q: ca.SX,
    qd: ca.SX,
    u: ca.SX,
    p: ca.SX,
    com_positions: list[tuple[ca.SX, ca.SX]],
    point_inertias: list[tuple[ca.SX, ca.SX]],
    spring_V: ca.SX,
    Q: ca.SX,
    D: ca.SX,
    power_in: ca.SX,
    g: ca.SX,
    positions: ca.SX,
    stretch: ca.SX,
    state_names: tuple[str, ...],
    extra_kinetic: ca.SX | float = 0.0,
    extra_dissipation: ca.SX | float = 0.0,
    chain: Sequence[Sequence[int]] | None = None,
) -> SymbolicModel:
    # Velocities are derived, not typed: v = (d pos / dq) q'.
    T = extra_kinetic
    V = spring_V
    for mass, pos in com_positions:
        vel = ca.jtimes(pos, q, qd)
        T += 0.5 * mass * ca.dot(vel, vel)
        V += mass * g * pos[1]
    for inertia, rate in point_inertias:
        T += 0.5 * inertia * rate**2
    # Point masses alone on a chain (``chain``: the coordinates each body adds): the mass matrix factors through
    # the positions' Jacobian (pendulab.model.lagrange), a third of the expression of the generic solve.
    if chain is not None and (point_inertias or not isinstance(extra_kinetic, float) or extra_kinetic != 0.0):
        raise ValueError(f"{kind}: a chain of point masses carries no other kinetic energy")
    bodies = None if chain is None else [(m, pos, c) for (m, pos), c in zip(com_positions, chain, strict=True)]
    eom = lagrange_equations(q, qd, T, V, D, Q, bodies=bodies)
    x = ca.vertcat(q, qd)
    xdot = ca.vertcat(qd, eom.qdd)
    return SymbolicModel(
        kind=kind,
        x=x,
        u=u,
        p=p,
        q=q,
        qd=qd,
        eom=eom,
        xdot=xdot,
        kinetic=T,
        potential=V,
        spring=spring_V,
        dissipation=2 * D + extra_dissipation,
        power_in=power_in,
        positions=positions,
        stretch=stretch,
        state_names=state_names,
    )


@cache
def build_rigid() -> SymbolicModel:
    """Rigid double pendulum, 2 DOF, parameters in ``RigidParams`` order (links, then a robot's drivetrain)."""
    theta = ca.SX.sym("theta", 2)
    omega = ca.SX.sym("omega", 2)
    u = ca.SX.sym("tau", 2)
    p = ca.SX.sym("p", len(RigidParams.names()))
    m1, m2, L1, L2, g, b1, b2, lc1, lc2, I1, I2, Ir, gr, cf1, cf2 = ca.vertsplit(p)
    e1, e2 = _unit(theta[0]), _unit(theta[1])
    com1 = lc1 * e1
    com2 = L1 * e1 + lc2 * e2
    Q, D, power = _joint_terms(theta, omega, u, b1, b2)
    T_rotor, Q_friction, P_friction = _drivetrain_terms(theta, omega, Ir, gr, cf1, cf2)
    return _assemble(
        "rigid",
        theta,
        omega,
        u,
        p,
        com_positions=[(m1, com1), (m2, com2)],
        point_inertias=[(I1, omega[0]), (I2, omega[1])],
        spring_V=ca.SX(0),
        Q=Q + Q_friction,
        D=D,
        power_in=power,
        g=g,
        positions=ca.vertcat(L1 * e1, L1 * e1 + L2 * e2),
        stretch=ca.SX.zeros(2, 1),
        state_names=STATE_NAMES["rigid"],
        extra_kinetic=T_rotor,
        extra_dissipation=P_friction,
    )


@cache
def build_elastic() -> SymbolicModel:
    """Elastic (spring-link) double pendulum, 4 DOF, parameters in ``ElasticParams`` order."""
    theta = ca.SX.sym("theta", 2)
    r = ca.SX.sym("r", 2)
    omega = ca.SX.sym("omega", 2)
    v = ca.SX.sym("v", 2)
    u = ca.SX.sym("tau", 2)
    p = ca.SX.sym("p", len(ElasticParams.names()))
    m1, m2, L1, L2, g, b1, b2, k1, k2, c1, c2 = ca.vertsplit(p)
    q = ca.vertcat(theta, r)
    qd = ca.vertcat(omega, v)
    bob1 = r[0] * _unit(theta[0])
    bob2 = bob1 + r[1] * _unit(theta[1])
    Q_theta, D_joint, power = _joint_terms(theta, omega, u, b1, b2)
    stretch = r - ca.vertcat(L1, L2)
    spring_V = 0.5 * k1 * stretch[0] ** 2 + 0.5 * k2 * stretch[1] ** 2
    D = D_joint + 0.5 * c1 * v[0] ** 2 + 0.5 * c2 * v[1] ** 2
    return _assemble(
        "elastic",
        q,
        qd,
        u,
        p,
        com_positions=[(m1, bob1), (m2, bob2)],
        point_inertias=[],
        spring_V=spring_V,
        Q=ca.vertcat(Q_theta, 0, 0),
        D=D,
        power_in=power,
        g=g,
        positions=ca.vertcat(bob1, bob2),
        stretch=stretch,
        state_names=STATE_NAMES["elastic"],
        chain=[(0, 2), (1, 3)],  # bob 1 adds (theta1, r1), bob 2 (theta2, r2)
    )

"""Generic Lagrange builder: M(q) q'' = rhs(q, q', u) from T, V, D and Q.

Lagrange's equations with Rayleigh dissipation read

    d/dt (dT/dq') - dT/dq + dV/dq + dD/dq' = Q.

Expanding the time derivative, d/dt (dT/dq') = M(q) q'' + (d/dq dT/dq') q'
with M = d^2 T / dq'^2, so

    M q'' = Q - (d/dq dT/dq') q' + dT/dq - dV/dq - dD/dq'.

Everything is obtained by symbolic differentiation in CasADi; no equation of
motion is ever written by hand.

A system of point masses on a chain (the elastic pendulum) has more structure:
with T = 1/2 sum m_i |J_i q'|^2 the mass matrix is M = J^T W J and the
Coriolis/centrifugal terms are J^T W (J' q'), so Lagrange's equations
M q'' + bias = G read J q'' = W^-1 J^-T G - J' q' (J' q' the positions' second
derivative along q'). On a chain, each body moves only with its own
coordinates and those of the bodies before it: J is block lower triangular with
2 x 2 diagonal blocks, and q'' follows from two block substitutions instead of
a symbolic solve with M. The same accelerations, a third of the expression
(elastic pendulum: 192 SX instructions instead of 623; see
:func:`point_mass_accelerations`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import casadi as ca

__all__ = ["LagrangeSystem", "lagrange_equations", "point_mass_accelerations"]


@dataclass(frozen=True)
class LagrangeSystem:
    """Symbolic equations of motion ``M(q) q'' = rhs(q, q', u)``.

    Attributes
    ----------
    M : casadi.SX, shape (n, n)
        Mass matrix (Hessian of T in q').
    rhs : casadi.SX, shape (n, 1)
        Right-hand side: generalized forces minus Coriolis/centrifugal,
        gravity/spring and dissipative terms.
    qdd : casadi.SX, shape (n, 1)
        Accelerations ``M^{-1} rhs``.
    bias : casadi.SX, shape (n, 1)
        ``(d/dq dT/dq') q' - dT/dq`` (Coriolis and centrifugal terms).
    """

    M: ca.SX
    rhs: ca.SX
    qdd: ca.SX
    bias: ca.SX


def lagrange_equations(
    q: ca.SX,
    qd: ca.SX,
    T: ca.SX,
    V: ca.SX,
    D: ca.SX,
    Q: ca.SX,
    bodies: Sequence[tuple[ca.SX, ca.SX, Sequence[int]]] | None = None,
) -> LagrangeSystem:
    """Derive the equations of motion from energies and generalized forces.

    Parameters
    ----------
    q, qd : casadi.SX, shape (n, 1)
        Generalized coordinates and velocities (pure symbols).
    T : casadi.SX, scalar
        Kinetic energy T(q, q'), quadratic in q' [J].
    V : casadi.SX, scalar
        Potential energy V(q) [J].
    D : casadi.SX, scalar
        Rayleigh dissipation function D(q'), power dissipated = 2 D for
        quadratic D [W].
    Q : casadi.SX, shape (n, 1)
        Generalized non-conservative forces (from inputs).
    bodies : sequence of (mass, position, coordinates), optional
        When ``T`` is exactly the kinetic energy of these point masses on a chain (see
        :func:`point_mass_accelerations`), ``qdd`` is computed by the factored form; ``M``, ``rhs`` and
        ``bias`` are the generic ones either way.

    Returns
    -------
    LagrangeSystem
        Mass matrix, right-hand side, accelerations and bias terms.

    Raises
    ------
    ValueError
        ``q`` and ``qd`` are not column vectors of equal size, or ``Q`` does
        not have the shape of ``q``.
    """
    if q.shape != qd.shape or q.shape[1] != 1:
        raise ValueError(f"q and qd must be column vectors of equal size, got {q.shape} and {qd.shape}")
    if Q.shape != q.shape:
        raise ValueError(f"Q must have the shape of q {q.shape}, got {Q.shape}")
    dT_dqd = ca.gradient(T, qd)
    M = ca.jacobian(dT_dqd, qd)
    bias = ca.jtimes(dT_dqd, q, qd) - ca.gradient(T, q)
    applied = Q - ca.gradient(V, q) - ca.gradient(D, qd)
    rhs = applied - bias
    qdd = ca.solve(M, rhs) if bodies is None else point_mass_accelerations(q, qd, bodies, applied)
    return LagrangeSystem(M=M, rhs=rhs, qdd=qdd, bias=bias)


def point_mass_accelerations(q: ca.SX, qd: ca.SX, bodies: Sequence[tuple[ca.SX, ca.SX, Sequence[int]]], applied: ca.SX) -> ca.SX:
    """Accelerations of point masses on a chain: ``J q'' = W^-1 J^-T G - J' q'`` by block substitution.

    Lagrange's equations for ``T = 1/2 sum_i m_i |d p_i/dt|^2`` (exactly, no other kinetic energy), with
    the mass matrix ``M = J^T W J`` and the bias ``J^T W J' q'`` factored through the Jacobian ``J`` of the
    positions (module docstring).

    Parameters
    ----------
    q, qd : casadi.SX, shape (n, 1)
        Generalized coordinates and velocities.
    bodies : sequence of (mass, position, coordinates)
        Point masses in chain order: mass (scalar SX) [kg], planar position (SX, shape (2, 1)) [m] and the
        indices of the two coordinates of ``q`` the body adds to the chain. Together the coordinates cover
        ``q`` once; a body's position may depend on its own and earlier bodies' coordinates only.
    applied : casadi.SX, shape (n, 1)
        Generalized applied forces ``G = Q - dV/dq - dD/dq'``.

    Returns
    -------
    casadi.SX, shape (n, 1)
        ``q''``.

    Raises
    ------
    ValueError
        The coordinates do not cover ``q`` once in pairs, or a body depends on a later body's coordinates
        (the Jacobian is not block lower triangular).
    """
    order = [i for _, _, coords in bodies for i in coords]
    if sorted(order) != list(range(q.numel())) or any(len(coords) != 2 for _, _, coords in bodies):
        raise ValueError(f"bodies must add two coordinates each and cover q once, got coordinates {order}")
    blocks, couplings, rates = [], [], []
    for k, (_, pos, coords) in enumerate(bodies):
        jac = ca.jacobian(pos, q)
        later = [i for _, _, c in bodies[k + 1 :] for i in c]
        if later and jac[:, later].nnz() > 0:
            raise ValueError(f"body {k} depends on a later body's coordinates {later}: not a chain")
        blocks.append(_inverse_2x2(jac[:, list(coords)]))
        couplings.append([jac[:, list(c)] for _, _, c in bodies[:k]])
        rates.append(ca.jtimes(ca.jtimes(pos, q, qd), q, qd))  # J' q': the position's second derivative along q'
    # J^T y = G, from the last body back (J^T is block upper triangular).
    y: list[ca.SX] = [ca.SX()] * len(bodies)
    for k in reversed(range(len(bodies))):
        g = applied[list(bodies[k][2])]
        for j in range(k + 1, len(bodies)):
            g -= couplings[j][k].T @ y[j]
        y[k] = blocks[k].T @ g
    # J q'' = y / m - J' q', from the first body on.
    qdd = ca.SX.zeros(q.numel(), 1)
    for k, (mass, _, coords) in enumerate(bodies):
        z = y[k] * (1 / mass) - rates[k]
        for j in range(k):
            z -= couplings[k][j] @ qdd[list(bodies[j][2])]
        qdd[list(coords)] = blocks[k] @ z
    return qdd


def _inverse_2x2(a: ca.SX) -> ca.SX:
    """Inverse of a symbolic 2 x 2 matrix by its adjugate (a generic solve expands to more operations)."""
    # One division, then products: a division costs a Taylor integrator far more than a product.
    inv_det = 1 / (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0])
    return ca.vertcat(ca.horzcat(a[1, 1], -a[0, 1]), ca.horzcat(-a[1, 0], a[0, 0])) * inv_det

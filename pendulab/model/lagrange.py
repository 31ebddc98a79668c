"""Generic Lagrange builder: M(q) q'' = rhs(q, q', u) from T, V, D and Q.

Lagrange's equations with Rayleigh dissipation read

    d/dt (dT/dq') - dT/dq + dV/dq + dD/dq' = Q.

Expanding the time derivative, d/dt (dT/dq') = M(q) q'' + (d/dq dT/dq') q'
with M = d^2 T / dq'^2, so

    M q'' = Q - (d/dq dT/dq') q' + dT/dq - dV/dq - dD/dq'.

Everything is obtained by symbolic differentiation in CasADi; no equation of
motion is ever written by hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

__all__ = ["LagrangeSystem", "lagrange_equations"]


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


def lagrange_equations(q: ca.SX, qd: ca.SX, T: ca.SX, V: ca.SX, D: ca.SX, Q: ca.SX) -> LagrangeSystem:
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
    rhs = Q - bias - ca.gradient(V, q) - ca.gradient(D, qd)
    qdd = ca.solve(M, rhs)
    return LagrangeSystem(M=M, rhs=rhs, qdd=qdd, bias=bias)

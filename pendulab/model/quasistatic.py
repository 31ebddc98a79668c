"""Quasi-static spring lengths: r such that the radial accelerations vanish.

For the elastic pendulum at angles theta and angular rates omega (and spring
rates v = 0), the quasi-static lengths r*(theta, omega) solve

    [rhs(theta, r, omega, 0, u)]_(dv1/dt, dv2/dt) = 0,

i.e. the springs carry gravity, the centrifugal load and the inertial coupling
of the current motion without oscillating. Starting there (instead of at rest
length) keeps the fast spring mode unexcited, and along a rigid trajectory
r*(theta(t), omega(t)) is the "rigid + quasi-static stretch" model of the
scene hierarchy. Everything comes from ``model.functions["rhs"]``.
"""

from __future__ import annotations

from functools import cache, lru_cache
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["quasi_static_state", "quasi_static_lengths"]


@cache
def _solver() -> tuple[ca.Function, ca.Function]:
    """r*(r0, theta, omega, u, p) by Newton on the radial accelerations, and that residual."""
    from .model import model_functions

    f = model_functions("elastic")["rhs"]
    npar = f.size1_in(2)
    r = ca.SX.sym("r", 2)
    theta, omega, u, p = ca.SX.sym("theta", 2), ca.SX.sym("omega", 2), ca.SX.sym("u", 2), ca.SX.sym("p", npar)
    radial_acc = f(ca.vertcat(theta, r, omega, ca.SX.zeros(2)), u, p)[6:8]
    G = ca.Function("qs_residual", [r, ca.vertcat(theta, omega, u, p)], [radial_acc])
    # Failure is detected from the residual afterwards, so a batch can name the point that failed.
    rf = ca.rootfinder("qs_newton", "newton", G, {"abstol": 1e-12, "max_iter": 50, "error_on_fail": False})
    rm0 = ca.MX.sym("r0", 2)
    thm, omm, um, pm = ca.MX.sym("theta", 2), ca.MX.sym("omega", 2), ca.MX.sym("u", 2), ca.MX.sym("p", npar)
    rs = rf(rm0, ca.vertcat(thm, omm, um, pm))
    solve = ca.Function("quasi_static_r", [rm0, thm, omm, um, pm], [rs], ["r0", "theta", "omega", "u", "p"], ["r"])
    residual = ca.Function("qs_res", [r, theta, omega, u, p], [radial_acc])
    return solve, residual


@lru_cache(maxsize=8)
def _mapped(n: int) -> tuple[ca.Function, ca.Function]:
    """The solver and its residual over ``n`` points (a trajectory is usually evaluated more than once)."""
    solve, residual = _solver()
    return solve.map(n), residual.map(n)


def _check_elastic(model: Any) -> None:
    if getattr(model, "kind", None) != "elastic":
        raise ValueError(f"model must be an elastic pendulab Model, got kind {getattr(model, 'kind', type(model).__name__)!r}")


def quasi_static_lengths(model: Any, theta: Any, omega: Any, u: Any = None) -> np.ndarray:
    """Quasi-static spring lengths r* [m] for one or many (theta, omega).

    Parameters
    ----------
    model : Model
        Elastic model.
    theta, omega : array_like, shape (2,) or (N, 2)
        Absolute angles [rad] and angular rates [rad/s].
    u : array_like, shape (2,), optional
        Constant torques [N.m] (default zero).

    Returns
    -------
    ndarray, shape (2,) or (N, 2)
        Lengths r1, r2 [m] with zero radial acceleration at v = 0.

    Raises
    ------
    ValueError
        Not an elastic model, or bad shapes.
    RuntimeError
        Newton did not converge (e.g. springs too soft to hold the motion).
    """
    _check_elastic(model)
    th = np.atleast_2d(np.asarray(theta, dtype=float))
    om = np.atleast_2d(np.asarray(omega, dtype=float))
    if th.shape[-1] != 2 or om.shape != th.shape:
        raise ValueError(f"theta and omega must both have shape (2,) or (N, 2), got {th.shape} and {om.shape}")
    uc = model.check_input(u, "u")
    r0 = model.rest_state()[2:4]
    n = th.shape[0]
    solve, residual = _solver()
    args = (th.T, om.T, uc, model.p)
    if n > 1:  # building a map costs milliseconds: a single point calls the functions themselves
        solve, residual = _mapped(n)
    r = np.asarray(solve(np.tile(r0, (n, 1)).T, *args))
    res = np.abs(np.asarray(residual(r, *args)))
    pr = model.params
    # Residual scale: spring force per unit mass at a stretch of one rest length (so the
    # test accepts length errors below ~1e-9 L whatever the masses and stiffnesses).
    scale = np.array([[pr.k1 * pr.L1 / pr.m1 + pr.g], [pr.k2 * pr.L2 / pr.m2 + pr.g]])
    bad = ~np.all(np.isfinite(r), axis=0) | ~np.all(res < 1e-9 * scale, axis=0) | np.any(r <= 0, axis=0)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise RuntimeError(
            f"quasi-static spring lengths: no solution at theta={th[i].tolist()} rad, omega={om[i].tolist()} rad/s "
            "(the springs are too soft to hold the centrifugal load there)"
        )
    r = r.T
    return r[0] if np.ndim(theta) == 1 else r


def quasi_static_state(model: Any, theta: Any, omega: Any = (0.0, 0.0), u: Any = None) -> np.ndarray:
    """Elastic state at (theta, omega) with quasi-static spring lengths and v = 0.

    Parameters
    ----------
    model : Model
        Elastic model.
    theta : array_like, shape (2,)
        Absolute angles [rad].
    omega : array_like, shape (2,)
        Angular rates [rad/s] (default at rest).
    u : array_like, shape (2,), optional
        Constant torques [N.m].

    Returns
    -------
    ndarray, shape (8,)
        theta1, theta2, r1, r2, omega1, omega2, v1 = 0, v2 = 0.

    Raises
    ------
    ValueError
        ``theta`` or ``omega`` does not have shape (2,), or ``model`` is not
        elastic.
    RuntimeError
        Newton did not converge (see :func:`quasi_static_lengths`).
    """
    th = np.asarray(theta, dtype=float)
    om = np.asarray(omega, dtype=float)
    if th.shape != (2,) or om.shape != (2,):
        raise ValueError(f"theta and omega must have shape (2,), got {th.shape} and {om.shape}")
    r = quasi_static_lengths(model, th, om, u)
    return np.concatenate([th, r, om, np.zeros(2)])

"""The robot's inverse dynamics as a linear regression ``tau = Y(q, q', q'') pi``, derived symbolically.

The *standard* parameters :data:`STANDARD_NAMES` make the inverse dynamics of
:func:`pendulab.model.robot.robot_inverse_dynamics` linear: per link the mass ``m``, the first
moment ``h = m r`` [kg.m] and the inertia about the joint ``I``; the rotor inertia ``Ir``; the
friction coefficients; and a constant offset ``o`` of each torque reading (``tau_read = tau + o``).
The regressor ``Y = d tau / d pi`` is CasADi's Jacobian of that symbolic inverse dynamics, never
typed by hand; the tests check ``Y pi`` against the inverse dynamics at random parameters.

Not every standard parameter shows in the motion: ``m1`` appears nowhere once ``h1`` and ``I1``
are given, and ``m2`` only in ``h1 + l1 m2`` and ``I1 + l1^2 m2``. :func:`base_parameters` finds
the identifiable combinations (the *base parameters*) from the regressor's columns numerically
and names them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from ..model.robot import ROBOT_PARAM_NAMES, robot_inverse_dynamics

__all__ = [
    "STANDARD_NAMES",
    "STANDARD_UNITS",
    "FIXED_NAMES",
    "regressor_function",
    "standard_to_robot",
    "robot_to_standard",
    "BaseParameters",
    "base_parameters",
]

#: Standard (linear) parameters, in regressor column order.
STANDARD_NAMES: tuple[str, ...] = ("m1", "h1", "I1", "m2", "h2", "I2", "Ir", "b1", "b2", "cf1", "cf2", "o1", "o2")

#: Units of :data:`STANDARD_NAMES`.
STANDARD_UNITS: Mapping[str, str] = {
    "m1": "kg", "h1": "kg.m", "I1": "kg.m2", "m2": "kg", "h2": "kg.m", "I2": "kg.m2", "Ir": "kg.m2",
    "b1": "N.m.s/rad", "b2": "N.m.s/rad", "cf1": "N.m", "cf2": "N.m", "o1": "N.m", "o2": "N.m",
}  # fmt: skip

#: Known quantities that are not fitted: link lengths [m], gravity [m/s^2], gear ratio [-].
FIXED_NAMES: tuple[str, ...] = ("l1", "l2", "g", "gr")


def _robot_vector(pi: ca.SX, fixed: ca.SX) -> ca.SX:
    s = dict(zip(STANDARD_NAMES, ca.vertsplit(pi), strict=True))
    f = dict(zip(FIXED_NAMES, ca.vertsplit(fixed), strict=True))
    values = {**s, **f, "r1": s["h1"] / s["m1"], "r2": s["h2"] / s["m2"]}
    return ca.vertcat(*[values[n] for n in ROBOT_PARAM_NAMES])


@cache
def regressor_function() -> ca.Function:
    """The regressor as a CasADi Function.

    Returns
    -------
    casadi.Function
        ``Y(q, qd, qdd, fixed) -> Y``, shape (2, 13): joint angles, rates and accelerations (each
        shape (2,)), the values of :data:`FIXED_NAMES`; ``tau_read = Y @ pi`` with ``pi`` the values
        of :data:`STANDARD_NAMES`.
    """
    q, qd, qdd = ca.SX.sym("q", 2), ca.SX.sym("qd", 2), ca.SX.sym("qdd", 2)
    pi, fixed = ca.SX.sym("pi", len(STANDARD_NAMES)), ca.SX.sym("fixed", len(FIXED_NAMES))
    tau = robot_inverse_dynamics()(q, qd, qdd, _robot_vector(pi, fixed)) + pi[-2:]
    # tau is linear in pi, so its Jacobian does not depend on pi; the masses must only be non-zero
    # where the expression divides by them (r = h / m) before the product cancels.
    Y = ca.substitute(ca.jacobian(tau, pi), pi, ca.DM.ones(len(STANDARD_NAMES)))
    return ca.Function("regressor", [q, qd, qdd, fixed], [Y], ["q", "qd", "qdd", "fixed"], ["Y"])


def standard_to_robot(pi: Mapping[str, float], fixed: Mapping[str, float]) -> dict[str, float]:
    """Robot parameters (:data:`~pendulab.model.robot.ROBOT_PARAM_NAMES`) from standard ones.

    Parameters
    ----------
    pi : mapping of str to float
        Values of :data:`STANDARD_NAMES` (offsets ignored: they belong to the sensor, not the plant).
    fixed : mapping of str to float
        Values of :data:`FIXED_NAMES`.

    Returns
    -------
    dict of str to float
        The robot's parameters, ``r = h / m``.
    """
    out = {n: float(pi[n]) for n in ("m1", "m2", "I1", "I2", "Ir", "b1", "b2", "cf1", "cf2")}
    out.update({n: float(fixed[n]) for n in FIXED_NAMES})
    out["r1"], out["r2"] = float(pi["h1"]) / out["m1"], float(pi["h2"]) / out["m2"]
    return {n: out[n] for n in ROBOT_PARAM_NAMES}


def robot_to_standard(params: Mapping[str, float]) -> dict[str, float]:
    """Standard parameters of a robot parameter set (offsets zero).

    Parameters
    ----------
    params : mapping of str to float
        Values of :data:`~pendulab.model.robot.ROBOT_PARAM_NAMES`.

    Returns
    -------
    dict of str to float
        Values of :data:`STANDARD_NAMES`.
    """
    p = {n: float(params[n]) for n in ROBOT_PARAM_NAMES}
    out = {n: p.get(n, 0.0) for n in STANDARD_NAMES}
    out["h1"], out["h2"] = p["m1"] * p["r1"], p["m2"] * p["r2"]
    out["o1"] = out["o2"] = 0.0
    return out


@dataclass(frozen=True)
class BaseParameters:
    """The identifiable combinations of a set of standard parameters.

    ``Y[:, dependent] = Y[:, independent] @ K`` on every sample, so ``Y pi = Y[:, independent] beta``
    with ``beta = pi[independent] + K @ pi[dependent]``.

    Attributes
    ----------
    columns : tuple of str
        The standard parameters considered (regressor columns).
    independent : tuple of str
        Columns kept, one per base parameter.
    dependent : tuple of str
        Columns that are combinations of the kept ones (or zero).
    K : numpy.ndarray, shape (len(independent), len(dependent))
        The combination coefficients.
    names : tuple of str
        Each base parameter written as its combination, e.g. ``"h1 + 0.2 m2"``.
    """

    columns: tuple[str, ...]
    independent: tuple[str, ...]
    dependent: tuple[str, ...]
    K: np.ndarray
    names: tuple[str, ...]

    def beta(self, pi: Mapping[str, float]) -> np.ndarray:
        """Base parameter values of standard parameters.

        Parameters
        ----------
        pi : mapping of str to float
            Values of (at least) :attr:`columns`.

        Returns
        -------
        numpy.ndarray, shape (len(independent),)
            ``pi[independent] + K @ pi[dependent]``.
        """
        ind = np.array([pi[n] for n in self.independent], dtype=float)
        dep = np.array([pi[n] for n in self.dependent], dtype=float)
        return ind + self.K @ dep if dep.size else ind


def base_parameters(Y: np.ndarray, columns: Sequence[str], rel_tol: float = 1e-8) -> BaseParameters:
    """Find the base parameters of stacked regressor rows.

    Columns are taken greedily in the given order, each kept if it raises the numerical rank (a
    singular value above ``rel_tol`` times the largest, of the column-scaled matrix); the others are
    expressed in the kept ones by least squares. The order is the naming preference: physical
    parameters first, the unidentifiable masses last, so they are the ones folded into combinations.

    Parameters
    ----------
    Y : numpy.ndarray, shape (m, len(columns))
        Regressor rows stacked over samples.
    columns : sequence of str
        Names of the columns, in the preferred order of keeping.
    rel_tol : float, default 1e-8
        Rank threshold relative to the largest singular value.

    Returns
    -------
    BaseParameters
        Kept columns, dependent columns and their combinations.

    Raises
    ------
    ValueError
        ``Y`` not 2-D with one column per name.
    """
    Y = np.asarray(Y, dtype=float)
    if Y.ndim != 2 or Y.shape[1] != len(columns):
        raise ValueError(f"Y must have shape (m, {len(columns)}), got {Y.shape}")
    scale = np.linalg.norm(Y, axis=0)
    Ys = Y / np.where(scale > 0, scale, 1.0)
    kept: list[int] = []
    for j in range(len(columns)):
        if scale[j] <= 1e-10 * scale.max():  # round-off of an exact zero (m1's column: h / m times m)
            continue
        trial = Ys[:, [*kept, j]]
        s = np.linalg.svd(trial, compute_uv=False)
        if s[-1] > rel_tol * s[0]:
            kept.append(j)
    dep = [j for j in range(len(columns)) if j not in kept]
    K = np.linalg.lstsq(Y[:, kept], Y[:, dep], rcond=None)[0] if dep else np.zeros((len(kept), 0))
    K[np.abs(K) < 1e-10 * max(1.0, np.abs(K).max(initial=0.0))] = 0.0
    names = []
    for i, j in enumerate(kept):
        terms = [columns[j]] + [f"{K[i, k]:+.6g} {columns[d]}" for k, d in enumerate(dep) if K[i, k] != 0.0]
        names.append(" ".join(terms).replace("+", "+ ").replace(" -", " - "))
    return BaseParameters(
        columns=tuple(columns), independent=tuple(columns[j] for j in kept), dependent=tuple(columns[j] for j in dep),
        K=K, names=tuple(names),
    )  # fmt: skip

"""Physically consistent weighted least squares on the inverse-dynamics regression.

``min  sum_j w_j |Y_j pi - tau_j|^2 / N  +  eps |(pi - pi_prior) / scale|^2`` over the structure's
free standard parameters (:mod:`pendulab.identify.regressor`), subject to physical consistency:
masses > 0, each link's inertia about its centre of mass non-negative (``m I - h^2 >= 0``, the
planar form of a positive semi-definite pseudo-inertia, a convex constraint), rotor inertia and
friction non-negative. CasADi states it and IPOPT solves it; the data enter only through the
normal equations ``Y^T W Y``, so leave-one-record-out fits cost a sum and a solve each.

The prior term only pins what the data cannot see (``m1`` and ``m2`` apart from their
combinations, weight 1e-2); on everything else it weighs 1e-6 of a unit-variance fit, far less
than the parameters' intervals. Intervals come from the spread of leave-one-record-out fits (the jackknife):
samples within a record are strongly correlated (filtered, 2 ms apart), so textbook OLS intervals
would be far too narrow.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .preprocess import Prepared
from .regressor import FIXED_NAMES, STANDARD_NAMES, BaseParameters, regressor_function

__all__ = ["Normals", "normals", "regressor_rows", "RegressionFit", "fit_regression", "realize", "INERTIAL", "MIN_MASS"]

#: Standard parameters every structure fits (the rigid links).
INERTIAL: tuple[str, ...] = ("m1", "h1", "I1", "m2", "h2", "I2")

#: Smallest mass a fit may return [kg].
MIN_MASS = 1e-3

#: Weight of the prior term relative to a unit-variance data term: tiny, except on the masses, which
#: the motion cannot see apart from their combinations (so pinning them biases nothing it can see).
PRIOR_WEIGHT = 1e-6
MASS_PRIOR_WEIGHT = 1e-2


@dataclass(frozen=True)
class Normals:
    """One record's regression data in normal-equation form (joint-weighted later).

    Attributes
    ----------
    A : numpy.ndarray, shape (2, 13, 13)
        Per joint ``Y_j^T Y_j`` over the usable samples.
    c : numpy.ndarray, shape (2, 13)
        Per joint ``Y_j^T tau_j``.
    s : numpy.ndarray, shape (2,)
        Per joint ``tau_j^T tau_j``.
    n : int
        Usable samples.
    """

    A: np.ndarray
    c: np.ndarray
    s: np.ndarray
    n: int

    def __add__(self, other: Normals) -> Normals:
        return Normals(self.A + other.A, self.c + other.c, self.s + other.s, self.n + other.n)

    def rms(self, pi: np.ndarray) -> np.ndarray:
        """Torque residual RMS per joint at standard parameters ``pi`` (all 13) [N.m].

        Parameters
        ----------
        pi : numpy.ndarray, shape (13,)
            Values of :data:`STANDARD_NAMES`.

        Returns
        -------
        numpy.ndarray, shape (2,)
            RMS of ``tau_j - Y_j pi`` over the samples.
        """
        sq = np.einsum("i,jik,k->j", pi, self.A, pi) - 2 * self.c @ pi + self.s
        return np.sqrt(np.maximum(sq, 0.0) / self.n)


def regressor_rows(prep: Prepared, fixed: Mapping[str, float]) -> np.ndarray:
    """Regressor of every usable sample.

    Parameters
    ----------
    prep : Prepared
        A prepared record.
    fixed : mapping of str to float
        Values of :data:`FIXED_NAMES`.

    Returns
    -------
    numpy.ndarray, shape (n_use, 2, 13)
        ``Y`` per sample.
    """
    idx = np.flatnonzero(prep.use)
    n = idx.size
    fx = np.tile([float(fixed[k]) for k in FIXED_NAMES], (n, 1)).T
    Y = np.asarray(regressor_function().map(n)(prep.q[idx].T, prep.qd[idx].T, prep.qdd[idx].T, fx))
    return Y.reshape(2, n, len(STANDARD_NAMES)).transpose(1, 0, 2)


def normals(prep: Prepared, fixed: Mapping[str, float]) -> Normals:
    """The normal equations of one prepared record.

    Parameters
    ----------
    prep : Prepared
        A prepared record.
    fixed : mapping of str to float
        Values of :data:`FIXED_NAMES`.

    Returns
    -------
    Normals
        Its regression data.
    """
    Y = regressor_rows(prep, fixed)
    tau = prep.tau_filtered[prep.use]
    return Normals(
        A=np.einsum("nji,njk->jik", Y, Y), c=np.einsum("nji,nj->ji", Y, tau), s=np.einsum("nj,nj->j", tau, tau), n=tau.shape[0]
    )


@dataclass(frozen=True)
class RegressionFit:
    """A consistent regression fit.

    Attributes
    ----------
    pi : dict of str to float
        All :data:`STANDARD_NAMES` (those outside the structure zero).
    structure : tuple of str
        The free parameters.
    rms : numpy.ndarray, shape (2,)
        Torque residual RMS per joint on the fitted data [N.m].
    weights : numpy.ndarray, shape (2,)
        Joint weights used (inverse residual variances of an unweighted first pass) [1/(N.m)^2].
    """

    pi: dict[str, float]
    structure: tuple[str, ...]
    rms: np.ndarray
    weights: np.ndarray

    def vector(self) -> np.ndarray:
        """The values of :data:`STANDARD_NAMES` in order.

        Returns
        -------
        numpy.ndarray, shape (13,)
            Standard parameters.
        """
        return np.array([self.pi[n] for n in STANDARD_NAMES])


def consistency_constraints(x: ca.SX, free: Sequence[str]) -> tuple[ca.SX, np.ndarray, np.ndarray]:
    """Physical-consistency constraints and bounds of a structure's free standard parameters.

    Parameters
    ----------
    x : casadi.SX, shape (len(free),)
        The free parameters (unscaled).
    free : sequence of str
        Their names.

    Returns
    -------
    g : casadi.SX
        ``m_i I_i - h_i^2`` for both links (must be >= 0).
    lbx, ubx : numpy.ndarray
        Bounds: masses >= :data:`MIN_MASS`, inertias, rotor inertia and friction >= 0.
    """
    v = dict(zip(free, ca.vertsplit(x), strict=True))
    g = ca.vertcat(v["m1"] * v["I1"] - v["h1"] ** 2, v["m2"] * v["I2"] - v["h2"] ** 2)
    lower = {"m1": MIN_MASS, "m2": MIN_MASS, "I1": 0.0, "I2": 0.0, "Ir": 0.0, "b1": 0.0, "b2": 0.0, "cf1": 0.0, "cf2": 0.0}
    lbx = np.array([lower.get(n, -np.inf) for n in free])
    return g, lbx, np.full(len(free), np.inf)


def prior_scale(prior: Mapping[str, float], free: Sequence[str]) -> np.ndarray:
    """Scale of each free parameter: its prior's magnitude, floored per kind.

    Parameters
    ----------
    prior : mapping of str to float
        Prior standard parameters.
    free : sequence of str
        Names.

    Returns
    -------
    numpy.ndarray
        Positive scales in the parameters' units.
    """
    floor = {"Ir": 1e-5, "o1": 0.01, "o2": 0.01}
    return np.array([max(abs(float(prior[n])), floor.get(n, 1e-3)) for n in free])


def prior_weights(free: Sequence[str]) -> np.ndarray:
    """Weights of the prior term per free parameter (scaled units).

    Parameters
    ----------
    free : sequence of str
        Names.

    Returns
    -------
    numpy.ndarray
        :data:`MASS_PRIOR_WEIGHT` for ``m1, m2``, :data:`PRIOR_WEIGHT` for the rest.
    """
    return np.array([MASS_PRIOR_WEIGHT if n in ("m1", "m2") else PRIOR_WEIGHT for n in free])


def fit_regression(
    data: Normals | Sequence[Normals], structure: Sequence[str], prior: Mapping[str, float], weights: np.ndarray | None = None
) -> RegressionFit:
    """Fit a structure's free standard parameters, physically consistent (see the module docstring).

    Parameters
    ----------
    data : Normals or sequence of Normals
        The records to fit (summed).
    structure : sequence of str
        Free standard parameters; must include :data:`INERTIAL`.
    prior : mapping of str to float
        Prior values of :data:`STANDARD_NAMES` (start and the tiny pinning term).
    weights : numpy.ndarray, shape (2,), optional
        Joint weights; default: inverse residual variances of an unweighted first pass.

    Returns
    -------
    RegressionFit
        The fit.

    Raises
    ------
    ValueError
        A structure without the rigid links' parameters or with unknown names.
    RuntimeError
        IPOPT failed.
    """
    total = data if isinstance(data, Normals) else sum(data[1:], start=data[0])
    free = tuple(n for n in STANDARD_NAMES if n in structure)
    unknown = sorted(set(structure) - set(STANDARD_NAMES))
    if unknown or not set(INERTIAL) <= set(free):
        raise ValueError(
            f"structure must contain {list(INERTIAL)} and only names of {list(STANDARD_NAMES)}; got {list(structure)}"
        )
    if weights is None:
        first = fit_regression(total, free, prior, weights=np.ones(2))
        weights = 1.0 / np.maximum(first.rms, 1e-9) ** 2
    idx = [STANDARD_NAMES.index(n) for n in free]
    A = sum(weights[j] * total.A[j][np.ix_(idx, idx)] for j in range(2)) / total.n
    c = sum(weights[j] * total.c[j][idx] for j in range(2)) / total.n
    s = float(weights @ total.s) / total.n
    scale = prior_scale(prior, free)
    x0 = np.array([float(prior[n]) for n in free])
    z = ca.SX.sym("z", len(free))  # scaled parameters, x = scale * z
    x = scale * z
    f = ca.dot(x, ca.DM(A) @ x) - 2 * ca.dot(ca.DM(c), x) + s + ca.dot(prior_weights(free), (z - x0 / scale) ** 2)
    g, lbx, ubx = consistency_constraints(x, free)
    solver = ca.nlpsol(
        "regression",
        "ipopt",
        {"x": z, "f": f, "g": g},
        {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": 1e-12},
    )
    start = np.clip(x0, lbx, ubx) / scale
    sol = solver(x0=start, lbx=lbx / scale, ubx=ubx / scale, lbg=0.0, ubg=np.inf)
    if not solver.stats()["success"]:
        raise RuntimeError(f"regression fit failed: IPOPT {solver.stats()['return_status']}")
    xs = scale * np.asarray(sol["x"]).ravel()
    pi = dict.fromkeys(STANDARD_NAMES, 0.0)
    pi.update(zip(free, xs.tolist(), strict=True))
    vec = np.array([pi[n] for n in STANDARD_NAMES])
    return RegressionFit(pi=pi, structure=free, rms=total.rms(vec), weights=np.asarray(weights, dtype=float))


def realize(base: BaseParameters, beta: np.ndarray, prior: Mapping[str, float], structure: Sequence[str]) -> dict[str, float]:
    """Physically consistent standard parameters with given base-parameter values, nearest the prior.

    The motion fixes only the base parameters; this picks the masses (and so the split of the
    combinations) nearest the prior subject to the consistency constraints.

    Parameters
    ----------
    base : BaseParameters
        The combinations.
    beta : numpy.ndarray, shape (n_base,)
        Their values.
    prior : mapping of str to float
        Prior standard parameters.
    structure : sequence of str
        Free standard parameters.

    Returns
    -------
    dict of str to float
        All :data:`STANDARD_NAMES` (outside the structure zero).

    Raises
    ------
    RuntimeError
        No consistent parameters reproduce ``beta`` (the data ask for a non-physical model).
    """
    free = tuple(n for n in STANDARD_NAMES if n in structure)
    scale = prior_scale(prior, free)
    z = ca.SX.sym("z", len(free))
    x = scale * z
    v = dict(zip(free, ca.vertsplit(x), strict=True))
    ind = ca.vertcat(*[v[n] for n in base.independent])
    dep = ca.vertcat(*[v[n] for n in base.dependent]) if base.dependent else ca.SX(0, 1)
    combo = ind + (ca.DM(base.K) @ dep if base.dependent else 0)
    x0 = np.array([float(prior[n]) for n in free])
    f = ca.sumsqr(z - x0 / scale)
    g_phys, lbx, ubx = consistency_constraints(x, free)
    g = ca.vertcat(g_phys, combo - ca.DM(beta))
    solver = ca.nlpsol(
        "realize",
        "ipopt",
        {"x": z, "f": f, "g": g},
        {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": 1e-12},
    )
    nb = len(base.independent)
    sol = solver(
        x0=np.clip(x0, lbx, ubx) / scale, lbx=lbx / scale, ubx=ubx / scale,
        lbg=np.r_[0.0, 0.0, np.zeros(nb)], ubg=np.r_[np.inf, np.inf, np.zeros(nb)],
    )  # fmt: skip
    if not solver.stats()["success"]:
        raise RuntimeError(
            f"no physically consistent parameters reproduce the fitted base parameters "
            f"{dict(zip(base.names, beta.tolist(), strict=True))}: "
            f"IPOPT {solver.stats()['return_status']}"
        )
    pi = dict.fromkeys(STANDARD_NAMES, 0.0)
    # IPOPT honours bounds to its tolerance (a friction of -1e-57): snap onto them.
    pi.update(zip(free, np.maximum(scale * np.asarray(sol["x"]).ravel(), lbx).tolist(), strict=True))
    # Likewise onto m I >= h^2: a link fitted as a point mass came out 1e-7 below it, which the plant file refuses.
    for i in ("1", "2"):
        if f"I{i}" in free:
            pi[f"I{i}"] = max(pi[f"I{i}"], pi[f"h{i}"] ** 2 / pi[f"m{i}"])
    return pi

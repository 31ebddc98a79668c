"""Which model the NMPC predicts an elastic plant with, and the plant state on that model's slow manifold.

The levels are the planning rule's (:func:`pendulab.control.swingup.rule.planning_rule`),
cheapest first:

``rigid``
    The rigid point-mass counterpart, links at the springs' rest lengths (4 states).
``rigid+quasi-static``
    The same 4-state rigid model, but each prediction stage has the link lengths
    the springs take quasi-statically along the reference, r*(theta_ref, omega_ref, u_ref)
    (:func:`pendulab.model.quasistatic.quasi_static_lengths`; after the reference: the
    upright static lengths). The lengths are NLP parameters, so the problem has the
    rigid problem's size.
``elastic``
    The elastic model itself (8 states, RK4 substeps resolving the spring modes).

``planning="auto"`` picks the cheapest level whose error predicted by the rule
(``rigid``: ``C_RIGID eps``, ``rigid+quasi-static``: ``C_QUASI_STATIC eps^2``,
``eps = w_p / w_s``) is within ``prediction_tolerance``. That tolerance is a relative error
of the prediction over the horizon, which the feedback corrects every sample: much looser than
the 1e-3 relative defect a plan run open loop must meet. Its default, 0.2, is *measured*
(``benchmarks/results/nmpc.md``): on the stiff tasks (predicted rigid 0.40,
quasi-static 0.15) the quasi-static level swings up through the elastic FMU; on the soft
ones (predicted 2.0 and 3.9) the reduced levels fail and the elastic model is needed.

A reduced (rigid) prediction needs a rigid state from the elastic measurement.
Dropping the spring states (``rigid_state``) keeps the link rates with their fast
part: a length oscillation r(t) makes omega oscillate with it (the link's angular
momentum is what stays slow), the feedback acts on that oscillation at the spring
frequency and excites the undamped springs further (measured: the QP fails and the
pendulum falls). The map used here is the projection on the slow manifold that keeps
the generalized angular momenta: ``omega_slow = M_rigid(theta, l)^-1 p_theta`` with
``p_theta = M_elastic[theta rows](theta, r) (omega, v)`` and ``l`` the prediction model's
link lengths at that state (rest lengths, or quasi-static lengths). On a quasi-static
state (r = r*, v = 0) it returns the angles and rates unchanged (``M_rigid(theta, r*)`` is
the angle block of ``M_elastic``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np

from ...model.counterpart import rigid_counterpart
from ...model.functions import model_functions
from ...model.model import Model
from ...model.params import ElasticParams, RigidParams, ordered_values

__all__ = ["PLANNING", "STATE_MAPS", "PredictionChoice", "choose_prediction", "prediction_model", "SlowStateMap", "LENGTH_PARAMS"]

#: Prediction models accepted by ``NMPCOptions.planning`` (``model`` = ``elastic``: the plant's own model).
PLANNING: tuple[str, ...] = ("auto", "model", "elastic", "rigid", "quasi-static")
#: Elastic state -> rigid state maps accepted by ``NMPCOptions.state_map`` (see :class:`SlowStateMap`).
STATE_MAPS: tuple[str, ...] = ("average", "momentum", "project")
#: Rigid parameters that carry a prediction stage's link lengths (point masses: lc = L).
LENGTH_PARAMS: tuple[str, ...] = ("L1", "L2", "lc1", "lc2")
_LEVEL_OF = {"model": "elastic", "elastic": "elastic", "rigid": "rigid", "quasi-static": "rigid+quasi-static"}


@dataclass(frozen=True)
class PredictionChoice:
    """The prediction level of an NMPC and why.

    Attributes
    ----------
    requested : str
        ``NMPCOptions.planning``.
    level : str
        ``rigid``, ``rigid+quasi-static`` or ``elastic`` (``rigid`` for a rigid plant: its own model).
    predicted : dict of str to float
        The planning rule's predicted relative error of each level (empty for a rigid plant).
    tolerance : float
        Relative prediction error the choice allows.
    reason : str
        One line.
    """

    requested: str
    level: str
    predicted: dict[str, float]
    tolerance: float
    reason: str

    @property
    def predicted_error(self) -> float:
        """Predicted relative error of the chosen level (0 for the plant's own model)."""
        return float(self.predicted.get(self.level, 0.0))


def choose_prediction(model: Model, planning: str, tolerance: float) -> PredictionChoice:
    """Apply the planning rule's levels to the NMPC's prediction model.

    Parameters
    ----------
    model : Model
        Plant model.
    planning : {"auto", "model", "elastic", "rigid", "quasi-static"}
        ``auto``: the cheapest level predicted within ``tolerance``; the others force a level.
    tolerance : float
        Relative prediction error the feedback tolerates (dimensionless, > 0).

    Returns
    -------
    PredictionChoice

    Raises
    ------
    ValueError
        Unknown ``planning``.
    """
    from ..swingup.rule import LEVELS, planning_rule

    if planning not in PLANNING:
        raise ValueError(f"planning must be one of {list(PLANNING)}, got {planning!r}")
    if model.kind != "elastic":
        return PredictionChoice(planning, "rigid", {}, tolerance, "rigid plant: predicted with its own model")
    d = planning_rule(model, tolerance, "auto")
    pred = {k: float(v) for k, v in d.predicted.items()}
    errs = ", ".join(f"{k} {pred[k]:.2g}" for k in LEVELS)
    head = f"springs {d.separation:.3g}x faster than the pendulum (predicted errors: {errs}; tolerance {tolerance:.2g})"
    if planning != "auto":
        return PredictionChoice(planning, _LEVEL_OF[planning], pred, tolerance, f"requested {planning!r}; {head}")
    level = d.chosen
    why = "no reduced model within tolerance" if level == "elastic" else "cheapest level within tolerance"
    return PredictionChoice(planning, level, pred, tolerance, f"{why}: {head}")


def prediction_model(model: Model, level: str) -> Model:
    """The model the NMPC predicts with at ``level``.

    Parameters
    ----------
    model : Model
        Plant model.
    level : {"rigid", "rigid+quasi-static", "elastic"}
        Prediction level.

    Returns
    -------
    Model
        ``model`` itself (rigid plant or ``elastic``), its rigid counterpart (``rigid``), or the
        counterpart with the upright static link lengths (``rigid+quasi-static``: the stages
        override them with the reference's quasi-static lengths; the terminal LQR uses these).
    """
    if model.kind != "elastic" or level == "elastic":
        return model
    plan = rigid_counterpart(model)
    if level == "rigid":
        return plan
    l1, l2 = upright_lengths(model)
    return replace_lengths(plan, l1, l2)


def upright_lengths(model: Model) -> tuple[float, float]:
    """Spring lengths [m] of the elastic upright equilibrium (compressed by the weight above)."""
    from ..feedback import upright_state

    x = upright_state(model)
    return float(x[2]), float(x[3])


def replace_lengths(plan: Model, l1: float, l2: float) -> Model:
    """Rigid point-mass model ``plan`` with link lengths ``l1, l2`` [m] (and ``lc = l``)."""
    return plan.with_params(L1=l1, L2=l2, lc1=l1, lc2=l2)


@cache
def _map_function(quasi_static: bool) -> ca.Function:
    """(x_elastic, u, p_elastic) -> rigid slow state; lengths: rest lengths or quasi-static (Newton)."""
    fe, fr = model_functions("elastic"), model_functions("rigid")
    npe = fe["rhs"].size1_in(2)
    x, u, p = ca.SX.sym("x", 8), ca.SX.sym("u", 2), ca.SX.sym("p", npe)
    theta, omega = x[0:2], x[4:6]
    if quasi_static:
        # Lengths with zero radial acceleration at (theta, omega measured, v = 0): the quasi-static lengths.
        r = ca.SX.sym("r", 2)
        acc = fe["rhs"](ca.vertcat(theta, r, omega, ca.SX.zeros(2)), u, p)[6:8]
        G = ca.Function("qs", [r, ca.vertcat(theta, omega, u, p)], [acc])
        rf = ca.rootfinder("qs_map", "newton", G, {"abstol": 1e-12, "max_iter": 20, "error_on_fail": False})
        xm, um, pm = ca.MX.sym("x", 8), ca.MX.sym("u", 2), ca.MX.sym("p", npe)
        lengths = rf(xm[2:4], ca.vertcat(xm[0:2], xm[4:6], um, pm))
        inner = _momentum_map(fe, fr)
        return ca.Function("slow_map", [xm, um, pm], [inner(xm, lengths, pm)], ["x", "u", "p"], ["x_slow"])
    lengths = p[2:4]  # rest lengths L1, L2
    inner = _momentum_map(fe, fr)
    return ca.Function("slow_map", [x, u, p], [inner(x, lengths, p)], ["x", "u", "p"], ["x_slow"])


def _momentum_map(fe: dict, fr: dict) -> ca.Function:
    """(x_elastic, lengths, p_elastic) -> (theta, M_rigid(theta, lengths)^-1 p_theta)."""
    x, lengths, p = ca.SX.sym("x", 8), ca.SX.sym("l", 2), ca.SX.sym("p", fe["rhs"].size1_in(2))
    Me = fe["mass_matrix"](x, p)  # over (theta1, theta2, r1, r2)
    p_theta = Me[0:2, :] @ ca.vertcat(x[4:6], x[6:8])
    # The rigid point-mass counterpart at the given lengths (by name: the vectors' order is the classes').
    e = dict(zip(ElasticParams.names(), ca.vertsplit(p), strict=True))
    rigid = {"m1": e["m1"], "m2": e["m2"], "L1": lengths[0], "L2": lengths[1], "g": e["g"], "b1": e["b1"], "b2": e["b2"],
             "lc1": lengths[0], "lc2": lengths[1]}  # fmt: skip
    pr = ca.vertcat(*ordered_values(RigidParams, rigid))
    Mr = fr["mass_matrix"](ca.vertcat(x[0:2], ca.SX.zeros(2)), pr)
    omega = ca.solve(Mr, p_theta)
    return ca.Function("momentum_map", [x, lengths, p], [ca.vertcat(x[0:2], omega)])


@cache
def _average_function(quasi_static: bool, periods: tuple[float, ...], steps: int) -> ca.Function:
    """(x_elastic, u, p_elastic) -> the slow map averaged over a window centred now (elastic model, RK4).

    The window is the convolution of boxcars of lengths ``periods`` (one per spring mode, each removes its
    mode exactly); the states inside it come from integrating the elastic model backward and forward
    from ``x`` with ``steps`` RK4 steps per shortest period, torques held.
    """
    fe = model_functions("elastic")["rhs"]
    npe = fe.size1_in(2)
    x, u, p = ca.MX.sym("x", 8), ca.MX.sym("u", 2), ca.MX.sym("p", npe)
    dt = min(periods) / steps
    kernel = np.ones(1)
    for T in periods:
        kernel = np.convolve(kernel, np.ones(max(1, round(T / dt))))
    kernel /= kernel.sum()
    half = (len(kernel) - 1) // 2
    xs_, us_, ps_ = ca.SX.sym("x", 8), ca.SX.sym("u", 2), ca.SX.sym("p", npe)

    def rk4(h: float) -> ca.Function:
        k1 = fe(xs_, us_, ps_)
        k2 = fe(xs_ + 0.5 * h * k1, us_, ps_)
        k3 = fe(xs_ + 0.5 * h * k2, us_, ps_)
        k4 = fe(xs_ + h * k3, us_, ps_)
        return ca.Function("rk4", [xs_, us_, ps_], [xs_ + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)])

    fwd, bwd = rk4(dt), rk4(-dt)
    smap = _map_function(quasi_static)
    pts = [x]
    xb, xf = x, x
    back, ahead = [], []
    for _ in range(half):
        xb, xf = bwd(xb, u, p), fwd(xf, u, p)
        back.append(xb)
        ahead.append(xf)
    pts = back[::-1] + [x] + ahead
    if len(kernel) % 2 == 0:  # even kernel: one more point ahead
        pts.append(fwd(xf, u, p))
    slow = sum(float(w) * smap(xk, u, p) for w, xk in zip(kernel, pts, strict=True))
    return ca.Function("slow_average", [x, u, p], [slow], ["x", "u", "p"], ["x_slow"])


@dataclass(frozen=True)
class SlowStateMap:
    """Elastic plant state -> rigid state on the slow manifold (angles; rates that keep the angular momenta).

    Attributes
    ----------
    model : Model
        The elastic plant model.
    quasi_static : bool
        Rigid link lengths of the map: the quasi-static lengths at the measured angles and rates
        (``rigid+quasi-static`` level) or the rest lengths (``rigid`` level).
    average : tuple of float
        Spring periods [s]: when given, the map is averaged over a window centred on the
        measurement (a boxcar per period, convolved), the states in it predicted with the elastic
        model; that removes what of the spring oscillation the instantaneous map leaves.
    """

    model: Model
    quasi_static: bool = True
    average: tuple[float, ...] = ()

    def __call__(self, x: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """Rigid state (theta1, theta2, omega1, omega2) of the elastic state ``x`` under torques ``u``.

        Parameters
        ----------
        x : ndarray, shape (8,)
            Elastic state.
        u : ndarray, shape (2,), optional
            Torques (tau1, tau2) [N.m] held now (they load the springs); default zero.

        Returns
        -------
        ndarray, shape (4,)
            Angles [rad] and slow angular rates [rad/s]. When the averaging window's prediction
            diverges (a spring near collapse), the instantaneous momentum map at rest lengths.

        Raises
        ------
        ValueError
            No finite image (a singular mass matrix).
        """
        uu = np.zeros(2) if u is None else u
        fn = _average_function(self.quasi_static, self.average, 8) if self.average else _map_function(self.quasi_static)
        out = np.asarray(fn(x, uu, self.model.p), dtype=float).ravel()
        if self.average and not np.all(np.isfinite(out)):
            # The window's prediction diverged (a spring driven near collapse): the instantaneous map is algebraic.
            out = np.asarray(_map_function(False)(x, uu, self.model.p), dtype=float).ravel()
        if not np.all(np.isfinite(out)) or math.isnan(out[2]):
            raise ValueError(f"x must be an elastic state with a slow-manifold image, got {x!r}")
        return out

"""Sampled-data controllers: the protocol a co-simulation master (or the native loop) drives.

A :class:`SampledController` is called once per sample with the plant state
and returns the torques it drives, which are then held constant until the next
sample (zero-order hold). The same object therefore runs natively through
``pendulab.simulate(..., dt=sample_time, u=as_feedback(controller, model))`` and
through an FMU with :func:`pendulab.cosim.master`.

Three controllers are provided:

* :class:`LinearStateFeedback` (from :func:`lqr_balance`): LQR balance about
  the upright equilibrium, either a fixed continuous-time LQR gain applied with
  a zero-order hold (``design="continuous"``, the classical sampled-data study)
  or a discrete LQR gain designed on the exact ZOH discretization at the sample
  time (``design="discrete"``);
* :class:`EnergySwingUp` (from :func:`energy_swingup`): energy pumping on
  ``tau1`` while ``tau2`` keeps the links aligned, then a switch to LQR balance;
* ``TVLQRTracker`` (module ``tracking_sampled``): tracks any reference
  ``(t, x_ref, u_ref)`` with time-varying gains, then hands over to a final
  controller.

The gains are designed by :func:`pendulab.control.lqr.lqr_balance` and
:func:`pendulab.control.lqr.discrete_tvlqr` on the exact Jacobians.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .._checks import positive_float
from ..analysis.equilibria import equilibrium
from ..analysis.linearize import linearize
from ..model.model import ACTUATIONS, INPUT_NAMES, Model
from .lqr import actuation_name, wrap_state_error, zoh
from .lqr import lqr_balance as lqr_design

__all__ = [
    "SampledController",
    "LinearStateFeedback",
    "EnergySwingUp",
    "lqr_balance",
    "energy_swingup",
    "upright_state",
    "closed_loop_spectral_radius",
    "as_feedback",
    "full_input",
    "make_controller",
    "CONTROLLERS",
]


@runtime_checkable
class SampledController(Protocol):
    """What a co-simulation master needs from a controller.

    Attributes
    ----------
    sample_time : float
        Sample period [s]; the output is held constant in between.
    input_names : tuple of str
        The plant inputs driven, a subset of ("tau1", "tau2"), in output order.
    """

    sample_time: float
    input_names: tuple[str, ...]

    def reset(self) -> None:
        """Forget internal state (mode switches) before a new run."""

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """Torques [N.m], shape (len(input_names),), from time ``t`` [s] and the plant state ``x``, shape (nx,)."""


# -- helpers -------------------------------------------------------------------------


def upright_state(model: Model) -> np.ndarray:
    """The up-up equilibrium (theta1 = theta2 = pi, at rest), shape (nx,).

    A thin wrapper of ``pendulab.analysis.equilibria.equilibrium(model, "up-up").x``:
    for the elastic model the springs carry the weight above them, so they are
    compressed (r1 = L1 - (m1 + m2) g / k1, r2 = L2 - m2 g / k2).
    """
    return equilibrium(model, "up-up").x.copy()


def _actuated(actuation: str | Sequence[str]) -> tuple[str, ...]:
    return tuple(INPUT_NAMES[i] for i in ACTUATIONS[actuation_name(actuation)])


def _angular_states(model: Model) -> np.ndarray:
    """Mask of the angles and link rates (the states an upright balance gain acts on), shape (nx,)."""
    return np.array([n.startswith(("theta", "omega")) for n in model.state_names])


def _angular_weight(model: Model, Q: Any) -> np.ndarray:
    """Embed a weight on (theta1, theta2, omega1, omega2), shape (4, 4) or (4,), into the full state (zero on r, v).

    At the aligned upright equilibrium the spring (radial) coordinates of the
    elastic model decouple from the angles to first order, so their modes are
    uncontrollable by the torques and get no weight (and no gain).
    """
    sel = np.flatnonzero(_angular_states(model))
    Qa = np.diag([10.0, 10.0, 1.0, 1.0]) if Q is None else np.atleast_2d(np.asarray(Q, dtype=float))
    if Qa.shape == (1, len(sel)):
        Qa = np.diag(Qa[0])
    if Qa.shape != (len(sel), len(sel)):
        raise ValueError(f"Q must have shape ({len(sel)}, {len(sel)}) or ({len(sel)},), got {np.shape(Q)}")
    Qf = np.zeros((model.nx, model.nx))
    Qf[np.ix_(sel, sel)] = Qa
    return Qf


# -- controllers -----------------------------------------------------------------


@dataclass
class LinearStateFeedback:
    """``u = u_eq - K (x - x_eq)`` (angles wrapped), optionally saturated.

    Attributes
    ----------
    model : Model
        Plant the gain was designed for (state order, angle wrapping).
    K : ndarray, shape (len(input_names), nx)
        Gain [N.m per state unit].
    x_eq : ndarray, shape (nx,)
        Operating point.
    u_eq : ndarray, shape (len(input_names),)
        Feed-forward torque [N.m].
    sample_time : float
        [s].
    input_names : tuple of str
    u_max : float or None
        Symmetric torque limit [N.m].
    P : ndarray or None
        Riccati solution (cost-to-go matrix) of the design, shape (nx, nx).
    design : str
        "continuous" or "discrete".
    """

    model: Model
    K: np.ndarray
    x_eq: np.ndarray
    u_eq: np.ndarray
    sample_time: float
    input_names: tuple[str, ...]
    u_max: float | None = None
    P: np.ndarray | None = None
    design: str = "continuous"

    def reset(self) -> None:
        """Stateless: nothing to forget."""

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        u = self.u_eq - self.K @ wrap_state_error(np.asarray(x, dtype=float) - self.x_eq, self.model.state_names)
        return u if self.u_max is None else np.clip(u, -self.u_max, self.u_max)

    def cost(self, x: np.ndarray) -> float:
        """Quadratic cost-to-go ``e' P e`` of the deviation from ``x_eq``."""
        e = wrap_state_error(np.asarray(x, dtype=float) - self.x_eq, self.model.state_names)
        return float(e @ self.P @ e) if self.P is not None else float(e @ e)


def lqr_balance(
    model: Model,
    sample_time: float,
    *,
    design: str = "continuous",
    Q: Any = None,
    R: Any = None,
    actuation: str | Sequence[str] = "full",
    u_max: float | None = None,
) -> LinearStateFeedback:
    """LQR balance about the upright equilibrium.

    Parameters
    ----------
    model : Model
        Rigid or elastic plant (design model).
    sample_time : float
        Sample period [s].
    design : {"continuous", "discrete"}
        ``"continuous"``: the continuous-time LQR gain, whatever the sample time
        (a fixed design applied with a zero-order hold; it degrades and finally
        destabilizes as the sample time grows). ``"discrete"``: discrete LQR on
        the exact ZOH discretization at ``sample_time`` (re-designed per rate).
    Q : array_like, optional
        State weight on the angular states (theta1, theta2, omega1, omega2),
        shape (4, 4) or (4,); default diag(10, 10, 1, 1).
    R : array_like, optional
        Input weight, shape (m, m) or (m,); default identity.
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        Which torques the controller drives.
    u_max : float, optional
        Torque limit [N.m].

    Returns
    -------
    LinearStateFeedback
    """
    h = positive_float("sample_time", sample_time)
    if design not in ("continuous", "discrete"):
        raise ValueError(f"design must be 'continuous' or 'discrete', got {design!r}")
    names = _actuated(actuation)
    lq = lqr_design(model, names, _angular_weight(model, Q), R, None if design == "continuous" else h)
    return LinearStateFeedback(model, lq.K, lq.x_eq, np.zeros(len(names)), h, names, u_max, lq.P, design)


def closed_loop_spectral_radius(model: Model, K: np.ndarray, h: float, input_names: Sequence[str] = INPUT_NAMES) -> float:
    """Spectral radius of ``Ad - Bd K``: the gain ``K`` applied with a ZOH of period ``h`` to the upright linearization.

    Below 1 the sampled linear closed loop is asymptotically stable. For the
    elastic model only the angular block is used: its spring modes are
    decoupled (and uncontrollable) at the upright equilibrium.
    """
    cols = [INPUT_NAMES.index(n) for n in input_names]
    lin = linearize(model, equilibrium(model, "up-up"))
    sel = _angular_states(model)
    Ad, Bd = zoh(lin.A[np.ix_(sel, sel)], lin.B[np.ix_(sel, cols)], positive_float("h", h))
    return float(np.max(np.abs(np.linalg.eigvals(Ad - Bd @ np.asarray(K)[:, sel]))))


@dataclass
class EnergySwingUp:
    """Energy pumping with ``tau1``, link alignment with ``tau2``, then LQR balance.

    Away from the top, ``tau1 = sat(k_energy (E_up - E) omega1)`` pumps energy
    (power ``tau1 omega1`` has the sign of the energy deficit) and ``tau2 =
    -kp (theta2 - theta1) - kd (omega2 - omega1)`` keeps the pair close to a
    single pendulum. When the LQR cost-to-go falls below ``catch_cost`` the
    controller switches to ``balance`` for good (until :meth:`reset`).
    """

    model: Model
    balance: LinearStateFeedback
    sample_time: float
    k_energy: float = 2.0
    kp: float = 40.0
    kd: float = 6.0
    u_max: float = 20.0
    catch_cost: float = 20.0
    input_names: tuple[str, ...] = INPUT_NAMES
    e_up: float = field(init=False)
    caught_at: float | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        self.e_up = float(self.model.energy(upright_state(self.model)))

    def reset(self) -> None:
        """Back to the pumping mode."""
        self.caught_at = None

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        if self.caught_at is None and self.balance.cost(x) < self.catch_cost:
            self.caught_at = float(t)
        if self.caught_at is not None:
            return np.clip(self.balance(t, x), -self.u_max, self.u_max)
        th1, th2 = x[0], x[1]
        w1, w2 = x[self.model.nq], x[self.model.nq + 1]
        deficit = self.e_up - float(self.model.energy(x))
        # Start from rest: no velocity to pump with, so kick.
        tau1 = self.k_energy * deficit * w1 if abs(w1) > 1e-3 else self.u_max
        rel = (th2 - th1 + np.pi) % (2 * np.pi) - np.pi
        tau2 = -self.kp * rel - self.kd * (w2 - w1)
        return np.clip(np.array([tau1, tau2]), -self.u_max, self.u_max)


def energy_swingup(
    model: Model,
    sample_time: float,
    *,
    k_energy: float = 2.0,
    u_max: float = 20.0,
    catch_cost: float = 20.0,
) -> EnergySwingUp:
    """Energy-pumping swing-up (full actuation) switching to continuous LQR balance.

    Parameters
    ----------
    model : Model
    sample_time : float
        [s].
    k_energy : float
        Pumping gain [N.m / (J rad/s)].
    u_max : float
        Torque limit [N.m].
    catch_cost : float
        Switch to LQR when the LQR cost-to-go ``e' P e`` falls below this.
    """
    h = positive_float("sample_time", sample_time)
    balance = lqr_balance(model, h, u_max=u_max)
    return EnergySwingUp(model, balance, h, k_energy=k_energy, u_max=positive_float("u_max", u_max), catch_cost=catch_cost)


# -- glue -----------------------------------------------------------------------------


def full_input(controller: SampledController, u: np.ndarray) -> np.ndarray:
    """Scatter a controller output into (tau1, tau2), zeros elsewhere, shape (2,)."""
    full = np.zeros(len(INPUT_NAMES))
    for name, value in zip(controller.input_names, np.atleast_1d(u), strict=True):
        full[INPUT_NAMES.index(name)] = value
    return full


def as_feedback(controller: SampledController, model: Model) -> Callable[[float, np.ndarray], np.ndarray]:
    """Wrap a controller (after resetting it) as ``u(t, x) -> (tau1, tau2)`` for :func:`pendulab.simulate`.

    Run ``simulate`` with ``dt = controller.sample_time`` so the output grid is
    the sample grid: simulate holds each value over its output step.
    """
    controller.reset()

    def feedback(t: float, x: np.ndarray) -> np.ndarray:
        return full_input(controller, controller(t, x))

    return feedback


#: Names accepted by :func:`make_controller`.
CONTROLLERS: tuple[str, ...] = ("lqr", "swingup", "tvlqr")


def make_controller(
    name: str,
    model: Model,
    sample_time: float,
    *,
    u_max: float = 20.0,
    t_ref: float = 6.0,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    actuation: str = "full",
) -> tuple[SampledController, np.ndarray]:
    """A named controller for ``model`` and its natural start state.

    Parameters
    ----------
    name : {"lqr", "swingup", "tvlqr"}
        ``lqr``: continuous LQR balance (start 0.1 rad off upright);
        ``swingup``: energy pumping + LQR catch (start hanging, theta1 = 0.1);
        ``tvlqr``: discrete TVLQR tracking of ``reference`` (default: the native
        energy swing-up, :func:`swingup_reference`, ``t_ref`` seconds) then
        discrete LQR balance; starts at the reference's first state.
    model : Model
        Design model (e.g. ``FmuInfo.model()`` for an FMU's parameters).
    sample_time : float
        [s].
    u_max : float
        Torque limit [N.m] (swing-up and tracking).
    t_ref : float
        Horizon [s] of the default ``tvlqr`` reference.
    reference : (t, x, u), optional
        Reference to track with ``tvlqr`` (any grid; e.g. an optimized swing-up or
        :func:`load_reference_csv`).
    actuation : {"full", "pendubot", "acrobot"}
        Driven torques of ``lqr`` and ``tvlqr`` (``swingup`` needs both).

    Returns
    -------
    controller : SampledController
    x0 : ndarray, shape (nx,)
    """
    h = positive_float("sample_time", sample_time)
    if name == "lqr":
        x0 = upright_state(model)
        x0[0] += 0.1
        return lqr_balance(model, h, actuation=actuation), x0
    if name == "swingup":
        if _actuated(actuation) != INPUT_NAMES:
            raise ValueError(f"the energy swing-up drives both torques; actuation must be 'full', got {actuation!r}")
        return energy_swingup(model, h, u_max=u_max), model.state(theta1=0.1)
    if name == "tvlqr":
        from .tracking_sampled import swingup_reference, tvlqr_tracker

        if reference is None:
            reference = swingup_reference(model, h, round(positive_float("t_ref", t_ref) / h) * h, u_max=u_max)
        tracker = tvlqr_tracker(model, *reference, h, u_max=u_max, actuation=actuation)
        return tracker, tracker.x_ref[0].copy()
    raise ValueError(f"controller must be one of {list(CONTROLLERS)}, got {name!r}")

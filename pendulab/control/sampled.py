"""Sampled-data controllers: the protocol a co-simulation master (or the native loop) drives.

A :class:`SampledController` is called once per sample with the plant state
and returns the torques it drives, which are then held constant until the next
sample (zero-order hold). The same object therefore runs natively through
``pendulab.simulate(..., dt=sample_time, u=as_feedback(controller, model))`` and
through an FMU with :func:`pendulab.fmu.cosim`.

Three controllers are provided:

* :class:`LinearStateFeedback` (from :func:`lqr_balance`): LQR balance about
  the upright equilibrium, either a fixed continuous-time LQR gain applied with
  a zero-order hold (``design="continuous"``, the classical sampled-data study)
  or a discrete LQR gain designed on the exact ZOH discretization at the sample
  time (``design="discrete"``);
* :class:`EnergySwingUp` (from :func:`energy_swingup`): energy pumping on
  ``tau1`` while ``tau2`` keeps the links aligned, then a switch to LQR balance;
* :class:`TVLQRTracker`: tracks any reference ``(t, x_ref, u_ref)`` with
  time-varying gains (e.g. :func:`discrete_tvlqr`, or those of an optimized
  swing-up), then hands over to a final controller.

The linear algebra uses the exact Jacobians ``model.functions["jac_rhs"]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.linalg as sla

from ..model.model import ACTUATIONS, INPUT_NAMES, Model

__all__ = [
    "SampledController",
    "LinearStateFeedback",
    "EnergySwingUp",
    "TVLQRTracker",
    "lqr_balance",
    "energy_swingup",
    "discrete_tvlqr",
    "swingup_reference",
    "upright_state",
    "linearize",
    "zoh",
    "closed_loop_spectral_radius",
    "angle_error",
    "as_feedback",
    "full_input",
    "make_controller",
    "CONTROLLERS",
    "resample_reference",
    "tvlqr_tracker",
    "load_reference_csv",
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


# -- linear algebra helpers ----------------------------------------------------


def _positive(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a positive number, got {value!r}") from exc
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return v


def _angle_mask(model: Model) -> np.ndarray:
    return np.array([n.startswith("theta") for n in model.state_names])


def angle_error(model: Model, x: np.ndarray, x_ref: np.ndarray) -> np.ndarray:
    """``x - x_ref`` with the angle entries wrapped to [-pi, pi), shape like ``x``."""
    e = np.asarray(x, dtype=float) - np.asarray(x_ref, dtype=float)
    mask = _angle_mask(model)
    e[..., mask] = (e[..., mask] + np.pi) % (2.0 * np.pi) - np.pi
    return e


def upright_state(model: Model) -> np.ndarray:
    """The up-up equilibrium (theta1 = theta2 = pi, at rest), shape (nx,).

    For the elastic model the springs carry the weight above them, so they are
    compressed: r1 = L1 - (m1 + m2) g / k1, r2 = L2 - m2 g / k2 (checked: the
    state derivative vanishes there).
    """
    x = np.zeros(model.nx)
    x[:2] = np.pi
    if model.kind == "elastic":
        pr = model.params
        x[2] = pr.L1 - (pr.m1 + pr.m2) * pr.g / pr.k1
        x[3] = pr.L2 - pr.m2 * pr.g / pr.k2
        if min(x[2], x[3]) <= 0.0:
            raise ValueError(
                f"model: springs too soft to hold the upright position (k1={pr.k1}, k2={pr.k2} N/m give "
                f"r1={x[2]:.3g}, r2={x[3]:.3g} m); expected positive upright spring lengths"
            )
    return x


def linearize(model: Model, x: np.ndarray, u: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exact Jacobians (A, B) of the state derivative at (x, u): shapes (nx, nx), (nx, 2)."""
    u = np.zeros(model.nu) if u is None else np.asarray(u, dtype=float)
    A, B = model.functions["jac_rhs"](x, u, model.p)
    return np.asarray(A), np.asarray(B)


def zoh(A: np.ndarray, B: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretization: ``Ad = e^{Ah}``, ``Bd = int_0^h e^{As} ds B``."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    E = sla.expm(M * h)
    return E[:n, :n], E[:n, n:]


def _design_states(model: Model) -> np.ndarray:
    """States the balance gain acts on.

    At the aligned upright equilibrium the spring (radial) coordinates of the
    elastic model decouple from the angles to first order, so their modes are
    uncontrollable by the torques; the design then uses the angular block only
    (zero gain on r, v).
    """
    return np.array([n.startswith(("theta", "omega")) for n in model.state_names])


def _actuated(actuation: str | Sequence[str]) -> tuple[str, ...]:
    if isinstance(actuation, str):
        if actuation not in ACTUATIONS:
            raise ValueError(f"actuation must be one of {list(ACTUATIONS)} or input names, got {actuation!r}")
        return tuple(INPUT_NAMES[i] for i in ACTUATIONS[actuation])
    names = tuple(actuation)
    if not names or any(n not in INPUT_NAMES for n in names):
        raise ValueError(f"actuation input names must be a non-empty subset of {list(INPUT_NAMES)}, got {names!r}")
    return names


def _weights(Q: Any, R: Any, n: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    Qm = np.eye(n) if Q is None else np.atleast_2d(np.asarray(Q, dtype=float))
    Rm = np.eye(m) if R is None else np.atleast_2d(np.asarray(R, dtype=float))
    if Qm.shape == (1, n):
        Qm = np.diag(Qm[0])
    if Rm.shape == (1, m) and m > 1:
        Rm = np.diag(Rm[0])
    if Qm.shape != (n, n):
        raise ValueError(f"Q must have shape ({n}, {n}) or ({n},), got {np.shape(Q)}")
    if Rm.shape != (m, m):
        raise ValueError(f"R must have shape ({m}, {m}) or ({m},), got {np.shape(R)}")
    return Qm, Rm


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
        u = self.u_eq - self.K @ angle_error(self.model, x, self.x_eq)
        return u if self.u_max is None else np.clip(u, -self.u_max, self.u_max)

    def cost(self, x: np.ndarray) -> float:
        """Quadratic cost-to-go ``e' P e`` of the deviation from ``x_eq``."""
        e = angle_error(self.model, x, self.x_eq)
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
    h = _positive("sample_time", sample_time)
    if design not in ("continuous", "discrete"):
        raise ValueError(f"design must be 'continuous' or 'discrete', got {design!r}")
    names = _actuated(actuation)
    cols = [INPUT_NAMES.index(n) for n in names]
    x_eq = upright_state(model)
    A, B = linearize(model, x_eq)
    sel = _design_states(model)
    Ar, Br = A[np.ix_(sel, sel)], B[np.ix_(sel, cols)]
    Qr, Rr = _weights(np.diag([10.0, 10.0, 1.0, 1.0]) if Q is None else Q, R, int(sel.sum()), len(cols))
    if design == "continuous":
        Pr = sla.solve_continuous_are(Ar, Br, Qr, Rr)
        Kr = np.linalg.solve(Rr, Br.T @ Pr)
    else:
        Ad, Bd = zoh(Ar, Br, h)
        Pr = sla.solve_discrete_are(Ad, Bd, Qr, Rr)
        Kr = np.linalg.solve(Rr + Bd.T @ Pr @ Bd, Bd.T @ Pr @ Ad)
    K = np.zeros((len(cols), model.nx))
    K[:, sel] = Kr
    P = np.zeros((model.nx, model.nx))
    P[np.ix_(sel, sel)] = Pr
    return LinearStateFeedback(model, K, x_eq, np.zeros(len(cols)), h, names, u_max, P, design)


def closed_loop_spectral_radius(model: Model, K: np.ndarray, h: float, input_names: Sequence[str] = INPUT_NAMES) -> float:
    """Spectral radius of ``Ad - Bd K``: the gain ``K`` applied with a ZOH of period ``h`` to the upright linearization.

    Below 1 the sampled linear closed loop is asymptotically stable. For the
    elastic model only the angular block is used: its spring modes are
    decoupled (and uncontrollable) at the upright equilibrium.
    """
    cols = [INPUT_NAMES.index(n) for n in input_names]
    A, B = linearize(model, upright_state(model))
    sel = _design_states(model)
    Ad, Bd = zoh(A[np.ix_(sel, sel)], B[np.ix_(sel, cols)], _positive("h", h))
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
    h = _positive("sample_time", sample_time)
    balance = lqr_balance(model, h, u_max=u_max)
    return EnergySwingUp(model, balance, h, k_energy=k_energy, u_max=_positive("u_max", u_max), catch_cost=catch_cost)


@dataclass
class TVLQRTracker:
    """Track a reference with time-varying gains, then hand over to ``final``.

    ``u = u_ref(t) - K(t) (x - x_ref(t))`` (angles wrapped) for ``t`` within the
    reference, where the reference is evaluated at the last reference sample at
    or before ``t`` (reference grid = sample grid gives the exact discrete law).

    Attributes
    ----------
    model : Model
    t_ref : ndarray, shape (N,)
        Reference times [s], increasing.
    x_ref : ndarray, shape (N, nx)
    u_ref : ndarray, shape (N, m) or (N-1, m)
        Reference torques [N.m] for ``input_names``.
    K : ndarray, shape (N-1, m, nx) or (N, m, nx)
        Gains.
    sample_time : float
    input_names : tuple of str
    final : SampledController or None
        Used after ``t_ref[-1]`` (e.g. LQR balance); holds ``u_ref[-1]`` if None.
    u_max : float or None
    """

    model: Model
    t_ref: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray
    K: np.ndarray
    sample_time: float
    input_names: tuple[str, ...] = INPUT_NAMES
    final: Any = None
    u_max: float | None = None

    def __post_init__(self) -> None:
        self.t_ref = np.asarray(self.t_ref, dtype=float)
        self.x_ref = np.asarray(self.x_ref, dtype=float)
        self.u_ref = np.asarray(self.u_ref, dtype=float).reshape(len(self.u_ref), -1)
        self.K = np.asarray(self.K, dtype=float)
        n, m = len(self.t_ref), len(self.input_names)
        if n < 2 or np.any(np.diff(self.t_ref) <= 0):
            raise ValueError(f"t_ref must be increasing with at least 2 samples, got {self.t_ref[:5]!r}...")
        if self.x_ref.shape != (n, self.model.nx):
            raise ValueError(f"x_ref must have shape ({n}, {self.model.nx}), got {self.x_ref.shape}")
        if self.u_ref.shape[0] not in (n - 1, n) or self.u_ref.shape[1] != m:
            raise ValueError(f"u_ref must have shape ({n}, {m}) or ({n - 1}, {m}), got {self.u_ref.shape}")
        if self.K.ndim != 3 or self.K.shape[0] not in (n - 1, n) or self.K.shape[1:] != (m, self.model.nx):
            raise ValueError(f"K must have shape ({n - 1}, {m}, {self.model.nx}), got {self.K.shape}")
        self.sample_time = _positive("sample_time", self.sample_time)

    def reset(self) -> None:
        """Reset the final controller."""
        if self.final is not None:
            self.final.reset()

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        # Masters accumulate time in floating point: a sample a hair before a grid time belongs to it.
        k = int(np.searchsorted(self.t_ref, t + 1e-9 * self.sample_time, side="right")) - 1
        if k >= min(len(self.K), len(self.u_ref)) or k >= len(self.t_ref) - 1:
            if self.final is not None:
                u = np.asarray(self.final(t, x), dtype=float)
            else:
                u = self.u_ref[-1].copy()
        else:
            k = max(k, 0)
            u = self.u_ref[k] - self.K[k] @ angle_error(self.model, x, self.x_ref[k])
        return u if self.u_max is None else np.clip(u, -self.u_max, self.u_max)


def discrete_tvlqr(
    model: Model,
    t_ref: np.ndarray,
    x_ref: np.ndarray,
    u_ref: np.ndarray,
    *,
    Q: Any = None,
    R: Any = None,
    Qf: Any = None,
    actuation: str | Sequence[str] = "full",
) -> np.ndarray:
    """Time-varying discrete LQR gains along a reference sampled on a uniform grid.

    Each interval is linearized at ``(x_ref[k], u_ref[k])`` and discretized
    exactly with a zero-order hold of the grid step, then the discrete Riccati
    recursion runs backwards from ``Qf``.

    Parameters
    ----------
    model : Model
    t_ref : ndarray, shape (N,)
        Uniform grid [s] (the controller's sample times).
    x_ref : ndarray, shape (N, nx)
    u_ref : ndarray, shape (N-1, 2) or (N, 2)
        Full torques (tau1, tau2) [N.m].
    Q, R, Qf : array_like, optional
        Weights; defaults: Q = diag(10 on angles, 1 elsewhere), R = I (m x m),
        Qf = the cost-to-go of the discrete LQR balance that takes over at the
        end (plus 1e-6 I, which keeps the uncontrollable spring block positive definite).
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        The torques the gains drive (m of them).

    Returns
    -------
    ndarray, shape (N-1, m, nx)
    """
    t_ref = np.asarray(t_ref, dtype=float)
    x_ref = model.check_state(x_ref, "x_ref")
    u_ref = model.check_input(u_ref, "u_ref")
    cols = [INPUT_NAMES.index(n) for n in _actuated(actuation)]
    h = np.diff(t_ref)
    if len(t_ref) < 2 or np.ptp(h) > 1e-9 * max(h.max(), 1e-300) + 1e-12 or h.min() <= 0:
        raise ValueError("t_ref must be a uniform increasing grid with at least 2 samples")
    n = model.nx
    q_diag = np.where(_angle_mask(model), 10.0, 1.0)
    Qm, Rm = _weights(np.diag(q_diag) if Q is None else Q, R, n, len(cols))
    if Qf is None:
        Qfm = lqr_balance(model, float(h[0]), design="discrete", actuation=actuation).P + 1e-6 * np.eye(n)
    else:
        Qfm = np.atleast_2d(np.asarray(Qf, dtype=float))
    P = Qfm
    K = np.empty((len(t_ref) - 1, len(cols), n))
    for k in range(len(t_ref) - 2, -1, -1):
        A, B = linearize(model, x_ref[k], u_ref[min(k, len(u_ref) - 1)])
        Ad, Bd = zoh(A, B[:, cols], float(h[k]))
        S = Rm + Bd.T @ P @ Bd
        K[k] = np.linalg.solve(S, Bd.T @ P @ Ad)
        P = Qm + Ad.T @ P @ (Ad - Bd @ K[k])
        P = 0.5 * (P + P.T)
    return K


def swingup_reference(
    model: Model, sample_time: float, t_final: float, *, x0: np.ndarray | None = None, u_max: float = 20.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A swing-up reference from the native energy-pumping loop: ``(t, x_ref, u_ref)``.

    Shapes (N,), (N, nx), (N, 2). Stands in for an optimized swing-up when none
    is at hand; any reference on the sample grid can be tracked the same way.
    """
    from ..model.simulate import simulate

    ctrl = energy_swingup(model, sample_time, u_max=u_max)
    x0 = model.state(theta1=0.1) if x0 is None else x0
    traj = simulate(model, x0, t_final, dt=sample_time, u=as_feedback(ctrl, model), rtol=1e-10, atol=1e-10)
    return traj.t, traj.x, traj.u


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


def resample_reference(
    t: np.ndarray, x: np.ndarray, u: np.ndarray, sample_time: float, model: Model | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Put a reference ``(t, x, u)`` on the uniform sample grid ``0, h, 2h, ... <= t[-1]``.

    Torques are zero-order held (the value of the last reference knot at or
    before each sample), so a reference whose knots are a multiple of ``h``
    apart keeps its torques exactly. States between knots are interpolated by
    cubic Hermite with the slopes ``f(x, u)`` of ``model`` (a coarse optimized
    trajectory stays close to a solution: linear interpolation would cut
    corners and the tracker would fight them), or linearly without a model.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times [s], starting at 0.
    x : ndarray, shape (N, nx)
    u : ndarray, shape (N, 2) or (N-1, 2)
        Torques held from ``t[k]`` [N.m].
    sample_time : float
        [s].
    model : Model, optional
        Gives the Hermite slopes.

    Returns
    -------
    t_s, x_s, u_s : ndarrays, shapes (M,), (M, nx), (M, 2)
    """
    h = _positive("sample_time", sample_time)
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    if t.ndim != 1 or len(t) < 2 or np.any(np.diff(t) <= 0) or abs(t[0]) > 1e-12:
        raise ValueError(f"reference times must increase from 0 with at least 2 samples, got {t[:3]!r}...")
    if x.shape[0] != len(t) or u.shape[0] not in (len(t), len(t) - 1):
        raise ValueError(f"reference x must have {len(t)} rows and u {len(t)} or {len(t) - 1}, got {x.shape}, {u.shape}")
    n = int(np.floor(t[-1] / h + 1e-9))
    if n < 1:
        raise ValueError(f"reference ({t[-1]:g} s) is shorter than one sample ({h:g} s)")
    ts = np.arange(n + 1) * h
    k = np.clip(np.searchsorted(t, ts + 1e-9 * h, side="right") - 1, 0, len(u) - 1)
    if model is None:
        xs = np.column_stack([np.interp(ts, t, x[:, j]) for j in range(x.shape[1])])
        return ts, xs, u[k]
    j = np.minimum(k, len(t) - 2)  # interval of each sample
    dt = t[j + 1] - t[j]
    s = ((ts - t[j]) / dt)[:, None]
    f0, f1 = model.rhs(x[j], u[j]), model.rhs(x[j + 1], u[j])
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    xs = h00 * x[j] + h10 * dt[:, None] * f0 + h01 * x[j + 1] + h11 * dt[:, None] * f1
    return ts, xs, u[k]


def tvlqr_tracker(
    model: Model,
    t: np.ndarray,
    x: np.ndarray,
    u: np.ndarray,
    sample_time: float,
    *,
    u_max: float | None = 20.0,
    actuation: str | Sequence[str] = "full",
    Q: Any = None,
    R: Any = None,
) -> TVLQRTracker:
    """TVLQR tracking of any swing-up reference (e.g. an optimized one), handing over to discrete LQR balance.

    The reference ``(t, x, u)`` (u: full torques (tau1, tau2), any grid) is
    resampled to the sample grid (:func:`resample_reference`); the gains come from
    :func:`discrete_tvlqr` for the torques named by ``actuation`` (a passive
    joint gets none); ``Q``, ``R`` as there.
    """
    ts, xs, us = resample_reference(t, x, u, sample_time, model)
    xs = model.check_state(xs, "x_ref")
    names = _actuated(actuation)
    cols = [INPUT_NAMES.index(n) for n in names]
    K = discrete_tvlqr(model, ts, xs, us, actuation=names, Q=Q, R=R)
    final = lqr_balance(model, sample_time, design="discrete", u_max=u_max, actuation=names, R=R)
    return TVLQRTracker(model, ts, xs, us[:, cols], K, sample_time, names, final=final, u_max=u_max)


def load_reference_csv(path: str, model: Model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read a reference ``(t, x, u)`` from a CSV with a header naming ``t``, the model's states and ``tau1, tau2``.

    Trajectory CSVs (``Trajectory.to_csv``, ``pendulab cosim``, ``pendulab simulate``) and the
    optimal trajectory of ``pendulab swingup`` (``optimal.csv``) have these columns.
    """
    import csv

    with open(path, newline="") as fh:
        reader = csv.reader(fh)
        header = [h.strip() for h in next(reader)]
        rows = np.array([[float(v) for v in row] for row in reader if row])
    need = ("t",) + model.state_names + INPUT_NAMES
    missing = [n for n in need if n not in header]
    if missing or rows.ndim != 2 or len(rows) < 2:
        raise ValueError(
            f"reference {path!r} must be a CSV with a header containing {list(need)} and at least 2 rows; missing {missing}"
        )
    col = {n: header.index(n) for n in need}
    return (
        rows[:, col["t"]],
        rows[:, [col[n] for n in model.state_names]],
        rows[:, [col[n] for n in INPUT_NAMES]],
    )


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
    h = _positive("sample_time", sample_time)
    if name == "lqr":
        x0 = upright_state(model)
        x0[0] += 0.1
        return lqr_balance(model, h, actuation=actuation), x0
    if name == "swingup":
        if _actuated(actuation) != INPUT_NAMES:
            raise ValueError(f"the energy swing-up drives both torques; actuation must be 'full', got {actuation!r}")
        return energy_swingup(model, h, u_max=u_max), model.state(theta1=0.1)
    if name == "tvlqr":
        if reference is None:
            reference = swingup_reference(model, h, round(_positive("t_ref", t_ref) / h) * h, u_max=u_max)
        tracker = tvlqr_tracker(model, *reference, h, u_max=u_max, actuation=actuation)
        return tracker, tracker.x_ref[0].copy()
    raise ValueError(f"controller must be one of {list(CONTROLLERS)}, got {name!r}")

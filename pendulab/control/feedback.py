"""Sampled-data controllers: the one controller protocol, and the controllers that keep it.

A :class:`SampledController` is called once per sample with the plant state
and returns the torques it drives, which are then held constant until the next
sample (zero-order hold). The same object therefore runs natively through
``pendulab.simulate(..., dt=sample_time, u=as_feedback(controller, model))`` and
through an FMU with :func:`pendulab.cosim.cosim`.

Controllers:

* :class:`LinearStateFeedback` (from :func:`balance_controller`): LQR balance
  about the upright equilibrium, a continuous-time gain applied with a ZOH or
  a discrete gain designed at the sample time;
* :class:`EnergySwingUp` (from :func:`energy_swingup`): energy pumping with
  the driven torque(s) (full, pendubot or acrobot), then a switch to LQR balance;
* :class:`~pendulab.control.tracking.TVLQRTracker` (in :mod:`.tracking`, with
  its design): tracks a reference with time-varying gains, then hands over to a
  final controller.

Every gain comes from the one LQR design, :func:`pendulab.control.lqr.lqr_balance`,
and the one Riccati recursion, :func:`pendulab.control.lqr.discrete_tvlqr`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from .._checks import positive_float
from .._inputs import checked
from ..analysis.equilibria import equilibrium
from ..analysis.linearize import linearize
from ..model.model import ACTUATIONS, INPUT_NAMES, Model
from .lqr import actuation_name, lqr_balance, wrap_state_error, zoh

__all__ = [
    "SampledController",
    "LinearStateFeedback",
    "EnergySwingUp",
    "balance_controller",
    "energy_swingup",
    "upright_state",
    "closed_loop_spectral_radius",
    "as_feedback",
    "full_input",
    "ControllerOutputError",
    "actuated_inputs",
    "angular_states",
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

    Parameters
    ----------
    *args, **kwargs
        Not used (a ``Protocol`` cannot be instantiated; any object with these
        attributes and methods satisfies it).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import SampledController, as_feedback
    >>> class ShoulderDamper:  # any object with these four members is a SampledController
    ...     sample_time = 0.01
    ...     input_names = ("tau1",)
    ...     def reset(self):
    ...         pass
    ...     def __call__(self, t, x):
    ...         return np.array([-0.5 * x[2]])  # tau1 = -0.5 N.m s/rad * omega1
    >>> isinstance(ShoulderDamper(), SampledController)
    True
    >>> model = pl.rigid()
    >>> traj = pl.simulate(model, model.state(theta1=1.0), 10.0, dt=0.01, u=as_feedback(ShoulderDamper(), model))
    >>> print(f"energy {model.energy(traj.x[0]):.2f} J -> {model.energy(traj.x[-1]):.2f} J")
    energy -20.41 J -> -26.99 J
    """

    sample_time: float
    input_names: tuple[str, ...]

    def reset(self) -> None:
        """Forget internal state (mode switches) before a new run."""

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """Torques [N.m], shape (len(input_names),), from time ``t`` [s] and the plant state ``x``, shape (nx,)."""


# -- helpers -------------------------------------------------------------------------


def upright_state(model: Model) -> np.ndarray:
    """The up-up equilibrium (theta1 = theta2 = pi, at rest).

    A thin wrapper of ``pendulab.analysis.equilibria.equilibrium(model, "up-up").x``:
    for the elastic model the springs carry the weight above them, so they are
    compressed (r1 = L1 - (m1 + m2) g / k1, r2 = L2 - m2 g / k2).

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum.

    Returns
    -------
    ndarray, shape (nx,)
        A fresh copy of the equilibrium state (angles [rad], lengths [m], zero rates).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import upright_state
    >>> np.round(upright_state(pl.rigid()), 4)
    array([3.1416, 3.1416, 0.    , 0.    ])
    >>> x = upright_state(pl.elastic(k1=500.0, k2=500.0))  # springs compressed by the weight above them
    >>> dict(zip(pl.elastic().state_names[:4], np.round(x[:4], 4).tolist()))
    {'theta1': 3.1416, 'theta2': 3.1416, 'r1': 0.9608, 'r2': 0.9804}
    """
    return equilibrium(model, "up-up").x.copy()


def actuated_inputs(actuation: str | Sequence[str]) -> tuple[str, ...]:
    """Names of the torques an actuation drives, e.g. ``("tau1",)`` for ``"pendubot"``.

    Parameters
    ----------
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        The actuation.

    Returns
    -------
    tuple of str
        A subset of ("tau1", "tau2") in input order.

    Raises
    ------
    ValueError
        Unknown actuation.

    Examples
    --------
    >>> from pendulab.control import actuated_inputs
    >>> actuated_inputs("pendubot"), actuated_inputs("acrobot"), actuated_inputs("full")
    (('tau1',), ('tau2',), ('tau1', 'tau2'))
    >>> actuated_inputs(["tau2", "tau1"])  # names in any order come back in input order
    ('tau1', 'tau2')
    """
    return tuple(INPUT_NAMES[i] for i in ACTUATIONS[actuation_name(actuation)])


def angular_states(model: Model) -> np.ndarray:
    """Mask of the angles and link rates (the states an upright balance gain acts on).

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum.

    Returns
    -------
    ndarray of bool, shape (nx,)
        True at ``theta*`` and ``omega*``.
    """
    return np.array([n.startswith(("theta", "omega")) for n in model.state_names])


def _angular_weight(model: Model, Q: Any) -> np.ndarray:
    """Embed a weight on (theta1, theta2, omega1, omega2), shape (4, 4) or (4,), into the full state (zero on r, v).

    At the aligned upright equilibrium the spring (radial) coordinates of the
    elastic model decouple from the angles to first order, so their modes are
    uncontrollable by the torques and get no weight (and no gain).
    """
    sel = np.flatnonzero(angular_states(model))
    Qa = np.diag([10.0, 10.0, 1.0, 1.0]) if Q is None else np.atleast_2d(np.asarray(Q, dtype=float))
    if Qa.shape == (1, len(sel)):
        Qa = np.diag(Qa[0])
    if Qa.shape != (len(sel), len(sel)):
        raise ValueError(f"Q must have shape ({len(sel)}, {len(sel)}) or ({len(sel)},), got {np.shape(Q)}")
    Qf = np.zeros((model.nx, model.nx))
    Qf[np.ix_(sel, sel)] = Qa
    return Qf


# -- controllers -----------------------------------------------------------------


@checked()
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

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import LinearStateFeedback, lqr_balance
    >>> model = pl.rigid()
    >>> d = lqr_balance(model, "pendubot")
    >>> ctrl = LinearStateFeedback(model, d.K, d.x_eq, np.zeros(1), 0.01, ("tau1",), u_max=5.0, P=d.P)
    >>> x = d.x_eq + [0.0, 0.02, 0.0, 0.0]
    >>> np.round(ctrl(0.0, x), 3), round(ctrl.cost(x), 4)  # u = u_eq - K (x - x_eq), and e' P e
    (array([2.689]), 0.9766)
    >>> ctrl(0.0, d.x_eq + [0.0, 0.1, 0.0, 0.0])  # saturated at u_max
    array([5.])
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
        """Quadratic cost-to-go ``e' P e`` of the deviation from ``x_eq``.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            Plant state; ``e = x - x_eq`` with angles wrapped into (-pi, pi].

        Returns
        -------
        float
            ``e' P e``, or ``e' e`` when ``P`` is None.
        """
        e = wrap_state_error(np.asarray(x, dtype=float) - self.x_eq, self.model.state_names)
        return float(e @ self.P @ e) if self.P is not None else float(e @ e)


@checked()
def balance_controller(
    model: Model,
    sample_time: float,
    *,
    design: str = "continuous",
    Q: Any = None,
    R: Any = None,
    actuation: str | Sequence[str] = "full",
    u_max: float | None = None,
) -> LinearStateFeedback:
    """LQR balance about the upright equilibrium as a sampled controller (gain: :func:`pendulab.control.lqr.lqr_balance`).

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
        Zero feed-forward torque; the gain acts on the angles and link rates only.

    Raises
    ------
    ValueError
        Non-positive ``sample_time``, unknown ``design`` or ``actuation``, or a
        ``Q`` of the wrong shape.
    UncontrollableError
        The actuation cannot balance the upright equilibrium.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import balance_controller
    >>> from pendulab.control.feedback import closed_loop_spectral_radius
    >>> model = pl.rigid()
    >>> fixed = balance_controller(model, 0.2)  # continuous-time gain, applied every 0.2 s
    >>> redesigned = balance_controller(model, 0.2, design="discrete")  # LQR of the 0.2 s ZOH discretization
    >>> for ctrl in (fixed, redesigned):  # below 1: the sampled loop is stable
    ...     print(ctrl.design, round(closed_loop_spectral_radius(model, ctrl.K, 0.2), 2))
    continuous 1.47
    discrete 0.62
    """
    h = float(sample_time)
    if design not in ("continuous", "discrete"):
        raise ValueError(f"design must be 'continuous' or 'discrete', got {design!r}")
    names = actuated_inputs(actuation)
    lq = lqr_balance(model, names, _angular_weight(model, Q), R, None if design == "continuous" else h)
    return LinearStateFeedback(model, lq.K, lq.x_eq, np.zeros(len(names)), h, names, u_max, lq.P, design)


def closed_loop_spectral_radius(model: Model, K: np.ndarray, h: float, input_names: Sequence[str] = INPUT_NAMES) -> float:
    """Spectral radius of ``Ad - Bd K``: the gain ``K`` applied with a ZOH of period ``h`` to the upright linearization.

    Below 1 the sampled linear closed loop is asymptotically stable. For the
    elastic model only the angular block is used: its spring modes are
    decoupled (and uncontrollable) at the upright equilibrium.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum, linearized at up-up.
    K : array_like, shape (m, nx)
        State-feedback gain [N.m per state unit]; only its angular columns are used.
    h : float
        Sample (hold) period [s], > 0.
    input_names : sequence of str
        The m torques the rows of ``K`` drive, from ("tau1", "tau2").

    Returns
    -------
    float
        Largest eigenvalue modulus of the sampled angular closed loop.
    """
    cols = [INPUT_NAMES.index(n) for n in input_names]
    lin = linearize(model, equilibrium(model, "up-up"))
    sel = angular_states(model)
    Ad, Bd = zoh(lin.A[np.ix_(sel, sel)], lin.B[np.ix_(sel, cols)], positive_float("h", h))
    return float(np.max(np.abs(np.linalg.eigvals(Ad - Bd @ np.asarray(K)[:, sel]))))


@checked()
@dataclass
class EnergySwingUp:
    """Energy pumping with the driven torques, then LQR balance.

    Away from the top the controller pumps energy with one torque so that the
    power it delivers has the sign of the energy deficit ``E_up - E``:

    * ``actuation="full"``: ``tau1 = sat(k_energy (E_up - E) omega1)`` pumps and
      ``tau2 = -kp (theta2 - theta1) - kd (omega2 - omega1)`` keeps the pair
      close to a single pendulum;
    * ``"pendubot"``: ``tau1 = sat(k_energy (E_up - E) omega1)`` (power
      ``tau1 omega1``), ``tau2 = 0``;
    * ``"acrobot"``: ``tau2 = sat(k_energy (E_up - E) (omega2 - omega1))`` (power
      ``tau2 (omega2 - omega1)``), ``tau1 = 0``.

    ``k_energy`` stands for :meth:`pump_gain` at the pumping rate, ``k_energy / (1 + k_energy rate² h)``:
    it keeps the sampled energy loop stable at high rates (without it the held torque chattered between
    the limits and the swing-up depended on the integrator's tolerance).

    When the LQR cost-to-go falls below ``catch_cost`` the controller switches
    to ``balance`` (designed for the same actuation); it stays there until
    :meth:`reset`, or, with ``release_factor``, until the cost-to-go exceeds
    ``release_factor * catch_cost`` (a failed catch: pump again and retry).
    All torques are clipped to ``[-u_max, u_max]``. Build it with :func:`energy_swingup`.

    Attributes
    ----------
    model : Model
        Plant (energy, state layout).
    balance : LinearStateFeedback
        Upright LQR that takes over at the catch (same ``input_names``).
    sample_time : float
        Sample period [s].
    k_energy : float
        Pumping gain [N.m / (J rad/s)].
    kp : float
        Alignment stiffness on ``theta2 - theta1`` [N.m/rad] (full actuation only).
    kd : float
        Alignment damping on ``omega2 - omega1`` [N.m s/rad] (full actuation only).
    u_max : float
        Symmetric torque limit [N.m].
    catch_cost : float
        Switch to ``balance`` once ``balance.cost(x)`` is below this.
    input_names : tuple of str
        Driven torques: ("tau1", "tau2") for full actuation, ("tau1",) for the
        pendubot, ("tau2",) for the acrobot.
    e_up : float
        Energy of the upright equilibrium [J] (set at construction).
    release_factor : float or None
        Back to pumping when ``balance.cost(x)`` exceeds ``release_factor *
        catch_cost`` after a catch; None: never.
    caught_at : float or None
        Time of the (last) switch to ``balance`` [s]; None while pumping.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import energy_swingup, upright_state
    >>> model = pl.rigid()
    >>> ctrl = energy_swingup(model, 0.01, actuation="acrobot", u_max=6.0)
    >>> ctrl.actuation, ctrl.input_names, round(ctrl.e_up, 2)  # upright energy [J]
    ('acrobot', ('tau2',), 29.43)
    >>> ctrl(0.0, model.state())  # hanging at rest: no rate to pump with, so a full kick
    array([6.])
    >>> x = upright_state(model) + [0.01, 0.0, 0.0, 0.0]
    >>> u = ctrl(0.5, x)  # near the top the LQR cost-to-go is below catch_cost: switch to balance
    >>> ctrl.caught_at, bool(np.allclose(u, ctrl.balance(0.5, x)))
    (0.5, True)
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
    release_factor: float | None = None
    e_up: float = field(init=False)
    caught_at: float | None = field(init=False, default=None)

    def __post_init__(self) -> None:
        self.e_up = float(self.model.energy(upright_state(self.model)))

    @property
    def actuation(self) -> str:
        """``"full"``, ``"pendubot"`` or ``"acrobot"`` (from ``input_names``)."""
        return actuation_name(self.input_names)

    def reset(self) -> None:
        """Back to the pumping mode."""
        self.caught_at = None

    def pump_gain(self, rate: float) -> float:
        """Pumping gain at the pumping joint's ``rate``: ``k_energy / (1 + k_energy rate² sample_time)``.

        Over one held sample the pumping torque itself changes the energy by ``tau rate h``, so the
        deficit's sample-to-sample loop gain is ``k rate² h``. With the plain gain ``k_energy`` that exceeds 1
        above ``|rate| = 1 / sqrt(k h)`` (10 rad/s for k = 1, h = 10 ms): the held torque then flips sign and
        grows every sample until it saturates (bang-bang chatter), which amplified integrator-level
        differences 1e5-fold within 0.1 s and made the swing-up depend on the integrator and its tolerance.
        This gain keeps the loop gain ``g / (1 + g)`` below 1 (``g = k rate² h``): ``k_energy`` at low rates, at
        most the deadbeat gain ``1 / (rate² h)`` at high ones.

        Parameters
        ----------
        rate : float
            Rate of the pumping joint [rad/s] (``omega1``; acrobot ``omega2 - omega1``).

        Returns
        -------
        float
            [N.m / (J rad/s)].
        """
        return self.k_energy / (1.0 + self.k_energy * rate * rate * self.sample_time)

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        cost = self.balance.cost(x)
        if self.caught_at is None and cost < self.catch_cost:
            self.caught_at = float(t)
        elif self.caught_at is not None and self.release_factor is not None and cost > self.release_factor * self.catch_cost:
            self.caught_at = None  # the catch failed: pump again
        if self.caught_at is not None:
            return np.clip(self.balance(t, x), -self.u_max, self.u_max)
        th1, th2 = x[0], x[1]
        w1, w2 = x[self.model.nq], x[self.model.nq + 1]
        deficit = self.e_up - float(self.model.energy(x))
        actuation = self.actuation
        # The pumping joint's rate: the power of the pumping torque is torque * rate.
        rate = w2 - w1 if actuation == "acrobot" else w1
        # Start from rest: no velocity to pump with, so kick (in the direction that adds energy next).
        pump = self.pump_gain(rate) * deficit * rate if abs(rate) > 1e-3 else self.u_max * np.sign(deficit)
        if actuation != "full":
            return np.clip(np.array([pump]), -self.u_max, self.u_max)
        rel = (th2 - th1 + np.pi) % (2 * np.pi) - np.pi
        tau2 = -self.kp * rel - self.kd * (w2 - w1)
        return np.clip(np.array([pump, tau2]), -self.u_max, self.u_max)


#: Default (k_energy [N.m / (J rad/s)], catch_cost) of :func:`energy_swingup` per actuation. The pendubot and
#: acrobot values were picked on the RealAIGym tasks (swingup_pendubot, swingup_acrobot: 6 N.m, 10 s) from
#: k_energy in {1, 2, 3, 5} x catch_cost in {5, 10, 20}, 6 runs each (nominal + 5 with 0.05 rad/s rate noise):
#: these two succeeded 6/6 on both tasks; many neighbours did not (the pumping phase is chaotic).
ENERGY_SWINGUP_DEFAULTS: dict[str, tuple[float, float]] = {"full": (2.0, 20.0), "pendubot": (1.0, 10.0), "acrobot": (1.0, 10.0)}
# One-joint swing-ups re-arm the pumping when a catch fails (cost-to-go above 4x catch_cost): more tries per episode.
_RELEASE_FACTOR = 4.0


@checked()
def energy_swingup(
    model: Model,
    sample_time: float,
    *,
    k_energy: float | None = None,
    u_max: float = 20.0,
    catch_cost: float | None = None,
    actuation: str | Sequence[str] = "full",
) -> EnergySwingUp:
    """Energy-pumping swing-up switching to continuous LQR balance, for full, pendubot or acrobot actuation.

    Parameters
    ----------
    model : Model
        Rigid or elastic plant (design model).
    sample_time : float
        [s].
    k_energy : float, optional
        Pumping gain [N.m / (J rad/s)]; default per actuation (:data:`ENERGY_SWINGUP_DEFAULTS`).
    u_max : float
        Torque limit [N.m].
    catch_cost : float, optional
        Switch to LQR when the LQR cost-to-go ``e' P e`` falls below this; default per actuation.
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        Driven torques: full pumps with ``tau1`` and aligns the links with
        ``tau2``; the pendubot pumps with ``tau1`` alone, the acrobot with ``tau2``
        alone (see :class:`EnergySwingUp`).

    Returns
    -------
    EnergySwingUp
        Pumping controller whose ``balance`` is the continuous-design upright
        LQR (:func:`balance_controller`) for the same actuation, saturated at ``u_max``.

    Raises
    ------
    ValueError
        Non-positive ``sample_time`` or ``u_max``, or an unknown ``actuation``.
    UncontrollableError
        The actuation cannot balance the upright equilibrium.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, energy_swingup
    >>> model = pl.rigid()
    >>> ctrl = energy_swingup(model, 0.01, u_max=20.0)  # pump with tau1, align the links with tau2
    >>> traj = pl.simulate(model, model.state(theta1=0.1), 5.0, dt=0.01, u=as_feedback(ctrl, model))
    >>> print(f"caught by the LQR at t = {ctrl.caught_at:.2f} s")
    caught by the LQR at t = 2.63 s
    >>> np.round(np.cos(traj.x[-1, :2]), 3)  # both links upright
    array([-1., -1.])
    """
    h = float(sample_time)
    limit = float(u_max)
    names = actuated_inputs(actuation)
    k_default, catch_default = ENERGY_SWINGUP_DEFAULTS[actuation_name(names)]
    k = k_default if k_energy is None else float(k_energy)
    catch = catch_default if catch_cost is None else float(catch_cost)
    balance = balance_controller(model, h, u_max=limit, actuation=names)
    release = None if names == INPUT_NAMES else _RELEASE_FACTOR
    return EnergySwingUp(model, balance, h, k, u_max=limit, catch_cost=catch, input_names=names, release_factor=release)


# -- glue -----------------------------------------------------------------------------


class ControllerOutputError(ValueError):
    """A controller returned a command that is not a finite torque per driven input (never applied)."""


def full_input(controller: SampledController, u: Any, t: float | None = None, *, who: str | None = None) -> np.ndarray:
    """Check a controller output and scatter it into (tau1, tau2), zeros elsewhere.

    Every runner that applies a controller's command (simulate's feedback, co-simulation, the
    RealAIGym protocols) passes it here, so a non-finite or wrongly sized command is an error
    naming the controller and the time, never a torque a plant integrates.

    Parameters
    ----------
    controller : SampledController
        Gives the names of the driven inputs.
    u : array_like, shape (len(controller.input_names),)
        The controller's torques [N.m].
    t : float, optional
        Time of the command [s], for the message.
    who : str, optional
        The name the message gives the controller (default its class's; a wrapper names what it wraps).

    Returns
    -------
    ndarray, shape (2,)
        (tau1, tau2) [N.m], zero on the undriven input.

    Raises
    ------
    ControllerOutputError
        ``u`` is not numbers, has the wrong size, or holds a NaN or an infinity.
    """
    names = tuple(controller.input_names)
    when = "" if t is None else f" at t = {t:.6g} s"
    who = type(controller).__name__ if who is None else who
    try:
        values = np.asarray(u, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ControllerOutputError(f"{who} returned {u!r}{when}: not torques ({exc})") from exc
    if values.shape != (len(names),) or not np.isfinite(values).all():
        raise ControllerOutputError(
            f"{who} returned {values.tolist()!r}{when}; expected {len(names)} finite torque(s) [N.m] for {list(names)}"
        )
    full = np.zeros(len(INPUT_NAMES))
    for name, value in zip(names, values, strict=True):
        full[INPUT_NAMES.index(name)] = value
    return full


def as_feedback(controller: SampledController, model: Model) -> Callable[[float, np.ndarray], np.ndarray]:
    """Wrap a controller (after resetting it) as ``u(t, x) -> (tau1, tau2)`` for :func:`pendulab.simulate`.

    Run ``simulate`` with ``dt = controller.sample_time`` so the output grid is
    the sample grid: simulate holds each value over its output step.

    Parameters
    ----------
    controller : SampledController
        Reset once, now.
    model : Model
        The plant (not used by the wrapper itself).

    Returns
    -------
    callable
        ``feedback(t, x) -> ndarray, shape (2,)``: the controller output at
        time ``t`` [s] and state ``x``, scattered by :func:`full_input` [N.m].

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, balance_controller, upright_state
    >>> model = pl.rigid()
    >>> ctrl = balance_controller(model, sample_time=0.01, actuation="pendubot")  # drives tau1 only
    >>> x0 = upright_state(model) + [0.0, 0.05, 0.0, 0.0]  # elbow link tilted by 0.05 rad
    >>> feedback = as_feedback(ctrl, model)
    >>> np.round(feedback(0.0, x0), 2)  # (tau1, tau2) [N.m]: the passive elbow gets 0
    array([6.75, 0.  ])
    >>> traj = pl.simulate(model, x0, 5.0, dt=ctrl.sample_time, u=feedback)  # torque held over each 10 ms sample
    >>> bool(np.allclose(traj.x[-1], upright_state(model), atol=1e-3))
    True
    """
    controller.reset()

    def feedback(t: float, x: np.ndarray) -> np.ndarray:
        return full_input(controller, controller(t, x), t)

    return feedback

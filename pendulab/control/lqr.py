"""LQR balancing about an equilibrium (by default up-up), continuous or sampled.

The gain is designed on the controllable subspace: at the vertical equilibria
of the elastic pendulum the torques cannot reach the spring (radial) motion to
first order, so (A, B) is not controllable there and a plain Riccati solve
fails. Uncontrollable modes that are asymptotically stable or undamped
oscillations are left alone (reported in ``uncontrollable_eigenvalues``); an
uncontrollable mode that is unstable or a drift (eigenvalue at 0) cannot be
balanced and raises ``UncontrollableError``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import control as ct
import numpy as np
from scipy.linalg import expm, solve_continuous_lyapunov, solve_discrete_lyapunov

from .._checks import check_model
from .._inputs import checked
from ..analysis.equilibria import Equilibrium, equilibrium
from ..analysis.linearize import check_actuation, linearize, linearize_along, not_equilibrium_error
from ..model.model import ACTUATIONS, INPUT_NAMES, Model
from .controllability import controllable_subspace

__all__ = [
    "LQRDesign",
    "UncontrollableError",
    "lqr_balance",
    "discrete_tvlqr",
    "wrap_state_error",
    "zoh",
    "actuation_name",
    "weight_matrix",
]


class UncontrollableError(ValueError):
    """LQR was asked to stabilize a configuration whose unstable or drifting modes the inputs cannot reach.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import UncontrollableError, lqr_balance
    >>> model = pl.rigid(g=0.0)  # no gravity: at rest the shoulder torque moves the links along one direction only
    >>> try:
    ...     lqr_balance(model, "pendubot", at=model.state())
    ... except UncontrollableError as err:
    ...     print(err)
    uncontrollable configuration: rigid model with actuation 'pendubot' at 'goal' has controllability rank 2 of 4, ...
    >>> issubclass(UncontrollableError, ValueError)
    True
    """


@dataclass(frozen=True)
class LQRDesign:
    """A state-feedback gain about an equilibrium: ``u = u_eq - K (x - x_eq)``.

    Attributes
    ----------
    K : ndarray, shape (m, nx)
        Gain on the state error [N.m per state unit]; m = 2 for ``full``, else 1.
    x_eq : ndarray, shape (nx,)
    u_eq : ndarray, shape (2,)
        Holding torques (tau1, tau2) [N.m] at the equilibrium.
    actuation : str
    input_indices : tuple of int
        Which of (tau1, tau2) the rows of K drive.
    Q : ndarray, shape (nx, nx)
    R : ndarray, shape (m, m)
    dt : float or None
        Sample time [s] of a discrete design (``None``: continuous).
    closed_loop_eigenvalues : ndarray of complex, shape (nx,)
        Of A - B K [1/s] (continuous) or of the ZOH-sampled loop (discrete, abs(z) < 1 is stable).
    uncontrollable_eigenvalues : ndarray of complex
        Modes the inputs cannot move (empty when controllable).
    equilibrium : str
    state_names, input_names : tuple of str
    kind : str
    P : ndarray, shape (nx, nx)
        Cost-to-go ``dx' P dx`` of the closed loop (Riccati solution on the
        controllable subspace, plus the free decay of stable uncontrollable
        modes when that cost is finite).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import balanced, lqr_balance
    >>> model = pl.rigid()
    >>> design = lqr_balance(model, "acrobot")  # an LQRDesign
    >>> design.actuation, design.input_indices, design.K.shape, design.equilibrium
    ('acrobot', (1,), (1, 4), 'up-up')
    >>> x0 = design.x_eq + [0.05, 0.0, 0.0, 0.0]
    >>> np.round(design.torque(x0), 2)  # (tau1, tau2) [N.m]: the passive shoulder stays at u_eq = 0
    array([ 0.  , 13.72])
    >>> traj = pl.simulate(model, x0, 5.0, dt=0.01, u=design.controller(u_max=20.0))
    >>> balanced(design, traj.x[-1])
    True
    """

    K: np.ndarray
    x_eq: np.ndarray
    u_eq: np.ndarray
    actuation: str
    input_indices: tuple[int, ...]
    Q: np.ndarray
    R: np.ndarray
    dt: float | None
    closed_loop_eigenvalues: np.ndarray
    uncontrollable_eigenvalues: np.ndarray
    equilibrium: str
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    kind: str
    P: np.ndarray | None = None

    def torque(self, x: Any) -> np.ndarray:
        """Full torque vector commanded at state ``x`` (angles compared modulo 2 pi).

        Parameters
        ----------
        x : array_like, shape (nx,)
            State in ``state_names`` order (angles [rad], lengths [m], rates
            [rad/s], [m/s]).

        Returns
        -------
        ndarray, shape (2,)
            ``u_eq - K (x - x_eq)`` on the driven inputs, ``u_eq`` on the
            others: (tau1, tau2) [N.m], unsaturated.
        """
        dx = wrap_state_error(np.asarray(x, dtype=float) - self.x_eq, self.state_names)
        u = self.u_eq.copy()
        u[list(self.input_indices)] += -self.K @ dx
        return u

    def controller(self, u_max: float | None = None) -> Callable[[float, np.ndarray], np.ndarray]:
        """Feedback ``u(t, x) -> (tau1, tau2)`` for :func:`pendulab.simulate`.

        Parameters
        ----------
        u_max : float, optional
            Saturation ``|tau| <= u_max`` [N.m] on each torque; None: no limit.

        Returns
        -------
        callable
            ``feedback(t, x) -> ndarray, shape (2,)``: :meth:`torque` clipped
            to ``[-u_max, u_max]`` [N.m]; ``t`` [s] is ignored.

        Raises
        ------
        ValueError
            ``u_max`` is not None and not a finite positive number.
        """
        if u_max is not None and not (np.isfinite(u_max) and u_max > 0):
            raise ValueError(f"u_max must be a positive torque in N.m or None, got {u_max!r}")

        def feedback(_t: float, x: np.ndarray) -> np.ndarray:
            u = self.torque(x)
            return u if u_max is None else np.clip(u, -u_max, u_max)

        return feedback


def wrap_state_error(dx: np.ndarray, state_names: tuple[str, ...]) -> np.ndarray:
    """Wrap the angle entries (names starting with ``theta``) of a state difference into (-pi, pi].

    Parameters
    ----------
    dx : array_like, shape (..., nx)
        State differences.
    state_names : tuple of str
        Names of the nx state entries; those starting with ``theta`` are wrapped.

    Returns
    -------
    ndarray, shape (..., nx)
        A copy of ``dx`` with the angle differences [rad] in (-pi, pi]; other
        entries unchanged.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control import wrap_state_error
    >>> dx = [2 * np.pi + 0.1, -0.2, 7.0, 0.0]  # one full turn too many on theta1; rates are not angles
    >>> np.round(wrap_state_error(dx, ("theta1", "theta2", "omega1", "omega2")), 3)
    array([ 0.1, -0.2,  7. ,  0. ])
    """
    dx = np.array(dx, dtype=float)
    for i, n in enumerate(state_names):
        if n.startswith("theta"):
            dx[..., i] = -((-dx[..., i] + np.pi) % (2 * np.pi) - np.pi)
    return dx


def weight_matrix(W: Any, n: int, name: str, definite: bool) -> np.ndarray:
    """A validated symmetric (n, n) weight matrix.

    Parameters
    ----------
    W : None or array_like, shape (n, n) or (n,)
        The weight; None gives the identity, a length-n vector a diagonal.
    n : int
        Required size.
    name : str
        Name used in error messages (e.g. ``"Q"``).
    definite : bool
        Require positive definite (True) rather than positive semi-definite.

    Returns
    -------
    ndarray, shape (n, n)
        The weight as a float matrix.

    Raises
    ------
    ValueError
        Wrong shape or non-finite entries, not symmetric, or not positive
        (semi-)definite.
    """
    if W is None:
        return np.eye(n)
    W = np.atleast_2d(np.asarray(W, dtype=float))
    if W.shape == (1, n) or W.shape == (n, 1):
        W = np.diag(W.ravel())
    if W.shape != (n, n) or not np.all(np.isfinite(W)):
        raise ValueError(f"{name} must be a finite ({n}, {n}) matrix or a length-{n} diagonal, got shape {W.shape}")
    if not np.allclose(W, W.T, rtol=1e-12, atol=1e-12 * np.max(np.abs(W))):
        raise ValueError(f"{name} must be symmetric")
    lo = np.linalg.eigvalsh(W).min()
    if (definite and lo <= 0) or lo < -1e-12 * max(1.0, np.abs(W).max()):
        kind = "positive definite" if definite else "positive semi-definite"
        raise ValueError(f"{name} must be {kind}; its smallest eigenvalue is {lo:.3g}")
    return W


@checked()
def zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold discretization of (A, B): ``Ad = expm(A dt)`` and ``Bd = (int_0^dt expm(A s) ds) B``.

    Parameters
    ----------
    A : ndarray, shape (n, n)
        Continuous state matrix [1/s].
    B : ndarray, shape (n, m)
        Continuous input matrix.
    dt : float
        Hold (sample) time [s].

    Returns
    -------
    Ad : ndarray, shape (n, n)
        Discrete state matrix.
    Bd : ndarray, shape (n, m)
        Discrete input matrix for an input held over ``dt``.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control import zoh
    >>> A = np.array([[0.0, 1.0], [0.0, 0.0]])  # double integrator: position, velocity
    >>> B = np.array([[0.0], [1.0]])
    >>> Ad, Bd = zoh(A, B, 0.1)
    >>> np.round(Ad, 3), np.round(Bd, 4)  # exact: [[1, h], [0, 1]] and [h^2 / 2, h]
    (array([[1. , 0.1],
           [0. , 1. ]]), array([[0.005],
           [0.1  ]]))
    """
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    E = expm(M * dt)
    return E[:n, :n], E[:n, n:]


def actuation_name(actuation: str | Sequence[str]) -> str:
    """Actuation name from a name or from the driven input names.

    Parameters
    ----------
    actuation : str or sequence of str
        ``"full"``, ``"pendubot"`` or ``"acrobot"``, or the driven inputs,
        e.g. ``("tau1",)`` (pendubot) or ``("tau1", "tau2")`` (full).

    Returns
    -------
    str
        ``"full"``, ``"pendubot"`` (tau1 only) or ``"acrobot"`` (tau2 only).

    Raises
    ------
    ValueError
        Unknown name or not a non-empty set of ("tau1", "tau2").

    Examples
    --------
    >>> from pendulab.control import actuation_name
    >>> actuation_name(("tau1",)), actuation_name(("tau2",)), actuation_name(("tau1", "tau2"))
    ('pendubot', 'acrobot', 'full')
    >>> actuation_name("acrobot")  # a name is checked and passed through
    'acrobot'
    """
    if isinstance(actuation, str):
        check_actuation(actuation)
        return actuation
    names = tuple(actuation)
    idx = tuple(sorted({INPUT_NAMES.index(n) for n in names if n in INPUT_NAMES}))
    if not names or len(idx) != len(names):
        raise ValueError(f"actuation input names must be a non-empty subset of {list(INPUT_NAMES)}, got {names!r}")
    return next(a for a, cols in ACTUATIONS.items() if cols == idx)


def _cost_to_go(Acl: np.ndarray, Qcl: np.ndarray, dt: float | None, P_ctrl: np.ndarray) -> np.ndarray:
    """Closed-loop cost-to-go (Lyapunov); ``P_ctrl`` (controllable part) when an undamped mode makes it infinite."""
    ev = np.linalg.eigvals(Acl)
    finite = np.all(np.abs(ev) < 1 - 1e-9) if dt is not None else np.all(ev.real < -1e-9 * max(1.0, np.abs(ev).max()))
    if not finite:
        return P_ctrl
    if dt is None:
        P = solve_continuous_lyapunov(Acl.T, -Qcl)
    else:
        P = solve_discrete_lyapunov(Acl.T, Qcl)
    return 0.5 * (P + P.T)


@checked()
def lqr_balance(
    model: Model,
    actuation: str | Sequence[str] = "full",
    Q: Any = None,
    R: Any = None,
    dt: float | None = None,
    *,
    at: str | Equilibrium | np.ndarray = "up-up",
    allow_non_equilibrium: bool = False,
) -> LQRDesign:
    """Linear-quadratic regulator about an equilibrium (default: balancing upright).

    Minimizes ``int (dx' Q dx + du' R du) dt`` (continuous) or the sampled sum
    (discrete, zero-order hold with sample time ``dt``) for the exact
    linearization.

    Parameters
    ----------
    model : Model
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
    Q : array_like, shape (nx, nx) or (nx,), optional
        State weight (diagonal if 1-D); default identity.
    R : array_like, shape (m, m) or (m,), optional
        Input weight [1/(N.m)^2]; default identity.
    dt : float, optional
        Sample time [s] for a discrete gain (co-simulation); ``None`` for continuous.
    at : str, Equilibrium or array_like of shape (nx,)
        Equilibrium name (zero torque), a solved :class:`Equilibrium`, or a
        state held with zero torque (e.g. a swing-up goal); a state must be an
        equilibrium under zero torque.
    allow_non_equilibrium : bool
        Design on the Jacobians at a state that is not an equilibrium (the
        regulator then fights the drift ``f(x, 0)`` with a steady error)
        instead of raising.

    Returns
    -------
    LQRDesign

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Unknown actuation or equilibrium name; bad Q, R or dt; ``at`` is a state
        that is not an equilibrium (the message names ``|f(x, u)|``).
    UncontrollableError
        An uncontrollable mode is unstable or a drift (the configuration cannot be balanced).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import lqr_balance
    >>> design = lqr_balance(pl.rigid(), "pendubot", Q=[10.0, 10.0, 1.0, 1.0])
    >>> np.round(design.K, 1)  # N.m per rad and per rad/s
    array([[  -0.3, -135.1,  -23.4,  -39.9]])
    >>> bool(np.all(design.closed_loop_eigenvalues.real < 0))  # stable upright
    True
    >>> sampled = lqr_balance(pl.rigid(), "pendubot", dt=0.02)  # discrete design for a 20 ms controller
    >>> bool(np.all(np.abs(sampled.closed_loop_eigenvalues) < 1))
    True
    >>> np.round(np.abs(lqr_balance(pl.elastic()).uncontrollable_eigenvalues), 2)  # springs left ringing [rad/s]
    array([36.18, 36.18, 13.82, 13.82])
    """
    check_model(model)
    actuation = actuation_name(actuation)
    if isinstance(at, str):
        eq: Equilibrium | np.ndarray = equilibrium(model, at)
    elif isinstance(at, Equilibrium):
        eq = at
    elif isinstance(at, (np.ndarray, list, tuple)):
        eq = model.check_state(at, "at")
        if eq.ndim != 1:
            raise ValueError(f"at must be a single state of shape ({model.nx},), got shape {eq.shape}")
    else:
        raise ValueError(f"at must be an equilibrium name, an Equilibrium or a state, got {at!r}")
    x_eq, u_eq, eq_name = (eq.x, eq.u, eq.name) if isinstance(eq, Equilibrium) else (eq, np.zeros(model.nu), "goal")
    if dt is not None and not (isinstance(dt, (int, float)) and np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive sample time in seconds or None, got {dt!r}")
    lin = linearize(model, x_eq, u_eq, inputs=actuation)
    if not lin.is_equilibrium and not allow_non_equilibrium:
        raise not_equilibrium_error("lqr_balance", lin)
    n, m = lin.B.shape
    Qm = weight_matrix(Q, n, "Q", definite=False)
    Rm = weight_matrix(R, m, "R", definite=True)
    Qc, Qu = controllable_subspace(lin.A, lin.B)
    unc = np.linalg.eigvals(Qu.T @ lin.A @ Qu) if Qu.shape[1] else np.zeros(0, dtype=complex)
    scale = max(1.0, float(np.max(np.abs(lin.eigenvalues))))
    bad = unc[(unc.real > 1e-7 * scale) | (np.abs(unc) <= 1e-7 * scale)]
    if bad.size:
        raise UncontrollableError(
            f"uncontrollable configuration: {model.kind} model with actuation {actuation!r} at {eq_name!r} has "
            f"controllability rank {Qc.shape[1]} of {n}, and the uncontrollable eigenvalue(s) "
            f"{np.round(bad, 6).tolist()} [1/s] are unstable or a drift; LQR cannot stabilize them "
            f"(try another actuation or equilibrium)"
        )
    Ar, Br, Qr = Qc.T @ lin.A @ Qc, Qc.T @ lin.B, Qc.T @ Qm @ Qc
    Qr = 0.5 * (Qr + Qr.T)  # exact symmetry for the Riccati solvers
    if dt is None:
        Kr, Sr, _ = ct.lqr(Ar, Br, Qr, Rm)
        K = np.asarray(Kr) @ Qc.T
        Acl = lin.A - lin.B @ K
    else:
        Ad, Bd = zoh(Ar, Br, float(dt))
        Kr, Sr, _ = ct.dlqr(Ad, Bd, Qr, Rm)
        K = np.asarray(Kr) @ Qc.T
        Afd, Bfd = zoh(lin.A, lin.B, float(dt))
        Acl = Afd - Bfd @ K
    P = _cost_to_go(Acl, Qm + K.T @ Rm @ K, dt, Qc @ np.asarray(Sr) @ Qc.T)
    return LQRDesign(
        K=K,
        x_eq=np.array(x_eq, dtype=float),
        u_eq=np.array(u_eq, dtype=float),
        actuation=actuation,
        input_indices=lin.input_indices,
        Q=Qm,
        R=Rm,
        dt=None if dt is None else float(dt),
        closed_loop_eigenvalues=np.linalg.eigvals(Acl),
        uncontrollable_eigenvalues=unc,
        equilibrium=eq_name,
        state_names=lin.state_names,
        input_names=lin.input_names,
        kind=model.kind,
        P=P,
    )


@checked()
def discrete_tvlqr(
    model: Model,
    x_lin: Any,
    u_lin: Any,
    dt: float,
    Q: np.ndarray,
    R: np.ndarray,
    P_final: np.ndarray,
    actuation: str | Sequence[str] = "full",
) -> np.ndarray:
    """Time-varying discrete LQR gains by the backward Riccati recursion on exact ZOH linearizations.

    Interval ``k`` (length ``dt``) is linearized at ``(x_lin[k], u_lin[k])``
    with the exact Jacobians and discretized for the hold (:func:`zoh`); the
    recursion starts from the terminal cost-to-go ``P_final``.

    Parameters
    ----------
    model : Model
    x_lin : array_like, shape (M, nx)
        Linearization states, one per interval.
    u_lin : array_like, shape (M, 2)
        Held torques (tau1, tau2) [N.m], one per interval.
    dt : float
        Interval length [s].
    Q : ndarray, shape (nx, nx)
        Stage state weight.
    R : ndarray, shape (m, m)
        Stage weight on the driven torques.
    P_final : ndarray, shape (nx, nx)
        Terminal cost-to-go (e.g. :attr:`LQRDesign.P` of the hand-over LQR).
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        Driven torques (m of them).

    Returns
    -------
    ndarray, shape (M, m, nx)
        Gains: ``u_k = u_lin[k] - K[k] (x_k - x_ref_k)`` on the driven torques.

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import discrete_tvlqr, lqr_balance
    >>> model = pl.rigid()
    >>> top = lqr_balance(model, "pendubot", dt=0.01)  # discrete LQR upright: its cost-to-go ends the recursion
    >>> x_lin, u_lin = np.tile(top.x_eq, (50, 1)), np.zeros((50, 2))  # 0.5 s of "reference" resting upright
    >>> K = discrete_tvlqr(model, x_lin, u_lin, 0.01, top.Q, top.R, top.P, actuation="pendubot")
    >>> K.shape  # (intervals, driven torques, states)
    (50, 1, 4)
    >>> bool(np.allclose(K, top.K))  # at an equilibrium the recursion stays at the stationary LQR gain
    True
    """
    check_model(model)
    As, Bs = linearize_along(model, x_lin, u_lin, inputs=actuation_name(actuation))
    M, nx, m = Bs.shape
    P = np.asarray(P_final, dtype=float)
    K = np.empty((M, m, nx))
    for k in range(M - 1, -1, -1):
        Ad, Bd = zoh(As[k], Bs[k], dt)
        BtP = Bd.T @ P
        K[k] = np.linalg.solve(R + BtP @ Bd, BtP @ Ad)
        P = Q + Ad.T @ P @ (Ad - Bd @ K[k])
        P = 0.5 * (P + P.T)
    return K

"""Equilibria of the double pendulum under a constant torque, found by Newton.

The four branches are named by where each link points: ``"down-down"``,
``"down-up"``, ``"up-down"``, ``"up-up"`` (link 1 first). With zero torque the
links hang or stand vertically (the elastic springs at their static stretch);
a constant torque tilts them ("arm held at an angle"). Seeds come from the
static balance of gravity and torque; CasADi's Newton rootfinder then solves
``qdd(q, qd=0, u) = 0`` on the model's own right-hand side, so the seeds only
need to be close.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from typing import Any

import casadi as ca
import numpy as np

from .._checks import check_model
from .._inputs import checked
from ..model.model import Model, model_functions
from ..model.statics import static_spring_lengths

__all__ = ["Equilibrium", "EquilibriumNotFoundError", "EQUILIBRIUM_NAMES", "equilibria", "equilibrium"]

#: Branch names, link 1 first: which way each link points.
EQUILIBRIUM_NAMES: tuple[str, ...] = ("down-down", "down-up", "up-down", "up-up")


@dataclass(frozen=True)
class Equilibrium:
    """One equilibrium of a model under a constant torque.

    Attributes
    ----------
    name : str
        One of ``EQUILIBRIUM_NAMES``.
    x : ndarray, shape (nx,)
        Equilibrium state (velocities zero; for the elastic model the spring
        lengths include the static stretch).
    u : ndarray, shape (2,)
        Constant torques (tau1, tau2) [N.m] that hold it.
    eigenvalues : ndarray of complex, shape (nx,)
        Eigenvalues of the linearization [1/s], sorted by decreasing real part.
    n_unstable : int
        Number of eigenvalues with positive real part (unstable modes).
    kind : str
        Model kind.
    state_names : tuple of str

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> eq = pl.equilibrium(pl.rigid(), "up-up")
    >>> eq
    Equilibrium('up-up', rigid, theta1=3.14159, theta2=3.14159, u=[0.0, 0.0], unstable (2 modes))
    >>> eq.n_unstable, eq.stable
    (2, False)
    >>> np.round(eq.eigenvalues.real, 3)  # two growth and two decay rates [1/s]
    array([ 5.787,  2.397, -2.397, -5.787])
    """

    name: str
    x: np.ndarray
    u: np.ndarray
    eigenvalues: np.ndarray
    n_unstable: int
    kind: str
    state_names: tuple[str, ...]

    @property
    def stable(self) -> bool:
        """True when no eigenvalue has a positive real part.

        Without damping the stable branch is an energy minimum with purely
        imaginary eigenvalues (Lyapunov stable); with damping it is
        asymptotically stable.
        """
        return self.n_unstable == 0

    @property
    def stability(self) -> str:
        """``"stable"`` or ``"unstable (n modes)"``."""
        return "stable" if self.stable else f"unstable ({self.n_unstable} mode{'s' if self.n_unstable > 1 else ''})"

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly summary of the equilibrium.

        Returns
        -------
        dict
            ``name``, ``kind``, ``state`` by name (SI units), ``u`` as
            ``{"tau1", "tau2"}`` [N.m], ``stable``, ``n_unstable`` and
            ``eigenvalues`` as a list of [re, im] [1/s].
        """
        return {
            "name": self.name,
            "kind": self.kind,
            "state": dict(zip(self.state_names, self.x.tolist(), strict=True)),
            "u": {"tau1": float(self.u[0]), "tau2": float(self.u[1])},
            "stable": self.stable,
            "n_unstable": self.n_unstable,
            "eigenvalues": [[float(e.real), float(e.imag)] for e in self.eigenvalues],
        }

    def __repr__(self) -> str:
        nq = len(self.state_names) // 2
        state = ", ".join(f"{n}={v:.6g}" for n, v in zip(self.state_names[:nq], self.x[:nq], strict=True))
        return f"Equilibrium({self.name!r}, {self.kind}, {state}, u={self.u.tolist()}, {self.stability})"


@cache
def _solver(kind: str) -> tuple[ca.Function, ca.Function]:
    """Newton rootfinder on the accelerations, and the potential gradient (per model kind)."""
    rhs = model_functions(kind)["rhs"]
    potential = model_functions(kind)["potential"]
    nx, nu, npar = rhs.size1_in(0), rhs.size1_in(1), rhs.size1_in(2)
    nq = nx // 2
    q = ca.SX.sym("q", nq)
    u = ca.SX.sym("u", nu)
    p = ca.SX.sym("p", npar)
    x = ca.vertcat(q, ca.SX.zeros(nq))
    residual = ca.Function("static_residual", [q, u, p], [rhs(x, u, p)[nq:]])
    newton = ca.rootfinder(
        "equilibrium",
        "newton",
        residual,
        {"abstol": 1e-13, "abstolStep": 1e-15, "max_iter": 50, "error_on_fail": True},
    )
    xs = ca.SX.sym("x", nx)
    grad_v = ca.Function("grad_V", [xs, p], [ca.gradient(potential(xs, p), xs)])
    return newton, grad_v


class EquilibriumNotFoundError(ValueError, RuntimeError):
    """Newton did not converge to the named equilibrium (a ``ValueError`` of the inputs, and a ``RuntimeError`` as before)."""


class _SpringsTooSoftError(ValueError):
    """The branch would need a non-positive spring length: it does not exist."""


def _check_name(name: Any) -> str:
    if not isinstance(name, str) or name not in EQUILIBRIUM_NAMES:
        raise ValueError(f"unknown equilibrium name {name!r}; expected one of {list(EQUILIBRIUM_NAMES)}")
    return name


def _seed(model: Model, name: str, u: np.ndarray, grad_v: ca.Function) -> np.ndarray:
    """Static balance of gravity and torque: dV/dtheta = generalized torque (tau1 - tau2, tau2)."""
    base = model.rest_state()
    amplitude = []
    for j in range(2):
        probe = base.copy()
        probe[j] = math.pi / 2  # gravity torque on link j is largest when it is horizontal
        amplitude.append(float(np.asarray(grad_v(probe, model.p))[j, 0]))
    gen_torque = (u[0] - u[1], u[1])
    q = base[: model.nq].copy()
    for j, (a, tau, side) in enumerate(zip(amplitude, gen_torque, name.split("-"), strict=True)):
        if model.params.g <= 0.0:
            raise ValueError(f"g = {model.params.g!r}: without gravity every configuration is an equilibrium; expected g > 0")
        if a <= 1e-12 * model.params.g and tau == 0.0:
            # Centre of mass on the joint: the link balances at any angle; keep the named one.
            q[j] = 0.0 if side == "down" else math.pi
            continue
        s = float(tau) / float(a) if a > 0.0 else math.copysign(math.inf, tau)  # floats: an overflow is inf, not a warning
        if abs(s) > 1.0:
            raise ValueError(
                f"u = {u.tolist()}: the generalized torque {tau:.6g} N.m on link {j + 1} exceeds the largest "
                f"gravity torque {a:.6g} N.m it can balance; no equilibrium exists"
            )
        q[j] = math.asin(s) if side == "down" else math.pi - math.asin(s)
    if model.kind == "elastic":
        q[2:4] = static_spring_lengths(model.params, q[0:2])
    return q


@checked()
def equilibrium(model: Model, name: str, u: Any = None) -> Equilibrium:
    """Solve for one named equilibrium.

    Parameters
    ----------
    model : Model
    name : {"down-down", "down-up", "up-down", "up-up"}
        Which way link 1 and link 2 point.
    u : array_like, shape (2,), optional
        Constant torques (tau1, tau2) [N.m]; default zero.

    Returns
    -------
    Equilibrium

    Raises
    ------
    ValueError
        Unknown name; ``u`` of the wrong size or non-finite; torque too large
        to be held by gravity; ``g = 0``; a spring too soft to hold the
        configuration (its length would not stay positive).
    EquilibriumNotFoundError
        Newton did not converge (a ``ValueError`` and a ``RuntimeError``).
    TypeError
        ``model`` is not a pendulab Model.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> eq = pl.equilibrium(pl.rigid(), "down-down", u=[1.0, 0.0])  # 1 N.m at the shoulder
    >>> np.round(eq.x, 5)  # link 1 deflected, link 2 hanging straight down, at rest
    array([0.05099, 0.     , 0.     , 0.     ])
    >>> print(f"{np.arcsin(1.0 / (2 * 9.81)):.5f}")  # tau1 = (m1 + m2) g L1 sin(theta1)
    0.05099
    >>> eq.stable
    True
    """
    check_model(model)
    name = _check_name(name)
    uv = model.check_input(u, "u")
    if uv.ndim != 1:
        raise ValueError(f"u must be a single input (tau1, tau2) of shape (2,), got shape {uv.shape}")
    newton, grad_v = _solver(model.kind)
    seed = _seed(model, name, uv, grad_v)
    if model.kind == "elastic" and np.any(seed[2:] <= 0.0):
        raise _SpringsTooSoftError(
            f"equilibrium {name!r} does not exist for {model.params}: the springs are too soft to hold it "
            f"(static lengths r = {seed[2:].tolist()} m are not positive); expected larger k1, k2"
        )
    try:
        q = np.asarray(newton(seed, uv, model.p), dtype=float).ravel()
    except RuntimeError as exc:
        raise EquilibriumNotFoundError(
            f"Newton did not converge to equilibrium {name!r} of the {model.kind} model under u = {uv.tolist()} from seed "
            f"{np.round(seed, 6).tolist()}; the torque may exceed what the links and springs can hold"
        ) from exc
    x = np.concatenate([q, np.zeros(model.nq)])
    if model.kind == "elastic" and np.any(q[2:] <= 0.0):
        raise _SpringsTooSoftError(
            f"equilibrium {name!r}: spring lengths {q[2:].tolist()} m are not positive; expected larger k1, k2"
        )
    # The exact Jacobian (what pendulab.linearize returns as A), evaluated here so that
    # linearize may depend on this module and not the other way round.
    A = np.asarray(model.functions["jac_rhs"](x, uv, model.p)[0], dtype=float)
    ev = np.linalg.eigvals(A)
    ev = ev[np.argsort(-ev.real, kind="stable")]
    # Undamped stable modes have eigenvalues on the imaginary axis; round-off gives them tiny real parts.
    tol = 1e-7 * max(1.0, float(np.max(np.abs(ev))))
    return Equilibrium(
        name=name,
        x=x,
        u=uv.copy(),
        eigenvalues=ev,
        n_unstable=int(np.sum(ev.real > tol)),
        kind=model.kind,
        state_names=model.state_names,
    )


@checked()
def equilibria(model: Model, u: Any = None) -> list[Equilibrium]:
    """All four equilibria of the model under a constant torque.

    Parameters
    ----------
    model : Model
    u : array_like, shape (2,), optional
        Constant torques (tau1, tau2) [N.m]; default zero.

    Returns
    -------
    list of Equilibrium
        In ``EQUILIBRIUM_NAMES`` order. Elastic branches whose springs are too
        soft to hold them (non-positive length) do not exist and are left out.

    Raises
    ------
    ValueError
        As :func:`equilibrium` (except for the too-soft-spring case).
    TypeError
        ``model`` is not a pendulab Model.

    Examples
    --------
    >>> import pendulab as pl
    >>> for eq in pl.equilibria(pl.rigid()):
    ...     print(eq.name, eq.stability)
    down-down stable
    down-up unstable (1 mode)
    up-down unstable (1 mode)
    up-up unstable (2 modes)

    Springs of 15 N/m cannot hold the 2 kg above them upright (that needs k1 > (m1 + m2) g / L1):

    >>> [eq.name for eq in pl.equilibria(pl.elastic(k1=15.0, k2=15.0))]
    ['down-down', 'down-up']
    """
    check_model(model)
    out = []
    for name in EQUILIBRIUM_NAMES:
        try:
            out.append(equilibrium(model, name, u))
        except _SpringsTooSoftError:
            continue
    return out

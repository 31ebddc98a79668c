"""The model levels of a scene, cheapest first: linearized, rigid, rigid + quasi-static, and the scene's own model.

Levels (all built from the scene's own model functions):

``linearized``
    The scene's model linearized about the nearest equilibrium (angles rounded
    to multiples of pi; spring lengths from :func:`quasi_static_state` at rest),
    propagated exactly on the output grid (modal solution of the linear ODE,
    zero-order-held torques); outputs through the nonlinear output map.
``rigid``
    The rigid counterpart (same m, L, g, joint dampers; links of the springs'
    rest length), started from the scene's angles and rates.
``rigid+quasi-static``
    The rigid motion with quasi-static spring lengths r*(theta, omega) (the
    springs' static and centrifugal stretch, zero radial acceleration) added
    afterwards, without their fast dynamics.
``elastic`` (``rigid`` for a rigid scene)
    The scene's own model: the reference.

Every level produces a state trajectory in the scene model's state order on
the scene's output grid, so errors are measured on the scene's outputs against
the reference. The a priori rule (:mod:`pendulab.scene.choice`) predicts each
level's error; the a posteriori study (:mod:`pendulab.bench.hierarchy`) runs them all.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.signal import lfilter

from ..integrate import simulate, time_grid
from ..integrate.trajectory import Trajectory
from ..model.counterpart import rigid_counterpart
from ..model.model import Model
from ..model.quasistatic import quasi_static_lengths, quasi_static_state
from .core import Scene

__all__ = [
    "LEVELS",
    "ModelLevel",
    "LinearSolution",
    "levels_for",
    "linear_solution",
    "scene_signals",
    "level_trajectory",
    "nearest_equilibrium",
]

#: Level names, cheapest first (a rigid scene has ``linearized`` and ``rigid`` only).
LEVELS: tuple[str, ...] = ("linearized", "rigid", "rigid+quasi-static", "elastic")


@dataclass(frozen=True)
class ModelLevel:
    """One level of the hierarchy: a way to compute the scene's trajectory.

    Attributes
    ----------
    name : str
        One of ``LEVELS``.
    model : Model
        The model it integrates (rigid for ``rigid`` and ``rigid+quasi-static``).
    run : callable
        ``run(scene) -> ndarray (N, nx)``: states in the scene model's state order.
    """

    name: str
    model: Model
    run: Callable[[Any], np.ndarray] = field(repr=False)

    def simulate(self, scene: Scene) -> Trajectory:
        """Trajectory of the scene with this level, in the scene model's signals.

        Parameters
        ----------
        scene : Scene
            The scene (model, start, horizon, output step, torques).

        Returns
        -------
        Trajectory
            States in the scene model's state order on the scene's output
            grid, with the scene's torques and the scene model's outputs.
        """
        return level_trajectory(scene, self.run(scene), self.name)


def _angles_rates(model: Model, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    names = model.state_names
    th = x[..., [names.index("theta1"), names.index("theta2")]]
    om = x[..., [names.index("omega1"), names.index("omega2")]]
    return th, om


def nearest_equilibrium(model: Model, x0: np.ndarray) -> np.ndarray:
    """The equilibrium nearest to ``x0``: angles rounded to multiples of pi, at rest, springs quasi-static.

    Parameters
    ----------
    model : Model
        Rigid or elastic model.
    x0 : ndarray, shape (nx,)
        State in ``model.state_names`` order.

    Returns
    -------
    ndarray, shape (nx,)
        The unforced equilibrium state.
    """
    th, _ = _angles_rates(model, np.asarray(x0, dtype=float))
    th_eq = np.pi * np.round(th / np.pi)
    if not np.any(th_eq):  # hanging: the rest state (springs at their static, i.e. quasi-static, lengths)
        return model.rest_state()
    if model.kind == "elastic":
        return quasi_static_state(model, th_eq)
    return np.concatenate([th_eq, np.zeros(2)])


@dataclass(frozen=True)
class LinearSolution:
    """The linearized level's solution and what the a priori rule needs from it.

    Attributes
    ----------
    x : ndarray, shape (N, nx)
        States on the scene's output grid.
    x_eq : ndarray, shape (nx,)
        The equilibrium linearized about.
    A, b : ndarray
        ``dx/dt = A (x - x_eq) + b + B u_sine(t)``: Jacobian (nx, nx) [1/s] and constant term (nx,)
        (the constant torques included).
    eigenvalues : ndarray, shape (nx,)
        Eigenvalues of ``A`` [1/s] (complex).
    eigenvectors : ndarray, shape (nx, nx) or None
        Their eigenvectors (columns); None when ``A`` is defective.
    B : ndarray, shape (nx, nu), or None
        Input Jacobian [1/(kg m^2)], with a sine input only.
    u_sine : ndarray, shape (N, nu), or None
        The sine part of the torques on the output grid [N.m] (``[input.sine]``), else None.
    """

    x: np.ndarray
    x_eq: np.ndarray
    A: np.ndarray
    b: np.ndarray
    eigenvalues: np.ndarray
    eigenvectors: np.ndarray | None = None
    B: np.ndarray | None = None
    u_sine: np.ndarray | None = None

    def forcing(self, idx: np.ndarray) -> np.ndarray:
        """The forcing ``b + B u_sine(t)`` of the linear model at some grid points.

        Parameters
        ----------
        idx : ndarray of int, shape (M,)
            Indices into the output grid.

        Returns
        -------
        ndarray, shape (M, nx)
            The forcing [state units / s].
        """
        if self.u_sine is None or self.B is None:
            return np.broadcast_to(self.b, (len(idx), len(self.b)))
        return self.b + self.u_sine[idx] @ self.B.T


def _phi(z: np.ndarray) -> np.ndarray:
    """(e^z - 1) / z, with its limit 1 at z = 0."""
    small = np.abs(z) < 1e-8
    return np.where(small, 1.0 + z / 2, np.expm1(z) / np.where(small, 1.0, z))


def linear_solution(scene: Scene) -> LinearSolution:
    """Solve the scene's model linearized about the nearest equilibrium, exactly, on the output grid.

    With ``A = V diag(lambda) V^-1`` the modal solution is evaluated at every
    grid time at once (no time stepping); a defective ``A`` (condition of ``V``
    above 1e8) falls back to the matrix exponential of one step. A sine input
    (``[input.sine]``) is held exactly as the reference run holds it
    (:meth:`Scene.input_spec`: the sine's value at the middle of each hold), and
    the modal solution is propagated exactly over each hold.

    Parameters
    ----------
    scene : Scene
        The scene.

    Returns
    -------
    LinearSolution
    """
    model = scene.model
    x_eq = nearest_equilibrium(model, np.asarray(scene.x0))
    u0 = np.zeros(model.nu)
    A, B = (np.asarray(m, dtype=float) for m in model.functions["jac_rhs"](x_eq, u0, model.p))
    u = u0 if scene.u is None else np.asarray(scene.u, dtype=float)
    b = B @ u + model.rhs(x_eq, u0)  # f(x_eq) is zero at an equilibrium; kept so a slight offset is exact
    t = time_grid(scene.t_final, scene.dt)
    dx0 = np.asarray(scene.x0, dtype=float) - x_eq
    lam, V = np.linalg.eig(A)
    diagonalizable = bool(np.linalg.cond(V) < 1e8)
    if getattr(scene, "u_amplitude", None) is not None:
        X, u_sine = _held_sine_solution(scene, t, A, B, b, dx0, lam, V if diagonalizable else None)
        return LinearSolution(X + x_eq, x_eq, A, b, lam, V if diagonalizable else None, B, u_sine)
    if diagonalizable:
        Vi = np.linalg.inv(V)
        z = np.outer(t, lam)
        Z = np.exp(z) * (Vi @ dx0) + (t[:, None] * _phi(z)) * (Vi @ b)
        X = np.real(Z @ V.T)
    else:  # defective: one exact step, repeated
        X = _stepped(A, np.broadcast_to(b, (len(t) - 1, len(b))), dx0, float(t[1] - t[0]))
    return LinearSolution(X + x_eq, x_eq, A, b, lam, V if diagonalizable else None)


def _stepped(A: np.ndarray, W: np.ndarray, dx0: np.ndarray, h: float) -> np.ndarray:
    """``dx/dt = A dx + w_k`` held over steps of ``h``, exactly (matrix exponential): states (len(W) + 1, nx)."""
    from scipy.linalg import expm

    n = len(dx0)
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n], M[:n, n:] = A, np.eye(n)
    E = expm(M * h)
    X = np.empty((len(W) + 1, n))
    X[0] = dx = dx0
    for k, w in enumerate(W):
        dx = E[:n, :n] @ dx + E[:n, n:] @ w
        X[k + 1] = dx
    return X


def _held_sine_solution(
    scene: Scene, t: np.ndarray, A: np.ndarray, B: np.ndarray, b: np.ndarray, dx0: np.ndarray, lam: np.ndarray, V: Any
) -> tuple[np.ndarray, np.ndarray]:
    """States (N, nx) relative to the equilibrium and the sine torques (N, nu) on the output grid ``t``."""
    spec = scene.input_spec()
    tg = spec.hold_grid(t)
    sub = (len(tg) - 1) // (len(t) - 1)  # holds per output interval
    h = float(tg[1] - tg[0])
    mid = 0.5 * (tg[:-1] + tg[1:])
    u_const = np.zeros(scene.model.nu) if scene.u is None else np.asarray(scene.u, dtype=float)
    U = np.asarray(spec.func(mid), dtype=float) - u_const  # the sine part, held at each hold's middle
    W = b + U @ B.T  # forcing over each hold, (M, nx)
    if V is None:
        X = _stepped(A, W, dx0, h)
    else:
        Vi = np.linalg.inv(V)
        z0, Wm = Vi @ dx0, W @ Vi.T  # modal start and forcing
        mu = np.exp(lam * h)
        gain = h * _phi(lam * h)
        Z = np.empty((len(tg), len(lam)), dtype=complex)
        Z[0] = z0
        for j in range(len(lam)):  # z[k+1] = mu z[k] + gain w[k], one recursion per mode (lfilter)
            Z[1:, j] = lfilter([1.0], [1.0, -mu[j]], gain[j] * Wm[:, j], zi=[mu[j] * z0[j]])[0]
        X = np.real(Z @ V.T)
    t_sine = np.sin(2 * np.pi * scene.u_frequency * t)
    return X[::sub], np.outer(t_sine, scene.u_amplitude)


def _run_linearized(scene: Scene) -> np.ndarray:
    return linear_solution(scene).x


def _scene_input(scene: Scene) -> Any:
    """The scene's torques for :func:`simulate`: defined in time when the scene has a sine (``Scene.input_spec``)."""
    spec = getattr(scene, "input_spec", None)
    return spec() if callable(spec) else scene.u


def _run_rigid_states(scene: Scene) -> np.ndarray:
    """The rigid counterpart's states (theta1, theta2, omega1, omega2) on the scene grid."""
    th, om = _angles_rates(scene.model, np.asarray(scene.x0))
    rm = rigid_counterpart(scene.model)
    return simulate(
        rm, np.concatenate([th, om]), scene.t_final, scene.dt, scene.method, scene.rtol, scene.atol, _scene_input(scene)
    ).x


def _embed(model: Model, th: np.ndarray, om: np.ndarray, r: np.ndarray | None) -> np.ndarray:
    """Rigid (theta, omega) as states of ``model`` (springs at length r, v = 0)."""
    if model.kind == "rigid":
        return np.hstack([th, om])
    if r is None:
        r = np.tile([model.params.L1, model.params.L2], (th.shape[0], 1))
    return np.hstack([th, r, om, np.zeros_like(r)])


def _run_rigid(scene: Scene) -> np.ndarray:
    X = _run_rigid_states(scene)
    return _embed(scene.model, X[:, :2], X[:, 2:], None)


def _run_rigid_qs(scene: Scene) -> np.ndarray:
    X = _run_rigid_states(scene)
    r = quasi_static_lengths(scene.model, X[:, :2], X[:, 2:], scene.u)  # constant part of the torques
    return _embed(scene.model, X[:, :2], X[:, 2:], r)


def _run_full(scene: Scene) -> np.ndarray:
    return simulate(scene.model, scene.x0, scene.t_final, scene.dt, scene.method, scene.rtol, scene.atol, _scene_input(scene)).x


def levels_for(model: Model) -> tuple[ModelLevel, ...]:
    """The hierarchy for a scene model, cheapest first; the last level is the reference.

    Parameters
    ----------
    model : Model
        The scene's model.

    Returns
    -------
    tuple of ModelLevel
        Rigid model: ``linearized``, ``rigid`` (the reference). Elastic model:
        ``linearized``, ``rigid``, ``rigid+quasi-static``, ``elastic``.
    """
    if model.kind == "rigid":
        return (ModelLevel("linearized", model, _run_linearized), ModelLevel("rigid", model, _run_full))
    rm = rigid_counterpart(model)
    return (
        ModelLevel("linearized", model, _run_linearized),
        ModelLevel("rigid", rm, _run_rigid),
        ModelLevel("rigid+quasi-static", rm, _run_rigid_qs),
        ModelLevel("elastic", model, _run_full),
    )


def scene_signals(scene: Scene, X: np.ndarray) -> dict[str, np.ndarray]:
    """The scene's outputs along states ``X`` (scene model's state order).

    Parameters
    ----------
    scene : Scene
        The scene (its model, outputs and torques).
    X : ndarray, shape (N, nx)
        States on the scene's output grid.

    Returns
    -------
    dict of str to ndarray, shape (N,)
        One series per name of ``scene.outputs``, in its unit.
    """
    model = scene.model
    U = scene.inputs() if getattr(scene, "u_amplitude", None) is not None else None
    u = np.zeros(model.nu) if scene.u is None else np.asarray(scene.u, dtype=float)
    if U is None:
        U = np.tile(u, (X.shape[0], 1))
    Y = None
    out: dict[str, np.ndarray] = {}
    for name in scene.outputs:
        group, i = model.signal_index(name)
        if group == "state":
            out[name] = X[:, i]
        elif group == "input":
            out[name] = U[:, i]
        else:
            if Y is None:
                Y = model.outputs(X, U)
            out[name] = Y[:, i]
    return out


def level_trajectory(scene: Scene, X: np.ndarray, level: str) -> Trajectory:
    """A level's states as a :class:`Trajectory` in the scene model's signals.

    Parameters
    ----------
    scene : Scene
        The scene.
    X : ndarray, shape (N, nx)
        States on the scene's output grid (scene model's state order).
    level : str
        Level name, recorded in ``method`` and ``message``.

    Returns
    -------
    Trajectory
    """
    model = scene.model
    U = scene.inputs() if getattr(scene, "u_amplitude", None) is not None else None
    if U is None:
        u = np.zeros(model.nu) if scene.u is None else np.asarray(scene.u, dtype=float)
        U = np.tile(u, (X.shape[0], 1))
    return Trajectory(
        t=time_grid(scene.t_final, scene.dt),
        x=X,
        u=U,
        y=model.outputs(X, U),
        state_names=model.state_names,
        input_names=model.input_names,
        output_names=model.output_names,
        method=f"{level} ({scene.method})",
        success=True,
        message=f"model level {level!r}",
        stats={},
    )

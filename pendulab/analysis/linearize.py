"""Exact linearization: A, B, C, D from CasADi Jacobians at any operating point.

The Jacobians come from the model's own CasADi Functions (``rhs``, ``outputs``)
evaluated on fresh symbols, so no physics is re-typed here. Outputs are chosen
by name: model states, model outputs (positions, energy, spring stretch) or the
groups ``"states"``, ``"positions"``, ``"energy"``, ``"stretch"``, ``"outputs"``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

import casadi as ca
import numpy as np

from .._checks import check_model
from .._inputs import checked
from ..model.model import ACTUATIONS, INPUT_NAMES, Model, make_model, model_functions
from .equilibria import Equilibrium

__all__ = [
    "Linearization",
    "OutputSpec",
    "linearize",
    "linearize_along",
    "resolve_outputs",
    "check_actuation",
    "operating_point",
    "selected_outputs",
    "equilibrium_residual",
    "EQUILIBRIUM_RTOL",
    "not_equilibrium_error",
]

#: Relative tolerance of the equilibrium test: a point is an equilibrium when every state derivative
#: ``|f_i(x, u)|`` is at most ``EQUILIBRIUM_RTOL * (1 + sum_j |A_ij| |x_j|)``, i.e. no larger than what a
#: relative perturbation of 1e-6 of the state would produce (round-off of a solved equilibrium is ~1e-15).
EQUILIBRIUM_RTOL = 1e-6

OutputSpec = str | Sequence[str]

_OUTPUT_GROUPS = ("states", "positions", "energy", "stretch", "outputs")


@dataclass(frozen=True)
class Linearization:
    """Linear model ``d(dx)/dt = A dx + B du``, ``dy = C dx + D du`` about an operating point.

    ``dx = x - x0``, ``du`` the actuated torques minus their operating values,
    ``dy = y - y0``.

    Attributes
    ----------
    A : ndarray, shape (nx, nx)
    B : ndarray, shape (nx, nu_act)
        Columns are the actuated inputs only (``input_names``).
    C : ndarray, shape (ny, nx)
    D : ndarray, shape (ny, nu_act)
    x0 : ndarray, shape (nx,)
        Operating-point state (SI units).
    u0 : ndarray, shape (2,)
        Operating-point torques (tau1, tau2) [N.m], both inputs even when only
        one is actuated.
    y0 : ndarray, shape (ny,)
        Outputs at the operating point.
    state_names, input_names, output_names : tuple of str
    actuation : {"full", "pendubot", "acrobot"}
    kind : {"rigid", "elastic"}
    input_indices : tuple of int
        Positions of the actuated inputs in (tau1, tau2).
    residual : float
        ``max_i |f_i(x0, u0)|`` [SI units of the state derivatives]: zero at an
        equilibrium up to round-off.
    is_equilibrium : bool
        True when ``(x0, u0)`` passes the equilibrium test of
        :func:`equilibrium_residual`. A linearization about a non-equilibrium
        (along a trajectory) is legitimate, but its deviation model lacks the
        drift ``f(x0, u0)``: ``modes``, ``to_statespace`` and ``lqr_balance``
        refuse such a point.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid()
    >>> lin = pl.linearize(model, pl.equilibrium(model, "up-up"), inputs="pendubot", outputs="positions")
    >>> lin.A.shape, lin.B.shape, lin.C.shape, lin.D.shape
    ((4, 4), (4, 1), (4, 4), (4, 1))
    >>> lin.input_names, lin.output_names
    (('tau1',), ('x1', 'y1', 'x2', 'y2'))
    >>> lin.is_equilibrium, np.round(np.sort(lin.eigenvalues.real), 3)
    (True, array([-5.787, -2.397,  2.397,  5.787]))
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    x0: np.ndarray
    u0: np.ndarray
    y0: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    actuation: str
    kind: str
    input_indices: tuple[int, ...]
    residual: float = 0.0
    is_equilibrium: bool = True

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of A [1/s], shape (nx,)."""
        return np.linalg.eigvals(self.A)

    def __repr__(self) -> str:
        return (
            f"Linearization({self.kind}, actuation={self.actuation!r}, states={list(self.state_names)}, "
            f"inputs={list(self.input_names)}, outputs={list(self.output_names)}"
            + ("" if self.is_equilibrium else f", not an equilibrium: |f(x0, u0)| = {self.residual:.3g}")
            + ")"
        )


def check_actuation(actuation: Any) -> tuple[int, ...]:
    """Indices into (tau1, tau2) of the torques driven by an actuation.

    Parameters
    ----------
    actuation : {"full", "pendubot", "acrobot"}
        Both torques, ``tau1`` only (pendubot) or ``tau2`` only (acrobot).

    Returns
    -------
    tuple of int
        ``(0, 1)``, ``(0,)`` or ``(1,)``.

    Raises
    ------
    ValueError
        ``actuation`` is not one of the names above.
    """
    if not isinstance(actuation, str) or actuation not in ACTUATIONS:
        raise ValueError(f"unknown actuation {actuation!r}; expected one of {list(ACTUATIONS)}")
    return ACTUATIONS[actuation]


@checked()
def resolve_outputs(model: Model, outputs: OutputSpec) -> tuple[str, ...]:
    """Expand an output specification into signal names.

    Parameters
    ----------
    model : Model
        Model whose states and outputs are named.
    outputs : str or sequence of str
        ``"states"`` (full state), ``"positions"`` (x1, y1, x2, y2),
        ``"energy"``, ``"stretch"`` (elastic only), ``"outputs"`` (all model
        outputs), or a list of state/output names.

    Returns
    -------
    tuple of str
        Signal names, each a model state or model output.

    Raises
    ------
    ValueError
        ``"stretch"`` for the rigid model, an unknown or repeated name, an
        empty list, or ``outputs`` neither a string nor iterable.
    """
    check_model(model)
    groups = {
        "states": model.state_names,
        "positions": ("x1", "y1", "x2", "y2"),
        "energy": ("energy",),
        "outputs": model.output_names,
    }
    if model.kind == "elastic":
        groups["stretch"] = ("stretch1", "stretch2")
    if isinstance(outputs, str):
        if outputs in groups:
            return tuple(groups[outputs])
        if outputs == "stretch":
            raise ValueError("outputs='stretch' needs the elastic model; the rigid model has no springs")
        names: Sequence[str] = (outputs,)
    else:
        try:
            names = tuple(outputs)
        except TypeError as exc:
            raise ValueError(f"outputs must be one of {list(_OUTPUT_GROUPS)} or a list of signal names, got {outputs!r}") from exc
    known = model.state_names + model.output_names
    bad = [n for n in names if not isinstance(n, str) or n not in known]
    if bad or not names:
        raise ValueError(
            f"outputs {outputs!r}: unknown signal(s) {bad}; expected one of {list(_OUTPUT_GROUPS)} "
            f"or names among states {list(model.state_names)} and outputs {list(model.output_names)}"
        )
    if len(set(names)) != len(names):
        raise ValueError(f"outputs {outputs!r} names a signal twice")
    return tuple(names)


@cache
def _output_function(kind: str, names: tuple[str, ...]) -> ca.Function:
    """CasADi Function ``(y, C, D)(x, u, p)`` of the named signals (built once per kind and names)."""
    functions = model_functions(kind)
    rhs = functions["rhs"]
    x = ca.SX.sym("x", rhs.size1_in(0))
    u = ca.SX.sym("u", rhs.size1_in(1))
    p = ca.SX.sym("p", rhs.size1_in(2))
    probe = make_model(kind)
    yall = functions["outputs"](x, u, p)
    rows = [x[probe.state_names.index(n)] if n in probe.state_names else yall[probe.output_names.index(n)] for n in names]
    y = ca.vertcat(*rows)
    return ca.Function("y_sel", [x, u, p], [y, ca.jacobian(y, x), ca.jacobian(y, u)], ["x", "u", "p"], ["y", "C", "D"])


@checked()
def selected_outputs(model: Model, outputs: OutputSpec) -> tuple[tuple[str, ...], ca.Function]:
    """Resolve output names and build the CasADi Function that evaluates them.

    Parameters
    ----------
    model : Model
        Model whose states and outputs are selected.
    outputs : str or sequence of str
        Output specification, as in :func:`resolve_outputs`.

    Returns
    -------
    names : tuple of str
        Resolved signal names (ny of them).
    function : casadi.Function
        ``(y, C, D) = function(x, u, p)`` with y (ny, 1), C = dy/dx (ny, nx)
        and D = dy/du (ny, 2); cached per model kind and names.

    Raises
    ------
    ValueError
        Invalid ``outputs`` (see :func:`resolve_outputs`).
    """
    check_model(model)
    names = resolve_outputs(model, outputs)
    return names, _output_function(model.kind, names)


@checked()
def operating_point(model: Model, x: Any, u: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Check an operating point: an Equilibrium (its own u unless ``u`` is given) or arrays.

    Parameters
    ----------
    model : Model
        Model the operating point belongs to.
    x : array_like, shape (nx,), or Equilibrium
        Operating-point state in ``model.state_names`` order, or a solved
        equilibrium.
    u : array_like, shape (2,), optional
        Torques (tau1, tau2) [N.m]; default zero, or the equilibrium's own
        torques when ``x`` is an Equilibrium.

    Returns
    -------
    x : ndarray, shape (nx,)
        Validated state.
    u : ndarray, shape (2,)
        Validated torques [N.m].

    Raises
    ------
    ValueError
        ``x`` or ``u`` is not a single finite vector of the right size.
    """
    check_model(model)
    if isinstance(x, Equilibrium):
        if u is None:
            u = x.u
        x = x.x
    xv = model.check_state(x, "x")
    if xv.ndim != 1:
        raise ValueError(f"x must be a single state of shape ({model.nx},), got shape {xv.shape}")
    uv = model.check_input(u, "u")
    if uv.ndim != 1:
        raise ValueError(f"u must be a single input (tau1, tau2) of shape ({model.nu},), got shape {uv.shape}")
    return xv, uv


@checked()
def linearize(
    model: Model,
    x: Any,
    u: Any = None,
    inputs: str = "full",
    outputs: OutputSpec = "states",
) -> Linearization:
    """Exact linearization of the model about an operating point.

    Parameters
    ----------
    model : Model
        Model to linearize, at its parameters ``model.p``.
    x : array_like, shape (nx,), or Equilibrium
        Operating-point state in ``model.state_names`` order (SI units). Need
        not be an equilibrium (time-varying linearization along a trajectory):
        the result then says so (``is_equilibrium`` False, ``residual`` =
        ``max |f(x, u)|``) instead of raising.
    u : array_like, shape (2,), optional
        Operating-point torques (tau1, tau2) [N.m]; default zero, or the
        equilibrium's own torques when ``x`` is an Equilibrium.
    inputs : {"full", "pendubot", "acrobot"}
        Which torques are inputs of the linear model (columns of B and D).
    outputs : str or sequence of str
        ``"states"`` (default), ``"positions"``, ``"energy"``, ``"stretch"``,
        ``"outputs"`` or a list of state/output names.

    Returns
    -------
    Linearization
        A (nx, nx), B (nx, m), C (ny, nx), D (ny, m) with m = 2 for ``full``,
        1 otherwise; signal names attached; ``residual`` and ``is_equilibrium``
        mark the operating point.

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Unknown actuation or output name, operating point of the wrong size or
        non-finite.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid()  # 1 kg, 1 m links
    >>> lin = pl.linearize(model, model.rest_state())  # hanging at rest
    >>> w = np.sort(lin.eigenvalues.imag[lin.eigenvalues.imag > 0])  # pendular frequencies [rad/s]
    >>> np.round(w, 4), np.round(np.sqrt(9.81 * (2 + np.array([-1, 1]) * np.sqrt(2))), 4)  # (g / L)(2 -+ sqrt 2)
    (array([2.3972, 5.7874]), array([2.3972, 5.7874]))
    >>> swing = pl.linearize(model, [0.5, 0.0, 0.0, 0.0])  # along a trajectory: not an equilibrium
    >>> swing.is_equilibrium, round(swing.residual, 3)
    (False, 7.648)
    """
    check_model(model)
    idx = check_actuation(inputs)
    xv, uv = operating_point(model, x, u)
    names, yfun = selected_outputs(model, outputs)
    A, B = model.functions["jac_rhs"](xv, uv, model.p)
    y, C, D = yfun(xv, uv, model.p)
    residual, is_eq = _residual(model, xv, uv, np.asarray(A, dtype=float))
    cols = list(idx)
    return Linearization(
        A=np.asarray(A, dtype=float),
        B=np.asarray(B, dtype=float)[:, cols],
        C=np.asarray(C, dtype=float),
        D=np.asarray(D, dtype=float)[:, cols],
        x0=xv,
        u0=uv,
        y0=np.asarray(y, dtype=float).ravel(),
        state_names=model.state_names,
        input_names=tuple(INPUT_NAMES[i] for i in idx),
        output_names=names,
        actuation=inputs,
        kind=model.kind,
        input_indices=tuple(idx),
        residual=residual,
        is_equilibrium=is_eq,
    )


def _residual(model: Model, x: np.ndarray, u: np.ndarray, A: np.ndarray) -> tuple[float, bool]:
    f = np.abs(np.asarray(model.functions["rhs"](x, u, model.p), dtype=float).ravel())
    scale = 1.0 + np.abs(A) @ np.abs(x)
    return float(np.max(f)), bool(np.all(f <= EQUILIBRIUM_RTOL * scale))


@checked()
def equilibrium_residual(model: Model, x: Any, u: Any = None) -> tuple[float, bool]:
    """How far an operating point is from an equilibrium: ``max_i |f_i(x, u)|`` and the verdict.

    The test is relative: ``|f_i(x, u)| <= EQUILIBRIUM_RTOL * (1 + sum_j |A_ij| |x_j|)``
    for every state derivative ``i`` (``A`` the exact Jacobian), so that a solved
    equilibrium of a stiff elastic model passes while a nonzero rate or a
    visibly tilted link fails.

    Parameters
    ----------
    model : Model
        The pendulum, at its parameters.
    x : array_like, shape (nx,), or Equilibrium
        State (or a solved equilibrium, with its own torques unless ``u`` is given).
    u : array_like, shape (2,), optional
        Torques (tau1, tau2) [N.m]; default zero.

    Returns
    -------
    residual : float
        ``max_i |f_i(x, u)|`` [SI units of the state derivatives: rad/s, m/s, rad/s^2, m/s^2].
    is_equilibrium : bool
        The verdict of the relative test.

    Raises
    ------
    TypeError
        ``model`` is not a Model.
    ValueError
        ``x`` or ``u`` of the wrong size or non-finite.
    """
    check_model(model)
    xv, uv = operating_point(model, x, u)
    A = np.asarray(model.functions["jac_rhs"](xv, uv, model.p)[0], dtype=float)
    return _residual(model, xv, uv, A)


def not_equilibrium_error(where: str, lin: Linearization, keyword: str = "allow_non_equilibrium") -> ValueError:
    """The one error of a function that needs an equilibrium and got another point (modes, LQR, bridge).

    Parameters
    ----------
    where : str
        Name of the refusing function.
    lin : Linearization
        The linearization at the point (its ``residual``, ``x0`` and ``u0`` are named).
    keyword : str
        The opt-out keyword of the function.

    Returns
    -------
    ValueError
        The caller raises it.
    """
    return ValueError(
        f"{where}: the operating point is not an equilibrium: |f(x, u)| = {lin.residual:.3g} (largest state "
        f"derivative, SI units) at x = {np.round(lin.x0, 12).tolist()}, u = {lin.u0.tolist()} [N.m]; expected an "
        f"equilibrium: solve one with pendulab.equilibrium(model, name, u) (or pass {keyword}=True to use this point anyway)"
    )


@checked()
def linearize_along(model: Model, X: Any, U: Any = None, inputs: str = "full") -> tuple[np.ndarray, np.ndarray]:
    """Jacobians A(t_k), B(t_k) along a trajectory in one vectorized CasADi call.

    Parameters
    ----------
    model : Model
        Model to linearize, at its parameters ``model.p``.
    X : array_like, shape (N, nx)
        States along the trajectory.
    U : array_like, shape (N, 2) or (2,), optional
        Torques (tau1, tau2) [N.m]; default zero.
    inputs : {"full", "pendubot", "acrobot"}
        Which torques are the columns of B.

    Returns
    -------
    A : ndarray, shape (N, nx, nx)
        df/dx at each sample (SI units).
    B : ndarray, shape (N, nx, m)
        df/du at each sample, m = 2 for ``full`` and 1 otherwise.
    """
    check_model(model)
    idx = list(check_actuation(inputs))
    Xv = np.atleast_2d(model.check_state(X, "X"))
    Uv = np.broadcast_to(model.check_input(U, "U"), (Xv.shape[0], model.nu))
    N, nx = Xv.shape
    A, B = model.functions["jac_rhs"].map(N)(Xv.T, np.ascontiguousarray(Uv.T), model.p)
    A = np.asarray(A, dtype=float).reshape(nx, N, nx).transpose(1, 0, 2)
    B = np.asarray(B, dtype=float).reshape(nx, N, model.nu).transpose(1, 0, 2)
    return A, B[:, :, idx]

"""python-control bridge: exact ``StateSpace`` and a ``NonlinearIOSystem`` with named signals.

Signal names come from the model (``theta1``, ``omega1``, ``tau1``, ``x2``,
...), so ``lqr``, ``feedback`` and ``interconnect`` can connect systems by name.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import control as ct
import numpy as np

from .._checks import check_model
from .._inputs import checked
from ..analysis.equilibria import equilibrium
from ..analysis.linearize import OutputSpec, check_actuation, linearize, not_equilibrium_error, selected_outputs
from ..model.model import INPUT_NAMES, Model

__all__ = ["to_statespace", "to_nlsys"]


@checked()
def to_statespace(
    model: Model,
    x: Any = "up-up",
    u: Any = None,
    actuation: str = "full",
    outputs: OutputSpec = "states",
    name: str | None = None,
    *,
    allow_non_equilibrium: bool = False,
) -> ct.StateSpace:
    """Exact linearization as a named ``control.StateSpace``.

    Parameters
    ----------
    model : Model
    x : str, Equilibrium or array_like of shape (nx,)
        Operating point: an equilibrium name (solved at torque ``u``), a solved
        Equilibrium, or a state that is an equilibrium under ``u``.
    u : array_like, shape (2,), optional
        Operating-point torques (tau1, tau2) [N.m]; default zero.
    actuation : {"full", "pendubot", "acrobot"}
    outputs : str or sequence of str
        As in :func:`pendulab.linearize`.
    name : str, optional
        System name (default ``"<kind>_<actuation>"``).
    allow_non_equilibrium : bool
        Accept a state that is not an equilibrium. The matrices are then the
        Jacobians there, and the deviation model misses the drift
        ``f(x0, u0)`` (kept in ``sys.x0``/``sys.u0``; see
        :func:`pendulab.linearize`, which reports ``residual``).

    Returns
    -------
    control.StateSpace
        States, inputs and outputs named after the model's signals; the
        operating point is kept in ``sys.x0``, ``sys.u0`` (full torque vector)
        and ``sys.y0`` (deviation variables are what the matrices act on).

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Unknown actuation, output or equilibrium name; a state of the wrong
        size; a state that is not an equilibrium (unless ``allow_non_equilibrium``).

    Examples
    --------
    >>> import control as ct
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import to_statespace
    >>> sys = to_statespace(pl.rigid(), "up-up", actuation="acrobot")
    >>> sys.state_labels, sys.input_labels
    (['theta1', 'theta2', 'omega1', 'omega2'], ['tau2'])
    >>> np.round(np.sort(sys.poles().real), 2)  # two unstable poles upright [1/s]
    array([-5.79, -2.4 ,  2.4 ,  5.79])
    >>> K, S, E = ct.lqr(sys, np.diag([10.0, 10.0, 1.0, 1.0]), 1.0)
    >>> bool(np.all(E.real < 0))
    True
    """
    check_model(model)
    check_actuation(actuation)
    if isinstance(x, str):
        x = equilibrium(model, x, u)
    lin = linearize(model, x, u, inputs=actuation, outputs=outputs)
    if not lin.is_equilibrium and not allow_non_equilibrium:
        raise not_equilibrium_error("to_statespace", lin)
    sys = ct.ss(
        lin.A,
        lin.B,
        lin.C,
        lin.D,
        states=list(lin.state_names),
        inputs=list(lin.input_names),
        outputs=list(lin.output_names),
        name=name or f"{model.kind}_{actuation}",
    )
    sys.x0, sys.u0, sys.y0 = lin.x0, lin.u0, lin.y0
    return sys


@checked()
def to_nlsys(
    model: Model,
    actuation: str = "full",
    outputs: OutputSpec = "states",
    name: str | None = None,
) -> ct.NonlinearIOSystem:
    """The nonlinear model as a named ``control.NonlinearIOSystem``.

    The update and output functions call the compiled CasADi functions; the
    physical parameters are the system's ``params`` (a dict by parameter name,
    SI units), so they can be changed per call, e.g.
    ``control.input_output_response(sys, T, U, X0, params={"m2": 2.0})``.

    Parameters
    ----------
    model : Model
        Supplies the default parameter values.
    actuation : {"full", "pendubot", "acrobot"}
        Inputs of the system; unactuated torques are zero.
    outputs : str or sequence of str
        As in :func:`pendulab.linearize` (default: the full state).
    name : str, optional

    Returns
    -------
    control.NonlinearIOSystem

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Unknown actuation or output name.

    Examples
    --------
    >>> import control as ct
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import to_nlsys
    >>> sys = to_nlsys(pl.rigid(), actuation="pendubot")
    >>> sys.ninputs, sys.nstates, sys.input_labels
    (1, 4, ['tau1'])
    >>> T = np.linspace(0.0, 1.0, 11)
    >>> tight = {"rtol": 1e-9, "atol": 1e-9}  # solve_ivp's defaults (1e-3) are loose
    >>> resp = ct.input_output_response(sys, T, 0.0, X0=[0.5, 0.0, 0.0, 0.0], params={"m2": 2.0}, solve_ivp_kwargs=tight)
    >>> ref = pl.simulate(pl.rigid(m2=2.0), [0.5, 0.0, 0.0, 0.0], 1.0, dt=0.1)
    >>> bool(np.allclose(resp.states[:, -1], ref.x[-1], atol=1e-4))
    True
    """
    check_model(model)
    idx = list(check_actuation(actuation))
    names, yfun = selected_outputs(model, outputs)
    rhs = model.functions["rhs"]
    param_names = model.param_names
    defaults = dict(zip(param_names, model.p.tolist(), strict=True))

    @lru_cache(maxsize=64)
    def checked(items: tuple[tuple[str, Any], ...]) -> np.ndarray:
        unknown = sorted(set(dict(items)) - set(param_names))
        if unknown:
            raise ValueError(f"unknown parameter name(s) {unknown}; expected one of {list(param_names)}")
        # Validate once per distinct parameter set (signs, finiteness) through the parameter class.
        return type(model.params)(**{**defaults, **dict(items)}).as_vector()

    def pvec(params: dict[str, Any] | None) -> np.ndarray:
        return checked(tuple(sorted((params or {}).items())))

    def full_u(u: np.ndarray) -> np.ndarray:
        uf = np.zeros(len(INPUT_NAMES))
        uf[idx] = np.asarray(u, dtype=float).ravel()
        return uf

    def update(_t: float, x: np.ndarray, u: np.ndarray, params: dict[str, Any]) -> np.ndarray:
        return np.asarray(rhs(x, full_u(u), pvec(params)), dtype=float).ravel()

    def output(_t: float, x: np.ndarray, u: np.ndarray, params: dict[str, Any]) -> np.ndarray:
        return np.asarray(yfun(x, full_u(u), pvec(params))[0], dtype=float).ravel()

    return ct.nlsys(
        update,
        output,
        states=list(model.state_names),
        inputs=[INPUT_NAMES[i] for i in idx],
        outputs=list(names),
        params=defaults,
        name=name or f"{model.kind}_{actuation}_nl",
    )

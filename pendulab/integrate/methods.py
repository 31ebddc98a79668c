"""The one method registry of :func:`pendulab.simulate`, assembled from its families.

Every family module exports ``METHOD_SPECS``; this module lists them
explicitly (no registration as a side effect of an import). ``rk`` (CasADi's
RK4 plugin in 0.1) is a deprecated name of ``rk4``: the same classical
Runge-Kutta method with the same steps.
"""

from __future__ import annotations

from . import casadi_methods, compiled, fixed_step, scipy_methods, taylor
from .registry import MethodSpec, Registry

__all__ = ["METHODS", "register_method"]

#: All integration methods by name (read-only; see :func:`register_method`).
METHODS: Registry = Registry(
    (
        *casadi_methods.METHOD_SPECS,
        *scipy_methods.METHOD_SPECS,
        *fixed_step.METHOD_SPECS,
        *taylor.METHOD_SPECS,
        *compiled.METHOD_SPECS,
    ),
    deprecated={"rk": "rk4"},
)


def register_method(spec: MethodSpec) -> None:
    """Add a method to :data:`METHODS` (e.g. a plug-in family).

    Parameters
    ----------
    spec : MethodSpec
        The method; its runner must keep the :class:`~pendulab.integrate.registry.Runner` contract.

    Raises
    ------
    ValueError
        The name is taken.

    Examples
    --------
    A plug-in method: Heun's method (explicit trapezoid), one step per output interval.

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.integrate import MethodSpec, RunResult, register_method
    >>> def heun(req):  # the runner contract: RunRequest in, RunResult out (inputs held per interval)
    ...     x, f = [req.x0], req.model.rhs
    ...     for k, h in enumerate(np.diff(req.t)):
    ...         u = req.schedule[k] if req.feedback is None else req.feedback_input(req.t[k], x[-1])
    ...         x.append(x[-1] + h / 2 * (f(x[-1], u) + f(x[-1] + h * f(x[-1], u), u)))
    ...     return RunResult(np.array(x), req.schedule, {"n_steps": len(x) - 1})
    >>> register_method(MethodSpec("heun-demo", "user", "Heun's method, one step per output interval", heun, True))
    >>> traj = pl.simulate(pl.rigid(), [0.5, 0.0, 0.0, 0.0], 1.0, dt=1e-3, method="heun-demo")
    >>> ref = pl.simulate(pl.rigid(), [0.5, 0.0, 0.0, 0.0], 1.0, dt=1e-3, method="cvodes", rtol=1e-10, atol=1e-10)
    >>> traj.method, bool(np.abs(traj.x - ref.x).max() < 1e-4)
    ('heun-demo', True)
    """
    METHODS.add(spec)

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
    """
    METHODS.add(spec)

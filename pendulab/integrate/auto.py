"""``method="auto"``, the default of :func:`pendulab.simulate`: pick the method from the model, the start and the tolerance.

The rule (backed by the work-precision study, ``docs/benchmarks.md``):

1. **Stiff or not.** ``omega_max`` is the largest magnitude of the eigenvalues
   of the exact Jacobian at the start (for the elastic model, the fast spring
   mode, ~1.618 sqrt(k/m) rad/s). An explicit 5th-order method needs steps
   ``h < 3.3 / omega_max`` to be stable, and steps of about
   ``h_acc = tol**(1/5) / omega_ref`` to meet the tolerance ``tol = min(rtol, atol)`` on the
   pendular motion, ``omega_ref = 2 sqrt(g / min(L1, L2))`` (6.3 rad/s for 1 m links;
   the fast pendular mode is 5.8 rad/s). The problem is *stiff* when stability,
   not accuracy, would limit the explicit step: ``omega_max h_acc > 3.3``.
   At tol = 1e-8 that is omega_max > 770 rad/s (k > ~2e5 N/m for 1 kg, 1 m);
   at 1e-12 omega_max > 4800 rad/s: tight tolerances make explicit steps small anyway.
2. **Not stiff:** ``taylor`` for the rigid model when heyoka is installed
   (10 s of chaos to 1e-9 in under a millisecond; its first run per tolerance
   compiles for ~0.2 s); otherwise, and for the elastic model (whose Taylor
   system takes seconds to compile per tolerance), ``compiled-dopri5`` when a C
   compiler is available (built once per machine, cached on disk);
   otherwise ``cvodes-adams``.
3. **Stiff:** ``compiled-rodas4`` (L-stable Rosenbrock with the exact
   Jacobian) when a C compiler is available, otherwise ``cvodes`` (BDF).

A method the user names is never overridden; the choice and the reason are in
``Trajectory.stats["auto"]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.model import Model
from .methods import METHODS

__all__ = ["AutoChoice", "choose_method", "STABILITY_LIMIT"]

#: |h lambda| stability limit of an explicit 5th-order Runge-Kutta method on the imaginary axis (DOPRI5: ~3.3).
STABILITY_LIMIT = 3.3


@dataclass(frozen=True)
class AutoChoice:
    """The method ``auto`` picked, and why.

    Attributes
    ----------
    method : str
        A key of :data:`pendulab.METHODS`.
    stiff : bool
        Whether the problem counts as stiff at this tolerance.
    omega_max : float
        Largest eigenvalue magnitude of the Jacobian at the start [rad/s].
    omega_limit : float
        The stiffness threshold at this tolerance [rad/s]: stiff when ``omega_max`` exceeds it.
    reason : str
        One line for logs and the CLI.
    """

    method: str
    stiff: bool
    omega_max: float
    omega_limit: float
    reason: str

    def as_dict(self) -> dict[str, object]:
        """JSON-friendly form.

        Returns
        -------
        dict
            The fields by name.
        """
        return {
            "method": self.method,
            "stiff": self.stiff,
            "omega_max": self.omega_max,
            "omega_limit": self.omega_limit,
            "reason": self.reason,
        }


def _usable(name: str) -> str | None:
    """None when the method can run here, else why not."""
    spec = METHODS.get(name)
    if spec is None:
        return f"method {name!r} is not registered"
    available = spec.settings.get("available")
    return available() if callable(available) else None


def choose_method(model: Model, x0: np.ndarray, u0: np.ndarray, rtol: float, atol: float) -> AutoChoice:
    """Apply the rule of this module.

    Parameters
    ----------
    model : Model
        The pendulum.
    x0 : ndarray, shape (nx,)
        Initial state.
    u0 : ndarray, shape (nu,)
        Torques at the start [N.m].
    rtol, atol : float
        Requested tolerances (positive).

    Returns
    -------
    AutoChoice
        The method and the numbers behind the choice.
    """
    A = np.asarray(model.functions["jac_rhs"](x0, u0, model.p)[0], dtype=float)
    omega_max = float(np.max(np.abs(np.linalg.eigvals(A))))
    p = model.params
    omega_ref = 2.0 * math.sqrt(p.g / min(p.L1, p.L2))
    tol = min(rtol, atol)
    h_acc = tol ** (1.0 / 5.0) / omega_ref
    omega_limit = STABILITY_LIMIT / h_acc
    stiff = omega_max > omega_limit
    if stiff:
        order = ("compiled-rodas4", "cvodes")
    elif model.kind == "rigid":
        order = ("taylor", "compiled-dopri5", "cvodes-adams")
    else:
        order = ("compiled-dopri5", "cvodes-adams")
    skipped = []
    for name in order:
        why_not = _usable(name)
        if why_not is None:
            break
        skipped.append(f"{name}: {why_not}")
    kind = "stiff" if stiff else "not stiff"
    reason = f"{kind}: omega_max = {omega_max:.3g} rad/s vs limit {omega_limit:.3g} rad/s at tol {tol:.1e}"
    if skipped:
        reason += "; skipped " + "; ".join(skipped)
    return AutoChoice(name, stiff, omega_max, omega_limit, reason)

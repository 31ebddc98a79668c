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
   compiles for ~0.2 s); otherwise, and for the elastic model, ``compiled-dopri5``
   when a C compiler is available (built once per machine, cached on disk). The
   elastic Taylor system took seconds to compile per tolerance when this rule was
   measured; since the translator emits 51 operations (was 130), its first run
   compiles in 0.3-0.5 s without heyoka's disk cache (2 s runs, 1e-8 / 1e-12), so
   the elastic choice is due for a new work-precision run;
   otherwise ``cvodes-adams``.
3. **Stiff, but the fast modes excited by the start:** the non-stiff choice of 2.
   An implicit method steps over a fast mode only when it is not there: an
   oscillation of the springs above the tolerance must be followed by every
   error-controlled method, with steps ``~ tol**(1/p) / omega_max`` well inside
   the explicit stability limit, and an explicit step is several times cheaper
   than a Rosenbrock step (Jacobian + LU). The *excitation* is the quasi-static
   distance of the start: per spring, the amplitude of its oscillation about the
   quasi-static length ``r*`` (zero radial acceleration at the start's angles,
   rates and torques; :func:`pendulab.model.quasistatic.quasi_static_lengths`),
   ``a = sqrt((r - r*)**2 + m v**2 / k)`` (the fast-mode energy
   ``k a**2 / 2``), divided by what the tolerance resolves, ``atol + rtol L``.
   Excited when the largest ratio exceeds ``EXCITATION_LIMIT`` = 1: a rest-length
   start, or ``model.state(theta1=1.0)`` (static *hanging* lengths at a swung
   angle), is excited; a ``quasi_static_state`` start is not.
4. **Stiff and not excited:** ``compiled-rodas4`` (L-stable Rosenbrock with the
   exact Jacobian) when a C compiler is available, otherwise ``cvodes`` (BDF).

Measured (``docs/fastpath.md``, 2 s runs at rtol = atol = 1e-8): k = 1e6 N/m from
rest length or static hanging lengths at theta1 = 1 rad: compiled-dopri5 and taylor
3.5-4x faster than compiled-rodas4; from the quasi-static state: compiled-rodas4 fastest.

A method the user names is never overridden; the choice and the reason are in
``Trajectory.stats["auto"]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.model import Model
from .methods import METHODS

__all__ = ["AutoChoice", "choose_method", "STABILITY_LIMIT", "EXCITATION_LIMIT", "spring_excitation"]

#: |h lambda| stability limit of an explicit 5th-order Runge-Kutta method on the imaginary axis (DOPRI5: ~3.3).
STABILITY_LIMIT = 3.3
#: A stiff start counts as exciting its fast (spring) modes when their amplitude exceeds this many tolerances.
EXCITATION_LIMIT = 1.0


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
    excitation : float or None
        Amplitude of the fast (spring) modes at the start in tolerances (:func:`spring_excitation`);
        None when not evaluated (not stiff, or the rigid model).
    """

    method: str
    stiff: bool
    omega_max: float
    omega_limit: float
    reason: str
    excitation: float | None = None

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
            "excitation": self.excitation,
        }


def _usable(name: str) -> str | None:
    """None when the method can run here, else why not."""
    spec = METHODS.get(name)
    if spec is None:
        return f"method {name!r} is not registered"
    available = spec.settings.get("available")
    return available() if callable(available) else None


def spring_excitation(model: Model, x0: np.ndarray, u0: np.ndarray, rtol: float, atol: float) -> float:
    """How far the start excites the spring modes, in tolerances: the quasi-static distance of ``x0``.

    Parameters
    ----------
    model : Model
        Elastic pendulum.
    x0 : ndarray, shape (8,)
        Initial state.
    u0 : ndarray, shape (2,)
        Torques at the start [N.m].
    rtol, atol : float
        Tolerances.

    Returns
    -------
    float
        ``max_j a_j / (atol + rtol L_j)``, ``a_j = sqrt((r_j - r*_j)**2 + m_j v_j**2 / k_j)`` [m]: the
        amplitude of spring j's oscillation about its quasi-static length ``r*_j`` (energy ``k_j a_j**2 / 2``);
        ``inf`` when there is no quasi-static length (springs too soft to hold the motion).
    """
    from ..model.quasistatic import quasi_static_lengths

    p = model.params
    x0 = np.asarray(x0, dtype=float)
    try:
        r_star = quasi_static_lengths(model, x0[0:2], x0[4:6], u0)
    except RuntimeError:
        return math.inf
    k = np.array([p.k1, p.k2])
    m = np.array([p.m1, p.m2])
    amplitude = np.sqrt((x0[2:4] - r_star) ** 2 + m * x0[6:8] ** 2 / k)
    resolved = atol + rtol * np.array([p.L1, p.L2])
    return float(np.max(amplitude / resolved))


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

    Raises
    ------
    ValueError
        The linearization at ``x0`` is not finite (a spring length or stiffness next to zero).
    """
    A = np.asarray(model.functions["jac_rhs"](x0, u0, model.p)[0], dtype=float)
    if not np.all(np.isfinite(A)):  # finite dynamics can still have an overflowing linearization (r1 = 1e-300)
        raise model.not_finite_error(np.asarray(x0, dtype=float), "x0", "the linearized equations of motion are")
    omega_max = float(np.max(np.abs(np.linalg.eigvals(A))))
    p = model.params
    # The pendular time scale; without gravity (g = 0) the motion's own rates set it, and a model at rest
    # without gravity does not move at all (1 rad/s: any method is accurate then).
    rates = np.abs(np.asarray(x0, dtype=float)[model.nq : model.nq + 2])
    omega_ref = max(2.0 * math.sqrt(p.g / min(p.L1, p.L2)), float(np.max(rates)), 1.0 if p.g == 0.0 else 0.0)
    tol = min(rtol, atol)
    h_acc = tol ** (1.0 / 5.0) / omega_ref
    omega_limit = STABILITY_LIMIT / h_acc
    stiff = omega_max > omega_limit
    excitation = spring_excitation(model, x0, u0, rtol, atol) if stiff and model.kind == "elastic" else None
    excited = excitation is not None and excitation > EXCITATION_LIMIT
    if stiff and not excited:
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
    if excitation is not None:
        reason += (
            f"; spring modes {'excited' if excited else 'not excited'} by the start "
            f"({excitation:.3g} tolerances from quasi-static{': follow them with an explicit method' if excited else ''})"
        )
    if skipped:
        reason += "; skipped " + "; ".join(skipped)
    return AutoChoice(name, stiff, omega_max, omega_limit, reason, excitation)

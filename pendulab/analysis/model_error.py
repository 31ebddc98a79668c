"""Predicted modelling errors from the modes: the formulas shared by the scene rule and the swing-up planner.

A cheaper model of the elastic pendulum (rigid links; rigid links with
quasi-static spring lengths) errs by an amount set by the spring-to-pendulum
frequency ratio and the load the springs carry. Over chaotic motion any error
grows like ``e^(lambda_1 t)``. This module holds those formulas, with no
integration and no model calls, so that :func:`pendulab.scene.choose_model`
(scenes: absolute output errors over a horizon) and the swing-up planning rule
(relative defects of a plan) predict from the same place.

Formulas (``w_p``: highest pendular, ``w_s``: lowest spring frequency [rad/s];
``eps = w_p / w_s``):

* :func:`mode_ratio_errors` -- the planning rule's relative defects:
  rigid ``C_RIGID * eps``, rigid + quasi-static ``C_QUASI_STATIC * eps**2``.
* :func:`spring_stretch` -- the stretch a spring takes under the load
  (gravity + centrifugal): ``delta = T / k``. With ``w_s**2 ~ k / m`` and
  ``w_p**2 ~ g / L`` this is ``delta / L ~ eps**2`` at rest: the same ratio,
  squared, as the absolute error of a rigid model's outputs.
* :func:`lyapunov_exponent` -- ``lambda_1`` from the energy above the hanging
  rest (table :data:`LYAPUNOV_TABLE` measured on the rigid pendulum, scaled by
  ``sqrt(g / L)``) times a stiffness factor (:data:`STIFFNESS_FACTOR`, from the
  Lyapunov study at 12.25 J, ``docs/lyapunov.md``).
* :func:`error_growth` -- how an initial relative model error ``nu`` grows into
  an angle error: secularly (a frequency error becomes a phase error,
  ``sum_j A_j w_j t / 2`` over the pendular modes) plus exponentially (``e^(lambda t) - 1``).
* :func:`validity_horizon` -- the first time a predicted error curve exceeds a tolerance.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "C_RIGID",
    "C_QUASI_STATIC",
    "LYAPUNOV_TABLE",
    "STIFFNESS_FACTOR",
    "mode_ratio_errors",
    "frequency_split",
    "spring_stretch",
    "lyapunov_exponent",
    "error_growth",
    "validity_horizon",
]

#: Planning rule: predicted relative defect of a rigid plan on the elastic dynamics per unit of w_p / w_s.
C_RIGID = 4.0
#: Planning rule: predicted relative defect of a quasi-statically lifted rigid plan per unit of (w_p / w_s)^2.
C_QUASI_STATIC = 15.0

#: Largest Lyapunov exponent of the rigid double pendulum against its energy, dimensionless:
#: rows (eps_E, lambda_1 / sqrt(g / Lbar)) with eps_E = (E - E_rest) / (V_upright - V_rest) and
#: Lbar = (L1 + L2) / 2. Measured with ``pendulab.ensemble.lyapunov.largest_lyapunov`` (heyoka,
#: 10 random equal-energy starts per row, seed 7, 5 s transient, 60 s averaging) on the unit
#: pendulum (m = 1 kg, L = 1 m, g = 9.81 m/s^2: V_upright - V_rest = 58.86 J, sqrt(g / L) = 3.132 /s);
#: rows below eps_E = 0.2 measured 0.02 ... 0.04 /s, the finite-time value of regular orbits, and are 0.
#: The 41.7 J row (1.36 /s) agrees with the 300 s study of docs/lyapunov.md (1.351 /s).
#: ``benchmarks/bench_model_choice.py --lyapunov-table`` remeasures it.
LYAPUNOV_TABLE: tuple[tuple[float, float], ...] = (
    (0.0, 0.0),
    (0.17, 0.0),
    (0.204, 0.008),
    (0.272, 0.039),
    (0.340, 0.085),
    (0.425, 0.207),
    (0.510, 0.311),
    (0.708, 0.434),
    (1.019, 0.318),
    (1.529, 0.334),
    (2.548, 0.360),
)

#: lambda_1(elastic) / lambda_1(rigid) at 12.25 J against log10(w_s / w_p) (docs/lyapunov.md: k = 1e2, 1e3,
#: 1e4, 1e5 N/m for the unit pendulum have w_s / w_p = 1.30, 4.08, 12.8, 40.6): 0.754, 1.765, 1.281, 0.998;
#: 1 beyond the stiffest, the softest value below the softest.
STIFFNESS_FACTOR: tuple[tuple[float, float], ...] = (
    (math.log10(1.30), 0.754),
    (math.log10(4.08), 1.765),
    (math.log10(12.8), 1.281),
    (math.log10(40.6), 0.998),
)


def mode_ratio_errors(pendular_frequency: float, spring_frequency: float) -> dict[str, float]:
    """Predicted relative defect of the cheaper planning models from the frequency ratio.

    Parameters
    ----------
    pendular_frequency : float
        Highest pendular frequency w_p [rad/s], > 0.
    spring_frequency : float
        Lowest spring frequency w_s [rad/s], > 0 (inf: rigid links).

    Returns
    -------
    dict of str to float
        ``{"rigid": C_RIGID * eps, "rigid+quasi-static": C_QUASI_STATIC * eps**2, "elastic": 0.0}``
        with ``eps = w_p / w_s`` (dimensionless).

    Raises
    ------
    ValueError
        A frequency that is not positive.
    """
    if not (pendular_frequency > 0 and spring_frequency > 0):
        raise ValueError(
            f"frequencies must be positive [rad/s], got pendular_frequency={pendular_frequency!r}, "
            f"spring_frequency={spring_frequency!r}"
        )
    eps = pendular_frequency / spring_frequency
    return {"rigid": C_RIGID * eps, "rigid+quasi-static": C_QUASI_STATIC * eps**2, "elastic": 0.0}


def frequency_split(eigenvalues: np.ndarray, kind: str) -> tuple[float, float]:
    """Highest pendular and lowest spring frequency [rad/s] from the eigenvalues at the hanging equilibrium.

    The two lowest |Im| pairs are the pendular modes, the two highest the spring
    modes (the split :func:`pendulab.analysis.modes.modes` makes by spring share when
    the two groups are apart; when they are not, the ratio is near 1 and every
    cheaper model is rejected anyway).

    Parameters
    ----------
    eigenvalues : ndarray, shape (nx,)
        Eigenvalues of the Jacobian at the hanging equilibrium [1/s] (4 rigid, 8 elastic).
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    w_p, w_s : float
        Highest pendular frequency and lowest spring frequency [rad/s] (``w_s`` inf for rigid).
    """
    w = np.sort(np.abs(np.asarray(eigenvalues)))
    w = w[::2]  # conjugate pairs (undamped) or pairs of real eigenvalues: one per mode
    if kind != "elastic":
        return float(w[-1]), math.inf
    return float(w[1]), float(w[2])


def spring_stretch(load: float, stiffness: float) -> float:
    """Stretch [m] of a spring of stiffness ``stiffness`` [N/m] under the tension ``load`` [N]: ``load / stiffness``.

    Parameters
    ----------
    load : float
        Spring tension [N] (gravity and centrifugal load of the masses it carries).
    stiffness : float
        Spring constant k [N/m], > 0.

    Returns
    -------
    float
        Stretch [m].
    """
    return abs(load) / stiffness


def lyapunov_exponent(energy_fraction: float, pendular_scale: float, frequency_ratio: float = math.inf) -> float:
    """Predicted largest Lyapunov exponent [1/s] from the energy and the stiffness.

    Parameters
    ----------
    energy_fraction : float
        ``(E - E_rest) / (V_upright - V_rest)``: energy above the hanging rest over the
        potential energy from hanging to upright (dimensionless, >= 0).
    pendular_scale : float
        ``sqrt(g / Lbar)`` [1/s], ``Lbar = (L1 + L2) / 2``.
    frequency_ratio : float
        ``w_s / w_p`` (inf: rigid links).

    Returns
    -------
    float
        ``lambda_1`` [1/s]: :data:`LYAPUNOV_TABLE` interpolated (constant beyond its last row)
        times ``pendular_scale`` times :data:`STIFFNESS_FACTOR` interpolated in ``log10(w_s / w_p)``.
    """
    e, lam = np.array(LYAPUNOV_TABLE).T
    base = float(np.interp(max(energy_fraction, 0.0), e, lam))
    factor = 1.0
    if math.isfinite(frequency_ratio):
        x, f = np.array(STIFFNESS_FACTOR).T
        factor = float(np.interp(math.log10(max(frequency_ratio, 1e-12)), x, f, left=f[0], right=1.0))
    return base * pendular_scale * factor


def error_growth(t: np.ndarray, phase_rate: float, lyapunov: float, *, secular: float = 1.0, chaotic: float = 1.0) -> np.ndarray:
    """Angle error [rad] per unit relative model error ``nu`` at times ``t``.

    A relative error ``nu`` of the pendulum's length changes each mode's frequency
    by ``nu / 2``: a phase error growing secularly, ``phase_rate * t / 2`` with
    ``phase_rate = sum_j A_j w_j`` (mode amplitude [rad] times frequency [rad/s]).
    Over chaotic motion an error grows like ``e^(lambda t)``. The weighted sum is used.

    Parameters
    ----------
    t : ndarray
        Times [s], >= 0.
    phase_rate : float
        ``sum_j A_j w_j`` over the pendular modes [rad/s].
    lyapunov : float
        lambda_1 [1/s] (0: regular motion).
    secular, chaotic : float
        Weights of the two terms (calibrated by the caller).

    Returns
    -------
    ndarray
        Same shape as ``t``: ``secular * phase_rate * t / 2 + chaotic * expm1(lambda t)`` [rad per unit nu].
    """
    t = np.asarray(t, dtype=float)
    return secular * phase_rate * t / 2 + chaotic * np.expm1(np.minimum(lyapunov * t, 700.0))


def validity_horizon(t: np.ndarray, error: np.ndarray, tolerance: float) -> float:
    """First time [s] at which ``error`` exceeds ``tolerance``; the last time when it never does.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times [s].
    error : ndarray, shape (N,)
        Error at those times (running maximum or not), in the tolerance's units.
    tolerance : float
        Accepted error.

    Returns
    -------
    float
        ``t[k]`` of the first ``error[k] > tolerance`` (linearly interpolated from
        ``t[k-1]`` on a log scale of the error), 0.0 when ``error[0]`` already
        exceeds it, ``t[-1]`` when it never does.
    """
    t = np.asarray(t, dtype=float)
    err = np.maximum.accumulate(np.nan_to_num(np.asarray(error, dtype=float), nan=np.inf))
    over = np.nonzero(err > tolerance)[0]
    if over.size == 0:
        return float(t[-1])
    k = int(over[0])
    if k == 0:
        return 0.0
    e0, e1 = err[k - 1], err[k]
    if not (np.isfinite(e1) and e0 > 0):
        return float(t[k])
    frac = math.log(tolerance / e0) / math.log(e1 / e0) if e1 > e0 else 1.0
    return float(t[k - 1] + min(max(frac, 0.0), 1.0) * (t[k] - t[k - 1]))

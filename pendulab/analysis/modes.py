"""Modes of the linearized pendulum: frequencies, damping, time constants, labelled shapes.

One :class:`Mode` per complex-conjugate eigenvalue pair (oscillation) or per
real eigenvalue (divergence or decay). Shapes are the position part of the
eigenvector (``theta1, theta2[, r1, r2]``), rotated to be real and scaled so
that the largest entry is +1 (mixed units: rad and m). Labels say what moves:
the kinetic-energy share of the spring coordinates separates pendular from
spring-stretch motion; the relative sign of the two dominant entries gives
in-phase / anti-phase.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import check_model
from .._inputs import checked
from ..model.model import Model
from .equilibria import Equilibrium, equilibrium
from .linearize import linearize, not_equilibrium_error, operating_point

__all__ = ["Mode", "modes", "mode_table", "stiffness_sweep"]


@dataclass(frozen=True)
class Mode:
    """One mode of the linearization at an operating point.

    Attributes
    ----------
    eigenvalue : complex
        lambda [1/s] (the one with positive imaginary part for an oscillation).
    kind : {"oscillatory", "unstable", "decaying", "neutral"}
    omega_n : float
        Natural frequency abs(lambda) [rad/s].
    freq_hz : float
        omega_n / (2 pi) [Hz].
    omega_d : float
        Damped frequency abs(Im lambda) [rad/s] (0 for real eigenvalues).
    damping_ratio : float
        -Re(lambda) / abs(lambda) (as ``control.damp``; -1 for a real unstable mode).
    time_constant : float
        1 / abs(Re lambda) [s]: e-folding time of growth (unstable) or decay;
        ``inf`` when undamped.
    shape : ndarray, shape (nq,)
        Normalized position part of the eigenvector (largest entry +1).
    shape_names : tuple of str
        Coordinates of ``shape`` (theta1, theta2[, r1, r2]).
    spring_share : float
        Fraction of the mode's kinetic energy in the spring coordinates (0 for rigid).
    label : str
        What moves, e.g. "pendular in-phase", "spring stretch anti-phase".

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> fast = pl.modes(pl.elastic(k1=1e4, k2=1e4))[-1]  # the highest of the four modes at rest
    >>> fast.label, fast.kind, round(fast.spring_share, 3)
    ('spring stretch anti-phase', 'oscillatory', 1.0)
    >>> print(f"{fast.omega_n:.2f} rad/s, analytic {(1 + np.sqrt(5)) / 2 * np.sqrt(1e4):.2f}")  # golden ratio x sqrt(k / m)
    161.80 rad/s, analytic 161.80
    >>> fast.shape_names, np.round(fast.shape, 3)  # the springs stretch in opposite senses
    (('theta1', 'theta2', 'r1', 'r2'), array([ 0.   ,  0.   , -0.618,  1.   ]))
    """

    eigenvalue: complex
    kind: str
    omega_n: float
    freq_hz: float
    omega_d: float
    damping_ratio: float
    time_constant: float
    shape: np.ndarray
    shape_names: tuple[str, ...]
    spring_share: float
    label: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly record (``inf`` time constants become ``None``).

        Returns
        -------
        dict
            ``label``, ``kind``, ``eigenvalue`` as [re, im] [1/s],
            ``omega_n_rad_s``, ``freq_hz``, ``omega_d_rad_s``,
            ``damping_ratio``, ``time_constant_s``, ``shape`` by coordinate
            name and ``spring_share``.
        """
        return {
            "label": self.label,
            "kind": self.kind,
            "eigenvalue": [float(self.eigenvalue.real), float(self.eigenvalue.imag)],
            "omega_n_rad_s": self.omega_n,
            "freq_hz": self.freq_hz,
            "omega_d_rad_s": self.omega_d,
            "damping_ratio": self.damping_ratio,
            "time_constant_s": None if math.isinf(self.time_constant) else self.time_constant,
            "shape": dict(zip(self.shape_names, self.shape.tolist(), strict=True)),
            "spring_share": self.spring_share,
        }


def _real_shape(v: np.ndarray) -> np.ndarray:
    k = int(np.argmax(np.abs(v)))
    if abs(v[k]) == 0.0:
        return np.zeros(v.shape)
    w = (v * np.conj(v[k]) / abs(v[k])).real
    w = w / np.max(np.abs(w))
    return np.where(np.abs(w) < 1e-12, 0.0, w)  # exact decoupling shows as 0, not +-1e-17


def _spring_share(shape: np.ndarray, M: np.ndarray) -> float:
    """Kinetic energy of the spring coordinates over that of angles plus springs (blocks of M)."""
    t_angle = shape[:2] @ M[:2, :2] @ shape[:2]
    t_spring = shape[2:] @ M[2:, 2:] @ shape[2:]
    total = t_angle + t_spring
    return float(t_spring / total) if total > 0 else 0.0


def _pair_label(a: float, b: float, names: tuple[str, str]) -> str:
    """In-phase / anti-phase, or the single coordinate that dominates."""
    big = max(abs(a), abs(b))
    if abs(b) < 0.1 * big:
        return f"mostly {names[0]}"
    if abs(a) < 0.1 * big:
        return f"mostly {names[1]}"
    return "in-phase" if a * b > 0 else "anti-phase"


def _label(shape: np.ndarray, spring_share: float, nq: int) -> str:
    if nq == 2 or spring_share < 0.5:
        return "pendular " + _pair_label(shape[0], shape[1], ("link 1", "link 2"))
    phase = _pair_label(shape[2], shape[3], ("spring 1", "spring 2"))
    return "spring stretch " + phase if not phase.startswith("mostly") else phase.replace("mostly ", "") + " stretch"


@checked()
def modes(
    model: Model, at: str | Equilibrium | Any = "down-down", u: Any = None, *, allow_non_equilibrium: bool = False
) -> tuple[Mode, ...]:
    """Modes of the exact linearization at an equilibrium.

    Parameters
    ----------
    model : Model
        Model to analyse, at its parameters.
    at : str, Equilibrium or array_like of shape (nx,)
        Equilibrium name (solved at torque ``u``), a solved Equilibrium, or a
        state that is an equilibrium under ``u`` (e.g. ``[pi, pi, 0, 0]``).
    u : array_like, shape (2,), optional
        Torques (tau1, tau2) [N.m]; default zero (or the Equilibrium's own).
    allow_non_equilibrium : bool
        Return the eigenstructure of the Jacobian at a state that is not an
        equilibrium (local, "frozen-time" modes) instead of raising.

    Returns
    -------
    tuple of Mode
        Sorted by natural frequency, unstable before decaying at equal frequency.

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Unknown equilibrium name, a state of the wrong size, or a state that is
        not an equilibrium (the message names ``|f(x, u)|`` and suggests
        :func:`pendulab.equilibrium`).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid()  # 1 kg, 1 m links
    >>> for mode in pl.modes(model):  # hanging at rest
    ...     print(mode.label, mode.kind, round(mode.omega_n, 4))
    pendular in-phase oscillatory 2.3972
    pendular anti-phase oscillatory 5.7874
    >>> np.round(np.sqrt(9.81 * (2 + np.array([-1, 1]) * np.sqrt(2))), 4)  # analytic: (g / L)(2 -+ sqrt 2)
    array([2.3972, 5.7874])
    >>> [(mode.kind, round(mode.time_constant, 3)) for mode in pl.modes(model, "up-up")]  # e-folding times [s]
    [('unstable', 0.417), ('decaying', 0.417), ('unstable', 0.173), ('decaying', 0.173)]
    """
    check_model(model)
    if isinstance(at, str):
        at = equilibrium(model, at, u)
    x, uv = operating_point(model, at, u)
    lin = linearize(model, x, uv)
    if not lin.is_equilibrium and not allow_non_equilibrium:
        raise not_equilibrium_error("modes", lin)
    A = lin.A
    M = model.mass_matrix(x)
    nq = model.nq
    ev, V = np.linalg.eig(A)
    scale = max(1.0, float(np.max(np.abs(ev))))
    tol = 1e-7 * scale  # round-off level of eigenvalues of A
    out = []
    for lam, v in zip(ev, V.T, strict=True):
        if lam.imag < -tol:
            continue  # the conjugate partner represents this oscillation
        if abs(lam.imag) > tol:
            kind = "oscillatory"
        elif lam.real > tol:
            kind = "unstable"
        elif lam.real < -tol:
            kind = "decaying"
        else:
            kind = "neutral"
        lam = complex(lam.real, abs(lam.imag)) if kind == "oscillatory" else complex(lam.real, 0.0)
        shape = _real_shape(v[:nq])
        share = _spring_share(shape, M) if nq == 4 else 0.0
        wn = abs(lam)
        out.append(
            Mode(
                eigenvalue=lam,
                kind=kind,
                omega_n=wn,
                freq_hz=wn / (2 * math.pi),
                omega_d=abs(lam.imag),
                damping_ratio=-lam.real / wn if wn > 0 and abs(lam.real) > tol else 0.0,
                time_constant=1.0 / abs(lam.real) if abs(lam.real) > tol else math.inf,
                shape=shape,
                shape_names=model.state_names[:nq],
                spring_share=share,
                label=_label(shape, share, nq),
            )
        )
    out.sort(key=lambda m: (round(m.omega_n, 9), -m.eigenvalue.real))
    return tuple(out)


def mode_table(mode_list: Sequence[Mode]) -> str:
    """Format modes as a plain-text table.

    Parameters
    ----------
    mode_list : sequence of Mode
        Modes, e.g. from :func:`modes`; the first one gives the shape columns.

    Returns
    -------
    str
        One row per mode: label, kind, omega_n [rad/s], f [Hz] (``-`` for a mode that does
        not oscillate: a real eigenvalue has a rate, not a frequency), damping ratio, time
        constant [s] (``-`` if infinite) and shape; ``"(no modes)"`` for an empty list.
    """
    if not mode_list:
        return "(no modes)"
    names = mode_list[0].shape_names
    head = f"{'mode':<28} {'kind':<11} {'omega_n [rad/s]':>15} {'f [Hz]':>8} {'zeta':>7} {'tau [s]':>8}  " + " ".join(
        f"{n:>7}" for n in names
    )
    lines = [head, "-" * len(head)]
    for m in mode_list:
        tau = "-" if math.isinf(m.time_constant) else f"{m.time_constant:.4g}"
        freq = f"{m.freq_hz:.4g}" if m.kind == "oscillatory" else "-"
        lines.append(
            f"{m.label:<28} {m.kind:<11} {m.omega_n:>15.5g} {freq:>8} {m.damping_ratio:>7.3f} {tau:>8}  "
            + " ".join(f"{s:>7.3f}" for s in m.shape)
        )
    return "\n".join(lines)


def stiffness_sweep(k_values: Sequence[float], **params: float) -> dict[str, np.ndarray]:
    """Down-down modal frequencies of the elastic model against spring stiffness (k1 = k2 = k).

    Parameters
    ----------
    k_values : sequence of float
        Stiffnesses [N/m], each > 0.
    **params : float
        Other elastic parameters (m1, m2, L1, L2, g, ...); the rigid reference uses
        the same masses, lengths and g.

    Returns
    -------
    dict
        ``k`` (n,) [N/m]; ``pendular`` (n, 2) and ``spring`` (n, 2) natural
        frequencies [rad/s], ascending; ``rigid`` (2,) [rad/s] of the rigid
        pendulum with the same masses and lengths.

    Raises
    ------
    ValueError
        ``k_values`` is empty or has a non-positive or non-finite entry.
    """
    from ..model.model import elastic, rigid

    k = np.asarray(k_values, dtype=float).ravel()
    if k.size == 0 or not np.all(np.isfinite(k)) or np.any(k <= 0):
        raise ValueError(f"k_values must be positive finite stiffnesses in N/m, got {k_values!r}")
    shared = {n: v for n, v in params.items() if n in ("m1", "m2", "L1", "L2", "g")}
    rigid_w = sorted(m.omega_n for m in modes(rigid(**shared), "down-down") if m.kind == "oscillatory")
    pend, spring = [], []
    for kk in k:
        ms = modes(elastic(**{**params, "k1": float(kk), "k2": float(kk)}), "down-down")
        pend.append(sorted(m.omega_n for m in ms if m.spring_share < 0.5))
        spring.append(sorted(m.omega_n for m in ms if m.spring_share >= 0.5))
    return {"k": k, "pendular": np.array(pend), "spring": np.array(spring), "rigid": np.array(rigid_w)}

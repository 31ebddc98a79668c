"""The a priori model rule of a scene: the cheapest level predicted within tolerance, and its horizon of validity.

:func:`choose_model` predicts, *without running the reference*, the error of
every level of the hierarchy (:mod:`pendulab.scene.levels`) on the scene's
outputs over its horizon, and picks the cheapest level predicted within the
scene's tolerance (the scene's own model always qualifies). Predictions
(constants calibrated by ``benchmarks/bench_model_choice.py``; ``docs/model_choice.md``):

``linearized``
    The linear solution itself is computed (it is the level's run, kept for
    reuse), then the neglected nonlinear terms along it,
    ``r(t) = f(x_lin, u) - A (x_lin - x_eq) - b``, are propagated through the
    linear dynamics (first-order perturbation, exact zero-order hold in the
    modal basis on at most :data:`RESIDUAL_POINTS` times) and mapped to the
    outputs through the output Jacobian: ``C_LINEAR * |C| |e(t)|``.
``rigid``, ``rigid+quasi-static``
    From the spring-to-pendulum frequency ratio and the load, as the swing-up
    planning rule (:mod:`pendulab.analysis.model_error`): each spring stretches by
    ``delta_i = T_i / k_i`` under gravity and the centrifugal load of the energy
    above rest; a start off the quasi-static lengths rings the spring by
    ``dR_i``. The relative length error ``nu = sum (delta_i + dR_i eps) / L_i``
    (``eps = w_p / w_s``) makes a phase error that grows secularly and, over
    chaotic motion, like ``e^(lambda_1 t)``: angle error
    ``nu (C_SECULAR A w_p t / 2 + C_CHAOS expm1(lambda_1 t))``. Position outputs add the
    spring-length error itself: ``delta_i + dR_i`` for rigid links,
    ``dR_i + delta_i eps^2`` with quasi-static lengths.
reference
    The scene's own model at its ``rtol``: ``C_REFERENCE * max(rtol, atol) *
    (1 + w_p t + expm1(lambda_1 t))``.

``lambda_1`` comes from the energy above the hanging rest and the stiffness
(:func:`pendulab.analysis.model_error.lyapunov_exponent`). The horizon of
validity of a level is the first time its predicted error exceeds the tolerance;
for the reference it is the predictability horizon at the scene's ``rtol``, and
``needed_rtol`` is the integrator tolerance that would hold the whole horizon.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.signal import lfilter

from .._checks import positive_float
from ..analysis.model_error import error_growth, frequency_split, lyapunov_exponent, spring_stretch, validity_horizon
from ..integrate import time_grid
from ..integrate.trajectory import Trajectory
from ..model.quasistatic import quasi_static_lengths
from .core import Scene
from .levels import LinearSolution, ModelLevel, level_trajectory, levels_for, linear_solution, scene_signals

__all__ = [
    "LevelPrediction",
    "Verification",
    "ModelChoice",
    "choose_model",
    "measure_levels",
    "C_LINEAR",
    "C_SLOW",
    "C_FAST",
    "C_CHAOS",
    "C_REFERENCE",
    "RESIDUAL_POINTS",
    "SCREEN",
    "DOUBLE_PRECISION_RTOL",
]

#: Safety factor on the first-order error of the linearization (calibrated).
C_LINEAR = 2.0
#: Phase drift of the slow (in-phase) pendular mode per unit nu and unit of its amplitude x frequency (calibrated).
C_SLOW = 0.1
#: Phase drift of the fast (anti-phase) pendular mode per unit nu and unit of its amplitude x frequency (calibrated).
C_FAST = 1.5
#: Chaotic part of the rigid / quasi-static angle error per unit nu (calibrated).
C_CHAOS = 0.1
#: Global error of the reference per unit of its max(rtol, atol), before growth (calibrated).
C_REFERENCE = 10.0
#: At most this many times carry the linearization's residual (cost of the rule, not of the level).
RESIDUAL_POINTS = 200
#: The linearization's residual is computed only when the amplitude screen is below SCREEN x tolerance.
SCREEN = 20.0
#: Smallest integrator tolerance a double-precision run can honour.
DOUBLE_PRECISION_RTOL = 1e-14


@dataclass(frozen=True)
class LevelPrediction:
    """The rule's prediction for one level.

    Attributes
    ----------
    name : str
        Level (one of :data:`pendulab.scene.levels.LEVELS`).
    error : float
        Predicted max abs error over the horizon and the outputs, against the
        scene's own model, in the outputs' units (0 for the reference; inf when the
        level cannot run the scene, e.g. a sine input for ``linearized``).
    horizon : float
        Time [s] up to which the predicted error stays within the tolerance
        (``t_final`` when throughout, 0 when never).
    within : bool
        ``error <= tolerance``.
    note : str
        Why (one line).
    """

    name: str
    error: float
    horizon: float
    within: bool
    note: str = ""


@dataclass(frozen=True)
class Verification:
    """Predicted against measured: the chosen level and the reference, both run.

    Attributes
    ----------
    level : str
        The chosen level.
    predicted_error, measured_error : float
        Max abs error over the horizon and the outputs against the reference, in the outputs' units.
    predicted_horizon, measured_horizon : float
        Time [s] up to which the chosen level's error stays within the tolerance.
    within : bool
        ``measured_error <= tolerance``.
    level_time, reference_time : float
        Wall time [s] of the chosen level's run and of the reference's run.
    reference_error : float or None
        Max abs error of the reference at the scene's rtol against a run at ``rtol * 1e-3``
        (chaotic scenes only, else None), in the outputs' units.
    reference_horizon : float or None
        Measured time [s] up to which the reference stays within the tolerance of that tighter run.
    """

    level: str
    predicted_error: float
    measured_error: float
    predicted_horizon: float
    measured_horizon: float
    within: bool
    level_time: float
    reference_time: float
    reference_error: float | None = None
    reference_horizon: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form (seconds in keys ending ``_s``).

        Returns
        -------
        dict
        """
        return {
            "level": self.level,
            "predicted_error": self.predicted_error,
            "measured_error": self.measured_error,
            "predicted_horizon_s": self.predicted_horizon,
            "measured_horizon_s": self.measured_horizon,
            "within_tolerance": self.within,
            "level_time_s": self.level_time,
            "reference_time_s": self.reference_time,
            "reference_error": self.reference_error,
            "reference_horizon_s": self.reference_horizon,
        }


@dataclass(frozen=True)
class ModelChoice:
    """Outcome of :func:`choose_model`.

    Attributes
    ----------
    scene : str
        Scene name.
    outputs : tuple of str
        Signals judged.
    tolerance : float
        Accepted max abs error of the outputs, in their units.
    t_final : float
        Scene horizon [s].
    chosen : str
        Cheapest level predicted within tolerance (the reference when none is).
    levels : tuple of LevelPrediction
        One per level, cheapest first; the reference last.
    lyapunov : float
        Predicted largest Lyapunov exponent [1/s] (0: regular motion).
    energy_fraction : float
        Energy above the hanging rest over the potential energy from hanging to upright.
    frequency_ratio : float
        Lowest spring over highest pendular frequency w_s / w_p (inf for rigid links).
    reference_horizon : float
        Time [s] up to which the reference at the scene's rtol keeps the outputs within
        tolerance (predictability horizon; ``t_final`` when throughout).
    needed_rtol : float
        Integrator tolerance with which the reference would hold the whole horizon.
    trusted_until : float
        ``min`` of the chosen level's horizon and the reference's [s]: no model at this
        rtol and tolerance gives the outputs beyond it.
    verdict : str
        One line for the user.
    rule_time : float
        Wall time of the rule [s].
    verification : Verification or None
        With ``verify=True``.
    _linear : LinearSolution or None
        The linear solution the rule computed (reused by :meth:`simulate` when ``linearized`` is chosen).
    """

    scene: str
    outputs: tuple[str, ...]
    tolerance: float
    t_final: float
    chosen: str
    levels: tuple[LevelPrediction, ...]
    lyapunov: float
    energy_fraction: float
    frequency_ratio: float
    reference_horizon: float
    needed_rtol: float
    trusted_until: float
    verdict: str
    rule_time: float
    verification: Verification | None = None
    _linear: LinearSolution | None = field(default=None, repr=False, compare=False)

    @property
    def level(self) -> str:
        """Alias of :attr:`chosen`."""
        return self.chosen

    def model_level(self, scene: Scene) -> ModelLevel:
        """The chosen :class:`~pendulab.scene.levels.ModelLevel` of ``scene``.

        Parameters
        ----------
        scene : Scene
            The scene the choice was made for.

        Returns
        -------
        ModelLevel
        """
        return next(lv for lv in levels_for(scene.model) if lv.name == self.chosen)

    def simulate(self, scene: Scene) -> Trajectory:
        """The scene's trajectory with the chosen level (the linear solution of the rule is reused).

        Parameters
        ----------
        scene : Scene
            The scene the choice was made for.

        Returns
        -------
        Trajectory
            In the scene model's signals (see :meth:`ModelLevel.simulate`).
        """
        if self.chosen == "linearized" and self._linear is not None:
            return level_trajectory(scene, self._linear.x, "linearized")
        return self.model_level(scene).simulate(scene)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form of the choice.

        Returns
        -------
        dict
            ``scene``, ``outputs``, ``tolerance``, ``t_final_s``, ``chosen``, ``levels`` (list of
            ``name``, ``predicted_error``, ``horizon_s``, ``within_tolerance``, ``note``),
            ``lyapunov_per_s``, ``energy_fraction``, ``frequency_ratio``, ``reference_horizon_s``,
            ``needed_rtol``, ``trusted_until_s``, ``verdict``, ``rule_time_s`` and ``verification``
            (None without ``verify``).
        """
        return {
            "scene": self.scene,
            "outputs": list(self.outputs),
            "tolerance": self.tolerance,
            "t_final_s": self.t_final,
            "chosen": self.chosen,
            "a_priori": True,
            "levels": [
                {
                    "name": lv.name,
                    "predicted_error": lv.error,
                    "horizon_s": lv.horizon,
                    "within_tolerance": lv.within,
                    "note": lv.note,
                }
                for lv in self.levels
            ],
            "lyapunov_per_s": self.lyapunov,
            "energy_fraction": self.energy_fraction,
            "frequency_ratio": self.frequency_ratio if math.isfinite(self.frequency_ratio) else None,
            "reference_horizon_s": self.reference_horizon,
            "needed_rtol": self.needed_rtol,
            "trusted_until_s": self.trusted_until,
            "verdict": self.verdict,
            "rule_time_s": self.rule_time,
            "verification": None if self.verification is None else self.verification.to_dict(),
        }

    def table(self) -> str:
        """Plain-text table of the predictions (and the verification, if any).

        Returns
        -------
        str
        """
        lines = [
            f"scene {self.scene}: outputs {', '.join(self.outputs)}; tolerance {self.tolerance:g}; horizon {self.t_final:g} s"
            f" (a priori, reference not run)",
            f"{'model':<20} {'predicted error':>15} {'valid until [s]':>16}  within",
        ]
        for lv in self.levels:
            lines.append(
                f"{lv.name:<20} {lv.error:>15.2e} {lv.horizon:>16.3g}  {'yes' if lv.within else 'no '}"
                + (f"  ({lv.note})" if lv.note else "")
            )
        lines.append(f"chosen: {self.chosen} (cheapest predicted within tolerance; rule {self.rule_time * 1e3:.1f} ms)")
        lines.append(self.verdict)
        v = self.verification
        if v is not None:
            lines.append(
                f"verify: {v.level} measured error {v.measured_error:.2e} (predicted {v.predicted_error:.2e}), "
                f"valid until {v.measured_horizon:.3g} s (predicted {v.predicted_horizon:.3g} s); "
                f"{'within' if v.within else 'NOT within'} tolerance; "
                f"run {v.level_time:.3g} s vs reference {v.reference_time:.3g} s"
            )
            if v.reference_horizon is not None:
                lines.append(
                    f"verify: the reference at its rtol is off a 1000x tighter run by {v.reference_error:.2e}, "
                    f"valid until {v.reference_horizon:.3g} s (predicted {self.reference_horizon:.3g} s)"
                )
        return "\n".join(lines)


# -- features -----------------------------------------------------------------
@dataclass(frozen=True)
class _Features:
    w_p: float  # highest pendular frequency [rad/s]
    w_s: float  # lowest spring frequency [rad/s]
    w_slow: float  # lowest pendular frequency [rad/s]
    lam: float  # predicted lambda_1 [1/s]
    amplitude: float  # angular amplitude [rad]
    phase_rate: float  # C_SLOW A_slow w_slow + C_FAST A_fast w_fast [rad/s]
    phase_sum: float  # sum_j A_j w_j over the pendular modes [rad/s]
    energy_fraction: float
    stretch_static: np.ndarray  # delta_i at hanging rest [m]
    stretch_start: np.ndarray  # delta_i of the start's centrifugal load beyond static [m]
    stretch_max: np.ndarray  # delta_i of the largest load (gravity + centrifugal of all energy) beyond static [m]
    ring: np.ndarray  # dR_i: start off the quasi-static lengths [m]
    lengths: np.ndarray  # L_i [m]

    @property
    def stretch(self) -> np.ndarray:
        return self.stretch_static + self.stretch_max

    def offsets(self, t: np.ndarray) -> np.ndarray:
        """Spring-length error of rigid links [m], (len(t), 2): static + centrifugal stretch, growing as the
        pendulum falls over a quarter of its slow period from the start's load to the largest, + the ring."""
        ramp = np.minimum(1.0, (np.asarray(t) * self.w_slow / (math.pi / 2)) ** 2)[:, None]
        dyn = self.stretch_start + (self.stretch_max - self.stretch_start) * ramp
        return self.ring + self.stretch_static + dyn


_HANGING: dict[tuple, tuple] = {}


def _hanging_modes(model: Any) -> tuple:
    """(rest state, its energy [J], eigenvalues, eigenvectors, w_p, w_s) at hanging; kept per model kind and parameters."""
    key = (model.kind, tuple(sorted(model.params.resolved().items())))
    hit = _HANGING.get(key)
    if hit is None:
        x_h = model.rest_state()
        A = np.asarray(model.functions["jac_rhs"](x_h, np.zeros(model.nu), model.p)[0], dtype=float)
        lam_A, V = np.linalg.eig(A)
        hit = (x_h, float(model.energy(x_h)), lam_A, V, *frequency_split(lam_A, model.kind))
        if len(_HANGING) > 256:  # bounded: a sweep over many parameters must not grow memory
            _HANGING.clear()
        _HANGING[key] = hit
    return hit


def _features(scene: Scene) -> _Features:
    model, p = scene.model, scene.model.params
    x_h, e_rest, lam_A, V, w_p, w_s = _hanging_modes(model)
    M1, M2 = p.m1 + p.m2, p.m2
    L = np.array([p.L1, p.L2])
    dV = 2.0 * (M1 * p.g * p.L1 + M2 * p.g * p.L2)
    u_bound = (0.0 if scene.u is None else np.sum(np.abs(scene.u))) + (
        0.0 if scene.u_amplitude is None else np.sum(np.abs(scene.u_amplitude))
    )
    x0 = np.asarray(scene.x0, dtype=float)
    e_above = max(float(model.energy(x0)) - e_rest, 0.0) + math.pi * float(u_bound)
    frac = e_above / dV
    i_th = [model.state_names.index("theta1"), model.state_names.index("theta2")]
    th0 = x0[i_th]
    amplitude = math.acos(max(-1.0, 1.0 - 2.0 * frac)) if frac < 1.0 else math.pi
    amplitude = max(amplitude, float(np.max(np.abs(np.remainder(th0 + math.pi, 2 * math.pi) - math.pi))))
    # Modal amplitudes of the start (linear modes at hanging): the phase error of each mode grows at its frequency;
    # the slow (in-phase) and the fast (anti-phase) pendular mode are weighted apart (C_SLOW, C_FAST).
    freq = np.abs(lam_A.imag)
    pendular = freq < 0.5 * (w_p + w_s) if math.isfinite(w_s) else np.ones(len(freq), bool)
    w_slow = float(np.min(freq[pendular])) if np.any(freq[pendular] > 0) else w_p
    slow = pendular & (freq < 0.5 * (w_slow + w_p))
    try:
        z0 = np.linalg.solve(V, x0 - x_h)
        amp = np.abs(z0) * np.max(np.abs(V[i_th]), axis=0)
        phase_rate = C_SLOW * float(np.sum((amp * freq)[slow])) + C_FAST * float(np.sum((amp * freq)[pendular & ~slow]))
        phase_sum = float(np.sum((amp * freq)[pendular]))
    except np.linalg.LinAlgError:
        phase_rate, phase_sum = C_FAST * amplitude * w_p, amplitude * w_p
    phase_sum = max(phase_sum, amplitude * w_slow)
    lam = lyapunov_exponent(frac, math.sqrt(p.g / L.mean()), w_s / w_p)
    if model.kind != "elastic":
        z = np.zeros(2)
        return _Features(w_p, w_s, w_slow, lam, amplitude, phase_rate, phase_sum, frac, z, z, z, z, L)
    share = np.array([1.0, M2 / M1])  # bob 2's share of the centrifugal load on spring 2
    static = np.array([M1 * p.g, M2 * p.g])
    centrifugal = 2 * e_above * share / L
    start = 2 * float(model.kinetic_energy(x0)) * share / L
    if scene.u is not None:  # a held torque loads the links like a weight at their end
        static = static + np.abs(np.asarray(scene.u, dtype=float)) / L
    k = np.array([p.k1, p.k2])
    stretch_static = np.array([spring_stretch(static[i], k[i]) for i in range(2)])
    try:
        r_qs = quasi_static_lengths(model, th0, x0[4:6], scene.u)
        ring = np.abs(x0[2:4] - r_qs) + np.abs(x0[6:8]) / w_s
    except RuntimeError:  # no quasi-static lengths: the springs cannot hold the motion
        ring = np.full(2, np.inf)
    return _Features(
        w_p, w_s, w_slow, lam, amplitude, phase_rate, phase_sum, frac, stretch_static, start / k, centrifugal / k, ring, L
    )


def _output_gains(scene: Scene, f: _Features) -> dict[str, tuple[float, float]]:
    """Per output (gain on the angle error [unit/rad], index of spring offsets it carries: 0 none, 1 bob 1, 2 both)."""
    gains: dict[str, tuple[float, float]] = {}
    L1, L2 = f.lengths
    for name in scene.outputs:
        group, _ = scene.model.signal_index(name)
        if group == "input":
            gains[name] = (0.0, 0)
        elif name.startswith("theta"):
            gains[name] = (1.0, 0)
        elif name.startswith("omega"):
            gains[name] = (max(f.w_p, 1.0), 0)
        elif name in ("x1", "y1"):
            gains[name] = (L1, 1)
        elif name in ("x2", "y2"):
            gains[name] = (L1 + L2, 2)
        elif name in ("r1", "stretch1"):
            gains[name] = (0.0, 3)
        elif name in ("r2", "stretch2"):
            gains[name] = (0.0, 4)
        elif name in ("v1", "v2"):
            gains[name] = (0.0, 5)
        else:  # energy
            gains[name] = (0.0, 6)
    return gains


def _spring_output_error(kind: int, offsets: np.ndarray, f: _Features, p: Any) -> np.ndarray | float:
    """Error of an output from the spring-length errors ``offsets`` [m], shape (n, 2)."""
    if kind == 0:
        return 0.0
    if kind in (1, 3):
        return offsets[:, 0]
    if kind == 2:
        return offsets[:, 0] + offsets[:, 1]
    if kind == 4:
        return offsets[:, 1]
    if kind == 5:
        return np.max(offsets, axis=1) * f.w_s
    return p.k1 * f.stretch[0] * offsets[:, 0] + p.k2 * f.stretch[1] * offsets[:, 1]


def _reduced_curve(scene: Scene, f: _Features, t: np.ndarray, quasi_static: bool) -> np.ndarray:
    """Predicted max output error of ``rigid`` / ``rigid+quasi-static`` at times ``t``."""
    eps = f.w_p / f.w_s
    offsets = f.offsets(t)  # (n, 2): spring-length errors of rigid links, growing as the pendulum speeds up
    nu = np.sum((offsets - f.ring + f.ring * eps) / f.lengths, axis=1)  # relative length error, (n,)
    nu = np.maximum.accumulate(nu)
    e_th = nu * error_growth(t, f.phase_rate, f.lam, chaotic=C_CHAOS)
    e_th = np.minimum(e_th, 2 * math.pi)  # angles of two motions differ by at most a turn or so
    if quasi_static:  # the lengths carry the load; what remains: the ring and the next order of the slow manifold
        offsets = f.ring + (offsets - f.ring) * eps**2
    worst = np.zeros_like(t)
    for gain, kind in _output_gains(scene, f).values():
        worst = np.maximum(worst, gain * e_th + _spring_output_error(int(kind), offsets, f, scene.model.params))
    return worst


def _reference_curve(scene: Scene, f: _Features, t: np.ndarray, rtol: float) -> np.ndarray:
    growth = 1.0 + f.w_p * t + np.expm1(np.minimum(f.lam * t, 700.0))
    gain = max((g for g, _ in _output_gains(scene, f).values()), default=1.0)
    return C_REFERENCE * rtol * growth * max(gain, 1.0)


def _linear_curve(scene: Scene, lin: LinearSolution, t_grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(times, predicted max output error) of the linearized level: residual propagated, outputs through |C|."""
    model = scene.model
    n = len(t_grid)
    stride = max(1, math.ceil((n - 1) / RESIDUAL_POINTS))
    idx = np.arange(0, n, stride)
    t, X = t_grid[idx], lin.x[idx]
    u = np.zeros(model.nu) if scene.u is None else np.asarray(scene.u, dtype=float)
    R = model.rhs(X, u) - (X - lin.x_eq) @ lin.A.T - lin.b
    lam, V = lin.eigenvalues, lin.eigenvectors
    if V is None or len(t) < 2:
        return t, np.full(len(t), np.inf)
    W = np.linalg.solve(V, R.T).T  # modal residual, (n, nx)
    h = float(t[1] - t[0])
    z = lam * h
    small = np.abs(z) < 1e-8
    gain = h * np.where(small, 1.0 + z / 2, np.expm1(z) / np.where(small, 1.0, z))
    C = 0.5 * (W[:-1] + W[1:]) * gain  # exact zero-order hold of z' = lam z + w over each step (w: its mean)
    Z = np.zeros_like(W)
    for j, mu in enumerate(np.exp(z)):  # z[k+1] = mu z[k] + C[k], one recursion per mode in C (lfilter)
        Z[1:, j] = lfilter([1.0], [1.0, -mu], C[:, j])
    E = np.abs(np.real(Z @ V.T))  # state error, (n, nx)
    # Output Jacobian at the equilibrium by central differences (outputs are smooth in the state).
    h = 1e-6
    P = lin.x_eq + np.vstack([np.eye(model.nx) * h, -np.eye(model.nx) * h])
    Yp = scene_signals(scene, P)
    worst = np.zeros(len(t))
    for name in scene.outputs:
        c = np.abs(Yp[name][: model.nx] - Yp[name][model.nx :]) / (2 * h)
        worst = np.maximum(worst, E @ c)
    return t, C_LINEAR * worst


def choose_model(
    scene: Scene,
    *,
    tolerance: float | None = None,
    verify: bool = False,
) -> ModelChoice:
    """Pick the cheapest model level predicted to keep the scene's outputs within tolerance, without running the reference.

    Parameters
    ----------
    scene : Scene
        A loaded scene (:func:`pendulab.scene.load_scene`).
    tolerance : float, optional
        Accepted max abs error of the outputs, in their units; default the scene's
        ``[outputs] tolerance``.
    verify : bool
        Also run the chosen level and the reference (and, on a chaotic scene, the
        reference at ``rtol * 1e-3``) and report predicted against measured error
        (:attr:`ModelChoice.verification`).

    Returns
    -------
    ModelChoice
        The chosen level, every level's predicted error and horizon of validity, the
        reference's predictability horizon and the tolerance it would need.

    Raises
    ------
    TypeError
        ``scene`` is not a :class:`Scene`.
    ValueError
        No tolerance (neither given nor in the scene), or not a positive number.
    SimulationError
        With ``verify``: the reference or the chosen level failed to integrate.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene must be a pendulab Scene (pendulab.scene.load_scene), got {type(scene).__name__}")
    tol = scene.tolerance if tolerance is None else tolerance
    if tol is None:
        raise ValueError(f"scene {scene.name!r}: tolerance is missing: state [outputs] tolerance in the scene or pass tolerance=")
    tol = positive_float("tolerance", tol, "(max abs error of the outputs, in their units)")
    if not isinstance(verify, bool):
        raise TypeError(f"verify must be True or False, got {verify!r}")
    start = time.perf_counter()
    f = _features(scene)
    t_grid = time_grid(scene.t_final, scene.dt)
    t_pred = np.linspace(0.0, scene.t_final, 201)
    preds: list[LevelPrediction] = []
    lin = None
    gain = max((g for g, _ in _output_gains(scene, f).values()), default=1.0)
    # Screen: a pendulum of amplitude A runs slow by A^2 / 16 of its frequency; past SCREEN x tolerance
    # the linearization is hopeless and its residual is not worth computing.
    screen = max(gain, 1.0) * f.amplitude**2 * f.phase_sum * t_pred / 16
    if getattr(scene, "u_amplitude", None) is not None:
        preds.append(LevelPrediction("linearized", math.inf, 0.0, False, "cannot run: sine input (constant torques only)"))
    elif screen[-1] > SCREEN * tol:
        note = f"screened: amplitude {f.amplitude:.2g} rad, A^2 sum(A_j w_j) T / 16 = {screen[-1]:.2g} > {SCREEN:g} x tolerance"
        preds.append(_prediction("linearized", t_pred, screen, tol, note))
    else:
        try:
            lin = linear_solution(scene)
            t_lin, e_lin = _linear_curve(scene, lin, t_grid)
            if not np.all(np.isfinite(lin.x)):
                e_lin = np.full_like(t_lin, np.inf)
            preds.append(_prediction("linearized", t_lin, e_lin, tol, "neglected nonlinear terms along the linear solution"))
        except RuntimeError as exc:
            preds.append(LevelPrediction("linearized", math.inf, 0.0, False, f"cannot run: {str(exc).splitlines()[0]}"))
    if scene.model.kind == "elastic":
        eps = f.w_p / f.w_s
        for name, qs in (("rigid", False), ("rigid+quasi-static", True)):
            e = _reduced_curve(scene, f, t_pred, qs)
            note = f"w_s/w_p = {1 / eps:.3g}, stretch {np.sum(f.stretch):.2g} m, ring {np.sum(f.ring):.2g} m"
            preds.append(_prediction(name, t_pred, e, tol, note))
    rtol = max(scene.rtol, scene.atol)
    e_ref = _reference_curve(scene, f, t_pred, rtol)
    ref_h = validity_horizon(t_pred, e_ref, tol)
    needed = rtol * tol / float(e_ref[-1])
    ref_name = "elastic" if scene.model.kind == "elastic" else "rigid"
    preds.append(LevelPrediction(ref_name, 0.0, scene.t_final, True, "reference (the scene's own model)"))
    chosen = next(p for p in preds if p.within)
    trusted = min(chosen.horizon if chosen.name != ref_name else scene.t_final, ref_h)
    if ref_h >= scene.t_final:
        verdict = f"the reference at rtol {rtol:g} holds the whole horizon ({scene.t_final:g} s)"
    elif needed >= DOUBLE_PRECISION_RTOL:
        verdict = (
            f"chaotic (lambda_1 ~ {f.lam:.2g} /s): at rtol {rtol:g} no model keeps the outputs within {tol:g} past "
            f"~{ref_h:.3g} s; the whole {scene.t_final:g} s needs rtol <= {needed:.1e}"
        )
    else:
        verdict = (
            f"chaotic (lambda_1 ~ {f.lam:.2g} /s): no model keeps the outputs within {tol:g} past ~{ref_h:.3g} s at rtol "
            f"{rtol:g}; the whole {scene.t_final:g} s would need rtol {needed:.1e}, beyond double precision"
        )
    rule_time = time.perf_counter() - start
    choice = ModelChoice(
        scene.name,
        tuple(scene.outputs),
        tol,
        float(scene.t_final),
        chosen.name,
        tuple(preds),
        f.lam,
        f.energy_fraction,
        f.w_s / f.w_p,
        ref_h,
        needed,
        trusted,
        verdict,
        rule_time,
        None,
        lin,
    )
    if not verify:
        return choice
    return _verified(scene, choice)


def _prediction(name: str, t: np.ndarray, e: np.ndarray, tol: float, note: str) -> LevelPrediction:
    err = float(np.max(e)) if len(e) else math.inf
    if not math.isfinite(err):
        err = math.inf
    return LevelPrediction(name, err, validity_horizon(t, e, tol), err <= tol, note)


def _error_curve(scene: Scene, X: np.ndarray, ref: dict[str, np.ndarray]) -> np.ndarray:
    if not np.all(np.isfinite(X)):
        return np.full(X.shape[0], np.inf)
    sig = scene_signals(scene, X)
    return np.max(np.vstack([np.abs(sig[n] - ref[n]) for n in scene.outputs]), axis=0)


def measure_levels(scene: Scene, *, tolerance: float | None = None) -> dict[str, dict[str, float]]:
    """Run every level and the reference; measured error and horizon of validity per level.

    Parameters
    ----------
    scene : Scene
        The scene.
    tolerance : float, optional
        Accepted error (default the scene's).

    Returns
    -------
    dict of str to dict
        Per level: ``error`` (max abs output error against the reference, inf when the level
        failed), ``horizon`` [s] (first time the error exceeds the tolerance) and ``time`` [s]
        (wall time of one run).

    Raises
    ------
    ValueError
        No positive tolerance.
    """
    tol = positive_float("tolerance", scene.tolerance if tolerance is None else tolerance)
    t = time_grid(scene.t_final, scene.dt)
    levels = levels_for(scene.model)
    t0 = time.perf_counter()
    X_ref = levels[-1].run(scene)
    out = {levels[-1].name: {"error": 0.0, "horizon": float(scene.t_final), "time": time.perf_counter() - t0}}
    ref = scene_signals(scene, X_ref)
    for lv in levels[:-1]:
        t0 = time.perf_counter()
        try:
            X = lv.run(scene)
        except RuntimeError:
            out[lv.name] = {"error": math.inf, "horizon": 0.0, "time": math.nan}
            continue
        wall = time.perf_counter() - t0
        e = _error_curve(scene, X, ref)
        out[lv.name] = {"error": float(np.max(e)), "horizon": validity_horizon(t, e, tol), "time": wall}
    return out


def _verified(scene: Scene, choice: ModelChoice) -> ModelChoice:
    import dataclasses

    t = time_grid(scene.t_final, scene.dt)
    levels = {lv.name: lv for lv in levels_for(scene.model)}
    ref_level = list(levels.values())[-1]
    t0 = time.perf_counter()
    X_ref = ref_level.run(scene)
    t_ref = time.perf_counter() - t0
    ref = scene_signals(scene, X_ref)
    t0 = time.perf_counter()
    X = X_ref if choice.chosen == ref_level.name else levels[choice.chosen].run(scene)
    t_level = time.perf_counter() - t0 if choice.chosen != ref_level.name else t_ref
    e = _error_curve(scene, X, ref)
    pred = next(p for p in choice.levels if p.name == choice.chosen)
    ref_err = ref_h = None
    if choice.reference_horizon < scene.t_final or choice.lyapunov > 0.1:
        from ..integrate import simulate

        tight = max(scene.rtol * 1e-3, DOUBLE_PRECISION_RTOL)
        X_t = simulate(
            scene.model, scene.x0, scene.t_final, scene.dt, scene.method, tight, max(scene.atol * 1e-3, 1e-16), scene.input_spec()
        ).x
        e_ref = _error_curve(scene, X_ref, scene_signals(scene, X_t))
        ref_err, ref_h = float(np.max(e_ref)), validity_horizon(t, e_ref, choice.tolerance)
    v = Verification(
        choice.chosen,
        pred.error,
        float(np.max(e)),
        pred.horizon,
        validity_horizon(t, e, choice.tolerance),
        bool(np.max(e) <= choice.tolerance),
        t_level,
        t_ref,
        ref_err,
        ref_h,
    )
    return dataclasses.replace(choice, verification=v)

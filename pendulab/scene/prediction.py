"""The a priori predictions of :func:`pendulab.scene.choose_model`: features of a scene and predicted error curves.

No level and no reference is run here: the modes at hanging (cached per model parameters), the
energy, the spring load and the start give each level's predicted error against time
(``docs/model_choice.md`` has the formulas; the constants are calibrated by
``benchmarks/bench_model_choice.py``). The linearized level's own solution is the one exception:
it is the level's run, computed once and reused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.signal import lfilter
from scipy.special import ellipk

from ..analysis.model_error import error_growth, frequency_split, lyapunov_exponent, spring_stretch
from ..model.quasistatic import quasi_static_lengths
from .core import Scene
from .levels import LinearSolution, scene_signals

__all__ = [
    "C_LINEAR",
    "C_SLOW",
    "C_FAST",
    "C_CHAOS",
    "C_REFERENCE",
    "C_ENERGY",
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
#: Energy error of a reduced level per unit of k delta^2 under the largest load (calibrated on rate and energy outputs).
C_ENERGY = 4.0
#: At most this many times carry the linearization's residual (cost of the rule, not of the level).
RESIDUAL_POINTS = 200
#: The linearization's residual is computed only when the amplitude screen is below SCREEN x tolerance.
SCREEN = 20.0
#: Smallest integrator tolerance a double-precision run can honour.
DOUBLE_PRECISION_RTOL = 1e-14


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
    stretch_start: np.ndarray  # |delta_i| under the start's own load (gravity along the links + centrifugal) [m]
    stretch_max: np.ndarray  # delta_i of the largest load (gravity + centrifugal of all energy) beyond static [m]
    ring: np.ndarray  # dR_i: start off the quasi-static lengths [m]
    lengths: np.ndarray  # L_i [m]
    kinetic_share: float = 1.0  # sqrt(kinetic / total energy above rest) at the start: 0 from rest
    quarter: float = 0.0  # time [s] the motion takes to reach its largest load: a quarter of the slow period
    energy_rigid: float = 0.0  # |E(x0) - E(rigid links at rest length, v = 0)| [J]: the rigid level's energy offset

    @property
    def stretch(self) -> np.ndarray:
        return self.stretch_static + self.stretch_max

    def offsets(self, t: np.ndarray) -> np.ndarray:
        """Spring-length error of rigid links [m], (len(t), 2): the stretch under the start's load, growing as
        the pendulum falls over a quarter of its (amplitude-dependent) slow period to the largest load, + the ring."""
        ramp = np.minimum(1.0, (np.asarray(t) / self.quarter) ** 2)[:, None] if self.quarter > 0 else 1.0
        final = self.stretch_static + self.stretch_max
        return self.ring + self.stretch_start + np.maximum(final - self.stretch_start, 0.0) * ramp

    def envelope(self, t: np.ndarray) -> np.ndarray:
        """Envelope of a phase error's angle error per unit of its secular size: a mode started at its turning
        point (at rest) has ``A dw t |sin(w t)|``, which grows as ``w t`` over the first radian of phase."""
        return np.minimum(1.0, self.kinetic_share + self.w_slow * np.asarray(t))


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
    kinetic_share = math.sqrt(min(1.0, float(model.kinetic_energy(x0)) / e_above)) if e_above > 0 else 1.0
    # A pendulum of amplitude A swings slower than its linear mode by 2 K(sin^2(A / 2)) / pi (capped near the top).
    stretch_period = 2.0 / math.pi * float(ellipk(math.sin(min(amplitude, 3.0) / 2) ** 2))
    quarter = math.pi / 2 / w_slow * stretch_period if w_slow > 0 else 0.0
    if model.kind != "elastic":
        z = np.zeros(2)
        return _Features(w_p, w_s, w_slow, lam, amplitude, phase_rate, phase_sum, frac, z, z, z, z, L, kinetic_share, quarter)
    share = np.array([1.0, M2 / M1])  # bob 2's share of the centrifugal load on spring 2
    static = np.array([M1 * p.g, M2 * p.g])
    centrifugal = 2 * e_above * share / L
    start = 2 * float(model.kinetic_energy(x0)) * share / L
    if scene.u is not None:  # a held torque loads the links like a weight at their end
        static = static + np.abs(np.asarray(scene.u, dtype=float)) / L
    k = np.array([p.k1, p.k2])
    stretch_static = np.array([spring_stretch(static[i], k[i]) for i in range(2)])
    stretch_start = stretch_static + start / k
    try:
        r_qs = quasi_static_lengths(model, th0, x0[4:6], scene.u)
        ring = np.abs(x0[2:4] - r_qs) + np.abs(x0[6:8]) / w_s
        stretch_start = np.abs(r_qs - L)  # the start's own load (a raised link carries less of its weight)
    except RuntimeError:  # no quasi-static lengths: the springs cannot hold the motion
        ring = np.full(2, np.inf)
    # The rigid level books the energy with springs at rest length and still: a constant offset from the start's.
    energy_rigid = abs(float(model.energy(x0)) - float(model.energy(np.concatenate([th0, L, x0[4:6], np.zeros(2)]))))
    return _Features(
        w_p,
        w_s,
        w_slow,
        lam,
        amplitude,
        phase_rate,
        phase_sum,
        frac,
        stretch_static,
        stretch_start,
        centrifugal / k,
        ring,
        L,
        kinetic_share,
        quarter,
        energy_rigid,
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
            gains[name] = (max(f.w_p, 1.0), 7)
        elif name in ("x1", "y1"):
            gains[name] = (L1, 1)
        elif name in ("x2", "y2"):
            gains[name] = (math.hypot(L1, L2), 2)  # the two angle errors are not in phase (calibrated)
        elif name in ("r1", "stretch1"):
            gains[name] = (0.0, 3)
        elif name in ("r2", "stretch2"):
            gains[name] = (0.0, 4)
        elif name in ("v1", "v2"):
            gains[name] = (0.0, 5)
        else:  # energy: the torques' work along a different path, and the springs' share (kind 6)
            torque = (0.0 if scene.u is None else np.sum(np.abs(scene.u))) + (
                0.0 if scene.u_amplitude is None else np.sum(np.abs(scene.u_amplitude))
            )
            gains[name] = (float(torque), 6)
    return gains


def _spring_output_error(kind: int, offsets: np.ndarray, f: _Features, p: Any, quasi_static: bool) -> np.ndarray | float:
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
    if kind == 7:
        # A ringing spring accelerates its bob radially by dR w_s^2, which turns the next link at w_s: a fast
        # part dR w_s / L of the link rates that no reduced level has.
        return float(np.sum(f.ring[np.isfinite(f.ring)])) * f.w_s / float(np.min(f.lengths)) if math.isfinite(f.w_s) else 0.0
    # Energy. Rigid links at rest length conserve the rigid energy, which differs from the scene's by the start's
    # offset (springs at rest length, still): exact but for the torque's work along a different path, hence 2x.
    # Quasi-static lengths book the springs' k delta^2 under the load, which changes along the motion.
    if not quasi_static:
        return np.full(len(offsets), 2.0 * f.energy_rigid)
    k = np.array([p.k1, p.k2])
    return C_ENERGY * np.sum(k * f.stretch * np.maximum(offsets, f.stretch), axis=1)


def _reduced_curve(scene: Scene, f: _Features, t: np.ndarray, quasi_static: bool) -> np.ndarray:
    """Predicted max output error of ``rigid`` / ``rigid+quasi-static`` at times ``t``."""
    eps = f.w_p / f.w_s
    offsets = f.offsets(t)  # (n, 2): spring-length errors of rigid links, growing as the pendulum speeds up
    nu = np.sum((offsets - f.ring + f.ring * eps) / f.lengths, axis=1)  # relative length error, (n,)
    nu = np.maximum.accumulate(nu)
    e_th = nu * error_growth(t, f.phase_rate, f.lam, chaotic=C_CHAOS) * f.envelope(t)
    e_th = np.minimum(e_th, 2 * math.pi)  # angles of two motions differ by at most a turn or so
    if quasi_static:  # the lengths carry the load; what remains: the ring and the next order of the slow manifold
        offsets = f.ring + (offsets - f.ring) * eps**2
    worst = np.zeros_like(t)
    for gain, kind in _output_gains(scene, f).values():
        worst = np.maximum(worst, gain * e_th + _spring_output_error(int(kind), offsets, f, scene.model.params, quasi_static))
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
    if lin.u_sine is not None:
        u = u + lin.u_sine[idx]
    R = model.rhs(X, u) - (X - lin.x_eq) @ lin.A.T - lin.forcing(idx)
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
    # Output Jacobian by central differences (outputs are smooth in the state) at the equilibrium and at the
    # linear solution's farthest state: an output flat at the equilibrium (the energy) has its slope there.
    h = 1e-6
    far = X[int(np.argmax(np.max(np.abs(X - lin.x_eq), axis=1)))]
    steps = np.vstack([np.eye(model.nx) * h, -np.eye(model.nx) * h])
    P = np.vstack([lin.x_eq + steps, far + steps])
    Yp = scene_signals(replace(scene, u_amplitude=None), P)  # the state's part: a sine input adds no slope
    worst = np.zeros(len(t))
    n = model.nx
    for name in scene.outputs:
        y = Yp[name]
        c = np.maximum(np.abs(y[:n] - y[n : 2 * n]), np.abs(y[2 * n : 3 * n] - y[3 * n :])) / (2 * h)
        worst = np.maximum(worst, E @ c)
    return t, C_LINEAR * worst

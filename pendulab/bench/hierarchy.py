"""Model no more than a scene needs, measured: every level of the hierarchy run on a scene (a posteriori).

The a priori rule (:func:`pendulab.scene.choose_model`) predicts each level's error without
running the reference; this module runs them all and measures, so it is the rule's calibration
and test benchmark (:func:`measure_levels`, ``benchmarks/bench_model_choice.py``) and the
``pendulab scene check --measure`` / ``pendulab bench hierarchy`` study.

Levels, cheapest first (all built from the scene's own model functions):

``linearized``
    The scene's model linearized about the nearest equilibrium (angles rounded
    to multiples of pi; spring lengths from :func:`quasi_static_state` at rest),
    propagated exactly on the output grid (matrix exponential, zero-order-held
    torques); outputs through the nonlinear output map.
``rigid``
    The rigid counterpart (same m, L, g, joint dampers; links of the springs'
    rest length), started from the scene's angles and rates.
``rigid+quasi-static``
    The rigid motion with quasi-static spring lengths r*(theta, omega) (the
    springs' static and centrifugal stretch, zero radial acceleration) added
    afterwards, without their fast dynamics.
``elastic``
    The scene's full elastic model: the reference.

Every level produces a state trajectory in the scene model's state order, so
errors are measured on the scene's outputs (state or output names) against
the reference, as the maximum absolute difference over the output grid.
The choice is the level with the smallest measured cost (median wall time)
among those within the scene's tolerance, where costs within ``TIE_RATIO``
of the cheapest count as equal and the simpler model wins; the reference
always qualifies.
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from .._checks import check_budget, is_interrupt, positive_float
from ..analysis.model_error import validity_horizon
from ..integrate import time_grid
from ..model.model import elastic
from ..scene import Scene
from ..scene.choice import error_curve
from ..scene.levels import LEVELS, ModelLevel, levels_for, scene_signals
from .workprecision import watch_interrupt

__all__ = [
    "LevelResult",
    "HierarchyReport",
    "ModelLevel",
    "check_scene",
    "measure_levels",
    "measure_model_choice",
    "levels_for",
    "stiffness_amplitude_study",
    "LEVELS",
    "TIE_RATIO",
]

#: Measured costs within this factor of the cheapest count as a tie (simpler model wins).
TIE_RATIO = 1.5


@dataclass(frozen=True)
class LevelResult:
    """Error and cost of one level on a scene.

    Attributes
    ----------
    name : str
        Level name (one of ``LEVELS``).
    error : float
        Max abs error over the grid and the scene outputs, in their units
        (inf when the level failed or went non-finite; 0 for the reference).
    errors : dict of str to float
        The same per output.
    wall_time : float
        Median wall time [s] (nan when the level failed).
    within : bool
        ``error`` is within the tolerance.
    note : str
        ``"reference"``, the failure message, or empty.
    """

    name: str
    error: float  # max abs error over the grid and the scene outputs (their units)
    errors: dict[str, float]  # per output
    wall_time: float  # median wall time [s]
    within: bool
    note: str = ""


@dataclass(frozen=True)
class HierarchyReport:
    """Outcome of :func:`check_scene`.

    Attributes
    ----------
    scene : str
        Scene name.
    outputs : tuple of str
        Signals compared (state or output names).
    tolerance : float
        Accepted max abs error, in the outputs' units.
    reference : str
        The reference level with its method and rtol.
    levels : tuple of LevelResult
        One per level, cheapest model first, the reference last.
    chosen : str
        Name of the chosen level.
    """

    scene: str
    outputs: tuple[str, ...]
    tolerance: float
    reference: str
    levels: tuple[LevelResult, ...]
    chosen: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly form of the report.

        Returns
        -------
        dict
            ``scene``, ``outputs``, ``tolerance``, ``reference``, ``chosen`` and
            ``levels``: a list of dicts with ``name``, ``error``, ``errors``,
            ``wall_time_s``, ``within_tolerance`` and ``note``.
        """
        return {
            "scene": self.scene,
            "outputs": list(self.outputs),
            "tolerance": self.tolerance,
            "reference": self.reference,
            "chosen": self.chosen,
            "levels": [
                {
                    "name": lv.name,
                    "error": lv.error,
                    "errors": lv.errors,
                    "wall_time_s": lv.wall_time,
                    "within_tolerance": lv.within,
                    "note": lv.note,
                }
                for lv in self.levels
            ],
        }

    def table(self) -> str:
        """Plain-text table of the levels.

        Returns
        -------
        str
            A header, one line per level (max error, wall time [s], within
            tolerance, note) and the chosen level.
        """
        lines = [
            f"scene {self.scene}: outputs {', '.join(self.outputs)}; tolerance {self.tolerance:g}; reference {self.reference}",
            f"{'model':<20} {'max error':>11} {'wall time [s]':>14}  within",
        ]
        for lv in self.levels:
            mark = "yes" if lv.within else "no"
            lines.append(
                f"{lv.name:<20} {lv.error:>11.3e} {lv.wall_time:>14.4f}  {mark}{'  (' + lv.note + ')' if lv.note else ''}"
            )
        lines.append(f"chosen: {self.chosen} (cheapest within tolerance)")
        return "\n".join(lines)


def _timed(fn: Callable[[], np.ndarray], repeats: int) -> tuple[np.ndarray, float]:
    times, X = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        X = fn()
        times.append(time.perf_counter() - start)
    return X, statistics.median(times)


def check_scene(scene: Scene, *, repeats: int = 3, tolerance: float | None = None) -> HierarchyReport:
    """Run the model hierarchy on a scene and pick the cheapest model within tolerance.

    Parameters
    ----------
    scene : Scene
        A loaded scene (``pendulab.scene.load_scene``) or any object with the
        attributes of :class:`Scene`.
    repeats : int
        Timed runs per level; the cost is the median wall time [s].
    tolerance : float, optional
        Overrides the scene's ``[outputs] tolerance`` (in the outputs' units).

    Returns
    -------
    HierarchyReport

    Raises
    ------
    ValueError
        No tolerance (neither in the scene nor given), or ``repeats`` < 1.
    """
    tol = scene.tolerance if tolerance is None else tolerance
    if tol is None or not (isinstance(tol, (int, float)) and tol > 0):
        raise ValueError(f"scene {scene.name!r}: tolerance must be a positive number ([outputs] tolerance), got {tol!r}")
    if not isinstance(repeats, int) or repeats < 1:
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")
    check_budget("repeats", "repeats", repeats)
    levels = levels_for(scene.model)
    with watch_interrupt() as interrupted:
        results, X_ref, wall_ref = _run_levels(scene, levels, repeats, tol, interrupted)
    results.append(LevelResult(levels[-1].name, 0.0, dict.fromkeys(scene.outputs, 0.0), wall_ref, True, "reference"))
    ok = [r for r in results if r.within]
    fastest = min(r.wall_time for r in ok)
    # Timings are noisy on a shared machine: costs within TIE_RATIO of the fastest
    # count as equal, and the simpler model (earlier in the hierarchy) wins the tie.
    chosen = next(r.name for r in ok if r.wall_time <= TIE_RATIO * fastest)
    return HierarchyReport(
        scene.name,
        tuple(scene.outputs),
        float(tol),
        f"{levels[-1].name} ({scene.method}, rtol {scene.rtol:g})",
        tuple(results),
        chosen,
    )


def _run_levels(
    scene: Scene, levels: tuple[ModelLevel, ...], repeats: int, tol: float, interrupted: Callable[[], bool]
) -> tuple[list[LevelResult], np.ndarray, float]:
    X_ref, wall_ref = _timed(lambda: levels[-1].run(scene), repeats)  # a failing reference propagates
    if interrupted():  # a native solver swallowed a Ctrl-C (and retried): stop anyway
        raise KeyboardInterrupt
    ref = scene_signals(scene, X_ref)
    results = []
    for lv in levels[:-1]:
        try:
            X, wall = _timed(lambda lv=lv: lv.run(scene), repeats)
        except RuntimeError as exc:  # e.g. no quasi-static solution, or an integrator failure
            if interrupted() or is_interrupt(exc):  # ... but a Ctrl-C is never a failed level
                raise KeyboardInterrupt from exc
            errors = dict.fromkeys(scene.outputs, math.inf)
            results.append(LevelResult(lv.name, math.inf, errors, math.nan, False, f"failed: {str(exc).splitlines()[0]}"))
            continue
        sig = scene_signals(scene, X) if np.all(np.isfinite(X)) else None
        errors = {n: (float(np.max(np.abs(sig[n] - ref[n]))) if sig is not None else math.inf) for n in scene.outputs}
        err = max(errors.values())
        results.append(LevelResult(lv.name, err, errors, wall, err <= tol))
        if interrupted():
            raise KeyboardInterrupt
    return results, X_ref, wall_ref


def measure_model_choice(scene: Scene, *, repeats: int = 3) -> tuple[ModelLevel, HierarchyReport]:
    """The cheapest model level within the scene's tolerance, and the report.

    Parameters
    ----------
    scene : Scene
        A loaded scene with an ``[outputs] tolerance``.
    repeats : int
        Timed runs per level (see :func:`check_scene`).

    Returns
    -------
    level : ModelLevel
        ``level.simulate(scene)`` gives the scene's trajectory with that level
        (in the scene model's signal names); ``level.model`` is the Model it integrates.
    report : HierarchyReport
        The check behind the choice.

    Raises
    ------
    ValueError
        As :func:`check_scene`: no positive tolerance, or ``repeats`` < 1.
    """
    report = check_scene(scene, repeats=repeats)
    level = next(lv for lv in levels_for(scene.model) if lv.name == report.chosen)
    return level, report


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
        e = error_curve(scene, X, ref)
        out[lv.name] = {"error": float(np.max(e)), "horizon": validity_horizon(t, e, tol), "time": wall}
    return out


# -- stiffness x amplitude study ----------------------------------------------
def stiffness_amplitude_study(
    ks: tuple[float, ...] = (1e2, 1e3, 1e4, 1e5, 1e6),
    amplitudes: tuple[float, ...] = (0.05, 0.3, 1.0, 2.0),
    *,
    t_final: float = 5.0,
    tolerance: float = 1e-2,
    repeats: int = 1,
    progress: Callable[[int, int, str], None] | None = None,
) -> list[dict[str, Any]]:
    """Hierarchy check over spring stiffness and release angle (theta1 = theta2 = amplitude).

    Scenes: m = 1 kg, L = 1 m, undamped, springs at their static length, outputs
    theta1, theta2, x2, y2 over ``t_final`` [s] with CVODES BDF at 1e-10.

    Parameters
    ----------
    ks : tuple of float
        Spring stiffnesses k1 = k2 [N/m].
    amplitudes : tuple of float
        Release angles [rad].
    t_final : float
        Horizon of each scene [s].
    tolerance : float
        Accepted max abs error of the outputs ([rad] and [m]).
    repeats : int
        Timed runs per level.
    progress : callable(int, int, str), optional
        Called as ``progress(done, total, message)`` after each scene.

    Returns
    -------
    list of dict
        One per (k, amplitude): ``k``, ``amplitude``, ``chosen``, and
        ``error[<level>]`` and ``time[<level>]`` [s] per level.
    """
    rows = []
    total, done = len(ks) * len(amplitudes), 0
    for k in ks:
        model = elastic(k1=k, k2=k)
        for a in amplitudes:
            sc = Scene(
                name=f"k={k:g}, theta={a:g}",
                description="stiffness x amplitude study",
                model=model,
                initial=MappingProxyType({"theta1": a, "theta2": a}),
                x0=model.state(theta1=a, theta2=a),
                t_final=t_final,
                dt=0.01,
                method="cvodes",
                rtol=1e-10,
                atol=1e-10,
                outputs=("theta1", "theta2", "x2", "y2"),
                tolerance=tolerance,
            )
            rep = check_scene(sc, repeats=repeats)
            row: dict[str, Any] = {"k": k, "amplitude": a, "chosen": rep.chosen}
            for lv in rep.levels:
                row[f"error[{lv.name}]"] = lv.error
                row[f"time[{lv.name}]"] = lv.wall_time
            rows.append(row)
            done += 1
            if progress is not None:
                progress(done, total, f"hierarchy k={k:g} theta={a:g}")
    return rows

"""What running a model level costs in this process: preparation it still owes (compilation) plus the integration.

The a priori rule (:func:`pendulab.scene.choose_model`) picks the cheapest level predicted within tolerance;
"cheapest" is this estimate, not the order of the hierarchy. A short scene is dominated by one-time
preparation: a rigid level that first compiles a heyoka Taylor integrator (0.3 s idle, 1.27 s measured on
a loaded machine) costs more than an elastic reference whose native library is already loaded (0.1 s), so
a compilation counts only while it is still owed (:func:`pendulab.native.loader.library_state`,
:func:`pendulab.integrate.taylor.cache.is_compiled`).

The integration estimate is ``n_out * OUTPUT_S + T * omega * (1e-8 / tol)**(1/5) * SECONDS_PER_RADIAN``:
explicit and Taylor methods follow the fastest mode at the start (``omega_max``), implicit ones step over
it and follow the pendular rate. The constants were measured on a 2-core x86-64 machine (5 s runs, rigid
and elastic k = 1e5 N/m, tol 1e-6 / 1e-8, warm caches); they rank methods and levels, they are not a
stopwatch (within ~3x of the measured run in those cases).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..integrate.auto import EXCITATION_LIMIT, choose_method
from ..model.counterpart import rigid_counterpart
from .core import Scene

__all__ = ["LevelCost", "level_cost", "PREPARATION_S", "SECONDS_PER_RADIAN"]

#: One-time preparation per process [s]: a heyoka Taylor compile (per structure and tolerance), a native
#: library's C build (once per machine, then cached on disk) and its load from disk.
PREPARATION_S: dict[str, dict[str, float]] = {
    "taylor": {"rigid": 0.32, "elastic": 0.54},
    "native build": {"rigid": 0.58, "elastic": 1.48},
    "native load": {"rigid": 0.01, "elastic": 0.01},
}
#: Integration cost per radian of the followed mode at tol 1e-8 [s/rad], by method family and model kind.
SECONDS_PER_RADIAN: dict[str, dict[str, float]] = {
    "taylor": {"rigid": 3e-6, "elastic": 3e-6},
    "compiled": {"rigid": 2e-6, "elastic": 2e-6},
    "casadi": {"rigid": 1e-5, "elastic": 1.5e-5},
    "other": {"rigid": 2e-4, "elastic": 3e-4},
}
#: Cost of each output point (interpolation, the Trajectory) [s].
OUTPUT_S = 2e-6
#: Extra cost per output point of the quasi-static spring lengths along a rigid run [s] (measured 1.0-1.4e-5).
QUASI_STATIC_OUTPUT_S = 1.4e-5


@dataclass(frozen=True)
class LevelCost:
    """Estimated cost of one level's run.

    Attributes
    ----------
    level : str
        Level name.
    method : str
        The integration method it would run (``auto`` resolved), or ``"closed form"``.
    preparation : float
        One-time preparation still owed in this process [s] (0 when compiled and loaded).
    integration : float
        Estimated integration [s].
    note : str
        What the preparation is (e.g. ``"heyoka compile (not cached)"``).
    """

    level: str
    method: str
    preparation: float
    integration: float
    note: str = ""

    @property
    def total(self) -> float:
        """Preparation plus integration [s]."""
        return self.preparation + self.integration


def level_cost(scene: Scene, level: str) -> LevelCost:
    """Estimated cost of running ``level`` on ``scene`` now, in this process.

    Parameters
    ----------
    scene : Scene
        The scene.
    level : {"linearized", "rigid", "rigid+quasi-static", "elastic"}
        The level (``elastic`` and the rigid scene's ``rigid`` are the scene's own model).

    Returns
    -------
    LevelCost

    Raises
    ------
    ValueError
        Unknown level.
    """
    n_out = int(round(scene.t_final / scene.dt)) + 1
    if level == "linearized":
        # The rule computes the linear solution while predicting its error: nothing is left to run.
        return LevelCost(level, "closed form", 0.0, 0.0, "computed by the rule itself")
    if level not in ("rigid", "rigid+quasi-static", "elastic"):
        raise ValueError(f"unknown level {level!r}")
    model, x0 = scene.model, np.asarray(scene.x0, dtype=float)
    if level != "elastic" and model.kind == "elastic":
        names = model.state_names
        x0 = x0[[names.index(n) for n in ("theta1", "theta2", "omega1", "omega2")]]
        model = rigid_counterpart(model)
    u0 = np.zeros(2) if scene.u is None else np.asarray(scene.u, dtype=float)
    tol = min(scene.rtol, scene.atol)
    auto = choose_method(model, x0, u0, scene.rtol, scene.atol)
    method = auto.method if scene.method == "auto" else scene.method
    preparation, note = _preparation(method, model, scene, tol)
    family = "taylor" if method == "taylor" else "compiled" if method.startswith("compiled-") else _family(method)
    p = model.params
    omega_ref = 2.0 * math.sqrt(p.g / min(p.L1, p.L2)) if p.g > 0 else 1.0
    implicit = method in ("compiled-rodas4", "cvodes", "cvodes-bdf", "idas", "Radau", "BDF", "LSODA")
    # Every error-controlled method follows a spring mode the start excites; an implicit one steps over it only
    # when it is not excited (pendulab.integrate.auto).
    quiet = auto.stiff and not (auto.excitation is not None and auto.excitation > EXCITATION_LIMIT)
    omega = omega_ref if implicit and quiet else max(omega_ref, auto.omega_max)
    per_output = OUTPUT_S + (QUASI_STATIC_OUTPUT_S if level == "rigid+quasi-static" else 0.0)
    integration = n_out * per_output + scene.t_final * omega * (1e-8 / tol) ** 0.2 * SECONDS_PER_RADIAN[family][model.kind]
    return LevelCost(level, method, preparation, integration, note)


def _family(method: str) -> str:
    return "casadi" if method.startswith(("cvodes", "idas", "collocation")) else "other"


def _preparation(method: str, model, scene: Scene, tol: float) -> tuple[float, str]:
    if method == "taylor":
        from ..integrate.taylor.cache import is_compiled, structure_key

        held = np.zeros(2) if scene.u is None else np.asarray(scene.u, dtype=float)
        sine = np.zeros(2) if scene.u_amplitude is None else np.asarray(scene.u_amplitude, dtype=float)
        zero = tuple(i for i in range(2) if held[i] == 0.0 and sine[i] == 0.0)
        # A run without any input schedule specialises no input (the runner's key then has none).
        if any(is_compiled(structure_key(model.kind, model.p, z, tol)) for z in {zero, ()}):
            return 0.0, "heyoka integrator compiled in this process"
        return PREPARATION_S["taylor"][model.kind], "heyoka compile (first run of this structure and tolerance)"
    if method.startswith("compiled-"):
        from ..native.loader import library_state

        state = library_state(model.kind)
        if state == "loaded":
            return 0.0, "native library loaded"
        key = "native load" if state == "on disk" else "native build"
        return PREPARATION_S[key][model.kind], f"native library {state}"
    return 0.0, ""

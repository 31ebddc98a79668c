"""Validate an exported FMU with fmpy against the native CasADi integrator.

By default the FMU is checked **at its own parameters and start values** (the
start values of its ``modelDescription.xml``, e.g. an FMU exported with
``--set k1=1e5 --init theta1=1.0`` runs with k1 = 1e5 and theta1 = 1.0): each
validation scene of its model kind lends only its horizon, output step, sine
torque, solver tolerance and bound. Named scenes (``scenes=[...]``, CLI
``--scene``) run as they are, with the scene's parameters and initial state.

For each validation case, the FMU is simulated with
fmpy as Co-Simulation with each embedded solver and as Model Exchange (fmpy's
CVode), with a sampled sine torque on ``tau1`` held constant over each
communication step (the same zero-order hold as :func:`pendulab.simulate`). The
reference is :func:`pendulab.simulate` with CasADi CVODES at rtol = atol = 1e-12,
fed the torque as a sampled-data callable so that the integrator restarts at
every torque step. (Passed as a sampled array instead, CVODES-BDF stops with
CV_ERR_FAILURE at 1e-12 and CVODES-Adams is off by ~2e-7 on these runs: the
one-call path does not restart at the input discontinuities.) Errors are max-abs errors over the
grid, normalised by ``max(1, max |reference|)`` of each signal, and checked
against the scene's stated bound.

Reading the FMU (kind, start values, unreadable archives) is :mod:`pendulab.fmu.fmu_file`; the
report, its table and plot are :mod:`pendulab.fmu.validation_report` (their public names are importable from here).
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..integrate import simulate
from ..model.model import make_model
from ..scene import Scene, list_scenes, load_scene
from .binaries import check_fmu_binary
from .codegen import SOLVER_NAMES
from .fmu_file import UnreadableFMUError, _first_line, _read, fmu_kind, fmu_start_values
from .validation_report import ValidationReport, ValidationRow, _plot

__all__ = [
    "ValidationScene",
    "SCENES",
    "ValidationRow",
    "ValidationReport",
    "validate",
    "fmu_kind",
    "UnreadableFMUError",
    "fmu_start_values",
]


REFERENCE_TOL = 1e-12
REFERENCE_METHOD = "cvodes"


@dataclass(frozen=True)
class ValidationScene:
    """A shipped validation scene (``pendulab/scenes/validation/*.toml``) with its acceptance settings.

    Attributes
    ----------
    scene : Scene
        Model, initial state, horizon, output step and the sine torque on tau1.
    tolerance : float
        Solver tolerance passed to the FMU (CS) and fmpy's CVode (ME) (``[validation] solver_tolerance``).
    bound : float
        Largest accepted normalised error of every signal (``[validation] bound``).
    """

    scene: Scene
    tolerance: float
    bound: float

    @property
    def name(self) -> str:
        """Scene name."""
        return self.scene.name

    @property
    def kind(self) -> str:
        """Model kind."""
        return self.scene.kind

    @property
    def note(self) -> str:
        """Scene description."""
        return self.scene.description


def _load_validation_scenes() -> tuple[ValidationScene, ...]:
    out = []
    for name in list_scenes("validation"):
        scene = load_scene(name)
        settings = scene.extra.get("validation", {})
        try:
            out.append(ValidationScene(scene, float(settings["solver_tolerance"]), float(settings["bound"])))
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"validation scene {str(scene.path)!r}: [validation] needs solver_tolerance and bound") from exc
    return tuple(out)


#: The validation scenes, rigid and elastic.
SCENES: tuple[ValidationScene, ...] = _load_validation_scenes()


def _at_fmu_start(scene: ValidationScene, params: dict[str, float], start: dict[str, float]) -> ValidationScene:
    """The validation scene with the FMU's own parameters and initial state (horizon, input, bound kept)."""
    model = make_model(scene.kind, **params)
    x0 = np.array([start[n] for n in model.state_names])
    x0.setflags(write=False)
    sc = dataclasses.replace(scene.scene, model=model, x0=x0, initial=dict(start))
    return dataclasses.replace(scene, scene=sc)


def _input_table(scene: ValidationScene) -> np.ndarray:
    """fmpy input table reproducing a zero-order hold: each change is a repeated time stamp."""
    t, u = scene.scene.grid(), scene.scene.inputs()
    times = np.repeat(t, 2)[1:]
    values = np.repeat(u, 2, axis=0)[:-1]
    table = np.zeros(len(times), dtype=[("time", float), ("tau1", float), ("tau2", float)])
    table["time"], table["tau1"], table["tau2"] = times, values[:, 0], values[:, 1]
    return table


def _run_fmu(unzipdir: str, md, scene: ValidationScene, fmi_type: str, solver: int, signals: Sequence[str]) -> np.ndarray:
    from fmpy import simulate_fmu

    model = scene.scene.model
    start = {name: float(v) for name, v in zip(model.param_names, model.p, strict=True)}
    start.update({name: float(v) for name, v in zip(model.state_names, scene.scene.x0, strict=True)})
    if fmi_type == "CoSimulation":
        start["solver"] = solver
        start["solver_tolerance"] = scene.tolerance
    res = simulate_fmu(
        unzipdir,
        model_description=md,
        fmi_type=fmi_type,
        start_time=0.0,
        stop_time=scene.scene.t_final,
        step_size=scene.scene.dt,
        output_interval=scene.scene.dt,
        relative_tolerance=scene.tolerance,
        start_values=start,
        input=_input_table(scene),
        output=list(signals),
        validate=False,
        record_events=False,
    )
    out = np.column_stack([res[s] for s in signals])
    n = len(scene.scene.grid())
    if len(out) != n:
        raise RuntimeError(f"{fmi_type} run of scene {scene.name!r} returned {len(out)} samples, expected {n}")
    return out


def _reference(scene: ValidationScene, signals: Sequence[str]) -> np.ndarray:
    sc = scene.scene
    u = sc.inputs()

    def held(t: float, x: np.ndarray) -> np.ndarray:
        return u[min(int(round(t / sc.dt)), len(u) - 1)]

    traj = simulate(
        sc.model, sc.x0, sc.t_final, dt=sc.dt, method=REFERENCE_METHOD, rtol=REFERENCE_TOL, atol=REFERENCE_TOL, u=held
    )
    return np.column_stack([traj[s] for s in signals])


def validate(
    fmu: str | os.PathLike,
    *,
    scenes: Sequence[str] | None = None,
    out_dir: str | os.PathLike | None = None,
    progress: Callable[[str], None] | None = None,
) -> ValidationReport:
    """Validate a pendulab FMU: fmpy ``validate_fmu`` plus agreement with the native integrator.

    Parameters
    ----------
    fmu : path-like
        FMU exported by :func:`pendulab.fmu.export` (FMI 2 or 3).
    scenes : sequence of str, optional
        Names from :data:`SCENES`, run with the scenes' own parameters and initial
        states. Default: every scene of the FMU's model kind, run at the FMU's own
        parameters and start values (:func:`fmu_start_values`).
    out_dir : path-like, optional
        Where to write the overlay plot ``<fmu stem>_validation.png``.
    progress : callable(str), optional
        Called with a one-line status before each run (the CLI prints it on stderr).

    Returns
    -------
    ValidationReport
        ``.passed``, ``.table()``, ``.rows`` (normalised max errors), ``.plot``.
        A run that raises is recorded in ``problems`` with nan errors.

    Raises
    ------
    FileNotFoundError
        ``fmu`` is not a file.
    UnreadableFMUError (ValueError)
        Not a zip archive, a truncated or corrupt archive, no
        ``modelDescription.xml`` or one that fails the FMI schema.
    FMUBinaryError (UnreadableFMUError)
        A binary that pendulab did not export (:func:`~pendulab.fmu.binaries.check_fmu_binary`)
        crashed (the signal is named), failed or hung in a probe process; it is never loaded here.
    ValueError
        Not a pendulab FMU, an unknown scene name, or a scene for the other
        model kind.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.fmu import export, validate
    >>> path = export(pl.rigid(), "rigid.fmu", timestamp=False)
    >>> report = validate(path, scenes=["rigid_forced"])  # the FMU's three runs against the native integrator
    >>> report.passed, report.problems  # fmpy's validate_fmu found nothing either
    (True, [])
    >>> sorted({row.run for row in report.rows})
    ['CS-dopri5', 'CS-rodas4', 'ME-CVode']
    >>> bool(max(row.max_error / row.bound for row in report.rows) < 1.0)  # every signal within its bound
    True
    """
    import time

    from fmpy import extract, read_model_description
    from fmpy.validation import validate_fmu

    fmu = Path(fmu)
    if not fmu.is_file():
        raise FileNotFoundError(f"FMU file not found: {str(fmu)!r}")
    problems, md = _read(fmu, validate_fmu, read_model_description)
    kind = fmu_kind(md)
    params, start = fmu_start_values(md, kind)
    chosen = [_at_fmu_start(s, params, start) for s in SCENES if s.kind == kind]
    if scenes:
        known = {s.name: s for s in SCENES}
        bad = [n for n in scenes if n not in known]
        if bad:
            raise ValueError(f"unknown validation scene(s) {bad}; expected some of {sorted(known)}")
        wrong = [n for n in scenes if known[n].kind != kind]
        if wrong:
            raise ValueError(f"scene(s) {wrong} are not for the {kind} model of {fmu.name}")
        chosen = [known[n] for n in scenes]
    report = ValidationReport(fmu=fmu, kind=kind, problems=problems)
    if scenes:
        report.settings = "scenes"
    else:
        report.params, report.start = params, start
    m0 = make_model(kind)
    signals = ["theta1", "theta2", *m0.output_names]
    runs = [("CoSimulation", i, f"CS-{n}") for i, n in enumerate(SOLVER_NAMES)] + [("ModelExchange", 0, "ME-CVode")]
    curves: dict[str, dict[str, np.ndarray]] = {}
    tmp = tempfile.mkdtemp(prefix="pendulab_validate_")
    try:
        try:
            unzipdir = extract(str(fmu), tmp)
        except Exception as exc:  # noqa: BLE001 - zipfile/OS errors of a corrupt archive, reported in one line
            raise UnreadableFMUError(f"FMU {str(fmu)!r}: cannot extract the archive: {_first_line(exc)}") from None
        check_fmu_binary(unzipdir, md, fmu=fmu)  # a binary pendulab did not export runs in a child process first
        for scene in chosen:
            if progress:
                progress(f"{scene.name}: reference ({REFERENCE_METHOD}, tol {REFERENCE_TOL:g})")
            ref = _reference(scene, signals)
            scale = np.maximum(1.0, np.abs(ref).max(axis=0))
            curves[scene.name] = {"reference": ref}
            for fmi_type, solver, label in runs:
                if progress:
                    progress(f"{scene.name}: {label}")
                t0 = time.perf_counter()
                try:
                    y = _run_fmu(unzipdir, md, scene, fmi_type, solver, signals)
                except Exception as exc:  # noqa: BLE001 - a failing run is a FAIL row, not a crash
                    problems.append(f"{scene.name} {label}: {type(exc).__name__}: {exc}")
                    y = np.full_like(ref, np.nan)
                report.wall_times[(scene.name, label)] = time.perf_counter() - t0
                curves[scene.name][label] = y
                err = np.abs(y - ref).max(axis=0) / scale
                for sig, e in zip(signals, err, strict=True):
                    report.rows.append(ValidationRow(scene.name, label, sig, float(e), scene.bound))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if out_dir is not None:
        report.plot = _plot(report, chosen, curves, signals, Path(out_dir), f"{REFERENCE_METHOD} (tol {REFERENCE_TOL:g})")
    return report

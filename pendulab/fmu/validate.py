"""Validate an exported FMU with fmpy against the native CasADi integrator.

By default the FMU is checked **at its own parameters and start values** (the
start values of its ``modelDescription.xml``, e.g. an FMU exported with
``--set k1=1e5 --initial theta1=1.0`` runs with k1 = 1e5 and theta1 = 1.0): each
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
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import tempfile
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..integrate import simulate
from ..model.model import make_model
from ..scene import Scene, list_scenes, load_scene
from .codegen import SOLVER_NAMES

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


class UnreadableFMUError(ValueError):
    """The file is not a readable FMU: not a zip archive, a truncated archive, no or a schema-invalid
    ``modelDescription.xml``. (The CLI reports it in one line with exit status 2, FAIL is status 1.)"""


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


@dataclass(frozen=True)
class ValidationRow:
    """Error of one signal in one FMU run against the native reference.

    Attributes
    ----------
    scene : str
        Validation scene name.
    run : str
        ``"CS-<solver>"`` (Co-Simulation with that embedded solver) or
        ``"ME-CVode"`` (Model Exchange under fmpy's CVode).
    signal : str
        ``theta1``, ``theta2`` or a model output.
    max_error : float
        Max-abs error over the grid divided by ``max(1, max |reference|)``
        of the signal [-]; nan when the run failed.
    bound : float
        The scene's accepted normalised error.
    """

    scene: str
    run: str  # "CS-dopri5", "CS-rodas4", "ME-CVode"
    signal: str
    max_error: float  # normalised
    bound: float

    @property
    def passed(self) -> bool:
        """Finite error within the bound."""
        return bool(np.isfinite(self.max_error) and self.max_error <= self.bound)


@dataclass
class ValidationReport:
    """Outcome of :func:`validate` for one FMU.

    Attributes
    ----------
    fmu : Path
        The validated FMU.
    kind : str
        "rigid" or "elastic".
    problems : list of str
        Findings of fmpy's ``validate_fmu`` and runs that raised.
    rows : list of ValidationRow
        One per (scene, run, signal).
    wall_times : dict
        Wall time [s] of each FMU run by (scene, run).
    plot : Path or None
        The overlay plot, when written.
    settings : str
        ``"fmu"``: run at the FMU's own parameters and start values (the default);
        ``"scenes"``: run at the named scenes' parameters and initial states.
    params, start : dict of str to float
        The parameters and initial state the runs used when ``settings == "fmu"`` (else empty).
    """

    fmu: Path
    kind: str
    problems: list[str]
    rows: list[ValidationRow] = field(default_factory=list)
    wall_times: dict[tuple[str, str], float] = field(default_factory=dict)
    plot: Path | None = None
    settings: str = "fmu"
    params: dict[str, float] = field(default_factory=dict)
    start: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly summary (``pendulab fmu validate --json``).

        Returns
        -------
        dict
            FMU path, kind, settings, parameters and start values used, problems,
            one entry per row (scene, run, signal, normalised error, bound, passed),
            wall times [s] per (scene, run), the plot path and ``passed``.
        """
        return {
            "fmu": str(self.fmu),
            "kind": self.kind,
            "settings": self.settings,
            "params": dict(self.params),
            "start": dict(self.start),
            "problems": list(self.problems),
            "rows": [
                {
                    "scene": r.scene,
                    "run": r.run,
                    "signal": r.signal,
                    "max_error": r.max_error if np.isfinite(r.max_error) else None,
                    "bound": r.bound,
                    "passed": r.passed,
                }
                for r in self.rows
            ],
            "wall_times_s": {f"{scene} {run}": t for (scene, run), t in self.wall_times.items()},
            "plot": None if self.plot is None else str(self.plot),
            "passed": self.passed,
        }

    @property
    def passed(self) -> bool:
        """No problems, at least one row, and every row passed."""
        return not self.problems and bool(self.rows) and all(r.passed for r in self.rows)

    def table(self) -> str:
        """Max normalised error per (scene, run) and signal, with PASS/FAIL.

        Returns
        -------
        str
            A header naming the FMU and its problems, one line per (scene,
            run) with the error of each signal and the bound, and an overall
            PASS/FAIL line.
        """
        lines = [
            f"FMU {self.fmu.name} ({self.kind}): fmpy validate_fmu: "
            + ("no problem" if not self.problems else f"{len(self.problems)} problem(s)")
        ]
        if self.settings == "fmu":
            default = make_model(self.kind)
            defaults = dict(zip(default.param_names, default.p, strict=True))
            changed = {k: v for k, v in self.params.items() if v != defaults.get(k)}
            shown = ", ".join(f"{k}={v:.6g}" for k, v in changed.items()) or "default parameters"
            state = ", ".join(f"{k}={v:.6g}" for k, v in self.start.items())
            lines.append(f"at the FMU's own parameters ({shown}) and start values ({state})")
        else:
            lines.append("at the named scenes' parameters and initial states")
        lines += [f"  problem: {p}" for p in self.problems]
        keys = list(dict.fromkeys((r.scene, r.run) for r in self.rows))
        signals = list(dict.fromkeys(r.signal for r in self.rows))
        w = max([15, *(len(scene) for scene, _ in keys)])
        head = f"{'scene':<{w}} {'run':<10} " + " ".join(f"{s:>9}" for s in signals) + f" {'bound':>8}  result"
        lines += [head, "-" * len(head)]
        for scene, run in keys:
            rs = {r.signal: r for r in self.rows if (r.scene, r.run) == (scene, run)}
            ok = all(r.passed for r in rs.values())
            errs = " ".join(f"{rs[s].max_error:9.2e}" if s in rs else f"{'':>9}" for s in signals)
            bound = next(iter(rs.values())).bound
            lines.append(f"{scene:<{w}} {run:<10} {errs} {bound:8.0e}  {'PASS' if ok else 'FAIL'}")
        lines.append("overall: " + ("PASS" if self.passed else "FAIL"))
        return "\n".join(lines)


def fmu_kind(model_description) -> str:
    """Model kind of a pendulab FMU from its model identifier.

    Parameters
    ----------
    model_description : fmpy.model_description.ModelDescription
        As read by ``fmpy.read_model_description``; the Co-Simulation (else
        Model Exchange) identifier is used.

    Returns
    -------
    str
        ``"rigid"`` or ``"elastic"``.

    Raises
    ------
    ValueError
        The identifier is neither ``pendulab_rigid`` nor ``pendulab_elastic``,
        or the FMU has neither interface.
    """
    interface = model_description.coSimulation or model_description.modelExchange
    if interface is None:
        raise ValueError("not a pendulab FMU: it has neither a Co-Simulation nor a Model Exchange interface")
    ident = interface.modelIdentifier
    for kind in ("rigid", "elastic"):
        if ident == f"pendulab_{kind}":
            return kind
    raise ValueError(f"not a pendulab FMU: model identifier {ident!r}, expected 'pendulab_rigid' or 'pendulab_elastic'")


def fmu_start_values(model_description, kind: str) -> tuple[dict[str, float], dict[str, float]]:
    """Parameter and state start values of a pendulab FMU, from its model description.

    Parameters
    ----------
    model_description : fmpy.model_description.ModelDescription
        As read by ``fmpy.read_model_description``.
    kind : {"rigid", "elastic"}
        The FMU's model kind (:func:`fmu_kind`).

    Returns
    -------
    params : dict of str to float
        Start values of the model parameters (SI units), by name.
    start : dict of str to float
        Start values of the states, by name (``model.state_names`` order).

    Raises
    ------
    ValueError
        A parameter or state of the model has no numeric start value in the FMU.
    """
    model = make_model(kind)
    starts = {v.name: v.start for v in model_description.modelVariables}
    out: list[dict[str, float]] = []
    for names, what in ((model.param_names, "parameter"), (model.state_names, "state")):
        values = {}
        for name in names:
            try:
                values[name] = float(starts[name])
            except (KeyError, TypeError, ValueError):
                raise ValueError(
                    f"not a pendulab FMU: {what} {name!r} has no numeric start value (got {starts.get(name)!r})"
                ) from None
        out.append(values)
    return out[0], out[1]


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
    ValueError
        Not a pendulab FMU, an unknown scene name, or a scene for the other
        model kind.
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
        report.plot = _plot(report, chosen, curves, signals, Path(out_dir))
    return report


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _read(fmu: Path, validate_fmu: Callable, read_model_description: Callable) -> tuple[list[str], Any]:
    """fmpy's findings and the model description, or UnreadableFMUError in one line (fmpy raises bare
    ``Exception``, ``BadZipFile``, ``KeyError`` and ``ValidationError`` for unreadable files)."""
    try:
        with zipfile.ZipFile(fmu) as zf:
            bad = zf.testzip()
            names = set(zf.namelist())
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise UnreadableFMUError(f"FMU {str(fmu)!r} is not a readable FMU (zip archive): {_first_line(exc)}") from None
    if bad is not None:
        raise UnreadableFMUError(f"FMU {str(fmu)!r} is a corrupt archive: member {bad!r} fails its CRC check")
    if "modelDescription.xml" not in names:
        raise UnreadableFMUError(f"FMU {str(fmu)!r} is not an FMU: the archive has no modelDescription.xml")
    try:
        problems = list(validate_fmu(str(fmu)))
        md = read_model_description(str(fmu))
    except Exception as exc:  # noqa: BLE001 - fmpy's errors of an unreadable file, reported in one line
        detail = getattr(exc, "problems", None)
        reason = f"{detail[0]}" + (f" (and {len(detail) - 1} more)" if len(detail) > 1 else "") if detail else _first_line(exc)
        raise UnreadableFMUError(f"FMU {str(fmu)!r}: modelDescription.xml is invalid: {reason}") from None
    return problems, md


def _plot(report: ValidationReport, scenes, curves, signals, out_dir: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(len(scenes), 2, figsize=(12, 3.2 * len(scenes)), squeeze=False)
    i1, i2 = signals.index("theta1"), signals.index("theta2")
    for row, scene in zip(axes, scenes, strict=True):
        t = scene.scene.grid()
        c = curves[scene.name]
        ref = c["reference"]
        ax = row[0]
        ax.plot(t, ref[:, i1], "k-", lw=2.5, alpha=0.35, label="theta1 native")
        ax.plot(t, ref[:, i2], "b-", lw=2.5, alpha=0.35, label="theta2 native")
        for (label, y), style in zip(((k, v) for k, v in c.items() if k != "reference"), ("--", ":", "-."), strict=False):
            ax.plot(t, y[:, i1], "k" + style, lw=1, label=f"theta1 {label}")
            ax.plot(t, y[:, i2], "b" + style, lw=1, label=f"theta2 {label}")
        ax.set_title(f"{scene.name}: angles, FMU overlaid on native")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("angle [rad]")
        ax.legend(fontsize=6, ncol=2)
        ax = row[1]
        scale = np.maximum(1.0, np.abs(ref).max(axis=0))
        for label, y in c.items():
            if label == "reference":
                continue
            err = (np.abs(y - ref) / scale).max(axis=1)
            ax.semilogy(t, np.maximum(err, 1e-17), label=label)
        ax.axhline(scene.bound, color="r", ls="--", lw=1, label=f"bound {scene.bound:g}")
        ax.set_title(f"{scene.name}: max normalised error over all signals")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("error [-] (abs / max(1, |ref|))")
        ax.legend(fontsize=7)
    fig.suptitle(f"{report.fmu.name}: FMU vs native CasADi {REFERENCE_METHOD} (tol {REFERENCE_TOL:g})")
    fig.tight_layout()
    path = out_dir / f"{report.fmu.stem}_validation.png"
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=90)

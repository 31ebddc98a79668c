"""The outcome of an FMU validation (:func:`pendulab.fmu.validate.validate`): rows, report, table and overlay plot."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..model.model import make_model

__all__ = ["ValidationRow", "ValidationReport"]


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

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.fmu import export, validate
    >>> report = validate(export(pl.rigid(), "rigid.fmu"), out_dir="validation")
    >>> report.kind, report.settings, report.passed  # run at the FMU's own parameters and start values
    ('rigid', 'fmu', True)
    >>> sorted({row.scene for row in report.rows})  # every validation scene of the rigid model
    ['rigid_chaotic_forced', 'rigid_forced']
    >>> print(report.table())
    FMU rigid.fmu (rigid): fmpy validate_fmu: no problem
    ...
    overall: PASS
    >>> report.plot.as_posix()  # the overlay of FMU and native runs
    'validation/rigid_validation.png'
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
            lines.append(
                "each row: a validation scene's horizon, output step, torque input and bound; NOT its parameters or "
                "initial state (--scene NAME runs a scene as written)"
            )
            first = "input of scene"
        else:
            lines.append("at the named scenes' own parameters and initial states (each scene as written)")
            first = "scene"
        lines += [f"  problem: {p}" for p in self.problems]
        keys = list(dict.fromkeys((r.scene, r.run) for r in self.rows))
        signals = list(dict.fromkeys(r.signal for r in self.rows))
        w = max([len(first), *(len(scene) for scene, _ in keys)])
        head = f"{first:<{w}} {'run':<10} " + " ".join(f"{s:>9}" for s in signals) + f" {'bound':>8}  result"
        lines += [head, "-" * len(head)]
        for scene, run in keys:
            rs = {r.signal: r for r in self.rows if (r.scene, r.run) == (scene, run)}
            ok = all(r.passed for r in rs.values())
            errs = " ".join(f"{rs[s].max_error:9.2e}" if s in rs else f"{'':>9}" for s in signals)
            bound = next(iter(rs.values())).bound
            lines.append(f"{scene:<{w}} {run:<10} {errs} {bound:8.0e}  {'PASS' if ok else 'FAIL'}")
        lines.append("overall: " + ("PASS" if self.passed else "FAIL"))
        return "\n".join(lines)


def _plot(report: ValidationReport, scenes, curves, signals, out_dir: Path, reference: str) -> Path:
    """Overlay plot of the FMU runs on the native reference (``reference``: its method and tolerance, for the title)."""
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
    fig.suptitle(f"{report.fmu.name}: FMU vs native CasADi {reference}")
    fig.tight_layout()
    path = out_dir / f"{report.fmu.stem}_validation.png"
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=90)

"""Helpers shared by the simulation commands: argument parsing and run summaries."""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..integrate.trajectory import Trajectory
from ..model.model import Model
from . import CLIError

__all__ = ["parse_number", "parse_settings", "trajectory_format", "write_trajectory", "summarize", "format_summary"]


def parse_number(option: str, text: str | None, *, positive: bool = False) -> float | None:
    """Parse a number given on the command line (None passes through); CLIError names the option."""
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise CLIError(f"{option} {text!r}: expected a number") from None
    if not math.isfinite(value) or (positive and value <= 0):
        raise CLIError(f"{option} {text!r}: expected a finite number" + (" > 0" if positive else ""))
    return value


def parse_settings(items: Sequence[str] | None) -> dict[str, float]:
    """Parse repeated ``--set name=value`` into a dict (later values win)."""
    out: dict[str, float] = {}
    for item in items or ():
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise CLIError(f"--set {item!r}: expected name=value, e.g. --set k1=500 or --set theta1=2.0")
        try:
            value = float(text)
        except ValueError:
            raise CLIError(f"--set {item!r}: value {text.strip()!r} of {name!r} is not a number") from None
        if not math.isfinite(value):
            raise CLIError(f"--set {item!r}: value of {name!r} must be finite")
        out[name] = value
    return out


def trajectory_format(path: str | Path) -> str:
    """``"csv"`` or ``"npz"`` from the suffix of ``--out``; CLIError otherwise."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".npz"):
        raise CLIError(f"--out {str(path)!r}: expected a file name ending in .csv or .npz")
    return suffix[1:]


def write_trajectory(traj: Trajectory, path: str | Path) -> Path:
    """Write a trajectory as CSV or NPZ, chosen by the file suffix."""
    return traj.to_csv(path) if trajectory_format(path) == "csv" else traj.to_npz(path)


def summarize(label: str, model: Model, traj: Trajectory) -> dict[str, Any]:
    """Key figures of one run (JSON-serializable): solver work, energy drift, spring stretch, final state."""
    energy = traj["energy"]
    drift = float(np.max(np.abs(energy - energy[0])))
    summary: dict[str, Any] = {
        "label": label,
        "model": model.kind,
        "params": {k: float(v) for k, v in model.params.resolved().items()},
        "method": traj.method,
        "method_choice": traj.stats["auto"]["reason"] if "auto" in traj.stats else "given",
        "t_final_s": float(traj.t[-1]),
        "n_points": int(traj.t.size),
        "wall_time_s": float(traj.stats.get("wall_time", float("nan"))),
        "n_rhs": traj.stats.get("n_rhs"),
        "n_steps": traj.stats.get("n_steps"),
        "energy_initial_J": float(energy[0]),
        "energy_drift_J": drift,
        "energy_drift_rel": drift / abs(float(energy[0])) if energy[0] != 0 else None,
        "max_stretch_m": None,
        "final_state": {n: float(v) for n, v in zip(traj.state_names, traj.x[-1], strict=True)},
    }
    if model.kind == "elastic":
        stretch = np.column_stack([traj["stretch1"], traj["stretch2"]])
        summary["max_stretch_m"] = float(np.max(np.abs(stretch)))
    return summary


def _fmt(value: Any, spec: str = ".4g") -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return format(value, spec)
    return str(value)


def format_summary(summaries: Sequence[dict[str, Any]]) -> str:
    """A plain-text table, one column per run."""
    rows: list[tuple[str, list[str]]] = [
        ("model", [s["model"] for s in summaries]),
        ("method", [s["method"] + (" (auto)" if s.get("method_choice", "given") != "given" else "") for s in summaries]),
        ("horizon [s]", [_fmt(s["t_final_s"]) for s in summaries]),
        ("wall time [s]", [_fmt(s["wall_time_s"], ".3f") for s in summaries]),
        ("RHS evaluations", [_fmt(s["n_rhs"]) for s in summaries]),
        ("initial energy [J]", [_fmt(s["energy_initial_J"], ".6g") for s in summaries]),
        ("energy drift [J]", [_fmt(s["energy_drift_J"], ".2e") for s in summaries]),
        ("energy drift (rel.)", [_fmt(s["energy_drift_rel"], ".2e") for s in summaries]),
        ("max |spring stretch| [m]", [_fmt(s["max_stretch_m"], ".4f") for s in summaries]),
    ]
    names: list[str] = []
    for s in summaries:
        names += [n for n in s["final_state"] if n not in names]
    for n in names:
        rows.append((f"final {n}", [_fmt(s["final_state"].get(n), ".6f") for s in summaries]))
    header = ("", [s["label"] for s in summaries])
    width0 = max(len(r[0]) for r in [header, *rows])
    widths = [max(len(r[1][j]) for r in [header, *rows]) for j in range(len(summaries))]
    lines = []
    for k, (name, cells) in enumerate([header, *rows]):
        lines.append("  ".join([name.ljust(width0), *(c.rjust(w) for c, w in zip(cells, widths, strict=True))]))
        if k == 0:
            lines.append("-" * len(lines[0]))
    return "\n".join(lines)


class ProgressBar:
    """A tqdm bar on stderr fed by a ``progress(done, total)`` callback (ensembles, scorecards); a no-op when disabled."""

    def __init__(self, desc: str, enabled: bool) -> None:
        self.desc, self.enabled, self.bar = desc, enabled, None

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=self.desc, unit="run", smoothing=0.1, file=sys.stderr)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()

    def iterate(self, n: int = 1, unit: str = "it") -> None:
        """Count ``n`` more steps of work whose total is unknown (IPOPT iterations, controller samples).

        The first call opens an open-ended bar (count and rate, no percentage) in ``unit``;
        a no-op when disabled. Close it with :meth:`close` before a counted phase starts.

        Parameters
        ----------
        n : int
            Steps done since the last call.
        unit : str
            Unit shown by the bar (used when the bar is created).
        """
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(total=None, desc=self.desc, unit=unit, smoothing=0.1, file=sys.stderr)
        self.bar.update(n)

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
from . import DOCS_URL, CLIError, docs_page  # noqa: F401 - DOCS_URL, docs_page: for the command modules

__all__ = [
    "PLANT_HELP",
    "add_plant_option",
    "read_plant",
    "plant_settings",
    "parse_number",
    "parse_settings",
    "trajectory_format",
    "write_trajectory",
    "summarize",
    "format_summary",
]

#: What ``--plant FILE`` means, in every command that takes it.
PLANT_HELP = (
    "an identified robot: the plant file `pendulab identify --out DIR` writes (DIR/plant.json), or c1 (the shipped "
    "identification of RealAIGym's design C.1); its links, friction and rotor inertia replace the nominal plant"
)


#: One CLI vocabulary: the option names every command uses for the same thing (the first is the name shown
#: in help; the others are older spellings kept as aliases). tests/test_cli_plant.py checks every command.
VOCABULARY: dict[str, tuple[str, ...]] = {
    "parameters": ("--set", "--param"),
    "initial state": ("--init", "--initial"),
    "model kind": ("--model", "--kind"),
}


def add_vocabulary_option(parser: Any, concept: str, dest: str, help: str, **kwargs: Any) -> None:
    """Declare the option of a :data:`VOCABULARY` concept on a parser, with its aliases.

    ``parameters`` and ``initial state`` take ``NAME=VALUE`` items, repeatable and several per flag
    (``--set a=1 --set b=2`` or ``--set a=1 b=2``); ``model kind`` takes ``rigid`` or ``elastic``.
    """
    names = VOCABULARY[concept]
    if concept == "model kind":
        parser.add_argument(*names, dest=dest, choices=("rigid", "elastic"), help=help, **kwargs)
    else:
        parser.add_argument(*names, dest=dest, action="extend", nargs="+", metavar="NAME=VALUE", help=help, **kwargs)


def typed_flag(args: Any, concept: str) -> str:
    """The spelling of a :data:`VOCABULARY` option the user typed (errors name it), else its primary name.

    The entry point keeps the command line in ``args.argv``.
    """
    names = VOCABULARY[concept]
    for token in getattr(args, "argv", ()):
        flag = token.split("=", 1)[0]
        if flag in names:
            return flag
    return names[0]


def add_plant_option(parser: Any, scope: str = "") -> None:
    """Declare ``--plant FILE`` on a parser (one wording everywhere; ``scope`` adds where it applies)."""
    parser.add_argument("--plant", default=None, metavar="FILE", help=PLANT_HELP + (f" ({scope})" if scope else ""))


def read_plant(args: Any) -> Any:
    """The plant of ``--plant FILE`` (``None`` without it); a bad file is a CLIError naming the option.

    Returns
    -------
    IdentifiedPlant or None
        The validated plant file.
    """
    path = getattr(args, "plant", None)
    if path is None:
        return None
    from ..model.plant_file import load_plant

    try:
        return load_plant(path)
    except (OSError, ValueError, KeyError) as exc:
        reason = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc
        raise CLIError(f"--plant {path}: {reason}") from None


def plant_settings(args: Any, kind: str) -> dict[str, float]:
    """The rigid-model parameters of ``--plant FILE`` (empty without it), for a model of ``kind``.

    Commands merge them under their own ``--set`` values: ``{**plant_settings(args, kind), **settings}``.

    Raises
    ------
    CLIError
        A bad plant file, or ``--plant`` with an elastic model.
    """
    plant = read_plant(args)
    if plant is None:
        return {}
    if kind != "rigid":
        raise CLIError(f"--plant {args.plant}: a plant file describes a rigid robot; it does not apply to the {kind} model")
    return plant.rigid_kwargs()


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


def parse_settings(items: Sequence[str] | None, option: str = "--set") -> dict[str, float]:
    """Parse repeated ``--set name=value`` (or another ``option``'s items) into a dict (later values win)."""
    out: dict[str, float] = {}
    for item in items or ():
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise CLIError(f"{option} {item!r}: expected name=value, e.g. {option} k1=500 or {option} theta1=2.0")
        try:
            value = float(text)
        except ValueError:
            raise CLIError(f"{option} {item!r}: value {text.strip()!r} of {name!r} is not a number") from None
        if not math.isfinite(value):
            raise CLIError(f"{option} {item!r}: value of {name!r} must be finite")
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
    """Key figures of one run (JSON-serializable): solver work, energy balance, spring stretch, final state.

    A conservative run (no torque, no damper) reports the energy drift ``max |E(t) - E(0)|``. A forced or
    damped run also reports the input work ``W`` and the dissipated energy ``D`` (accumulated along the
    trajectory by :func:`pendulab.integrate.simulate.energy_flows`, or taken from the run's own finer input
    grid) and the **energy balance error** ``max |E(t) - E(0) - W(t) + D(t)|``: the part of the energy change
    that the torques and dampers do not explain, i.e. the integration (and quadrature) error.
    """
    from ..integrate.simulate import trajectory_energy_flows

    energy = traj["energy"]
    change = energy - energy[0]
    drift = float(np.max(np.abs(change)))
    work, dissipated = trajectory_energy_flows(model, traj)
    forced = bool(np.any(traj.u != 0.0))
    damped = bool(np.any(dissipated != 0.0))
    balance = float(np.max(np.abs(change - work + dissipated)))
    # Relative to the largest energy in play: the initial energy or what the torques and dampers moved.
    scale = max(abs(float(energy[0])), float(np.max(np.abs(work))), float(np.max(dissipated)), drift)
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
        "forced": forced,
        "damped": damped,
        "energy_change_J": float(change[-1]),
        "input_work_J": float(work[-1]),
        "dissipated_J": float(dissipated[-1]),
        "energy_balance_error_J": balance,
        "energy_balance_error_rel": balance / scale if scale > 0 else None,
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
    """A plain-text table, one column per run.

    Conservative runs show the energy drift; forced or damped runs show the energy change, the input
    work, the dissipated energy and the energy balance error instead (a drift there is physics, not error).
    A run of a model level (``model_level``, ``pendulab simulate --model auto``) names it.
    """

    def balanced(s: dict[str, Any]) -> bool:
        return bool(s.get("forced") or s.get("damped"))

    def col(key: str, spec: str, when: Any = None) -> list[str]:
        return [_fmt(s.get(key), spec) if when is None or when(s) else "-" for s in summaries]

    rows: list[tuple[str, list[str]]] = [("model", [s["model"] for s in summaries])]
    if any("model_level" in s for s in summaries):
        rows.append(("model level", [str(s.get("model_level", "-")) for s in summaries]))
    rows += [
        ("method", [s["method"] + (" (auto)" if s.get("method_choice", "given") != "given" else "") for s in summaries]),
        ("horizon [s]", [_fmt(s["t_final_s"]) for s in summaries]),
        ("wall time [s]", [_fmt(s["wall_time_s"], ".3f") for s in summaries]),
        ("RHS evaluations", [_fmt(s["n_rhs"]) for s in summaries]),
        ("initial energy [J]", [_fmt(s["energy_initial_J"], ".6g") for s in summaries]),
    ]
    if not all(balanced(s) for s in summaries):
        conservative = lambda s: not balanced(s)  # noqa: E731 - a one-line predicate
        rows += [
            ("energy drift [J]", col("energy_drift_J", ".2e", conservative)),
            ("energy drift (rel.)", col("energy_drift_rel", ".2e", conservative)),
        ]
    if any(balanced(s) for s in summaries):
        rows += [
            ("energy change [J]", col("energy_change_J", ".4g", balanced)),
            ("input work [J]", col("input_work_J", ".4g", balanced)),
            ("dissipated [J]", col("dissipated_J", ".4g", balanced)),
            ("energy balance error [J]", col("energy_balance_error_J", ".2e", balanced)),
            ("energy balance error (rel.)", col("energy_balance_error_rel", ".2e", balanced)),
        ]
    stretch_label = "max |spring stretch| [m]"
    if any(s.get("stretch_source") for s in summaries):
        stretch_label += " (" + ", ".join(sorted({s["stretch_source"] for s in summaries if s.get("stretch_source")})) + ")"
    rows.append((stretch_label, [_fmt(s["max_stretch_m"], ".4f") for s in summaries]))
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


class _LogLines:
    """tqdm's output where stderr is not a terminal (a CI log, a file): each refresh a line of its own.

    tqdm redraws its bar with carriage returns, which a log keeps as one line of thousands of updates.
    """

    def __init__(self, stream: Any) -> None:
        self.stream = stream

    def write(self, text: str) -> None:
        line = text.replace("\r", "").rstrip()
        if line:
            self.stream.write(line + "\n")

    def flush(self) -> None:
        self.stream.flush()


#: Seconds between two progress lines in a log (a terminal redraws the bar continuously).
LOG_INTERVAL_S = 30.0


def _tqdm(desc: str, total: int | None, unit: str) -> Any:
    from tqdm import tqdm

    if sys.stderr.isatty():
        return tqdm(total=total, desc=desc, unit=unit, smoothing=0.1, file=sys.stderr)
    return tqdm(total=total, desc=desc, unit=unit, smoothing=0.1, file=_LogLines(sys.stderr), mininterval=LOG_INTERVAL_S,
                ascii=True)  # fmt: skip


class ProgressBar:
    """A tqdm bar on stderr fed by a ``progress(done, total)`` callback (ensembles, scorecards); a no-op when disabled.

    On a terminal the bar redraws in place; in a log (stderr not a terminal) it writes a line every
    :data:`LOG_INTERVAL_S` seconds and one at the end.
    """

    def __init__(self, desc: str, enabled: bool, unit: str = "run") -> None:
        self.desc, self.enabled, self.unit, self.bar = desc, enabled, unit, None

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        if self.bar is None:
            self.bar = _tqdm(self.desc, total, self.unit)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        """Finish the bar (its last line in a log); a later update opens a new one."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None

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
            self.bar = _tqdm(self.desc, None, unit)
        self.bar.update(n)

    def note(self, text: str) -> None:
        """Write one line of status on stderr (between bar updates, without garbling the bar); a no-op when disabled.

        Parameters
        ----------
        text : str
            The line, e.g. ``"building the NLP (radau N=100) ..."``.
        """
        if not self.enabled:
            return
        from tqdm import tqdm

        tqdm.write(f"{self.desc}: {text}", file=sys.stderr)

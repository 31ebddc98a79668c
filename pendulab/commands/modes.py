"""``pendulab modes``: equilibria, their modes and (optionally) controllability, as tables or JSON."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from ._common import VOCABULARY, CLIError, add_plant_option, add_vocabulary_option, parse_settings, plant_settings

__all__ = ["register", "run"]

_KINDS = ("rigid", "elastic")


def register(subparsers: Any) -> None:
    """Add the ``modes`` sub-command."""
    p = subparsers.add_parser(
        "modes",
        help="equilibria, natural frequencies, damping, mode shapes (and controllability)",
        description=(
            "Solve the equilibria of a model (optionally under a constant torque), linearize exactly and list "
            "each mode: natural frequency [rad/s, Hz], damping ratio, time constant [s] and normalized shape."
        ),
    )
    # Validated by the command (a one-line error naming the option), not by argparse's choices.
    p.add_argument(*VOCABULARY["model kind"], dest="model", required=True, metavar="KIND", help="rigid | elastic")
    add_vocabulary_option(p, "parameters", "set", "parameter in SI units, e.g. k1=800; repeatable")
    add_plant_option(p, "--model rigid; --set overrides its values")
    p.add_argument("--equilibrium", default="all", metavar="NAME", help="down-down | down-up | up-down | up-up | all (default)")
    p.add_argument("--torque", metavar="TAU1,TAU2", help="constant torques [N.m] holding the arm, e.g. 2,0.5")
    p.add_argument("--controllability", action="store_true", help="also report controllability/observability per actuation")
    p.add_argument("--json", action="store_true", help="print JSON instead of tables")
    p.add_argument("--plot", metavar="DIR", help="write mode-shape figures (and, elastic, the stiffness chart) into DIR")
    p.add_argument("--out", metavar="DIR", help="write modes.json (what --json prints) and the figures into DIR")
    p.set_defaults(func=run)


def _parse_torque(text: str | None) -> list[float] | None:
    if text is None:
        return None
    parts = text.split(",")
    try:
        values = [float(v) for v in parts]
    except ValueError:
        raise CLIError(f"--torque {text!r}: expected two numbers TAU1,TAU2 in N.m") from None
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise CLIError(f"--torque {text!r}: expected two finite numbers TAU1,TAU2 in N.m")
    return values


def run(args: argparse.Namespace) -> int:
    """Execute ``pendulab modes``; return the exit status."""
    from ..analysis.equilibria import EQUILIBRIUM_NAMES, equilibria, equilibrium
    from ..analysis.modes import mode_table, modes
    from ..model.model import make_model

    if args.model not in _KINDS:
        raise CLIError(f"--model {args.model!r}: expected one of {list(_KINDS)}")
    if args.equilibrium != "all" and args.equilibrium not in EQUILIBRIUM_NAMES:
        raise CLIError(f"--equilibrium {args.equilibrium!r}: expected one of {[*EQUILIBRIUM_NAMES, 'all']}")
    model = make_model(args.model, **{**plant_settings(args, args.model), **parse_settings(args.set)})
    torque = _parse_torque(args.torque)
    eqs = equilibria(model, torque) if args.equilibrium == "all" else [equilibrium(model, args.equilibrium, torque)]

    result: dict[str, Any] = {"model": model.kind, "params": model.params.resolved(), "equilibria": []}
    text = []
    for eq in eqs:
        ms = modes(model, eq)
        result["equilibria"].append({**eq.as_dict(), "modes": [m.as_dict() for m in ms]})
        state = ", ".join(f"{n} = {v:.6g}" for n, v in zip(model.state_names[: model.nq], eq.x[: model.nq], strict=True))
        text.append(f"== {eq.name}: {eq.stability}; {state}\n{mode_table(ms)}\n")
    if args.controllability:
        from ..control.controllability import controllability_report, format_report

        rows = controllability_report(model, eqs)
        result["controllability"] = [r.as_dict() for r in rows]
        text.append("== controllability (staircase rank, finite-horizon Gramian T = 1 s; encoders theta1, theta2)")
        text.append(format_report(rows))
    if args.out is not None and args.plot is not None and args.plot != args.out:
        raise CLIError("--out DIR writes the figures into DIR; give --plot only without --out, or the same DIR")
    figure_dir = args.out if args.out is not None else args.plot
    if figure_dir is not None:
        from ..viz.modes import save_mode_figures

        print("pendulab modes: drawing figures ...", file=sys.stderr)
        written = save_mode_figures(model, figure_dir, eqs)
        result["figures"] = [str(p) for p in written]
        for path in written:
            print(f"pendulab modes: wrote {path}", file=sys.stderr)
    if args.out is not None:
        from .._io import atomic_write_text

        path = atomic_write_text(Path(args.out) / "modes.json", json.dumps(result, indent=2) + "\n")
        print(f"pendulab modes: wrote {path}", file=sys.stderr)
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print("\n".join(text))
    return 0

"""``pendulab score``: robustness scorecard of a controller on a swing-up task, the RealAIGym score, the leaderboard."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from . import CLIError
from ._common import ProgressBar

__all__ = ["register", "run_score"]


def register(subparsers: Any) -> None:
    """Add the ``score`` command.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The dispatcher's sub-parsers.
    """
    p = subparsers.add_parser(
        "score",
        help="robustness scorecard of a controller on a swing-up task (or --realai, --leaderboard)",
        description=(
            "Robustness scorecard: the controller runs the task under swept perturbations (model parameters, "
            "measurement and torque noise, torque response, delay, pushes; docs/scorecard.md) and succeeds when "
            "the end effector stays above 0.9 (L1 + L2) over the last second within the torque limit. Writes "
            "DIR/scorecard.json, DIR/scorecard.png and DIR/scorecard.md. --realai scores the controller on "
            "RealAIGym's simulation leaderboard instead; --leaderboard regenerates docs/leaderboard.md."
        ),
    )
    p.add_argument("--controller", default=None, metavar="NAME", help="lqr | tvlqr | swingup | nmpc (--realai: also best)")
    p.add_argument(
        "--task", default=None, metavar="TASK", help="swing-up task name (pendulab swingup --list); --realai: pendubot | acrobot"
    )
    p.add_argument("--runs", default="20", metavar="N", help="runs per level of the stochastic categories (default 20)")
    p.add_argument("--categories", default=None, metavar="A,B", help="comma-separated categories (default: all that apply)")
    p.add_argument("--seed", default="0", metavar="S", help="base seed (default 0)")
    p.add_argument("--workers", default=None, metavar="N", help="worker processes (default: all cores)")
    p.add_argument("--out", default=None, metavar="DIR", help="output directory (--leaderboard: the markdown file)")
    p.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--realai", action="store_true", help="RealAIGym simulation leaderboard score (pendubot | acrobot)")
    mode.add_argument("--leaderboard", action="store_true", help="regenerate docs/leaderboard.md (all controllers x tasks)")
    p.set_defaults(func=run_score)


def _int(option: str, text: str, lo: int) -> int:
    try:
        value = int(text)
    except (TypeError, ValueError):
        raise CLIError(f"{option} {text!r}: expected an integer") from None
    if value < lo:
        raise CLIError(f"{option} {text!r}: expected an integer >= {lo}")
    return value


def run_score(args: argparse.Namespace) -> int:
    """Run ``pendulab score``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        0 on success.

    Raises
    ------
    CLIError
        Missing or bad options, unknown task, controller or category.
    """
    workers = None if args.workers is None else _int("--workers", args.workers, 1)
    runs = _int("--runs", args.runs, 1)
    if args.leaderboard:
        from .leaderboard import write_leaderboard

        path = write_leaderboard(args.out, runs=runs, workers=workers, progress=not args.no_progress)
        print(f"wrote {path}", file=sys.stderr)
        return 0
    if args.controller is None or args.task is None:
        raise CLIError("--controller and --task are required (or --leaderboard)")
    if args.realai:
        return _run_realai(args)
    from ..control.controllers import TASK_CONTROLLERS
    from ..control.scorecard import CATEGORIES, score
    from ..control.swingup.tasks import load_task, task_names

    if args.controller not in TASK_CONTROLLERS:
        raise CLIError(f"--controller {args.controller!r}: expected one of {list(TASK_CONTROLLERS)}")
    try:
        task = load_task(args.task)
    except FileNotFoundError:
        raise CLIError(f"--task {args.task!r}: unknown task; shipped tasks: {list(task_names())}") from None
    cats = None
    if args.categories:
        cats = [c.strip() for c in args.categories.split(",") if c.strip()]
        bad = [c for c in cats if c not in CATEGORIES]
        if bad:
            raise CLIError(f"--categories: unknown {bad}; expected some of {list(CATEGORIES)}")
    bar = ProgressBar(f"score {args.controller} on {task.name}", not args.no_progress)
    try:
        card = score(
            args.controller, task, runs=runs, categories=cats, seed=_int("--seed", args.seed, 0), workers=workers, progress=bar
        )
    finally:
        bar.close()
    if args.out:
        from ..viz.scorecard import plot_scorecard

        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "scorecard.json").write_text(card.to_json() + "\n")
        (out / "scorecard.md").write_text(card.table() + "\n")
        plot_scorecard(card, out / "scorecard.png")
        print(f"wrote {out / 'scorecard.json'}, scorecard.md, scorecard.png", file=sys.stderr)
    if args.json:
        print(card.to_json())
    else:
        print(card.table())
        print(f"\n{len(card.records)} runs, {len(card.failures)} failed, {card.wall_time:.1f} s")
    return 0


def _run_realai(args: argparse.Namespace) -> int:
    if args.task not in ("pendubot", "acrobot"):
        raise CLIError(f"--task {args.task!r}: --realai expects pendubot or acrobot")
    try:
        from ..control.realai import realai_score
    except ImportError:
        raise CLIError("--realai: pendulab.control.realai.realai_score is not available in this installation") from None
    csv_path = None
    if args.out:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        csv_path = Path(args.out) / "realai.csv"
    result = realai_score(args.task, args.controller, csv_path=csv_path)
    summary = result.to_dict()
    if args.out:
        (Path(args.out) / "realai.json").write_text(json.dumps(summary, indent=2) + "\n")
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        crit = ", ".join(f"{k} {v:.4g}" for k, v in summary.get("criteria", {}).items())
        print(f"RealAIGym {args.task} / {args.controller}: success {summary.get('success')}, score {summary.get('score'):.3f}")
        if crit:
            print(f"criteria: {crit}")
    return 0

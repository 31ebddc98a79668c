"""``pendulab scene check FILE``: which model does a scene need? Decided before running (a priori rule)."""

from __future__ import annotations

import argparse
import json
import sys

from .._checks import check_budget
from . import CLIError
from ._common import docs_page

__all__ = ["register"]


def _check(args: argparse.Namespace) -> int:
    from ..scene import load_scene

    if args.repeats is not None and not args.measure:
        raise CLIError("--repeats applies to --measure only (the a priori rule runs no level)")
    if args.repeats is not None:
        check_budget("repeats", "--repeats", args.repeats)
    if args.fail_on_miss and not args.verify:
        raise CLIError("--fail-on-miss applies to --verify (only a verification measures what a prediction missed)")
    if args.measure and args.verify:
        raise CLIError("give --verify (run the chosen level and the reference) or --measure (run every level), not both")
    scene = load_scene(args.file)
    if args.measure:
        from ..bench.hierarchy import check_scene

        result = check_scene(scene, repeats=3 if args.repeats is None else args.repeats, tolerance=args.tolerance)
    else:
        from ..scene.choice import choose_model

        result = choose_model(scene, tolerance=args.tolerance, verify=args.verify)
    if args.out is not None:
        from pathlib import Path

        from .._io import atomic_write_text

        out = Path(args.out)
        atomic_write_text(out / "check.md", result.table() + "\n")
        # last: a check.json means the check finished
        path = atomic_write_text(out / "check.json", json.dumps(result.to_dict(), indent=1) + "\n")
        print(f"pendulab scene check: wrote {path} and check.md", file=sys.stderr)
    print(json.dumps(result.to_dict(), indent=1) if args.json else result.table())
    missed = result.misses() if args.verify else []
    if missed and args.fail_on_miss:
        print(f"pendulab scene check: {len(missed)} prediction(s) missed (--fail-on-miss): exit 1", file=sys.stderr)
        return 1
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("scene", help="scene tools (which model a scene needs)", description=__doc__)
    sub = p.add_subparsers(dest="scene_command", metavar="SCENE")
    sub.required = True
    c = sub.add_parser(
        "check",
        help="predict the error of linearized / rigid / rigid+quasi-static models on a scene without running the "
        "reference; name the cheapest within tolerance and the horizon of validity",
        description="Predict, without running the reference, each model level's error on the scene's outputs and "
        "horizon, pick the cheapest within the scene's tolerance, and say up to when each level (and the reference "
        f"at the scene's rtol, on chaotic scenes) keeps the outputs within tolerance. See {docs_page('model_choice')}.",
    )
    c.add_argument("file", help="scene TOML file or shipped scene name")
    c.add_argument("--json", action="store_true", help="print the result as JSON")
    c.add_argument("--out", metavar="DIR", help="also write the result to DIR/check.json and DIR/check.md")
    c.add_argument("--tolerance", type=float, default=None, help="override the scene's [outputs] tolerance")
    c.add_argument(
        "--verify",
        action="store_true",
        help="also run the chosen level and the reference; report predicted against measured error and horizon",
    )
    c.add_argument(
        "--fail-on-miss",
        action="store_true",
        help="with --verify: exit 1 when a prediction missed (measured error or horizon worse than predicted)",
    )
    c.add_argument(
        "--measure",
        action="store_true",
        help="a posteriori instead: run every level and the reference, timed, and pick on measured error and cost",
    )
    c.add_argument("--repeats", type=int, default=None, help="with --measure: timed runs per level (median; default 3)")
    c.set_defaults(func=_check)

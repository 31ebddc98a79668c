"""``pendulab scene check FILE``: which model does a scene need?"""

from __future__ import annotations

import argparse
import json

__all__ = ["register"]


def _check(args: argparse.Namespace) -> int:
    from ..bench.hierarchy import check_scene
    from ..scene import load_scene

    report = check_scene(load_scene(args.file), repeats=args.repeats, tolerance=args.tolerance)
    print(json.dumps(report.to_dict(), indent=1) if args.json else report.table())
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("scene", help="scene tools (model hierarchy check)", description=__doc__)
    sub = p.add_subparsers(dest="scene_command", metavar="SCENE")
    sub.required = True
    c = sub.add_parser(
        "check",
        help="run linearized / rigid / rigid+quasi-static / elastic models on a scene; name the cheapest within tolerance",
    )
    c.add_argument("file", help="scene TOML file or shipped scene name")
    c.add_argument("--json", action="store_true", help="print the report as JSON")
    c.add_argument("--repeats", type=int, default=3, help="timed runs per model (median; default 3)")
    c.add_argument("--tolerance", type=float, default=None, help="override the scene's [outputs] tolerance")
    c.set_defaults(func=_check)

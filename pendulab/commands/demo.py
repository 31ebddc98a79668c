"""``pendulab demo``: the seed paper's experiment, rigid vs elastic, with its figures, data and a summary."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from .._io import atomic_write_text
from ._common import format_summary, parse_number, summarize

__all__ = ["register", "run"]


def register(subparsers: Any) -> None:
    """Add the ``demo`` sub-command."""
    p = subparsers.add_parser(
        "demo",
        help="rigid vs elastic double pendulum (seed paper): figures, GIF, CSV, summary",
        description=(
            "Run the seed paper's scene for the elastic pendulum and its rigid counterpart (same masses, "
            "lengths, gravity, joint dampers) from identical initial conditions, and write the paper's "
            "figures (Figs. 2-6), spring stretch, energy exchange, an animated GIF, the CSV data and a "
            "summary into the output directory."
        ),
    )
    p.add_argument("--out", metavar="DIR", default="pendulab-out", help="output directory (default: ./pendulab-out)")
    p.add_argument("--scene", metavar="FILE|NAME", default="seed_paper", help="scene to run (default: seed_paper)")
    p.add_argument("--t-final", metavar="S", help="override the scene's horizon [s]")
    p.add_argument("--no-gif", action="store_true", help="skip the animation (the slowest output)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON instead of a table")
    p.set_defaults(func=run)


def _progress(message: str) -> None:
    print(f"pendulab demo: {message}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    """Execute ``pendulab demo``; return the exit status."""
    from ..integrate import simulate
    from ..model.counterpart import rigid_counterpart, rigid_state
    from ..scene import load_scene
    from ..viz.animate import animate
    from ..viz.figures import save_figures

    start = time.perf_counter()
    t_final = parse_number("--t-final", args.t_final, positive=True)
    scene = load_scene(args.scene)
    horizon = scene.t_final if t_final is None else t_final
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    runs: dict[str, tuple[Any, Any]] = {}
    rigid = rigid_counterpart(scene.model)
    settings = {"t_final": horizon, "dt": scene.dt, "method": scene.method, "rtol": scene.rtol, "atol": scene.atol}
    _progress(f"scene {scene.name!r}: {scene.description}")
    _progress(f"simulating rigid model ({scene.method}, {horizon:g} s) ...")
    runs["rigid"] = (rigid, simulate(rigid, rigid_state(scene.model, scene.x0), u=scene.input_spec(), **settings))
    if scene.model.kind == "elastic":
        _progress(f"simulating elastic model ({scene.method}, {horizon:g} s) ...")
        runs["elastic"] = (scene.model, scene.simulate(**settings))

    files: dict[str, str] = {}
    for label, (_, traj) in runs.items():
        files[f"{label}.csv"] = str(traj.to_csv(out / f"{label}.csv"))
    _progress(f"writing figures into {out}/ ...")
    for name, path in save_figures(runs, out).items():
        files[name] = str(path)
    if not args.no_gif:
        last = [-1]

        def report(done: int, total: int) -> None:
            decile = 10 * done // total
            if decile != last[0] and decile % 2 == 0:
                last[0] = decile
                _progress(f"animation {done}/{total} frames")

        files["animation"] = str(animate(runs, out / "pendulums.gif", duration=min(horizon, 10.0), progress=report))

    summaries = [summarize(label, model, traj) for label, (model, traj) in runs.items()]
    report_data = {"scene": scene.name, "description": scene.description, "runs": summaries, "files": files}
    # Atomic, and last: a summary.json means every other file of the run is complete.
    atomic_write_text(out / "summary.json", json.dumps(report_data, indent=2))
    files["summary.json"] = str(out / "summary.json")
    _progress(f"done in {time.perf_counter() - start:.1f} s; {len(files)} files in {out}/")
    if args.json:
        print(json.dumps(report_data, indent=2))
    else:
        print(format_summary(summaries))
    return 0

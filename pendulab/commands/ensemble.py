"""``pendulab ensemble``: many runs at once; ``flipmap`` draws the double pendulum's time-to-first-flip map."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

from .._checks import require_extra
from . import CLIError
from ._common import VOCABULARY, ProgressBar
from .outputs import output_directory

__all__ = ["register", "run_flipmap", "DEFAULT_K"]

_KINDS = ("rigid", "elastic")
#: Default output directory, relative to the current directory (never into the repository's docs/).
_OUT = "pendulab-out/ensemble-flipmap"
#: Spring stiffness [N/m] of the elastic flip map (both springs); see docs/ensembles.md for the choice.
DEFAULT_K = 1e4


def register(subparsers: Any) -> None:
    """Add the ``ensemble`` command and its ``flipmap`` sub-command."""
    p = subparsers.add_parser("ensemble", help="ensembles of runs (flip map)", description=__doc__)
    sub = p.add_subparsers(dest="ensemble_command", metavar="ENSEMBLE")
    sub.required = True
    fm = sub.add_parser(
        "flipmap",
        help="time to the first flip over a grid of release angles",
        description=(
            "Release the double pendulum at rest at every (theta1, theta2) of an N x N grid over (-pi, pi) and "
            "integrate (method taylor) until a link flips (|theta| = pi) or T passes. Points whose energy is too "
            "low to ever flip are skipped (exact). Writes DIR/flipmap.npz (theta1, theta2, t_flip[i_theta1, "
            "i_theta2], NaN = no flip) and DIR/flipmap.png; with --compare (default for --model elastic) also "
            "the rigid map and DIR/flipmap_compare.png (rigid | elastic). Finished blocks of runs are recorded in "
            "DIR/flipmap_<kind>.partial.npz as they complete; --resume continues an interrupted run from there."
        ),
    )
    fm.add_argument(*VOCABULARY["model kind"], dest="model", default="rigid", metavar="KIND", help="rigid (default) | elastic")
    fm.add_argument("--grid", default="400", metavar="N", help="grid points per angle (default 400)")
    fm.add_argument("--t-max", default="10", metavar="T", help="horizon [s] (default 10)")
    fm.add_argument("--out", default=_OUT, metavar="DIR", help=f"output directory (default ./{_OUT})")
    fm.add_argument("--scheduler", default=None, metavar="ADDRESS", help="Dask scheduler address tcp://host:port")
    fm.add_argument("--k", default=None, metavar="K", help=f"elastic spring stiffness k1 = k2 [N/m] (default {DEFAULT_K:g})")
    fm.add_argument("--threads", default=None, metavar="N", help="local threads (default: all cores)")
    fm.add_argument("--rtol", default="1e-12", metavar="TOL", help="integration tolerance (default 1e-12)")
    cmp = fm.add_mutually_exclusive_group()
    cmp.add_argument("--compare", dest="compare", action="store_true", default=None, help="also draw rigid | elastic")
    cmp.add_argument("--no-compare", dest="compare", action="store_false", help="no comparison (elastic)")
    fm.add_argument("--max-wall-time", default=None, metavar="S", help="wall-time budget of each map [s] (default none)")
    fm.add_argument(
        "--resume", action="store_true", help="continue an interrupted run from DIR/flipmap_<kind>.partial.npz (same settings)"
    )
    fm.add_argument("--json", action="store_true", help="print one JSON summary object on stdout (nothing else)")
    fm.add_argument("--no-progress", action="store_true", help="no progress bar")
    fm.set_defaults(func=run_flipmap)


def _compute(kind: str, k: float, args: argparse.Namespace, grid: int, t_max: float, rtol: float, threads: Any, out: Path) -> Any:
    from ..ensemble.flipmap import flip_map
    from ..model.model import make_model

    model = make_model(kind, **({"k1": k, "k2": k} if kind == "elastic" else {}))
    checkpoint = out / f"flipmap_{kind}.partial.npz"
    bar = ProgressBar(f"flip map {kind}", not args.no_progress)
    try:
        fmap = flip_map(
            model,
            grid,
            t_max,
            client=args.scheduler,
            threads=threads,
            progress=bar,
            rtol=rtol,
            max_wall_time=args.max_wall_time,
            checkpoint=checkpoint,
            resume=args.resume,
            block_size=_BLOCK,
        )
    except ValueError as exc:
        from .._journal import JournalError

        if isinstance(exc, JournalError) or "checkpoint" in str(exc):
            raise CLIError(f"--resume: {exc}") from None
        raise
    finally:
        bar.close()
    return fmap, checkpoint


#: Runs per recorded block of the CLI's flip maps (each finished block is written to the partial file). Each block
#: costs ~17 ms of setup and recording: the 400 x 400 map took 1.30 s in blocks of 5,000 and 1.16 s in blocks of 14,000.
_BLOCK = 15000


def run_flipmap(args: argparse.Namespace) -> int:
    """Execute ``pendulab ensemble flipmap``; return the exit status."""
    if args.model not in _KINDS:
        raise CLIError(f"--model {args.model!r}: expected one of {list(_KINDS)}")
    # --grid, --t-max, --rtol, --threads, --k and --max-wall-time were checked against their declarations
    # right after parsing (pendulab.commands.options.check_options).
    grid, t_max, rtol, threads = args.grid, args.t_max, args.rtol, args.threads
    if args.k is not None and args.model == "rigid" and not args.compare:
        raise CLIError("--k: only meaningful with --model elastic or --compare")
    k = DEFAULT_K if args.k is None else args.k
    if args.scheduler is not None and not args.scheduler.startswith(("tcp://", "tls://", "inproc://", "ucx://")):
        raise CLIError(f"--scheduler {args.scheduler!r}: expected a Dask scheduler address like tcp://127.0.0.1:8786")
    compare = args.compare if args.compare is not None else args.model == "elastic"
    out = output_directory(args.out)
    if out.exists() and not out.is_dir():
        raise CLIError(f"--out {args.out!r}: exists and is not a directory")
    from .figure_process import FigureProcess

    with FigureProcess() as figures:  # imports matplotlib on the other core while the maps are computed
        return _flipmap(args, figures, grid, t_max, rtol, threads, k, compare, out)


def _flipmap(
    args: argparse.Namespace, figures: Any, grid: int, t_max: float, rtol: float, threads: Any, k: float, compare: bool, out: Path
) -> int:
    require_extra("heyoka", "taylor", "pendulab ensemble flipmap")
    if args.scheduler is not None:
        require_extra("distributed", "dask", "--scheduler")
    out.mkdir(parents=True, exist_ok=True)

    from ..ensemble.flipmap import plot_flip_map, plot_flip_map_compare

    t0 = time.perf_counter()
    main, partial = _compute(args.model, k, args, grid, t_max, rtol, threads, out)
    figures.start(plot_flip_map, main, out / "flipmap.png")  # drawn while the map is saved
    written = [main.save_npz(out / "flipmap.npz"), out / "flipmap.png"]
    partials = [partial]
    maps = {args.model: main}
    if compare:
        other = "elastic" if args.model == "rigid" else "rigid"
        maps[other], partial = _compute(other, k, args, grid, t_max, rtol, threads, out)
        written.append(maps[other].save_npz(out / f"flipmap_{other}.npz"))
        partials.append(partial)
        figures.start(plot_flip_map_compare, [maps["rigid"], maps["elastic"]], out / "flipmap_compare.png")
        written.append(out / "flipmap_compare.png")
    figures.finish()
    for p in partials:  # every map is in its .npz now
        p.unlink(missing_ok=True)
    if args.json:
        summary = {
            "command": "ensemble flipmap",
            "grid": grid,
            "t_max_s": t_max,
            "wall_time_s": time.perf_counter() - t0,
            "files": [str(p) for p in written],
            "maps": {
                kind: {
                    "n_points": int(m.t_flip.size),
                    "n_integrated": int(m.n_simulated),
                    "n_resumed": int(m.n_resumed),
                    "n_skipped": int(m.skipped.sum()),
                    "n_flipped": int(m.flipped.sum()),
                    "energy_threshold_J": float(m.energy_threshold),
                    "wall_time_s": float(m.wall_time),
                    "params": m.params,
                    "settings": m.settings,
                }
                for kind, m in maps.items()
            },
        }
        print(json.dumps(summary))
        return 0
    for kind, m in maps.items():
        n = m.t_flip.size
        resumed = f", {m.n_resumed} taken from the partial file" if m.n_resumed else ""
        print(
            f"{kind}: {grid} x {grid}, t_max {t_max:g} s: {m.n_simulated} runs integrated{resumed} "
            f"({int(m.skipped.sum())} skipped below V_flip = {m.energy_threshold:.4f} J), "
            f"{int(m.flipped.sum())}/{n} flip; {m.wall_time:.2f} s"
        )
    print(f"total {time.perf_counter() - t0:.2f} s; wrote " + ", ".join(str(p) for p in written))
    return 0

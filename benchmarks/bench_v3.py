"""RealAIGym v3 simulation protocol: scores of pendulab's controllers over seeds (rows of benchmarks/results/v3.md).

Run: ``python benchmarks/bench_v3.py [--seeds 0 1 2] [--controllers global library ...] [--tasks pendubot acrobot]
[--md benchmarks/results/v3.md]``. Prints one Markdown row per (task, controller): the scores, their mean and spread
over the seeds, swing-ups, per-call controller time (median / max over all runs; the 2 ms period is the real-time
budget), the wall time and the load average; with ``--md`` the table is appended to that file as a dated section.
The ``library`` controller's plans are built (or completed) first, with a progress bar, under
``./pendulab-out/plan_library`` (``pendulab.control.plan_library``); ``--build-only`` stops after that.
``--grow-seeds 10 11 ...`` first plays the library on those *training* seeds (disjoint from the scored ones) and adds
the reset hand-overs it did not cover (lookup distance above ``--grow-distance``) as starts of the library
(``--ship``: to the list shipped with pendulab, which every checkout's default library includes).
``--schedule published`` draws the resets as the published ICRA 2025 simulation runs did (seeds 777 pendubot, 333
acrobot are those runs' schedules; :func:`pendulab.evaluate.realai.v3_definition.reset_schedule`).
"""

from __future__ import annotations

import argparse
import datetime
import os
import time
from pathlib import Path

import numpy as np

from pendulab.evaluate.realai.v3 import PUBLISHED_V3, v3_score


def _build(task: str, build: bool = True) -> object:
    from pendulab.commands._common import ProgressBar
    from pendulab.control.plan_library import library_controller

    bar = ProgressBar(f"plan library ({task})", True)
    try:
        return library_controller(task, build=build, progress=bar)
    finally:
        bar.close()


def _grow(task: str, seeds: list[int], distance: float, ship: bool = False) -> int:
    """Play the library on training ``seeds``; add the hand-overs farther than ``distance`` from every knot as starts.

    The starts go to the library's local list (``./pendulab-out/plan_library``), or with ``ship`` to the list shipped
    with pendulab (``pendulab/control/realai/plans/grown_<task>.npz``, its training seeds recorded beside them).
    """
    from pendulab._io import atomic_path
    from pendulab.control.plan_library import read_shipped_grown, shipped_grown_path

    ctrl = _build(task)
    new = []
    for seed in seeds:
        ctrl.handovers.clear()
        v3_score(task, ctrl, seed=seed)
        new += [h for h in ctrl.handovers if ctrl.library.nearest(h)[2] > distance]
    new_starts = np.array(new).reshape(-1, 4)
    if ship:
        path = shipped_grown_path(task)
        old, old_seeds = read_shipped_grown(task, ctrl.design_digest)
        starts = np.vstack([old, new_starts])
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, starts=starts, design=np.str_(ctrl.design_digest), seeds=np.array(old_seeds + list(seeds)))
    else:
        path = ctrl.grown_starts  # the list of this library's design: no other library reads it
        old = np.load(path) if path.exists() else np.zeros((0, 4))
        starts = np.vstack([old, new_starts])
        with atomic_path(path) as tmp:
            np.save(tmp, starts)
    print(f"{task}: {len(new)} hand-overs farther than {distance} from the library added ({len(starts)} grown starts in {path})")
    return len(new)


def _call_bench(task: str, ctrl: object, n: int = 20000) -> str:
    """Worst-path call time of the library controller (a fresh lookup every call) on ``n`` random states: wall and CPU."""
    rs = np.random.RandomState(0)
    xs = np.column_stack([rs.uniform(-np.pi, np.pi, (n, 2)), rs.normal(0.0, 5.0, (n, 2))])
    wall, cpu = np.empty(n), np.empty(n)
    for k, x in enumerate(xs):
        ctrl._plan = None  # force the nearest-knot lookup (the most expensive path)
        w0, c0 = time.perf_counter(), time.thread_time()
        ctrl(k * 0.002, x)
        cpu[k], wall[k] = time.thread_time() - c0, time.perf_counter() - w0
    wall, cpu = wall * 1e3, cpu * 1e3
    return (
        f"| {task} | {len(ctrl.library)} plans | wall median {np.median(wall):.3f} / p99 {np.percentile(wall, 99):.3f} / "
        f"max {wall.max():.2f} ms, {int(np.sum(wall > 2.0))} of {n} > 2 ms | CPU median {np.median(cpu):.3f} / "
        f"max {cpu.max():.2f} ms, {int(np.sum(cpu > 2.0))} > 2 ms | load {os.getloadavg()[0]:.1f} |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--controllers", nargs="+", default=["library", "global"])
    ap.add_argument("--tasks", nargs="+", default=["pendubot", "acrobot"])
    ap.add_argument("--md", type=Path, default=None, help="append the table to this Markdown file")
    ap.add_argument("--build-only", action="store_true", help="build the plan libraries and stop")
    ap.add_argument("--cached-only", action="store_true", help="library: use the cached plans only, solve none")
    ap.add_argument("--grow-seeds", type=int, nargs="+", default=None, help="training seeds: add uncovered hand-overs")
    ap.add_argument("--grow-distance", type=float, default=0.2, help="lookup distance above which a hand-over is added")
    ap.add_argument("--ship", action="store_true", help="--grow-seeds: add to the grown starts shipped with pendulab")
    ap.add_argument(
        "--schedule", choices=["current", "published"], default="current",
        help="reset draw: upstream's current code, or the published runs' (seed 777 pendubot / 333 acrobot)",
    )  # fmt: skip
    args = ap.parse_args()
    if args.grow_seeds is not None:
        if set(args.grow_seeds) & set(args.seeds):
            ap.error(f"--grow-seeds {args.grow_seeds} must not overlap the scored --seeds {args.seeds}")
        for task in args.tasks:
            _grow(task, args.grow_seeds, args.grow_distance, args.ship)
    calls = []
    if "library" in args.controllers or args.build_only:
        built = {task: _build(task, not args.cached_only) for task in args.tasks}
        if args.build_only:
            return
        calls = [
            "",
            "| task | library | per call, lookup forced on every call (20000 random states) | CPU time | |",
            "|---|---|---|---|---|",
        ]
        calls += [_call_bench(task, built[task]) for task in args.tasks]
        print("\n".join(calls), flush=True)
    lines = [
        f"| task | controller | scores ({args.schedule} schedule, seeds {' '.join(map(str, args.seeds))}) "
        "| mean | spread (max - min) | swing-ups (mean) | call median / max [ms] | calls > 2 ms | wall [s] "
        "| load avg (1 min) | published best |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    print("\n".join(lines), flush=True)
    for task in args.tasks:
        for name in args.controllers:
            t0 = time.perf_counter()
            scores, swings, call_lists, loads = [], [], [], []
            for seed in args.seeds:
                ctrl = built[task] if name == "library" else name
                r = v3_score(task, ctrl, seed=seed, schedule=args.schedule)
                scores.append(r.score)
                swings.append(r.n_swingups)
                call_lists.append(r.call_times)
                loads.append(os.getloadavg()[0])
            ct = np.concatenate(call_lists) * 1e3
            best = max(PUBLISHED_V3[task].items(), key=lambda kv: kv[1])
            label = name
            if name == "library":
                lib = built[task].library
                label = f"library ({len(lib)} plans, {lib.n_refined} band-entry)"
            row = (
                f"| {task} | {label} | {' '.join(f'{s:.3f}' for s in scores)} | {np.mean(scores):.3f} "
                f"| {np.ptp(scores):.3f} | {np.mean(swings):.1f} | {np.median(ct):.3f} / {np.max(ct):.2f} "
                f"| {int(np.sum(ct > 2.0))} of {len(ct)} | {time.perf_counter() - t0:.1f} | {max(loads):.1f} "
                f"| {best[0]} {best[1]} |"
            )
            print(row, flush=True)
            lines.append(row)
    if args.md is not None:
        stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        with open(args.md, "a", encoding="utf-8") as fh:
            fh.write(f"\n### bench_v3.py run, {stamp}\n\n" + "\n".join(lines + calls) + "\n")


if __name__ == "__main__":
    main()

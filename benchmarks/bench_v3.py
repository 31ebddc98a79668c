"""RealAIGym v3 simulation protocol: scores of pendulab's controllers over seeds (rows of benchmarks/results/v3.md).

Run: ``python benchmarks/bench_v3.py [--seeds 0 1 2] [--controllers global library ...] [--tasks pendubot acrobot]
[--md benchmarks/results/v3.md]``. Prints one Markdown row per (task, controller): the scores, their mean and spread
over the seeds, swing-ups, per-call controller time (median / max over all runs; the 2 ms period is the real-time
budget), the wall time and the load average; with ``--md`` the table is appended to that file as a dated section.
The ``library`` controller's plans are built (or completed) first, with a progress bar, under
``./pendulab-out/plan_library`` (``pendulab.control.plan_library``); ``--build-only`` stops after that.
"""

from __future__ import annotations

import argparse
import datetime
import os
import time
from pathlib import Path

import numpy as np

from pendulab.evaluate.realai.v3 import PUBLISHED_V3, v3_score


def _build(task: str) -> object:
    from pendulab.commands._common import ProgressBar
    from pendulab.control.plan_library import library_controller

    bar = ProgressBar(f"plan library ({task})", True)
    try:
        return library_controller(task, progress=bar)
    finally:
        bar.close()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--controllers", nargs="+", default=["library", "global"])
    ap.add_argument("--tasks", nargs="+", default=["pendubot", "acrobot"])
    ap.add_argument("--md", type=Path, default=None, help="append the table to this Markdown file")
    ap.add_argument("--build-only", action="store_true", help="build the plan libraries and stop")
    args = ap.parse_args()
    if "library" in args.controllers or args.build_only:
        built = {task: _build(task) for task in args.tasks}
        if args.build_only:
            return
    lines = [
        "| task | controller | scores (seeds " + " ".join(map(str, args.seeds)) + ") | mean | spread (max - min) "
        "| swing-ups (mean) | call median / max [ms] | calls > 2 ms | wall [s] | load avg (1 min) | published best |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    print("\n".join(lines), flush=True)
    for task in args.tasks:
        for name in args.controllers:
            t0 = time.perf_counter()
            scores, swings, calls, loads = [], [], [], []
            for seed in args.seeds:
                ctrl = built[task] if name == "library" else name
                r = v3_score(task, ctrl, seed=seed)
                scores.append(r.score)
                swings.append(r.n_swingups)
                calls.append(r.call_times)
                loads.append(os.getloadavg()[0])
            ct = np.concatenate(calls) * 1e3
            best = max(PUBLISHED_V3[task].items(), key=lambda kv: kv[1])
            row = (
                f"| {task} | {name} | {' '.join(f'{s:.3f}' for s in scores)} | {np.mean(scores):.3f} "
                f"| {np.ptp(scores):.3f} | {np.mean(swings):.1f} | {np.median(ct):.3f} / {np.max(ct):.2f} "
                f"| {int(np.sum(ct > 2.0))} of {len(ct)} | {time.perf_counter() - t0:.1f} | {max(loads):.1f} "
                f"| {best[0]} {best[1]} |"
            )
            print(row, flush=True)
            lines.append(row)
    if args.md is not None:
        stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        with open(args.md, "a", encoding="utf-8") as fh:
            fh.write(f"\n### bench_v3.py run, {stamp}\n\n" + "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()

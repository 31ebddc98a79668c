"""RealAIGym v3 simulation protocol: scores of pendulab's controllers over seeds (writes benchmarks/results/v3.md rows).

Run: ``python benchmarks/bench_v3.py [--seeds 0 1 2] [--controllers global best tvlqr swingup]``.
Prints one Markdown row per (task, controller): score mean and spread over the seeds, uptime, swing-ups,
per-call controller time (median / max over all runs) and the wall time.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pendulab.evaluate.realai.v3 import PUBLISHED_V3, v3_score


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--controllers", nargs="+", default=["global", "best", "tvlqr", "swingup"])
    ap.add_argument("--tasks", nargs="+", default=["pendubot", "acrobot"])
    args = ap.parse_args()
    print(
        "| task | controller | scores (seeds " + " ".join(map(str, args.seeds)) + ") | mean | spread (max - min) "
        "| swing-ups (mean) | call median / max [ms] | wall [s] | published best |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for task in args.tasks:
        for name in args.controllers:
            t0 = time.perf_counter()
            scores, swings, calls = [], [], []
            for seed in args.seeds:
                r = v3_score(task, name, seed=seed)
                scores.append(r.score)
                swings.append(r.n_swingups)
                calls.append(r.call_times)
            ct = np.concatenate(calls) * 1e3
            best = max(PUBLISHED_V3[task].items(), key=lambda kv: kv[1])
            print(
                f"| {task} | {name} | {' '.join(f'{s:.3f}' for s in scores)} | {np.mean(scores):.3f} "
                f"| {np.ptp(scores):.3f} | {np.mean(swings):.1f} | {np.median(ct):.3f} / {np.max(ct):.2f} "
                f"| {time.perf_counter() - t0:.1f} | {best[0]} {best[1]} |",
                flush=True,
            )


if __name__ == "__main__":
    main()

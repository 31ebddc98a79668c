"""Time of one full robustness scorecard (all categories, 20 runs per level), and the cost of one episode vs a peer.

    python benchmarks/bench_scorecard.py [--repeats 3] [--controller swingup] [--task pendubot] [--workers 2]
                                         [--out benchmarks/results/scorecard.md]

Target (issue 13): the scorecard of one controller on one task, all categories, 20 runs per level, in <= 60 s on
2 cores.

Reported:

* wall time of the whole scorecard (``pendulab.evaluate.score``, ``workers`` processes), median of ``repeats``;
  and the CPU time of one closed-loop episode in this process, so that a result measured on a loaded machine can
  be extrapolated: ``runs x CPU per episode / workers``;
* per episode (10 s, nominal): the scorecard's fixed-step RK4 plant (one compiled sample map per controller
  sample) vs the peer, ``pendulab.simulate(..., u=as_feedback(controller))`` with CVODES at rtol = atol = 1e-8
  (the general adaptive integrator restarted at every ZOH segment), in the same run; medians of ``repeats``.
* the machine's load average at the start and the end (the benchmark host is shared).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import pendulab as pl
from pendulab.control.controllers import controller_for_task
from pendulab.control.feedback import as_feedback
from pendulab.control.swingup.tasks import load_task
from pendulab.evaluate.perturb import run_perturbed_episode
from pendulab.evaluate.scorecard import score


def _cpu(fn, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--controller", default="swingup")
    ap.add_argument("--task", default="pendubot")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "scorecard.md"))
    args = ap.parse_args(argv)

    load0 = os.getloadavg()
    task = load_task(args.task)
    ctrl, x0 = controller_for_task(args.controller, task)
    run_perturbed_episode(ctrl, task, x0)  # warm-up: JIT-compiles the plant's sample map

    ep_cpu = _cpu(lambda: run_perturbed_episode(ctrl, task, x0), args.repeats * 3)
    peer = lambda: pl.simulate(task.model, x0, task.t_final, dt=ctrl.sample_time, u=as_feedback(ctrl, task.model))  # noqa: E731
    peer_cpu = _cpu(peer, args.repeats)
    ref = pl.simulate(task.model, x0, 2.0, dt=ctrl.sample_time, u=as_feedback(ctrl, task.model), rtol=1e-11, atol=1e-11)
    err = float(np.max(np.abs(run_perturbed_episode(ctrl, task, x0, t_final=2.0).x - ref.x)))

    walls, cpus, cards = [], [], []
    for k in range(args.repeats):
        print(f"scorecard {k + 1}/{args.repeats} ...", file=sys.stderr)
        t0, c0 = time.perf_counter(), os.times()
        cards.append(score(args.controller, task, runs=args.runs, workers=args.workers))
        walls.append(time.perf_counter() - t0)
        c1 = os.times()
        # CPU of this process and of the (finished, reaped) worker processes.
        cpus.append(sum(c1[i] - c0[i] for i in range(4)))
    load1 = os.getloadavg()
    card = cards[-1]
    n = len(card.records)
    wall = statistics.median(walls)
    cpu = statistics.median(cpus)
    lines = [
        "# Robustness scorecard: time of one full scorecard",
        "",
        f"Command: `python benchmarks/bench_scorecard.py --repeats {args.repeats} --controller {args.controller} "
        f"--task {args.task} --workers {args.workers} --runs {args.runs}`",
        "",
        f"Host: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"pendulab {pl.__version__}. Load average (1 min) at start {load0[0]:.1f}, at end {load1[0]:.1f} "
        "(the host is shared: wall times above ~2 x the CPU-based estimate mean other processes took the cores).",
        "",
        f"Scorecard of `{args.controller}` on `{task.name}`: {len(card.categories)} categories, {n} episodes "
        f"({args.runs} runs per level of the stochastic categories, one per level of the deterministic ones), "
        f"RK4 substeps per sample {card.n_sub}, {args.workers} worker processes.",
        "",
        "| quantity | value |",
        "|---|---|",
        f"| scorecard wall time, median of {args.repeats} [s] | {wall:.1f} (runs: {', '.join(f'{w:.1f}' for w in walls)}) |",
        f"| scorecard CPU time, all processes, median [s] | {cpu:.1f} |",
        f"| scorecard CPU time / {args.workers} workers (wall time on idle cores) [s] | {cpu / args.workers:.1f} |",
        f"| CPU per 10 s episode, scorecard plant (median of {args.repeats * 3}) [s] | {ep_cpu:.3f} |",
        f"| estimate on {args.workers} idle cores: episodes x CPU / workers [s] | {n * ep_cpu / args.workers:.1f} |",
        f"| CPU per 10 s episode, peer `pl.simulate` CVODES + `as_feedback` (median of {args.repeats}) [s] | {peer_cpu:.3f} |",
        f"| ratio peer / scorecard plant | {peer_cpu / ep_cpu:.1f} |",
        f"| scorecard plant vs CVODES (rtol 1e-11), max state error over 2 s | {err:.1e} |",
        f"| overall score (same every repeat: seeded) | {card.overall:.3f} ({', '.join(f'{c.overall:.3f}' for c in cards)}) |",
        "",
        "Target: <= 60 s on 2 cores.",
        "",
    ]
    Path(args.out).write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

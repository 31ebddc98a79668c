"""Swing-up benchmark: solve time and iterations vs N per task, and success rates over randomized starts.

Run:  PYTHONPATH=$PWD python benchmarks/bench_swingup.py [--quick]
Writes benchmarks/results/swingup.md. Progress on stderr.

* Timing: medians over repeats of ``swing_up`` (NLP already built and cached: the build time is
  reported separately), default guess ``auto``; the Legendre transcription at the same N is the
  peer measured in the same run.
* Success rate: >= 20 randomized starts per task (angles +-0.3 rad, rates +-0.5 rad/s uniform around
  hanging at rest); a start counts as a success when the solve succeeds AND the TVLQR + LQR closed
  loop meets the height criterion over the 10 s episode. Compared between initial-guess strategies.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from pendulab.control import swing_up
from pendulab.control.swingup.episode import run_episode
from pendulab.control.swingup.tasks import load_task, task_names

OUT = Path(__file__).resolve().parent / "results" / "swingup.md"


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def timing(quick: bool) -> list[str]:
    rows = [
        "| task | method | N | build [s] | solve median [s] | iterations median | runs | all succeeded |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in task_names():
        task = load_task(name)
        elastic = task.model.kind == "elastic"
        Ns = (50, 100) if elastic else (25, 50, 100, 200)
        reps = 1 if quick else (3 if elastic else 5)
        for N in Ns:
            methods = ("radau",) if (elastic or N != 100) else ("radau", "legendre")
            for method in methods:
                t0 = time.perf_counter()
                first = swing_up(task.problem, method, N)
                build = first.build_time
                runs = [first] + [swing_up(task.problem, method, N) for _ in range(reps - 1)]
                times = [r.wall_time for r in runs] if reps == 1 else [r.wall_time for r in runs[1:]] + [first.wall_time]
                its = [r.iterations for r in runs]
                ok = all(r.success for r in runs)
                med_t, med_it = statistics.median(times), statistics.median(its)
                rows.append(f"| {name} | {method} | {N} | {build:.2f} | {med_t:.3f} | {med_it:.0f} | {reps} | {ok} |")
                log(f"[timing] {name} {method} N={N}: median {med_t:.3f} s, {med_it:.0f} it ({time.perf_counter() - t0:.1f} s)")
    return rows


def success_rates(n_starts: int, quick: bool) -> list[str]:
    rows = ["| task | guess | N | starts | solved | closed-loop success | median solve [s] |", "|---|---|---|---|---|---|---|"]
    for name in task_names():
        task = load_task(name)
        elastic = task.model.kind == "elastic"
        N = task.N
        guesses = ("auto",) if elastic else ("auto", "linear", "energy")
        rng = np.random.default_rng(2026)
        starts = []
        for _ in range(n_starts):
            x0 = task.problem.start.copy()
            x0[0:2] += rng.uniform(-0.3, 0.3, 2)
            x0[task.model.nq : task.model.nq + 2] += rng.uniform(-0.5, 0.5, 2)
            starts.append(x0)
        for guess in guesses:
            solved = ok = 0
            times = []
            for i, x0 in enumerate(starts):
                t = replace(task, problem=task.problem.replace(x0=x0))
                ep = run_episode(t, N=N, guess=guess, do_replay=False)
                solved += ep.result.success
                ok += ep.success
                times.append(ep.result.wall_time)
                log(
                    f"[success] {name} guess={guess} start {i + 1}/{len(starts)}: "
                    f"solved={ep.result.success} episode={ep.success} ({ep.result.status})"
                )
            n_s, med = len(starts), statistics.median(times)
            rows.append(f"| {name} | {guess} | {N} | {n_s} | {solved}/{n_s} | {ok}/{n_s} | {med:.2f} |")
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one repeat, 3 starts (smoke run, not recorded)")
    ap.add_argument("--starts", type=int, default=20)
    ap.add_argument("--success-only", action="store_true", help="rerun only the success rates; keep the recorded timing table")
    args = ap.parse_args()
    n = 3 if args.quick else max(20, args.starts)
    head = [
        "# Swing-up benchmark",
        "",
        f"Machine: {platform.machine()}, {platform.python_version()}, 2 cores shared with other jobs (timings noisy).",
        "Command: `PYTHONPATH=$PWD python benchmarks/bench_swingup.py`. Targets: rigid N=100 < 1 s median, elastic < 10 s.",
        "Solve time = IPOPT wall time incl. guess and homotopy stages (elastic: incl. the rigid counterpart solve),",
        "NLP build excluded (built once per structure and cached; build time listed, 0.00 = NLP reused from an",
        "earlier row of the same structure: model kind, method, N, IPOPT options).",
        "",
        "## Solve time and iterations vs N",
        "",
    ]
    if args.success_only and OUT.exists():
        recorded = OUT.read_text().split("## Success rate")[0].rstrip().splitlines()
        head, t_rows = recorded, []
    else:
        t_rows = timing(args.quick)
    s_rows = success_rates(n, args.quick)
    text = (
        "\n".join(
            head
            + t_rows
            + [
                "",
                f"## Success rate over {n} randomized starts",
                "",
                "Starts: hanging at rest + uniform(+-0.3 rad) on both angles and uniform(+-0.5 rad/s) on both rates",
                "(seed 2026). Solved = IPOPT success with dynamics/bounds verified; closed-loop success = TVLQR + LQR,",
                "native CVODES, height criterion over the 10 s episode.",
                "",
            ]
            + s_rows
        )
        + "\n"
    )
    if args.quick:
        print(text)
    else:
        OUT.write_text(text)
        log(f"wrote {OUT}")


if __name__ == "__main__":
    main()

"""RealAIGym robustness leaderboard v2 (full protocol, 722 runs per controller and task), and the results table.

    python benchmarks/bench_robustness.py [--controllers tvlqr best] [--tasks pendubot acrobot] [--workers 2]
                                          [--seed 0] [--out-dir pendulab-out/score] [--report-only]
                                          [--results benchmarks/results/robustness_v2.md]

Each (controller, task) runs as ``pendulab score --protocol robustness-v2`` does: the journal
``OUT_DIR/robustness-v2-CONTROLLER-TASK/runs.json`` keeps every finished batch, and a rerun resumes
from it (Ctrl-C is safe); ``robustness.json`` is written when the run is complete. Then every
``robustness.json`` (and, for unfinished runs, the journal's partial counts) goes into the Markdown
table beside the published rows (``PUBLISHED_ROBUSTNESS``) and the numbers issue 21 quotes for
pendulab's controllers run through upstream's own benchmark code.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
from pathlib import Path

from tqdm import tqdm

from pendulab.evaluate.realai.robustness import CATEGORIES, PUBLISHED_ROBUSTNESS, robustness_v2

#: Issue 21's numbers: pendulab's controllers through upstream's benchmark code (full grids, unseeded): score only.
ISSUE_21 = {("tvlqr", "pendubot"): 0.748, ("tvlqr", "acrobot"): 0.679, ("best", "pendubot"): 0.779, ("best", "acrobot"): 0.619}
#: Directory suffix of runs with ``--every-step`` (the controller called every 2 ms, as upstream calls its controllers).
EVERY = "@2ms"
SHORT = {
    "model": "model",
    "measurement_noise": "vel. noise",
    "u_noise": "torque noise",
    "u_responsiveness": "torque resp.",
    "delay": "delay",
    "perturbation": "perturb.",
}


def run(controller: str, task: str, out_dir: Path, workers: int, seed: int, every_step: bool = False) -> None:
    """Run (or resume) one full protocol and write robustness.json, robustness.png."""
    from pendulab._io import atomic_write_text
    from pendulab.viz.robustness import plot_robustness

    out = out_dir / f"robustness-v2-{controller}{EVERY if every_step else ''}-{task}"
    bar = tqdm(desc=f"robustness-v2 {controller} {task}", unit="run", file=sys.stderr, mininterval=30)

    def progress(done: int, total: int) -> None:
        bar.total = total
        bar.update(done - bar.n)

    res = robustness_v2(
        task,
        controller,
        seed=seed,
        workers=workers,
        progress=progress,
        journal=out / "runs.json",
        resume=True,
        every_step=every_step,
    )
    bar.close()
    plot_robustness(res, out / "robustness.png")
    atomic_write_text(out / "robustness.json", json.dumps(res.to_dict(), indent=1) + "\n")
    print(f"{controller} {task}: score {res.score:.3f}, {res.wall_time:.0f} s", file=sys.stderr)


def seed_spread(controllers: list[str], task: str, out_dir: Path, workers: int, seeds: tuple[int, ...] = (1, 2)) -> None:
    """The velocity-noise category alone with other seeds: how much the majority-of-10 rule depends on the draws."""
    from pendulab.evaluate.realai.controllers import resolve_controller

    path = out_dir / "robustness-v2-seeds.json"
    data = json.loads(path.read_text()) if path.is_file() else {}
    for c in controllers:
        _, ctrl = resolve_controller(task, c)
        for seed in seeds:
            r = robustness_v2(task, ctrl, seed=seed, workers=workers, categories=["measurement_noise"])
            data[f"{c}-{task}-seed{seed}"] = {
                "rate": r.rates["measurement_noise"],
                "level_rates": r.level_rates()["measurement_noise"],
            }
            path.write_text(json.dumps(data, indent=1) + "\n")


def _label(c: str) -> str:
    if c.endswith(EVERY):
        return f"pendulab `{c[: -len(EVERY)]}` called every 2 ms"
    return f"pendulab `{c}`"


def _row(name: str, rates: dict, score: float | str, extra: str = "") -> str:
    cells = " | ".join(f"{100 * rates[c]:.1f}" if c in rates else "–" for c in CATEGORIES)
    s = f"{score:.3f}" if isinstance(score, float) else score
    return f"| {name} | {cells} | **{s}** | {extra} |"


def report(controllers: list[str], tasks: list[str], out_dir: Path, results: Path, seed: int, workers: int) -> None:
    """Write the Markdown table of every finished (or partial) run beside the published rows."""
    lines = [
        "# RealAIGym robustness leaderboard v2: pendulab's controllers on the owners' protocol",
        "",
        f"Command: `nice python benchmarks/bench_robustness.py --controllers {' '.join(controllers)} "
        f"--tasks {' '.join(tasks)} --workers {workers} --seed {seed}` "
        f"(= `pendulab score --protocol robustness-v2 --task TASK --controller NAME --workers {workers} --seed {seed}`), "
        f"{platform.machine()}, Python {platform.python_version()}; machine shared with other jobs (2 cores), so wall "
        "times are upper bounds. Rates in percent; a noise level counts when more than half of its 10 repetitions "
        "succeed; score = mean of the six rates.",
        "",
    ]
    for task in tasks:
        lines += [
            f"## {task}",
            "",
            "| controller | "
            + " | ".join(SHORT[c] for c in CATEGORIES)
            + " | score | runs, wall time, controller time per call |",
            "|---|" + "---|" * len(CATEGORIES) + "---|---|",
        ]
        for c in [*controllers, *(f"{c}{EVERY}" for c in controllers)]:
            out = out_dir / f"robustness-v2-{c}-{task}"
            if c.endswith(EVERY) and not out.is_dir():
                continue
            if (out / "robustness.json").is_file():
                d = json.loads((out / "robustness.json").read_text())
                ct = d["controller_time"]
                extra = (
                    f"{d['runs']} runs, {d['wall_time']:.0f} s; median {1e6 * ct['median_per_call']:.0f} µs, "
                    f"max {1e3 * ct['max_per_call']:.1f} ms (period {1e3 * ct['sample_time']:.0f} ms)"
                )
                lines.append(_row(f"{_label(c)} (seed {d['seed']})", d["rates"], d["score"], extra))
            elif (out / "runs.json").is_file():
                from pendulab._journal import trusted_records
                from pendulab.evaluate.realai.robustness import JOURNAL_KIND, category_rates, level_successes

                # Only runs that validate (version, settings, each run's SHA-256) are counted in the table.
                recs = list(trusted_records(out / "runs.json", JOURNAL_KIND).values())
                rates = category_rates(level_successes(recs))
                lines.append(_row(f"{_label(c)} (unfinished)", rates, "–", f"{len(recs)} of 722 runs finished"))
            else:
                lines.append(f"| pendulab `{c}` | not run | | | | | | | |")
            if (c, task) in ISSUE_21:
                lines.append(
                    f"| pendulab `{c}`, upstream's code (issue 21) | | | | | | | {ISSUE_21[(c, task)]:.3f} | as quoted |"
                )
        spread = out_dir / "robustness-v2-seeds.json"
        if spread.is_file():
            sd = json.loads(spread.read_text())
            for c in controllers:
                got = {k.rsplit("seed", 1)[1]: v["rate"] for k, v in sd.items() if k.startswith(f"{c}-{task}-seed")}
                if got:
                    seeds = ", ".join(f"seed {k}: {100 * v:.1f}" for k, v in sorted(got.items()))
                    lines.append(f"| pendulab `{c}`, velocity noise with other seeds | | {seeds} | | | | | | `--seed-spread` |")
        for name, (rates, score) in PUBLISHED_ROBUSTNESS[task].items():
            lines.append(_row(f"published `{name}`", {c: r / 100 for c, r in zip(CATEGORIES, rates, strict=True)}, score))
        lines.append("")
    lines += [
        "## Notes",
        "",
        "* The runner is checked run for run against upstream's own `benchmarker` on reduced grids (same seed, same "
        "controller: identical successes, final states of the stabilized runs within 4e-13; "
        "`tests/evaluate/test_robustness_v2.py`), so the differences to the issue's numbers are not the protocol's.",
        "* Issue 21 quotes only totals of unseeded upstream runs. `tvlqr` acrobot agrees (0.679); the others do "
        "not decompose consistently with these rates (deterministic categories included), so they come from "
        "another controller adaptor or plan version, and the noise categories from other draws.",
        "* Other rows: `nice python benchmarks/bench_robustness.py --controllers tvlqr --every-step` (called every "
        "2 ms) and `... --controllers tvlqr best --seed-spread` (the velocity-noise category alone, pendubot, seeds 1 "
        "and 2: its spread is the draws' effect on the majority-of-10 rule near 50 % success).",
        "* `called every 2 ms`: the controller is called every step, as upstream's simulator calls its controllers "
        "(`robustness_v2(every_step=True)`, `--every-step`), instead of on its own 10 ms grid with the output held. "
        "Fresh noisy measurements every 2 ms average out; one held sample drives 10 ms.",
        "* Controller time: the median per call is the controller's cost (~10 µs); the maximum is the shared "
        "machine's scheduling (the per-run maxima have a median of 12-18 ms for the same 10 µs controller at nice 10 "
        "on 2 cores shared by 4 jobs), not the controller.",
        "",
    ]
    results.parent.mkdir(parents=True, exist_ok=True)
    results.write_text("\n".join(lines) + "\n")
    print(f"wrote {results}", file=sys.stderr)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--controllers", nargs="+", default=["tvlqr", "best"])
    ap.add_argument("--tasks", nargs="+", default=["pendubot", "acrobot"])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out-dir", type=Path, default=Path("pendulab-out/score"))
    ap.add_argument("--results", type=Path, default=Path("benchmarks/results/robustness_v2.md"))
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--every-step", action="store_true", help="call the controllers every 2 ms step (upstream's loop)")
    ap.add_argument("--seed-spread", action="store_true", help="velocity-noise category with seeds 1 and 2 (pendubot)")
    a = ap.parse_args()
    if a.seed_spread:
        seed_spread(a.controllers, "pendubot", a.out_dir, a.workers)
    elif not a.report_only:
        for task in a.tasks:
            for c in a.controllers:
                run(c, task, a.out_dir, a.workers, a.seed, a.every_step)
    report(a.controllers, a.tasks, a.out_dir, a.results, a.seed, a.workers)


if __name__ == "__main__":
    main()

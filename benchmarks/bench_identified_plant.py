"""pendulab's controllers on the identified C.1 robot beside the nominal plant: RealAIGym v2 and v3 (simulation).

The leaderboards simulate design C.1 as DFKI's model 1.0/1.1 (no friction, no rotor inertia). ``pendulab identify``
finds, from the robot's own measured records, Coulomb friction of 0.16 / 0.12 N.m on the two joints and a rotor
inertia (the shipped plant, :data:`pendulab.model.plant_file.SHIPPED_PLANTS`). This study runs each controller, designed
exactly as for the leaderboard, on both plants: the v2 run (10 s from hanging) and v3 episodes (60 s, 15 resets;
seeds 0, 1, 2). The cases are the leaderboard's own (``pendulab score --leaderboard`` reads them back): journaled
under ``--root`` (default ``./pendulab-out/leaderboard``), one file per finished case, skipped when already there.

Writes ``benchmarks/results/identified_plant.md`` and ``identified_plant.json``.

Usage::

    python benchmarks/bench_identified_plant.py [--v2 best tvlqr ...] [--v3 best global ...] [--tasks pendubot acrobot]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
from pathlib import Path

from tqdm import tqdm

from pendulab.evaluate.realai.leaderboard import DEFAULT_CONTROLLERS, DEFAULT_ROOT, TASKS, run_protocols
from pendulab.evaluate.realai.leaderboard_tables import _identified_table, _v2_table, _v3_table
from pendulab.evaluate.realai.plant import plant_label
from pendulab.model.plant_file import load_plant

RESULTS = Path(__file__).resolve().parent / "results"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--v2", nargs="+", default=list(DEFAULT_CONTROLLERS["v2"]), help="controllers of the v2 runs")
    ap.add_argument("--v3", nargs="+", default=["best", "global", "replan"], help="controllers of the nominal v3 episodes")
    # replan on the identified robot re-plans nearly every sample (its plans never meet the friction): measured
    # 7.5 steps/s, an hour per 60 s episode, so it is left out of the default
    ap.add_argument("--v3-identified", nargs="+", default=["best", "global"], help="controllers of the identified v3 episodes")
    ap.add_argument("--tasks", nargs="+", default=list(TASKS))
    ap.add_argument("--root", type=Path, default=DEFAULT_ROOT, help="journal directory (shared with the leaderboard)")
    args = ap.parse_args()
    controllers = {"v2": args.v2, "v2-identified": args.v2, "v3": args.v3, "v3-identified": args.v3_identified}
    bars: dict[str, tqdm] = {}

    def progress(label: str, done: int, total: int) -> None:
        bar = bars.get(label)
        if bar is None:
            for old in bars.values():
                old.close()
            bar = bars[label] = tqdm(total=total, desc=label, unit="step", mininterval=2.0)
        bar.update(done - bar.n)

    run = run_protocols(controllers, tasks=args.tasks, protocols=list(controllers), resume=True, root=args.root,
                        progress=progress)  # fmt: skip
    for bar in bars.values():
        bar.close()
    plant = load_plant("c1")
    lines = [
        "# pendulab's controllers on the identified C.1 robot beside the nominal plant",
        "",
        f"Recorded {datetime.date.today()} by `python benchmarks/bench_identified_plant.py` on {platform.node()} "
        f"({os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}). Plant: `{plant_label(plant)}` "
        f"(cf1 {plant.params['cf1']:.3f}, cf2 {plant.params['cf2']:.3f} N.m, b1 {plant.params['b1']:.4f}, "
        f"b2 {plant.params['b2']:.4f} N.m.s/rad, Ir {plant.params['Ir']:.2e} kg.m², m2 {plant.params['m2']:.3f} kg, "
        f"r2 {plant.params['r2']:.3f} m). Controllers designed as for the leaderboard (on model 1.0/1.1).",
        "",
    ]
    for task in args.tasks:
        lines += [f"## {task}", "", "### scores", "", *_identified_table(run, task), ""]
        lines += ["### v2 on the identified robot", "", *_v2_table(run, task, "v2-identified"), ""]
        lines += ["### v3 on the identified robot", "", *_v3_table(run, task, "v3-identified"), ""]
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "identified_plant.md").write_text("\n".join(lines) + "\n")
    cases = [{"protocol": c.protocol, "task": c.task, "controller": c.controller, "status": c.status, "reason": c.reason,
              "score": (c.summary.get("mean") if c.protocol.startswith("v3") else c.summary.get("score"))}
             for c in run.cases]  # fmt: skip
    (RESULTS / "identified_plant.json").write_text(json.dumps({"plant": plant_label(plant), "cases": cases}, indent=1) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

"""State estimation and the robust controller under RealAIGym robustness-v2 disturbances.

A small harness of the v2 disturbances on pendulab's leaderboard RK4 loop (2 ms, 10 s), one disturbance per run,
as upstream's ``Simulator`` applies them: velocity-measurement noise, torque noise, torque response
``u = u_last + k (u_cmd - u_last)``, measurement delay ``x_meas(t_k) = x(t_{k-n})`` with ``n = int(delay/dt)``;
success = final state within (0.35, 0.35, 1, 1) of upright (relative angles). Prefer H1's
``pendulab.evaluate.realai.robustness`` for the full protocol when it exists.

Usage::

    nice python benchmarks/bench_estimation.py --task pendubot --controller robust --category delay --levels 21
    # upstream's protocol (pendulab.evaluate.realai.robustness), chosen categories, one worker, journaled:
    nice python benchmarks/bench_estimation.py --protocol --task acrobot --controller robust \
        --categories measurement_noise,delay --out pendulab-out/bench_estimation
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from pendulab.control.feedback import full_input
from pendulab.control.realai.spec import DT, N_STEPS, TASKS, TORQUE_LIMIT, leaderboard_model
from pendulab.evaluate.realai.simulate import rk4_rollout

LEVELS = {
    "noise": np.linspace(0.0, 0.5, 21),
    "unoise": np.linspace(0.0, 1.1, 21),
    "response": np.linspace(0.1, 2.0, 21),
    "delay": np.linspace(0.0, 0.04, 21),
}


def make(task: str, name: str):
    if name == "best":
        from pendulab.control.realai.design import best_controller

        return best_controller(task)
    if name == "robust":
        from pendulab.control.robust import robust_controller

        return robust_controller(task)
    from pendulab.control.controllers import controller_for_task
    from pendulab.control.realai.spec import leaderboard_task

    return controller_for_task(name, leaderboard_task(task))[0]


def run_case(task, controller, *, noise=0.0, unoise=0.0, response=1.0, delay=0.0, seed=0, timings=None, cpu=None):
    """One 10 s run with one disturbance; returns (success, final relative state)."""
    model = leaderboard_model(task)
    rng = np.random.default_rng(seed)
    limit = np.zeros(2)
    limit[TASKS[task]] = TORQUE_LIMIT
    n_delay = int(delay / DT)
    ratio = round(controller.sample_time / DT)
    hist: list[np.ndarray] = []
    last = np.zeros(2)
    held = np.zeros(2)
    controller.reset()

    def policy(k, t, x):
        nonlocal last, held
        hist.append(x.copy())
        xm = hist[max(len(hist) - 1 - n_delay, 0)].copy()
        if noise > 0:
            xm[2:] += rng.normal(0.0, noise, 2)
        if k % ratio == 0:
            t0, c0 = time.perf_counter(), time.thread_time()
            held = np.clip(full_input(controller, controller(t, xm)), -limit, limit)
            if timings is not None:
                timings.append(time.perf_counter() - t0)
            if cpu is not None:
                cpu.append(time.thread_time() - c0)
        u = last + response * (held - last)
        if unoise > 0:
            u = u + rng.normal(0.0, unoise, 2)
        u = np.clip(u, -limit, limit)
        last = u
        return u

    _, x, _ = rk4_rollout(model, model.state(), policy, N_STEPS)
    xf = x[-1]
    rel = np.array([xf[0], xf[1] - xf[0], xf[2], xf[3] - xf[2]])
    err = np.abs([(rel[0] - np.pi + np.pi) % (2 * np.pi) - np.pi, (rel[1] + np.pi) % (2 * np.pi) - np.pi, rel[2], rel[3]])
    ok = bool(np.all(np.isfinite(err)) and np.all(err < [0.35, 0.35, 1.0, 1.0]))
    return ok, rel


def protocol(args) -> None:
    """Categories of upstream's robustness-v2 protocol through pendulab.evaluate.realai.robustness (one worker)."""
    from pathlib import Path

    from pendulab.evaluate.realai.robustness import robustness_v2

    cats = args.categories.split(",")
    out = Path(args.out) / f"{args.controller}-{args.task}-{'+'.join(cats)}"
    out.mkdir(parents=True, exist_ok=True)
    journal = out / "runs.json"
    res = robustness_v2(
        args.task, args.controller, workers=1, categories=cats, journal=journal, resume=journal.exists(), seed=args.seed
    )
    rec = res.records
    med = float(np.median([r["ctrl_median"] for r in rec])) * 1e3
    mx = float(np.max([r["ctrl_max"] for r in rec])) * 1e3
    summary = {
        "task": args.task,
        "controller": args.controller,
        "categories": cats,
        "rates": res.rates,
        "runs": len(rec),
        "wall_s": res.wall_time,
        "ctrl_ms_median_of_run_medians": med,
        "ctrl_ms_max": mx,
        "runs_with_a_call_over_2ms": int(sum(r["ctrl_max"] > 0.002 for r in rec)),
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(json.dumps(summary))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--protocol", action="store_true", help="run upstream's protocol categories instead of the harness")
    ap.add_argument("--categories", default="measurement_noise,delay")
    ap.add_argument("--out", default="pendulab-out/bench_estimation")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timing", action="store_true", help="per-call time percentiles of one nominal and one 40 ms-delay run")
    ap.add_argument("--task", default="pendubot")
    ap.add_argument("--controller", default="robust")
    ap.add_argument("--category", default="delay", choices=list(LEVELS))
    ap.add_argument("--levels", type=int, default=21, help="use every (21 // levels)-th level")
    ap.add_argument("--reps", type=int, default=1)
    args = ap.parse_args()
    if args.protocol:
        protocol(args)
        return
    if args.timing:
        for name in ("best", args.controller):
            ctrl = make(args.task, name)
            for kw in ({}, {"delay": 0.04}):
                tm: list[float] = []
                cpu: list[float] = []
                run_case(args.task, ctrl, timings=tm, cpu=cpu, **kw)
                q = np.percentile(np.array(tm) * 1e3, [50, 99, 99.9, 100])
                qc = np.percentile(np.array(cpu) * 1e3, [50, 99, 99.9, 100])
                print(json.dumps({"controller": name, "task": args.task, **kw, "ms_p50_p99_p999_max": np.round(q, 3).tolist(),
                                  "calls_over_2ms": int(np.sum(np.array(tm) > 2e-3)), "calls": len(tm),
                                  "cpu_ms_p50_p99_p999_max": np.round(qc, 3).tolist()}))  # fmt: skip
        return
    ctrl = make(args.task, args.controller)
    levels = LEVELS[args.category][:: max(1, 21 // args.levels)]
    timings: list[float] = []
    rows = []
    for lv in levels:
        succ = [run_case(args.task, ctrl, **{args.category: float(lv)}, seed=s, timings=timings)[0] for s in range(args.reps)]
        rows.append((float(lv), float(np.mean(succ))))
        print(f"{args.category}={lv:.4f} success={np.mean(succ):.2f}", flush=True)
    tm = np.array(timings) * 1e3
    print(
        json.dumps(
            {
                "task": args.task,
                "controller": args.controller,
                "category": args.category,
                "rate": float(np.mean([r for _, r in rows])),
                "call_ms_median": float(np.median(tm)),
                "call_ms_max": float(tm.max()),
            }
        )
    )


if __name__ == "__main__":
    main()

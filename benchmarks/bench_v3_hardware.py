"""RealAIGym v3-hardware protocol: pendulab's controllers against the ICRA 2025 hardware final (results: v3_hardware.md).

Run: ``python benchmarks/bench_v3_hardware.py [--tasks pendubot acrobot] [--controllers best global replan library]
[--seeds-pendubot 333] [--seeds-acrobot 777] [--allowance 0 0.5] [--md benchmarks/results/v3_hardware.md]
[--sensing] [--velocity-limit 16] [--plant FILE]``. One Markdown row per (task, controller, passive allowance): the
score per seed, the mean, swing-ups, limit resets and safety stops, the largest measured joint rate, the controller's per-call
time (median / max over all calls; the loop's period is 2 ms) and the wall time. With the 0.5 N.m allowance
pendulab's controllers run wrapped in :class:`~pendulab.evaluate.realai.v3_hardware.FrictionCompensated` (the
identified C.1 friction, compensated on both joints from the measured rates), as the hardware teams used the
allowance. The planning controllers (``RATE_BOUNDED``: ``library``, ``replan``, ``mpc_library``) plan with their joint
rates bounded by ``--velocity-limit`` (default ``PLAN_VELOCITY_LIMIT_HW``, 18 rad/s; 0: unbounded), as ``v3_hardware_score``
does (both through :func:`~pendulab.evaluate.realai.v3_hardware.hardware_entry`, as ``pendulab score``). Each
finished case is kept in ``./pendulab-out/bench_v3_hardware/`` and a re-run reuses it. ``--sensing`` prints the
measured sensing and timing table (``docs/realai_v3.md``). With ``--md`` the rows
are appended to that file as a dated section.

``--plant FILE`` simulates another robot (a plant file, e.g. a what-if copy of the identified C.1 written with
``save_plant(load_plant("c1").with_params(cf1=0.033), FILE)``) while the controllers stay as they are designed for
the identified C.1 (their models and friction compensation): a sensitivity study of the protocol to the robot.
Its cases are kept apart (the file's parameters are part of each case's name).
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import os
import time
from pathlib import Path

import numpy as np

from pendulab._journal import read_case, write_case
from pendulab.evaluate.realai.plant import actuated_joint
from pendulab.evaluate.realai.v3_hardware import PLAN_VELOCITY_LIMIT_HW, PUBLISHED_HARDWARE, hardware_entry, run_v3_hardware
from pendulab.identify.sensing import c1_sensing
from pendulab.model.plant_file import IdentifiedPlant, load_plant


def sensing_table() -> list[str]:
    """Markdown table of the sensing and timing measured on the C.1 excitation records."""
    s = c1_sensing()
    st = s.interval_stats()
    return [
        "| quantity | joint 1 | joint 2 | how |",
        "|---|---|---|---|",
        f"| encoder step [rad] | {s.position_step:.4e} | (same) | smallest position change; all changes whole multiples "
        f"(largest deviation {s.position_multiple_error:.1e} steps) |",
        f"| velocity noise std [rad/s] | {s.velocity_noise[0]:.3f} | {s.velocity_noise[1]:.3f} | reply - Savitzky-Golay "
        "derivative of position (cubic, 42 ms) where that is < 0.5 rad/s |",
        f"| velocity noise lag-1 correlation | {s.velocity_correlation[0]:.2f} | {s.velocity_correlation[1]:.2f} | same "
        "residual |",
        f"| torque reading step [N m] | {s.torque_step:.4e} | (same) | smallest change of the reading |",
        f"| torque reading noise std [N m] | {s.torque_noise[0]:.4f} | {s.torque_noise[1]:.4f} | reading - "
        "Savitzky-Golay smoothing (quadratic, 22 ms) |",
        f"| loop interval [ms] | median {1e3 * st['median']:.4f}, min {1e3 * st['min']:.4f}, max {1e3 * st['max']:.3f} | "
        f"p99.9 {1e3 * st['p999']:.3f}; {100 * st['overrun_fraction']:.2f} % above 2.05 ms | time-stamp differences, "
        f"{int(st['n'])} intervals |",
    ]


#: One JSON per finished (task, controller, seed, allowance, rate bound) case; a re-run reads it instead of running.
CASES = Path("pendulab-out/bench_v3_hardware")


def plant_tag(plant: IdentifiedPlant | None) -> str:
    """The part of a case's name that tells the simulated robot: empty for the identified C.1, else its digest."""
    if plant is None or plant.params == load_plant("c1").params:
        return ""
    digest = hashlib.sha256(json.dumps(plant.params, sort_keys=True).encode()).hexdigest()[:10]
    return f"-plant{digest}"


def _run(
    task: str, name: str, seed: int, allowance: float, velocity_limit: float | None, plant: IdentifiedPlant | None = None
) -> dict[str, object]:
    path = CASES / f"{task}-{name}-seed{seed}-allowance{allowance:g}-vmax{velocity_limit or 0:g}{plant_tag(plant)}.json"
    rec = read_case(path)  # None when not run yet, or run by other code
    if rec is not None:
        rec["calls"] = np.asarray(rec["calls"], dtype=float)
        return rec
    # The controller as designed for the identified C.1; the simulated robot may be another (--plant).
    label, ctrl, _, _ = hardware_entry(task, name, allowance, velocity_limit=velocity_limit)
    res = run_v3_hardware(task, ctrl, label, seed=seed, passive_allowance=allowance, plant=plant)
    rec = {
        "score": res.score,
        "swingups": res.n_swingups,
        "limit_resets": res.limit_resets,
        "stopped_at": res.stopped_at,
        "max_rate": res.to_dict()["max_joint_rate"],
        "calls": np.asarray(res.call_times, dtype=float).tolist(),
        "wall": res.wall_time,
        "plant": None if plant is None else {"params": plant.params, "what_if": plant.meta.get("what_if")},
    }
    write_case(path, rec)
    print(f"  {task} {name} seed {seed} allowance {allowance:g}: {res.score:.3f}", flush=True)
    rec["calls"] = np.asarray(rec["calls"], dtype=float)
    return rec


def _passive_cf(task: str) -> str:
    """The robot parameter of the passive joint's Coulomb friction in ``task`` ("cf1" acrobot, "cf2" pendubot)."""
    return f"cf{2 - actuated_joint(task)}"


def friction_figure(path: Path, controller: str = "mpc") -> Path:
    """Score against the simulated robot's passive Coulomb friction, from the recorded cases (the ``--plant`` study).

    One panel per task; per passive allowance the mean over the seeds recorded at every friction value (line) and each
    of those seeds (dots); the identified value and the hardware winner's score marked. Cases of robots that differ
    from the identified C.1 in more than the passive joint's ``cf`` are left out.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c1 = load_plant("c1").params
    points: dict[tuple[str, float], dict[float, dict[int, float]]] = {}
    for f in sorted(CASES.glob(f"*-{controller}-seed*.json")):
        task = f.name.split("-")[0]
        rec = read_case(f)
        if rec is None:  # run by other code
            continue
        params = (rec.get("plant") or {}).get("params") or c1
        cf = _passive_cf(task)
        if any(params[k] != v for k, v in c1.items() if k != cf):
            continue
        allowance = float(f.name.split("-allowance")[1].split("-")[0])
        seed = int(f.name.split("-seed")[1].split("-")[0])
        points.setdefault((task, allowance), {}).setdefault(float(params[cf]), {})[seed] = float(rec["score"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 5), sharey=True)
    for ax, task in zip(axes, ("pendubot", "acrobot"), strict=True):
        cf = _passive_cf(task)
        joint = f"{('shoulder', 'elbow')[int(cf[-1]) - 1]}, {cf}"
        for (t, allowance), by_cf in sorted(points.items()):
            if t != task:
                continue
            xs = sorted(by_cf)
            seeds = sorted(set.intersection(*(set(by_cf[x]) for x in xs)))  # the same seeds at every friction value
            if not seeds:
                continue
            label = (
                "strict rule (allowance 0)"
                if allowance == 0
                else f"allowance {allowance:g} N m (compensating the identified friction)"
            )
            line = ax.plot(xs, [np.mean([by_cf[x][k] for k in seeds]) for x in xs], "-o", label=f"{label}, seeds {seeds}")[0]
            for x in xs:
                ax.plot([x] * len(seeds), [by_cf[x][k] for k in seeds], ".", color=line.get_color(), alpha=0.5)
        ax.axvline(c1[cf], color="k", ls=":", lw=1, label="identified C.1")
        ax.axhline(PUBLISHED_HARDWARE[task]["acados_mpc"], color="tab:red", ls="--", lw=1, label="hardware winner (robot)")
        ax.set_title(f"{task}: '{controller}' on v3-hardware")
        ax.set_xlabel(f"passive joint's Coulomb friction ({joint}) [N m]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), fontsize=7)  # below the panel: the data fill it
    axes[0].set_ylabel("score (uptime / 60 s) [-]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tasks", nargs="+", default=["pendubot", "acrobot"])
    ap.add_argument("--controllers", nargs="+", default=["best", "global", "replan", "library"])
    ap.add_argument("--seeds-pendubot", nargs="+", type=int, default=[333])
    ap.add_argument("--seeds-acrobot", nargs="+", type=int, default=[777])
    ap.add_argument("--allowance", nargs="+", type=float, default=[0.0, 0.5], help="passive allowances [N m]")
    ap.add_argument("--md", type=Path, default=None, help="append the rows to this Markdown file")
    ap.add_argument("--sensing", action="store_true", help="print the measured sensing table first")
    ap.add_argument(
        "--velocity-limit", type=float, default=PLAN_VELOCITY_LIMIT_HW, help="plans' rate bound [rad/s] (0: unbounded)"
    )
    ap.add_argument("--plant", default=None, help="plant file of the simulated robot (default the identified C.1)")
    ap.add_argument(
        "--friction-figure",
        type=Path,
        help="only draw the recorded scores of one --controllers (default mpc) against the passive friction (PNG)",
    )
    args = ap.parse_args()
    if args.friction_figure is not None:
        print(friction_figure(args.friction_figure, args.controllers[0] if len(args.controllers) == 1 else "mpc"))
        return
    vmax = args.velocity_limit or None
    lines: list[str] = []
    plant = None if args.plant is None else load_plant(args.plant)
    if plant is not None:
        changed = plant.meta.get("what_if") or {}
        what = ", ".join(f"{k} {v['identified']:.4g} -> {v['value']:.4g}" for k, v in changed.items()) or "parameters of the file"
        lines += [f"Simulated robot: `{args.plant}` ({what}); controllers as designed for the identified C.1.", ""]
        print(lines[-2], flush=True)
    if args.sensing:
        lines += ["### Sensing and timing measured on the C.1 excitation records", "", *sensing_table(), ""]
        print("\n".join(lines), flush=True)
    head = (
        "| task | controller | passive allowance [N m] | scores (seeds) | mean | hardware winner | gap | swing-ups | "
        "limit resets | safety stop [s] | max rate [rad/s] | call median / max [ms] | wall [s] |"
    )
    rows = [head, "|" + "---|" * (head.count("|") - 1)]
    print("\n".join(rows), flush=True)
    for task in args.tasks:
        seeds = args.seeds_pendubot if task == "pendubot" else args.seeds_acrobot
        winner, target = max(PUBLISHED_HARDWARE[task].items(), key=lambda kv: kv[1])
        for name in args.controllers:
            for allowance in args.allowance:
                w0 = time.perf_counter()
                try:
                    runs = [_run(task, name, s, allowance, vmax, plant) for s in seeds]
                except Exception as exc:  # noqa: BLE001 - a benchmark row records why a controller failed
                    row = f"| {task} | {name} | {allowance:g} | failed: {type(exc).__name__}: {str(exc)[:80]} | | | | | | | | | |"
                    rows.append(row)
                    print(row, flush=True)
                    continue
                scores = [float(r["score"]) for r in runs]
                calls = np.concatenate([r["calls"] for r in runs])
                mean = float(np.mean(scores))
                stops = [f"{r['stopped_at']:.1f}" for r in runs if r["stopped_at"] is not None]
                row = (
                    f"| {task} | {name} | {allowance:g} | {' '.join(f'{s:.3f}' for s in scores)} | **{mean:.3f}** | "
                    f"{winner} {target:.3f} | {mean - target:+.3f} | {np.mean([r['swingups'] for r in runs]):.1f} | "
                    f"{sum(int(r['limit_resets']) for r in runs)} | {' '.join(stops) or '—'} | "
                    f"{max(float(r['max_rate']) for r in runs):.1f} | "
                    f"{1e3 * np.median(calls):.3f} / {1e3 * calls.max():.1f} | {time.perf_counter() - w0:.0f} |"
                )
                rows.append(row)
                print(row, flush=True)
    if args.md is not None:
        stamp = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
        load = os.getloadavg()[0]
        text = [f"## Run of {stamp} (load average {load:.1f})", "", *lines, *rows, ""]
        with args.md.open("a") as fh:
            fh.write("\n".join(text) + "\n")


if __name__ == "__main__":
    main()

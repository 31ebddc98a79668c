"""NMPC swing-up and hold of the rigid pendubot and acrobot tasks through the FMU: success and solve times per solver.

For each task (``swingup_pendubot``, ``swingup_acrobot``: RealAIGym design C.1, 6 N.m on one joint)
and each solver (``sqp`` = sqpmethod + hpipm real-time iteration, ``ipopt``, ``fatrop``): the NMPC of
:func:`pendulab.control.nmpc.nmpc_for_task` (50 Hz, horizon 20 intervals = 0.4 s) runs the FMU of the
task's model (FMI 2, comm step 0.01 s) for 10 s from hanging at rest through
:func:`pendulab.cosim.cosim`. Recorded: success (end effector above 0.9 (L1 + L2) over the last
second), the controller's per-call solve time (median, max) and iterations; medians over
``--repeats`` runs (the max column is the largest max). The ratio column is the solve-time median
against the ``sqp`` run measured in the same invocation. A figure (angles, torque, solve time per
step) goes to ``docs/figures/nmpc_swingup.png``.

Elastic tasks (stiff ``swingup_*_elastic``, k = 25000 N/m, and ``*_elastic_soft``, k = 1000 N/m, undamped
springs; FMU comm step = the task's dt, 0.005 s; NMPC ``sqp`` at 50 Hz): the default ``planning="auto"``
(the planning rule's cheapest level within ``prediction_tolerance``) over ``--elastic-repeats`` runs, the
8-state elastic prediction (``planning="model"``) once in the same invocation (the ratio column), and
once each the levels the rule rejects or the state maps it does not use (measured, to check the rule).

Usage::

    PYTHONPATH=. python benchmarks/bench_nmpc.py [--repeats 3] [--solvers sqp,ipopt,fatrop] [--elastic-repeats 3]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pendulab.control.nmpc import nmpc_for_task
from pendulab.control.swingup.check import height_success
from pendulab.control.swingup.tasks import load_task
from pendulab.cosim import cosim
from pendulab.cosim.plant import StepRejectedError
from pendulab.fmu.export import export

TASKS = ("swingup_pendubot", "swingup_acrobot")
ELASTIC = ("swingup_pendubot_elastic", "swingup_acrobot_elastic", "swingup_pendubot_elastic_soft", "swingup_acrobot_elastic_soft")
#: Checks of the rule, one run each: (task, planning, state_map) the rule does not pick.
CHECKS = (
    ("swingup_pendubot_elastic", "rigid", "average"),
    ("swingup_pendubot_elastic", "quasi-static", "momentum"),
    ("swingup_pendubot_elastic", "quasi-static", "project"),
    ("swingup_pendubot_elastic_soft", "quasi-static", "average"),
)


def run_once(task, fmu: Path, solver: str, **options) -> dict:
    ctrl, x0 = nmpc_for_task(task, sample_time=0.02, solver=solver, **options)
    params = {n: float(getattr(task.model.params, n)) for n in task.model.param_names}
    note = ""
    try:
        traj = cosim(fmu, ctrl, min(0.01, task.dt), task.t_final, x0=x0, params=params)
        check = height_success(traj, task.rest_lengths, task.success_fraction)
        ok, t_up = bool(check.success and check.t_up <= traj.t[-1] - 1.0), check.t_up
    except StepRejectedError as exc:  # a spring driven to collapse: the FMU refuses the step
        traj, ok, t_up, note = None, False, float("nan"), f"FMU stopped: {exc}"
    st = ctrl.stats()
    return {
        "success": ok,
        "t_up": t_up,
        "note": note,
        "level": st["prediction_level"],
        "states": st["prediction_states"],
        "map": st["state_map"],
        "predicted": st["prediction_predicted_error"],
        "median": st["solve_time_median"],
        "max": st["solve_time_max"],
        "it_med": st["iterations_median"],
        "it_max": st["iterations_max"],
        "failures": st["failures"],
        "traj": traj,
        "times": np.array(ctrl.solve_times),
    }


def elastic_rows(tmp: Path, repeats: int) -> list[tuple[str, str, list[dict]]]:
    """Runs on the elastic tasks: auto (``repeats``), the elastic prediction (once), the rule's checks (once each)."""
    # Each task's auto runs next to its elastic-prediction run, so the ratio sees the same machine load.
    jobs = [job for name in ELASTIC for job in ((name, "auto", "average", repeats), (name, "model", "average", 1))]
    jobs += [(name, planning, smap, 1) for name, planning, smap in CHECKS]
    bar = tqdm(total=sum(j[3] for j in jobs), desc="elastic nmpc runs", file=sys.stderr)
    fmus, out = {}, []
    for name, planning, smap, n in jobs:
        task = load_task(name)
        if name not in fmus:
            fmus[name] = export(task.model, tmp / f"{name}.fmu", 2)
        res = []
        for _ in range(n):
            res.append(run_once(task, fmus[name], "sqp", planning=planning, state_map=smap))
            bar.update()
        out.append((name, planning, res))
    bar.close()
    return out


def elastic_table(erows: list) -> list[str]:
    """Markdown table of the elastic runs, ratio against the elastic prediction of the same task."""
    ref = {name: statistics.median(r["median"] for r in res) for name, planning, res in erows if planning == "model"}
    lines = [
        "",
        "## Elastic tasks: the prediction model chosen by the planning rule",
        "",
        "FMU (FMI 2) as the plant with the task's comm step (0.005 s), NMPC `sqp` at 50 Hz, 20 intervals, 10 s from hanging "
        'at rest. *auto* = the default `planning="auto"`: the planning rule\'s cheapest level whose predicted relative '
        "error is within `prediction_tolerance` = 0.2 (rigid `4 w_p/w_s`, rigid + quasi-static `15 (w_p/w_s)^2`); a rigid "
        "prediction gets the measured state through `state_map`. *model* = the 8-state elastic prediction (the former "
        "default), the peer of the ratio column. The other rows check the rule (one run each). Medians over the runs.",
        "",
        "| task | planning | level (states, map) | predicted error | success | t_up [s] | solve median [ms] | solve max [ms] "
        "| failures | median / elastic median |",
        "|---|---|---|---:|---|---:|---:|---:|---:|---:|",
    ]
    notes = []
    for name, planning, res in erows:
        r0 = res[0]
        med = statistics.median(r["median"] for r in res)
        t_up = statistics.median(r["t_up"] for r in res)
        lines.append(
            f"| {name} | {planning} | {r0['level']} ({r0['states']}, {r0['map']}) | {r0['predicted']:.2g} | "
            f"{sum(r['success'] for r in res)}/{len(res)} | {t_up:.2f} | {med * 1e3:.2f} | "
            f"{max(r['max'] for r in res) * 1e3:.2f} | {sum(r['failures'] for r in res)} | {med / ref[name]:.2f} |"
        )
        notes += [f"- {name}, {planning} ({r0['map']}): {r['note']}" for r in res if r["note"]]
    return lines + ([""] + notes if notes else [])


def plot(runs: dict, path: Path) -> None:
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, len(TASKS), figsize=(11, 8), sharex=True, constrained_layout=True)
    for j, name in enumerate(TASKS):
        r = runs[(name, "sqp")]
        tr = r["traj"]
        ax = axes[0, j]
        ax.plot(tr.t, tr["theta1"], label="theta1")
        ax.plot(tr.t, tr["theta2"], label="theta2")
        ax.axhline(np.pi, color="k", lw=0.5, ls=":")
        ax.set(title=f"{name} (FMU plant, NMPC sqp, 50 Hz)", ylabel="angle [rad]")
        ax.legend(loc="lower right")
        ax = axes[1, j]
        ax.step(tr.t, tr.u[:, 0], where="post", label="tau1")
        ax.step(tr.t, tr.u[:, 1], where="post", label="tau2")
        ax.set(ylabel="torque [N.m]")
        ax.legend(loc="upper right")
        ax = axes[2, j]
        for solver in ("sqp", "ipopt", "fatrop"):
            if (name, solver) in runs:
                rr = runs[(name, solver)]
                ax.semilogy(np.arange(len(rr["times"])) * 0.02, rr["times"] * 1e3, lw=0.8, label=solver)
        ax.axhline(20.0, color="r", lw=0.8, ls="--", label="20 ms (one sample)")
        ax.set(xlabel="time [s]", ylabel="controller call [ms]")
        ax.yaxis.set_major_locator(matplotlib.ticker.FixedLocator([1, 2, 5, 10, 20, 50, 100, 200]))
        ax.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.legend(loc="upper right", fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--solvers", default="sqp,ipopt,fatrop")
    ap.add_argument("--no-elastic", action="store_true", help="skip the elastic tasks")
    ap.add_argument("--elastic-repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=Path("benchmarks/results/nmpc.md"))
    ap.add_argument("--figure", type=Path, default=Path("docs/figures/nmpc_swingup.png"))
    args = ap.parse_args()
    solvers = [s.strip() for s in args.solvers.split(",") if s.strip()]
    rows, runs = [], {}
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        jobs = [(name, solver) for name in TASKS for solver in solvers]
        bar = tqdm(total=len(jobs) * args.repeats, desc="nmpc runs", file=sys.stderr)
        for name in TASKS:
            task = load_task(name)
            fmu = export(task.model, Path(tmp) / f"{name}.fmu", 2)
            for solver in solvers:
                res = []
                for _ in range(args.repeats):
                    res.append(run_once(task, fmu, solver))
                    bar.update()
                runs[(name, solver)] = res[-1]
                rows.append((name, solver, res))
        bar.close()
        erows = [] if args.no_elastic else elastic_rows(Path(tmp), args.elastic_repeats)
    base = {name: statistics.median(r["median"] for r in res) for name, solver, res in rows if solver == "sqp"}
    lines = [
        "# NMPC swing-up and hold through the FMU",
        "",
        f"`PYTHONPATH=. python benchmarks/bench_nmpc.py --repeats {args.repeats} --solvers {args.solvers}` on "
        f"{platform.machine()} / Python {platform.python_version()} (shared 2-core machine, 1-min load average "
        f"{load_before:.1f} before and {os.getloadavg()[0]:.1f} after the runs: absolute times are noisy; the ratio "
        "column is measured in the same invocation).",
        "",
        "Rigid RealAIGym tasks (design C.1, 6 N.m on the actuated joint), FMU (FMI 2, comm step 0.01 s) as the plant, "
        "from hanging at rest, 10 s, NMPC at 50 Hz, 20 intervals (0.4 s) of RK4 (2 substeps), tracking the task's "
        "optimized swing-up then regulating upright. Solve time = wall time of one controller call (state mapping, "
        "solve and warm start). Medians over the runs; *max* is the largest over all runs.",
        "",
        "| task | solver | success | t_up [s] | solve median [ms] | solve max [ms] | iterations median / max | failures "
        "| median / sqp median |",
        "|---|---|---|---:|---:|---:|---|---:|---:|",
    ]
    for name, solver, res in rows:
        med = statistics.median(r["median"] for r in res)
        lines.append(
            f"| {name} | {solver} | {sum(r['success'] for r in res)}/{len(res)} | "
            f"{statistics.median(r['t_up'] for r in res):.2f} | {med * 1e3:.2f} | {max(r['max'] for r in res) * 1e3:.2f} | "
            f"{statistics.median(r['it_med'] for r in res):g} / {max(r['it_max'] for r in res)} | "
            f"{sum(r['failures'] for r in res)} | {med / base[name]:.1f} |"
        )
    if erows:
        lines += elastic_table(erows)
    lines += ["", f"Figure: `{args.figure}` (last run of each task with sqp; solve time per call of every solver).", ""]
    args.out.write_text("\n".join(lines))
    plot(runs, args.figure)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

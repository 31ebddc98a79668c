"""Elastic NMPC in real time: the compiled RTI of the 8-state elastic prediction through the elastic FMU, at 50 Hz.

For each elastic task (stiff ``swingup_*_elastic``, k = 25000 N/m; soft ``*_elastic_soft``, k = 1000 N/m; undamped
springs) the RTI (:func:`pendulab.control.nmpc.rti.rti_for_task`: one compiled Gauss-Newton step per sample, the
8-state elastic model predicted over 30 intervals of 20 ms (0.6 s), RK4 sub-steps of at most 10 ms and at least
``h omega_fast``, tracking the task's swing-up plan then regulating upright) runs the task's FMU (FMI 2, comm step
the task's dt) for the task's duration from hanging at rest through :func:`pendulab.cosim.cosim`, beside the peer
it replaces: the NMPC of :func:`pendulab.control.nmpc.nmpc_for_task` (``sqp``: sqpmethod + hpipm real-time
iteration) with the same 8-state prediction (``planning="model"``, its default 20 intervals), in the same
invocation, alternating.
Recorded: success (end effector above 0.9 of the links' rest lengths over the last second, as ``bench_nmpc``),
the swing-up time and the per-call time (median, max); the ratio column divides the medians.

Usage::

    PYTHONPATH=. python benchmarks/bench_rti_elastic.py [--repeats 3] [--out benchmarks/results/rti_elastic.md]

Each finished (task, controller, round) case is kept in ``./pendulab-out/bench_rti_elastic/``; a re-run reuses it.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pendulab._journal import read_case, write_case
from pendulab.control.nmpc import nmpc_for_task
from pendulab.control.nmpc.rti import rti_for_task
from pendulab.control.swingup.check import height_success
from pendulab.control.swingup.tasks import load_task
from pendulab.cosim import cosim
from pendulab.cosim.plant import StepRejectedError
from pendulab.fmu.export import export

ELASTIC = ("swingup_pendubot_elastic", "swingup_acrobot_elastic", "swingup_pendubot_elastic_soft", "swingup_acrobot_elastic_soft")
CASES = Path("pendulab-out/bench_rti_elastic")
SAMPLE = 0.02  # 50 Hz
#: RTI prediction: 30 intervals (0.6 s). 20 (0.4 s, the nmpc default) loses the soft acrobot (0/3 through the FMU,
#: 74 failed steps a run; 30 swings it up, as does q_rate 0.1 or 100 Hz with 40 intervals: measured 2026-11-28).
RTI_HORIZON = 30


def build(task, kind: str):
    if kind == "rti":
        return rti_for_task(task, sample_time=SAMPLE, interval=SAMPLE, horizon=RTI_HORIZON)
    return nmpc_for_task(task, sample_time=SAMPLE, solver="sqp", planning="model")


def run_once(task, fmu: Path, kind: str) -> dict:
    ctrl, x0 = build(task, kind)
    params = {n: float(getattr(task.model.params, n)) for n in task.model.param_names}
    note = ""
    try:
        traj = cosim(fmu, ctrl, min(0.01, task.dt), task.t_final, x0=x0, params=params)
        check = height_success(traj, task.rest_lengths, task.success_fraction)
        ok, t_up = bool(check.success and check.t_up <= traj.t[-1] - 1.0), float(check.t_up)
    except StepRejectedError as exc:  # a spring driven to collapse: the FMU refuses the step
        ok, t_up, note = False, float("nan"), f"FMU stopped: {exc}"
    st = ctrl.stats()
    return {
        "success": ok,
        "t_up": t_up,
        "note": note,
        "median": float(st["solve_time_median"]),
        "max": float(st["solve_time_max"]),
        "failures": int(st["failures"]),
        "unsolved": int(st.get("qp_unsolved", 0)),
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=None, help="write the Markdown table here")
    args = ap.parse_args()
    CASES.mkdir(parents=True, exist_ok=True)
    load0 = os.getloadavg()
    order = (("rti", "nmpc"), ("nmpc", "rti"))  # alternating, so both see the same load
    jobs = [(name, rnd, kind) for name in ELASTIC for rnd in range(args.repeats) for kind in order[rnd % 2]]
    results: dict[tuple[str, str], list[dict]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        fmus: dict[str, Path] = {}
        for name, rnd, kind in tqdm(jobs, desc="elastic RTI / NMPC runs"):
            label = f"{kind}-h{RTI_HORIZON}" if kind == "rti" else kind
            path = CASES / f"{name}-{label}-round{rnd}.json"
            rec = read_case(path)  # None when not run yet, or run by other code
            if rec is None:
                task = load_task(name)
                if name not in fmus:
                    fmus[name] = export(task.model, Path(tmp) / f"{name}.fmu", 2)
                rec = run_once(task, fmus[name], kind)
                write_case(path, rec)
            results.setdefault((name, kind), []).append(rec)
    load1 = os.getloadavg()
    lines = [
        "# Elastic NMPC in real time: compiled RTI of the 8-state prediction against the `sqp` NMPC",
        "",
        f"`PYTHONPATH=. python benchmarks/bench_rti_elastic.py --repeats {args.repeats}` on {platform.machine()} / Python "
        f"{platform.python_version()} ({os.cpu_count()} cores, shared; 1-min load average {load0[0]:.1f} before, "
        f"{load1[0]:.1f} after). FMU (FMI 2) plant, comm step the task's dt, 50 Hz, the 8-state elastic prediction in "
        f"both (rti: {RTI_HORIZON} intervals of 20 ms; nmpc: its default 20); medians over the rounds (controllers "
        "alternating), max over all calls. Times in ms (whole controller call).",
        "",
        "| task | controller | success | t_up [s] | call median [ms] | call max [ms] | failed steps | unsolved QPs | "
        "median / nmpc median |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name in ELASTIC:
        peer = statistics.median(r["median"] for r in results[(name, "nmpc")])
        for kind in ("rti", "nmpc"):
            rs = results[(name, kind)]
            med = statistics.median(r["median"] for r in rs)
            t_ups = [r["t_up"] for r in rs if np.isfinite(r["t_up"])]
            lines.append(
                f"| {name} | {kind} | {sum(r['success'] for r in rs)}/{len(rs)} | "
                f"{statistics.median(t_ups) if t_ups else float('nan'):.2f} | {1e3 * med:.3f} | "
                f"{1e3 * max(r['max'] for r in rs):.2f} | {sum(r['failures'] for r in rs)} | "
                f"{sum(r['unsolved'] for r in rs)} | {med / peer:.3f} |"
            )
    notes = sorted({f"- {name}, {kind}: {r['note']}" for (name, kind), rs in results.items() for r in rs if r["note"]})
    lines += ["", *notes] if notes else []
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Real-time-iteration NMPC at 500 Hz on the rigid leaderboard tasks: per-call time, success, v2 score; solver comparison.

For each task (``pendubot``, ``acrobot``: RealAIGym design C.1, 6 N.m on one joint):

1. **Closed loop** (``--repeats`` runs): the ``rti`` controller (:func:`pendulab.control.nmpc.rti.rti_for_task`:
   2 ms sample, 30 intervals of 10 ms, compiled step) through the leaderboard v2 simulator
   (:func:`pendulab.evaluate.realai.simulate.run_leaderboard`: RK4 at 2 ms, the controller called every step,
   10 s). Recorded: success and v2 score, swing-up time, and the wall time and the thread CPU time of every
   controller call (checks, reference window, warm start and step): median and max over all runs.
2. **Same problem, same inputs, same run**: at every 10th sample of the first closed-loop run, the step's
   inputs (measured state, warm start, reference window) are recorded; each solver then solves that same
   problem from that same guess, ``--repeats`` passes: the compiled RTI step, the same step uncompiled
   (CasADi MX graph), ``sqpmethod`` + ``hpipm`` with one Gauss-Newton iteration (the current ``nmpc``
   default; :func:`pendulab.control.nmpc.ocp.build_ocp` with the same horizon, interval, RK4, weights and
   torque bound) and ``fatrop`` to convergence. Times are of the solver call alone (the first torque
   read back); ratios are against the compiled RTI step. The first-torque difference against
   sqpmethod + hpipm says it is the same QP.

On a shared machine wall times carry preemption by other processes (a 2-core machine at load average
> 2 shows 5-15 ms spikes in any loop); the thread CPU time per call shows what the step itself costs.
Before each closed-loop run the garbage collector is run and its objects frozen (``gc.freeze()``), as a
real-time Python loop would do, so a full collection of the benchmark's own objects does not land in a call.

A figure (last run of each task: angles, torque, wall and CPU time per call) goes to
``docs/figures/rti_timing.png``.

Usage::

    PYTHONPATH=. python benchmarks/bench_rti.py [--repeats 3] [--tasks pendubot,acrobot]
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pendulab.control.lqr import lqr_balance
from pendulab.control.nmpc.ocp import build_ocp
from pendulab.control.nmpc.rti import RTIController, rti_for_task
from pendulab.control.realai.spec import leaderboard_task
from pendulab.evaluate.realai.simulate import run_leaderboard

OUT = Path(__file__).resolve().parent / "results" / "rti.md"
FIGURE = Path(__file__).resolve().parents[1] / "docs" / "figures" / "rti_timing.png"


class Timed:
    """Wraps the controller: records the thread CPU time of every call (its own wall time is in ``solve_times``)."""

    def __init__(self, ctrl: RTIController, record_every: int = 0) -> None:
        self.ctrl, self.cpu, self.record_every, self.records = ctrl, [], record_every, []
        self.sample_time, self.input_names = ctrl.sample_time, ctrl.input_names

    def reset(self) -> None:
        self.ctrl.reset()
        self.cpu, self.records = [], []

    def __call__(self, t, x):
        c = time.thread_time()
        u = self.ctrl(t, x)
        self.cpu.append(time.thread_time() - c)
        if self.record_every and len(self.cpu) % self.record_every == 1:
            self.records.append([a.copy() for a in self.ctrl._in])  # the inputs the step just solved
        return u


def closed_loop(task: str, repeats: int) -> tuple[dict, list]:
    ctrl, _ = rti_for_task(leaderboard_task(task))
    timed = Timed(ctrl, record_every=10)
    wall, cpu, runs, records = [], [], [], None
    for _ in tqdm(range(repeats), desc=f"{task} closed loop", leave=False):
        gc.collect()
        gc.freeze()  # as a real-time loop would: the setup's objects leave the collector's full passes
        res = run_leaderboard(task, timed, "rti")
        gc.unfreeze()
        wall += ctrl.solve_times
        cpu += timed.cpu
        st = ctrl.stats()
        runs.append((res.success, res.score, res.swingup_time, st["failures"], st["qp_unsolved"]))
        records = records or timed.records
    w, c = np.array(wall) * 1e3, np.array(cpu) * 1e3
    row = {
        "success": f"{sum(r[0] for r in runs)}/{repeats}",
        "score": float(np.median([r[1] for r in runs])),
        "t_up": float(np.median([r[2] for r in runs])),
        "failures": sum(r[3] for r in runs),
        "unsettled": sum(r[4] for r in runs),
        "wall": (np.median(w), np.percentile(w, 99), w.max()),
        "cpu": (np.median(c), np.percentile(c, 99), c.max()),
        "calls": len(w),
        "over": (int(np.sum(w > 1.0)), int(np.sum(w > 2.0)), int(np.sum(c > 1.0)), int(np.sum(c > 2.0))),
        "last": (res, np.array(ctrl.solve_times) * 1e3, np.array(timed.cpu) * 1e3),
    }
    return row, (ctrl, records)


def plot(rows: dict, path: Path) -> None:
    """Angles and torque of the last run of each task, and the wall and CPU time of every call."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(rows), figsize=(11, 6.5), sharex=True, squeeze=False, constrained_layout=True)
    for j, (task, r) in enumerate(rows.items()):
        res, wall, cpu = r["last"]
        ax = axes[0, j]
        ax.plot(res.t, res.x[:, 0], label="theta1 [rad]")
        ax.plot(res.t, res.x[:, 1], label="theta2 [rad]")
        ax.step(res.t, res.u[:, 0 if task == "pendubot" else 1], where="post", lw=0.8, label="torque [N.m]")
        ax.axhline(np.pi, color="k", lw=0.5, ls=":")
        ax.set(title=f"{task}: rti at 500 Hz, v2 simulator, score {res.score:.3f}")
        ax.set(ylabel="angle [rad], torque [N.m]")
        ax.legend(loc="lower right", fontsize=8)
        ax = axes[1, j]
        tc = np.arange(len(wall)) * 0.002
        ax.semilogy(tc, wall, ".", ms=1.5, label="wall time per call")
        ax.semilogy(tc, cpu, ".", ms=1.5, label="thread CPU time per call")
        for lim, ls in ((1.0, "--"), (2.0, "-")):
            ax.axhline(lim, color="r", lw=0.8, ls=ls, label=f"{lim:g} ms")
        ax.set(xlabel="time [s]", ylabel="per call [ms]")
        ax.legend(loc="upper right", fontsize=8, markerscale=6)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def solvers(ctrl: RTIController):
    """name -> (solve(inputs) -> first torque), every solver on the RTI's problem."""
    o, m = ctrl.options, len(ctrl.input_names)
    n = ctrl.model.nx // 2
    Q = np.diag([o.q_angle] * n + [o.q_rate] * n)
    R = np.eye(m) * (o.r if o.r is not None else 1.0 / ctrl.u_max**2)
    P = lqr_balance(ctrl.model, ctrl.input_names, Q, R, o.interval, at=ctrl.goal).P
    out = {}
    buf_in, buf_out = ctrl._in, ctrl._out

    def rti(inp):
        for a, b in zip(buf_in, inp, strict=True):
            a[:] = b
        ctrl._eval()
        return buf_out[0].copy()

    out["rti (compiled C)"] = rti
    graph = ctrl.graph

    def rti_graph(inp):
        return np.asarray(graph(*[np.asarray(a).T if a.ndim == 2 else a for a in inp])[0]).ravel()

    out["rti (CasADi graph)"] = rti_graph
    for label, solver, it in (("sqpmethod + hpipm (1 GN iter)", "sqp", 1), ("fatrop (converged)", "fatrop", 50)):
        ocp = build_ocp(
            ctrl.model, ctrl.input_names, N=o.horizon, sample_time=o.interval, substeps=o.steps_per_interval, Q=Q, R=R,
            P=P, u_max=ctrl.u_max, velocity_limit=None, slack_weight=1.0, solver=solver, max_iter=it,
        )  # fmt: skip

        def solve(inp, ocp=ocp):
            x0, X, U, XR, UR = inp
            w0 = np.zeros(ocp.n_w)
            w0[ocp.x_idx], w0[ocp.u_idx] = X, U
            lbx, ubx = ocp.lbx.copy(), ocp.ubx.copy()
            lbx[ocp.x_idx[0]] = ubx[ocp.x_idx[0]] = x0
            sol = ocp.solver(x0=w0, p=np.concatenate([XR.ravel(), UR.ravel()]), lbx=lbx, ubx=ubx, lbg=ocp.lbg, ubg=ocp.ubg)
            return np.asarray(sol["x"]).ravel()[ocp.u_idx[0, :m]]

        out[label] = solve
    return out


def compare(ctrl: RTIController, records: list, repeats: int) -> dict:
    fns = solvers(ctrl)
    times = {k: [] for k in fns}
    cpu = {k: [] for k in fns}
    first = {k: [] for k in fns}
    for rep in tqdm(range(repeats), desc="same-problem solves", leave=False):
        for inp in records:
            for name, fn in fns.items():
                t0, c0 = time.perf_counter(), time.thread_time()
                u = fn(inp)
                times[name].append(time.perf_counter() - t0)
                cpu[name].append(time.thread_time() - c0)
                if rep == 0:
                    first[name].append(u)
    ref = np.median(times["rti (compiled C)"])
    base = np.array(first["sqpmethod + hpipm (1 GN iter)"])
    return {
        k: (
            np.median(v) * 1e3, np.max(v) * 1e3, np.median(cpu[k]) * 1e3, np.median(v) / ref,
            float(np.max(np.abs(np.array(first[k]) - base))),
        )
        for k, v in times.items()
    }  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--tasks", default="pendubot,acrobot")
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    rows, comps = {}, {}
    for task in args.tasks.split(","):
        rows[task], (ctrl, records) = closed_loop(task, args.repeats)
        comps[task] = compare(ctrl, records, args.repeats)
        comps[task]["n"] = len(records)
    load1 = os.getloadavg()[0]
    plot(rows, FIGURE)
    o = ctrl.options
    lines = [
        "# Real-time-iteration NMPC at 500 Hz (rigid leaderboard tasks)",
        "",
        f"`PYTHONPATH=. python benchmarks/bench_rti.py --repeats {args.repeats}` on {platform.machine()} / Python "
        f"{platform.python_version()} ({os.cpu_count()} cores, shared; 1-min load average {load0:.1f} before and "
        f"{load1:.1f} after the runs).",
        "",
        f"Controller `rti`: sample time {o.sample_time * 1e3:g} ms, {o.horizon} intervals of {o.interval * 1e3:g} ms "
        f"({o.horizon * o.interval:g} s), RK4 {o.steps_per_interval} step(s) per interval, one Gauss-Newton SQP step per "
        f"call (condensed box QP, {o.qp_iterations} primal-dual active-set solves), compiled C (cached).",
        "",
        "## Closed loop through the leaderboard v2 simulator (RK4 at 2 ms, 10 s, controller called every step)",
        "",
        "Per call = the whole controller call from Python (checks, reference window, warm start, step). Wall time "
        "includes preemption by other processes; thread CPU time is what the call itself costs (garbage collector "
        "frozen before each run).",
        "",
        "| task | success | v2 score | t_up [s] | failures | QP not solved | calls | wall median / p99 / max [ms] "
        "| CPU median / p99 / max [ms] | calls > 1 / > 2 ms (wall; CPU) |",
        "|---|---|---:|---:|---:|---:|---:|---|---|---|",
    ]
    for task, r in rows.items():
        w, c = r["wall"], r["cpu"]
        lines.append(
            f"| {task} | {r['success']} | {r['score']:.3f} | {r['t_up']:.2f} | {r['failures']} | {r['unsettled']} | "
            f"{r['calls']} | {w[0]:.3f} / {w[1]:.2f} / {w[2]:.2f} | {c[0]:.3f} / {c[1]:.3f} / {c[2]:.3f} | "
            f"{r['over'][0]} / {r['over'][1]}; {r['over'][2]} / {r['over'][3]} |"
        )
    lines += [
        "",
        "## Same problem, same inputs, same run",
        "",
        "Every 10th sample of the first closed-loop run: the measured state, warm start and reference window of the "
        "RTI step; each solver solves that problem from that guess (solver call only). Max |du0| = largest difference "
        "of the first torque against sqpmethod + hpipm (1 iteration: the same QP; fatrop: the converged NLP).",
        "",
        "| task | solver | samples x passes | wall median [ms] | wall max [ms] | CPU median [ms] | wall median / compiled RTI "
        "| max abs du0 [N.m] |",
        "|---|---|---|---:|---:|---:|---:|---:|",
    ]
    for task, c in comps.items():
        n = c.pop("n")
        for name, (med, mx, cmed, ratio, du) in c.items():
            row = f"| {task} | {name} | {n} x {args.repeats} | {med:.3f} | {mx:.2f} | {cmed:.3f} | {ratio:.1f} | {du:.1e} |"
            lines.append(row)
    lines += ["", f"Figure: `docs/figures/{FIGURE.name}` (last run of each task: angles, torque, time per call)."]
    OUT.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines), file=sys.stderr)


if __name__ == "__main__":
    main()

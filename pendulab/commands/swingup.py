"""``pendulab swingup``: solve a swing-up task, track it in closed loop, write results."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .._io import atomic_open, atomic_write_text
from . import CLIError

__all__ = ["register"]


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "swingup",
        help="swing-up trajectory optimization + TVLQR/LQR closed loop",
        description=(
            "Solve a swing-up task with IPOPT (collocation or multiple shooting), replay it through the native "
            "integrator, stabilise it with time-varying LQR handing over to LQR balancing, and write a trajectory "
            "CSV, plots, an animated GIF and a JSON summary."
        ),
    )
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--task", help="shipped task name (see --list)")
    src.add_argument("--scene", help="scene TOML file with a [task] section")
    src.add_argument("--list", action="store_true", help="list the shipped tasks and exit")
    p.add_argument("--method", choices=("radau", "legendre", "shooting"), help="transcription (default: the task's)")
    p.add_argument("--N", type=int, help="number of control intervals (default: the task's)")
    p.add_argument("--guess", default="auto", choices=("auto", "linear", "energy", "homotopy"), help="initial guess")
    p.add_argument(
        "--tolerance",
        type=float,
        help="relative defect the plan must meet under independent re-integration (default: the task's)",
    )
    p.add_argument("--no-refine", action="store_true", help="one solve on the initial mesh; report the error estimate only")
    p.add_argument(
        "--planning",
        choices=("auto", "rigid", "quasi-static", "elastic"),
        help="planning model of an elastic task (default: the task's; see docs/swingup.md)",
    )
    p.add_argument(
        "--starts", type=int, default=0, help="also track the plan from this many randomized starts near the start (success rate)"
    )
    p.add_argument("--out", help="output directory (required unless --list)")
    p.add_argument("--no-gif", action="store_true", help="skip the animated GIF")
    p.add_argument("--fmu", action="store_true", help="also run the closed loop through an exported FMI 2 Co-Simulation FMU")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..control.swingup.episode import run_episode
    from ..control.swingup.tasks import load_task, task_names

    if args.list:
        for name in task_names():
            print(f"{name:24s} {load_task(name).description}")
        return 0
    if not args.out:
        raise CLIError("--out DIR is required")
    if args.N is not None and args.N < 2:
        raise CLIError(f"--N must be an integer >= 2, got {args.N}")
    if args.tolerance is not None and not (0.0 < args.tolerance < 1.0):
        raise CLIError(f"--tolerance must be a relative defect in (0, 1), got {args.tolerance}")
    if args.starts < 0:
        raise CLIError(f"--starts must be >= 0, got {args.starts}")
    task = load_task(args.task or args.scene)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"[swingup] solving {task.name} ({args.method or task.method}, N={args.N or task.N}) ...", file=sys.stderr)
    ep = run_episode(
        task,
        method=args.method,
        N=args.N,
        guess=args.guess,
        tolerance=args.tolerance,
        refine=not args.no_refine,
        planning=args.planning,
    )
    summary = ep.summary()
    if not ep.result.success:
        _write_summary(out, summary)
        print(f"swing-up failed: {ep.result.message}")
        _print_plan(summary)
        print(f"summary: {out / 'summary.json'}")
        return 1
    from ..viz.swingup import animate_episode, plot_episode

    print("[swingup] writing trajectory, plots and animation ...", file=sys.stderr)
    ep.closed_loop.to_csv(out / "closed_loop.csv")
    _optimal_csv(ep, out / "optimal.csv")
    figs = plot_episode(ep, out)
    if not args.no_gif:
        figs.append(animate_episode(ep, out / "swingup.gif"))
    if args.fmu:
        summary.update(_fmu_loop(ep, out))
    if args.starts:
        from ..control.swingup.episode import closed_loop_success_rate

        print(f"[swingup] tracking the plan from {args.starts} randomized starts ...", file=sys.stderr)
        rate = closed_loop_success_rate(task, args.starts, episode=ep)
        summary.update(
            {
                "closed_loop_starts": rate.starts,
                "closed_loop_successes": rate.successes,
                "closed_loop_success_rate": rate.rate,
                "closed_loop_start_spread": [rate.angle_spread, rate.rate_spread],
            }
        )
    # Last: a summary.json means every other output of the run is complete.
    _write_summary(out, summary)
    s = summary
    print(f"task {s['task']}: {'SUCCESS' if s['success'] else 'FAILED'} (end effector above {s['height_threshold_m']:.3f} m)")
    print(f"  solve: {s['ipopt_status']}, {s['iterations']} iterations, {s['solve_time_s']:.2f} s", end="")
    print(f" (+ build {s['build_time_s']:.2f} s), {s['refinements']} mesh refinements, final N = {s['N']}")
    _print_plan(s)
    print(f"  replay: max interval defect {s['replay_interval_defect']:.2e}", end="")
    print(f", open-loop deviation {s['replay_open_loop_max_deviation']:.2e}")
    print(f"  swing-up time {s['swing_up_time_s']:.3f} s, max torque {s['max_torque_Nm']:.3f} N.m", end="")
    print(f" (limit {s['torque_limit_Nm']:g}), control energy {s['control_energy_N2m2s']:.4g} N^2.m^2.s")
    if "closed_loop_starts" in s:
        print(f"  closed loop from randomized starts: {s['closed_loop_successes']}/{s['closed_loop_starts']} succeeded")
    if "fmu_success" in s:
        print(f"  FMU closed loop: {'SUCCESS' if s['fmu_success'] else 'FAILED'}", end="")
        print(f", max state deviation from the native closed loop {s['fmu_max_state_deviation']:.2e}")
        figs.append(out / "closed_loop_fmu.csv")
    for f in [out / "summary.json", out / "closed_loop.csv", out / "optimal.csv", *figs]:
        print(f"  wrote {f}")
    return 0 if s["success"] else 1


def _print_plan(s: dict) -> None:
    if "planning_model" in s and s["model"] == "elastic":
        print(f"  planning model: {s['planning_model']} (rule: {s['planning_reason']})")
        tried = ", ".join(f"{a['level']} {a['worst']:.2e}" for a in s["planning_attempts"])
        print(f"  levels tried (worst relative defect on the elastic dynamics): {tried}")
    if "error_worst" in s:
        verdict = "pass" if s["error_passed"] else "FAIL"
        print(
            f"  error estimate ({s['error_method']}): worst relative defect {s['error_worst']:.2e} "
            f"(interval {s['error_worst_interval']}, {s['error_worst_state']}), tolerance {s['error_tolerance']:.1e}: {verdict}"
        )


def _fmu_loop(ep, out: Path) -> dict:
    import numpy as np

    from ..control.swingup.check import height_success
    from ..cosim import cosim
    from ..fmu.export import export

    print("[swingup] exporting the FMU and running the closed loop through it ...", file=sys.stderr)
    task = ep.task
    fmu = export(task.model, out / f"{task.name}.fmu", 2, x0=ep.x0, stop_time=task.t_final, step_size=task.dt)
    params = dict(zip(task.model.param_names, task.model.p.tolist(), strict=True))
    traj = cosim(fmu, ep.controller, task.dt, task.t_final, params=params, x0=ep.x0, tolerance=1e-8)
    traj.to_csv(out / "closed_loop_fmu.csv")
    hc = height_success(traj, task.rest_lengths, task.success_fraction)
    dev = float(np.max(np.abs(traj.x - ep.closed_loop.x)))
    return {"fmu_success": hc.success, "fmu_swing_up_time_s": hc.t_up, "fmu_max_state_deviation": dev}


def _write_summary(out: Path, summary: dict) -> None:
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=2, default=float) + "\n")


def _optimal_csv(ep, path: Path) -> None:
    import numpy as np

    res = ep.result
    names = ep.task.model.state_names + ep.task.model.input_names
    u = np.vstack([res.u, res.u[-1:]])
    with atomic_open(path, "w") as fh:
        np.savetxt(fh, np.column_stack([res.t, res.x, u]), delimiter=",", header=",".join(("t",) + names), comments="")

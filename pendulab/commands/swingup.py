"""``pendulab swingup``: solve a swing-up task, track it in closed loop, write results."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from .._checks import bounded_int
from .._io import atomic_open, atomic_write_text
from . import CLIError
from ._common import add_plant_option, docs_page

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
    p.add_argument("--N", help="number of control intervals (default: the task's)")
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
        help=f"planning model of an elastic task (default: the task's; see {docs_page('swingup')})",
    )
    p.add_argument(
        "--starts", type=int, default=0, help="also track the plan from this many randomized starts near the start (success rate)"
    )
    add_plant_option(p, "a rigid task: the plan and the closed loop use the identified robot")
    p.add_argument("--out", help="output directory (default ./pendulab-out/swingup/TASK)")
    p.add_argument("--max-wall-time", type=float, help="wall-time budget [s] of the planning (IPOPT stops once it is spent)")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object on stdout (messages go to stderr)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-gif", action="store_true", help="skip the animated GIF")
    p.add_argument("--fmu", action="store_true", help="also run the closed loop through an exported FMI 2 Co-Simulation FMU")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``pendulab swingup``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        0 when the closed loop succeeds, 1 when the task fails.

    Raises
    ------
    CLIError
        Bad or inapplicable options.
    """
    from ..control.swingup.episode import run_episode
    from ..control.swingup.iterations import observe
    from ..control.swingup.tasks import load_task, task_names
    from ..control.swingup.transcription import INTERVALS_WHY, MAX_INTERVALS
    from ._common import ProgressBar, parse_number, plant_settings
    from .outputs import output_directory

    if args.list:
        for name in task_names():
            print(f"{name:24s} {load_task(name).description}")
        return 0
    N = None
    if args.N is not None:
        try:
            N = bounded_int("--N", args.N, low=2, high=MAX_INTERVALS, why=INTERVALS_WHY)
        except ValueError as exc:
            raise CLIError(str(exc)) from None
    if args.tolerance is not None and not (0.0 < args.tolerance < 1.0):
        raise CLIError(f"--tolerance must be a relative defect in (0, 1), got {args.tolerance}")
    budget = parse_number("--max-wall-time", None if args.max_wall_time is None else str(args.max_wall_time), positive=True)
    task = load_task(args.task or args.scene)
    robot = plant_settings(args, task.model.kind)
    if robot:  # plan (and run the closed loop) on the identified robot: its friction and rotor inside the NLP
        from ..model.model import make_model

        task = task.with_model(make_model("rigid", **robot))
    if args.planning not in (None, "auto", "rigid") and task.model.kind != "elastic":
        raise CLIError(f"--planning {args.planning} applies to elastic tasks only; task {task.name!r} is rigid")
    # With --json, stdout carries the summary alone: every message goes to stderr.
    say = (lambda *a, **k: print(*a, **k, file=sys.stderr)) if args.json else print
    out = output_directory(args.out or Path("pendulab-out") / "swingup" / (task.name + ("-identified" if robot else "")))
    out.mkdir(parents=True, exist_ok=True)
    print(f"[swingup] solving {task.name} ({args.method or task.method}, N={N or task.N}) ...", file=sys.stderr)
    bar = ProgressBar(f"[swingup] planning {task.name} (IPOPT)", not args.no_progress)

    def stage(what: str) -> None:
        bar.close()  # the planning is over: its bar's last line comes before the next stage's
        print(f"[swingup] {what} ...", file=sys.stderr)

    try:
        with observe(lambda: bar.iterate(1, "iter"), lambda d: bar.note(f"building the NLP ({d}) ...")):
            ep = run_episode(
                task,
                method=args.method,
                N=N,
                guess=args.guess,
                tolerance=args.tolerance,
                refine=not args.no_refine,
                planning=args.planning,
                max_wall_time=budget,
                stage=stage,
            )
    finally:
        bar.close()
    summary = ep.summary()
    if not ep.result.success:
        _write_summary(out, summary)
        if args.json:
            print(json.dumps(summary, default=float))
        say(f"swing-up failed: {ep.result.message}")
        _print_plan(summary, say)
        say(f"summary: {out / 'summary.json'}")
        return 1
    from ..viz.swingup import animate_episode, plot_episode

    print("[swingup] writing trajectory, plots and animation ...", file=sys.stderr)
    ep.closed_loop.to_csv(out / "closed_loop.csv")
    _optimal_csv(ep, out / "optimal.csv")
    figs = plot_episode(ep, out)
    if not args.no_gif:
        frames = ProgressBar("[swingup] writing swingup.gif", not args.no_progress, "frame")
        try:
            figs.append(animate_episode(ep, out / "swingup.gif", progress=frames))
        finally:
            frames.close()
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
    if args.json:
        print(json.dumps(summary, default=float))
    s = summary
    say(f"task {s['task']}: {'SUCCESS' if s['success'] else 'FAILED'} (end effector above {s['height_threshold_m']:.3f} m)")
    say(f"  solve: {s['ipopt_status']}, {s['iterations']} iterations, {s['solve_time_s']:.2f} s", end="")
    say(f" (+ build {s['build_time_s']:.2f} s), {s['refinements']} mesh refinements, final N = {s['N']}")
    _print_plan(s, say)
    say(f"  replay: max interval defect {s['replay_interval_defect']:.2e}", end="")
    say(f", open-loop deviation {s['replay_open_loop_max_deviation']:.2e}")
    say("    (the defect is the plan's accuracy; the open-loop replay of an unstable plant drifts away from any")
    say("    plan, so a large open-loop deviation is expected: the closed loop below is what tracks it)")
    say(f"  swing-up time {s['swing_up_time_s']:.3f} s, max torque {s['max_torque_Nm']:.3f} N.m", end="")
    say(f" (limit {s['torque_limit_Nm']:g}), control energy {s['control_energy_N2m2s']:.4g} N^2.m^2.s")
    say(f"  tracking torque: {s['tracking_torque_rms_Nm']:.3f} N.m RMS from the plan, {s['tracking_torque_note']}")
    if "closed_loop_starts" in s:
        say(f"  closed loop from randomized starts: {s['closed_loop_successes']}/{s['closed_loop_starts']} succeeded")
    if "fmu_success" in s:
        say(f"  FMU closed loop: {'SUCCESS' if s['fmu_success'] else 'FAILED'}", end="")
        say(f", max state deviation from the native closed loop {s['fmu_max_state_deviation']:.2e}")
        figs.append(out / "closed_loop_fmu.csv")
    for f in [out / "summary.json", out / "closed_loop.csv", out / "optimal.csv", *figs]:
        say(f"  wrote {f}")
    return 0 if s["success"] else 1


def _print_plan(s: dict, say: Any = print) -> None:
    if "planning_model" in s and s["model"] == "elastic":
        say(f"  planning model: {s['planning_model']} (rule: {s['planning_reason']})")
        tried = ", ".join(f"{a['level']} {a['worst']:.2e}" for a in s["planning_attempts"])
        say(f"  levels tried (worst relative defect on the elastic dynamics): {tried}")
    if "error_worst" in s:
        verdict = "pass" if s["error_passed"] else "FAIL"
        say(
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

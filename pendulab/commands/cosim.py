"""``pendulab cosim``: co-simulate a pendulab FMU under a sampled controller; ``pendulab cosim sweep``: the comm-step study."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import BudgetError, bounded_int, check_budget, relative_tolerance
from .._io import atomic_write_text
from . import CLIError
from ._common import add_plant_option, add_vocabulary_option, docs_page, plant_settings, typed_flag
from .outputs import output_directory

_DEFAULT_T_FINAL = {"lqr": 5.0, "swingup": 10.0, "tvlqr": 8.0, "nmpc": 10.0}
_CONTROLLERS = ("lqr", "swingup", "tvlqr", "nmpc")  # = pendulab.control.controllers.CONTROLLERS (not imported at parser build)


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "cosim",
        help="co-simulate an FMU under a sampled controller (or: cosim sweep)",
        description="Co-simulate a pendulab FMU (Co-Simulation, FMI 2 or 3) as the plant of a sampled-data controller. "
        "Writes cosim.csv, cosim.png, cosim.gif and summary.json to --out. `pendulab cosim sweep --help` for the "
        "communication-step study.",
    )
    p.add_argument("--fmu", type=Path, help="pendulab FMU; default: export one for --model into --out")
    add_vocabulary_option(p, "model kind", "kind", "model exported when neither --fmu nor --task is given (default rigid)")
    p.add_argument("--fmi-version", type=int, choices=(2, 3), default=2, help="FMI version of the exported FMU")
    p.add_argument("--controller", choices=_CONTROLLERS, default="lqr")
    p.add_argument(
        "--task",
        help="shipped swing-up task (e.g. pendubot; swingup_pendubot is an alias): the FMU gets the task's model, the "
        "controller its actuation and torque limit; start, t_final and comm step from the task; summary.json gets the "
        "success flag",
    )
    p.add_argument("--nmpc-solver", choices=("sqp", "ipopt", "fatrop"), default="sqp", help="NLP solver of nmpc (default sqp)")
    p.add_argument("--comm-step", type=float, help="communication step [s] (default 0.01, or the task's dt)")
    p.add_argument(
        "--sample-time", type=float, help="controller sample time [s], a multiple of --comm-step (default: equal; nmpc 0.02)"
    )
    p.add_argument("--t-final", type=float, help="horizon [s] (default: lqr 5, swingup 10, tvlqr 8, nmpc 10, or the task's)")
    p.add_argument(
        "--reference",
        type=Path,
        help="tvlqr: CSV with columns t, states, tau1, tau2 to track (e.g. optimal.csv of `pendulab swingup`); "
        "default: the native energy swing-up",
    )
    p.add_argument(
        "--actuation",
        choices=("full", "pendubot", "acrobot"),
        default=None,
        help="driven torques (default full; not with --task)",
    )
    add_vocabulary_option(p, "parameters", "param", "FMU parameters (also used for the controller design)", default=[])
    add_vocabulary_option(p, "initial state", "init", "initial state entries, e.g. theta1=3.0", default=[])
    add_plant_option(
        p,
        "rigid: the FMU gets the identified robot's parameters; with --task the controller keeps the task's model, "
        "without it --set overrides and the controller is designed on the identified robot",
    )
    p.add_argument(
        "--estimator",
        choices=("ekf", "mmae"),
        default=None,
        help=f"feed the controller a state estimate of the measurement ({docs_page('estimation')})",
    )
    p.add_argument(
        "--measurement-noise",
        default=None,
        metavar="SIGMA",
        help="std [rad/s] of Gaussian noise on omega1, omega2 seen by the controller",
    )
    p.add_argument("--measurement-delay", default=None, metavar="N", help="measurement delay [controller samples]")
    p.add_argument("--measurement-seed", default=None, metavar="S", help="seed of the measurement noise (default 0)")
    p.add_argument("--solver", choices=("dopri5", "rodas4"), help="embedded solver (default: the FMU's)")
    p.add_argument("--tolerance", type=float, help="embedded solver relative tolerance in (0, 1) (default: the FMU's)")
    p.add_argument("--u-max", type=float, default=None, help="torque limit [N.m] (default 20; not with --task)")
    p.add_argument("--out", type=Path, default=Path("pendulab-out/cosim"), help="output directory (default ./pendulab-out/cosim)")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object on stdout (messages go to stderr)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--no-gif", action="store_true", help="skip the animation")
    p.add_argument(
        "--gif-fps", type=int, default=20, help="animation frames per simulated second (default 20, at most 160 frames)"
    )
    p.set_defaults(func=run)
    sub = p.add_subparsers(dest="cosim_action", metavar="ACTION")
    s = sub.add_parser(
        "sweep",
        help="communication-step study of LQR balance (rigid + elastic)",
        description="Fixed continuous LQR balance gain applied with a zero-order hold at growing communication "
        "steps: predicted (spectral radius of the discretized linear closed loop) vs measured through the FMU. "
        "Writes sweep.png, sweep.md, sweep.csv, sweep.json to --out.",
    )
    s.add_argument("--kinds", default="rigid,elastic", help="comma-separated plant kinds (default rigid,elastic)")
    s.add_argument("--fmu-rigid", type=Path, help="rigid FMU (default: export one into --out)")
    s.add_argument("--fmu-elastic", type=Path, help="elastic FMU (default: export one into --out)")
    s.add_argument("--fmi-version", type=int, choices=(2, 3), default=2)
    s.add_argument("--steps", default="0.01:0.25:0.01", help="START:STOP:STEP or comma list of comm steps [s]")
    s.add_argument("--solver", choices=("dopri5", "rodas4"), default="dopri5")
    s.add_argument("--tolerance", type=float, default=1e-10)
    s.add_argument("--native", action="store_true", help="run the native sampled loop instead of the FMU")
    s.add_argument("--out", type=Path, default=Path("pendulab-out/cosim-sweep"), help="output directory")
    s.add_argument(
        "--json", action="store_true", help="print the critical steps as one JSON object on stdout (messages go to stderr)"
    )
    s.set_defaults(func=run_sweep)


def _progress(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _fmu_for(kind: str, fmu: Path | None, version: int, out: Path, model: Any = None, label: str = "") -> Path:
    if fmu is not None:
        return fmu
    from .. import make_model
    from ..fmu.export import export

    path = out / f"{label or kind}_fmi{version}.fmu"
    _progress(f"exporting the {label or kind} model to {path}")
    return export(make_model(kind) if model is None else model, path, version)


def _named_values(items: list[str], names: tuple[str, ...], flag: str) -> dict[str, float]:
    values = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or name not in names:
            raise CLIError(f"{flag}: expected NAME=VALUE with NAME in {list(names)}, got {item!r}")
        try:
            values[name] = float(value)
        except ValueError:
            raise CLIError(f"{flag}: value of {name} must be a number, got {value!r}") from None
    return values


def _init_state(x0: np.ndarray, names: tuple[str, ...], items: list[str]) -> np.ndarray:
    x = x0.copy()
    for name, value in _named_values(items, names, "--init").items():
        x[names.index(name)] = value
    return x


def _load_task(name: str) -> Any:
    from ..control.swingup.tasks import load_task

    try:
        return load_task(name)
    except (FileNotFoundError, ValueError) as exc:
        raise CLIError(f"--task: {exc}") from None


class _Counted:
    """A sampled controller that reports each call to a progress bar and keeps the state it was given."""

    def __init__(self, ctrl: Any, bar: Any) -> None:
        self.ctrl, self.bar = ctrl, bar
        self.sample_time, self.input_names = ctrl.sample_time, ctrl.input_names
        self.u_max = getattr(ctrl, "u_max", None)
        self.seen: list[tuple[float, np.ndarray]] = []

    def reset(self) -> None:
        self.ctrl.reset()
        self.seen = []

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        self.seen.append((t, np.array(x, dtype=float)))
        u = self.ctrl(t, x)
        self.bar.iterate(1, "sample")
        return u


def _measurement(args: argparse.Namespace) -> Any:
    """The measurement model of --measurement-noise/-delay/-seed (None without noise and delay)."""
    from ..evaluate.measurement import MeasurementModel

    noise, delay, seed = args.measurement_noise, args.measurement_delay, args.measurement_seed
    if seed is not None and noise is None:
        raise CLIError("--measurement-seed applies with --measurement-noise only")
    if noise is None and delay is None:
        return None
    try:
        sigma = 0.0 if noise is None else float(noise)
    except ValueError:
        raise CLIError(f"--measurement-noise must be a standard deviation >= 0 [rad/s], got {noise!r}") from None
    try:
        seed = bounded_int("--measurement-seed", 0 if seed is None else seed, low=0, high=2**63 - 1, why="a numpy seed")
        return MeasurementModel(sigma, 0 if delay is None else delay, seed=seed)
    except ValueError as exc:
        flag = "--measurement-delay" if str(exc).startswith("delay") else "--measurement-noise"
        raise CLIError(f"{flag}: {exc}" if not str(exc).startswith("--") else str(exc)) from None


def _seen_summary(ctrl: _Counted, traj: Any) -> dict[str, Any]:
    """RMS error [rad/s] of the link rates the controller was given (measurement or estimate) against the plant's."""
    if not ctrl.seen:
        return {}
    h = float(traj.t[1] - traj.t[0])
    nq = traj.x.shape[1] // 2
    err = np.array([x[nq : nq + 2] - traj.x[round(t / h)][nq : nq + 2] for t, x in ctrl.seen])
    return {"controller_rate_rms_error": float(np.sqrt(np.mean(err**2)))}


def run(args: argparse.Namespace) -> int:
    """Run ``pendulab cosim``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        0 on success.

    Raises
    ------
    CLIError
        Bad or inapplicable options.
    """
    from ..control.controllers import controller_for_task, make_controller
    from ..control.swingup.iterations import observe
    from ..control.tracking import load_reference_csv
    from ..cosim import cosim, inspect_fmu
    from ..cosim.master import MAX_COMM_STEPS
    from ..cosim.plots import animate_cosim, plot_cosim
    from ._common import ProgressBar

    # With --json, stdout carries the summary alone: every message goes to stderr.
    say = (lambda msg: print(msg, file=sys.stderr)) if args.json else print
    out: Path = output_directory(args.out)
    for flag, value in (("--comm-step", args.comm_step), ("--sample-time", args.sample_time), ("--t-final", args.t_final)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise CLIError(f"{flag} must be a positive number [s], got {value!r}")
    if args.gif_fps < 1:
        raise CLIError(f"--gif-fps must be a positive integer, got {args.gif_fps!r}")
    if args.tolerance is not None:
        try:
            relative_tolerance("--tolerance", args.tolerance)
        except ValueError as exc:
            raise CLIError(str(exc)) from None
    measurement = _measurement(args)
    task = _load_task(args.task) if args.task is not None else None
    if task is not None:
        options = (
            ("--reference", args.reference), (typed_flag(args, "parameters"), args.param), ("--u-max", args.u_max),
            ("--actuation", args.actuation), (typed_flag(args, "model kind"), args.kind),
        )  # fmt: skip
        given = [flag for flag, value in options if value not in (None, [])]
        if given:
            raise CLIError(
                f"--task sets the model, actuation, torque limit and plan; {', '.join(given)} cannot be combined with it"
            )
    elif args.fmu is not None and args.kind is not None:
        raise CLIError(
            f"{typed_flag(args, 'model kind')} chooses the model to export; it does not apply with --fmu (the FMU says its kind)"
        )
    kind = args.kind or "rigid"
    robot = plant_settings(args, task.model.kind if task is not None else kind)
    actuation = args.actuation or "full"
    u_max = 20.0 if args.u_max is None else args.u_max
    if not (math.isfinite(u_max) and u_max > 0):
        raise CLIError(f"--u-max must be a positive torque [N.m], got {u_max!r}")
    comm_step = args.comm_step if args.comm_step is not None else (task.dt if task is not None else 0.01)
    default_ts = 0.02 if args.controller == "nmpc" else comm_step
    sample_time = args.sample_time if args.sample_time is not None else default_ts
    t_final = args.t_final if args.t_final is not None else (task.t_final if task else _DEFAULT_T_FINAL[args.controller])
    n_steps = max(1, round(t_final / comm_step))
    if n_steps > MAX_COMM_STEPS:
        raise CLIError(
            f"--t-final {t_final:g} s at comm step {comm_step:g} s is {n_steps} communication steps; at most {MAX_COMM_STEPS} "
            "(each step is a row of the result and a controller call)"
        )
    t_final = n_steps * comm_step  # a whole number of steps
    plant_model = None
    if robot:
        from .. import make_model

        plant_model = make_model("rigid", **robot)
    if task is None:
        fmu = _fmu_for(kind, args.fmu, args.fmi_version, out, plant_model, "identified" if robot else "")
    else:
        sim = task.model if plant_model is None else plant_model
        fmu = _fmu_for(sim.kind, args.fmu, args.fmi_version, out, sim, task.name + ("-identified" if robot else ""))
    info = inspect_fmu(fmu)
    missing = sorted(set(robot) - set(info.parameter_names))
    if missing:
        raise CLIError(f"--plant: the FMU {fmu} has no parameters {missing} (exported before pendulab modelled a drivetrain)")
    if task is not None:
        # The simulated robot's parameters also go to the FMU explicitly (a user --fmu may carry other start values).
        sim = task.model if plant_model is None else plant_model
        params = {n: float(getattr(sim.params, n)) for n in info.parameter_names if n in sim.param_names}
    else:
        params = {**robot, **_named_values(args.param, info.parameter_names, typed_flag(args, "parameters"))}
    model = info.model(params)
    reference = None
    if args.reference is not None:
        if args.controller not in ("tvlqr", "nmpc"):
            raise CLIError(f"--reference is for --controller tvlqr or nmpc, got --controller {args.controller}")
        reference = load_reference_csv(str(args.reference), model)
    if args.controller in ("tvlqr", "nmpc"):
        _progress(f"planning the {args.controller} reference" + ("" if args.reference or task else " (native model)"))
    planning = ProgressBar(f"planning {args.controller} (IPOPT)", not args.no_progress)
    try:
        with observe(lambda: planning.iterate(1, "iter"), lambda d: planning.note(f"building the NLP ({d}) ...")):
            if task is not None:
                ctrl, x0 = controller_for_task(args.controller, task, sample_time=sample_time, nmpc_solver=args.nmpc_solver)
            else:
                ctrl, x0 = make_controller(
                    args.controller, model, sample_time, u_max=u_max, reference=reference, actuation=actuation,
                    nmpc_solver=args.nmpc_solver,
                )  # fmt: skip
    except ValueError as exc:
        raise CLIError(f"--controller {args.controller}: {exc}") from None
    finally:
        planning.close()
    x0 = _init_state(x0, info.state_names, args.init)
    _progress(f"co-simulating {fmu.name} ({info.kind}, FMI {info.fmi_version}) under {args.controller} for {t_final:g} s")
    # A progress bar of the controller samples where a run takes seconds (NMPC solves per sample).
    bar = ProgressBar(f"co-simulating ({args.controller})", not args.no_progress and args.controller == "nmpc")
    counted = _Counted(ctrl, bar)
    try:
        traj = cosim(fmu, counted, comm_step, t_final, x0=x0, params=params, solver=args.solver,
                     tolerance=args.tolerance, estimator=args.estimator, measurement=measurement)  # fmt: skip
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    finally:
        bar.close()
    out.mkdir(parents=True, exist_ok=True)
    traj.to_csv(out / "cosim.csv")
    summary = {
        "fmu": str(fmu),
        "kind": info.kind,
        "fmi_version": info.fmi_version,
        "controller": args.controller,
        "actuation": task.problem.actuation if task is not None else actuation,
        "torque_limit": task.problem.torque_limit if task is not None else u_max,
        "params": params,
        "plant": args.plant,
        "comm_step": comm_step,
        "sample_time": sample_time,
        "t_final": float(traj.t[-1]),
        "x0": dict(zip(info.state_names, x0.tolist(), strict=True)),
        "x_final": dict(zip(info.state_names, traj.x[-1].tolist(), strict=True)),
        "max_abs_torque": float(np.abs(traj.u).max()),
        "caught_at": getattr(ctrl, "caught_at", None),
        "stats": {k: float(v) for k, v in traj.stats.items()},
        "estimator": args.estimator,
        "measurement": None
        if measurement is None
        else {"velocity_noise": measurement.velocity_noise, "delay_samples": measurement.delay, "seed": measurement.seed},
    }
    summary.update(_seen_summary(counted, traj))
    summary.update(_controller_summary(ctrl))
    if task is not None:
        summary.update(_task_summary(task, traj))
    _progress("writing figures")
    plot_cosim(traj, out / "cosim.png", _title(info.kind, args.controller, comm_step, summary),
               torque_limit=summary["torque_limit"], solve_times=getattr(ctrl, "solve_times", None),
               sample_time=sample_time)  # fmt: skip
    if not args.no_gif:
        animate_cosim(traj, out / "cosim.gif", fps=args.gif_fps, title=f"{args.controller}: ")
    # Atomic, and last: a summary.json means every other output of the run is complete.
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=2))
    if args.json:
        print(json.dumps(summary, indent=2))
    say(f"wrote {out / 'cosim.csv'}, cosim.png{'' if args.no_gif else ', cosim.gif'}, summary.json")
    wall, inside = traj.stats["wall_time"] * 1e3, traj.stats["time_in_do_step"] * 1e3
    say(f"{traj.message}; wall {wall:.1f} ms, of which doStep {inside:.1f} ms")
    if "solve_time_median" in summary:
        med, mx = summary["solve_time_median"] * 1e3, summary["solve_time_max"] * 1e3
        say(f"controller solve time median {med:.2f} ms, max {mx:.2f} ms, failures {summary['failures']}")
    if measurement is not None or args.estimator is not None:
        seen = "estimate" if args.estimator else "measurement"
        say(f"controller saw the {seen}: link-rate RMS error {summary['controller_rate_rms_error']:.4g} rad/s")
    if task is not None:
        say(f"task {task.name}: {'success' if summary['success'] else 'FAILED'} (t_up {summary['t_up']})")
    return 0


def _title(kind: str, controller: str, comm_step: float, summary: dict[str, Any]) -> str:
    """Figure title: plant, controller, comm step; task and outcome when a task was run."""
    title = f"{kind} FMU, {controller}, comm step {comm_step:g} s"
    if "task" in summary:
        t_up = summary["t_up"]
        outcome = f"success (up at {t_up:.2f} s)" if summary["success"] else "FAILED"
        title = f"task {summary['task']}: {outcome}\n" + title
    return title


def _controller_summary(ctrl: Any) -> dict[str, Any]:
    """Solve-time statistics of controllers that keep them (NMPC); nothing for the others."""
    if not callable(getattr(ctrl, "stats", None)):
        return {}
    st = ctrl.stats()
    return {
        "solve_time_median": st["solve_time_median"],
        "solve_time_max": st["solve_time_max"],
        "iterations": {"median": st["iterations_median"], "max": st["iterations_max"]},
        "failures": st["failures"],
        "controller_stats": st,
    }


def _task_summary(task: Any, traj: Any) -> dict[str, Any]:
    """RealAIGym criterion: the end effector above ``fraction (L1 + L2)`` over the whole last second."""
    from ..control.swingup.check import height_success

    check = height_success(traj, task.rest_lengths, task.success_fraction)
    success = bool(check.success and check.t_up <= traj.t[-1] - 1.0 + 1e-9)
    return {
        "task": task.name,
        "success": success,
        "t_up": None if math.isnan(check.t_up) else check.t_up,
        "height_threshold": check.threshold,
    }


def _steps(text: str) -> list[float]:
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if step <= 0 or stop < start:
                raise ValueError
            check_budget("sweep_points", "--steps", text, (stop - start) / step + 1.0)  # before np.arange allocates
            return [round(v, 12) for v in np.arange(start, stop + 0.5 * step, step)]
        return [float(v) for v in text.split(",") if v.strip()]
    except BudgetError:
        raise
    except ValueError:
        raise CLIError(f"--steps: expected START:STOP:STEP or a comma list of positive steps [s], got {text!r}") from None


def run_sweep(args: argparse.Namespace) -> int:
    from ..cosim import inspect_fmu
    from ..cosim.sweep import comm_step_sweep, fmu_runner, native_runner, plot_sweep

    steps = _steps(args.steps)
    if not steps or min(steps) <= 0:
        raise CLIError(f"--steps must be positive communication steps [s], got {args.steps!r}")
    kinds = [k.strip() for k in args.kinds.split(",") if k.strip()]
    if not kinds or any(k not in ("rigid", "elastic") for k in kinds):
        raise CLIError(f"--kinds must list rigid and/or elastic, got {args.kinds!r}")
    out: Path = output_directory(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    for kind in kinds:
        if args.native:
            from .. import make_model

            model, run, label = make_model(kind), None, "native loop"
            run = native_runner(model)
        else:
            fmu = _fmu_for(kind, getattr(args, f"fmu_{kind}"), args.fmi_version, out)
            model = inspect_fmu(fmu).model()
            run = fmu_runner(fmu, tolerance=args.tolerance, solver=args.solver)
            label = f"FMU, {args.solver}"
        results.append(comm_step_sweep(model, steps, run, runner_name=label, progress=_progress))
    plot_sweep(results, out / "sweep.png")
    lines = ["# Communication-step sweep: fixed continuous LQR gain under ZOH", ""]
    rows = [("kind", "h", "rho_pred", "rho_meas", "stable_small", "stable_large", "err_small", "err_large")]
    for res in results:
        lines += [
            f"## {res.kind} ({res.runner})",
            "",
            f"- predicted critical step (spectral radius = 1): {res.h_crit_pred * 1e3:.2f} ms",
            f"- measured (contraction of a {res.small:g} rad perturbation crosses 1): {res.h_crit_meas * 1e3:.2f} ms",
            f"- lost from a {res.large:g} rad perturbation from: {res.h_crit_large * 1e3:.2f} ms",
            "",
            res.table(),
            "",
        ]
        rows += [
            (res.kind, p.h, p.rho_pred, p.rho_meas, p.stable_small, p.stable_large, p.err_small, p.err_large) for p in res.points
        ]
        print(
            f"{res.kind}: critical comm step predicted {res.h_crit_pred * 1e3:.2f} ms, measured {res.h_crit_meas * 1e3:.2f} ms, "
            f"large perturbation lost from {res.h_crit_large * 1e3:.2f} ms",
            file=sys.stderr if args.json else sys.stdout,
        )
    # Atomic writes; the summaries (sweep.json, then the sweep.md table) last.
    atomic_write_text(out / "sweep.csv", "\n".join(",".join(str(v) for v in row) for row in rows) + "\n")
    critical = [
        {"kind": r.kind, "h_crit_pred": r.h_crit_pred, "h_crit_meas": r.h_crit_meas, "h_crit_large": r.h_crit_large}
        for r in results
    ]
    atomic_write_text(out / "sweep.json", json.dumps(critical, indent=2))
    atomic_write_text(out / "sweep.md", "\n".join(lines))
    print(f"wrote {out / 'sweep.png'}, sweep.md, sweep.csv, sweep.json", file=sys.stderr if args.json else sys.stdout)
    if args.json:
        print(json.dumps({"out": str(out), "critical_steps": critical}))
    return 0

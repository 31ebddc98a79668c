"""``pendulab score``: robustness scorecard of a controller on a swing-up task, the RealAIGym score, the leaderboard."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from .._checks import bounded_int
from .._io import atomic_write_text
from . import CLIError
from ._common import ProgressBar, add_plant_option, docs_page, parse_number, read_plant
from .outputs import check_journal, output_directory

__all__ = ["register", "run_score"]


def register(subparsers: Any) -> None:
    """Add the ``score`` command.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        The dispatcher's sub-parsers.
    """
    p = subparsers.add_parser(
        "score",
        help="robustness scorecard of a controller on a swing-up task (or --realai, --leaderboard)",
        description=(
            "Robustness scorecard: the controller runs the task under swept perturbations (model parameters, "
            f"measurement and torque noise, torque response, delay, pushes; {docs_page('scorecard')}) and succeeds when "
            "the end effector stays above 0.9 (L1 + L2) over the last second within the torque limit. Writes "
            "DIR/records.json after every batch of runs (--resume continues from it), then DIR/scorecard.md, "
            "DIR/scorecard.png and DIR/scorecard.json. --realai scores the controller on RealAIGym's simulation "
            "leaderboard instead; --leaderboard writes the leaderboard of every controller on every task "
            f"(published at {docs_page('leaderboard')}). --protocol robustness-v2 | v3 runs RealAIGym's "
            f"robustness-v2 or v3 protocol ({docs_page('realai')}, {docs_page('realai_v3')})."
        ),
    )
    p.add_argument(
        "--controller",
        default=None,
        metavar="NAME",
        help=f"scorecard: {' | '.join(_SCORECARD_CONTROLLERS)}; --realai and --protocol: {' | '.join(_REALAI_CONTROLLERS)}",
    )
    p.add_argument(
        "--task", default=None, metavar="TASK", help="swing-up task name (pendulab swingup --list); --realai: pendubot | acrobot"
    )
    p.add_argument("--runs", default=None, metavar="N", help="runs per level of the stochastic categories (default 20)")
    p.add_argument(
        "--estimator",
        default=None,
        metavar="NAME",
        help=f"scorecard: feed the controller a state estimate of the measurement: ekf | mmae ({docs_page('estimation')})",
    )
    p.add_argument("--categories", default=None, metavar="A,B", help="comma-separated categories (default: all that apply)")
    p.add_argument("--seed", default=None, metavar="S", help="base seed (default 0)")
    p.add_argument("--workers", default=None, metavar="N", help="worker processes (default: all cores)")
    p.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="output directory (default ./pendulab-out/score/CONTROLLER-TASK, "
        "--realai: ./pendulab-out/score/realai-CONTROLLER-TASK); "
        "--leaderboard: the markdown file (default ./pendulab-out/leaderboard/leaderboard.md; "
        f"in a source checkout, --out over the Markdown source of {docs_page('leaderboard')} regenerates that page)",
    )
    p.add_argument(
        "--resume", action="store_true", help="continue an interrupted scorecard from DIR/records.json (same settings)"
    )
    p.add_argument("--max-wall-time", default=None, metavar="S", help="wall-time budget [s] of the scorecard's runs")
    p.add_argument("--json", action="store_true", help="print the result as JSON on stdout")
    p.add_argument(
        "--protocol",
        default=None,
        choices=PROTOCOLS,
        help="a RealAIGym protocol on --task pendubot | acrobot: v2 (the simulation leaderboard, = --realai), "
        "robustness-v2 (the robustness leaderboard v2: 722 runs, journaled, --resume, --workers, --seed, --quick), "
        "v3 (the ICRA 2025 global protocol), v3-hardware (its hardware final: 10 PID resets of 1 s on the identified "
        f"C.1 robot with measured sensing and loop timing, {docs_page('realai_v3')}); with --leaderboard: that "
        "protocol's cases and tables only (no own scorecards); --out over a page with other sections replaces that "
        "protocol's section and keeps the rest",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="--protocol robustness-v2 on a reduced grid (levels 0, 10, 20 of each category, 2 velocity-noise "
        "repetitions, 5 perturbation runs; 77 runs); --leaderboard: robustness v2 on 13 runs, v3 one 10 s episode, "
        "no own scorecards: a smoke test, not a score to publish",
    )
    p.add_argument(
        "--controllers",
        default=None,
        metavar="A,B",
        help="--leaderboard: RealAIGym controllers for every protocol (default: v2 best,tvlqr,robust,rti,global,replan; "
        "robustness-v2 best,tvlqr,robust; v3 and v3-hardware best,global,replan,library,mpc)",
    )
    p.add_argument(
        "--passive-allowance",
        default=None,
        metavar="N.M",
        help="--protocol v3-hardware and --leaderboard's v3-hardware cases: torque the controller may put on the "
        "passive joint [N.m] (the hardware rules "
        "grant 0.5 to compensate motor friction; default 0); pendulab's controllers use it to compensate the "
        "identified friction",
    )
    add_plant_option(p, "the scorecard of a rigid task, --realai and every --protocol; the controller keeps its design model")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--realai", action="store_true", help="RealAIGym simulation leaderboard score (pendubot | acrobot)")
    mode.add_argument("--leaderboard", action="store_true", help="regenerate the leaderboard (all controllers x tasks)")
    p.set_defaults(func=run_score)


#: Controller names, written here so that ``--help`` does not import the controllers (tests/test_cli_plant.py
#: checks them against ``TASK_CONTROLLERS`` and the RealAIGym ``CONTROLLERS``).
_SCORECARD_CONTROLLERS: tuple[str, ...] = ("lqr", "tvlqr", "swingup", "nmpc", "robust")
_REALAI_CONTROLLERS: tuple[str, ...] = (
    "best", "tvlqr", "lqr", "swingup", "nmpc", "rti", "mpc", "mpc_library", "robust", "global", "replan",
    "replan_delayed", "library",
)  # fmt: skip

#: RealAIGym protocols of ``--protocol`` (``v2`` is ``--realai``).
PROTOCOLS: tuple[str, ...] = ("v2", "robustness-v2", "v3", "v3-hardware")

#: Options of the scorecard that the other modes do not take (an error there, not ignored).
_SCORECARD_ONLY = (
    ("estimator", "--estimator"),
    ("categories", "--categories"),
    ("seed", "--seed"),
    ("resume", "--resume"),
    ("max_wall_time", "--max-wall-time"),
)


def _reject(args: argparse.Namespace, mode: str, names: tuple[tuple[str, str], ...]) -> None:
    given = [flag for attr, flag in names if getattr(args, attr) not in (None, False)]
    if given:
        raise CLIError(f"{', '.join(given)} {'does' if len(given) == 1 else 'do'} not apply to {mode}")


def _int(option: str, text: str | None, lo: int, hi: int, why: str, default: int | None = None) -> int | None:
    if text is None:
        return default
    try:
        return bounded_int(option, text, low=lo, high=hi, why=why)
    except ValueError as exc:
        raise CLIError(str(exc)) from None


def run_score(args: argparse.Namespace) -> int:
    """Run ``pendulab score``.

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
        Missing, bad or inapplicable options, unknown task, controller or category.
    """
    from ..evaluate.scorecard import MAX_RUNS

    if args.protocol not in (None, "v2") and args.realai:
        raise CLIError(f"--realai is --protocol v2; it does not combine with --protocol {args.protocol}")
    if args.quick and args.protocol != "robustness-v2" and not args.leaderboard:
        raise CLIError("--quick applies to --protocol robustness-v2 and --leaderboard only")
    if args.passive_allowance is not None and (args.protocol or ("v3-hardware" if args.leaderboard else None)) != "v3-hardware":
        raise CLIError("--passive-allowance applies to --protocol v3-hardware and to --leaderboard (its v3-hardware cases)")
    if args.controllers is not None and not args.leaderboard:
        raise CLIError("--controllers applies to --leaderboard only (use --controller NAME otherwise)")
    if args.plant is not None and args.leaderboard:
        raise CLIError("--plant does not apply to --leaderboard (it scores the nominal and the shipped identified C.1 plant)")
    plant = read_plant(args)
    from ..evaluate.realai.plant import plant_label

    if args.protocol in ("robustness-v2", "v3", "v3-hardware") and not args.leaderboard:
        if args.controller is None or args.task is None:
            raise CLIError(f"--protocol {args.protocol} needs --controller and --task")
        return _run_protocol(args, plant)
    workers = _int("--workers", args.workers, 1, 1024, "worker processes")
    runs = _int("--runs", args.runs, 1, MAX_RUNS, "runs per level of each stochastic category", 20)
    if args.leaderboard:
        return _run_leaderboard(args, runs, workers)
    if args.controller is None or args.task is None:
        raise CLIError("--controller and --task are required (or --leaderboard)")
    if args.realai or args.protocol == "v2":
        _reject(
            args, "--realai (one deterministic leaderboard run)", (*_SCORECARD_ONLY, ("workers", "--workers"), ("runs", "--runs"))
        )
        return _run_realai(args, plant)
    from ..control.controllers import TASK_CONTROLLERS
    from ..control.swingup.iterations import observe
    from ..control.swingup.tasks import load_task, task_names
    from ..evaluate import CATEGORIES, score

    if args.controller not in TASK_CONTROLLERS:
        raise CLIError(f"--controller {args.controller!r}: expected one of {list(TASK_CONTROLLERS)}")
    from ..control.robust import ESTIMATORS

    if args.estimator is not None and args.estimator not in ESTIMATORS:
        raise CLIError(f"--estimator {args.estimator!r}: expected one of {list(ESTIMATORS)}")
    try:
        task = load_task(args.task)
    except FileNotFoundError:
        raise CLIError(f"--task {args.task!r}: unknown task; shipped tasks: {list(task_names())}") from None
    cats = None
    if args.categories:
        cats = [c.strip() for c in args.categories.split(",") if c.strip()]
        bad = [c for c in cats if c not in CATEGORIES]
        if bad:
            raise CLIError(f"--categories: unknown {bad}; expected some of {list(CATEGORIES)}")
    seed = _int("--seed", args.seed, 0, 2**63 - 1, "a seed of numpy's SeedSequence", 0)
    budget = parse_number("--max-wall-time", args.max_wall_time, positive=True)
    fed = f"+{args.estimator}" if args.estimator else ""
    out = output_directory(
        args.out or Path("pendulab-out") / "score" / f"{args.controller}{fed}-{task.name}{_plant_suffix(plant)}"
    )
    # estimator None matches records files written before the option (data.get("estimator") is None).
    settings = {"controller": args.controller, "task": task.name, "runs": runs, "seed": seed, "categories": cats,
                "estimator": args.estimator, "plant": plant_label(plant)}  # fmt: skip
    check_journal(out / _RECORDS)
    # Validated before the controller is built: only runs that pass their hashes are reused.
    journal, completed = _resume(out / _RECORDS, settings, args.resume)

    def save(records: tuple, complete: bool = False) -> None:
        from ..evaluate.scorecard_journal import save_records

        out.mkdir(parents=True, exist_ok=True)  # only once there is something to keep (bad input writes nothing)
        save_records(journal, records, complete=complete)

    planning = ProgressBar(f"planning {args.controller} on {task.name} (IPOPT)", not args.no_progress)
    bar = ProgressBar(f"score {args.controller} on {task.name}", not args.no_progress)

    def progress(done: int, total: int) -> None:
        planning.close()
        bar(done, total)

    try:
        with observe(lambda: planning.iterate(1, "iter"), lambda d: planning.note(f"building the NLP ({d}) ...")):
            card = score(
                args.controller, task, runs=runs, categories=cats, seed=seed, workers=workers, progress=progress,
                completed=completed, on_records=save, max_wall_time=budget, estimator=args.estimator, plant=plant,
            )  # fmt: skip
    finally:
        planning.close()
        bar.close()
    save(card.records, complete=True)
    from ..viz.scorecard import plot_scorecard

    atomic_write_text(out / "scorecard.md", card.table() + "\n")
    plot_scorecard(card, out / "scorecard.png")
    # Last: a scorecard.json means every other output of the run is complete.
    atomic_write_text(out / "scorecard.json", card.to_json() + "\n")
    print(f"wrote {out / 'scorecard.json'}, scorecard.md, scorecard.png, {_RECORDS}", file=sys.stderr)
    if args.json:
        print(card.to_json())
    else:
        print(card.table())
        resumed = f", {len(completed)} resumed" if completed else ""
        print(f"\n{len(card.records)} runs{resumed}, {len(card.failures)} failed, {card.wall_time:.1f} s")
    return 0


def _run_leaderboard(args: argparse.Namespace, runs: int | None, workers: int | None) -> int:
    """``--leaderboard``: the three RealAIGym protocols and the own scorecards (pendulab.commands.leaderboard)."""
    _reject(
        args, "--leaderboard (it scores every controller on every task)", (("categories", "--categories"), ("seed", "--seed"))
    )
    if args.controller is not None or args.task is not None:
        raise CLIError("--controller and --task do not apply to --leaderboard (use --controllers A,B)")
    if args.json:
        raise CLIError("--json does not apply to --leaderboard (it writes a markdown page)")
    from ..evaluate.realai.leaderboard import check_controllers
    from .leaderboard import print_summary, write_leaderboard

    names = None
    if args.controllers is not None:
        names = [c.strip() for c in args.controllers.split(",") if c.strip()]
        try:
            check_controllers(names)
        except ValueError as exc:
            raise CLIError(f"--controllers {args.controllers!r}: {exc}") from None
    budget = parse_number("--max-wall-time", args.max_wall_time, positive=True)
    try:
        path = write_leaderboard(
            args.out, runs=runs or 20, workers=workers, progress=not args.no_progress, controllers=names,
            quick=args.quick, resume=args.resume, max_wall_time=budget,
            protocols=None if args.protocol is None else (args.protocol,), passive_allowance=args.passive_allowance or 0.0,
        )  # fmt: skip
    except KeyboardInterrupt:
        again = "pendulab score --leaderboard --resume" + (" --quick" if args.quick else "")
        print(f"interrupted: finished cases are journaled under ./pendulab-out/leaderboard/; continue with `{again}`",
              file=sys.stderr)  # fmt: skip
        raise
    except ValueError as exc:
        if "journal" in str(exc):
            raise CLIError(f"--resume: {exc}") from None
        raise
    print_summary(path)
    return 0


#: Every finished run of a scorecard, rewritten atomically after each batch (``--resume`` reads it).
_RECORDS = "records.json"


def _resume(path: Path, settings: dict[str, Any], resume: bool) -> tuple[Any, tuple]:
    """The scorecard's journal and, with ``resume``, its validated runs (pendulab.evaluate.scorecard_journal)."""
    from .._journal import JournalError
    from ..evaluate.scorecard_journal import open_journal

    if resume and not path.is_file():
        print(f"--resume: no {path}; starting a new scorecard", file=sys.stderr)
    try:
        journal, records = open_journal(path, settings, resume=resume)
    except JournalError as exc:
        raise CLIError(f"--resume: {exc}") from None
    if resume and path.is_file():
        print(f"--resume: {len(records)} runs already recorded in {path} (validated)", file=sys.stderr)
    return journal, records


def _plant_suffix(plant: Any) -> str:
    """Default output directories of a run on an identified plant end in ``-identified`` (the nominal run's stay)."""
    return "" if plant is None else "-identified"


def _protocol_task(args: argparse.Namespace) -> str:
    from ..control.swingup.tasks import short_name

    task = short_name(args.task)
    if task not in ("pendubot", "acrobot"):
        raise CLIError(f"--task {args.task!r}: --protocol {args.protocol} expects pendubot or acrobot")
    return task


def _run_protocol(args: argparse.Namespace, plant: Any) -> int:
    """``--protocol robustness-v2`` and ``--protocol v3``."""
    common = (
        ("runs", "--runs"), ("categories", "--categories"), ("max_wall_time", "--max-wall-time"), ("estimator", "--estimator")
    )  # fmt: skip
    if args.protocol in ("v3", "v3-hardware"):
        _reject(args, f"--protocol {args.protocol}", (*common, ("workers", "--workers"), ("resume", "--resume")))
        return _run_v3(args, plant)
    _reject(args, "--protocol robustness-v2", common)
    task = _protocol_task(args)
    from ..evaluate.realai.controllers import CONTROLLERS
    from ..evaluate.realai.robustness import CATEGORIES, QUICK_LEVELS, robustness_v2

    if args.controller not in CONTROLLERS:
        raise CLIError(f"--controller {args.controller!r}: --protocol robustness-v2 expects one of {list(CONTROLLERS)}")
    workers = _int("--workers", args.workers, 1, 1024, "worker processes")
    seed = _int("--seed", args.seed, 0, 2**32 - 1, "a seed of numpy's legacy RandomState (upstream's np.random.seed)", 0)
    out = output_directory(
        args.out or Path("pendulab-out") / "score" / f"robustness-v2-{args.controller}-{task}{_plant_suffix(plant)}"
    )
    journal = out / "runs.json"
    check_journal(journal)
    if args.resume and not journal.is_file():
        print(f"--resume: no {journal}; starting a new run", file=sys.stderr)
    quick = {"levels": QUICK_LEVELS, "repetitions": 2, "perturbation_repetitions": 5} if args.quick else {}
    bar = ProgressBar(f"robustness-v2 {args.controller} on {task}", not args.no_progress)
    try:
        res = robustness_v2(
            task, args.controller, seed=seed, workers=workers, progress=bar, journal=journal, resume=args.resume,
            plant=plant, **quick,
        )  # fmt: skip
    except ValueError as exc:
        if "journal" in str(exc):
            raise CLIError(f"--resume: {exc}") from None
        raise
    finally:
        bar.close()
    from ..viz.robustness import plot_robustness

    plot_robustness(res, out / "robustness.png")
    summary = res.to_dict()
    # Last: a robustness.json means every other output of the run is complete.
    atomic_write_text(out / "robustness.json", json.dumps(summary, indent=1) + "\n")
    print(f"wrote {out / 'robustness.json'}, robustness.png, runs.json", file=sys.stderr)
    if args.json:
        print(json.dumps(summary, indent=1))
        return 0
    grid = "" if res.complete else " (reduced grid: --quick)"
    print(f"RealAIGym robustness v2, {task} / {args.controller}{grid}: score {res.score:.3f}")
    for c in CATEGORIES:
        print(f"  {c:<18} {100 * res.rates[c]:5.1f} %")
    best = summary["published_best"]
    print(f"published best: {best['name']} {best['score']:.3f}")
    print(
        f"{len(res.records)} runs, {res.wall_time:.1f} s; controller call median {1e6 * res.ctrl_time_median:.0f} us, "
        f"max {1e3 * res.ctrl_time_max:.2f} ms (period {1e3 * res.sample_time:g} ms)"
    )
    return 0


def _run_v3(args: argparse.Namespace, plant: Any) -> int:
    task = _protocol_task(args)
    seed = _int("--seed", args.seed, 0, 2**32 - 1, "a seed of the v3 protocol's resets", 0)
    protocol = args.protocol
    hardware = protocol == "v3-hardware"
    # Only the v3-hardware runner takes the allowance (refused with the others in run_score); in its settings and
    # in the default output directory, so runs of two allowances never overwrite each other.
    options = {"passive_allowance": args.passive_allowance or 0.0} if hardware else {}
    allowance = f"-allowance{args.passive_allowance:g}" if hardware and args.passive_allowance else ""
    out = output_directory(
        args.out or Path("pendulab-out") / "score" / f"{protocol}-{args.controller}-{task}{allowance}{_plant_suffix(plant)}"
    )
    try:
        from ..evaluate.realai.controllers import LIBRARY_PLAYERS, library_bound
        from ..evaluate.realai.v3 import v3_score
        from ..evaluate.realai.v3_hardware import v3_hardware_score
    except ImportError as exc:
        raise CLIError(f"--protocol {protocol} is not available in this installation ({exc})") from None
    # The hardware protocol's plant is the identified C.1 robot unless --plant names another.
    run = v3_hardware_score if hardware else v3_score
    if args.controller in LIBRARY_PLAYERS:  # the plan library is solved once and cached: build it with its own bar
        from ..control.plan_library import DEFAULT_LIBRARY_DIR, library_controller

        # The bound the controller will play with (the hardware protocol's, rate-bounded plans cached apart).
        bound = library_bound(args.controller, hardware)
        plans = ProgressBar(f"plan library for {task} (IPOPT; cached in ./{DEFAULT_LIBRARY_DIR})", not args.no_progress)
        try:
            library_controller(task, progress=plans, velocity_limit=bound)
        finally:
            plans.close()
    bar = ProgressBar(f"{protocol} {args.controller} on {task}", not args.no_progress)
    try:
        res = run(task, args.controller, seed=seed, progress=bar, out=out, plant=plant, **options)
    except ValueError as exc:
        raise CLIError(f"--protocol {protocol} (--controller {args.controller!r}): {exc}") from None
    finally:
        bar.close()
    summary = res.to_dict()
    out.mkdir(parents=True, exist_ok=True)
    name = protocol.replace("-", "_") + ".json"
    atomic_write_text(out / name, json.dumps(summary, indent=1) + "\n")
    print(f"wrote {out / name}", file=sys.stderr)
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        where = "hardware protocol, simulated C.1 robot" if protocol == "v3-hardware" else "simulation"
        print(f"RealAIGym {protocol.split('-')[0]} ({where}), {task} / {args.controller}: score {res.score:.3f}")
        ct = summary["controller_time"]
        if ct["calls"]:
            print(f"controller call median {1e3 * ct['median_s']:.3f} ms, max {1e3 * ct['max_s']:.2f} ms ({ct['calls']} calls)")
        if hardware:
            stop = "none" if summary["stopped_at"] is None else f"{summary['stopped_at']:.1f} s"
            print(
                f"passive allowance {res.passive_allowance:g} N.m, plan rate bound {summary['entry']['velocity_limit']} "
                f"rad/s; max measured joint rate {summary['max_joint_rate']:.1f} rad/s, {summary['limit_resets']} limit "
                f"resets, safety stop {stop}"
            )
    return 0


def _run_realai(args: argparse.Namespace, plant: Any) -> int:
    from ..control.swingup.iterations import observe
    from ..control.swingup.tasks import short_name

    task = short_name(args.task)
    if task not in ("pendubot", "acrobot"):
        raise CLIError(f"--task {args.task!r}: --realai expects pendubot or acrobot (or swingup_pendubot, swingup_acrobot)")
    from ..evaluate.realai import CONTROLLER_NAMES, realai_score

    if args.controller not in CONTROLLER_NAMES:
        raise CLIError(
            f"--controller {args.controller!r}: the RealAIGym protocols (--realai, --protocol) expect one of "
            f"{list(CONTROLLER_NAMES)}"
        )
    out = output_directory(args.out or Path("pendulab-out") / "score" / f"realai-{args.controller}-{task}{_plant_suffix(plant)}")
    planning = ProgressBar(f"planning {args.controller} on {task} (IPOPT)", not args.no_progress)
    steps = ProgressBar(f"RealAIGym run ({args.controller} on {task}, 5000 steps of 2 ms)", not args.no_progress, "step")
    try:
        with observe(lambda: planning.iterate(1, "iter"), lambda d: planning.note(f"building the NLP ({d}) ...")):

            def run_progress(done: int, total: int) -> None:
                planning.close()
                steps(done, total)

            result = realai_score(task, args.controller, progress=run_progress, plant=plant)
    finally:
        planning.close()
        steps.close()
    summary = result.to_dict()
    out.mkdir(parents=True, exist_ok=True)
    if hasattr(result, "write_csv"):
        result.write_csv(out / "realai.csv")
    if hasattr(result, "t"):
        from ..viz.scorecard import plot_realai

        plot_realai(result, out / "realai.png")
    # Last: a realai.json means every other output of the run is complete.
    atomic_write_text(out / "realai.json", json.dumps(summary, indent=2) + "\n")
    print(f"wrote {out / 'realai.json'}, realai.csv, realai.png", file=sys.stderr)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        crit = ", ".join(f"{k} {v:.4g}" for k, v in summary.get("criteria", {}).items())
        print(f"RealAIGym {task} / {args.controller}: success {summary.get('success')}, score {summary.get('score'):.3f}")
        if crit:
            print(f"criteria: {crit}")
    return 0

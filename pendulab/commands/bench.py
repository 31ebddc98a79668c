"""``pendulab bench``: work-precision and stability benchmarks (results as CSV + PNG)."""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

from .._checks import check_budget
from .._io import atomic_open, atomic_write_text
from . import CLIError
from ._common import ProgressBar, docs_page

__all__ = ["register"]

_OUT_WP = "pendulab-out/bench-work-precision"
_OUT_STABILITY = "pendulab-out/bench-stability"
_OUT_HIERARCHY = "pendulab-out/bench-hierarchy"
_DOCS_NOTE = f"; in a source checkout --out docs/benchmarks regenerates the shipped results; see {docs_page('benchmarks')}"


class _Bar:
    """Progress of a benchmark as a tqdm bar on stderr, fed by ``progress(done, total, label)``."""

    def __init__(self, desc: str = "bench") -> None:
        self.desc = desc
        self.bar: Any = None

    def __call__(self, done: int, total: int, label: str) -> None:
        from tqdm import tqdm

        if self.bar is None:
            self.bar = tqdm(total=total, desc=self.desc, unit="step", file=sys.stderr, dynamic_ncols=True)
        self.bar.total = total
        self.bar.n = done
        self.bar.set_postfix_str(label[:60], refresh=False)
        self.bar.refresh()
        if done >= total:
            self.bar.close()
            self.bar = None


def _progress(desc: str, args: argparse.Namespace) -> tuple[ProgressBar, Any]:
    """The project's progress bar and a ``progress(done, total, label)`` callback feeding it."""
    bar = ProgressBar(desc, not args.no_progress)
    return bar, lambda done, total, label: bar(done, total)


def _json(obj: Any) -> str:
    """Strict JSON (NaN and inf become null; paths and NumPy numbers become str / numbers)."""

    def clean(v: Any) -> Any:
        if isinstance(v, dict):
            return {str(k): clean(x) for k, x in v.items()}
        if isinstance(v, (list, tuple)):
            return [clean(x) for x in v]
        if hasattr(v, "item") and callable(v.item):  # NumPy scalar
            v = v.item()
        if isinstance(v, float) and not math.isfinite(v):
            return None
        return v if isinstance(v, (str, int, float, bool, type(None))) else str(v)

    return json.dumps(clean(obj), indent=1, allow_nan=False)


def _resumable(journal: Path, study: str, args: argparse.Namespace) -> int:
    """Entries a ``--resume`` run will reuse (a note on stderr when there is nothing to resume)."""
    from .._journal import trusted_records

    if not args.resume:
        return 0
    if not journal.exists():
        print(f"pendulab bench: nothing to resume in {journal.parent} (no {journal.name}); starting", file=sys.stderr)
        return 0
    return len(trusted_records(journal, study))  # only entries that validate; the study reports the others


def _resume_hint(journal: Path) -> None:
    """After Ctrl-C: where the finished work is and how to continue (stderr; a new line ends the progress bar's)."""
    print(f"\nfinished work is kept in {journal}; run the same command with --resume to continue", file=sys.stderr)


def _work_precision(args: argparse.Namespace) -> int:
    from ..bench import workprecision as wp

    if args.merge and args.resume:
        raise CLIError("--merge and --resume: use one (--resume continues this run's journal, --merge combines CSVs)")
    if args.repeats < 1:
        raise CLIError(f"--repeats {args.repeats}: expected an integer >= 1")
    check_budget("repeats", "--repeats", args.repeats)  # before any reference or run
    out = Path(args.out)
    journal = out / "work_precision_journal.json"
    resumed = _resumable(journal, "work-precision", args)
    start = time.perf_counter()
    bar, progress = _progress("bench work-precision", args)
    try:
        rows = wp.run_work_precision(
            args.cases,
            args.methods,
            quick=args.quick,
            repeats=args.repeats,
            progress=progress,
            journal=journal,
            resume=args.resume,
        )
    except KeyboardInterrupt:
        _resume_hint(journal)
        raise
    finally:
        bar.close()
    elapsed = time.perf_counter() - start
    csv_path = out / "work_precision.csv"
    if args.merge and csv_path.exists():
        # Charts and tables below are regenerated from the complete, merged CSV.
        rows = wp.merge_rows(wp.read_csv(csv_path), rows)
    wp.write_csv(rows, csv_path)
    files = [csv_path]
    files += [
        wp.plot_work_precision(rows, out / f"work_precision_{metric}.png", metric)
        for metric in ("grid_error", "final_error", "energy_drift")
    ]
    files.append(wp.plot_work_precision(rows, out / "work_precision_grid_error_cpu.png", "grid_error", time_metric="cpu_median"))
    files.append(atomic_write_text(out / "work_precision_fastest.md", _fastest_markdown(rows)))
    status = Counter(r.status for r in rows)
    failed = [
        {"case": r.case, "method": r.method, "setting": r.setting, "status": r.status, "message": r.message}
        for r in rows
        if r.status in ("failed", "unstable")
    ]
    if args.json:
        summary = {
            "command": "bench work-precision",
            "out": str(out),
            "quick": args.quick,
            "cases": list(dict.fromkeys(r.case for r in rows)),
            "methods": list(dict.fromkeys(r.method for r in rows)),
            "points": len(rows),
            "status": dict(status),
            "resumed_points": resumed,
            "wall_time_s": elapsed,
            "failed": failed,
            "journal": str(journal),
            "files": [str(f) for f in files],
        }
        print(_json(summary))
        return 0
    counts = ", ".join(f"{n} {k}" for k, n in sorted(status.items()))
    print(f"{status.get('ok', 0)}/{len(rows)} points ok ({counts}); {resumed} resumed from the journal; {elapsed:.0f} s")
    for f in failed:
        print(f"  {f['status']}: {f['case']} {f['method']} {f['setting']:g}: {f['message']}")
    print("wrote " + ", ".join(str(f) for f in files))
    return 0


def _fastest_markdown(rows: list) -> str:
    """Per case: the fastest method reaching each error level (grid error), with the runner-up."""
    from ..bench import workprecision as wp

    parts = []
    for case in dict.fromkeys(r.case for r in rows):
        parts += [
            f"### {case}",
            "",
            "| error level | fastest method (setting) | achieved error | median wall time | runner-up (x slower) |",
            "|---|---|---|---|---|",
        ]
        for e in wp.fastest_table(rows, case):
            if e["method"] is None:
                parts.append(f"| {e['level']:.0e} | none reached it | | | |")
                continue
            setting = f"{'rtol' if e['sweep'] == 'tol' else 'h'} = {e['setting']:g}"
            runner = f"{e['runner_up']} ({e['ratio']:.1f}x)" if "runner_up" in e else "-"
            wall = f"{e['wall_median'] * 1e3:.1f} ms"
            parts.append(f"| {e['level']:.0e} | {e['method']} ({setting}) | {e['grid_error']:.1e} | {wall} | {runner} |")
        parts.append("")
    return "\n".join(parts)


def _stability(args: argparse.Namespace) -> int:
    from ..bench import stability as st

    out = Path(args.out)
    journal = out / "stability_journal.json"
    resumed = _resumable(journal, "stability", args)
    start = time.perf_counter()
    bar, progress = _progress("bench stability", args)
    try:
        result = st.run_stability(quick=args.quick, progress=progress, journal=journal, resume=args.resume)
    except KeyboardInterrupt:
        _resume_hint(journal)
        raise
    finally:
        bar.close()
    elapsed = time.perf_counter() - start
    paths = st.write_stability(result, out)
    if args.json:
        summary = {
            "command": "bench stability",
            "out": str(out),
            "quick": args.quick,
            "resumed_units": resumed,
            "wall_time_s": elapsed,
            **result.summary(),
            "journal": str(journal),
            "files": [str(p) for p in paths],
        }
        print(_json(summary))
        return 0
    for k, hm, hp in result.blowup:
        print(f"RK4 blow-up step at k = {k:.0e} N/m: measured {hm:.4g} s, predicted {hp:.4g} s ({hm / hp - 1:+.2%})")
    for label, (_, dE) in result.energy.items():
        print(f"energy change after {_horizon(result):g} s, {label}: {float(dE[-1]):+.3e} J")
    for f in result.failures:
        print(f"  failed: {f['unit']}: {f['reason']}")
    print(f"{len(result.failures)} units failed; {resumed} resumed from the journal; {elapsed:.0f} s")
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def _horizon(result: Any) -> float:
    """Horizon [s] of the energy study (its last time point)."""
    return max((float(t[-1]) for t, _ in result.energy.values()), default=0.0)


def _hierarchy(args: argparse.Namespace) -> int:
    from ..bench.hierarchy import LEVELS, stiffness_amplitude_study

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ks = (1e2, 1e4, 1e6) if args.quick else (1e2, 1e3, 1e4, 1e5, 1e6)
    amps = (0.05, 1.0) if args.quick else (0.05, 0.3, 1.0, 2.0)
    rows = stiffness_amplitude_study(ks, amps, tolerance=args.tolerance, repeats=1 if args.quick else 3, progress=_Bar())
    path = out / "hierarchy_table.csv"
    with atomic_open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows)
    lines = [
        "| k [N/m] | " + " | ".join(f"theta0 = {a:g} rad" for a in amps) + " |",
        "|---|" + "---|" * len(amps),
    ]
    for k in ks:
        cells = []
        for a in amps:
            r = next(r for r in rows if r["k"] == k and r["amplitude"] == a)
            errs = ", ".join(f"{lv[:3] if lv != 'rigid+quasi-static' else 'r+qs'} {r[f'error[{lv}]']:.1e}" for lv in LEVELS[:-1])
            cells.append(f"**{r['chosen']}** ({errs})")
        lines.append(f"| {k:.0e} | " + " | ".join(cells) + " |")
    atomic_write_text(out / "hierarchy_table.md", "\n".join(lines) + "\n")
    scene_lines = _shipped_scene_table(quick=args.quick)
    atomic_write_text(out / "hierarchy_scenes.md", "\n".join(scene_lines) + "\n")
    files = [str(path), str(out / "hierarchy_table.md"), str(out / "hierarchy_scenes.md")]
    if args.json:
        finite = [{k: (v if not isinstance(v, float) or math.isfinite(v) else None) for k, v in r.items()} for r in rows]
        print(json.dumps({"stiffness": list(ks), "amplitudes": list(amps), "rows": finite, "files": files}, indent=1))
    else:
        print("\n".join(lines))
        print("\n".join(scene_lines))
    print(f"wrote {', '.join(files)}", file=sys.stderr if args.json else sys.stdout)
    return 0


def _shipped_scene_table(quick: bool) -> list[str]:
    """Markdown table: the hierarchy's choice for every shipped scene that states a tolerance."""
    from ..bench.hierarchy import check_scene
    from ..scene import list_scenes, load_scene

    lines = [
        "| scene | model | tolerance | linearized: error / cost | rigid | rigid+quasi-static"
        " | scene model (reference) cost | chosen |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name in list_scenes():
        scene = load_scene(name)
        if scene.tolerance is None:
            continue
        rep = check_scene(scene, repeats=1 if quick else 3)
        by = {lv.name: lv for lv in rep.levels}
        cells = [
            f"{by[n].error:.1e} / {by[n].wall_time * 1e3:.0f} ms" if n in by else "-"
            for n in ("linearized", "rigid", "rigid+quasi-static")
        ]
        ref = by[rep.levels[-1].name]
        lines.append(
            f"| {name} | {scene.model.kind} | {rep.tolerance:g} | " + " | ".join(cells) + f" | {ref.wall_time * 1e3:.0f} ms"
            f" | **{rep.chosen}** |"
        )
    return lines


def _references(args: argparse.Namespace) -> int:
    from ..bench.cases import get_cases
    from ..bench.reference import REFERENCE_DIR, compute_reference

    directory = Path(args.out) if args.out else REFERENCE_DIR
    written = []
    for case in get_cases(args.cases):
        ref = compute_reference(case, progress=lambda msg: print(msg, file=sys.stderr, flush=True))
        path = ref.save(directory)
        written.append({"case": case.name, "accuracy": ref.accuracy, "notes": ref.notes, "file": str(path)})
        if not args.json:
            print(f"{case.name}: accuracy {ref.accuracy:.3e} ({ref.notes}) -> {path}")
    if args.json:
        print(json.dumps({"command": "bench references", "out": str(directory), "references": written}, indent=1))
    return 0


def _ensemble(args: argparse.Namespace) -> int:
    from ..bench import ensemble as eb
    from .ensemble import DEFAULT_K

    for name in ("grid", "repeats"):
        if getattr(args, name) < 1:
            raise CLIError(f"--{name} {getattr(args, name)}: expected an integer >= 1")
    for name in ("runs", "hand_runs"):
        value = getattr(args, name)
        if value is not None and value < 1:
            raise CLIError(f"--{name.replace('_', '-')} {value}: expected an integer >= 1")
    if not args.t_max > 0:
        raise CLIError(f"--t-max {args.t_max}: expected a number > 0")
    if any(n < 1 for n in [*args.threads, *args.workers]):
        raise CLIError("--threads/--workers: expected integers >= 1")
    check_budget("runs", "--grid", args.grid, float(args.grid) ** 2)
    for option, value in (("--runs", args.runs), ("--hand-runs", args.hand_runs)):
        if value is not None:
            check_budget("runs", option, value)
    check_budget("repeats", "--repeats", args.repeats)
    out = Path(args.out)
    bench = eb.run_ensemble_bench(
        grid=args.grid,
        t_max=args.t_max,
        runs=args.runs,
        hand_runs=args.hand_runs,
        repeats=args.repeats,
        threads=tuple(args.threads),
        workers=tuple(args.workers),
        progress=_Bar("bench ensemble"),
    )
    if not args.no_cli:
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            cli = ["ensemble", "flipmap", "--model", "rigid", "--grid", str(args.grid), "--t-max", f"{args.t_max:g}"]
            bench.extra["cli"] = eb.time_cli(cli, tmp, repeats=args.repeats)
    if args.elastic_grid:
        bench.extra["elastic"] = eb.elastic_rigid_ratio(args.elastic_grid, args.t_max, args.k or DEFAULT_K)
    text = eb.ensemble_markdown(bench)
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out, text)
    if args.json:
        print(json.dumps({"out": str(out), "report": text}))
    else:
        print(text)
    print(f"wrote {out}", file=sys.stderr if args.json else sys.stdout)
    return 0


def _add_study_options(p: argparse.ArgumentParser, journal: str, unit: str) -> None:
    p.add_argument(
        "--resume",
        action="store_true",
        help=f"continue an interrupted or crashed run in the same --out: every finished {unit} is recorded in "
        f"OUT/{journal} and is not recomputed (same --quick/--repeats required)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON summary on stdout instead of text")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("bench", help="work-precision and stability benchmarks", description=__doc__)
    sub = p.add_subparsers(dest="bench_command", metavar="BENCH")
    sub.required = True

    wp = sub.add_parser("work-precision", help="median wall time against achieved error, per case")
    wp.add_argument("--cases", nargs="+", metavar="CASE", help="case names (default: all)")
    wp.add_argument("--methods", nargs="+", metavar="METHOD", help="method names (default: all)")
    wp.add_argument(
        "--out", default=_OUT_WP, help=f"output directory for CSV, charts and journal (default ./{_OUT_WP}{_DOCS_NOTE})"
    )
    wp.add_argument("--quick", action="store_true", help="short sweeps (CI smoke run)")
    wp.add_argument("--repeats", type=int, default=3, help="timed runs per point; the median is reported (default 3)")
    wp.add_argument(
        "--merge",
        action="store_true",
        help="replace only the re-measured (case, method) rows of an existing OUT/work_precision.csv; charts and tables "
        "are redrawn from the merged CSV",
    )
    _add_study_options(wp, "work_precision_journal.json", "point")
    wp.set_defaults(func=_work_precision)

    st = sub.add_parser("stability", help="stable/inaccurate/unstable map over stiffness and step, step counts, energy")
    st.add_argument("--out", default=_OUT_STABILITY, help=f"output directory (default ./{_OUT_STABILITY}{_DOCS_NOTE})")
    st.add_argument("--quick", action="store_true", help="coarse map (CI smoke run)")
    _add_study_options(st, "stability_journal.json", "unit (map cell, bisection, step count, energy run)")
    st.set_defaults(func=_stability)

    hi = sub.add_parser("hierarchy", help="model-hierarchy choice over spring stiffness x release angle")
    hi.add_argument("--out", default=_OUT_HIERARCHY, help=f"output directory (default ./{_OUT_HIERARCHY}{_DOCS_NOTE})")
    hi.add_argument("--quick", action="store_true", help="3 x 2 grid (CI smoke run)")
    hi.add_argument("--tolerance", type=float, default=1e-2, help="error tolerance on theta1, theta2 [rad], x2, y2 [m]")
    hi.add_argument("--json", action="store_true", help="print one JSON summary on stdout (messages go to stderr)")
    hi.set_defaults(func=_hierarchy)

    rf = sub.add_parser("references", help="recompute the stored reference solutions of the cases")
    rf.add_argument("--cases", nargs="+", metavar="CASE", help="case names (default: all)")
    rf.add_argument("--out", default=None, help="directory (default: the package's bench/references)")
    rf.add_argument("--json", action="store_true", help="print one JSON summary on stdout instead of text")
    rf.set_defaults(func=_references)

    en = sub.add_parser(
        "ensemble",
        help="ensemble throughput (runs/s) on the rigid flip map: threads, Dask workers, hand-written heyoka loop",
        description="Throughput of pendulab.ensemble (local threads, Dask LocalCluster worker processes) against a "
        "hand-written single-core heyoka loop, on the runs of the rigid flip map; also times the whole "
        "`pendulab ensemble flipmap` command and the elastic map against the rigid one.",
    )
    en.add_argument("--grid", type=int, default=400, help="flip-map grid defining the workload (default 400)")
    en.add_argument("--t-max", type=float, default=10.0, help="horizon [s] (default 10)")
    en.add_argument("--runs", type=int, default=None, help="time a seeded random subset of this many runs (default all)")
    en.add_argument("--hand-runs", type=int, default=None, help="runs of the hand-written loop (default: as --runs)")
    en.add_argument("--repeats", type=int, default=3, help="timed repetitions; medians reported (default 3)")
    en.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="local thread counts (default 1 2)")
    en.add_argument("--workers", type=int, nargs="*", default=[1, 2], help="Dask worker processes (default 1 2)")
    en.add_argument("--no-cli", action="store_true", help="do not time the whole flipmap command")
    en.add_argument("--elastic-grid", type=int, default=100, help="grid of the elastic/rigid timing (0: skip; default 100)")
    en.add_argument("--k", type=float, default=None, help="elastic stiffness [N/m] (default: the flipmap command's)")
    en.add_argument("--out", default="benchmarks/results/ensemble.md", help="Markdown results file")
    en.add_argument("--json", action="store_true", help="print one JSON summary on stdout (messages go to stderr)")
    en.set_defaults(func=_ensemble)

"""``pendulab bench``: work-precision and stability benchmarks (results as CSV + PNG)."""

from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

__all__ = ["register"]

_DEFAULT_OUT = "docs/benchmarks"


class _Bar:
    """A one-line progress bar on stderr."""

    def __init__(self, width: int = 30) -> None:
        self.width = width
        self.start = time.perf_counter()

    def __call__(self, done: int, total: int, label: str) -> None:
        frac = done / total if total else 1.0
        fill = int(self.width * frac)
        elapsed = time.perf_counter() - self.start
        sys.stderr.write(f"\r[{'#' * fill}{'.' * (self.width - fill)}] {done}/{total} {elapsed:6.1f}s {label[:60]:<60}")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def _work_precision(args: argparse.Namespace) -> int:
    from ..bench import workprecision as wp

    out = Path(args.out)
    rows = wp.run_work_precision(args.cases, args.methods, quick=args.quick, repeats=args.repeats, progress=_Bar())
    csv_path = out / "work_precision.csv"
    if args.merge and csv_path.exists():
        # Charts and tables below are regenerated from the complete, merged CSV.
        rows = wp.merge_rows(wp.read_csv(csv_path), rows)
    wp.write_csv(rows, csv_path)
    figs = [
        wp.plot_work_precision(rows, out / f"work_precision_{metric}.png", metric)
        for metric in ("grid_error", "final_error", "energy_drift")
    ]
    figs.append(wp.plot_work_precision(rows, out / "work_precision_grid_error_cpu.png", "grid_error", time_metric="cpu_median"))
    md = out / "work_precision_fastest.md"
    md.write_text(_fastest_markdown(rows))
    figs.append(md)
    n_ok = sum(r.status == "ok" for r in rows)
    print(f"{n_ok}/{len(rows)} runs ok; wrote {csv_path} and {', '.join(str(f) for f in figs)}")
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
    result = st.run_stability(quick=args.quick, progress=_Bar())
    paths = st.write_stability(result, out)
    print(json.dumps(result.summary(), indent=1))
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0


def _hierarchy(args: argparse.Namespace) -> int:
    from ..bench.hierarchy import LEVELS, stiffness_amplitude_study

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    ks = (1e2, 1e4, 1e6) if args.quick else (1e2, 1e3, 1e4, 1e5, 1e6)
    amps = (0.05, 1.0) if args.quick else (0.05, 0.3, 1.0, 2.0)
    rows = stiffness_amplitude_study(ks, amps, tolerance=args.tolerance, repeats=1 if args.quick else 3, progress=_Bar())
    path = out / "hierarchy_table.csv"
    with path.open("w", newline="") as fh:
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
    (out / "hierarchy_table.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    scene_lines = _shipped_scene_table(quick=args.quick)
    (out / "hierarchy_scenes.md").write_text("\n".join(scene_lines) + "\n")
    print("\n".join(scene_lines))
    print(f"wrote {path}, {out / 'hierarchy_table.md'} and {out / 'hierarchy_scenes.md'}")
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
    for case in get_cases(args.cases):
        ref = compute_reference(case, progress=lambda msg: print(msg, file=sys.stderr, flush=True))
        path = ref.save(directory)
        print(f"{case.name}: accuracy {ref.accuracy:.3e} ({ref.notes}) -> {path}")
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("bench", help="work-precision and stability benchmarks", description=__doc__)
    sub = p.add_subparsers(dest="bench_command", metavar="BENCH")
    sub.required = True

    wp = sub.add_parser("work-precision", help="median wall time against achieved error, per case")
    wp.add_argument("--cases", nargs="+", metavar="CASE", help="case names (default: all)")
    wp.add_argument("--methods", nargs="+", metavar="METHOD", help="method names (default: all)")
    wp.add_argument("--out", default=_DEFAULT_OUT, help=f"output directory for CSV and charts (default {_DEFAULT_OUT})")
    wp.add_argument("--quick", action="store_true", help="short sweeps (CI smoke run)")
    wp.add_argument("--repeats", type=int, default=3, help="timed runs per point; the median is reported (default 3)")
    wp.add_argument(
        "--merge",
        action="store_true",
        help="replace only the re-measured (case, method) rows of an existing OUT/work_precision.csv; charts and tables "
        "are redrawn from the merged CSV",
    )
    wp.set_defaults(func=_work_precision)

    st = sub.add_parser("stability", help="stable/inaccurate/unstable map over stiffness and step, step counts, energy")
    st.add_argument("--out", default=_DEFAULT_OUT, help=f"output directory (default {_DEFAULT_OUT})")
    st.add_argument("--quick", action="store_true", help="coarse map (CI smoke run)")
    st.set_defaults(func=_stability)

    hi = sub.add_parser("hierarchy", help="model-hierarchy choice over spring stiffness x release angle")
    hi.add_argument("--out", default=_DEFAULT_OUT, help=f"output directory (default {_DEFAULT_OUT})")
    hi.add_argument("--quick", action="store_true", help="3 x 2 grid (CI smoke run)")
    hi.add_argument("--tolerance", type=float, default=1e-2, help="error tolerance on theta1, theta2 [rad], x2, y2 [m]")
    hi.set_defaults(func=_hierarchy)

    rf = sub.add_parser("references", help="recompute the stored reference solutions of the cases")
    rf.add_argument("--cases", nargs="+", metavar="CASE", help="case names (default: all)")
    rf.add_argument("--out", default=None, help="directory (default: the package's bench/references)")
    rf.set_defaults(func=_references)

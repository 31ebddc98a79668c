"""``pendulab bench``: work-precision and stability benchmarks (results as CSV + PNG)."""

from __future__ import annotations

import argparse
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
    csv_path = wp.write_csv(rows, out / "work_precision.csv")
    figs = [
        wp.plot_work_precision(rows, out / f"work_precision_{metric}.png", metric)
        for metric in ("grid_error", "final_error", "energy_drift")
    ]
    n_ok = sum(r.status == "ok" for r in rows)
    print(f"{n_ok}/{len(rows)} runs ok; wrote {csv_path} and {', '.join(str(f) for f in figs)}")
    return 0


def _stability(args: argparse.Namespace) -> int:
    from ..bench import stability as st

    out = Path(args.out)
    result = st.run_stability(quick=args.quick, progress=_Bar())
    paths = st.write_stability(result, out)
    print(json.dumps(result.summary(), indent=1))
    print("wrote " + ", ".join(str(p) for p in paths))
    return 0


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
    wp.set_defaults(func=_work_precision)

    st = sub.add_parser("stability", help="stable/inaccurate/unstable map over stiffness and step, step counts, energy")
    st.add_argument("--out", default=_DEFAULT_OUT, help=f"output directory (default {_DEFAULT_OUT})")
    st.add_argument("--quick", action="store_true", help="coarse map (CI smoke run)")
    st.set_defaults(func=_stability)

    rf = sub.add_parser("references", help="recompute the stored reference solutions of the cases")
    rf.add_argument("--cases", nargs="+", metavar="CASE", help="case names (default: all)")
    rf.add_argument("--out", default=None, help="directory (default: the package's bench/references)")
    rf.set_defaults(func=_references)

"""``method="auto"``: its pick against the fastest method, per case and tolerance.

    python benchmarks/bench_auto.py [--repeats 3] [--tols 1e-6 1e-8 1e-10] [--out benchmarks/results/auto.md]

Cases (2 s, theta1 = 1 rad or the chaotic (2, 2) start): the rigid pendulum, and elastic pendulums with
k = 200, 1e5 and 1e6 N/m started three ways — ``model.state(theta1=1)`` (static hanging spring lengths,
which excite the stiff springs a little), quasi-static (no spring motion excited) and at rest length
(strongly excited). Methods: compiled-dopri5, compiled-rodas4, taylor, cvodes, cvodes-adams at
rtol = atol = tol. Each run once as a warm-up (JIT / C build), then ``--repeats`` interleaved rounds;
medians. Achieved error: max over the final state against taylor at 1e-14. "fastest" is the fastest
at the same tolerance (achieved errors differ and are shown beside each time). The warm-up is excluded:
taylor's elastic system compiles for seconds per tolerance on first use, which the rule weighs (it picks
compiled-dopri5 for the elastic model when not stiff) and this table does not.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from collections.abc import Iterator
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
from tqdm import tqdm

import pendulab as pl
from pendulab.integrate.auto import choose_method
from pendulab.model.quasistatic import quasi_static_state

T_FINAL = 2.0
METHODS = ("compiled-dopri5", "compiled-rodas4", "taylor", "cvodes", "cvodes-adams")
OUT = Path(__file__).resolve().parent / "results" / "auto.md"


def cases() -> Iterator[tuple[str, pl.Model, np.ndarray]]:
    """(label, model, start) of every case."""
    r = pl.rigid()
    yield "rigid regular (1, 0)", r, r.state(theta1=1.0)
    yield "rigid chaotic (2, 2)", r, r.state(theta1=2.0, theta2=2.0)
    for k in (200.0, 1e5, 1e6):
        m = pl.elastic(k1=k, k2=k)
        yield f"elastic k={k:g} model.state(theta1=1)", m, m.state(theta1=1.0)
        yield f"elastic k={k:g} quasi-static (1, 0)", m, quasi_static_state(m, (1.0, 0.0))
        yield f"elastic k={k:g} rest length (1, 0)", m, m.state(theta1=1.0, r1=1.0, r2=1.0)


def measure(tol: float, repeats: int, bar: tqdm) -> list[dict]:
    """One row per case at ``tol``: the auto pick, and each method's median time and achieved error."""
    rows = []
    for label, model, x0 in cases():
        ref = pl.simulate(model, x0, T_FINAL, method="taylor", rtol=1e-14, atol=1e-14).x[-1]
        times: dict[str, list[float]] = {m: [] for m in METHODS}
        errors: dict[str, float] = {}
        for m in METHODS:  # warm-up
            errors[m] = float(np.max(np.abs(pl.simulate(model, x0, T_FINAL, method=m, rtol=tol, atol=tol).x[-1] - ref)))
        for _ in range(repeats):  # interleaved rounds: every method sees the same load
            for m in METHODS:
                t0 = time.perf_counter()
                pl.simulate(model, x0, T_FINAL, method=m, rtol=tol, atol=tol)
                times[m].append(time.perf_counter() - t0)
        median = {m: statistics.median(v) for m, v in times.items()}
        choice = choose_method(model, x0, np.zeros(model.nu), tol, tol)
        fastest = min(median, key=median.__getitem__)
        rows.append({"case": label, "tol": tol, "auto": choice.method, "fastest": fastest, "median": median, "error": errors})
        bar.update(1)
    return rows


def table(rows: list[dict]) -> str:
    """Markdown table: pick, fastest, time ratio of the pick to the fastest, and every method's time (error)."""
    short = {m: m.replace("compiled-", "") for m in METHODS}
    head = "| case | tol | auto pick | fastest | pick / fastest | " + " | ".join(short[m] for m in METHODS) + " |"
    lines = [head, "|" + "---|" * (5 + len(METHODS))]
    for r in rows:
        ratio = r["median"][r["auto"]] / r["median"][r["fastest"]] if r["auto"] in r["median"] else float("nan")
        cells = []
        for m in METHODS:
            cell = f"{r['median'][m] * 1e3:.2f} ms ({r['error'][m]:.0e})"
            cells.append(f"**{cell}**" if m == r["fastest"] else cell)
        pick, fast = short.get(r["auto"], r["auto"]), short[r["fastest"]]
        lines.append(f"| {r['case']} | {r['tol']:.0e} | {pick} | {fast} | {ratio:.2f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--tols", type=float, nargs="+", default=[1e-6, 1e-8, 1e-10])
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    n_cases = sum(1 for _ in cases())
    rows: list[dict] = []
    with tqdm(total=n_cases * len(args.tols), desc="auto vs fastest", unit="case") as bar:
        for tol in args.tols:
            rows += measure(tol, args.repeats, bar)
    within = sum(r["median"][r["auto"]] <= 1.5 * r["median"][r["fastest"]] for r in rows)
    text = (
        '# `method="auto"` against the fastest method\n\n'
        f"`python benchmarks/bench_auto.py --repeats {args.repeats}` on {platform.processor() or platform.machine()}, "
        f"{datetime.now(timezone.utc):%Y-%m-%d}; {T_FINAL:g} s runs, medians of {args.repeats} interleaved rounds after a "
        "warm-up (excluded: taylor's elastic system compiles for seconds per tolerance on first use, which the rule "
        "weighs and this table does not); achieved error (max over the final state against taylor at 1e-14) in brackets; "
        "fastest in bold.\n\n"
        f"The pick is within 1.5x of the fastest method in {within} of {len(rows)} cases.\n\n" + table(rows) + "\n"
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()

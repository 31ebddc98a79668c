"""``method="taylor"`` against a hand-written heyoka system and the other fast methods.

    python benchmarks/bench_fastpath.py [--repeats N] [--out benchmarks/results/fastpath.md]

Case: rigid model with default parameters (m = 1 kg, L = 1 m, g = 9.81 m/s^2),
theta1 = theta2 = 2 rad at rest, 10 s, output every 10 ms (the chaotic case).

The anchor is a HAND-WRITTEN heyoka system of the same equations (the standard
double-pendulum equations in absolute angles, typed below with m = L = 1 and
g = 9.81 folded in) propagated over the same output grid; the script first
checks that it equals ``model.rhs`` at random states. Against it:
``pl.simulate(..., method="taylor")`` at tol 1e-12 and 1e-15 (the whole call:
argument checks, integration, outputs on the grid), SciPy DOP853 at
rtol = atol = 1e-13, CVODES Adams at 1e-14 and CVODES BDF at 1e-12.

Timing: every run once as a warm-up (JIT compilation, integrator construction),
then ``--repeats`` rounds in which every run is timed once, interleaved so that
all see the same machine load; medians. Errors: against the stored 32-digit
reference ``rigid_chaotic_10s`` (Gragg-Bulirsch-Stoer in mpmath), at t = 10 s
and as the max over the reference grid (every 50 ms).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import casadi as ca
import heyoka as hy
import numpy as np
import scipy
from tqdm import tqdm

import pendulab as pl
from pendulab.bench.cases import CASES
from pendulab.bench.reference import load_reference
from pendulab.integrate import taylor, time_grid
from pendulab.model.pycode import to_python

X0 = np.array([2.0, 2.0, 0.0, 0.0])
T_FINAL = 10.0
DT = 0.01
M1 = M2 = L1 = L2 = 1.0
G = 9.81
OUT = Path(__file__).resolve().parent / "results" / "fastpath.md"


def hand_written_system() -> list[tuple[hy.expression, hy.expression]]:
    """The standard rigid double pendulum, absolute angles from the downward vertical, typed by hand.

    With d = theta2 - theta1:
    w1' = (m2 L1 w1^2 sin d cos d + m2 g sin th2 cos d + m2 L2 w2^2 sin d - (m1 + m2) g sin th1) / den1
    w2' = (-m2 L2 w2^2 sin d cos d + (m1 + m2)(g sin th1 cos d - L1 w1^2 sin d - g sin th2)) / den2
    den1 = (m1 + m2) L1 - m2 L1 cos^2 d, den2 = (L2 / L1) den1.
    """
    th1, th2, w1, w2 = hy.make_vars("theta1", "theta2", "omega1", "omega2")
    d = th2 - th1
    sd, cd = hy.sin(d), hy.cos(d)
    den1 = (M1 + M2) * L1 - M2 * L1 * cd * cd
    den2 = (L2 / L1) * den1
    dw1 = (M2 * L1 * w1 * w1 * sd * cd + M2 * G * hy.sin(th2) * cd + M2 * L2 * w2 * w2 * sd - (M1 + M2) * G * hy.sin(th1)) / den1
    dw2 = (-M2 * L2 * w2 * w2 * sd * cd + (M1 + M2) * (G * hy.sin(th1) * cd - L1 * w1 * w1 * sd - G * hy.sin(th2))) / den2
    return [(th1, w1), (th2, w2), (w1, dw1), (w2, dw2)]


def check_hand_written(model: pl.Model, system: list) -> float:
    """Max relative difference between the hand-written RHS and ``model.rhs`` at 200 random states."""
    f = hy.cfunc([e for _, e in system], [v for v, _ in system])
    rng = np.random.default_rng(7)
    X = np.column_stack([rng.uniform(-np.pi, np.pi, (200, 2)), rng.normal(0.0, 4.0, (200, 2))])
    got = f(np.ascontiguousarray(X.T)).T
    want = model.rhs(X)
    diff = float(np.max(np.abs(got - want) / np.maximum(1.0, np.abs(want))))
    if diff > 1e-12:
        raise SystemExit(f"hand-written equations differ from model.rhs by {diff:.3e} (> 1e-12): fix them")
    return diff


@dataclass
class Run:
    label: str
    settings: str
    fn: Callable[[], tuple[np.ndarray, int, float | None]]  # -> (X on the grid, steps, integration time or None)
    anchor: str | None = None  # label of the hand-written run of the same tolerance
    times: list[float] = field(default_factory=list)
    integ: list[float] = field(default_factory=list)
    x: np.ndarray | None = None
    steps: int = 0

    @property
    def median(self) -> float:
        return statistics.median(self.times)


def heyoka_run(system: list, tol: float, grid: np.ndarray) -> Callable[[], tuple[np.ndarray, int, None]]:
    ta = hy.taylor_adaptive(system, list(X0), tol=tol)

    def run() -> tuple[np.ndarray, int, None]:
        ta.time = 0.0
        ta.state[:] = X0
        res = ta.propagate_grid(grid)
        return res[-1], int(res[3]), None

    return run


def simulate_run(model: pl.Model, method: str, tol: float) -> Callable[[], tuple[np.ndarray, int, float]]:
    def run() -> tuple[np.ndarray, int, float]:
        tr = pl.simulate(model, X0, T_FINAL, dt=DT, method=method, rtol=tol, atol=tol)
        return tr.x, int(tr.stats.get("n_steps") or 0), float(tr.stats["wall_time"])

    return run


def vectorised_outputs(model: pl.Model) -> Callable[..., np.ndarray]:
    """``outputs(x, u, p)`` as straight-line NumPy over whole columns (the same CasADi graph, not retyped)."""
    return to_python(model.functions["outputs"], vectorized=True)


def timed(fn: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def machine_info() -> str:
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"
    return (
        f"{platform.machine()}, {os.cpu_count()} logical CPUs, load average at start {load}; {platform.system()} "
        f"{platform.release()}; Python {platform.python_version()}; heyoka {hy.__version__}, casadi {ca.__version__}, "
        f"numpy {np.__version__}, scipy {scipy.__version__}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=7, help="timed rounds (median), default 7")
    ap.add_argument("--out", type=Path, default=OUT, help=f"Markdown output (default {OUT})")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    info = machine_info()
    model = pl.rigid()
    grid = time_grid(T_FINAL, DT)
    ref = load_reference(CASES["rigid_chaotic_10s"])
    stride = int(round((ref.t[1] - ref.t[0]) / DT))
    if not np.allclose(grid[::stride], ref.t, rtol=0, atol=1e-12):
        raise SystemExit("the reference grid is not a subgrid of the output grid")

    system = hand_written_system()
    rhs_diff = check_hand_written(model, system)

    # First call of method="taylor" in a process: translation of the CasADi graph plus JIT compilation
    # (heyoka's on-disk cache off: "cold"), or a hit in that cache ("warm"), then one run.
    first_call = {}
    disk = hy.llvm_state.get_diskcache_enabled()
    for label, enabled in (("cold", False), ("warm", disk)):
        hy.llvm_state.set_diskcache_enabled(enabled)
        hy.llvm_state.clear_memcache()
        for tol in (1e-12, 1e-15):
            taylor.clear_cache()
            first_call[label, tol] = timed(simulate_run(model, "taylor", tol))
    hy.llvm_state.set_diskcache_enabled(disk)

    runs = [
        Run("heyoka, hand-written", "tol 1e-12", heyoka_run(system, 1e-12, grid)),
        Run("heyoka, hand-written", "tol 1e-15", heyoka_run(system, 1e-15, grid)),
        Run("taylor (simulate)", "rtol = atol = 1e-12", simulate_run(model, "taylor", 1e-12), "tol 1e-12"),
        Run("taylor (simulate)", "rtol = atol = 1e-15", simulate_run(model, "taylor", 1e-15), "tol 1e-15"),
        Run("DOP853 (simulate)", "rtol = atol = 1e-13", simulate_run(model, "DOP853", 1e-13)),
        Run("cvodes-adams (simulate)", "rtol = atol = 1e-14", simulate_run(model, "cvodes-adams", 1e-14)),
        Run("cvodes (simulate)", "rtol = atol = 1e-12", simulate_run(model, "cvodes", 1e-12)),
    ]
    # Where the time of a taylor simulate() goes: outputs on the grid (front end) besides the runner.
    tr = pl.simulate(model, X0, T_FINAL, dt=DT, method="taylor", rtol=1e-15, atol=1e-15)
    parts: dict[str, list[float]] = {"outputs": [], "map": [], "numpy": []}
    out_fn = model.functions["outputs"]
    numpy_outputs = vectorised_outputs(model)
    y_np = np.asarray(numpy_outputs(tr.x.T, tr.u.T, model.p)).T
    if not np.allclose(y_np, model.outputs(tr.x, tr.u), rtol=1e-13, atol=1e-13):
        raise SystemExit("the vectorised NumPy outputs differ from model.outputs")

    with tqdm(total=len(runs) * (args.repeats + 1), desc="fastpath", unit="run", file=sys.stderr) as bar:
        for r in runs:  # warm-up
            r.x, r.steps, _ = r.fn()
            bar.update()
        for _ in range(args.repeats):
            for r in runs:
                t0 = time.perf_counter()
                _, _, integ = r.fn()
                r.times.append(time.perf_counter() - t0)
                r.integ.append(integ if integ is not None else r.times[-1])
                bar.update()
            parts["outputs"].append(timed(lambda: model.outputs(tr.x, tr.u)))
            parts["map"].append(timed(lambda: out_fn.map(len(grid))))
            parts["numpy"].append(timed(lambda: np.asarray(numpy_outputs(tr.x.T, tr.u.T, model.p)).T))
    # CasADi returns a live mapped Function from its cache: hold one only after the timings above.
    mapped = out_fn.map(len(grid))
    mapped_eval = [timed(lambda: np.asarray(mapped(tr.x.T, tr.u.T, model.p)).T) for _ in range(args.repeats)]

    t_parts = {k: statistics.median(v) for k, v in parts.items()}
    t_parts["map_eval"] = statistics.median(mapped_eval)
    text = render(runs, ref, stride, rhs_diff, first_call, t_parts, info, args.repeats)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)
    return 0


def render(runs: list[Run], ref, stride: int, rhs_diff: float, first_call: dict, t_parts: dict, info: str, repeats: int) -> str:
    hand = {r.settings: r for r in runs if r.label.startswith("heyoka")}
    tight = hand["tol 1e-15"]
    err = {id(r): (float(np.max(np.abs(r.x[-1] - ref.x[-1]))), float(np.max(np.abs(r.x[::stride] - ref.x)))) for r in runs}
    rows = []
    for r in runs:
        same = f"{r.median / hand[r.anchor].median:.2f}" if r.anchor else ""
        rows.append(
            f"| {r.label} | {r.settings} | {r.median * 1e3:.3f} | {statistics.median(r.integ) * 1e3:.3f} | {same} | "
            f"{r.median / tight.median:.2f} | {err[id(r)][0]:.1e} | {err[id(r)][1]:.1e} | {r.steps or 'n/a'} |"
        )
    tay = {r.settings: r for r in runs if r.label.startswith("taylor")}
    t15, t12 = tay["rtol = atol = 1e-15"], tay["rtol = atol = 1e-12"]
    dop = next(r for r in runs if r.label.startswith("DOP853"))
    runner15 = statistics.median(t15.integ)
    t_outputs = t_parts["outputs"]
    rest15 = max(t15.median - runner15 - t_outputs, 0.0)
    projected = t15.median - t_outputs + t_parts["numpy"]
    e15 = err[id(t15)][0]

    def verdict(ok: bool) -> str:
        return "**met**" if ok else "**missed**"

    h12 = hand["tol 1e-12"].median
    run12 = statistics.median(t12.integ)
    targets = [
        (
            "taylor at tight tolerance: final error ≤ 1e-9",
            f"{e15:.1e} (tol 1e-15); {err[id(t12)][0]:.1e} (tol 1e-12)",
            verdict(e15 <= 1e-9),
        ),
        (
            "taylor ≤ 1.5× hand-written heyoka (whole `simulate`)",
            f"{t15.median / tight.median:.2f}× at 1e-15, {t12.median / h12:.2f}× at 1e-12",
            verdict(t15.median <= 1.5 * tight.median),
        ),
        (
            "taylor runner ≤ 1.5× hand-written heyoka (integration only)",
            f"{runner15 / tight.median:.2f}× at 1e-15, {run12 / h12:.2f}× at 1e-12",
            verdict(runner15 <= 1.5 * tight.median),
        ),
        (
            "taylor ≥ 100× faster than DOP853 (whole `simulate`)",
            f"{dop.median / t15.median:.0f}× (taylor 1e-15 vs DOP853 1e-13)",
            verdict(dop.median >= 100 * t15.median),
        ),
        (
            "taylor ≥ 100× faster than DOP853 (integration only)",
            f"{statistics.median(dop.integ) / runner15:.0f}× (taylor 1e-15 vs DOP853 1e-13)",
            verdict(statistics.median(dop.integ) >= 100 * runner15),
        ),
    ]
    target_rows = "\n".join(f"| {a} | {b} | {c} |" for a, b, c in targets)
    header = (
        "| run | settings | time [ms] | integration [ms] | × hand-written, same tol | × hand-written 1e-15 "
        "| final error | grid error | steps |"
    )

    date = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"""# Fast path: `method="taylor"` against a hand-written heyoka system

Generated by `python benchmarks/bench_fastpath.py --repeats {repeats}` on {date}.

Machine: {info}. The machine is shared with other jobs: absolute times are noisy; the
ratios are measured in the same run (interleaved rounds).

**Case.** Rigid model, default parameters (m1 = m2 = 1 kg, L1 = L2 = 1 m, g = 9.81 m/s²),
θ1 = θ2 = 2 rad at rest, 10 s, output every 10 ms (1001 points); chaotic (errors grow ~1e4–1e6).

**Anchor.** A hand-written heyoka system of the standard equations (absolute angles, m = L = 1 and g
folded in as numbers), checked against `model.rhs` at 200 random states: max relative difference
{rhs_diff:.1e}. Timed as `propagate_grid` over the same output grid (no Python around it).

**Reference.** Stored `rigid_chaotic_10s` (Gragg–Bulirsch–Stoer, 32-digit mpmath; accuracy
{ref.accuracy:.1e}). "Final error" = max |x(10 s) − x_ref(10 s)| over the four states; "grid error" = max over
the reference grid (every 50 ms).

**Timing.** Median of {repeats} interleaved rounds after a warm-up round. *Time* is the whole call
(`pl.simulate`: argument checks, integration, outputs on the grid); *integration* is the runner alone
(`Trajectory.stats["wall_time"]`). Ratios divide *time*.

{header}
|---|---|---:|---:|---:|---:|---:|---:|---:|
{chr(10).join(rows)}

**First call** of `method="taylor"` in a process (translation of the CasADi graph + JIT compilation + one
run): {first_call["cold", 1e-12] * 1e3:.0f} ms at 1e-12, {first_call["cold", 1e-15] * 1e3:.0f} ms at 1e-15; with a hit in heyoka's
on-disk JIT cache (a previous process compiled the same structure): {first_call["warm", 1e-12] * 1e3:.0f} ms and
{first_call["warm", 1e-15] * 1e3:.0f} ms. Later calls reuse the compiled integrator (also after `model.with_params(...)`).

## Where the time of `simulate(method="taylor")` goes (tol 1e-15)

| part | time [ms] | share |
|---|---:|---:|
| whole `simulate` call | {t15.median * 1e3:.3f} | 100% |
| Taylor runner (translation cached; set state, `propagate_grid`) | {runner15 * 1e3:.3f} | {runner15 / t15.median:.0%} |
| `model.outputs(X, U)` on the 1001-point grid (front end) | {t_outputs * 1e3:.3f} | {t_outputs / t15.median:.0%} |
| rest of the front end (argument checks, grid, Trajectory) | {rest15 * 1e3:.3f} | {rest15 / t15.median:.0%} |

The hand-written anchor itself takes {tight.median * 1e3:.3f} ms: the runner adds
{(runner15 - tight.median) * 1e3:.3f} ms to it ({runner15 / tight.median:.2f}×; the translated system, parameter setup and
result checks included). Most of the whole call is `simulate`'s evaluation of the outputs, not the runner:
in `model.outputs`, CasADi's `Function.map(1001)` is rebuilt on every call (nothing holds it between calls;
{t_parts["map"] * 1e3:.3f} ms), then evaluates the 1001 points in CasADi's virtual machine
({t_parts["map_eval"] * 1e3:.3f} ms). The same CasADi graph translated to straight-line NumPy over whole columns
(`to_python` with NumPy functions; equal to `model.outputs` to 1e-13) takes {t_parts["numpy"] * 1e3:.3f} ms; with it
the whole call would take about {projected * 1e3:.3f} ms
(**estimate**: measured parts added), {projected / tight.median:.2f}× the anchor.

## Targets

| target | measured | |
|---|---|---|
{target_rows}
"""


if __name__ == "__main__":
    raise SystemExit(main())

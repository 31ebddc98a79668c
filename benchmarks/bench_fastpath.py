"""``method="taylor"`` against a hand-written heyoka system and the other fast methods.

    python benchmarks/bench_fastpath.py [--repeats N] [--inner K] [--out benchmarks/results/fastpath.md]

Cases: rigid model with default parameters (m = 1 kg, L = 1 m, g = 9.81 m/s^2),
theta1 = theta2 = 2 rad at rest, 10 s, output every 10 ms (the chaotic case); elastic model
with default parameters (k1 = k2 = 500 N/m), the same angles, springs at their static lengths.

The anchor of each case is a HAND-WRITTEN heyoka system of the same equations (the standard
double-pendulum equations in absolute angles, typed below with m = L = 1 and
g = 9.81 folded in) propagated over the same output grid; the script first
checks that it equals ``model.rhs`` at random states. Against it:
``pl.simulate(..., method="taylor")`` at tol 1e-12 and 1e-15 (the whole call:
argument checks, integration, outputs on the grid), SciPy DOP853 at
rtol = atol = 1e-13, CVODES Adams at 1e-14 and CVODES BDF at 1e-12.

Timing: every run once as a warm-up (JIT compilation, integrator construction),
then ``--repeats`` rounds in which every run is timed once (``--inner`` calls in a row, their mean: one call
of ~0.5 ms is at the mercy of a single scheduler tick on a shared machine), interleaved so that all see the same
machine load; medians. Errors: against the stored 32-digit
reference ``rigid_chaotic_10s`` (Gragg-Bulirsch-Stoer in mpmath), at t = 10 s
and as the max over the reference grid (every 50 ms).
"""

from __future__ import annotations

import argparse
import copy
import gc
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
from pendulab.integrate.taylor import cache as taylor_cache
from pendulab.integrate.taylor import outputs as taylor_outputs

X0 = np.array([2.0, 2.0, 0.0, 0.0])
T_FINAL = 10.0
DT = 0.01
M1 = M2 = L1 = L2 = 1.0
G = 9.81
OUT = Path(__file__).resolve().parent / "results" / "fastpath.md"
K_EL = 500.0  # default spring stiffness of pl.elastic() [N/m]; rest lengths L1 = L2 = 1 m


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


def hand_written_elastic() -> list[tuple[hy.expression, hy.expression]]:
    """The elastic double pendulum (point masses on linear springs), polar coordinates, typed by hand.

    Newton on each bob, projected on the spring direction e_i = (sin th_i, -cos th_i) and its normal;
    T_i = k (r_i - L0) the spring tensions, d = th1 - th2, m = 1 kg:
    w1' = (-T2 sin d - g sin th1 - 2 v1 w1) / r1,   w2' = (T1 sin d - 2 v2 w2) / r2,
    v1' = -T1 + T2 cos d + g cos th1 + r1 w1^2,      v2' = -2 T2 + T1 cos d + r2 w2^2.
    """
    th1, th2, r1, r2, w1, w2, v1, v2 = hy.make_vars("theta1", "theta2", "r1", "r2", "omega1", "omega2", "v1", "v2")
    t1, t2 = K_EL * (r1 - L1), K_EL * (r2 - L2)
    d = th1 - th2
    sd, cd = hy.sin(d), hy.cos(d)
    dw1 = (-t2 * sd - G * hy.sin(th1) - 2.0 * v1 * w1) / r1
    dw2 = (t1 * sd - 2.0 * v2 * w2) / r2
    dv1 = -t1 + t2 * cd + G * hy.cos(th1) + r1 * w1 * w1
    dv2 = -2.0 * t2 + t1 * cd + r2 * w2 * w2
    return [(th1, w1), (th2, w2), (r1, v1), (r2, v2), (w1, dw1), (w2, dw2), (v1, dv1), (v2, dv2)]


def check_hand_written(model: pl.Model, system: list) -> float:
    """Max relative difference between the hand-written RHS and ``model.rhs`` at 200 random states."""
    f = hy.cfunc([e for _, e in system], [v for v, _ in system])
    rng = np.random.default_rng(7)
    nq = model.nx // 2
    angles = rng.uniform(-np.pi, np.pi, (200, 2))
    lengths = rng.uniform(0.8, 1.2, (200, nq - 2))  # elastic: spring lengths [m]
    X = np.column_stack([angles, lengths, rng.normal(0.0, 4.0, (200, nq))])
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


def heyoka_run(system: list, tol: float, grid: np.ndarray, x0: np.ndarray = X0) -> Callable[[], tuple[np.ndarray, int, None]]:
    ta = hy.taylor_adaptive(system, list(x0), tol=tol)

    def run() -> tuple[np.ndarray, int, None]:
        ta.time = 0.0
        ta.state[:] = x0
        res = ta.propagate_grid(grid)
        return res[-1], int(res[3]), None

    return run


def simulate_run(model: pl.Model, method: str, tol: float, x0: np.ndarray = X0) -> Callable[[], tuple[np.ndarray, int, float]]:
    def run() -> tuple[np.ndarray, int, float]:
        tr = pl.simulate(model, x0, T_FINAL, dt=DT, method=method, rtol=tol, atol=tol)
        return tr.x, int(tr.stats.get("n_steps") or 0), float(tr.stats["wall_time"])

    return run


def floor_run(model: pl.Model, tol: float, grid: np.ndarray, x0: np.ndarray = X0) -> Callable[[], tuple[np.ndarray, int, None]]:
    """pendulab's own compiled integrator and compiled outputs with no Python front end around them: the floor.

    What ``simulate(method="taylor")`` would cost without its argument checks, grid, budget, result checks and
    ``Trajectory``: the difference between the two rows is the front end, measured in the same run.
    """
    entry, pars = taylor_cache.prepared(model.kind, model.p, tuple(range(model.nu)), tol)
    ta = copy.copy(entry.template)
    evaluate = taylor_outputs.output_evaluator(model.kind)
    if evaluate is None:
        raise SystemExit(f"no compiled outputs for the {model.kind} model")
    zero_u = np.zeros((len(grid), model.nu))

    def run() -> tuple[np.ndarray, int, None]:
        ta.time = 0.0
        ta.state[:] = x0
        ta.pars[:] = pars
        res = ta.propagate_grid(grid, max_steps=0)
        evaluate(res[-1], zero_u, model.p)
        return res[-1], int(res[3]), None

    return run


def timed(fn: Callable[[], object], calls: int = 1) -> float:
    """Mean wall time [s] of ``calls`` calls in a row."""
    t0 = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - t0) / calls


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
    ap.add_argument("--inner", type=int, default=10, help="calls per timed sample (their mean), default 10")
    ap.add_argument("--out", type=Path, default=OUT, help=f"Markdown output (default {OUT})")
    args = ap.parse_args(argv)
    if args.repeats < 1 or args.inner < 1:
        ap.error("--repeats and --inner must be >= 1")
    info = machine_info()
    model = pl.rigid()
    elastic = pl.elastic()
    x0_el = elastic.state(theta1=2.0, theta2=2.0)  # springs at their static lengths, at rest
    if not np.allclose(elastic.p[elastic.param_names.index("k1")], K_EL):
        raise SystemExit("pl.elastic()'s default stiffness changed: update K_EL")
    grid = time_grid(T_FINAL, DT)
    ref = load_reference(CASES["rigid_chaotic_10s"])
    stride = int(round((ref.t[1] - ref.t[0]) / DT))
    if not np.allclose(grid[::stride], ref.t, rtol=0, atol=1e-12):
        raise SystemExit("the reference grid is not a subgrid of the output grid")

    system = hand_written_system()
    rhs_diff = check_hand_written(model, system)
    system_el = hand_written_elastic()
    rhs_diff_el = check_hand_written(elastic, system_el)

    # First call of method="taylor" in a process: translation of the CasADi graph plus JIT compilation
    # (heyoka's on-disk cache off: "cold"), or a hit in that cache ("warm"), then one run.
    first_call = {}
    disk = hy.llvm_state.get_diskcache_enabled()
    for label, enabled in (("cold", False), ("warm", disk)):
        hy.llvm_state.set_diskcache_enabled(enabled)
        hy.llvm_state.clear_memcache()
        for tol in (1e-12, 1e-15):
            taylor.clear_cache()
            # As in a new process: the first call evaluates its outputs in NumPy (compiled from the second on).
            taylor_outputs._EVALUATORS.clear()
            taylor_outputs._CALLS.clear()
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
    runs_el = [
        Run("heyoka, hand-written", "tol 1e-12", heyoka_run(system_el, 1e-12, grid, x0_el)),
        Run("heyoka, hand-written", "tol 1e-15", heyoka_run(system_el, 1e-15, grid, x0_el)),
        Run("taylor (simulate)", "rtol = atol = 1e-12", simulate_run(elastic, "taylor", 1e-12, x0_el), "tol 1e-12"),
        Run("taylor (simulate)", "rtol = atol = 1e-15", simulate_run(elastic, "taylor", 1e-15, x0_el), "tol 1e-15"),
    ]
    # The floor of each Taylor row (pendulab's integrator and outputs, no front end): after the rows above compiled them.
    for r in runs + runs_el:
        r.fn()
    floor = "integrator + outputs, no front end"
    for tol in (1e-12, 1e-15):
        runs.append(Run(floor, f"tol {tol:g}", floor_run(model, tol, grid), f"tol {tol:g}"))
        runs_el.append(Run(floor, f"tol {tol:g}", floor_run(elastic, tol, grid, x0_el), f"tol {tol:g}"))
    # Where the time of a taylor simulate() goes besides the runner: the outputs on the grid (compiled, and
    # the NumPy evaluation every other method uses), and the input-check decorator around simulate if any.
    tr = pl.simulate(model, X0, T_FINAL, dt=DT, method="taylor", rtol=1e-15, atol=1e-15)
    inner = getattr(pl.simulate, "__wrapped__", None)
    if inner is not None:  # simulate without its input-check decorator, timed like the other runs

        def inner_run() -> tuple[np.ndarray, int, float]:
            tr = inner(model, X0, T_FINAL, dt=DT, method="taylor", rtol=1e-15, atol=1e-15)
            return tr.x, int(tr.stats["n_steps"]), float(tr.stats["wall_time"])

        runs.insert(4, Run("taylor (`simulate.__wrapped__`)", "rtol = atol = 1e-15", inner_run, "tol 1e-15"))
    parts: dict[str, list[float]] = {"compiled": [], "numpy": [], "front_short": []}

    def front_short() -> float:
        """Time outside the runner of a call as large but 1000x shorter (10 ms, 1001 points): the fixed cost."""
        t0 = time.perf_counter()
        tr = pl.simulate(model, X0, T_FINAL / 1000, dt=DT / 1000, method="taylor", rtol=1e-15, atol=1e-15)
        return time.perf_counter() - t0 - float(tr.stats["wall_time"])

    y_c = taylor_outputs.grid_outputs(model, tr.x, tr.u)
    if not np.allclose(y_c, model.outputs(tr.x, tr.u), rtol=1e-13, atol=1e-13):
        raise SystemExit("the compiled outputs differ from model.outputs")

    every = runs + runs_el
    with tqdm(total=len(every) * (args.repeats + 1), desc="fastpath", unit="run", file=sys.stderr) as bar:
        for r in every:  # warm-up
            r.x, r.steps, _ = r.fn()
            bar.update()
        for _ in range(args.repeats):
            for r in every:
                integ = []
                # As timeit does: no cyclic garbage collection inside a sample. The rounds allocate alike, so the
                # collector would otherwise stop in the same run every round and bias that one row (0.5 ms of a
                # 0.7 ms call was seen); the garbage is collected between samples instead.
                gc.collect()
                gc.disable()
                t0 = time.perf_counter()
                for _ in range(args.inner):
                    integ.append(r.fn()[2])
                r.times.append((time.perf_counter() - t0) / args.inner)
                gc.enable()
                r.integ.append(statistics.fmean(integ) if None not in integ else r.times[-1])
                bar.update()
            parts["compiled"].append(timed(lambda: taylor_outputs.grid_outputs(model, tr.x, tr.u), args.inner))
            parts["numpy"].append(timed(lambda: model.outputs(tr.x, tr.u), args.inner))
            parts["front_short"].append(statistics.fmean(front_short() for _ in range(args.inner)))

    # Elementary operations of each Taylor system (heyoka's decomposition, tol 1e-15): what a step costs.
    ops = {
        kind: len(next(e.template for k, e in taylor_cache._CACHE.items() if k.kind == kind and k.tol == 1e-15).decomposition)
        for kind in ("rigid", "elastic")
    }
    ops_anchor = {
        kind: len(hy.taylor_adaptive(sys_, [0.0] * len(sys_), tol=1e-15).decomposition)
        for kind, sys_ in (("rigid", system), ("elastic", system_el))
    }
    t_parts = {k: statistics.median(v) for k, v in parts.items()}
    timing = (args.repeats, args.inner)
    text = render(runs, runs_el, ref, stride, (rhs_diff, rhs_diff_el), first_call, t_parts, info, timing, (ops, ops_anchor))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)
    return 0


def _table(runs: list[Run], err: dict | None) -> tuple[list[str], dict[str, Run]]:
    hand = {r.settings: r for r in runs if r.label.startswith("heyoka")}
    tight = hand["tol 1e-15"]
    rows = []
    for r in runs:
        same = f"{r.median / hand[r.anchor].median:.2f}" if r.anchor else ""
        if err is not None:
            errs = f"{err[id(r)][0]:.1e} | {err[id(r)][1]:.1e} | "
        else:  # no reference: the difference from the hand-written run at 1e-15
            errs = f"{float(np.max(np.abs(r.x[-1] - tight.x[-1]))):.1e} | "
        rows.append(
            f"| {r.label} | {r.settings} | {r.median * 1e3:.3f} | {statistics.median(r.integ) * 1e3:.3f} | {same} | "
            f"{r.median / tight.median:.2f} | {errs}{r.steps or 'n/a'} |"
        )
    return rows, hand


def render(
    runs: list[Run],
    runs_el: list[Run],
    ref,
    stride: int,
    rhs_diff: tuple,
    first_call: dict,
    t_parts: dict,
    info: str,
    timing: tuple[int, int],
    op_counts: tuple[dict, dict],
) -> str:
    ops, ops_anchor = op_counts
    repeats, inner = timing
    err = {id(r): (float(np.max(np.abs(r.x[-1] - ref.x[-1]))), float(np.max(np.abs(r.x[::stride] - ref.x)))) for r in runs}
    rows, hand = _table(runs, err)
    rows_el, hand_el = _table(runs_el, None)
    tight = hand["tol 1e-15"]
    tay = {r.settings: r for r in runs if r.label.startswith("taylor (simulate)")}
    tay_el = {r.settings: r for r in runs_el if r.label.startswith("taylor")}
    t15, t12 = tay["rtol = atol = 1e-15"], tay["rtol = atol = 1e-12"]
    e15s, e12s = tay_el["rtol = atol = 1e-15"], tay_el["rtol = atol = 1e-12"]
    dop = next(r for r in runs if r.label.startswith("DOP853"))
    kinds = (("rigid", runs), ("elastic", runs_el))
    floors = {(kind, r.settings): r for kind, rs in kinds for r in rs if r.label.startswith("integrator")}
    front = {
        (kind, tol): (sim.median - floors[kind, f"tol {tol}"].median) * 1e3
        for kind, tay_k in (("rigid", tay), ("elastic", tay_el))
        for tol, sim in (("1e-12", tay_k["rtol = atol = 1e-12"]), ("1e-15", tay_k["rtol = atol = 1e-15"]))
    }
    front_text = (
        "**The front end, measured.** The rows *integrator + outputs, no front end* run pendulab's own compiled "
        "integrator and compiled outputs with no Python around them (`floor_run`): what `simulate` would cost without "
        "its argument checks, grid, budgets, result checks and `Trajectory`. The front end is the difference: "
        + ", ".join(f"{kind} {front[kind, tol]:.3f} ms at {tol}" for kind in ("rigid", "elastic") for tol in ("1e-12", "1e-15"))
        + ". For the whole call to stay within 1.1× of the anchor it may spend 0.1× the anchor plus what the "
        "integrator gains on it: "
        + ", ".join(
            f"{kind} {(1.1 * hh[f'tol {tol}'].median - floors[kind, f'tol {tol}'].median) * 1e3:.3f} ms at {tol}"
            for kind, hh in (("rigid", hand), ("elastic", hand_el))
            for tol in ("1e-12", "1e-15")
        )
        + "."
    )
    runner15 = statistics.median(t15.integ)
    t_out = t_parts["compiled"]
    rest15 = max(t15.median - runner15 - t_out, 0.0)
    e15 = err[id(t15)][0]
    h12 = hand["tol 1e-12"].median
    run12 = statistics.median(t12.integ)

    def ratio(r: Run, h: dict[str, Run]) -> float:
        return r.median / h[r.anchor].median

    def verdict(ok: bool) -> str:
        return "**met**" if ok else "**missed**"

    worst = max(ratio(t15, hand), ratio(t12, hand), ratio(e15s, hand_el), ratio(e12s, hand_el))
    targets = [
        (
            "taylor at tight tolerance: final error ≤ 1e-9",
            f"{e15:.1e} (tol 1e-15); {err[id(t12)][0]:.1e} (tol 1e-12)",
            verdict(e15 <= 1e-9),
        ),
        (
            "taylor ≤ 1.1× hand-written heyoka, same tolerance (whole `simulate`, rigid and elastic)",
            f"rigid {ratio(t15, hand):.2f}× at 1e-15, {ratio(t12, hand):.2f}× at 1e-12; "
            f"elastic {ratio(e15s, hand_el):.2f}× at 1e-15, {ratio(e12s, hand_el):.2f}× at 1e-12",
            verdict(worst <= 1.1),
        ),
        (
            "taylor runner ≤ 1.5× hand-written heyoka (integration only)",
            f"rigid {runner15 / tight.median:.2f}× at 1e-15, {run12 / h12:.2f}× at 1e-12; elastic "
            f"{statistics.median(e15s.integ) / hand_el['tol 1e-15'].median:.2f}× at 1e-15, "
            f"{statistics.median(e12s.integ) / hand_el['tol 1e-12'].median:.2f}× at 1e-12",
            verdict(
                max(
                    runner15 / tight.median,
                    run12 / h12,
                    *(statistics.median(r.integ) / hand_el[r.anchor].median for r in (e15s, e12s)),
                )
                <= 1.5
            ),
        ),
        (
            "taylor ≥ 100× faster than DOP853 (whole `simulate`)",
            f"{dop.median / t15.median:.0f}× (taylor 1e-15 vs DOP853 1e-13)",
            verdict(dop.median >= 100 * t15.median),
        ),
    ]
    target_rows = "\n".join(f"| {a} | {b} | {c} |" for a, b, c in targets)
    header = "| run | settings | time [ms] | integration [ms] | × hand-written, same tol | × hand-written 1e-15 |"
    wrapped = next((r for r in runs if "__wrapped__" in r.label), None)
    if wrapped is not None:
        deco = t15.median - wrapped.median
        deco_text = (
            "`simulate` is wrapped by the input-check decorator `pendulab._inputs.checked`; the undecorated function "
            f"(`pl.simulate.__wrapped__`, row above) takes {wrapped.median * 1e3:.3f} ms "
            f"({wrapped.median / tight.median:.2f}× the anchor): the decorator costs about {deco * 1e3:.3f} ms per call."
        )
    else:
        deco_text = "`simulate` has no input-check decorator in this version."

    date = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return f"""# Fast path: `method="taylor"` against a hand-written heyoka system

Generated by `python benchmarks/bench_fastpath.py --repeats {repeats} --inner {inner}` on {date}.

Machine: {info}. The machine is shared with other jobs: absolute times are noisy; the
ratios are measured in the same run (interleaved rounds).

**Timing.** Median of {repeats} interleaved rounds after a warm-up round (every run of both cases timed once per
round, as the mean of {inner} calls in a row, with Python's cyclic garbage collector paused as `timeit` does).
*Time* is the whole call (`pl.simulate`: argument checks, integration, outputs on the grid);
*integration* is the runner alone (`Trajectory.stats["wall_time"]`). Ratios divide *time*. The anchors are
`propagate_grid` of a hand-written heyoka system over the same output grid (no Python around it).

## Rigid, chaotic

Default parameters (m1 = m2 = 1 kg, L1 = L2 = 1 m, g = 9.81 m/s²), θ1 = θ2 = 2 rad at rest, 10 s, output every
10 ms (1001 points); chaotic (errors grow ~1e4–1e6). Anchor: the standard equations in absolute angles (m = L = 1
and g folded in as numbers), equal to `model.rhs` at 200 random states to {rhs_diff[0]:.1e} (relative).
Reference: stored `rigid_chaotic_10s` (Gragg–Bulirsch–Stoer, 32-digit mpmath; accuracy {ref.accuracy:.1e}).
"Final error" = max |x(10 s) − x_ref(10 s)|; "grid error" = max over the reference grid (every 50 ms).

{header} final error | grid error | steps |
|---|---|---:|---:|---:|---:|---:|---:|---:|
{chr(10).join(rows)}

## Elastic

Default parameters (point masses 1 kg on springs of rest length 1 m, k1 = k2 = {K_EL:.0f} N/m), θ1 = θ2 = 2 rad at
rest with the springs at their static lengths, 10 s, output every 10 ms. Anchor: Newton's law of each bob
projected on its spring and the normal (no mass matrix to invert; see `hand_written_elastic`), equal to
`model.rhs` at 200 random states to {rhs_diff[1]:.1e} (relative). No stored reference: "final difference" is
max |x(10 s) − x_hand,1e-15(10 s)|.

The translated system has {ops["elastic"]} elementary operations (heyoka's decomposition) against the anchor's
{ops_anchor["elastic"]}. pendulab derives it from Lagrange's equations with the mass matrix factored through the
bobs' Jacobian (`pendulab.model.lagrange.point_mass_accelerations`: two 2 x 2 block substitutions); the
generic solve with the 4 x 4 mass matrix gave 307 operations and 10.66× the anchor's whole-call time (recorded
2026-11-28 07:23 UTC); then 130 operations (4.66×) until the translator (`pendulab.integrate.taylor.algebra`)
learned to key each sine/cosine by its angle as a canonical linear combination (one pair per distinct angle), to
cancel a reciprocal against its factor (the block inverses' `r * (x / r)`), to keep a spring force as
`k (r - L)` and to give an opposite coefficient its own parameter (heyoka treats `-par` as a series): 130 -> 51,
with as many products, divisions and sine/cosine pairs as the anchor (`tests/integrate/test_taylor_translate.py`).

{header} final difference | steps |
|---|---|---:|---:|---:|---:|---:|---:|
{chr(10).join(rows_el)}

{front_text}

**First call** of `method="taylor"` in a process (translation of the CasADi graph + JIT compilation of the
integrator and of the outputs + one run): {first_call["cold", 1e-12] * 1e3:.0f} ms at 1e-12,
{first_call["cold", 1e-15] * 1e3:.0f} ms at 1e-15; with a hit in heyoka's on-disk JIT cache (a previous process
compiled the same structure): {first_call["warm", 1e-12] * 1e3:.0f} ms and
{first_call["warm", 1e-15] * 1e3:.0f} ms. Later calls reuse the compiled integrator (also after `model.with_params(...)`).

## Where the time of `simulate(method="taylor")` goes (rigid, tol 1e-15)

| part | time [ms] | share |
|---|---:|---:|
| whole `simulate` call | {t15.median * 1e3:.3f} | 100% |
| Taylor runner (cached integrator; set state, `propagate_grid`) | {runner15 * 1e3:.3f} | {runner15 / t15.median:.0%} |
| outputs on the 1001-point grid (compiled heyoka `cfunc`) | {t_out * 1e3:.3f} | {t_out / t15.median:.0%} |
| rest of the front end (argument checks, grid, Trajectory) | {rest15 * 1e3:.3f} | {rest15 / t15.median:.0%} |

The hand-written anchor takes {tight.median * 1e3:.3f} ms; the runner {runner15 / tight.median:.2f}× that (the translated
system has {ops["rigid"]} elementary operations against the anchor's {ops_anchor["rigid"]}). The outputs are the
model's CasADi graph replayed as
heyoka expressions and compiled once per model kind (a `cfunc` in batch mode): {t_out * 1e3:.3f} ms for 1001
points, against {t_parts["numpy"] * 1e3:.3f} ms for `model.outputs` (element-wise NumPy, what the other methods use).
{deco_text}
The same call over 10 ms instead of 10 s (1001 output points, a few Taylor steps) spends {t_parts["front_short"] * 1e3:.3f} ms
outside its runner, against {(t15.median - runner15) * 1e3:.3f} ms here: the front end (checks, grid, outputs, Trajectory)
costs about that much per call of this size however long the run; what the 10 s call spends beyond it is the cost of
caches the long integration emptied.

## Targets

| target | measured | |
|---|---|---|
{target_rows}
"""


if __name__ == "__main__":
    raise SystemExit(main())

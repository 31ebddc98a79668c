"""Ensemble throughput on the rigid flip map: local threads, Dask workers, a hand-written heyoka loop.

The workload is the set of runs the rigid flip map really integrates
(:func:`pendulab.ensemble.flipmap.flip_map`: grid points with enough energy to
flip, one of each mirror pair), released at rest, integrated with
``method="taylor"`` to the first flip or ``t_max``. Every configuration runs
the same initial states (or the same seeded random subset of them), so the
throughputs (runs/s) and their ratios come from one run of this module.

The peer is a **hand-written single-core heyoka loop**: the textbook
point-mass rigid equations typed here (and only here: the benchmark checks
them against ``model.rhs`` before use), a terminal event
``theta_i**2 - pi**2`` per link, one initial condition after another on one
``taylor_adaptive`` object. It is what a user would write by hand, so the
engine's ratio to it shows what its chunking, threads and workers buy.
"""

from __future__ import annotations

import math
import os
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import check_budget, require_extra

__all__ = [
    "EnsembleBench",
    "hand_written_rigid",
    "check_hand_written",
    "hand_loop",
    "flipmap_workload",
    "run_ensemble_bench",
    "time_cli",
    "elastic_rigid_ratio",
    "ensemble_markdown",
]


def hand_written_rigid(params: Any) -> tuple[list[tuple[Any, Any]], Any]:
    """The textbook rigid double pendulum (point masses), typed by hand as heyoka expressions.

    Parameters
    ----------
    params : RigidParams
        Point-mass parameters (``lc = L``, ``I = 0``, no dampers).

    Returns
    -------
    system : list of (variable, expression)
        heyoka ODE system in the state order (theta1, theta2, omega1, omega2).
    variables : tuple
        The heyoka variables ``(theta1, theta2, omega1, omega2)``.

    Raises
    ------
    ValueError
        Parameters with distributed mass or dampers (not covered by these equations).
    """
    hy = require_extra("heyoka", "taylor", "the ensemble benchmark")

    pr = params.resolved()
    if pr["lc1"] != pr["L1"] or pr["lc2"] != pr["L2"] or pr["I1"] or pr["I2"] or pr["b1"] or pr["b2"]:
        raise ValueError(f"the hand-written equations cover point masses without dampers only, got {params!r}")
    m1, m2, L1, L2, g = (pr[k] for k in ("m1", "m2", "L1", "L2", "g"))
    th1, th2, w1, w2 = hy.make_vars("theta1", "theta2", "omega1", "omega2")
    d = th1 - th2
    den = 2 * m1 + m2 - m2 * hy.cos(2 * th1 - 2 * th2)
    a1 = (
        -g * (2 * m1 + m2) * hy.sin(th1)
        - m2 * g * hy.sin(th1 - 2 * th2)
        - 2 * hy.sin(d) * m2 * (w2**2 * L2 + w1**2 * L1 * hy.cos(d))
    ) / (L1 * den)
    a2 = (2 * hy.sin(d) * (w1**2 * L1 * (m1 + m2) + g * (m1 + m2) * hy.cos(th1) + w2**2 * L2 * m2 * hy.cos(d))) / (L2 * den)
    return [(th1, w1), (th2, w2), (w1, a1), (w2, a2)], (th1, th2, w1, w2)


def check_hand_written(model: Any, n: int = 50, seed: int = 0) -> float:
    """Largest difference between the hand-written equations and ``model.rhs`` at random states.

    Parameters
    ----------
    model : Model
        Rigid point-mass model.
    n : int
        Number of random states (angles in (-pi, pi), rates in (-10, 10) rad/s).
    seed : int
        Random seed.

    Returns
    -------
    float
        max |f_hand - f_model| over the states, relative to max(1, |f_model|).
    """
    hy = require_extra("heyoka", "taylor", "the ensemble benchmark")

    system, variables = hand_written_rigid(model.params)
    f = hy.cfunc([e for _, e in system], vars=list(variables))
    rng = np.random.default_rng(seed)
    X = np.column_stack([rng.uniform(-math.pi, math.pi, (n, 2)), rng.uniform(-10, 10, (n, 2))])
    ours = np.asarray(f(np.ascontiguousarray(X.T))).T
    ref = np.asarray(model.rhs(X)).reshape(n, 4)
    return float(np.max(np.abs(ours - ref) / np.maximum(1.0, np.abs(ref))))


def hand_loop(model: Any, x0: np.ndarray, t_max: float, tol: float = 1e-12) -> tuple[np.ndarray, float]:
    """Time to the first flip of each initial state, one after another on one core.

    Parameters
    ----------
    model : Model
        Rigid point-mass model.
    x0 : ndarray, shape (N, 4)
        Initial states.
    t_max : float
        Horizon [s].
    tol : float
        heyoka tolerance.

    Returns
    -------
    t_flip : ndarray, shape (N,)
        Flip times [s], NaN when no flip before ``t_max``.
    wall : float
        Wall time of the loop [s] (compilation excluded).

    Raises
    ------
    RuntimeError
        heyoka stopped for another reason than a flip or ``t_max``.
    """
    hy = require_extra("heyoka", "taylor", "the ensemble benchmark")

    system, (th1, th2, _, _) = hand_written_rigid(model.params)
    events = [hy.t_event(th1**2 - math.pi**2), hy.t_event(th2**2 - math.pi**2)]
    ta = hy.taylor_adaptive(system, [0.0] * 4, tol=tol, t_events=events)
    out = np.full(len(x0), np.nan)
    limit = hy.taylor_outcome.time_limit
    t0 = time.perf_counter()
    for i, x in enumerate(x0):
        ta.time = 0.0
        ta.state[:] = x
        outcome = ta.propagate_until(t_max)[0]
        if outcome == limit:
            continue
        if int(outcome) < 0 and int(outcome) > -10:  # -1 - event index: a terminal event
            out[i] = ta.time
            continue
        raise RuntimeError(f"hand-written heyoka loop: run {i} from {x.tolist()} stopped with {outcome} at t = {ta.time}")
    return out, time.perf_counter() - t0


def flipmap_workload(model: Any, grid: int, t_max: float) -> np.ndarray:
    """The initial states the flip map integrates (enough energy to flip; one of each mirror pair).

    Parameters
    ----------
    model : Model
        Rigid or elastic model.
    grid : int
        Points per angle.
    t_max : float
        Horizon [s] (only for the signature symmetry with :func:`flip_map`).

    Returns
    -------
    ndarray, shape (N, nx)
        Initial states, in grid order.
    """
    from ..ensemble.flipmap import flip_energy_threshold, flip_initial_states, flip_map_grid

    del t_max
    th = flip_map_grid(grid)
    T1, T2 = np.meshgrid(th, th, indexing="ij")
    x0 = flip_initial_states(model, T1.ravel(), T2.ravel())
    V0 = np.asarray(model.potential_energy(x0), dtype=float)
    thr = flip_energy_threshold(model)
    flat = np.arange(grid * grid).reshape(grid, grid)
    keep = (V0 >= thr - 1e-9 * (abs(thr) + np.max(np.abs(V0)))) & (flat <= flat[::-1, ::-1]).ravel()
    return x0[keep]


@dataclass
class EnsembleBench:
    """Results of :func:`run_ensemble_bench`.

    Attributes
    ----------
    grid, t_max : int, float
        Flip-map grid and horizon [s].
    n_runs : int
        Runs per timed ensemble.
    n_workload : int
        Runs of the full flip-map workload (``n_runs`` may be a subset).
    rows : list of dict
        One per configuration: ``name``, ``runs``, ``times`` [s], ``median`` [s], ``throughput`` [runs/s].
    hand_error : float
        :func:`check_hand_written` of the hand-written equations.
    agreement : dict
        Flip/no-flip agreement and flip-time differences between the engine and the hand loop.
    extra : dict
        CLI timing and elastic/rigid ratio, when measured.
    """

    grid: int
    t_max: float
    n_runs: int
    n_workload: int
    rows: list[dict[str, Any]] = field(default_factory=list)
    hand_error: float = float("nan")
    agreement: dict[str, Any] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)

    def row(self, name: str) -> dict[str, Any] | None:
        """The row named ``name``, or None.

        Parameters
        ----------
        name : str
            Configuration name.

        Returns
        -------
        dict or None
            The row.
        """
        return next((r for r in self.rows if r["name"] == name), None)


def _timed(fn: Callable[[], Any], repeats: int) -> tuple[list[float], Any]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return times, out


def run_ensemble_bench(
    *,
    grid: int = 400,
    t_max: float = 10.0,
    runs: int | None = None,
    hand_runs: int | None = None,
    repeats: int = 3,
    threads: Sequence[int] = (1, 2),
    workers: Sequence[int] = (1, 2),
    seed: int = 0,
    progress: Callable[[int, int, str], Any] | None = None,
) -> EnsembleBench:
    """Measure runs/s of the ensemble engine (threads, Dask workers) and of the hand-written loop.

    Parameters
    ----------
    grid : int
        Flip-map grid (points per angle) defining the workload.
    t_max : float
        Horizon [s].
    runs : int, optional
        Use a seeded random subset of this many runs of the workload (default all).
    hand_runs : int, optional
        Runs of the hand-written loop (a subset of the engine's runs; default all of them).
    repeats : int
        Timed repetitions per configuration; medians are reported.
    threads : sequence of int
        Local thread counts.
    workers : sequence of int
        Dask LocalCluster worker processes (one thread each); empty to skip Dask.
    seed : int
        Seed of the subsets.
    progress : callable(done, total, label), optional
        Progress callback.

    Returns
    -------
    EnsembleBench
        Rows per configuration and the agreement check.

    Raises
    ------
    BudgetError
        ``grid ** 2``, ``runs`` or ``hand_runs`` beyond the runs budget (``PENDULAB_MAX_RUNS``), or
        ``repeats`` beyond the repetitions budget (``PENDULAB_MAX_REPEATS``); checked before any work.
    MissingExtraError
        heyoka (``pendulab[taylor]``) or, with ``workers``, dask.distributed (``pendulab[dask]``)
        is not installed; the message names the extra.
    """
    # Budgets before any import or integration: grid^2 runs, each timed `repeats` times.
    check_budget("runs", "grid", grid, float(grid) ** 2)
    for name, value in (("runs", runs), ("hand_runs", hand_runs)):
        if value is not None:
            check_budget("runs", name, value)
    check_budget("repeats", "repeats", repeats)
    require_extra("heyoka", "taylor", "pendulab bench ensemble")
    if workers:
        require_extra("dask.distributed", "dask", "pendulab bench ensemble --workers (Dask rows)")
    from ..ensemble.engine import ensemble
    from ..model.model import rigid

    model = rigid()
    work = flipmap_workload(model, grid, t_max)
    rng = np.random.default_rng(seed)
    x0 = work if runs is None or runs >= len(work) else work[np.sort(rng.choice(len(work), runs, replace=False))]
    nh = len(x0) if hand_runs is None else min(hand_runs, len(x0))
    hand_idx = np.sort(rng.choice(len(x0), nh, replace=False)) if nh < len(x0) else np.arange(len(x0))
    bench = EnsembleBench(grid=grid, t_max=t_max, n_runs=len(x0), n_workload=len(work))
    bench.hand_error = check_hand_written(model)
    steps = [f"local {t} thread{'s' if t > 1 else ''}" for t in threads]
    steps += [f"dask {w} worker{'s' if w > 1 else ''}" for w in workers] + ["hand-written heyoka loop, 1 core"]
    done = 0

    def tick(label: str) -> None:
        nonlocal done
        if progress is not None:
            progress(done, len(steps), label)

    engine_tf = None
    ensemble(model, x0[: min(50, len(x0))], t_max, events=["flip"], threads=1)  # compile once
    for t in threads:
        name = steps[done]
        tick(name)
        times, res = _timed(lambda t=t: ensemble(model, x0, t_max, events=["flip"], threads=t, rtol=1e-12, atol=1e-12), repeats)
        engine_tf = np.asarray(res.event_times["flip"], float)
        bench.rows.append(_row(name, len(x0), times))
        done += 1
    for w in workers:
        name = steps[done]
        tick(name)
        dd = require_extra("dask.distributed", "dask", "the ensemble benchmark's Dask rows (--workers)")
        Client, LocalCluster = dd.Client, dd.LocalCluster  # noqa: N806

        with (
            LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
            Client(cluster) as client,
        ):
            ensemble(model, x0[: min(50 * w, len(x0))], t_max, events=["flip"], client=client, chunk_size=50)  # warm-up
            times, res = _timed(
                lambda c=client: ensemble(model, x0, t_max, events=["flip"], client=c, rtol=1e-12, atol=1e-12), repeats
            )
        tf = np.asarray(res.event_times["flip"], float)
        if engine_tf is not None:
            bench.agreement[f"{name} vs local"] = _agree(tf, engine_tf)
        bench.rows.append(_row(name, len(x0), times))
        done += 1
    name = steps[done]
    tick(name)
    hand_times, hand_tf = [], None
    for _ in range(repeats):
        hand_tf, wall = hand_loop(model, x0[hand_idx], t_max)
        hand_times.append(wall)
    bench.rows.append(_row(name, nh, hand_times))
    if engine_tf is not None:
        bench.agreement["hand loop vs local"] = _agree(hand_tf, engine_tf[hand_idx])
    done += 1
    tick("done")
    return bench


def _row(name: str, runs: int, times: list[float]) -> dict[str, Any]:
    med = statistics.median(times)
    return {"name": name, "runs": runs, "times": times, "median": med, "throughput": runs / med}


def _agree(a: np.ndarray, b: np.ndarray) -> dict[str, Any]:
    same_class = np.isnan(a) == np.isnan(b)
    both = ~np.isnan(a) & ~np.isnan(b)
    diff = np.abs(a[both] - b[both])
    return {
        "runs": int(a.size),
        "same flip/no-flip": float(np.mean(same_class)),
        "flip time within 1e-6 s": float(np.mean(diff <= 1e-6)) if diff.size else 1.0,
        "median |dt| [s]": float(np.median(diff)) if diff.size else 0.0,
    }


def time_cli(args: Sequence[str], out: str | Path, repeats: int = 1) -> dict[str, Any]:
    """Wall time of one ``pendulab`` command in a fresh process (imports and compilation included).

    Parameters
    ----------
    args : sequence of str
        Arguments after ``pendulab``; ``--out OUT --no-progress`` is appended.
    out : str or Path
        Output directory.
    repeats : int
        Runs of the command with the disk cache on (medians reported, each run in a fresh process).

    Returns
    -------
    dict
        ``command``, ``wall`` [s] and ``cpu`` [s] (user + system of the command and its worker processes;
        medians over ``repeats``), ``walls`` (every run), ``stdout`` (of the last run); ``cold_wall``,
        ``cold_cpu``: the same command once with heyoka's on-disk JIT cache disabled (every compilation done
        from scratch, as on a machine where that cache is missing or not writable).

    Raises
    ------
    RuntimeError
        The command failed.
    """
    tail = [*args, "--out", str(out), "--no-progress"]
    # Disk cache off in the command's process; forked workers inherit the setting.
    no_cache = "import sys, heyoka; heyoka.llvm_state.set_diskcache_enabled(False); from pendulab._entry import run; run()"
    result: dict[str, Any] = {"command": "pendulab " + " ".join(args)}
    runs = [("cold_", [sys.executable, "-c", no_cache, *tail])] + [("", [sys.executable, "-m", "pendulab", *tail])] * int(repeats)
    walls: dict[str, list[float]] = {"cold_": [], "": []}
    cpus: dict[str, list[float]] = {"cold_": [], "": []}
    for label, cmd in runs:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
        walls[label].append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if proc.returncode:
            raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): {proc.stderr.strip()[-300:]}")
        cpus[label].append((after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime))
        result[f"{label}stdout"] = proc.stdout.strip()
    for label in walls:
        result[f"{label}wall"] = float(np.median(walls[label]))
        result[f"{label}cpu"] = float(np.median(cpus[label]))
    result["walls"] = walls[""]
    return result


def elastic_rigid_ratio(grid: int, t_max: float, k: float, threads: int | None = None) -> dict[str, Any]:
    """Wall time of the elastic flip map (k1 = k2 = k) against the rigid one on the same grid.

    Parameters
    ----------
    grid : int
        Points per angle.
    t_max : float
        Horizon [s].
    k : float
        Spring stiffness [N/m].
    threads : int, optional
        Local threads.

    Returns
    -------
    dict
        ``rigid`` and ``elastic`` wall times [s] (second of two calls, so compilation is excluded),
        runs integrated, and ``ratio``.
    """
    from ..ensemble.flipmap import flip_map
    from ..model.model import elastic, rigid

    out: dict[str, Any] = {"grid": grid, "t_max": t_max, "k": k}
    for name, model in (("rigid", rigid()), ("elastic", elastic(k1=k, k2=k))):
        flip_map(model, 5, 0.1, threads=threads)  # compile
        m = flip_map(model, grid, t_max, threads=threads)
        out[name] = m.wall_time
        out[f"{name} runs"] = m.n_simulated
        out[f"{name} flipped"] = float(np.mean(m.flipped))
    out["ratio"] = out["elastic"] / out["rigid"]
    return out


def ensemble_markdown(bench: EnsembleBench) -> str:
    """The results as Markdown (throughputs, ratios, agreement, CLI and elastic timings).

    Parameters
    ----------
    bench : EnsembleBench
        Results.

    Returns
    -------
    str
        Markdown text.
    """
    hand = bench.row("hand-written heyoka loop, 1 core")
    local2 = next((r for r in bench.rows if r["name"] == "local 2 threads"), None)
    lines = [
        "# Ensemble throughput on the rigid flip map",
        "",
        f"Workload: the runs the rigid flip map integrates on a {bench.grid} x {bench.grid} grid, t_max = "
        f"{bench.t_max:g} s (enough energy to flip, one of each mirror pair: {bench.n_workload} runs); "
        + (
            f"timed on all {bench.n_runs}."
            if bench.n_runs == bench.n_workload
            else f"timed on a seeded random subset of {bench.n_runs}."
        ),
        f"Machine: {os.cpu_count()} logical CPUs. Medians of {len(bench.rows[0]['times']) if bench.rows else 0} "
        "repeats; all rows measured in one run of `pendulab bench ensemble`.",
        f"Hand-written equations checked against `model.rhs`: max relative difference {bench.hand_error:.1e}.",
        "",
        "| configuration | runs | median wall [s] | throughput [runs/s] | vs hand loop | vs local 2 threads |",
        "|---|---|---|---|---|---|",
    ]
    for r in bench.rows:
        vs_hand = f"{r['throughput'] / hand['throughput']:.2f}x" if hand else "-"
        vs_l2 = f"{r['throughput'] / local2['throughput']:.0%}" if local2 else "-"
        lines.append(f"| {r['name']} | {r['runs']} | {r['median']:.2f} | {r['throughput']:.0f} | {vs_hand} | {vs_l2} |")
    if bench.agreement:
        lines += ["", "Agreement of the flip times (same initial states):", ""]
        lines += [
            "| pair | runs | same flip/no-flip | flip time within 1e-6 s | median abs difference [s] |",
            "|---|---|---|---|---|",
        ]
        for k, a in bench.agreement.items():
            lines.append(
                f"| {k} | {a['runs']} | {a['same flip/no-flip']:.2%} | {a['flip time within 1e-6 s']:.2%} | "
                f"{a['median |dt| [s]']:.1e} |"
            )
    cli = bench.extra.get("cli")
    if cli:
        runs = len(cli.get("walls", [cli["wall"]]))
        lines += [
            "",
            "## Whole CLI command",
            "",
            f"`{cli['command']}` in a fresh process, median of {runs}: **{cli['wall']:.2f} s** wall "
            f"({', '.join(f'{w:.2f}' for w in cli.get('walls', [cli['wall']]))})",
        ]
        if "cpu" in cli:
            lines[-1] += (
                f", {cli['cpu']:.1f} s of CPU (command and workers). With heyoka's on-disk JIT cache disabled (every "
                f"compilation from scratch): {cli['cold_wall']:.1f} s wall, {cli['cold_cpu']:.1f} s of CPU"
            )
        lines[-1] += "."
        lines += ["", "```text", cli["stdout"], "```"]
    er = bench.extra.get("elastic")
    if er:
        lines += [
            "",
            "## Elastic against rigid",
            "",
            f"Flip map {er['grid']} x {er['grid']}, t_max = {er['t_max']:g} s, k1 = k2 = {er['k']:g} N/m (quasi-static start): "
            f"rigid {er['rigid']:.2f} s ({er['rigid runs']} runs), elastic {er['elastic']:.2f} s ({er['elastic runs']} runs): "
            f"**{er['ratio']:.1f}x**.",
        ]
    return "\n".join(lines) + "\n"

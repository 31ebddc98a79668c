"""Markdown tables of a :class:`~.leaderboard.LeaderboardRun`: each protocol beside its published rows."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from .leaderboard import TASKS, Case, LeaderboardRun
from .leaderboard_published import (
    PUBLISHED_ROBUSTNESS_ROWS,
    PUBLISHED_V2_ROWS,
    PUBLISHED_V3_ROWS,
    SOURCES,
)
from .robustness_grid import CATEGORIES

__all__ = ["protocol_tables", "CATEGORY_HEADERS"]

#: Column headers of the robustness-v2 categories (upstream's page names).
CATEGORY_HEADERS: Mapping[str, str] = {
    "model": "model",
    "measurement_noise": "vel. noise",
    "u_noise": "torque noise",
    "u_responsiveness": "torque resp.",
    "delay": "delay",
    "perturbation": "perturb.",
}


def _ms(seconds: float | None) -> str:
    if seconds is None or not math.isfinite(seconds):
        return "—"
    return f"{1e3 * seconds:.3f}" if seconds < 1e-2 else f"{1e3 * seconds:.1f}"


def _cell_note(case: Case, ncols: int) -> str:
    text = f"{case.status} ({case.reason})" if case.reason else case.status
    return f"| pendulab `{case.controller}` | {text} |" + " |" * (ncols - 2)


def _v2_table(run: LeaderboardRun, task: str) -> list[str]:
    head = ["entry", "success", "swing-up time [s]", "energy [J]", "torque cost [N² m² s]", "smoothness [N m]",
            "velocity cost [rad²/s]", "score", "wall time [s]", "controller per call: median / max [ms] (period)"]  # fmt: skip
    rows: list[tuple[float, str]] = []
    for name in run.controllers("v2"):
        case = run.case("v2", task, name)
        if case.status != "done":
            rows.append((-1.0, _cell_note(case, len(head))))
            continue
        d = case.summary
        c = d["criteria"]
        ct = d["controller_time"]
        rows.append((
            d["score"],
            f"| **pendulab `{name}`** | {int(d['success'])} | {c['swingup_time']:.3f} | {c['energy']:.2f} | "
            f"{c['torque_cost']:.3f} | {c['torque_smoothness']:.4f} | {c['velocity_cost']:.1f} | **{d['score']:.3f}** | "
            f"{d['wall_time']:.1f} | {_ms(ct['median_per_call'])} / {_ms(ct['max_per_call'])} ({_ms(ct['sample_time'])}) |",
        ))  # fmt: skip
    for p in PUBLISHED_V2_ROWS[task]:
        v = p.values
        rows.append((
            p.score or 0.0,
            f"| published {p.label} (`{p.name}`) | 1 | {v['swingup_time']:g} | {v['energy']:g} | {v['torque_cost']:g} | "
            f"{v['torque_smoothness']:g} | {v['velocity_cost']:g} | {p.score:.3f} | | |",
        ))  # fmt: skip
    rows.sort(key=lambda r: -r[0])
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head), *(r for _, r in rows)]


def _robustness_table(run: LeaderboardRun, task: str) -> list[str]:
    head = ["entry", *(CATEGORY_HEADERS[c] for c in CATEGORIES), "score", "runs", "wall time [s]",
            "controller per call: median / max [ms] (period)"]  # fmt: skip
    rows: list[tuple[float, str]] = []
    for name in run.controllers("robustness-v2"):
        case = run.case("robustness-v2", task, name)
        if case.status != "done":
            rows.append((-1.0, _cell_note(case, len(head))))
            continue
        d = case.summary
        rates = " | ".join(f"{100 * d['rates'][c]:.1f}" if c in d["rates"] else "—" for c in CATEGORIES)
        score = d["score"]
        ct = d["controller_time"]
        s = "—" if score is None else f"**{score:.3f}**"
        rows.append((
            -0.5 if score is None else score,
            f"| **pendulab `{name}`** | {rates} | {s} | {d['runs']} | {d['wall_total']:.0f} | "
            f"{_ms(ct['median_per_call'])} / {_ms(ct['max_per_call'])} ({_ms(ct['sample_time'])}) |",
        ))  # fmt: skip
    for p in PUBLISHED_ROBUSTNESS_ROWS[task]:
        rates = " | ".join(f"{100 * p.values[c]:.1f}" for c in CATEGORIES)
        rows.append((p.score or 0.0, f"| published {p.label} (`{p.name}`) | {rates} | {p.score:.3f} | 722 | | |"))
    rows.sort(key=lambda r: -r[0])
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head), *(r for _, r in rows)]


def _v3_table(run: LeaderboardRun, task: str) -> list[str]:
    seeds = list(run.settings.v3_seeds)
    head = ["entry", *(f"seed {s}" for s in seeds), "mean", "swing-ups (mean)", "wall time [s]",
            "controller per call: median / max [ms] (period 2 ms)"]  # fmt: skip
    rows: list[tuple[float, str]] = []
    for name in run.controllers("v3"):
        case = run.case("v3", task, name)
        if case.status != "done":
            rows.append((-1.0, _cell_note(case, len(head))))
            continue
        ss: list[dict[str, Any]] = case.summary["seeds"]
        med = [s["controller_time"]["median_s"] for s in ss if s["controller_time"]["median_s"] is not None]
        mx = [s["controller_time"]["max_s"] for s in ss if s["controller_time"]["max_s"] is not None]
        per = " | ".join(f"{s['uptime_fraction']:.3f}" for s in ss)
        swing = sum(s["n_swingups"] for s in ss) / len(ss)
        wall = sum(s["wall_time_s"] for s in ss)
        rows.append((
            case.summary["mean"],
            f"| **pendulab `{name}`** | {per} | **{case.summary['mean']:.3f}** | {swing:.1f} | {wall:.0f} | "
            f"{_ms(max(med) if med else None)} / {_ms(max(mx) if mx else None)} |",
        ))  # fmt: skip
    for p in PUBLISHED_V3_ROWS[task]:
        cells = " | ".join("" for _ in seeds)
        score = "score not in the stored sources" if p.score is None else f"{p.score:.3f} (one unseeded run)"
        rows.append((p.score if p.score is not None else -2.0, f"| published {p.label} (`{p.name}`) | {cells} | {score} | | | |"))
    rows.sort(key=lambda r: -r[0])
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head), *(r for _, r in rows)]


_TITLES = {
    "v2": "RealAIGym simulation leaderboard v2 (performance)",
    "robustness-v2": "RealAIGym robustness leaderboard v2",
    "v3": "RealAIGym v3 (ICRA 2025 global protocol, simulation)",
}


def _explain(run: LeaderboardRun, protocol: str) -> str:
    if protocol == "v2":
        return (
            "One deterministic 10 s run from hanging (RK4 at 2 ms, 6 N m on the driven joint); score = success × "
            "(1 − mean of tanh(π c/n) over the five criteria); docs/realai.md. Wall time includes building the controller."
        )
    if protocol == "robustness-v2":
        grid = (
            "722 runs per entry, seed 0 (upstream's draws after `np.random.seed(0)`)"
            if run.settings.comparable
            else "**quick grid (13 runs: grid points 0 and 20, parameters m2 and b2, one repetition, one perturbation run): "
            "NOT comparable with the published rows**"
        )
        return (
            "Rates in percent: model parameters (10 × 21), velocity noise, torque noise, torque response, delay (21 levels "
            "each), perturbations (50 runs); a noise level counts when more than half of its repetitions succeed; "
            f"score = mean of the six rates. {grid}. Wall time: the sum of the runs' wall times (one worker each); "
            "controller time: median over runs of each run's median call, and the longest call of all runs (scheduler "
            "pauses of the shared machine included)."
        )
    if run.settings.comparable:
        grid = f"60 s per episode, schedule seeds {', '.join(map(str, run.settings.v3_seeds))}"
    else:
        grid = "**quick: seed 0, the first 10 s only, score = uptime / 10 s: NOT comparable with the published rows**"
    return (
        "Score = the fraction of the episode with the end effector above 0.9 (L1 + L2); 15 resets by PID to random "
        f"configurations; {grid}. Wall time includes the controller's design and every plan it solves."
    )


def protocol_tables(run: LeaderboardRun) -> list[str]:
    """Markdown lines: one section per protocol, one table per task, pendulab's rows beside the published ones.

    Parameters
    ----------
    run : LeaderboardRun
        The cases (:func:`~.leaderboard.run_protocols`).

    Returns
    -------
    list of str
        Lines (no trailing newlines). Cases that failed or were not run show their reason in the row.
    """
    lines: list[str] = []
    makers = {"v2": _v2_table, "robustness-v2": _robustness_table, "v3": _v3_table}
    for protocol in ("v2", "robustness-v2", "v3"):
        if not run.controllers(protocol):
            continue
        lines += [f"## {_TITLES[protocol]}", "", _explain(run, protocol), ""]
        for task in TASKS:
            if not any(c.task == task and c.protocol == protocol for c in run.cases):
                continue
            lines += [f"### {task}", "", *makers[protocol](run, task), ""]
        lines += [SOURCES[protocol], ""]
    return lines

"""Markdown tables of a :class:`~.leaderboard.LeaderboardRun`: each protocol beside its published rows."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from .leaderboard import IDENTIFIED, TASKS, Case, LeaderboardRun
from .leaderboard_published import (
    PUBLISHED_HARDWARE,
    PUBLISHED_ROBUSTNESS_ROWS,
    PUBLISHED_V2_ROWS,
    PUBLISHED_V3_ROWS,
    SOURCES,
)
from .robustness_grid import CATEGORIES
from .upstream_records import ENTRY_LABELS, UPSTREAM_RECORDS, EntryScores, spearman_rho

__all__ = ["protocol_sections", "protocol_tables", "section_heading", "CATEGORY_HEADERS"]

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


def _v2_table(run: LeaderboardRun, task: str, protocol: str = "v2") -> list[str]:
    head = ["entry", "success", "swing-up time [s]", "energy [J]", "torque cost [N² m² s]", "smoothness [N m]",
            "velocity cost [rad²/s]", "score", "wall time [s]", "controller per call: median / max [ms] (period)"]  # fmt: skip
    rows: list[tuple[float, str]] = []
    for name in run.controllers(protocol):
        case = run.case(protocol, task, name)
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
    for p in PUBLISHED_V2_ROWS[task] if protocol == "v2" else ():  # published rows: the nominal plant's
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


def _v3_table(run: LeaderboardRun, task: str, protocol: str = "v3") -> list[str]:
    seeds = list(run.settings.v3_seeds)
    head = ["entry", *(f"seed {s}" for s in seeds), "mean", "swing-ups (mean)", "wall time [s]",
            "controller per call: median / max [ms] (period 2 ms)"]  # fmt: skip
    rows: list[tuple[float, str]] = []
    for name in run.controllers(protocol):
        case = run.case(protocol, task, name)
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
    if protocol == "v3-hardware":  # the ICRA 2025 hardware final's rows: one run each on the real robot
        blank = " | ".join("" for _ in seeds)
        for key, score in PUBLISHED_HARDWARE[task].items():
            rows.append((score, f"| published {ENTRY_LABELS[key]} (`{key}`, real robot) | {blank} | {score:.3f} | | | |"))
    for p in PUBLISHED_V3_ROWS[task] if protocol == "v3" else ():  # published rows: the nominal plant's
        cells = " | ".join("" for _ in seeds)
        score = "score not in the stored sources" if p.score is None else f"{p.score:.3f} (one unseeded run)"
        swing = f"{p.values['swingups']:.0f}" if "swingups" in p.values else ""
        rows.append((
            p.score if p.score is not None else -2.0,
            f"| published {p.label} (`{p.name}`) | {cells} | {score} | {swing} | | |",
        ))  # fmt: skip
    rows.sort(key=lambda r: -r[0])
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head), *(r for _, r in rows)]


def _score_cell(run: LeaderboardRun, protocol: str, task: str, name: str) -> tuple[str, float | None]:
    """One controller's score on one protocol (v2: the run's score, v3: the mean over seeds), or why there is none."""
    try:
        case = run.case(protocol, task, name)
    except KeyError:
        return "—", None
    if case.status != "done":
        return (f"{case.status} ({case.reason})" if case.reason else case.status), None
    value = float(case.summary["mean"] if protocol.startswith("v3") else case.summary["score"])
    return f"{value:.3f}", value


def _identified_table(run: LeaderboardRun, task: str) -> list[str]:
    head = ["entry", "v2 nominal", "v2 identified", "v3 nominal (mean)", "v3 identified (mean)"]
    rows: list[tuple[float, str]] = []
    names = list(dict.fromkeys([*run.controllers("v2-identified"), *run.controllers("v3-identified")]))
    for name in names:
        cells = [_score_cell(run, p, task, name) for p in ("v2", "v2-identified", "v3", "v3-identified")]
        known = [v for _, v in cells[1::2] if v is not None]
        rows.append((max(known) if known else -1.0, f"| pendulab `{name}` | " + " | ".join(c for c, _ in cells) + " |"))
    rows.sort(key=lambda r: -r[0])
    return ["| " + " | ".join(head) + " |", "|" + "---|" * len(head), *(r for _, r in rows)]


_TITLES = {
    "v2": "RealAIGym simulation leaderboard v2 (performance)",
    "robustness-v2": "RealAIGym robustness leaderboard v2",
    "v3": "RealAIGym v3 (ICRA 2025 global protocol, simulation)",
    "identified": "On the identified robot: design C.1 as its measured records show it",
    "v3-hardware": "RealAIGym v3 hardware protocol (ICRA 2025 final) on the simulated C.1 robot",
}


def _explain(run: LeaderboardRun, protocol: str) -> str:
    if protocol == "identified":
        return (
            "The same v2 run and v3 episodes on the robot pendulab identifies from RealAIGym's eight measured C.1 "
            "excitation records (`pendulab identify --dataset c1`; links, Coulomb and viscous friction, rotor inertia; "
            "docs/identification.md) instead of the frictionless model 1.0/1.1 the leaderboards simulate. Each "
            "controller is designed exactly as for the nominal plant, as it would meet the real robot. The ICRA 2025 "
            "hardware final inverted the simulation ranking (VIMPPI 0.799 in simulation, 0.401 on the robot); this "
            "table is pendulab's first look at that gap."
        )
    if protocol == "v3-hardware":
        allowance = run.settings.passive_allowance
        return (
            "The ICRA 2025 hardware final's protocol (10 resets of 1 s by a PID, kp 2, kd 0.3; limit resets at 3.5π rad "
            "/ 20 rad/s; safety stop at 4π rad / 25 rad/s) on the identified C.1 robot with the sensing and loop timing "
            "measured on its excitation records (quantized angles, noisy rates, 2.0–3.7 ms loop intervals, torque "
            f"noise; docs/realai_v3.md); passive joint allowance {allowance:g} N m. Published rows: the real robot, "
            "one run each. Score = uptime / episode length over the measured angles."
        )
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


def _upstream_table(task: str, entries: Sequence[EntryScores], skipped: Sequence[str], allowance: float) -> list[str]:
    """The ICRA 2025 entries' recorded v3-hardware means beside their real-robot scores, and the rank correlation."""
    lines = [f"The ICRA 2025 entries on this protocol ({task}, allowance {allowance:g} N m; recorded by "
             "`benchmarks/bench_upstream_entries.py` with upstream's code, not in CI):", ""]  # fmt: skip
    if not entries:
        lines += [f"*No recorded episodes in `{UPSTREAM_RECORDS}/`: run the benchmark (docs/realai_v3.md).*"]
    else:
        head = "| entry | pendulab v3-hardware: mean | std over seeds | seeds | real robot (best run) | ran as |"
        lines += [head, "|---|---|---|---|---|---|"]
        lines += [
            f"| {e.label} (`{e.entry}`) | **{e.mean:.3f}** | {e.std:.3f} | {len(e.seeds)} | {e.published_hardware:.3f} | "
            f"{e.approximation or 'submitted'} |"
            for e in entries
        ]
        ran = ", ".join(e.label for e in entries)
        missing = [ENTRY_LABELS[k] for k in PUBLISHED_HARDWARE[task] if k not in {e.entry for e in entries}]
        rho = f"{_rho(entries):+.2f}" if len(entries) > 1 else "— (one entry)"
        lines += ["", f"Spearman ρ of these means against the real robot over the entries that ran ({ran}): **{rho}**"
                  + (f"; not run: {', '.join(missing)}." if missing else ".")]  # fmt: skip
        exact = [e for e in entries if not e.approximation]
        if len(exact) != len(entries) and len(exact) > 1:
            lines[-1] += (f" Over the entries that ran as submitted ({', '.join(e.label for e in exact)}): "
                          f"**{_rho(exact):+.2f}**.")  # fmt: skip
    lines += [f"*Skipped record {s}*" for s in skipped]
    return lines


def _rho(entries: Sequence[EntryScores]) -> float:
    """Spearman rho of the entries' simulated means against their real-robot scores."""
    return spearman_rho([e.mean for e in entries], [e.published_hardware for e in entries])


def protocol_sections(
    run: LeaderboardRun, upstream: Mapping[str, tuple[Sequence[EntryScores], Sequence[str]]] | None = None
) -> list[tuple[str, list[str]]]:
    """Markdown sections: one per protocol, one table per task, pendulab's rows beside the published ones.

    Parameters
    ----------
    run : LeaderboardRun
        The cases (:func:`~.leaderboard.run_protocols`).
    upstream : mapping, optional
        Task -> (entries, skipped records) of :func:`~.upstream_records.read_hardware_entries`: shown under that
        task's v3-hardware table.

    Returns
    -------
    list of (str, list of str)
        (section key, lines) in page order. The key is a protocol name of
        :data:`~.leaderboard.PROTOCOLS`, or ``"identified"`` for the section of both identified protocols; the lines
        start with the section's ``## `` heading (no trailing newlines). Cases that failed or were not run show their
        reason in the row.
    """
    makers: dict[str, Any] = {
        "v2": _v2_table, "robustness-v2": _robustness_table, "v3": _v3_table, "identified": _identified_table,
        "v3-hardware": lambda r, t: _v3_table(r, t, "v3-hardware"),
    }  # fmt: skip
    if run.controllers("v2-identified") or run.controllers("v3-identified"):
        protocols: tuple[str, ...] = ("v2", "robustness-v2", "v3", "identified", "v3-hardware")
    else:
        protocols = ("v2", "robustness-v2", "v3", "v3-hardware")
    sections: list[tuple[str, list[str]]] = []
    for protocol in protocols:
        if protocol != "identified" and not run.controllers(protocol):
            continue
        lines = [section_heading(protocol), "", _explain(run, protocol), ""]
        for task in TASKS:
            members = IDENTIFIED if protocol == "identified" else (protocol,)
            if not any(c.task == task and c.protocol in members for c in run.cases):
                continue
            lines += [f"### {task}", "", *makers[protocol](run, task), ""]
            if protocol == "v3-hardware" and upstream is not None and task in upstream:
                lines += [*_upstream_table(task, *upstream[task], run.settings.passive_allowance), ""]
        if protocol in SOURCES:
            lines += [SOURCES[protocol], ""]
        sections.append((protocol, lines))
    return sections


def section_heading(key: str) -> str:
    """The ``## `` heading of a section of :func:`protocol_sections`.

    Parameters
    ----------
    key : str
        A protocol of :data:`~.leaderboard.PROTOCOLS` that has a section of its own, or ``"identified"``.

    Returns
    -------
    str
        The heading line, ``"## "`` and the section's title.

    Raises
    ------
    KeyError
        An unknown key.
    """
    return f"## {_TITLES[key]}"


def protocol_tables(
    run: LeaderboardRun, upstream: Mapping[str, tuple[Sequence[EntryScores], Sequence[str]]] | None = None
) -> list[str]:
    """The lines of every section of :func:`protocol_sections`, in page order.

    Parameters
    ----------
    run : LeaderboardRun
        The cases (:func:`~.leaderboard.run_protocols`).
    upstream : mapping, optional
        As :func:`protocol_sections`.

    Returns
    -------
    list of str
        The sections' lines, concatenated (no trailing newlines).
    """
    return [line for _key, lines in protocol_sections(run, upstream) for line in lines]

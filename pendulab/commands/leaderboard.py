"""The leaderboard (``pendulab score --leaderboard``): RealAIGym's three protocols beside the published rows, and the
project's own robustness scorecards.

Written to ``./pendulab-out/leaderboard/leaderboard.md`` by default (figures in ``figures/`` beside it); the shipped
``docs/leaderboard.md`` is regenerated explicitly with ``--out docs/leaderboard.md`` from the repository root (one
protocol's section alone with ``--protocol P``: :mod:`.leaderboard_splice`). Every
finished case is journaled under ``./pendulab-out/leaderboard/`` (:mod:`pendulab.evaluate.realai.leaderboard`;
scorecards in ``scorecard/TASK-CONTROLLER/records.json``); ``--resume`` continues, Ctrl-C keeps finished work.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .._io import atomic_write_text, check_writable
from .._version import __version__
from .leaderboard_splice import LEADERBOARD_TITLE, SCORECARD_HEADING, UNFINISHED_HEADING, needs_splice, splice_sections

__all__ = ["write_leaderboard", "LEADERBOARD_TASKS", "LEADERBOARD_CONTROLLERS", "DEFAULT_PATH"]

#: Tasks of the scorecard table: pendubot and acrobot, rigid and elastic (soft springs, which visibly take part).
LEADERBOARD_TASKS: tuple[str, ...] = ("pendubot", "acrobot", "pendubot_elastic_soft", "acrobot_elastic_soft")
#: Controllers of the scorecard table (names of ``controller_for_task``).
LEADERBOARD_CONTROLLERS: tuple[str, ...] = ("lqr", "tvlqr", "swingup", "nmpc")
#: Cards not run, with the reason. NMPC on the soft elastic plants predicts with the 8-state elastic model (the
#: planning rule's choice at w_s / w_p = 2; ~13 ms per solve, docs/nmpc.md): its pendubot card is scored; on the
#: acrobot its nominal swing-up already fails (a spring nears collapse at 4.2 s with every prediction model).
SKIPPED: dict[tuple[str, str], str] = {
    ("nmpc", "acrobot_elastic_soft"): "not scored (its nominal swing-up fails: a spring nears collapse at 4.2 s; docs/nmpc.md)"
}
#: Controllers whose nominal run of the scorecard table is also run with every integrator and tolerance
#: (:mod:`pendulab.cosim.integrators`): the energy swing-up's chaotic pumping made its "nominal ok" depend on the
#: integrator, so its bracket says with which integrators it holds (a table below the scorecards).
INTEGRATOR_CHECKED: tuple[str, ...] = ("swingup",)
#: Where the leaderboard is written by default (relative to the current directory; never into docs/:
#: regenerate the shipped page explicitly with ``--out docs/leaderboard.md`` from the repository root).
DEFAULT_PATH = Path("pendulab-out") / "leaderboard" / "leaderboard.md"


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".replace("|", "/")[:160]


class _Bars:
    """One ProgressBar per case label (the previous one closed when the label changes)."""

    def __init__(self, enabled: bool) -> None:
        self.enabled, self.label, self.bar = enabled, None, None

    def __call__(self, label: str, done: int, total: int) -> None:
        from ._common import ProgressBar

        if label != self.label:
            self.close()
            unit = "runs" if label.startswith("robustness") else "plans" if label.startswith("plan library") else "2 ms steps"
            self.label, self.bar = label, ProgressBar(f"{label} ({unit})", self.enabled)
        if self.bar is not None:
            self.bar(done, total)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        self.label, self.bar = None, None


def write_leaderboard(
    path: str | Path | None = None,
    *,
    runs: int = 20,
    workers: int | None = None,
    progress: bool = True,
    controllers: Sequence[str] | Mapping[str, Sequence[str]] | None = None,
    quick: bool = False,
    resume: bool = False,
    max_wall_time: float | None = None,
    root: str | Path | None = None,
    tasks: Sequence[str] | None = None,
    scorecards: bool = True,
    protocols: Sequence[str] | None = None,
    passive_allowance: float = 0.0,
    upstream_records: str | Path | None = None,
) -> Path:
    """Regenerate the leaderboard markdown and its figures.

    Parameters
    ----------
    path : str or Path, optional
        Output file; default :data:`DEFAULT_PATH` (``./pendulab-out/leaderboard/leaderboard.md``). Figures go to
        ``figures/leaderboard_*.png`` beside it.
    runs : int
        Runs per level of the stochastic categories of every own scorecard.
    workers : int, optional
        Worker processes of the robustness-v2 runs and the scorecards (default 1 for robustness v2).
    progress : bool
        Show a tqdm bar per case on stderr.
    controllers : sequence of str or mapping, optional
        RealAIGym controller names for all three protocols (or protocol -> names); default
        :data:`pendulab.evaluate.realai.leaderboard.DEFAULT_CONTROLLERS`. The own scorecards keep
        :data:`LEADERBOARD_CONTROLLERS`.
    quick : bool
        Smoke run (:data:`pendulab.evaluate.realai.leaderboard.QUICK`), labelled not comparable; the own scorecards
        are not run.
    resume : bool
        Reuse the journals of finished cases.
    max_wall_time : float, optional
        Budget [s], checked before each case; cases not started by then are marked "not run".
    root : str or Path, optional
        Journal directory (default ``./pendulab-out/leaderboard``).
    tasks : sequence of str, optional
        RealAIGym tasks (default pendubot and acrobot).
    scorecards : bool
        Include the own scorecard section (it is "not run" with ``quick``, and left out with ``protocols``).
    protocols : sequence of str, optional
        Only these protocols' cases and tables (names of :data:`pendulab.evaluate.realai.leaderboard.PROTOCOLS`);
        default all, and the own scorecards. The page's command line names ``--protocol`` when one is asked (the
        CLI takes one); for several it names none, and says so. Over an existing page that holds other sections
        too, only these protocols' sections are replaced (each saying which command regenerated it) and the rest
        of the page is kept (:mod:`pendulab.commands.leaderboard_splice`).
    passive_allowance : float
        Torque the v3-hardware entries may put on the passive joint [N.m], in [0, 0.5] (the hardware rules' friction
        allowance; pendulab's controllers compensate the identified friction with it).
    upstream_records : str or Path, optional
        Records of ``benchmarks/bench_upstream_entries.py`` whose v3-hardware episodes of the ICRA 2025 entries are
        shown beside their real-robot scores (default
        :data:`pendulab.evaluate.realai.upstream_records.UPSTREAM_RECORDS`).

    Returns
    -------
    Path
        The markdown file written.

    Raises
    ------
    ValueError
        Unknown controller or task names, or a journal of other settings with ``resume``
        (:class:`~pendulab._journal.JournalError`; journals that were edited, lack fields or were written by
        another pendulab are not an error: their cases or runs are run again, with a
        :class:`~pendulab._journal.JournalWarning`).
    PermissionError, NotADirectoryError
        The page's folder or the journal directory cannot be written (checked before any case runs).
    KeyboardInterrupt
        Ctrl-C; the finished cases stay journaled (continue with ``resume``).
    """
    from ..evaluate.realai.leaderboard import DEFAULT_ROOT, PROTOCOLS, TASKS, check_controllers, run_protocols
    from ..evaluate.realai.leaderboard_tables import protocol_sections, section_heading
    from ..evaluate.realai.upstream_records import UPSTREAM_RECORDS, read_hardware_entries

    check_controllers(controllers)  # bad names fail before anything runs
    out = DEFAULT_PATH if path is None else Path(path)
    jroot = DEFAULT_ROOT if root is None else Path(root)
    for where in (out.parent, jroot):  # before hours of cases, not at their first save
        check_writable(where)
    w0 = time.perf_counter()
    bars = _Bars(progress)
    try:
        board = run_protocols(
            controllers, tasks=TASKS if tasks is None else tasks, protocols=PROTOCOLS if protocols is None else protocols,
            quick=quick, resume=resume, root=jroot, workers=1 if workers is None else workers, progress=bars,
            max_wall_time=max_wall_time, passive_allowance=passive_allowance,
        )  # fmt: skip
        remaining = None if max_wall_time is None else max(0.0, max_wall_time - (time.perf_counter() - w0))
        own = scorecards and not quick and protocols is None
        cards = _scorecards(runs, workers, progress, resume, jroot / "scorecard", remaining) if own else None
        checks = None if cards is None else _integrator_checks(resume, jroot / "integrators")
    finally:
        bars.close()
    hardware_tasks = sorted({c.task for c in board.cases if c.protocol == "v3-hardware"})
    records = UPSTREAM_RECORDS if upstream_records is None else Path(upstream_records)
    upstream = {t: read_hardware_entries(records, t, passive_allowance) for t in hardware_tasks}
    figs = _figures(board, out.parent / "figures", upstream)
    options = _options(protocols, passive_allowance, controllers, runs, path)
    cmd = "pendulab score --leaderboard" + (" --quick" if quick else "") + (" --resume" if resume else "") + options
    sections = [
        (section_heading(key), lines + _figure_lines(figs.get(key, ()))) for key, lines in protocol_sections(board, upstream)
    ]
    not_run = [c for c in board.cases if c.status != "done"]
    again = "pendulab score --leaderboard --resume" + (" --quick" if quick else "") + options
    unfinished = [f"* {c.protocol} / {c.task} / `{c.controller}`: {c.status} ({c.reason})" for c in not_run]
    ran = {p: n for p, n in board.counts().items() if protocols is None or p in protocols}
    reused = "journaled cases reused: " + ", ".join(f"{p} {r}" for p, (_, r) in ran.items())
    wall = f"{time.perf_counter() - w0:.0f} s"
    old = _existing_page(out) if protocols is not None else ""
    if needs_splice(old, [heading for heading, _ in sections]):
        if unfinished:  # the page-level list belongs to the page's own generation
            sections[-1][1].extend([f"Cases not finished here (continue with `{again}`):", "", *unfinished, ""])
        note = (
            f"*This section: regenerated by `{cmd}` (pendulab {__version__}, {time.strftime('%Y-%m-%d')}; "
            f"wall time {wall}, {reused}); the rest of the page by the command above.*"
        )
        text = splice_sections(old, sections, protocols or (), note)
    else:
        lines = _page_head(cmd, quick, protocols)
        lines += [line for _, section in sections for line in section]
        if protocols is None:
            lines += _scorecard_section(cards, runs, quick, checks)
        if unfinished:
            lines += [UNFINISHED_HEADING, "", f"Continue with `{again}` (finished cases are reused).", "", *unfinished, ""]
        lines += [f"Wall time of this generation: {wall} ({reused}).", ""]
        text = "\n".join(lines).rstrip("\n") + "\n"
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out, text)
    return out


def _existing_page(out: Path) -> str:
    """The text of the page about to be written over ("" when there is none, or it is not UTF-8 text)."""
    try:
        return out.read_text(encoding="utf-8")
    except (FileNotFoundError, IsADirectoryError, UnicodeDecodeError):
        return ""


def _page_head(cmd: str, quick: bool, protocols: Sequence[str] | None) -> list[str]:
    """A whole page's title, provenance and regenerate lines."""
    lines = [
        LEADERBOARD_TITLE,
        "",
        f"Generated by `{cmd}` (pendulab {__version__}, {time.strftime('%Y-%m-%d')}). Do not edit by hand. "
        "Journals of every finished case: `./pendulab-out/leaderboard/` (`--resume` reuses them).",
        "",
        f"Regenerate: `{cmd}` (repository root){_several(protocols)}"
        if protocols is not None
        else "Regenerate: `pendulab score --leaderboard --resume --runs 10 --out docs/leaderboard.md` (repository root; "
        "`--workers N` for the robustness-v2 runs and scorecards, `--controllers A,B` to choose the RealAIGym "
        "controllers, `--max-wall-time S` to stop starting new cases after S seconds). A full run takes hours on 2 "
        "cores: robustness v2 is 722 runs of 10 s per controller and task (300-700 s; `robust` ~1500 s), a v3 episode "
        "20-700 s; `--protocol P` regenerates one protocol's section of an existing page and keeps the rest. "
        "`--quick` is a smoke run (robustness v2 on 13 runs, one 10 s v3 episode, no own scorecards) whose numbers are "
        "not comparable; its journals live in `./pendulab-out/leaderboard/quick/`.",
        "",
    ]
    if quick:
        lines += ["**QUICK RUN (`--quick`): reduced grids and one short v3 episode. These numbers are a smoke test, NOT "
                  "comparable with the published rows.**", ""]  # fmt: skip
    return lines


def _figure_lines(figs: Sequence[Path]) -> list[str]:
    """A section's figure links and the caption of their kinds."""
    lines = [line for p in figs for line in (f"![{p.stem}](figures/{p.name})", "")]
    captions = [text for kind, text in _CAPTIONS.items() if any(_figure_kind(p) == kind for p in figs)]
    return lines + (["*" + " ".join(captions) + "*", ""] if captions else [])


#: The caption of each kind of leaderboard figure (a kind is the figure file's name).
_CAPTIONS: dict[str, str] = {
    "robustness": (
        "Robustness v2: success rate against each category's level, one line per controller (model parameters: the mean "
        "over the ten parameters at each grid point; noise: mean over the repetitions; perturbations: runs binned by "
        "their largest pulse on the driven joint). Upstream publishes only category rates, so the published entries "
        "are gray ticks right of each panel (the best named)."
    ),
    "v3": "v3: score per seed and the mean, the dashed line the best published score.",
    "v3_hardware": (
        "v3-hardware: each ICRA 2025 entry's mean score on this protocol (± std over seeds) against its best run on "
        "the real robot (the diagonal is agreement; hollow: the entry could only run approximated), pendulab's "
        "controllers as dashed lines (they have no real-robot run)."
    ),
}


def _figure_kind(path: Path) -> str:
    stem = path.stem.removeprefix("leaderboard_")
    return "robustness" if stem.startswith("robustness") else stem


def _several(protocols: Sequence[str]) -> str:
    """The end of the regenerate sentence: the CLI takes one ``--protocol``, the API several."""
    if len(protocols) == 1:
        return "."
    return f" with `write_leaderboard(protocols={list(protocols)!r})` (the CLI takes one `--protocol`)."


def _options(protocols: Sequence[str] | None, allowance: float, controllers: Any, runs: int, path: str | Path | None) -> str:
    """The command-line options that reproduce these settings (after ``--leaderboard``, ``--quick``, ``--resume``)."""
    text = f" --runs {runs}" if runs != 20 else ""
    text += f" --controllers {','.join(controllers)}" if isinstance(controllers, (list, tuple)) else ""
    text += f" --protocol {protocols[0]}" if protocols is not None and len(protocols) == 1 else ""
    text += f" --passive-allowance {allowance:g}" if allowance else ""
    return text + (f" --out {path}" if path else "")


def _figures(board: Any, fig_dir: Path, upstream: Mapping[str, Any]) -> dict[str, list[Path]]:
    """The figures of the protocols run, keyed by the section they belong to (a protocol name)."""
    from ..evaluate.realai.leaderboard import TASKS
    from ..viz.leaderboard import plot_hardware_agreement, plot_robustness_levels, plot_v3_seeds

    def done(protocol: str, task: str | None = None) -> bool:
        return any(c.protocol == protocol and c.status == "done" and task in (None, c.task) for c in board.cases)

    figs: dict[str, list[Path]] = {}
    for task in TASKS:
        if done("robustness-v2", task):
            path = fig_dir / f"leaderboard_robustness_{task}.png"
            figs.setdefault("robustness-v2", []).append(plot_robustness_levels(board, task, path))
    if done("v3"):
        figs["v3"] = [plot_v3_seeds(board, fig_dir / "leaderboard_v3.png")]
    if done("v3-hardware"):
        figs["v3-hardware"] = [plot_hardware_agreement(board, upstream, fig_dir / "leaderboard_v3_hardware.png")]
    return figs


def _journal_wall(journal: Any) -> float | None:
    """The wall time [s] journaled (and validated) with a scorecard's records (None: not journaled)."""
    wall = journal.meta.get("wall_time")
    return float(wall) if isinstance(wall, (int, float)) else None


def _complete(journal: Any, resume: bool) -> bool:
    """Whether a resumed scorecard journal holds the whole card (complete, and no record of it was dropped)."""
    return resume and bool(journal.meta.get("complete")) and not journal.notices


def _scorecards(runs: int, workers: int | None, progress: bool, resume: bool, root: Path, budget: float | None) -> dict[str, Any]:
    """The own scorecards, each journaled in ``root/TASK-CONTROLLER/records.json`` (``cards`` and their ``walls`` [s])."""
    from ..control.swingup.iterations import observe
    from ..control.swingup.tasks import load_task
    from ..evaluate import score
    from ..evaluate.scorecard_journal import open_journal, save_records
    from ._common import ProgressBar

    w0 = time.perf_counter()
    cards: dict[tuple[str, str], Any] = {}
    walls: dict[tuple[str, str], float | None] = {}
    for task_name in LEADERBOARD_TASKS:
        task = load_task(task_name)
        for ctrl in LEADERBOARD_CONTROLLERS:
            if (ctrl, task_name) in SKIPPED:
                cards[(ctrl, task_name)] = SKIPPED[(ctrl, task_name)]
                continue
            path = root / f"{task.name}-{ctrl}" / "records.json"
            settings = {"controller": ctrl, "task": task.name, "runs": runs, "seed": 0, "categories": None}
            # Validated before anything is built: edited, incomplete or older records are run again (notices).
            journal, completed = open_journal(path, settings, resume=resume)
            if budget is not None and time.perf_counter() - w0 > budget and not _complete(journal, resume):
                # Past the budget only complete journals are read back (their card is rebuilt, nothing runs).
                done = f", {len(completed)} runs journaled" if completed else ""
                cards[(ctrl, task_name)] = f"not run (wall-time budget reached{done}; continue with --resume)"
                continue

            before = _journal_wall(journal) if completed else 0.0  # None: journaled without its wall time
            complete_before = _complete(journal, resume)
            t_card = time.perf_counter()

            def save(
                records: tuple, complete: bool = False, journal: Any = journal, before: float | None = before,
                t_card: float = t_card, frozen: bool = complete_before,
            ) -> None:  # fmt: skip
                wall = before if (frozen or before is None) else before + time.perf_counter() - t_card
                save_records(journal, records, complete=complete, wall_time=wall)

            planning = ProgressBar(f"planning {ctrl} on {task_name} (IPOPT)", progress)
            bar = ProgressBar(f"scorecard {ctrl} on {task_name} (runs)", progress)

            def report(done: int, total: int, planning: ProgressBar = planning, bar: ProgressBar = bar) -> None:
                planning.close()
                bar(done, total)

            try:
                with observe(
                    lambda p=planning: p.iterate(1, "iter"), lambda d, p=planning: p.note(f"building the NLP ({d}) ...")
                ):
                    card = score(ctrl, task, runs=runs, workers=workers, progress=report, completed=completed,
                                 on_records=save)  # fmt: skip
                save(card.records, complete=True)
                cards[(ctrl, task_name)] = card
                walls[(ctrl, task_name)] = _journal_wall(journal)
            except (ValueError, RuntimeError) as exc:  # e.g. a swing-up the optimizer cannot solve
                cards[(ctrl, task_name)] = f"not available ({_one_line(exc)})"
            finally:
                planning.close()
                bar.close()
    return {"cards": cards, "walls": walls}


def _integrator_checks(resume: bool, root: Path) -> dict[tuple[str, str], Any]:
    """The nominal run of each :data:`INTEGRATOR_CHECKED` controller on each task with every integrator and tolerance.

    Journaled in ``root/TASK-CONTROLLER.json`` (:class:`~pendulab._journal.Journal`, kind ``integrator-check``; one
    record per run, reused with ``resume`` when every run of the grid validates). Values: tuples of
    :class:`~pendulab.cosim.integrators.IntegratorRun`, or a one-line reason.
    """
    from .._journal import Journal
    from ..control.controllers import controller_for_task
    from ..control.swingup.tasks import load_task
    from ..cosim.integrators import FMU_SOLVERS, NATIVE_METHODS, TOLERANCES, IntegratorRun, integrator_runs

    n_runs = (len(NATIVE_METHODS) + len(FMU_SOLVERS)) * len(TOLERANCES) + 1
    out: dict[tuple[str, str], Any] = {}
    for ctrl in INTEGRATOR_CHECKED:
        for task_name in LEADERBOARD_TASKS:
            task = load_task(task_name)
            settings = {"controller": ctrl, "task": task.name, "methods": list(NATIVE_METHODS), "solvers": list(FMU_SOLVERS),
                        "tolerances": list(TOLERANCES)}  # fmt: skip
            journal = Journal(root / f"{task.name}-{ctrl}.json", "integrator-check", settings, resume=resume,
                              check=lambda _key, data: IntegratorRun.from_dict(data))  # fmt: skip
            if len(journal) == n_runs:
                out[(ctrl, task_name)] = tuple(IntegratorRun.from_dict(journal.get(f"{i:03d}")) for i in range(n_runs))
                continue
            try:
                found = integrator_runs(lambda c=ctrl, t=task: controller_for_task(c, t), task)
            except (ValueError, RuntimeError) as exc:
                out[(ctrl, task_name)] = f"not available ({_one_line(exc)})"
                continue
            for i, run in enumerate(found):
                journal.add(f"{i:03d}", run.to_dict())
            journal.save(complete=True)
            out[(ctrl, task_name)] = found
    return out


def _scorecard_section(
    result: dict[str, Any] | None, runs: int, quick: bool, checks: dict[tuple[str, str], Any] | None = None
) -> list[str]:
    from ..cosim.integrators import integrator_summary, integrator_table
    from ..evaluate import CATEGORIES

    checks = checks or {}

    cards = None if result is None else result["cards"]
    walls = {} if result is None else result["walls"]

    lines = [SCORECARD_HEADING, ""]
    if cards is None:
        why = "--quick" if quick else "scorecards=False"
        return lines + [f"not run ({why}); the full leaderboard scores it (docs/scorecard.md).", ""]
    lines += [
        "pendulab's own protocol (not RealAIGym's: its own categories, levels and success rule; docs/scorecard.md). "
        "Overall score = mean over the categories of the mean success rate over the levels; "
        f"{runs} runs per level of the stochastic categories. In brackets: does the nominal run (no perturbation) "
        "succeed on the scorecard's plant (fixed-step RK4), for "
        + ", ".join(f"`{c}`" for c in INTEGRATOR_CHECKED)
        + " also with which integrators (table below), and the card's wall time.",
        "",
        "| controller | " + " | ".join(LEADERBOARD_TASKS) + " |",
        "|---|" + "---|" * len(LEADERBOARD_TASKS),
    ]
    for ctrl in LEADERBOARD_CONTROLLERS:
        cells = []
        for task_name in LEADERBOARD_TASKS:
            card = cards[(ctrl, task_name)]
            if isinstance(card, str):
                cells.append(card)
                continue
            wall = walls.get((ctrl, task_name))
            check = checks.get((ctrl, task_name))
            nominal = _nominal(card)
            if check is not None:
                nominal += f"; {check if isinstance(check, str) else integrator_summary(check)}"
            timing = "wall time not journaled)" if wall is None else f"{wall:.0f} s)"
            cells.append(f"**{card.overall:.2f}** ({nominal}, {timing}")
        lines.append(f"| {ctrl} | " + " | ".join(cells) + " |")
    for ctrl in INTEGRATOR_CHECKED:
        found = {t: checks[(ctrl, t)] for t in LEADERBOARD_TASKS if not isinstance(checks.get((ctrl, t)), (str, type(None)))}
        if not found:
            continue
        lines += [
            "",
            f"### `{ctrl}`: the nominal run with every integrator",
            "",
            "The task's nominal episode (start hanging, 10 s, success: y2 > 0.9 (L1 + L2) until the end) through "
            "`pendulab.simulate` (method, rtol = atol), through the exported FMU with `pendulab.cosim` (embedded solver, "
            "tolerance; the path of `pendulab cosim`) and on the scorecard's fixed-step RK4 plant "
            "(`pendulab.cosim.integrators`; in brackets: t_up, the start of the final stretch above the line).",
            "",
            *integrator_table(found),
        ]
    lines += ["", "### Category scores", ""]
    for task_name in LEADERBOARD_TASKS:
        scored = [(c, cards[(c, task_name)]) for c in LEADERBOARD_CONTROLLERS if not isinstance(cards[(c, task_name)], str)]
        if not scored:
            continue
        names = [c.name for c in scored[0][1].categories]
        lines += [f"`{task_name}`:", "", "| controller | " + " | ".join(names) + " |", "|---|" + "---|" * len(names)]
        for ctrl, card in scored:
            lines.append(f"| {ctrl} | " + " | ".join(f"{card.category(n).score:.2f}" for n in names) + " |")
        lines.append("")
    lines += ["Categories: " + "; ".join(f"`{c.name}`: {c.description} [{c.unit}]" for c in CATEGORIES.values()), ""]
    return lines


def _nominal(card: Any) -> str:
    """'nominal ok' / 'nominal fails' from a run of the card without perturbation (torque noise level 0 or mass 1.0)."""
    for rec in card.records:
        if (rec.category == "mass" and rec.level == 1.0) or (rec.category == "torque_noise" and rec.level == 0.0):
            return "nominal ok" if rec.success else "nominal fails"
    return "nominal ?"


def print_summary(path: Path) -> None:
    """One line on stderr naming the file written (the CLI's report).

    Parameters
    ----------
    path : Path
        The markdown file.
    """
    print(f"wrote {path} (figures in {path.parent / 'figures'})", file=sys.stderr)

"""All three RealAIGym protocols for a set of controllers, journaled: what ``pendulab score --leaderboard`` runs.

Every finished case is recorded atomically under ``root`` (default ``./pendulab-out/leaderboard/``;
``--quick`` cases under ``root/quick/``, never mixed with full ones):

* ``v2/TASK-CONTROLLER.json``: the v2 performance run (criteria, score, wall time, controller time per call);
* ``robustness-v2/TASK-CONTROLLER/runs.json``: the robustness-v2 journal of
  :func:`~.robustness.robustness_v2` (rewritten after every batch of runs; ``pendulab score --protocol robustness-v2
  --out DIR`` writes the same file, so such a run is picked up too);
* ``v3/TASK-CONTROLLER-seedS.json``: one v3 episode (:meth:`~.v3_result.V3Result.to_dict`);
* ``v2-identified/...``, ``v3-identified/...``: the same v2 and v3 cases on the identified robot (the shipped
  identification of design C.1 from its measured records, :data:`pendulab.model.plant_file.SHIPPED_PLANTS`), the controllers
  designed as for the nominal plant, as they would meet the real robot;
* ``v3-hardware/TASK-CONTROLLER-seedS.json``: one episode of the ICRA 2025 *hardware* protocol (:mod:`.v3_hardware`:
  10 PID resets of 1 s, the identified C.1 robot with its measured sensing and loop timing).

With ``resume=True`` a recorded case is read back instead of run (robustness v2: only its missing runs are run);
a record written with other settings is an error. Ctrl-C ends the current case; everything recorded before stays.

``quick=True`` (:data:`QUICK`) is a smoke run, not comparable with the published rows: robustness v2 on grid points
0 and 20 of every category, two model parameters, one repetition per noise level and one perturbation run (13 runs);
v3 one seed over the first 10 s (score = uptime / 10 s); v2 is one deterministic run either way.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..._inputs import checked
from ..._io import check_writable
from ..._journal import trusted_records
from .controllers import CONTROLLERS, LIBRARY_PLAYERS, PLAN_VELOCITY_LIMIT_HW, library_bound
from .leaderboard_runs import CASE_KIND, _read, _run_robustness, _run_v2, _run_v3, _summary_check, _write

__all__ = [
    "PROTOCOLS",
    "IDENTIFIED",
    "HARDWARE",
    "TASKS",
    "DEFAULT_CONTROLLERS",
    "DEFAULT_ROOT",
    "FULL",
    "QUICK",
    "Case",
    "LeaderboardRun",
    "ProtocolSettings",
    "check_controllers",
    "run_protocols",
]

#: The three protocols, then v2 and v3 on the identified robot (:data:`IDENTIFIED`), then the v3 hardware protocol
#: (:data:`HARDWARE`), in table order.
PROTOCOLS: tuple[str, ...] = ("v2", "robustness-v2", "v3", "v2-identified", "v3-identified", "v3-hardware")
#: Protocols run on the identified robot: protocol -> (the protocol it runs, the shipped plant's name).
IDENTIFIED: Mapping[str, tuple[str, str]] = {"v2-identified": ("v2", "c1"), "v3-identified": ("v3", "c1")}
#: Hardware-faithful protocols (:mod:`.v3_hardware`, journaled as v3 episodes): protocol -> the shipped plant's name.
HARDWARE: Mapping[str, str] = {"v3-hardware": "c1"}
#: Leaderboard tasks.
TASKS: tuple[str, ...] = ("pendubot", "acrobot")
#: Controllers scored by default on each protocol (names of :data:`~.controllers.CONTROLLERS`): on v2 every default
#: (one cheap run each, and the compiled 500 Hz ``rti``); robustness v2 the trackers with and without the estimator;
#: v3 the controllers that can start from any state (``global``, ``replan``, the real-time plan ``library``: its first
#: use solves and caches the library, minutes per task; the goal-regulating RTI ``mpc``) beside the v2 best; the
#: hardware protocol also the goal RTI led out of the hanging well by the rate-bounded library (``mpc_library``).
DEFAULT_CONTROLLERS: Mapping[str, tuple[str, ...]] = {
    "v2": ("best", "tvlqr", "robust", "rti", "global", "replan"),
    "robustness-v2": ("best", "tvlqr", "robust"),
    "v3": ("best", "global", "replan", "library", "mpc"),
    "v2-identified": ("best", "tvlqr", "robust", "rti", "global", "replan"),
    "v3-identified": ("best", "global", "replan", "library", "mpc"),
    "v3-hardware": ("best", "global", "replan", "library", "mpc", "mpc_library"),
}
#: Journal directory (relative to the current directory).
DEFAULT_ROOT = Path("pendulab-out") / "leaderboard"


@dataclass(frozen=True)
class ProtocolSettings:
    """How much of each protocol is run.

    Attributes
    ----------
    name : str
        ``"full"`` or ``"quick"``.
    robustness : mapping
        Keyword arguments of :func:`~.robustness.robustness_v2` (empty: the full 722-run protocol).
    v3_seeds : tuple of int
        Schedule seeds of the v3 episodes.
    v3_steps : int
        RK4 steps per v3 episode (30000: the protocol's 60 s); v3-hardware runs ``v3_steps * 2 ms`` of loop time.
    passive_allowance : float
        v3-hardware: torque the entry may put on the passive joint [N.m] (0, or up to the rules' 0.5).
    hardware_plans : str
        v3-hardware: how the entries are designed (``hardware_entry`` of :mod:`.v3_hardware`: plans with their
        joint rates bounded to :data:`~.controllers.PLAN_VELOCITY_LIMIT_HW`, friction compensation with an
        allowance). Part of the settings so that a journal of episodes designed otherwise is not resumed as these.
    """

    name: str
    robustness: Mapping[str, Any]
    v3_seeds: tuple[int, ...]
    v3_steps: int
    passive_allowance: float = 0.0
    hardware_plans: str = f"joint rates bounded {PLAN_VELOCITY_LIMIT_HW:g} rad/s, friction-compensated"

    @property
    def comparable(self) -> bool:
        """Whether the scores are the protocols' own (comparable with the published rows)."""
        return self.name == "full"


#: The protocols as published: robustness v2 in full (722 runs, seed 0), v3 on seeds 0, 1, 2 (60 s each).
FULL = ProtocolSettings("full", {}, (0, 1, 2), 30000)
#: Smoke run (tests, ``--quick``): NOT comparable with the published rows.
QUICK = ProtocolSettings(
    "quick",
    {
        "levels": (0, 20),
        "repetitions": 1,
        "perturbation_repetitions": 1,
        "u_noise_repetitions": 1,
        "model_params": ("m2", "b2"),
    },
    (0,),
    5000,
)


@dataclass
class Case:
    """One (protocol, task, controller) cell of the leaderboard.

    Attributes
    ----------
    protocol, task, controller : str
        The cell.
    status : str
        ``"done"``, ``"failed"`` (the controller could not be built or run: ``reason``) or ``"not run"`` (``reason``).
    reason : str
        Why a case failed or was not run.
    summary : dict
        v2: the run's :meth:`~.simulate.RealAIResult.to_dict` plus ``wall_time`` [s] and ``controller_time``;
        robustness v2: :meth:`~.robustness_scores.RobustnessResult.to_dict` plus ``wall_total`` (sum of the runs'
        wall times [s]), ``perturbation_amplitude`` (largest pulse on the driven joint per perturbation run [N m])
        and ``model_level_indices``; v3: ``seeds`` (one :meth:`~.v3_result.V3Result.to_dict` per seed, with
        ``duration`` [s] and ``uptime_fraction``) and their ``mean``.
    executed, reused : int
        Runs done by this call / read back from the journal (robustness v2: protocol runs; v2, v3: episodes).
    """

    protocol: str
    task: str
    controller: str
    status: str = "not run"
    reason: str = ""
    summary: dict[str, Any] = field(default_factory=dict, repr=False)
    executed: int = 0
    reused: int = 0


@dataclass
class LeaderboardRun:
    """The cases of one leaderboard call.

    Attributes
    ----------
    settings : ProtocolSettings
        Full or quick.
    cases : list of Case
        In protocol, task, controller order.
    root : Path
        Journal directory of this call.
    wall_time : float
        Wall time of this call [s].
    """

    settings: ProtocolSettings
    cases: list[Case]
    root: Path
    wall_time: float = 0.0

    def case(self, protocol: str, task: str, controller: str) -> Case:
        """The case of a cell.

        Parameters
        ----------
        protocol, task, controller : str
            The cell.

        Returns
        -------
        Case

        Raises
        ------
        KeyError
            No such cell in this run.
        """
        for c in self.cases:
            if (c.protocol, c.task, c.controller) == (protocol, task, controller):
                return c
        raise KeyError(f"no case ({protocol!r}, {task!r}, {controller!r}) in this leaderboard run")

    def controllers(self, protocol: str) -> list[str]:
        """Controllers of a protocol, in order.

        Parameters
        ----------
        protocol : str
            One of :data:`PROTOCOLS`.

        Returns
        -------
        list of str
            Controller names with a case of ``protocol``.
        """
        out: list[str] = []
        for c in self.cases:
            if c.protocol == protocol and c.controller not in out:
                out.append(c.controller)
        return out

    def counts(self) -> dict[str, tuple[int, int]]:
        """Runs done and runs read back, per protocol.

        Returns
        -------
        dict of str to (int, int)
            Protocol -> (executed, reused): robustness-v2 protocol runs, v2 and v3 episodes.
        """
        out = {p: (0, 0) for p in PROTOCOLS}
        for c in self.cases:
            e, r = out[c.protocol]
            out[c.protocol] = (e + c.executed, r + c.reused)
        return out


def check_controllers(controllers: Mapping[str, Sequence[str]] | Sequence[str] | None) -> dict[str, tuple[str, ...]]:
    """Controllers per protocol from a list for all three, a mapping, or None (:data:`DEFAULT_CONTROLLERS`).

    Parameters
    ----------
    controllers : sequence of str, mapping of str to sequence of str, or None
        Names of :data:`~.controllers.CONTROLLERS`.

    Returns
    -------
    dict of str to tuple of str
        Protocol -> controller names (duplicates dropped, order kept).

    Raises
    ------
    ValueError
        An unknown controller or protocol name, or an empty list.
    TypeError
        Not a sequence of strings or a mapping.
    """
    if controllers is None:
        return {p: tuple(DEFAULT_CONTROLLERS[p]) for p in PROTOCOLS}
    if isinstance(controllers, str):
        raise TypeError(f"controllers must be a sequence of names, not the string {controllers!r} (use [{controllers!r}])")
    per = dict(controllers) if isinstance(controllers, Mapping) else {p: controllers for p in PROTOCOLS}
    bad_p = [p for p in per if p not in PROTOCOLS]
    if bad_p:
        raise ValueError(f"controllers: unknown protocols {bad_p}; expected some of {list(PROTOCOLS)}")
    out: dict[str, tuple[str, ...]] = {}
    for p, names in per.items():
        if isinstance(names, str) or not all(isinstance(n, str) for n in names):
            raise TypeError(f"controllers[{p!r}] must be a sequence of controller names, got {names!r}")
        bad = [n for n in names if n not in CONTROLLERS]
        if bad:
            raise ValueError(f"controllers: unknown {bad}; expected names of {list(CONTROLLERS)}")
        if not names:
            raise ValueError(f"controllers[{p!r}] is empty; expected at least one of {list(CONTROLLERS)}")
        out[p] = tuple(dict.fromkeys(names))
    return out


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0] if text else ''}".replace("|", "/")[:160]


@checked()
def run_protocols(
    controllers: Mapping[str, Sequence[str]] | Sequence[str] | None = None,
    *,
    tasks: Sequence[str] = TASKS,
    protocols: Sequence[str] = PROTOCOLS,
    quick: bool = False,
    resume: bool = False,
    root: str | Path | None = None,
    workers: int = 1,
    progress: Callable[[str, int, int], None] | None = None,
    max_wall_time: float | None = None,
    passive_allowance: float = 0.0,
) -> LeaderboardRun:
    """Run (or read back) every (protocol, task, controller) case of the leaderboard.

    Parameters
    ----------
    controllers : sequence of str or mapping, optional
        Names of :data:`~.controllers.CONTROLLERS` for all three protocols, or protocol -> names; default
        :data:`DEFAULT_CONTROLLERS`.
    tasks : sequence of str
        Subset of ``("pendubot", "acrobot")``.
    protocols : sequence of str
        Subset of :data:`PROTOCOLS`.
    quick : bool
        The smoke settings :data:`QUICK` (not comparable) instead of :data:`FULL`.
    resume : bool
        Read recorded cases back (robustness v2: run only the missing runs); without it every case is run anew
        and its record overwritten.
    root : str or Path, optional
        Journal directory (default :data:`DEFAULT_ROOT`; quick cases in ``root/quick``).
    workers : int
        Worker processes of the robustness-v2 runs.
    progress : callable, optional
        ``progress(label, done, total)``: ``label`` names the case (and its unit: runs or 2 ms steps).
    max_wall_time : float, optional
        Budget [s] of this call, checked before each case: cases not started by then are "not run" (with
        ``resume``, cases whose journals are complete are still read back; a partial journal is reported as such).
    passive_allowance : float
        v3-hardware: torque the entries may put on the passive joint [N.m], in [0, 0.5] (the hardware rules'
        friction allowance); journaled, so a record of another allowance is not read back.

    Returns
    -------
    LeaderboardRun
        The cases; a controller that cannot be built or run gets status ``"failed"`` with the reason.

    Raises
    ------
    ValueError
        Unknown task, protocol or controller name; a journal of other settings (with ``resume``:
        :class:`~pendulab._journal.JournalError`; an edited, incomplete or older journal is run again instead,
        with a :class:`~pendulab._journal.JournalWarning`).
    PermissionError, NotADirectoryError
        The journal directory cannot be written (checked before the first case).
    TypeError
        Badly typed ``controllers``, ``tasks`` or ``protocols``.
    KeyboardInterrupt
        Ctrl-C (the cases and robustness-v2 batches finished before it are recorded).
    """
    per = check_controllers(controllers)
    for what, given, allowed in (("tasks", tasks, TASKS), ("protocols", protocols, PROTOCOLS)):
        if isinstance(given, str) or not all(isinstance(v, str) for v in given):
            raise TypeError(f"{what} must be a sequence of names, got {given!r}")
        bad = [v for v in given if v not in allowed]
        if bad or not given:
            raise ValueError(f"{what}: got {list(given)!r}; expected a non-empty subset of {list(allowed)}")
    workers = int(workers)  # workers, max_wall_time and passive_allowance: checked where they entered (@checked)
    budget = None if max_wall_time is None else float(max_wall_time)
    settings = QUICK if quick else FULL
    if passive_allowance != 0.0:
        from dataclasses import replace

        settings = replace(settings, passive_allowance=float(passive_allowance))
    base = DEFAULT_ROOT if root is None else Path(root)
    jroot = base / "quick" if quick else base
    check_writable(jroot)  # before the first case, not at its first save
    w0 = time.perf_counter()
    cases: list[Case] = []
    for protocol in (p for p in PROTOCOLS if p in protocols):
        for task in (t for t in TASKS if t in tasks):
            for name in per.get(protocol, ()):
                case = Case(protocol, task, name)
                cases.append(case)
                over = budget is not None and time.perf_counter() - w0 > budget
                try:
                    if over and not resume:
                        case.reason = f"wall-time budget of {budget:g} s reached before this case"
                    else:
                        # Past the budget, finished journals are still read back; nothing new is run.
                        _run_case(case, settings, jroot, resume, workers, progress, run_new=not over)
                except (RuntimeError, ArithmeticError) as exc:
                    case.status, case.reason = "failed", _one_line(exc)
                except ValueError as exc:
                    if "journal" in str(exc):
                        raise
                    case.status, case.reason = "failed", _one_line(exc)
    return LeaderboardRun(settings, cases, jroot, time.perf_counter() - w0)


def _finished(case: Case, settings: ProtocolSettings, jroot: Path) -> bool:
    """Whether a case's journal holds all of it (reading it back runs nothing)."""
    task, name = case.task, case.controller
    base = "v3" if case.protocol in HARDWARE else IDENTIFIED.get(case.protocol, (case.protocol,))[0]
    # Only journals that validate count as finished (an edited one would otherwise be re-run past the budget).
    if base == "v2":
        return "summary" in trusted_records(jroot / case.protocol / f"{task}-{name}.json", CASE_KIND, _summary_check(base))
    if base == "v3":
        return all(
            "summary" in trusted_records(jroot / case.protocol / f"{task}-{name}-seed{s}.json", CASE_KIND, _summary_check(base))
            for s in settings.v3_seeds
        )
    from .robustness import JOURNAL_KIND
    from .robustness_grid import plan_runs

    journal = jroot / "robustness-v2" / f"{task}-{name}" / "runs.json"
    n = len(trusted_records(journal, JOURNAL_KIND))
    total = len(plan_runs(task, **settings.robustness))
    if n < total:
        case.reason = f"{n} of {total} runs journaled; "
    return n >= total


def _reporter(progress: Callable[[str, int, int], None] | None, label: str) -> Callable[[int, int], None] | None:
    if progress is None:
        return None

    def report(done: int, total: int) -> None:
        progress(label, done, total)

    return report


def _build_library(task: str, bound: float | None, progress: Callable[[str, int, int], None] | None) -> str:
    """Solve (or read from its cache) the plan library a v3 case of ``library`` or ``mpc_library`` will use (its
    plans' rate ``bound`` [rad/s], None: unbounded), reporting each start.

    Returns the library's :meth:`~pendulab.control.plan_library.PlanLibrary.digest`: the case's journals name it, so
    a resumed leaderboard never reads back the scores of another library (one grown or re-planned since) as its own.
    """
    from ...control.plan_library import library_controller

    ctrl = library_controller(task, progress=_reporter(progress, f"plan library for {task}"), velocity_limit=bound)
    return ctrl.library.digest()


def _run_case(
    case: Case, settings: ProtocolSettings, jroot: Path, resume: bool, workers: int,
    progress: Callable[[str, int, int], None] | None, run_new: bool = True,
) -> None:  # fmt: skip
    task, name = case.task, case.controller
    label = f"{case.protocol} {name} on {task}"
    report = _reporter(progress, label)
    if not run_new and not _finished(case, settings, jroot):
        case.reason += "wall-time budget reached before this case finished; resume continues it"
        return
    base, plant = case.protocol, None
    if case.protocol in IDENTIFIED:
        from ...model.plant_file import load_plant
        from .plant import plant_label

        base, plant_name = IDENTIFIED[case.protocol]
        plant = load_plant(plant_name)
    elif case.protocol in HARDWARE:
        from ...model.plant_file import load_plant
        from .plant import plant_label

        base, plant = "v3", load_plant(HARDWARE[case.protocol])
    # a journal names its plant: a re-identified shipped plant is stale, not read back
    on = {} if plant is None else {"plant": plant_label(plant)}
    if base == "v2":
        path = jroot / case.protocol / f"{task}-{name}.json"
        keys = {"protocol": case.protocol, "task": task, "controller": name, **on}
        summary = _read(path, keys) if resume else None
        if summary is None:
            summary = _run_v2(task, name, report, plant)
            _write(path, keys, summary)
            case.executed = 1
        else:
            case.reused = 1
        case.summary, case.status = summary, "done"
    elif case.protocol == "robustness-v2":
        journal = jroot / "robustness-v2" / f"{task}-{name}" / "runs.json"
        case.summary, case.executed, case.reused = _run_robustness(
            task, name, journal, settings.robustness, resume, workers, report
        )
        case.status = "done"
    else:
        seeds = []
        hardware = case.protocol in HARDWARE
        if name in LIBRARY_PLAYERS:  # minutes of planning at first use: a bar of its own; the journals name the library
            on = {**on, "library_sha256": _build_library(task, library_bound(name, hardware), progress)}
        for seed in settings.v3_seeds:
            path = jroot / case.protocol / f"{task}-{name}-seed{seed}.json"
            keys = {"protocol": case.protocol, "task": task, "controller": name, "seed": seed, "n_steps": settings.v3_steps, **on}
            if hardware:
                keys["passive_allowance"] = settings.passive_allowance
                keys["hardware_plans"] = settings.hardware_plans
            summary = _read(path, keys) if resume else None
            if summary is None:
                summary = _run_v3(
                    task, name, seed, settings.v3_steps, _reporter(progress, f"{label}, seed {seed}"), plant,
                    passive_allowance=settings.passive_allowance if hardware else None,
                )  # fmt: skip
                _write(path, keys, summary)
                case.executed += 1
            else:
                case.reused += 1
            seeds.append(summary)
        scores = [s["uptime_fraction"] for s in seeds]
        case.summary = {"seeds": seeds, "mean": float(sum(scores) / len(scores)) if scores else math.nan}
        case.status = "done"

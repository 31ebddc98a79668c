"""Robustness scorecard: success rates of one controller on one task under swept perturbations.

Each category of :data:`CATEGORIES` sweeps one perturbation over levels (ranges
after RealAIGym's robustness benchmark, see ``docs/scorecard.md``). Every run is
one closed-loop episode (:func:`pendulab.control.perturb.run_episode`) judged by
the RealAIGym criterion: end effector at or above ``0.9 (L1 + L2)`` over the last
second, every torque command finite and within the task's limit. Stochastic
categories (noise, pushes) run ``runs`` seeded episodes per level; deterministic
ones (model errors, response, delay) give the same outcome every time, so they
run once per level.

Scores: a category's score is the mean success rate over its levels; the
overall score is the mean of the category scores (as RealAIGym's robustness
leaderboard averages its criteria).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._checks import bounded_int, positive_float
from ..ensemble.pool import default_workers, map_runs
from .controllers import controller_for_task
from .feedback import SampledController
from .perturb import Perturbation, run_episode, substeps

if TYPE_CHECKING:
    from .swingup.tasks import Task

__all__ = [
    "Category", "CATEGORIES", "RunRecord", "CategoryScore", "Scorecard", "score", "rerun", "categories_for",
    "MAX_RUNS", "MAX_LEVELS", "run_key", "record_from_dict",
]  # fmt: skip


@dataclass(frozen=True)
class Category:
    """One perturbation swept over levels.

    Attributes
    ----------
    name : str
        Category name (CLI ``--categories``).
    description : str
        What is perturbed, in one line.
    unit : str
        Unit of the levels.
    levels : tuple of float
        Default levels.
    stochastic : bool
        True: ``runs`` seeded episodes per level; False: one episode per level.
    kinds : tuple of str
        Model kinds the category applies to.
    """

    name: str
    description: str
    unit: str
    levels: tuple[float, ...]
    stochastic: bool
    kinds: tuple[str, ...] = ("rigid", "elastic")

    def perturbation(self, task: Task, level: float, seed: tuple[int, ...]) -> Perturbation:
        """The perturbation of one run.

        Parameters
        ----------
        task : Task
            Gives the nominal parameters that factors scale.
        level : float
            The level [``unit``].
        seed : tuple of int
            Seed of the run.

        Returns
        -------
        Perturbation
            What differs from the nominal closed loop.
        """
        par = task.model.params.resolved()
        scaled = {
            "mass": ("m1", "m2"),
            "length": ("L1", "L2", "lc1", "lc2") if task.model.kind == "rigid" else ("L1", "L2"),
            "inertia": ("I1", "I2"),
            "stiffness": ("k1", "k2"),
        }
        if self.name in scaled:
            return Perturbation(params={n: par[n] * level for n in scaled[self.name]}, seed=seed)
        if self.name == "damping":
            return Perturbation(params={"b1": par["b1"] + level, "b2": par["b2"] + level}, seed=seed)
        kw: dict[str, Any] = {
            "friction": {"friction": (level, level)},
            "measurement_noise": {"meas_noise": level},
            "torque_noise": {"torque_noise": level},
            "torque_response": {"response": level},
            "delay": {"delay": level},
            "pushes": {"push_amplitude": level},
        }[self.name]
        return Perturbation(seed=seed, **kw)


#: The categories, in report order. Ranges after RealAIGym's robustness benchmark (docs/scorecard.md).
CATEGORIES: Mapping[str, Category] = {
    c.name: c
    for c in (
        Category("mass", "masses m1, m2 scaled by the factor", "x", (0.75, 0.875, 1.0, 1.125, 1.25), False),
        Category("length", "lengths L1, L2 (and lc1, lc2) scaled by the factor", "x", (0.75, 0.875, 1.0, 1.125, 1.25), False),
        Category("inertia", "inertias I1, I2 scaled by the factor", "x", (0.75, 0.875, 1.0, 1.125, 1.25), False, ("rigid",)),
        Category("damping", "joint damping b1, b2 increased by", "N.m.s/rad", (0.0, 0.025, 0.05, 0.075, 0.1), False),
        Category("friction", "Coulomb friction on both joints", "N.m", (0.0, 0.05, 0.1, 0.15, 0.2), False),
        Category(
            "stiffness", "spring stiffnesses k1, k2 scaled by the factor", "x", (0.5, 0.75, 1.0, 1.25, 1.5), False, ("elastic",)
        ),
        Category("measurement_noise", "Gaussian noise on omega1, omega2 (std)", "rad/s", (0.0, 0.1, 0.2, 0.3, 0.5), True),
        Category("torque_noise", "Gaussian noise on the driven torques (std)", "N.m", (0.0, 0.25, 0.5, 0.75, 1.0), True),
        Category("torque_response", "torque responsiveness factor per sample", "-", (0.1, 0.5, 1.0, 1.5, 2.0), False),
        Category("delay", "measurement delay", "s", (0.0, 0.01, 0.02, 0.03, 0.04), False),
        Category("pushes", "3 Gaussian torque pulses per joint, amplitude up to", "N.m", (0.5, 1.0, 2.0, 3.0, 5.0), True),
    )
}


def categories_for(kind: str) -> tuple[str, ...]:
    """Names of the categories that apply to a model kind.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    tuple of str
        In :data:`CATEGORIES` order (no ``inertia`` for the point-mass elastic
        model, no ``stiffness`` for the rigid one).
    """
    return tuple(name for name, c in CATEGORIES.items() if kind in c.kinds)


@dataclass(frozen=True)
class RunRecord:
    """One run of the scorecard.

    Attributes
    ----------
    category : str
        Category name.
    level_index : int
        Index into the category's levels.
    level : float
        The level [category unit].
    run : int
        Run number within the level.
    seed : tuple of int
        ``(seed, category index, level index, run)``: the run's random stream.
    success : bool
        RealAIGym criterion met.
    reason : str
        Why it failed ("" on success).
    t_up : float
        Swing-up time [s] (nan on failure).
    """

    category: str
    level_index: int
    level: float
    run: int
    seed: tuple[int, ...]
    success: bool
    reason: str
    t_up: float


@dataclass(frozen=True)
class CategoryScore:
    """Success rates of one category.

    Attributes
    ----------
    name : str
        Category name.
    unit : str
        Unit of the levels.
    levels : tuple of float
        Levels swept.
    runs : tuple of int
        Runs per level.
    success_rates : tuple of float
        Fraction of successful runs per level, in [0, 1].
    score : float
        Mean of ``success_rates``.
    """

    name: str
    unit: str
    levels: tuple[float, ...]
    runs: tuple[int, ...]
    success_rates: tuple[float, ...]
    score: float


@dataclass(frozen=True)
class Scorecard:
    """Robustness of one controller on one task.

    Attributes
    ----------
    controller : str
        Controller name.
    task : str
        Task name.
    categories : tuple of CategoryScore
        Per category and level success rates.
    overall : float
        Mean of the category scores, in [0, 1].
    records : tuple of RunRecord
        Every run, failures with their reasons.
    seed : int
        Base seed.
    runs_per_level : int
        Runs per level of the stochastic categories.
    wall_time : float
        Wall time of the scorecard [s].
    n_sub : int
        RK4 substeps per controller sample of every run's plant.
    """

    controller: str
    task: str
    categories: tuple[CategoryScore, ...]
    overall: float
    records: tuple[RunRecord, ...]
    seed: int
    runs_per_level: int
    wall_time: float
    n_sub: int = 1

    @property
    def failures(self) -> tuple[RunRecord, ...]:
        """The failed runs (with reasons)."""
        return tuple(r for r in self.records if not r.success)

    def category(self, name: str) -> CategoryScore:
        """One category's scores.

        Parameters
        ----------
        name : str
            Category name.

        Returns
        -------
        CategoryScore
            Its per-level success rates.

        Raises
        ------
        KeyError
            The scorecard has no such category.
        """
        for c in self.categories:
            if c.name == name:
                return c
        raise KeyError(f"no category {name!r} in this scorecard; it has {[c.name for c in self.categories]}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready content.

        Returns
        -------
        dict
            controller, task, overall, seed, runs_per_level, wall_time_s,
            categories (name, unit, levels, runs, success_rates, score) and
            failures (category, level, run, seed, reason).
        """
        return {
            "controller": self.controller,
            "task": self.task,
            "overall": self.overall,
            "seed": self.seed,
            "runs_per_level": self.runs_per_level,
            "n_runs": len(self.records),
            "wall_time_s": self.wall_time,
            "rk4_substeps": self.n_sub,
            "aggregation": "category score = mean success rate over its levels; overall = mean of category scores",
            "categories": [asdict(c) for c in self.categories],
            "failures": [
                {"category": r.category, "level": r.level, "run": r.run, "seed": list(r.seed), "reason": r.reason}
                for r in self.failures
            ],
        }

    def to_json(self, indent: int | None = 2) -> str:
        """The scorecard as JSON (:meth:`to_dict`).

        Parameters
        ----------
        indent : int or None
            JSON indentation.

        Returns
        -------
        str
            JSON text (NaN-free: non-finite numbers become null).
        """
        return json.dumps(_finite(self.to_dict()), indent=indent)

    def table(self) -> str:
        """Markdown table: one row per category, success rate per level, category score.

        Returns
        -------
        str
            Markdown (header, one row per category, the overall score).
        """
        lines = [
            f"Robustness of `{self.controller}` on `{self.task}` (success rate per level; "
            f"{self.runs_per_level} runs per level of the stochastic categories)",
            "",
            "| category | unit | levels: success rate | score |",
            "|---|---|---|---|",
        ]
        for c in self.categories:
            cells = ", ".join(f"{lv:g}: {rate:.0%}" for lv, rate in zip(c.levels, c.success_rates, strict=True))
            lines.append(f"| {c.name} | {c.unit} | {cells} | {c.score:.2f} |")
        lines.append(f"| **overall** | | | **{self.overall:.2f}** |")
        return "\n".join(lines)


def _finite(obj: Any) -> Any:
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


ControllerSpec = str | Callable[["Task"], tuple[SampledController, np.ndarray]]


def _resolve(controller: ControllerSpec, task: Task | str) -> tuple[Task, str, SampledController, np.ndarray]:
    from .swingup.tasks import resolve_task

    tk = resolve_task(task)
    if isinstance(controller, str):
        ctrl, x0 = controller_for_task(controller, tk)
        return tk, controller, ctrl, np.asarray(x0, dtype=float)
    if not callable(controller):
        raise TypeError(f"controller must be a name or a factory task -> (controller, x0), got {type(controller).__name__}")
    made = controller(tk)
    if not (isinstance(made, tuple) and len(made) == 2):
        raise TypeError("a controller factory must return (controller, x0)")
    ctrl, x0 = made
    return tk, getattr(controller, "__name__", type(controller).__name__), ctrl, np.asarray(x0, dtype=float)


def _check_selection(task: Task, categories: Sequence[str] | None, levels: Mapping[str, Sequence[float]] | None) -> list[str]:
    applicable = categories_for(task.model.kind)
    names = list(applicable) if categories is None else list(categories)
    for name in names:
        if name not in CATEGORIES:
            raise ValueError(f"unknown category {name!r}; expected some of {list(CATEGORIES)}")
        if name not in applicable:
            raise ValueError(f"category {name!r} does not apply to the {task.model.kind} model of task {task.name!r}")
    for name, values in (levels or {}).items():
        if name not in names:
            raise ValueError(f"levels given for {name!r}, which is not among the categories {names}")
        if len(values) == 0 or not all(math.isfinite(float(v)) for v in values):
            raise ValueError(f"levels of {name!r} must be a non-empty sequence of finite numbers, got {values!r}")
        bounded_int(f"len(levels[{name!r}])", len(values), high=MAX_LEVELS, why="levels of one category (a sweep, not a grid)")
    if not names:
        raise ValueError("categories must name at least one category")
    return names


#: Largest number of runs per level of a stochastic category (a scorecard of 11 categories x 5 levels stays below
#: ~3e5 episodes, hours on 2 cores; more runs do not make a success rate of a few significant digits more useful).
MAX_RUNS = 5000
#: Most levels of one category.
MAX_LEVELS = 100
#: Identity of a run within a scorecard (category, level index, run, seed): what ``completed`` records are matched by.
RunKey = tuple[str, int, int, tuple[int, ...]]


def record_from_dict(data: Mapping[str, Any]) -> RunRecord:
    """A :class:`RunRecord` from its JSON form (``dataclasses.asdict`` of a record, ``t_up`` null for nan).

    Parameters
    ----------
    data : mapping
        Fields of :class:`RunRecord`.

    Returns
    -------
    RunRecord
        The record.

    Raises
    ------
    ValueError
        Missing or malformed fields.
    """
    try:
        t_up = data["t_up"]
        return RunRecord(
            str(data["category"]), int(data["level_index"]), float(data["level"]), int(data["run"]),
            tuple(int(v) for v in data["seed"]), bool(data["success"]), str(data["reason"]),
            float("nan") if t_up is None else float(t_up),
        )  # fmt: skip
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"not a scorecard run record: {dict(data)!r} ({exc})") from None


def run_key(record: RunRecord) -> RunKey:
    """The identity of a run (category, level index, run number, seed) used to skip completed runs.

    Parameters
    ----------
    record : RunRecord
        A run.

    Returns
    -------
    tuple
        ``(category, level_index, run, seed)``.
    """
    return (record.category, int(record.level_index), int(record.run), tuple(int(v) for v in record.seed))


def score(
    controller: ControllerSpec,
    task: Task | str,
    *,
    runs: int = 20,
    categories: Sequence[str] | None = None,
    levels: Mapping[str, Sequence[float]] | None = None,
    seed: int = 0,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    completed: Iterable[RunRecord] = (),
    on_records: Callable[[tuple[RunRecord, ...]], None] | None = None,
    max_wall_time: float | None = None,
) -> Scorecard:
    """Robustness scorecard of a controller on a swing-up task.

    Parameters
    ----------
    controller : str or callable
        A name of :func:`pendulab.control.controllers.controller_for_task`
        (``lqr``, ``tvlqr``, ``swingup``, ...) or a factory ``task -> (controller, x0)``.
        The controller is designed once on the nominal model; every run resets it.
    task : Task or str
        Swing-up task, or its name (``pendubot``; ``swingup_pendubot`` is an alias).
    runs : int
        Seeded runs per level of the stochastic categories, in [1, :data:`MAX_RUNS`].
    categories : sequence of str, optional
        Default: every category of :data:`CATEGORIES` that applies to the task's model.
    levels : mapping of str to sequence of float, optional
        Levels overriding a category's defaults.
    seed : int
        Base seed (>= 0); run ``(category c, level l, run r)`` uses ``(seed, c, l, r)``.
    workers : int, optional
        Worker processes (:func:`pendulab.ensemble.pool.map_runs`).
    progress : callable, optional
        ``progress(done, total)`` in runs (completed runs count as done).
    completed : iterable of RunRecord
        Runs of an earlier, interrupted scorecard with the same settings (e.g. read
        back from the partial-results file): they are not run again.
    on_records : callable, optional
        ``on_records(records)`` with every record so far, after each finished batch
        (whole levels): the CLI writes them to a partial-results file, so an
        interrupted scorecard can resume.
    max_wall_time : float, optional
        Wall-time budget [s]: once spent, the scorecard stops after the running
        batch and raises ``TimeoutError`` (the finished batches were passed to
        ``on_records``). None: no budget.

    Returns
    -------
    Scorecard
        Success rates per category and level, the overall score, every run.

    Raises
    ------
    ValueError
        Unknown task, controller or category, a category that does not apply
        to the model, bad levels, ``runs`` or ``seed`` out of range, or completed
        records that are not runs of this scorecard.
    TypeError
        A controller that is neither a name nor a factory, a task that is neither
        a Task nor a name.
    TimeoutError
        The wall-time budget ran out.
    KeyboardInterrupt
        Ctrl-C; the batches finished before it were passed to ``on_records``.
    """
    runs = bounded_int("runs", runs, low=1, high=MAX_RUNS, why="runs per level of each stochastic category")
    seed = bounded_int("seed", seed, low=0, high=2**63 - 1, why="a seed of numpy's SeedSequence")
    if max_wall_time is not None:
        max_wall_time = positive_float("max_wall_time", max_wall_time, "[s]")
    if categories is not None and (isinstance(categories, str) or not isinstance(categories, Sequence)):
        raise TypeError(f"categories must be a sequence of category names, got {type(categories).__name__}")
    t0 = time.perf_counter()
    from .swingup.tasks import resolve_task

    # Every selection is checked before the controller is designed (a tvlqr or nmpc plan takes seconds).
    names = _check_selection(resolve_task(task), categories, levels)
    tk, cname, ctrl, x0 = _resolve(controller, task)
    plan: list[tuple[str, int, float, int, tuple[int, ...]]] = []
    for name in names:
        cat = CATEGORIES[name]
        ci = list(CATEGORIES).index(name)
        lv = tuple(float(v) for v in (levels or {}).get(name, cat.levels))
        for li, level in enumerate(lv):
            for r in range(runs if cat.stochastic else 1):
                plan.append((name, li, level, r, (int(seed), ci, li, r)))
    done: dict[RunKey, RunRecord] = {}
    by_key = {(n, li, r, sd): (n, li, lv, r, sd) for n, li, lv, r, sd in plan}
    for rec in completed:
        if not isinstance(rec, RunRecord):
            raise TypeError(f"completed must hold RunRecord objects, got {type(rec).__name__}")
        key = run_key(rec)
        if key not in by_key or by_key[key][2] != rec.level:
            raise ValueError(f"completed record {key} (level {rec.level}) is not a run of this scorecard (other settings?)")
        done[key] = rec
    total = len(plan)
    if progress is not None:
        progress(len(done), total)  # the bar shows up before the plant is compiled
    # One substep count for every run, fine enough for the stiffest/lightest plant of the plan, and its sample
    # map compiled here before the workers fork (so it is built once, not once per worker).
    n_sub = _plan_substeps(tk, ctrl, x0, plan)
    run_episode(ctrl, tk, x0, t_final=ctrl.sample_time, n_sub=n_sub)

    def one(item: tuple[str, int, float, int, tuple[int, ...]]) -> RunRecord:
        name, li, level, r, sd = item
        res = run_episode(ctrl, tk, x0, CATEGORIES[name].perturbation(tk, level, sd), n_sub=n_sub)
        return RunRecord(name, li, level, r, sd, res.success, res.reason, res.t_up)

    todo = [item for item in plan if (item[0], item[1], item[3], item[4]) not in done]
    for batch in _batches(todo, workers):
        if max_wall_time is not None and time.perf_counter() - t0 > max_wall_time:
            raise TimeoutError(
                f"scorecard stopped by its wall-time budget max_wall_time={max_wall_time:g} s: "
                f"{len(done)} of {total} runs recorded"
            )
        base = len(done)

        def report(k: int, n: int, base: int = base) -> None:
            if progress is not None:
                progress(base + k, total)

        for rec in map_runs(one, batch, workers=workers, progress=report):
            done[run_key(rec)] = rec
        if on_records is not None:
            on_records(tuple(done.values()))
    records = [done[(n, li, r, sd)] for n, li, _, r, sd in plan]
    cats: list[CategoryScore] = []
    for name in names:
        mine = [r for r in records if r.category == name]
        n_levels = max(r.level_index for r in mine) + 1
        lv, counts, rates = [], [], []
        for li in range(n_levels):
            at = [r for r in mine if r.level_index == li]
            lv.append(at[0].level)
            counts.append(len(at))
            rates.append(sum(r.success for r in at) / len(at))
        cats.append(CategoryScore(name, CATEGORIES[name].unit, tuple(lv), tuple(counts), tuple(rates), float(np.mean(rates))))
    overall = float(np.mean([c.score for c in cats]))
    return Scorecard(cname, tk.name, tuple(cats), overall, tuple(records), int(seed), runs, time.perf_counter() - t0, n_sub)


def _batches(
    todo: list[tuple[str, int, float, int, tuple[int, ...]]], workers: int | None
) -> list[list[tuple[str, int, float, int, tuple[int, ...]]]]:
    """Whole levels of the plan, consecutive levels merged until a batch keeps every worker busy (>= 4 runs each)."""
    per = 4 * (default_workers() if workers is None else max(1, int(workers)))
    out: list[list[tuple[str, int, float, int, tuple[int, ...]]]] = []
    cur: list[tuple[str, int, float, int, tuple[int, ...]]] = []
    for k, item in enumerate(todo):
        cur.append(item)
        end_of_level = k + 1 == len(todo) or todo[k + 1][:2] != item[:2]
        end_of_category = k + 1 == len(todo) or todo[k + 1][0] != item[0]
        if end_of_level and (len(cur) >= per or end_of_category):
            out.append(cur)
            cur = []
    if cur:
        out.append(cur)
    return out


def _plan_substeps(
    task: Task, ctrl: SampledController, x0: np.ndarray, plan: list[tuple[str, int, float, int, tuple[int, ...]]]
) -> int:
    """Largest RK4 substep count over the distinct plants of a plan (model-parameter levels change the fastest mode)."""
    n = substeps(task.model, ctrl.sample_time, x0)
    seen: set[tuple[str, float]] = set()
    for name, _, level, _, sd in plan:
        pert = CATEGORIES[name].perturbation(task, level, sd)
        if pert.params and (name, level) not in seen:
            seen.add((name, level))
            n = max(n, substeps(task.model.with_params(**dict(pert.params)), ctrl.sample_time, x0))
    return n


def rerun(controller: ControllerSpec, task: Task | str, record: RunRecord, *, n_sub: int | None = None) -> RunRecord:
    """Run one scorecard run again, directly (same category, level and seed).

    Parameters
    ----------
    controller : str or callable
        As for :func:`score`.
    task : Task or str
        As for :func:`score`.
    record : RunRecord
        A run of a scorecard.
    n_sub : int, optional
        RK4 substeps per sample (the scorecard's: ``Scorecard.n_sub``); default from the run's plant.

    Returns
    -------
    RunRecord
        The run's outcome now (equal to ``record`` for a deterministic controller).
    """
    tk, _, ctrl, x0 = _resolve(controller, task)
    pert = CATEGORIES[record.category].perturbation(tk, record.level, record.seed)
    res = run_episode(ctrl, tk, x0, pert, n_sub=n_sub)
    return RunRecord(
        record.category, record.level_index, record.level, record.run, record.seed, res.success, res.reason, res.t_up
    )

"""Robustness scorecard: success rates of one controller on one task under swept perturbations.

Each category of :data:`CATEGORIES` sweeps one perturbation over levels (ranges
after RealAIGym's robustness benchmark, see ``docs/scorecard.md``). Every run is
one closed-loop episode (:func:`pendulab.evaluate.perturb.run_perturbed_episode`) judged by
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

import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .._checks import bounded_int
from .._inputs import checked
from ..control.controllers import controller_for_task
from ..control.feedback import SampledController
from ..control.swingup.tasks import resolve_task
from ..ensemble.pool import default_workers, map_runs
from ..model.model import rigid
from ..model.plant_file import IdentifiedPlant

# Category, categories_for, record_from_dict: re-exported (the old pendulab.control.scorecard had them).
from .card import CategoryScore, RunKey, RunRecord, Scorecard, record_from_dict, run_key  # noqa: F401
from .categories import CATEGORIES, Category, categories_for  # noqa: F401
from .perturb import run_perturbed_episode, substeps

if TYPE_CHECKING:
    from ..control.swingup.tasks import Task

__all__ = ["score", "rerun", "MAX_RUNS", "MAX_LEVELS"]


ControllerSpec = str | SampledController | Callable[["Task"], tuple[SampledController, np.ndarray]]


def _is_object(controller: Any) -> bool:
    """A controller object rather than a factory: a SampledController or a RealAIGym controller."""
    from ..control.realai.adapter import is_realai_controller

    sampled = callable(controller) and all(hasattr(controller, a) for a in ("sample_time", "input_names", "reset"))
    return sampled or is_realai_controller(controller)


def _resolve(
    controller: ControllerSpec, task: Task | str, estimator: Any = None
) -> tuple[Task, str, SampledController, np.ndarray]:
    tk = resolve_task(task)
    if isinstance(controller, str):
        ctrl, x0 = controller_for_task(controller, tk, estimator=estimator)
        return tk, controller, ctrl, np.asarray(x0, dtype=float)
    if _is_object(controller):
        # a controller object (pendulab's, or a RealAIGym one adapted at the task's sample time) starts at the task's start
        from ..control.realai.adapter import from_realai, is_realai_controller

        name = type(controller).__name__
        if is_realai_controller(controller):
            controller = from_realai(controller, task=tk.problem.actuation, sample_time=tk.dt)
        x0 = np.asarray(tk.problem.start, dtype=float)
        ctrl = controller if estimator is None else _estimated(controller, tk, x0, estimator)
        return tk, name, ctrl, x0
    if not callable(controller):
        raise TypeError(f"controller must be a name or a factory task -> (controller, x0), got {type(controller).__name__}")
    made = controller(tk)
    if not (isinstance(made, tuple) and len(made) == 2):
        raise TypeError("a controller factory must return (controller, x0)")
    ctrl, x0 = made
    x0 = np.asarray(x0, dtype=float)
    if estimator is not None:
        ctrl = _estimated(ctrl, tk, x0, estimator)
    return tk, getattr(controller, "__name__", type(controller).__name__), ctrl, x0


def _estimated(ctrl: SampledController, task: Task, x0: np.ndarray, estimator: Any) -> SampledController:
    """A factory's controller fed by ``estimator`` (a name built on the task's model, or an object)."""
    from ..control.robust import EstimatedController, build_estimator
    from ..model.model import INPUT_NAMES

    limit = float(task.problem.torque_limit)
    torque = np.array([limit if n in ctrl.input_names else 0.0 for n in INPUT_NAMES])
    est = build_estimator(estimator, task.model, float(ctrl.sample_time), x0=x0, torque_limit=torque)
    return EstimatedController(ctrl, est, u_max=limit)


def _check_estimator(estimator: Any) -> str | None:
    """The estimator's name for the card (None: none), checked before any design."""
    if estimator is None:
        return None
    from ..control.robust import ESTIMATORS

    if isinstance(estimator, str):
        if estimator not in ESTIMATORS:
            raise ValueError(
                f"estimator must be one of {list(ESTIMATORS)} or an object with reset() and update(), got {estimator!r}"
            )
        return estimator
    if not (callable(getattr(estimator, "reset", None)) and callable(getattr(estimator, "update", None))):
        raise TypeError(
            f"estimator must be one of {list(ESTIMATORS)} or an object with reset() and update(), got {type(estimator).__name__}"
        )
    return type(estimator).__name__


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


@checked(runs="runs_per_level")
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
    estimator: Any = None,
    plant: IdentifiedPlant | None = None,
) -> Scorecard:
    """Robustness scorecard of a controller on a swing-up task.

    Parameters
    ----------
    controller : str or callable
        A name of :func:`pendulab.control.controllers.controller_for_task`
        (``lqr``, ``tvlqr``, ``swingup``, ...) or a factory ``task -> (controller, x0)``.
        The controller is designed once on the nominal model; every run resets it.
        Or a controller object started at the task's start state: a
        :class:`~pendulab.control.feedback.SampledController`, or a RealAIGym controller (``init``,
        ``get_control_output(x, t)``, ``reset``) adapted by :func:`~pendulab.control.realai.adapter.from_realai`
        at the task's sample time on its driven joint.
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
    estimator : {"ekf", "mmae"} or StateEstimator, optional
        Feed every run's controller the estimator's state instead of the measurement
        (:class:`~pendulab.control.robust.EstimatedController`; a name is built by
        :func:`~pendulab.control.robust.build_estimator` on the task's model at the controller's
        sample time from the start state, and reset with the controller before each run). The
        measurement-noise and delay categories then act on the filter's input.
    plant : IdentifiedPlant, optional
        Run every episode on an identified robot (``pendulab identify``; a rigid task only)
        instead of the task's model; the controller is still designed on the task's model (as on
        the real robot), the model-parameter categories perturb the identified values.

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
        a Task nor a name, an estimator that is neither a name nor an object with
        ``reset`` and ``update``.
    TimeoutError
        The wall-time budget ran out.
    KeyboardInterrupt
        Ctrl-C; the batches finished before it were passed to ``on_records``.

    Examples
    --------
    >>> from pendulab.evaluate import score
    >>> levels = {"damping": [0.0, 0.1], "friction": [0.0, 0.2]}  # added joint damping [N.m.s/rad], Coulomb friction [N.m]
    >>> card = score("swingup", "pendubot", categories=list(levels), levels=levels, workers=1)
    >>> print(card.table())
    Robustness of `swingup` on `pendubot` (success rate per level; 20 runs per level of the stochastic categories)
    <BLANKLINE>
    | category | unit | levels: success rate | score |
    |---|---|---|---|
    | damping | N.m.s/rad | 0: 100%, 0.1: 0% | 0.50 |
    | friction | N.m | 0: 100%, 0.2: 0% | 0.50 |
    | **overall** | | | **0.50** |
    """
    runs = int(runs)
    seed = int(seed)
    if max_wall_time is not None:
        max_wall_time = float(max_wall_time)
    if categories is not None and (isinstance(categories, str) or not isinstance(categories, Sequence)):
        raise TypeError(f"categories must be a sequence of category names, got {type(categories).__name__}")
    t0 = time.perf_counter()
    # Every selection is checked before the controller is designed (a tvlqr or nmpc plan takes seconds).
    names = _check_selection(resolve_task(task), categories, levels)
    est_name = _check_estimator(estimator)
    plant_model = None
    if plant is not None:
        if not isinstance(plant, IdentifiedPlant):
            raise TypeError(
                f"plant must be an IdentifiedPlant (pendulab.model.plant_file.load_plant), got {type(plant).__name__}"
            )
        plant_model = rigid(**plant.rigid_kwargs())
        resolve_task(task).with_model(plant_model)  # a kind mismatch raises here, before the design
    tk, cname, ctrl, x0 = _resolve(controller, task, estimator)
    if plant_model is not None:  # the controller above is designed on the task; the episodes below run on the plant
        tk = tk.with_model(plant_model)
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
    run_perturbed_episode(ctrl, tk, x0, t_final=ctrl.sample_time, n_sub=n_sub)

    def one(item: tuple[str, int, float, int, tuple[int, ...]]) -> RunRecord:
        name, li, level, r, sd = item
        res = run_perturbed_episode(ctrl, tk, x0, CATEGORIES[name].perturbation(tk, level, sd), n_sub=n_sub)
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
    return Scorecard(
        cname, tk.name, tuple(cats), overall, tuple(records), int(seed), runs, time.perf_counter() - t0, n_sub, est_name
    )


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


@checked()
def rerun(
    controller: ControllerSpec, task: Task | str, record: RunRecord, *, n_sub: int | None = None, estimator: Any = None
) -> RunRecord:
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
    estimator : {"ekf", "mmae"} or StateEstimator, optional
        As for :func:`score` (the scorecard's ``Scorecard.estimator``).

    Returns
    -------
    RunRecord
        The run's outcome now (equal to ``record`` for a deterministic controller).

    Examples
    --------
    >>> from pendulab.evaluate import score
    >>> card = score("swingup", "pendubot", categories=["damping"], levels={"damping": [0.0, 0.1]}, workers=1)
    >>> from pendulab.evaluate import rerun
    >>> failed = card.failures[0]  # look at one failed run again, alone
    >>> failed.category, failed.level, failed.reason
    ('damping', 0.1, 'end effector below 0.45 m in the last second (min -0.463 m)')
    >>> rerun("swingup", "pendubot", failed) == failed  # the same seed: the same outcome
    True
    """
    _check_estimator(estimator)
    tk, _, ctrl, x0 = _resolve(controller, task, estimator)
    pert = CATEGORIES[record.category].perturbation(tk, record.level, record.seed)
    res = run_perturbed_episode(ctrl, tk, x0, pert, n_sub=n_sub)
    return RunRecord(
        record.category, record.level_index, record.level, record.run, record.seed, res.success, res.reason, res.t_up
    )

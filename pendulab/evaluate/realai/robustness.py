"""RealAIGym robustness leaderboard v2: the owners' benchmark protocol, run on pendulab's plant with any controller.

What the protocol does (read in github.com/dfki-ric-underactuated-lab/double_pendulum, stored
copy at commit 1e8544e: ``leaderboard/{pendubot,acrobot}/robustness_v2/benchmark_controller.py``
and ``sim_parameters.py``, ``src/python/double_pendulum/analysis/benchmark.py`` (``benchmarker``),
``analysis/benchmark_scores.py``, ``analysis/utils.py`` (``get_par_list``),
``simulation/simulation.py`` (``Simulator``), ``simulation/perturbations.py``,
``leaderboard/*/robustness_v2/create_leaderboard.py``):

* plant: design C.1, model 1.0, motor inertia, damping and Coulomb friction 0, torque limit
  6 N.m on the actuated joint (:mod:`.plant`); classic RK4 at 2 ms from hanging at rest, while
  ``t < 10`` (5000 steps, ``t`` accumulated in floating point);
* every step: measurement (state ``n_delay = int(delay/dt) + 1`` records back, then
  ``normal(x, sigma)`` on the joint-coordinate state), controller at ``(t, x_meas)``, applied
  torque ``u = u_last + k (u_cmd - u_last)`` (``u_last``: the torque applied in the previous
  step), ``normal(u, sigma_u)``, clipped to the limits, plus the perturbation at
  ``int(t/dt)`` (after the clip; the plant's input matrix drops the passive joint's),
  one RK4 step, ``normal(x, 0)`` process noise;
* six categories (:data:`CATEGORIES`): 10 model parameters x 21 values; velocity measurement
  noise sigma = linspace(0, 0.5, 21) x 10 repetitions; torque noise sigma = linspace(0, 1.1, 21)
  x 10 repetitions; torque responsiveness k = linspace(0.1, 2, 21); delay linspace(0, 0.04, 21)
  (positions and velocities); 50 runs with 3 Gaussian torque pulses per joint
  (``get_random_gauss_perturbation_array(10, 0.002, 3, 1.0, [0.05, 0.1], [0.5, 5.0])``);
  722 runs in all;
* success: only the final state, angles wrapped (``wrap_angles_top``), within
  (0.35, 0.35, 1, 1) of (pi, 0, 0, 0) in joint coordinates;
* category rate: successes / runs (model, responsiveness, delay, perturbations); for the two
  noise categories a level succeeds when the mean of its 10 repetitions exceeds 0.5;
  score = the mean of the six rates (:func:`robustness_score`).

Random numbers: upstream draws everything from NumPy's global legacy generator (4 normals for
the measurement, 2 for the torque and 4 for the process noise every step, also at sigma 0;
``rand``, ``shuffle``, ``rand``, ``uniform`` for a perturbation). :func:`robustness_v2` makes the
same draws in the same order from ``np.random.RandomState(seed)``, so it reproduces an upstream
run seeded with ``np.random.seed(seed)`` draw for draw; each run's generator state is computed
up front, which lets the runs go to parallel workers in any order.

The protocol is in four modules: :mod:`.robustness_grid` (the definition: grids, plan, random draws),
:mod:`.robustness_episode` (one run), :mod:`.robustness_scores` (rates, score, result) and this one (running the
plan: workers, journal, resume).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ..._inputs import checked
from ..._journal import Journal
from ...control.feedback import SampledController
from ...control.realai.spec import DT, check_task
from ...control.swingup.tasks import short_name
from ...ensemble.pool import default_workers, map_runs
from ...model.plant_file import IdentifiedPlant
from .controllers import controller_name, resolve_controller
from .plant import MODEL_VARIATIONS, plant_label
from .robustness_episode import _hold_ratio, run_protocol_episode
from .robustness_grid import (
    CATEGORIES,
    CATEGORY_LABELS,
    PERTURBATION_REPETITIONS,
    PUBLISHED_ROBUSTNESS,
    QUICK_LEVELS,
    REPETITIONS,
    RunSpec,
    _check_names,
    _n_steps,
    _rng_states,
    plan_runs,
    protocol_grid,
    random_gauss_perturbation,
)
from .robustness_scores import RobustnessResult, category_rates, level_successes, robustness_score

__all__ = [
    "CATEGORIES",
    "CATEGORY_LABELS",
    "PUBLISHED_ROBUSTNESS",
    "QUICK_LEVELS",
    "RobustnessResult",
    "RunSpec",
    "category_rates",
    "level_successes",
    "plan_runs",
    "protocol_grid",
    "random_gauss_perturbation",
    "robustness_score",
    "robustness_v2",
    "run_protocol_episode",
]

# -- the protocol ---------------------------------------------------------------------------------------------------


def _levels(plan: Sequence[RunSpec]) -> dict[str, Any]:
    lv: dict[str, Any] = {"model": {}}
    for s in plan:
        if s.category == "model":
            lv["model"].setdefault(s.param, [])
            if s.level not in lv["model"][s.param]:
                lv["model"][s.param].append(s.level)
        else:
            seq = lv.setdefault(s.category, [])
            value = s.level_index if s.category == "perturbation" else s.level
            if value not in seq:
                seq.append(value)
    return lv


#: Kind of the robustness-v2 journals (:mod:`pendulab._journal`).
JOURNAL_KIND = "robustness-v2"
#: Fields of every journaled run (:func:`run_protocol_episode`); a perturbation run also has :data:`_PULSE_FIELDS`.
_RUN_FIELDS = (
    "index", "category", "param", "level_index", "level", "rep", "success", "final", "ctrl_median", "ctrl_max", "calls",
    "wall",
)  # fmt: skip
_PULSE_FIELDS = ("mu", "sigma", "amplitude")


def _run_check(plan: Sequence[RunSpec]) -> Callable[[str, Any], None]:
    """``check(key, record)`` of the journal: raise for a record that lacks a field or is not the plan's run ``key``."""
    by_index = {str(s.index): s for s in plan}

    def check(key: str, rec: Any) -> None:
        if not isinstance(rec, Mapping):
            raise TypeError(f"a run record is a JSON object, got {type(rec).__name__}")
        spec = by_index.get(key)
        if spec is None:
            raise ValueError(f"run {key} is not in this plan")
        for name in _RUN_FIELDS + (_PULSE_FIELDS if spec.category == "perturbation" else ()):
            if name not in rec:
                raise KeyError(name)
        stored = (rec["index"], rec["category"], rec["param"], rec["level_index"], rec["rep"])
        if stored != (spec.index, spec.category, spec.param, spec.level_index, spec.rep) or not isinstance(rec["success"], bool):
            raise ValueError(f"its fields are not those of run {key} ({spec.category} {spec.param} level {spec.level_index})")

    return check


@checked(seed="legacy_seed", perturbation_repetitions="repetitions", u_noise_repetitions="repetitions")
def robustness_v2(
    task: str,
    controller: str | SampledController | Callable[[str], Any] = "best",
    *,
    seed: int = 0,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    journal: str | Path | None = None,
    resume: bool = False,
    levels: Sequence[int] | None = None,
    repetitions: int = REPETITIONS,
    perturbation_repetitions: int = PERTURBATION_REPETITIONS,
    categories: Sequence[str] | None = None,
    model_params: Sequence[str] | None = None,
    u_noise_repetitions: int = REPETITIONS,
    every_step: bool = False,
    plant: IdentifiedPlant | None = None,
) -> RobustnessResult:
    """Score a controller on the RealAIGym robustness leaderboard v2 protocol.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (``swingup_pendubot``, ``swingup_acrobot`` are aliases).
    controller : str, SampledController or callable
        See :func:`resolve_controller` (names: :data:`CONTROLLERS`).
    seed : int
        Seed of the legacy generator; the draws equal upstream's after ``np.random.seed(seed)``.
    workers : int, optional
        Worker processes (:func:`pendulab.ensemble.pool.map_runs`; default all cores).
    progress : callable, optional
        ``progress(done, total)`` in runs (journaled runs count as done).
    journal : str or Path, optional
        Journal rewritten atomically after every batch of finished runs (:mod:`pendulab._journal`: pendulab
        version, settings, each run with its SHA-256).
    resume : bool
        Read ``journal`` first (before the controller is built) and run only the runs it lacks; runs that were
        edited, lack fields or were written by another pendulab version are run again, with a
        :class:`~pendulab._journal.JournalWarning` naming the file and the runs.
    levels : sequence of int, optional
        Reduced grid: the grid indices (0 ... 20) to run in every category (default all).
    repetitions : int
        Repetitions per measurement-noise level (upstream 10; torque noise: always 10, as upstream).
    perturbation_repetitions : int
        Perturbation runs (upstream 50).
    categories, model_params, u_noise_repetitions
        A reduced protocol (tests, comparisons): see :func:`plan_runs`. Without all six
        categories the score is NaN (``None`` in :meth:`RobustnessResult.to_dict`).
    every_step : bool
        Call the controller every 2 ms step (as upstream's simulator calls its controllers) instead of on
        its own sample grid with the output held. A 10 ms controller fed fresh noisy measurements every
        2 ms averages the velocity noise out; held, one noisy sample drives 10 ms.
    plant : IdentifiedPlant, optional
        Simulate an identified robot (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model; the model
        variations are relative to the identified values.

    Returns
    -------
    RobustnessResult
        Rates, score, per-level successes, records, wall time, controller timing.

    Raises
    ------
    ValueError
        Unknown task or controller name, bad grid, seed out of range, a journal of other settings
        (:class:`~pendulab._journal.JournalError`), a controller whose sample time is not a multiple of 2 ms.
    PermissionError
        Nothing can be written where ``journal`` goes (checked before any run).
    TypeError
        A controller that is neither a name, a controller nor a factory.
    KeyboardInterrupt
        Ctrl-C (the batches finished before it are in the journal).
    """
    if not isinstance(task, str):
        raise TypeError(f"task must be 'pendubot' or 'acrobot', got {type(task).__name__}")
    task = check_task(short_name(task))
    seed = int(seed)
    if resume and journal is None:
        raise ValueError("resume=True needs a journal path")
    w0 = time.perf_counter()
    plan = plan_runs(
        task, levels=levels, repetitions=repetitions, perturbation_repetitions=perturbation_repetitions,
        categories=categories, model_params=model_params, u_noise_repetitions=u_noise_repetitions, plant=plant,
    )  # fmt: skip
    settings = {
        "protocol": "robustness-v2",
        "task": task,
        "controller": controller_name(controller),
        "seed": seed,
        "levels": None if levels is None else sorted({int(v) for v in levels}),
        "repetitions": int(repetitions),
        "perturbation_repetitions": int(perturbation_repetitions),
        "categories": list(_check_names("categories", categories, CATEGORIES)),
        "model_params": list(_check_names("model_params", model_params, MODEL_VARIATIONS)),
        "u_noise_repetitions": int(u_noise_repetitions),
        "every_step": bool(every_step),
        "plant": plant_label(plant),
    }
    # The journal is validated before the controller is built (a plan or an ROA takes seconds to minutes): only
    # runs that pass their hashes and belong to this plan are reused; the others are run again (JournalWarning).
    log = Journal(journal, JOURNAL_KIND, settings, resume=resume, check=_run_check(plan))
    done: dict[int, dict[str, Any]] = {int(k): rec for k, rec in log.records.items()}
    name, ctrl = resolve_controller(task, controller)
    if not every_step:
        _hold_ratio(ctrl)
    total = len(plan)
    if progress is not None:
        progress(len(done), total)
    states = _rng_states(plan, seed, _n_steps())

    def one(i: int) -> dict[str, Any]:
        return run_protocol_episode(task, ctrl, plan[i], states[i], every_step=every_step, plant=plant)

    todo = [s.index for s in plan if s.index not in done]
    n_work = default_workers() if workers is None else int(workers)
    per = max(8, 4 * n_work)
    for b in range(0, len(todo), per):
        batch = todo[b : b + per]
        base = len(done)

        def report(k: int, n: int, base: int = base) -> None:
            if progress is not None:
                progress(base + k, total)

        for rec in map_runs(one, batch, workers=n_work, progress=report, chunks_per_worker=1):
            done[rec["index"]] = rec
            log.add(str(rec["index"]), rec)
        log.save()
    records = [done[s.index] for s in plan]
    successes = level_successes(records)
    rates = category_rates(successes)
    complete = (
        levels is None and repetitions == REPETITIONS and perturbation_repetitions == PERTURBATION_REPETITIONS
        and categories is None and model_params is None and u_noise_repetitions == REPETITIONS
    )  # fmt: skip
    score = robustness_score(rates) if all(c in rates for c in CATEGORIES) else math.nan
    return RobustnessResult(
        task, name, seed, rates, score, successes, _levels(plan), records,
        time.perf_counter() - w0, DT if every_step else float(ctrl.sample_time), complete, plant_label(plant),
    )  # fmt: skip

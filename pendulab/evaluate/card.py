"""What a robustness scorecard records: each run, the success rates per category, the card and its JSON/Markdown.

The aggregation rule (a category's score is the mean success rate over its
levels; the overall score the mean of the category scores) is stated in
:class:`Scorecard` and in its JSON.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

__all__ = ["RunRecord", "CategoryScore", "Scorecard", "RunKey", "run_key", "record_from_dict"]

#: Identity of a run within a scorecard (category, level index, run, seed): what ``completed`` records are matched by.
RunKey = tuple[str, int, int, tuple[int, ...]]


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

    Examples
    --------
    >>> from pendulab.evaluate import score
    >>> card = score("swingup", "pendubot", categories=["damping"], levels={"damping": [0.0, 0.1]}, workers=1)
    >>> for record in card.records:
    ...     print(record.category, record.level, record.seed, record.success, record.t_up)
    damping 0.0 (0, 3, 0, 0) True 5.13
    damping 0.1 (0, 3, 1, 0) False nan
    >>> card.records[1].reason
    'end effector below 0.45 m in the last second (min -0.463 m)'
    """

    category: str
    level_index: int
    level: float
    run: int
    seed: tuple[int, ...]
    success: bool
    reason: str
    t_up: float

    def __eq__(self, other: object) -> bool:
        # Field by field, with a nan swing-up time (every failed run) equal to nan: rerun() of a failed run equals it.
        if not isinstance(other, RunRecord):
            return NotImplemented
        same_t_up = self.t_up == other.t_up or (math.isnan(self.t_up) and math.isnan(other.t_up))
        return same_t_up and (self.category, self.level_index, self.level, self.run, self.seed, self.success, self.reason) == (
            other.category, other.level_index, other.level, other.run, other.seed, other.success, other.reason,
        )  # fmt: skip


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

    Examples
    --------
    >>> from pendulab.evaluate import score
    >>> card = score("swingup", "pendubot", categories=["damping"], levels={"damping": [0.0, 0.1]}, workers=1)
    >>> damping = card.categories[0]
    >>> damping.name, damping.unit, damping.levels, damping.runs
    ('damping', 'N.m.s/rad', (0.0, 0.1), (1, 1))
    >>> damping.success_rates, damping.score  # swings up without joint damping, not with 0.1 N.m.s/rad more
    ((1.0, 0.0), 0.5)
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
    estimator : str or None
        The state estimator every run's controller was fed by (``"ekf"``, ``"mmae"`` or the class name of an
        estimator object); None: the controller saw the measurement.

    Examples
    --------
    >>> from pendulab.evaluate import score
    >>> card = score("swingup", "pendubot", categories=["damping"], levels={"damping": [0.0, 0.1]}, workers=1)
    >>> card.controller, card.task, card.overall, len(card.records)
    ('swingup', 'pendubot', 0.5, 2)
    >>> [f.reason for f in card.failures]
    ['end effector below 0.45 m in the last second (min -0.463 m)']
    >>> import json
    >>> json.loads(card.to_json())["overall"]
    0.5
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
    estimator: str | None = None

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
            controller, estimator, task, overall, seed, runs_per_level, wall_time_s,
            categories (name, unit, levels, runs, success_rates, score) and
            failures (category, level, run, seed, reason).
        """
        return {
            "controller": self.controller,
            "estimator": self.estimator,
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
        fed = f" fed by `{self.estimator}`" if self.estimator else ""
        lines = [
            f"Robustness of `{self.controller}`{fed} on `{self.task}` (success rate per level; "
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

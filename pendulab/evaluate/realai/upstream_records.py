"""The ICRA 2025 entries' scores on pendulab's v3-hardware protocol, read from ``benchmarks/bench_upstream_entries.py``'s records.

The entries (AcadosMPC, AR-EAPO, MC-PILCO; VIMPPI needs a GPU) run only with the upstream package installed from a
fetched snapshot, in a venv of their own, never in CI. That benchmark writes one JSON per finished case into
``./pendulab-out/upstream_entries/`` (:data:`UPSTREAM_RECORDS`); the leaderboard reads the hardware-final submissions'
v3-hardware cases back from there, to put each entry's simulated score beside its score on the real robot
(:data:`~.leaderboard_published.PUBLISHED_HARDWARE`). A record that does not have the expected fields is skipped and named, never
guessed at.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .leaderboard_published import PUBLISHED_HARDWARE

__all__ = ["UPSTREAM_RECORDS", "ENTRY_LABELS", "EntryScores", "read_hardware_entries", "spearman_rho"]

#: Where ``benchmarks/bench_upstream_entries.py`` records its cases (relative to the current directory).
UPSTREAM_RECORDS = Path("pendulab-out") / "upstream_entries"
#: Upstream entry id -> the name on the ICRA 2025 leaderboard.
ENTRY_LABELS: dict[str, str] = {"acados_mpc": "AcadosMPC", "ar_eapo": "AR-EAPO", "mcpilco": "MC-PILCO", "vimppi": "VIMPPI"}


@dataclass(frozen=True)
class EntryScores:
    """One entry's recorded v3-hardware episodes on one task.

    Attributes
    ----------
    entry : str
        Upstream id (``acados_mpc``, ...).
    task : str
        ``pendubot`` or ``acrobot``.
    seeds : tuple of int
        Schedule seeds of the episodes, ascending.
    scores : tuple of float
        Score (uptime / 60 s) of each episode, in ``seeds`` order.
    published_hardware : float
        The entry's best run on the real robot (ICRA 2025 final).
    approximation : str
        Empty when the submitted controller ran as submitted; else the benchmark's note on how it was approximated
        (e.g. the acados acrobot entry's SQP capped at 3 iterations: the available acados has no SQP timeout).
    """

    entry: str
    task: str
    seeds: tuple[int, ...]
    scores: tuple[float, ...]
    published_hardware: float
    approximation: str = ""

    @property
    def label(self) -> str:
        """The leaderboard's name of the entry."""
        return ENTRY_LABELS.get(self.entry, self.entry)

    @property
    def mean(self) -> float:
        """Mean score over the seeds."""
        return float(np.mean(self.scores))

    @property
    def std(self) -> float:
        """Standard deviation of the scores over the seeds (0 for one seed)."""
        return float(np.std(self.scores, ddof=1)) if len(self.scores) > 1 else 0.0


def read_hardware_entries(directory: str | Path, task: str, passive_allowance: float) -> tuple[list[EntryScores], list[str]]:
    """The hardware-final submissions' recorded v3-hardware episodes on ``task`` at ``passive_allowance``.

    Parameters
    ----------
    directory : str or Path
        The benchmark's record folder (default location :data:`UPSTREAM_RECORDS`); a missing folder gives no entries.
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    passive_allowance : float
        Only episodes run with this passive-joint allowance [N.m] are read.

    Returns
    -------
    entries : list of EntryScores
        One per entry with at least one finished episode, best published hardware score first.
    skipped : list of str
        Files that looked like such records but could not be read, each with the reason.

    Raises
    ------
    ValueError
        ``task`` is not a leaderboard task.
    """
    if task not in PUBLISHED_HARDWARE:
        raise ValueError(f"task must be one of {list(PUBLISHED_HARDWARE)}, got {task!r}")
    folder = Path(directory)
    runs: dict[str, dict[int, float]] = {}
    approximations: dict[str, str] = {}
    skipped: list[str] = []
    # The benchmark names each case <variant>_<entry>_<task>_<protocol>_s<seed>[_a<allowance>].json.
    for path in sorted(folder.glob(f"hw_*_{task}_v3-hardware_s*.json")) if folder.is_dir() else ():
        try:
            rec = json.loads(path.read_text())
            if rec.get("status") != "ok":
                continue
            if not math.isclose(float(rec["allowance"]), passive_allowance, abs_tol=1e-12):
                continue
            entry, seed, score = str(rec["entry"]), int(rec["seed"]), float(rec["score"])
            notes = [str(n) for n in rec.get("notes", [])]
            if rec["variant"] != "hw" or rec["task"] != task or rec["protocol"] != "v3-hardware":
                raise ValueError(f"its fields (variant {rec['variant']!r}, task {rec['task']!r}) contradict its name")
            if entry not in PUBLISHED_HARDWARE[task] or not (math.isfinite(score) and 0.0 <= score <= 1.0):
                raise ValueError(f"entry {entry!r} or score {score!r} outside what the hardware final published")
        except (OSError, ValueError, KeyError, TypeError) as exc:
            skipped.append(f"{path.name}: {type(exc).__name__}: {exc}")
            continue
        runs.setdefault(entry, {})[seed] = score
        # The benchmark says "an approximation of the submitted controller" where it could not run it as submitted.
        for note in (n for n in notes if "approximation" in n):
            approximations[entry] = note
    entries = []
    for e, by_seed in runs.items():
        seeds = tuple(sorted(by_seed))
        scores = tuple(by_seed[k] for k in seeds)
        entries.append(EntryScores(e, task, seeds, scores, PUBLISHED_HARDWARE[task][e], approximations.get(e, "")))
    entries.sort(key=lambda es: -es.published_hardware)
    return entries, skipped


def spearman_rho(a: Sequence[float], b: Sequence[float]) -> float:
    """Spearman's rank correlation of two equally long sequences (ties take their mean rank).

    Parameters
    ----------
    a, b : sequence of float, length n >= 2
        Paired values.

    Returns
    -------
    float
        rho in [-1, 1]; nan when either sequence is constant.

    Raises
    ------
    ValueError
        Different lengths or fewer than two pairs.
    """
    x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if x.shape != y.shape or x.ndim != 1 or x.size < 2:
        raise ValueError(f"a and b must be two sequences of the same length >= 2, got shapes {x.shape} and {y.shape}")
    rx, ry = _ranks(x), _ranks(y)
    if np.ptp(rx) == 0 or np.ptp(ry) == 0:
        return float("nan")
    return float(np.corrcoef(rx, ry)[0, 1])


def _ranks(v: np.ndarray) -> np.ndarray:
    order = np.argsort(v, kind="stable")
    ranks = np.empty(v.size)
    ranks[order] = np.arange(1, v.size + 1)
    for value in np.unique(v):  # ties: the mean of their ranks
        tied = v == value
        ranks[tied] = ranks[tied].mean()
    return ranks

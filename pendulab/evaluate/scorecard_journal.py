"""The scorecard's journal: every finished run, with the pendulab version, the settings and SHA-256 hashes.

``pendulab score`` (``DIR/records.json``) and the leaderboard's own scorecards (``scorecard/TASK-CONTROLLER/
records.json``) rewrite it after each batch of runs and, with ``--resume``, read back only the runs that validate
(:mod:`pendulab._journal`): an edited, incomplete or older record is run again, never published.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

from .._journal import Journal, finite
from .card import RunRecord, record_from_dict, run_key

__all__ = ["KIND", "record_id", "open_journal", "save_records"]

#: Kind of the scorecard journals.
KIND = "scorecard"


def record_id(record: RunRecord) -> str:
    """The journal key of a run: ``category/level_index/run/seed,seed,...``.

    Parameters
    ----------
    record : RunRecord
        A run.

    Returns
    -------
    str
        Its key (:func:`~pendulab.evaluate.card.run_key` as text).
    """
    cat, li, r, seed = run_key(record)
    return f"{cat}/{li}/{r}/{','.join(str(v) for v in seed)}"


def _check(key: str, data: Any) -> None:
    """Raise for a journaled run that lacks a field, is malformed or is filed under another run's key."""
    if not isinstance(data, Mapping):
        raise TypeError(f"a run record is a JSON object, got {type(data).__name__}")
    missing = [f.name for f in fields(RunRecord) if f.name not in data]
    if missing:
        raise KeyError(missing[0])  # reported as "lacks field ..."
    if record_id(record_from_dict(data)) != key:
        raise ValueError(f"its fields are those of run {record_id(record_from_dict(data))}")


def open_journal(path: str | Path, settings: Mapping[str, Any], *, resume: bool) -> tuple[Journal, tuple[RunRecord, ...]]:
    """The scorecard journal at ``path`` and, with ``resume``, the runs of it that validate.

    Parameters
    ----------
    path : str or Path
        The journal file (``records.json``).
    settings : mapping
        Everything the runs depend on (controller, task, runs, seed, categories, ...).
    resume : bool
        Read the file's validated runs (notices as :class:`~pendulab._journal.JournalWarning`).

    Returns
    -------
    journal : Journal
        To pass to :func:`save_records`.
    completed : tuple of RunRecord
        The validated runs (for :func:`~pendulab.evaluate.scorecard.score`'s ``completed``).

    Raises
    ------
    pendulab._journal.JournalError
        ``resume`` and a journal of this pendulab version with other settings, or of another kind.
    """
    journal = Journal(path, KIND, settings, resume=resume, check=_check)
    return journal, tuple(record_from_dict(d) for d in journal.records.values())


def save_records(journal: Journal, records: Iterable[RunRecord], **meta: Any) -> None:
    """Journal ``records`` (every run so far) and rewrite the file atomically.

    Parameters
    ----------
    journal : Journal
        From :func:`open_journal`.
    records : iterable of RunRecord
        The runs.
    **meta
        Meta data (``complete``, ``wall_time``), hashed with the records.
    """
    for r in records:
        journal.add(record_id(r), finite(asdict(r)))
    journal.save(**meta)

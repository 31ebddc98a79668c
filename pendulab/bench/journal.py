"""Journal of a long study: every finished unit of work, rewritten atomically after each one.

A study (work-precision, stability, the model-choice benchmark) records each finished case in a journal of
:mod:`pendulab._journal` (kind = the study's name, settings = its ``config``): an interrupted or crashed run keeps
everything finished before it, and a run with ``resume=True`` skips the recorded keys that validate (pendulab
version, settings and each entry's SHA-256; an edited, incomplete or older entry is computed again, with a
:class:`~pendulab._journal.JournalWarning`). The file is replaced atomically after every entry, so it is never
truncated. Values are JSON (NaN and inf are written as the JSON extensions ``NaN`` / ``Infinity``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .._journal import Journal as _Journal

__all__ = ["Journal"]


class Journal(_Journal):
    """Finished units of one study, kept in a validated journal file (or only in memory when ``path`` is None).

    Parameters
    ----------
    path : str or Path or None
        The journal file; None keeps the entries in memory only.
    study : str
        Name of the study (a journal of another study is not resumed).
    config : mapping
        Settings that change the results (e.g. ``quick``, ``repeats``); resuming
        a journal of this pendulab version written with other settings is an error.
    resume : bool
        Continue the validated entries of an existing journal; otherwise start empty
        (an existing file is replaced at the first entry).
    check : callable, optional
        ``check(key, value)`` raising ``KeyError``, ``ValueError`` or ``TypeError`` for an entry that is
        incomplete or malformed (it is computed again).

    Raises
    ------
    ValueError
        ``resume`` and the file is a journal of another study, or of this pendulab version written with
        another ``config`` (:class:`~pendulab._journal.JournalError`).
    """

    def __init__(
        self,
        path: str | Path | None,
        study: str,
        config: Mapping[str, Any],
        *,
        resume: bool = False,
        check: Callable[[str, Any], Any] | None = None,
    ) -> None:
        super().__init__(path, study, config, resume=resume, check=check)
        self.study, self.config = study, self.settings

    @property
    def entries(self) -> dict[str, Any]:
        """The recorded values by key."""
        return self.records

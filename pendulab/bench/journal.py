"""Journal of a long study: every finished unit of work, rewritten atomically after each one.

A study (work-precision, stability) records each finished case in a JSON file
``{"study": ..., "config": {...}, "entries": {key: value}}``; an interrupted or
crashed run keeps everything finished before it, and a run with ``resume=True``
skips the recorded keys. The file is replaced with :func:`pendulab._io.atomic_write_text`
after every entry, so it is never truncated. Values are JSON (NaN and inf are
written as the JSON extensions ``NaN`` / ``Infinity`` that :mod:`json` reads back).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .._io import atomic_write_text

__all__ = ["Journal"]


class Journal:
    """Finished units of one study, kept in a JSON file (or only in memory when ``path`` is None).

    Parameters
    ----------
    path : str or Path or None
        The journal file; None keeps the entries in memory only.
    study : str
        Name of the study (a journal of another study is not resumed).
    config : mapping
        Settings that change the results (e.g. ``quick``, ``repeats``); resuming
        a journal written with other settings is an error.
    resume : bool
        Continue the entries of an existing journal; otherwise start empty
        (an existing file is replaced at the first entry).

    Raises
    ------
    ValueError
        ``resume`` and the file is not a journal of this study, or was written
        with another ``config``.
    """

    def __init__(self, path: str | Path | None, study: str, config: Mapping[str, Any], *, resume: bool = False) -> None:
        self.path = None if path is None else Path(path)
        self.study = study
        self.config = dict(config)
        self.entries: dict[str, Any] = {}
        self.resumed = 0
        if resume and self.path is not None and self.path.exists():
            try:
                data = json.loads(self.path.read_text(encoding="utf-8"))
            except (OSError, ValueError) as exc:
                raise ValueError(f"resume: cannot read the journal {str(self.path)!r}: {exc}") from None
            if not isinstance(data, dict) or data.get("study") != study or not isinstance(data.get("entries"), dict):
                raise ValueError(f"resume: {str(self.path)!r} is not a journal of the {study!r} study")
            if data.get("config") != self.config:
                raise ValueError(
                    f"resume: the journal {str(self.path)!r} was written with {data.get('config')}, this run uses "
                    f"{self.config}; rerun with the same settings, or without --resume to start again"
                )
            self.entries = dict(data["entries"])
            self.resumed = len(self.entries)

    def __contains__(self, key: str) -> bool:
        return key in self.entries

    def __len__(self) -> int:
        return len(self.entries)

    def get(self, key: str) -> Any:
        """The recorded value of ``key`` (None when not recorded).

        Parameters
        ----------
        key : str
            Unit of work.

        Returns
        -------
        Any
            The JSON value given to :meth:`record`.
        """
        return self.entries.get(key)

    def record(self, key: str, value: Any) -> None:
        """Record a finished unit and rewrite the journal file atomically.

        Parameters
        ----------
        key : str
            Unit of work.
        value : Any
            JSON-serializable result.
        """
        self.entries[key] = value
        if self.path is not None:
            text = json.dumps({"study": self.study, "config": self.config, "entries": self.entries})
            atomic_write_text(self.path, text)

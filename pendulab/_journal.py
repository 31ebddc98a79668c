"""Journals that cannot lie: resumable work, recorded with its pendulab version, its settings and integrity hashes.

Every resumable piece of work (a scorecard, a RealAIGym protocol, a leaderboard case, a flip map, a benchmark
study) keeps its finished units in a journal, rewritten atomically (:func:`pendulab._io.atomic_write_text`)
after each batch. A journal file is one JSON object::

    {"format": "pendulab-journal", "format_version": 1, "kind": "scorecard",
     "pendulab_version": "0.1.0+src.1a2b3c4d5e6f7a8b", "settings": {...}, "header_sha256": "...",
     "meta": {...}, "meta_sha256": "...",
     "records": {"KEY": {"sha256": "...", "data": {...}}, ...}}

``header_sha256`` is the SHA-256 of the canonical JSON (sorted keys, no spaces) of the kind, the version and the
settings; each record's ``sha256`` covers the same and the record's key and data; ``meta_sha256`` the same and the
meta data (wall time, "complete"). Reading for resume (:class:`Journal` with ``resume=True``) validates before any
work is done, and trusts nothing that does not validate:

* a file that is not valid JSON (truncated, damaged), a JSON file without the journal format (written by an
  older pendulab), another pendulab version, another format version, or a header that does not match its hash
  (settings edited by hand): **stale** -- no record is reused, everything is re-run, one notice. The version is
  :func:`~pendulab._version.source_version`: the release number *and* a digest of the package's source, so the work
  of edited code (a changed controller constant) is stale too, though the release number stayed the same;
* a record that does not match its hash (edited, damaged) or that lacks fields or does not belong to this work
  (the caller's ``check``): **dropped** and re-run, one notice per problem naming the records;
* meta data that do not match their hash: dropped (e.g. a wall time is then "not journaled"), one notice;
* a pendulab journal of another kind, or one of this version written with other settings: :class:`JournalError`
  (a ``ValueError``) naming the file and what differs -- it is another experiment, not stale work, and a resume
  must not overwrite it (run without resume, or use another output location);
* a path that exists and is not a regular file: ``IsADirectoryError``.

Notices are :class:`JournalWarning` warnings (the library never prints; the ``pendulab`` command shows them as one
line on stderr). The hashes detect hand edits and damage; they are not a signature (anyone can recompute them).
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from ._checks import stacklevel_outside_package
from ._io import atomic_write_text, check_writable
from ._version import source_version

__all__ = [
    "FORMAT", "FORMAT_VERSION", "Journal", "JournalError", "JournalWarning", "canonical_json", "digest", "finite",
    "header", "header_problem", "notify", "read_case", "trusted_records", "write_case",
]  # fmt: skip

#: The ``format`` marker of every journal file.
FORMAT = "pendulab-journal"
#: Version of the file layout (not of pendulab); another one is stale.
FORMAT_VERSION = 1
#: Record keys named in one notice before "and N more".
_NAMED = 5


class JournalWarning(RuntimeWarning):
    """A journal (or some of its records) was not trusted on resume: that work is run again."""


class JournalError(ValueError):
    """A journal that a resume must neither reuse nor overwrite (another kind, or other settings)."""


def canonical_json(obj: Any) -> str:
    """The canonical JSON text of ``obj``: sorted keys, no spaces, NaN and infinities as JSON extensions.

    Parameters
    ----------
    obj : Any
        JSON-serializable value (tuples are written as lists).

    Returns
    -------
    str
        The text the hashes are taken over (equal values give equal texts).
    """
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=True)


def digest(obj: Any) -> str:
    """SHA-256 (hex) of :func:`canonical_json` of ``obj``.

    Parameters
    ----------
    obj : Any
        JSON-serializable value.

    Returns
    -------
    str
        64 hex digits.
    """
    return hashlib.sha256(canonical_json(obj).encode("ascii")).hexdigest()


def _plain(obj: Any) -> Any:
    """``obj`` as it reads back from JSON (tuples -> lists, keys -> str): what is hashed and stored."""
    return json.loads(json.dumps(obj, allow_nan=True))


def _names(keys: list[str]) -> str:
    shown = ", ".join(keys[:_NAMED])
    more = f" and {len(keys) - _NAMED} more" if len(keys) > _NAMED else ""
    return f"record{'s' if len(keys) > 1 else ''} {shown}{more}"


def _problem(exc: BaseException) -> str:
    """What is wrong with a record, from the exception its ``check`` raised."""
    if isinstance(exc, KeyError):
        return f"incomplete (lacks field {exc.args[0]!r})" if exc.args else "incomplete"
    text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    return f"malformed or not part of this run ({text[:200]})"


def notify(notices: Iterable[str]) -> None:
    """Issue each notice as a :class:`JournalWarning` attributed to the first caller outside pendulab.

    Parameters
    ----------
    notices : iterable of str
        One line each, naming the file and the problem.
    """
    for line in notices:
        warnings.warn(line, JournalWarning, stacklevel=stacklevel_outside_package())


def header(kind: str, settings: Mapping[str, Any], version: str | None = None) -> dict[str, Any]:
    """The header of a journal: format, kind, pendulab version, settings and ``header_sha256`` over them.

    Parameters
    ----------
    kind : str
        What the journal records.
    settings : mapping
        Everything its records depend on.
    version : str, optional
        The pendulab version; default: this code's :func:`~pendulab._version.source_version` (release and source
        digest, so that a journal of edited code is stale even when the release number is the same).

    Returns
    -------
    dict
        The header fields of the file.
    """
    version = source_version() if version is None else version
    head = {"format": FORMAT, "format_version": FORMAT_VERSION, "kind": kind, "pendulab_version": version,
            "settings": _plain(dict(settings))}  # fmt: skip
    return {**head, "header_sha256": digest(head)}


def _code_changed(then: Any, now: str) -> str:
    """Say so when only the code differs (same release number): the case a static release number used to hide."""
    same_release = isinstance(then, str) and then.split("+")[0] == now.split("+")[0]
    return " (same release, other code: its source changed since)" if same_release else ""


def header_problem(doc: Any, kind: str, settings: Mapping[str, Any], path: str | Path) -> str | None:
    """Why the header of a journal document is stale (None: it validates against ``kind`` and ``settings``).

    Parameters
    ----------
    doc : Any
        The parsed journal (or any JSON value read where one was expected).
    kind : str
        The kind expected.
    settings : mapping
        The settings of this run.
    path : str or Path
        The file (named in errors).

    Returns
    -------
    str or None
        The reason (no format or version, another pendulab version or format, a header edited by hand).

    Raises
    ------
    JournalError
        A pendulab journal of another kind, or of this version written with other settings.
    """
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        n = len(doc["records"]) if isinstance(doc, dict) and isinstance(doc.get("records"), (list, dict)) else 0
        what = f"its {n} records are" if n else "it is"
        return f"carries no pendulab version or integrity hash (an older pendulab's?); {what} not trusted"
    if doc.get("kind") != kind:
        raise JournalError(
            f"journal {path} is a {doc.get('kind')!r} journal, not a {kind!r} one; "
            "use another output location (resuming it would overwrite it)"
        )
    if doc.get("format_version") != FORMAT_VERSION:
        return f"has journal format {doc.get('format_version')!r}, this pendulab writes {FORMAT_VERSION}"
    version, now_version = doc.get("pendulab_version"), source_version()
    if version != now_version:
        return f"was written by pendulab {version}, this is pendulab {now_version}{_code_changed(version, now_version)}"
    stored = doc.get("settings")
    head = {k: doc.get(k) for k in ("format", "format_version", "kind", "pendulab_version", "settings")}
    if doc.get("header_sha256") != digest(head):
        return "has a header (version, settings) that does not match its SHA-256 (edited by hand?)"
    now = _plain(dict(settings))
    if stored != now:
        stored = stored if isinstance(stored, dict) else {}
        differ = sorted(k for k in set(stored) | set(now) if stored.get(k) != now.get(k))
        what = ", ".join(f"{k} {stored.get(k)!r} there, {now.get(k)!r} now" for k in differ)
        raise JournalError(
            f"journal {path} was written with other settings ({what}); run without resume to replace it, "
            "or use another output location"
        )
    return None


class Journal:
    """The finished units of one piece of resumable work, in a validated journal file.

    Parameters
    ----------
    path : str or Path or None
        The journal file; None keeps the records in memory only.
    kind : str
        What the journal records (``"scorecard"``, ``"robustness-v2"``, ...); a journal of another kind is never
        resumed.
    settings : mapping
        Everything the records depend on (JSON-serializable); resuming a journal of this pendulab version written
        with other settings raises :class:`JournalError`.
    resume : bool
        Read and validate the file's records (see the module docstring); otherwise start empty (an existing file
        is replaced at the first save).
    check : callable, optional
        ``check(key, data)`` raises ``KeyError`` (a missing field), ``ValueError`` or ``TypeError`` for a record
        that is incomplete, malformed or not part of this work: the record is dropped (and re-run).
    warn : bool
        Issue the notices as :class:`JournalWarning` (False: only collect them in :attr:`notices`).

    Attributes
    ----------
    records : dict of str to Any
        The validated records (JSON form) by key, then every record added.
    meta : dict
        Validated meta data (empty when there were none or they failed their hash).
    notices : list of str
        One line per problem found on resume, each naming the file.
    resumed : int
        Records taken from the file.
    stale : bool
        The file as a whole was not trusted (nothing was reused from it).

    Raises
    ------
    JournalError
        ``resume`` and the file is a pendulab journal of another kind, or of this pendulab version with other
        settings.
    IsADirectoryError
        ``path`` exists and is not a regular file.
    PermissionError, NotADirectoryError
        Nothing can be written where the journal goes (checked before any work).
    """

    def __init__(
        self,
        path: str | Path | None,
        kind: str,
        settings: Mapping[str, Any],
        *,
        resume: bool = False,
        check: Callable[[str, Any], Any] | None = None,
        warn: bool = True,
    ) -> None:
        self.path = None if path is None else Path(path)
        self.kind = str(kind)
        self.settings: dict[str, Any] = _plain(dict(settings))
        self.version = source_version()
        self.records: dict[str, Any] = {}
        self.meta: dict[str, Any] = {}
        self.notices: list[str] = []
        self.stale = False
        self._digests: dict[str, str] = {}
        if self.path is not None:
            if self.path.exists() and not self.path.is_file():
                raise IsADirectoryError(f"journal {self.path} exists and is not a file; remove it or choose another output")
            check_writable(self.path.parent)
            if resume and self.path.is_file():
                self._load(check)
        self.resumed = len(self.records)
        if warn:
            notify(self.notices)

    # -- hashes -------------------------------------------------------------------------------------------------
    def record_digest(self, key: str, data: Any) -> str:
        """SHA-256 of a record: over the journal's header (kind, version, settings), the key and the data.

        Parameters
        ----------
        key : str
            Unit of work.
        data : Any
            Its JSON form.

        Returns
        -------
        str
            64 hex digits.
        """
        return digest({**header(self.kind, self.settings), "key": key, "data": data})

    def _meta_digest(self, meta: Any) -> str:
        return digest({**header(self.kind, self.settings), "meta": meta})

    # -- reading ------------------------------------------------------------------------------------------------
    def _stale(self, why: str) -> None:
        self.stale = True
        self.notices.append(f"journal {self.path} {why}; nothing in it is reused, its work is run again")

    def _load(self, check: Callable[[str, Any], Any] | None) -> None:
        path = self.path
        if path is None:
            return None
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError as exc:
            return self._stale(f"is not valid JSON text (damaged: {exc.reason})")
        except OSError as exc:
            raise JournalError(f"journal {path} cannot be read ({exc.strerror or exc}); fix its permissions") from None
        try:
            data = json.loads(text)
        except ValueError as exc:
            return self._stale(f"is not valid JSON (truncated or damaged: {exc})")
        why = header_problem(data, self.kind, self.settings, path)
        if why is not None:
            return self._stale(why)
        records = data.get("records")
        if not isinstance(records, dict):
            return self._stale("has no record table")
        problems: dict[str, list[str]] = {}
        for key, entry in records.items():
            if not isinstance(entry, dict) or "data" not in entry:
                problems.setdefault("malformed (no data)", []).append(key)
                continue
            if check is not None:
                try:
                    check(key, entry["data"])
                except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
                    problems.setdefault(_problem(exc), []).append(key)
                    continue
            if entry.get("sha256") != self.record_digest(key, entry["data"]):
                problems.setdefault("edited by hand or damaged (does not match its SHA-256)", []).append(key)
                continue
            self.records[key] = entry["data"]
            self._digests[key] = entry["sha256"]
        for why, keys in problems.items():
            self.notices.append(f"journal {path}: {_names(keys)} {why}; not trusted, run again")
        meta = data.get("meta", {})
        if meta and data.get("meta_sha256") != self._meta_digest(meta):
            self.notices.append(f"journal {path}: its meta data ({', '.join(sorted(meta))}) do not match their SHA-256; dropped")
        elif isinstance(meta, dict):
            self.meta = meta

    # -- use ----------------------------------------------------------------------------------------------------
    def __contains__(self, key: str) -> bool:
        return key in self.records

    def __len__(self) -> int:
        return len(self.records)

    def get(self, key: str) -> Any:
        """The recorded data of ``key`` (None when not recorded).

        Parameters
        ----------
        key : str
            Unit of work.

        Returns
        -------
        Any
            Its JSON form.
        """
        return self.records.get(key)

    def add(self, key: str, data: Any) -> None:
        """Record (or replace) one unit in memory; :meth:`save` writes it.

        Parameters
        ----------
        key : str
            Unit of work.
        data : Any
            JSON-serializable result (stored as it reads back: tuples become lists).
        """
        plain = _plain(data)
        self.records[str(key)] = plain
        self._digests[str(key)] = self.record_digest(str(key), plain)

    def record(self, key: str, data: Any) -> None:
        """Record one unit and rewrite the journal file atomically.

        Parameters
        ----------
        key : str
            Unit of work.
        data : Any
            JSON-serializable result.
        """
        self.add(key, data)
        self.save()

    def save(self, **meta: Any) -> Path | None:
        """Rewrite the journal file atomically (a no-op without a path).

        Parameters
        ----------
        **meta
            Meta data to set (merged into :attr:`meta`; hashed like the records).

        Returns
        -------
        Path or None
            The file written.
        """
        self.meta.update(_plain(meta))
        if self.path is None:
            return None
        doc: dict[str, Any] = header(self.kind, self.settings)
        if self.meta:
            doc["meta"], doc["meta_sha256"] = self.meta, self._meta_digest(self.meta)
        doc["records"] = {k: {"sha256": self._digests[k], "data": v} for k, v in self.records.items()}
        return atomic_write_text(self.path, json.dumps(doc, allow_nan=True) + "\n")


def trusted_records(path: str | Path, kind: str, check: Callable[[str, Any], Any] | None = None) -> dict[str, Any]:
    """The records of a journal file that validate against its own settings (no notices; {} when none do).

    For reports that count finished work before (or without) resuming it; a resume validates again against the
    run's settings.

    Parameters
    ----------
    path : str or Path
        The journal file.
    kind : str
        Its kind.
    check : callable, optional
        As for :class:`Journal`.

    Returns
    -------
    dict of str to Any
        Record data by key.
    """
    try:
        stored = json.loads(Path(path).read_text(encoding="utf-8")).get("settings")
    except (OSError, ValueError, AttributeError):
        return {}
    if not isinstance(stored, dict):
        return {}
    try:
        return Journal(path, kind, stored, resume=True, check=check, warn=False).records
    except (JournalError, OSError):
        return {}


def finite(d: Mapping[str, Any]) -> dict[str, Any]:
    """``d`` with non-finite floats as None (strict JSON for records read by other tools).

    Parameters
    ----------
    d : mapping
        A flat record.

    Returns
    -------
    dict
        A copy.
    """
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in d.items()}


def write_case(path: str | Path, record: Mapping[str, Any]) -> Path:
    """Keep one finished case of a long study (a benchmark's run), stamped with the code that produced it.

    Parameters
    ----------
    path : str or Path
        The case's JSON file (written atomically; its folder is made).
    record : mapping
        JSON-serializable results of the case.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    RuntimeError
        The folder cannot be written.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps({**record, "code_version": source_version()}) + "\n")
    return path


def read_case(path: str | Path) -> dict[str, Any] | None:
    """A case :func:`write_case` kept, or None when there is none, it is unreadable, or *other code* produced it.

    A study resumed after an edit to pendulab (a controller constant, a planner's bound) must run its cases again,
    never report the old code's results as the new code's: the stamp is :func:`~pendulab._version.source_version`.

    Parameters
    ----------
    path : str or Path
        The case's JSON file.

    Returns
    -------
    dict or None
        The record (with its ``code_version`` stamp).
    """
    try:
        rec = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(rec, dict) or rec.get("code_version") != source_version():
        return None
    return rec

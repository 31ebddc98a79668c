"""Output directories of the command running now, and the marker an interrupted run leaves in them.

Kept apart from the heavier helpers so the entry point can import it without NumPy or CasADi.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from .._io import atomic_write_text, check_writable

__all__ = ["output_directory", "check_writable", "check_journal", "mark_interrupted", "forget_output_directories"]

#: Output directories the running command declared (:func:`output_directory`); :func:`mark_interrupted` marks them.
_OUTPUT_DIRECTORIES: list[Path] = []


def output_directory(path: str | Path) -> Path:
    """Declare ``path`` an output directory of the command running now, and return it as a Path.

    It is checked writable *before* any work (a protocol that runs minutes must not find out at its
    first save): the directory, or the nearest existing folder above it, must take a new entry;
    nothing is left behind by the check. If the command is interrupted (Ctrl-C), ``pendulab``'s entry
    point calls :func:`mark_interrupted`, which leaves ``DIR/summary.json`` with ``"status":
    "interrupted"`` and the files the run did finish, so partial outputs never pass for a finished run.

    Raises
    ------
    NotADirectoryError
        ``path`` (or a folder above it) is a file.
    PermissionError
        Nothing can be written there (read-only mount, permissions).
    """
    out = Path(path)
    check_writable(out)
    if out not in _OUTPUT_DIRECTORIES:
        _OUTPUT_DIRECTORIES.append(out)
    return out


def check_journal(path: Path) -> None:
    """Raise unless ``path`` is absent or a regular file (a journal that is a directory is not "no records yet").

    Raises
    ------
    IsADirectoryError
        ``path`` exists and is not a regular file.
    """
    if path.exists() and not path.is_file():
        raise IsADirectoryError(f"journal {path} exists and is not a file; remove it or choose another --out")


def mark_interrupted(command: Sequence[str]) -> list[Path]:
    """Write ``summary.json`` with ``"status": "interrupted"`` into every declared output directory that exists.

    Parameters
    ----------
    command : sequence of str
        The command line (without the program name), recorded in the marker.

    Returns
    -------
    list of Path
        The markers written (each declared directory is forgotten: one marker per run).
    """
    written = []
    while _OUTPUT_DIRECTORIES:
        out = _OUTPUT_DIRECTORIES.pop(0)
        if not out.is_dir():
            continue  # interrupted before it wrote anything
        files = sorted(str(p.relative_to(out)) for p in out.rglob("*") if p.is_file() and p != out / "summary.json")
        marker = {
            "status": "interrupted",
            "command": "pendulab " + " ".join(command),
            "finished_files": files,
            "note": "the run was interrupted: the files listed are what it finished, not a complete result "
            "(journals among them let --resume continue where the command offers it)",
        }
        written.append(atomic_write_text(out / "summary.json", json.dumps(marker, indent=1) + "\n"))
    return written


def forget_output_directories() -> None:
    """Start a new run's record of output directories (the entry point calls it before each command)."""
    _OUTPUT_DIRECTORIES.clear()

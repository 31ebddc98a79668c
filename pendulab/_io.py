"""Atomic file output: write to a temporary file beside the target, then rename over it.

An interrupted or failing run never leaves a truncated file where a good one
was expected: the target either keeps its old content or gets the complete new
one (``os.replace`` is atomic on POSIX and Windows within one directory).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

__all__ = ["atomic_path", "atomic_open", "atomic_write_text", "check_writable"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path to write to; on success it replaces ``path``, on any exception it is removed.

    Parameters
    ----------
    path : path-like
        The final file; its directory is created if missing.

    Yields
    ------
    Path
        A temporary file name in the same directory (same suffix, so writers that pick a format by
        suffix, e.g. matplotlib or NumPy, behave the same).
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=f".tmp{target.suffix}", dir=target.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    # mkstemp creates 0600; give the file the permissions a plain open() would (0666 less the umask).
    umask = os.umask(0)
    os.umask(umask)
    tmp.chmod(0o666 & ~umask)
    try:
        yield tmp
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


@contextlib.contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w", **kwargs: Any) -> Iterator[IO[Any]]:
    """``open`` for writing that replaces ``path`` only once the file is complete.

    Parameters
    ----------
    path : path-like
        The final file.
    mode : str
        A writing mode (``"w"``, ``"wb"``, ...).
    **kwargs
        Passed to :func:`open` (``newline``, ``encoding``, ...).

    Yields
    ------
    file object
        Open on a temporary file in the same directory.
    """
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


def atomic_write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically.

    Parameters
    ----------
    path : path-like
        The final file.
    text : str
        Content.
    encoding : str
        Text encoding.

    Returns
    -------
    Path
        ``path``.
    """
    with atomic_open(path, "w", encoding=encoding) as fh:
        fh.write(text)
    return Path(path)


def check_writable(out: str | os.PathLike[str]) -> None:
    """Raise unless a directory ``out`` can be created or written into (checked before work that writes there).

    The directory, or the nearest existing folder above it, must take a new entry; nothing is left behind.

    Parameters
    ----------
    out : path-like
        The directory.

    Raises
    ------
    NotADirectoryError
        ``out`` (or a folder above it) is a file.
    PermissionError
        Nothing can be written there (read-only mount, permissions).
    """
    out = Path(out)
    probe = out
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise NotADirectoryError(f"output directory {out}: {probe} is a file, not a directory")
    try:
        Path(tempfile.mkdtemp(prefix=".pendulab-write-check-", dir=probe)).rmdir()
    except OSError as exc:
        raise PermissionError(f"output directory {out}: cannot write under {probe} ({exc.strerror or exc})") from None

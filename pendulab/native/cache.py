"""The on-disk cache of built files (native libraries, the Gymnasium backend's FMU), verified by SHA-256.

The cache directory is ``$PENDULAB_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pendulab``
or ``~/.cache/pendulab`` (:func:`cache_dir`). A cached file cannot poison later runs
(:func:`cached_artifact`): each file is built to a temporary name, its SHA-256 is written
beside it (``<file>.sha256``) and both are renamed into place; every later use checks the
digest *before* the file is loaded, and a missing or wrong digest rebuilds the file once,
with a :class:`CacheRebuildWarning` naming the path. Builds of one file are serialized by a
lock file (``<file>.lock``, POSIX ``flock``).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

from .compiler import CompilerNotFoundError

__all__ = ["cache_dir", "CacheRebuildWarning", "file_digest", "digest_path", "verify_cached", "cached_artifact"]


class CacheRebuildWarning(RuntimeWarning):
    """A cached file (native library, gym FMU) was damaged or failed to load, and is being rebuilt."""


def cache_dir() -> Path:
    """Folder of the cached native libraries (not created here).

    Returns
    -------
    Path
        ``$PENDULAB_CACHE_DIR/native``, else ``$XDG_CACHE_HOME/pendulab/native``,
        else ``~/.cache/pendulab/native``.
    """
    root = os.environ.get("PENDULAB_CACHE_DIR")
    if root:
        return Path(root).expanduser() / "native"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "pendulab" / "native"


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes.

    Parameters
    ----------
    path : Path
        The file.

    Returns
    -------
    str
        Hex digest.

    Raises
    ------
    OSError
        The file cannot be read.
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def digest_path(path: Path) -> Path:
    """Where the SHA-256 of a cached file is kept: ``<file>.sha256`` beside it.

    Parameters
    ----------
    path : Path
        The cached file.

    Returns
    -------
    Path
    """
    path = Path(path)
    return path.with_name(path.name + ".sha256")


def verify_cached(path: Path) -> str | None:
    """Why the cached file ``path`` must not be used, or None when it matches the digest written beside it.

    Reads the file and hashes it; nothing is loaded or executed, so a damaged file is harmless here.

    Parameters
    ----------
    path : Path
        The cached file.

    Returns
    -------
    str or None
        ``"is missing"`` (not built yet), a reason the file is damaged (no digest file, digest
        mismatch, unreadable), or None when it is intact.
    """
    path = Path(path)
    if not path.exists():
        return "is missing"
    try:
        expected = digest_path(path).read_text(encoding="ascii").strip()
    except FileNotFoundError:
        return f"has no digest file {digest_path(path).name}"
    except (OSError, UnicodeDecodeError) as exc:
        return f"has an unreadable digest file ({exc})"
    try:
        actual = file_digest(path)
    except OSError as exc:
        return f"cannot be read ({exc})"
    if actual != expected:
        return f"does not match its SHA-256 digest (damaged or replaced; {path.stat().st_size} bytes)"
    return None


@contextlib.contextmanager
def _build_lock(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``<path>.lock`` (POSIX ``flock``; no lock elsewhere). Ctrl-C interrupts the wait."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: the atomic renames still keep readers safe
        yield
        return
    with open(path.with_name(path.name + ".lock"), "a+b") as fh:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


def cached_artifact(path: Path, make: Callable[[Path], object], *, what: str, rebuild: str | None = None) -> Path:
    """The cached file ``path``, verified by its digest; built by ``make`` when missing, rebuilt when damaged.

    ``make(tmp)`` writes the file to a temporary path in the same folder (same suffix); its SHA-256
    goes to :func:`digest_path`, and both are renamed into place. A file that exists but fails
    :func:`verify_cached` (or any file when ``rebuild`` gives a reason, e.g. a load failure) is
    rebuilt with a :class:`CacheRebuildWarning` naming the path.

    Parameters
    ----------
    path : Path
        The cached file.
    make : callable
        ``make(tmp_path)`` builds the file at ``tmp_path``.
    what : str
        Who needs the file, for messages (e.g. ``"method 'compiled-dopri5' needs its native library; it"``).
    rebuild : str, optional
        Rebuild even if the digest matches, for this reason (e.g. ``"failed to load (...)"``).

    Returns
    -------
    Path
        ``path``, intact.

    Raises
    ------
    RuntimeError
        The folder cannot be written, or ``make`` failed; the message names ``path``.
    """
    path = Path(path)
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RuntimeError(
            f"{what} needs a writable cache folder, but {folder} cannot be created ({exc}); "
            "set $PENDULAB_CACHE_DIR to a writable folder"
        ) from exc
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(_build_lock(path))
        except OSError as exc:
            raise RuntimeError(
                f"{what} cannot lock its cache file {path} ({exc}); set $PENDULAB_CACHE_DIR to a writable folder"
            ) from exc
        reason = rebuild if rebuild is not None else verify_cached(path)  # again: another process may have built it
        if reason is None:
            return path
        if reason != "is missing":
            warnings.warn(
                f"pendulab: the cached file {path} {reason}; rebuilding it (the cache folder is {folder})",
                CacheRebuildWarning,
                stacklevel=_stacklevel_outside_package(),
            )
        _build_into(path, make, what)
    reason = verify_cached(path)
    if reason is not None:  # pragma: no cover - someone damaged it again between the rename and here
        raise RuntimeError(f"{what}: the cached file {path} {reason} right after it was built; delete {folder} and retry")
    return path


#: The pendulab package folder: a warning points at the first frame outside it (the user's call).
_PACKAGE_DIR = str(Path(__file__).resolve().parents[1]) + os.sep


def _stacklevel_outside_package() -> int:
    """``stacklevel`` (for a ``warnings.warn`` in the caller) of the first frame outside the pendulab package."""
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level


def _build_into(path: Path, make: Callable[[Path], object], what: str) -> None:
    """Build with ``make`` to temporary files in ``path``'s folder, write the digest, rename both into place."""
    folder = path.parent
    tmp_file = tmp_digest = None
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=path.suffix, dir=folder)
        os.close(fd)
        tmp_file = Path(name)
        try:
            make(tmp_file)
        except (CompilerNotFoundError, KeyboardInterrupt):
            raise
        except Exception as exc:
            raise RuntimeError(f"{what} could not be built into the cache file {path}: {exc}") from exc
        digest = file_digest(tmp_file)
        fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".sha256", dir=folder)
        tmp_digest = Path(name)
        with os.fdopen(fd, "w", encoding="ascii") as fh:
            fh.write(digest + "\n")
        # The file first, then its digest: a reader between the two renames sees a mismatch and waits on the lock.
        os.replace(tmp_file, path)
        os.replace(tmp_digest, digest_path(path))
    except OSError as exc:
        raise RuntimeError(
            f"{what} could not write the cache file {path} ({exc}); set $PENDULAB_CACHE_DIR to a writable folder"
        ) from exc
    finally:
        for tmp in (tmp_file, tmp_digest):
            if tmp is not None:
                with contextlib.suppress(OSError):
                    tmp.unlink()

"""The one mechanism of every on-disk cache (native libraries, RTI steps, the gym FMU, plan-library entries).

The cache directory of the built files is ``$PENDULAB_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/pendulab``
or ``~/.cache/pendulab`` (:func:`cache_dir`); the plan library keeps its entries in a folder of its own,
through the same functions. A cached file cannot poison later runs (:func:`cached_artifact`):

* **published atomically**: each file is built to a temporary name in its folder, its *seal* is
  written beside it (``<file>.sha256``: the file's SHA-256 and the **key** of the entry it was
  built for) and both are renamed into place (:func:`publish`). A file in place is never
  rewritten, only replaced by a rename, so a process that has it mapped keeps its own copy;
* **verified before use**: :func:`verify_cached` (or :func:`read_sealed`, which hashes the very
  bytes it returns) checks the digest and the key before the file is loaded or read. A missing,
  damaged or edited file fails the digest, an entry swapped for another's (file and seal moved
  together) fails the key;
* **rebuilt, never used**: a file that fails is rebuilt once with a :class:`CacheRebuildWarning`
  naming the path (or a clear error where it cannot be rebuilt);
* **built once**: builds of one entry are serialized by a lock file (``<file>.lock``, POSIX
  ``flock``) and the entry is verified again under the lock, so concurrent processes wait for
  the first build instead of building it again.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

from .._checks import stacklevel_outside_package
from .compiler import CompilerNotFoundError

__all__ = [
    "cache_dir",
    "CacheRebuildWarning",
    "file_digest",
    "digest_path",
    "seal",
    "sealed_key",
    "verify_cached",
    "read_sealed",
    "cache_lock",
    "publish",
    "warn_rebuild",
    "cached_artifact",
]


class CacheRebuildWarning(RuntimeWarning):
    """A cached file (native library, RTI step, gym FMU, plan entry) was damaged, swapped or failed to load: rebuilt."""


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
    """Where the seal of a cached file (its SHA-256 and its entry's key) is kept: ``<file>.sha256`` beside it.

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


def _default_key(path: Path) -> str:
    """The key of an entry whose caller names none: its file name (which carries a digest of what it was built from)."""
    return Path(path).name


def seal(path: Path, key: str, *, digest: str | None = None) -> None:
    """Write the seal of the cached file ``path`` (its SHA-256 and ``key``) beside it, atomically.

    :func:`publish` seals each entry it builds; call this directly only to re-seal a file by hand.

    Parameters
    ----------
    path : Path
        The cached file.
    key : str
        What the entry was built for (e.g. the digest of its sources, or the design and start of a plan).
    digest : str, optional
        The file's SHA-256 if already known; default: hash the file now.

    Raises
    ------
    OSError
        The file cannot be read or the seal cannot be written.
    """
    path = Path(path)
    text = _seal_text(digest or file_digest(path), key)
    fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".sha256", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(name, digest_path(path))
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(name)
        raise


def _seal_text(digest: str, key: str) -> str:
    """The text of a seal: one line of JSON."""
    return json.dumps({"sha256": digest, "key": str(key)}, sort_keys=True) + "\n"


def _read_seal(path: Path) -> tuple[str, str] | str:
    """``(sha256, key)`` of the seal beside ``path``, or why it cannot be used."""
    try:
        text = digest_path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        return f"has no digest file {digest_path(path).name}"
    except (OSError, UnicodeDecodeError) as exc:
        return f"has an unreadable digest file ({exc})"
    try:
        data = json.loads(text)
        digest, key = data["sha256"], data["key"]
    except (ValueError, TypeError, KeyError):
        return f"has a digest file {digest_path(path).name} in an unknown format (not written by this pendulab)"
    if not (isinstance(digest, str) and isinstance(key, str) and len(digest) == 64):
        return f"has a digest file {digest_path(path).name} in an unknown format (not written by this pendulab)"
    return digest, key


def sealed_key(path: Path) -> str | None:
    """The key the cached file ``path`` was sealed for, or None without a readable seal.

    Parameters
    ----------
    path : Path
        The cached file.

    Returns
    -------
    str or None
    """
    found = _read_seal(Path(path))
    return found[1] if isinstance(found, tuple) else None


def _short(key: str) -> str:
    """A key short enough for a message: itself, or its head and a digest of the whole."""
    return repr(key) if len(key) <= 80 else f"{key[:60]!r}... (sha256 {hashlib.sha256(key.encode()).hexdigest()[:12]})"


def _check(path: Path, key: str | None, data: bytes | None) -> str | None:
    """The reason ``path`` (whose bytes are ``data`` when already read) fails its seal, or None."""
    found = _read_seal(path)
    if isinstance(found, str):
        return found
    expected, sealed_for = found
    if key is not None and sealed_for != key:
        # Checked before the digest: an entry swapped for another's (file and seal together) is intact but wrong.
        return f"was built for another entry (sealed for key {_short(sealed_for)}, expected {_short(key)}): swapped or copied"
    try:
        actual = hashlib.sha256(data).hexdigest() if data is not None else file_digest(path)
    except OSError as exc:
        return f"cannot be read ({exc})"
    if actual != expected:
        size = len(data) if data is not None else path.stat().st_size
        return f"does not match its SHA-256 digest (damaged, edited or replaced; {size} bytes)"
    return None


def verify_cached(path: Path, key: str | None = None) -> str | None:
    """Why the cached file ``path`` must not be used, or None when it matches the seal written beside it.

    Reads the file and hashes it; nothing is loaded or executed, so a damaged file is harmless here.

    Parameters
    ----------
    path : Path
        The cached file.
    key : str, optional
        The entry the caller wants: a file sealed for another key fails (an entry swapped for another's).
        Default: the key is not checked, only the digest.

    Returns
    -------
    str or None
        ``"is missing"`` (not built yet), a reason the file must not be used (no or an unreadable
        seal, digest mismatch, sealed for another key, unreadable), or None when it is intact.
    """
    path = Path(path)
    if not path.exists():
        return "is missing"
    return _check(path, key, None)


def read_sealed(path: Path, key: str | None = None) -> tuple[bytes | None, str | None]:
    """The bytes of the cached file ``path`` after checking *those bytes* against its seal.

    Unlike :func:`verify_cached` followed by a read, the bytes checked are the bytes returned: a file
    replaced between the check and the read cannot slip through.

    Parameters
    ----------
    path : Path
        The cached file.
    key : str, optional
        The entry the caller wants (see :func:`verify_cached`).

    Returns
    -------
    data : bytes or None
        The file's bytes when intact, else None.
    reason : str or None
        None when intact, else why not (``"is missing"`` when there is no file).
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None, "is missing"
    except OSError as exc:
        return None, f"cannot be read ({exc})"
    reason = _check(path, key, data)
    return (data, None) if reason is None else (None, reason)


#: What to do about an unwritable cache folder, in messages (callers with a folder of their own pass theirs).
_FOLDER_HINT = "set $PENDULAB_CACHE_DIR to a writable folder"


@contextlib.contextmanager
def cache_lock(path: Path) -> Iterator[None]:
    """Hold the exclusive lock of the cache entry ``path`` (``<path>.lock``, POSIX ``flock``). Ctrl-C interrupts the wait.

    Every build of an entry holds it; a reader that finds an entry failing its seal takes it before
    judging the entry damaged (a writer may be between its two renames).

    Parameters
    ----------
    path : Path
        The cached file.

    Yields
    ------
    None

    Raises
    ------
    OSError
        The lock file cannot be created (a read-only folder).
    """
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


def _locked(path: Path, what: str, hint: str) -> contextlib.AbstractContextManager[None]:
    """:func:`cache_lock` of ``path`` after creating its folder; RuntimeError naming the folder when it cannot."""
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RuntimeError(f"{what} needs a writable cache folder, but {folder} cannot be created ({exc}); {hint}") from exc
    stack = contextlib.ExitStack()
    try:
        stack.enter_context(cache_lock(path))
    except OSError as exc:
        raise RuntimeError(f"{what} cannot lock its cache file {path} ({exc}); {hint}") from exc
    return stack


def publish(
    path: Path,
    make: Callable[[Path], object],
    *,
    what: str,
    key: str | None = None,
    check: Callable[[Path], str | None] | None = None,
    hint: str = _FOLDER_HINT,
) -> Path:
    """Build the cache entry ``path`` afresh and publish it atomically (write elsewhere, verify, seal, rename).

    ``make(tmp)`` writes the file to a temporary path in the same folder (same suffix); ``check(tmp)``,
    if given, verifies it there; its seal (SHA-256 and ``key``) is written to a temporary file too, and
    both are renamed into place, under the entry's lock. A failure publishes nothing.

    Parameters
    ----------
    path : Path
        The cached file.
    make : callable
        ``make(tmp_path)`` builds the file at ``tmp_path``.
    what : str
        Who needs the file, for messages (e.g. ``"method 'compiled-dopri5' needs its native library; it"``).
    key : str, optional
        What the entry is built for (sealed with it); default: the file name.
    check : callable, optional
        ``check(tmp_path)``: why the built file is unusable, or None; a reason fails the build.
    hint : str
        What to do about an unwritable folder, for messages.

    Returns
    -------
    Path
        ``path``, intact.

    Raises
    ------
    RuntimeError
        The folder cannot be written, ``make`` failed or ``check`` refused its file; the message names ``path``.
    """
    path = Path(path)
    with _locked(path, what, hint):
        _build_into(path, make, what, _default_key(path) if key is None else key, check, hint)
    return path


def cached_artifact(
    path: Path,
    make: Callable[[Path], object],
    *,
    what: str,
    rebuild: str | None = None,
    key: str | None = None,
    check: Callable[[Path], str | None] | None = None,
    hint: str = _FOLDER_HINT,
) -> Path:
    """The cached file ``path``, verified by its seal; built by ``make`` when missing, rebuilt when it fails.

    ``make(tmp)`` writes the file to a temporary path in the same folder (same suffix); its seal
    (SHA-256 and ``key``) goes to :func:`digest_path`, and both are renamed into place
    (:func:`publish`). A file that exists but fails :func:`verify_cached` for ``key`` (damaged,
    edited, or an entry swapped for another's), or any file when ``rebuild`` gives a reason (e.g. a
    load failure), is rebuilt with a :class:`CacheRebuildWarning` naming the path. The check is
    repeated under the entry's lock, so concurrent callers build an entry once.

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
    key : str, optional
        What the entry is built for (sealed with it, checked on every use); default: the file name.
    check : callable, optional
        ``check(tmp_path)``: why a freshly built file is unusable, or None (see :func:`publish`).
    hint : str
        What to do about an unwritable folder, for messages.

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
    key = _default_key(path) if key is None else key
    with _locked(path, what, hint):
        reason = rebuild if rebuild is not None else verify_cached(path, key)  # again: another process may have built it
        if reason is None:
            return path
        if reason != "is missing":
            warnings.warn(
                f"pendulab: the cached file {path} {reason}; rebuilding it (the cache folder is {folder})",
                CacheRebuildWarning,
                stacklevel=stacklevel_outside_package(),
            )
        _build_into(path, make, what, key, check, hint)
    reason = verify_cached(path, key)
    if reason is not None:  # pragma: no cover - someone damaged it again between the rename and here
        raise RuntimeError(f"{what}: the cached file {path} {reason} right after it was built; delete {folder} and retry")
    return path


def warn_rebuild(message: str) -> None:
    """Warn with a :class:`CacheRebuildWarning` that points at the first caller outside pendulab.

    Parameters
    ----------
    message : str
        What was found and what is done about it (names the cached file).
    """
    warnings.warn(message, CacheRebuildWarning, stacklevel=stacklevel_outside_package())


def _build_into(
    path: Path,
    make: Callable[[Path], object],
    what: str,
    key: str,
    check: Callable[[Path], str | None] | None,
    hint: str,
) -> None:
    """Build with ``make`` to temporary files in ``path``'s folder, check, seal, rename both into place (lock held)."""
    folder = path.parent
    tmp_file = tmp_digest = None
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=path.suffix, dir=folder)
        os.close(fd)
        tmp_file = Path(name)
        try:
            make(tmp_file)
            problem = None if check is None else check(tmp_file)
        except (CompilerNotFoundError, KeyboardInterrupt):
            raise
        except Exception as exc:
            raise RuntimeError(f"{what} could not be built into the cache file {path}: {exc}") from exc
        if problem is not None:
            raise RuntimeError(f"{what} could not be built into the cache file {path}: the built file {problem}")
        digest = file_digest(tmp_file)
        fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".sha256", dir=folder)
        tmp_digest = Path(name)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(_seal_text(digest, key))
        # The file first, then its seal: a reader between the two renames sees a mismatch and waits on the lock.
        # Renames only: a file in place is never rewritten (a process that mapped it keeps its copy).
        os.replace(tmp_file, path)
        os.replace(tmp_digest, digest_path(path))
    except OSError as exc:
        raise RuntimeError(f"{what} could not write the cache file {path} ({exc}); {hint}") from exc
    finally:
        for tmp in (tmp_file, tmp_digest):
            if tmp is not None:
                with contextlib.suppress(OSError):
                    tmp.unlink()

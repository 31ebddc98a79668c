"""pendulab's release and the identity of the code that is running."""

from __future__ import annotations

import functools
from pathlib import Path

__version__ = "0.1.0"

#: Suffixes of the files that make up the package (its code and the data it ships: scenes, plans, plants, records,
#: C sources of the FMU); anything else in its folder (byte code, editor files) is not part of what runs.
SOURCE_SUFFIXES: frozenset[str] = frozenset({".py", ".c", ".h", ".toml", ".json", ".npz", ".txt"})


def source_digest(root: Path) -> str:
    """SHA-256 over the relative path and content of every package file under ``root``.

    Parameters
    ----------
    root : Path
        A package folder.

    Returns
    -------
    str
        64 hex digits; equal trees give equal digests, any file edited, added, removed or renamed gives another.
    """
    import hashlib
    import os

    files = []
    for folder, subfolders, names in os.walk(root):
        subfolders[:] = [d for d in subfolders if d != "__pycache__"]
        rel = Path(folder).relative_to(root)
        files += [(rel / n).as_posix() for n in names if os.path.splitext(n)[1] in SOURCE_SUFFIXES]
    total = hashlib.sha256()
    for name in sorted(files):
        total.update(name.encode() + b"\0")
        total.update(hashlib.sha256((root / name).read_bytes()).digest())
    return total.hexdigest()


@functools.cache
def source_version() -> str:
    """The release and the digest of the code running it, e.g. ``"0.1.0+src.1a2b3c4d5e6f7a8b"``.

    The release number does not change with every edit, so what a journal or cache keeps is stamped with this: work
    done by other code (another checkout, an edited controller constant) is never read back as this code's. Computed
    once per process (~10 ms for the package's files).

    Returns
    -------
    str
        ``__version__`` plus the first 16 hex digits of :func:`source_digest` of the installed package.
    """
    return f"{__version__}+src.{source_digest(Path(__file__).parent)[:16]}"

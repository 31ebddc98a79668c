"""The flip-map files: :class:`FlipMap` (the result, with its NPZ file) and the partial-results checkpoint.

:func:`pendulab.ensemble.flipmap.flip_map` computes the map; this module holds what is stored of it:
the finished map (:meth:`FlipMap.save_npz` / :meth:`FlipMap.load_npz`) and, while a map with a
``checkpoint`` runs, the flip times of the blocks already done (written atomically after each block).
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path
from .._journal import Journal, header, header_problem, notify
from .._version import __version__

__all__ = ["FlipMap"]


@dataclass(frozen=True)
class FlipMap:
    """Time to the first flip over a grid of release angles.

    Attributes
    ----------
    theta1 : ndarray, shape (n1,)
        Release angles of link 1 [rad] (absolute, from the downward vertical).
    theta2 : ndarray, shape (n2,)
        Release angles of link 2 [rad].
    t_flip : ndarray, shape (n1, n2)
        Time to the first flip [s], indexed ``[i_theta1, i_theta2]``; NaN
        where neither link flipped before ``t_max`` (or could not, see ``skipped``).
    t_max : float
        Horizon [s].
    kind : str
        Model kind, ``"rigid"`` or ``"elastic"``.
    params : dict of str to float
        The model's parameters (SI units).
    energy_threshold : float
        ``V_flip`` [J], the least potential energy of a flipped configuration.
    skipped : ndarray of bool, shape (n1, n2)
        Points not integrated because their release energy is below ``energy_threshold``.
    n_simulated : int
        Number of integrations actually run (after the energy skip and symmetry).
    wall_time : float
        Wall-clock time of :func:`flip_map` [s].
    settings : dict
        How the map was computed: ``start``, ``rtol``, ``batch_size``, ``skip_low_energy``,
        ``symmetry``, ``max_steps``, ``pendulab_version`` (stored in the NPZ file).
    n_resumed : int
        Integrations taken from a checkpoint instead of being run again.
    """

    theta1: np.ndarray
    theta2: np.ndarray
    t_flip: np.ndarray
    t_max: float
    kind: str
    params: dict[str, float] = field(default_factory=dict)
    energy_threshold: float = float("nan")
    skipped: np.ndarray | None = None
    n_simulated: int = 0
    wall_time: float = float("nan")
    settings: dict[str, Any] = field(default_factory=dict)
    n_resumed: int = 0

    @property
    def flipped(self) -> np.ndarray:
        """Boolean mask, shape (n1, n2): the points that flipped before ``t_max``."""
        return np.isfinite(self.t_flip)

    def save_npz(self, path: str | Path) -> Path:
        """Write the map as NPZ.

        Keys: ``theta1`` (n1,), ``theta2`` (n2,) [rad], ``t_flip`` (n1, n2) [s]
        indexed ``[i_theta1, i_theta2]`` with NaN for no flip; also ``t_max``,
        ``kind``, ``energy_threshold``, ``skipped``, ``params`` (JSON) and ``settings``
        (JSON: start mode, tolerance, batch width, pendulab version, ...).

        Parameters
        ----------
        path : str or Path
            File name (``.npz`` is appended by NumPy when missing).

        Returns
        -------
        Path
            The file written.
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        skipped = self.skipped if self.skipped is not None else np.zeros(self.t_flip.shape, bool)
        with atomic_path(path if path.suffix == ".npz" else Path(f"{path}.npz")) as tmp:
            np.savez(
                tmp,
                theta1=self.theta1,
                theta2=self.theta2,
                t_flip=self.t_flip,
                t_max=np.float64(self.t_max),
                kind=np.str_(self.kind),
                energy_threshold=np.float64(self.energy_threshold),
                skipped=skipped,
                params=np.str_(json.dumps(self.params)),
                settings=np.str_(json.dumps({**self.settings, "pendulab_version": __version__})),
            )
        return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")

    @classmethod
    def load_npz(cls, path: str | Path) -> FlipMap:
        """Read a map written by :meth:`save_npz`.

        Parameters
        ----------
        path : str or Path
            NPZ file.

        Returns
        -------
        FlipMap
            The map (``n_simulated`` and ``wall_time`` are not stored).
        """
        with np.load(path) as z:
            return cls(
                theta1=z["theta1"],
                theta2=z["theta2"],
                t_flip=z["t_flip"],
                t_max=float(z["t_max"]),
                kind=str(z["kind"]),
                params=json.loads(str(z["params"])),
                energy_threshold=float(z["energy_threshold"]),
                skipped=z["skipped"],
                settings=json.loads(str(z["settings"])) if "settings" in z.files else {},
            )


# -- partial-results checkpoint -------------------------------------------------
#: Kind of the checkpoint's journal (:mod:`pendulab._journal`): each finished block of runs is a record.
CHECKPOINT_KIND = "flipmap-checkpoint"


def _block_digest(identity: dict[str, Any], a: int, b: int, values: np.ndarray) -> str:
    """SHA-256 of block ``[a, b)``: over the checkpoint's header (version, identity), the block and its flip times."""
    return Journal(None, CHECKPOINT_KIND, identity).record_digest(f"{a}-{b}", values[a:b].tolist())


def _save_checkpoint(path: Path, identity: dict[str, Any], values: np.ndarray, done: np.ndarray, digests: dict[str, str]) -> None:
    """Write the finished flip times atomically (an interrupted write keeps the previous checkpoint).

    ``digests`` holds the SHA-256 of each finished block (``"a-b"``, :func:`_block_digest`), kept by the caller so that
    a block is hashed once.
    """
    doc = {**header(CHECKPOINT_KIND, identity), "records": dict(digests)}
    with atomic_path(path) as tmp:
        np.savez(tmp, journal=np.str_(json.dumps(doc)), values=values, done=done)


def _load_checkpoint(
    path: Path, identity: dict[str, Any], n: int, blocks: list[tuple[int, int]]
) -> tuple[np.ndarray, np.ndarray, dict[str, str]]:
    """Flip times, done mask and block digests of the blocks of a checkpoint that validate.

    A file that cannot be read, was written by another pendulab (or before checkpoints carried a version), or whose
    header was edited is stale: nothing is taken from it. A block whose flip times do not match its SHA-256 is run
    again. Each problem is a :class:`~pendulab._journal.JournalWarning` naming the file.

    Raises
    ------
    pendulab._journal.JournalError
        A checkpoint of this pendulab version written with other settings (a ``ValueError``).
    """
    values, done, digests = np.full(n, np.nan), np.zeros(n, bool), {}
    try:
        with np.load(path, allow_pickle=False) as z:
            doc = json.loads(str(z["journal"])) if "journal" in z.files else None
            stored_values, stored_done = np.array(z["values"], dtype=float), np.array(z["done"], dtype=bool)
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        notify([f"journal {path} cannot be read as a flip-map checkpoint (truncated or damaged: {exc}); "
                "nothing in it is reused, its work is run again"])  # fmt: skip
        return values, done, digests
    why = header_problem(doc, CHECKPOINT_KIND, identity, path)
    if why is None and (stored_values.shape != (n,) or stored_done.shape != (n,) or not isinstance(doc.get("records"), dict)):
        why = "has arrays of other sizes than its settings (damaged)"
    if why is not None:
        notify([f"journal {path} {why}; nothing in it is reused, its work is run again"])
        return values, done, digests
    bad = []
    for a, b in blocks:
        if not stored_done[a:b].any():
            continue
        key = f"{a}-{b}"
        if stored_done[a:b].all() and doc["records"].get(key) == _block_digest(identity, a, b, stored_values):
            values[a:b], done[a:b], digests[key] = stored_values[a:b], True, doc["records"][key]
        else:
            bad.append(key)
    if bad:
        shown = ", ".join(bad[:5]) + (f" and {len(bad) - 5} more" if len(bad) > 5 else "")
        notify([f"journal {path}: block{'s' if len(bad) > 1 else ''} {shown} edited by hand or damaged "
                "(does not match its SHA-256); not trusted, run again"])  # fmt: skip
    return values, done, digests

"""The result of an ensemble: :class:`EnsembleResult`."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path
from .._version import __version__

__all__ = ["EnsembleResult"]


@dataclass(frozen=True)
class EnsembleResult:
    """Final states, end times, event times and status of n runs of one model.

    Attributes
    ----------
    x_final : ndarray, shape (n, nx)
        State at the end of each run: at its terminal event, at ``t_final``, or where it failed.
    t_final : ndarray, shape (n,)
        Time each run ended [s].
    event_times : dict of str to ndarray, shape (n,)
        First crossing time of each event per run [s]; NaN when the event did not trigger
        (for a terminal event: the time the run stopped on it).
    status : ndarray of str, shape (n,)
        ``"ok"`` (reached ``t_final``), ``"event"`` (stopped by a terminal event) or ``"failed"``.
    message : ndarray of str, shape (n,)
        Why a run failed ("" for the others).
    terminal_event : ndarray of str, shape (n,)
        Name of the terminal event that stopped the run ("" when none did).
    x : ndarray, shape (n, len(t_eval), nx), or None
        States on ``t_eval`` (NaN after a run ended); None without ``t_eval``.
    t_eval : ndarray or None
        The output grid [s].
    x0 : ndarray, shape (n, nx)
        Initial states.
    params : ndarray, shape (n, np)
        Parameter vector of each run, in ``param_names`` order.
    state_names, param_names : tuple of str
        Names of the columns of ``x_final``/``x0`` and ``params``.
    stats : dict
        ``method``, ``n_runs``, ``n_chunks``, ``threads``, ``batch_size``, ``n_steps``, ``wall_time`` [s], ...

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.ensemble import EnsembleResult
    >>> t_eval = np.linspace(0.0, 2.0, 5)
    >>> res = pl.ensemble(pl.rigid(), [0.5, 0.0, 0.0, 0.0], 2.0, params={"m2": [0.5, 1.0, 2.0]}, t_eval=t_eval)
    >>> res.n, res.x.shape, res.params.shape  # 3 runs, 5 output times, 4 states; 15 parameters per run
    (3, (3, 5, 4), (3, 15))
    >>> res.params[:, res.param_names.index("m2")], res.success
    (array([0.5, 1. , 2. ]), array([ True,  True,  True]))
    >>> np.round(res.x_final[:, 0], 3)  # theta1 at t = 2 s [rad]: the heavier link 2, the different swing
    array([-0.167, -0.1  ,  0.228])
    >>> back = EnsembleResult.from_npz(res.to_npz("runs.npz"))
    >>> bool(np.array_equal(back.x, res.x))
    True
    """

    x_final: np.ndarray
    t_final: np.ndarray
    event_times: dict[str, np.ndarray]
    status: np.ndarray
    message: np.ndarray
    terminal_event: np.ndarray
    x: np.ndarray | None
    t_eval: np.ndarray | None
    x0: np.ndarray
    params: np.ndarray
    state_names: tuple[str, ...]
    param_names: tuple[str, ...]
    stats: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.t_final)

    @property
    def n(self) -> int:
        """Number of runs."""
        return len(self.t_final)

    @property
    def success(self) -> np.ndarray:
        """Boolean (n,): the run did not fail."""
        return self.status != "failed"

    def table(self) -> np.ndarray:
        """One row per run as a structured NumPy array (no pandas needed).

        Returns
        -------
        ndarray, shape (n,), structured
            Fields ``run``, ``status``, ``t_final``, ``terminal_event``, ``<state>0`` for each
            initial state, ``<param>`` for each parameter, ``<state>`` for each final state,
            ``t_<event>`` for each event time, ``message``. ``pandas.DataFrame(result.table())``
            gives a data frame.
        """
        cols: list[tuple[str, np.ndarray]] = [
            ("run", np.arange(self.n)),
            ("status", self.status.astype("U6")),
            ("t_final", self.t_final),
            ("terminal_event", self.terminal_event.astype(str)),
        ]
        cols += [(f"{s}0", self.x0[:, i]) for i, s in enumerate(self.state_names)]
        cols += [(p, self.params[:, i]) for i, p in enumerate(self.param_names)]
        cols += [(s, self.x_final[:, i]) for i, s in enumerate(self.state_names)]
        cols += [(f"t_{name}", t) for name, t in self.event_times.items()]
        cols.append(("message", self.message.astype(str)))
        out = np.empty(self.n, dtype=[(name, np.asarray(v).dtype) for name, v in cols])
        for name, v in cols:
            out[name] = v
        return out

    def to_npz(self, path: str | os.PathLike) -> Path:
        """Write every array, the names and the settings to a compressed ``.npz`` file (atomically).

        Besides the arrays the file holds ``settings``: a JSON object with the run's settings and
        statistics (``method``, ``rtol``, ``atol``, ``batch_size``, ``chunk_size``, ``max_steps``,
        ``max_wall_time``, ...) and ``pendulab_version``; :meth:`from_npz` reads it all back.

        Parameters
        ----------
        path : str or path-like
            Target file; ``numpy.load(path)`` reads it back (``event_time_<name>`` per event).

        Returns
        -------
        Path
            The file written (``.npz`` appended when missing).
        """
        arrays: dict[str, Any] = {
            "x_final": self.x_final,
            "t_final": self.t_final,
            "status": self.status.astype(str),
            "message": self.message.astype(str),
            "terminal_event": self.terminal_event.astype(str),
            "x0": self.x0,
            "params": self.params,
            "state_names": np.array(self.state_names),
            "param_names": np.array(self.param_names),
            "event_names": np.array(list(self.event_times), dtype=str),
            "settings": np.str_(json.dumps({**_plain(self.stats), "pendulab_version": __version__})),
        }
        for name, t in self.event_times.items():
            arrays[f"event_time_{name}"] = t
        if self.x is not None:
            arrays["x"] = self.x
            arrays["t_eval"] = self.t_eval
        final = Path(path) if str(path).endswith(".npz") else Path(f"{path}.npz")  # NumPy's naming rule
        with atomic_path(final) as tmp:
            np.savez_compressed(tmp, **arrays)
        return final

    @classmethod
    def from_npz(cls, path: str | os.PathLike) -> EnsembleResult:
        """Read a result written by :meth:`to_npz`.

        Parameters
        ----------
        path : str or path-like
            The ``.npz`` file.

        Returns
        -------
        EnsembleResult
            Equal array by array to the one written; ``stats`` holds the stored settings
            (including ``pendulab_version``).

        Raises
        ------
        ValueError
            The file is not an ensemble result (a key is missing).
        """
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in _KEYS if k not in z.files]
            if missing:
                raise ValueError(f"path {str(path)!r} is not an ensemble result written by to_npz (missing {missing})")
            events = [str(e) for e in z["event_names"]]
            return cls(
                x_final=z["x_final"],
                t_final=z["t_final"],
                event_times={e: z[f"event_time_{e}"] for e in events},
                status=z["status"],
                message=z["message"],
                terminal_event=z["terminal_event"],
                x=z["x"] if "x" in z.files else None,
                t_eval=z["t_eval"] if "t_eval" in z.files else None,
                x0=z["x0"],
                params=z["params"],
                state_names=tuple(str(v) for v in z["state_names"]),
                param_names=tuple(str(v) for v in z["param_names"]),
                stats=json.loads(str(z["settings"])) if "settings" in z.files else {},
            )


_KEYS = ("x_final", "t_final", "status", "message", "terminal_event", "x0", "params", "state_names", "param_names", "event_names")


def _plain(d: dict[str, Any]) -> dict[str, Any]:
    """JSON-friendly copy of a stats dict (NumPy scalars to Python, others to str)."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, np.generic):
            v = v.item()
        out[str(k)] = v if v is None or isinstance(v, (bool, int, float, str)) else str(v)
    return out

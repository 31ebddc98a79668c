"""The result of an ensemble: :class:`EnsembleResult`."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path

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

    def to_npz(self, path: str | os.PathLike) -> None:
        """Write every array (and the names) to a compressed ``.npz`` file.

        Parameters
        ----------
        path : str or path-like
            Target file; ``numpy.load(path)`` reads it back (``event_time_<name>`` per event).
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
        }
        for name, t in self.event_times.items():
            arrays[f"event_time_{name}"] = t
        if self.x is not None:
            arrays["x"] = self.x
            arrays["t_eval"] = self.t_eval
        final = Path(path) if str(path).endswith(".npz") else Path(f"{path}.npz")  # NumPy's naming rule
        with atomic_path(final) as tmp:
            np.savez_compressed(tmp, **arrays)

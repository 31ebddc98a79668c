"""The result of a v3 run: trajectory, resets, uptime, score, per-call controller time; JSON and CSV."""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..._io import atomic_open
from ...control.realai.spec import DT, TASKS, TORQUE_LIMIT, leaderboard_model
from .v3_definition import N_RESETS, PLANT_LIMIT, PUBLISHED_V3, RESET_LENGTH, T_FINAL_V3, _end_height

__all__ = [
    "V3Result",
]


@dataclass
class V3Result:
    """One v3 run: trajectory, reset schedule, uptime and score.

    Attributes
    ----------
    task, controller : str
        Task and controller name.
    seed : int
        Schedule seed.
    t : ndarray, shape (N,)
        Scored sample times [s] (N = 30000: 0 ... 59.998).
    x : ndarray, shape (N, 4)
        pendulab states (absolute angles) [rad, rad/s].
    u : ndarray, shape (N, 2)
        Applied torques (tau1, tau2) [N.m], held over [t_k, t_k + 2 ms].
    reset_times : ndarray, shape (n_resets,)
        Scheduled reset times [s].
    reset_states : ndarray, shape (n_resets, 4)
        The configurations the resets drive toward (upstream's relative angles, zero rates).
    intervals : list of (float, float)
        Actual reset intervals (PID active) [s].
    uptime : float
        [s].
    score : float
        ``uptime / 60``.
    n_swingups : int
        Swing-ups counted as upstream counts them.
    threshold : float
        Height line ``0.9 (L1 + L2)`` [m].
    call_times : ndarray
        Wall time of each controller call [s].
    wall_time : float
        Wall time of the run [s].
    plant : str
        The simulated plant (:func:`~pendulab.evaluate.realai.plant.plant_label`).
    link_lengths : tuple of float
        L1, L2 of the simulated plant [m] (the end-effector height).
    passive_limit : float
        Torque the entry was allowed on the passive joint [N.m] (0: the rules).
    schedule : str
        How the resets were drawn from ``seed`` (:func:`~.v3_definition.reset_schedule`).
    """

    task: str
    controller: str
    seed: int
    t: np.ndarray = field(repr=False)
    x: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    reset_times: np.ndarray = field(repr=False)
    reset_states: np.ndarray = field(repr=False)
    intervals: list[tuple[float, float]] = field(repr=False)
    uptime: float
    score: float
    n_swingups: int
    threshold: float
    call_times: np.ndarray = field(repr=False)
    wall_time: float = 0.0
    plant: str = "nominal"
    link_lengths: tuple[float, float] | None = None
    passive_limit: float = 0.0
    schedule: str = "current"

    @property
    def height(self) -> np.ndarray:
        """End-effector height [m] at each sample."""
        if self.link_lengths is None:
            return _end_height(leaderboard_model(self.task), self.x)
        L1, L2 = self.link_lengths
        return -L1 * np.cos(self.x[:, 0]) - L2 * np.cos(self.x[:, 1])

    def interval_uptimes(self) -> list[dict[str, float]]:
        """Uptime per segment between resets (before the first reset, then from each reset's start).

        Returns
        -------
        list of dict
            ``start``, ``end`` [s], ``reset_end`` (end of the reset PID phase, None for the first segment),
            ``uptime`` [s] and ``fraction`` (uptime / segment length).
        """
        starts = [0.0, *(a for a, _ in self.intervals)]
        ends = [*(a for a, _ in self.intervals), float(self.t[-1]) + DT]
        dt = np.diff(self.t, prepend=0.0)
        up = self.height > self.threshold
        out = []
        for i, (a, b) in enumerate(zip(starts, ends, strict=True)):
            sel = (self.t >= a) & (self.t < b) & up
            value = float(np.sum(dt[sel]))
            out.append(
                {
                    "start": a,
                    "end": b,
                    "reset_end": None if i == 0 else float(self.intervals[i - 1][1]),
                    "uptime": value,
                    "fraction": value / (b - a) if b > a else 0.0,
                }
            )
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary.

        Returns
        -------
        dict
            protocol, task, controller, seed, score, uptime [s], n_swingups, per-interval uptimes, controller
            per-call time (median, max, count, against the 2 ms period), the best published entry and
            ``beats_published``, the reset schedule and the run's wall time.
        """
        name, best = max(PUBLISHED_V3[self.task].items(), key=lambda kv: kv[1])
        ct = np.asarray(self.call_times, dtype=float)
        return {
            "protocol": "v3",
            "task": self.task,
            "controller": self.controller,
            "seed": int(self.seed),
            "score": float(self.score),
            "uptime": float(self.uptime),
            "n_swingups": int(self.n_swingups),
            "intervals": self.interval_uptimes(),
            "controller_time": {
                "median_s": float(np.median(ct)) if ct.size else None,
                "max_s": float(np.max(ct)) if ct.size else None,
                "calls": int(ct.size),
                "period_s": DT,
                "median_fits_period": bool(ct.size and np.median(ct) <= DT),
            },
            "published_best": {"name": name, "score": best},
            "beats_published": bool(self.score > best),
            "reset_times": [float(v) for v in self.reset_times],
            "reset_states_relative": [[float(v) for v in row[:2]] for row in self.reset_states],
            "simulation": {
                "integrator": "rk4",
                "dt": DT,
                "t_final": T_FINAL_V3,
                "plant_torque_limit": [PLANT_LIMIT, PLANT_LIMIT],
                "entry_torque_limit": [TORQUE_LIMIT if i == TASKS[self.task] else self.passive_limit for i in range(2)],
                "n_resets": N_RESETS,
                "reset_length": RESET_LENGTH,
                "schedule": self.schedule,
                "upstream": "dfki-ric-underactuated-lab/double_pendulum@1e8544e leaderboard/*/simulation_v3",
                "plant": self.plant,
            },
            "wall_time_s": float(self.wall_time),
        }

    def write_csv(self, path: str | Path) -> Path:
        """Write ``t, theta1, theta2, omega1, omega2, tau1, tau2, height, reset`` (one row per 2 ms step), atomically.

        Parameters
        ----------
        path : str or Path
            CSV file (parent directories are created).

        Returns
        -------
        Path
            The file written.
        """
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        in_reset = np.zeros(len(self.t), dtype=bool)
        for a, b in self.intervals:
            in_reset |= (self.t >= a) & (self.t < b)
        h = self.height
        with atomic_open(p, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t", "theta1", "theta2", "omega1", "omega2", "tau1", "tau2", "height", "reset"])
            for k in range(len(self.t)):
                w.writerow(
                    [repr(float(self.t[k])), *(repr(float(v)) for v in self.x[k]), *(repr(float(v)) for v in self.u[k])]
                    + [repr(float(h[k])), int(in_reset[k])]
                )
        return p

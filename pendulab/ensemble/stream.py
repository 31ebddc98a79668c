"""The streaming phase of a chunk: lanes refilled inside heyoka's event callbacks, without stopping the batch.

Between two stops of ``propagate_until`` the batch integrator runs in compiled code; every stop costs
Python bookkeeping for all lanes. On the flip map a run ends (flips) every ~0.1 s of batch time, so the
stepped loop of :func:`pendulab.ensemble.batch.run_chunk` stopped once per finished run and spent ~40 %
of its time between steps. Here every terminal event has a callback (:class:`Terminal`) that records the
run's end and puts the lane's next run in place, and returns True: the batch never stops for it.

Two obstacles, and how they are handled:

* **A callback may not change the time.** A lane's runs follow each other on its time axis; each run
  keeps its start time ``t0`` (double length, hi + lo) and its elapsed time is computed exactly
  (:func:`elapsed`), so an event time is the same double as when the run starts at t = 0.
* **The horizon.** ``hy.time`` in an event changes heyoka's step control (measured: a flip time moved by
  3e-5 s and depended on the lane's time offset), so each run carries its own clock, an extra state
  ``c' = rate`` reset to 0 at the start of a run, whose values stay below 2^-30: far below every state of
  the pendulum, so heyoka's error control and step sizes, and the pendulum's trajectory to the last bit, are
  the same as without it. The clock event ends the streaming phase of a run at ``t_final (1 - 2^-8)``; the
  runs still going then are finished exactly to ``t_final`` by the stepped loop (a few steps each).

The per-run step budget is counted in whole propagation slices here: a run that started inside a slice
is charged from the next one, so it can pass its budget by less than one slice
(:data:`pendulab.ensemble.batch.SLICE_STEPS` batch steps) before it fails.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["CLOCK_EVENT", "CLOCK_STILL", "Terminal", "Stream", "elapsed", "clock_settings"]

#: Internal event index of the run clock's end (streaming phase only).
CLOCK_EVENT = -20
#: The clock ends the streaming phase of a run at ``t_final * (1 - SWITCH_FRACTION)``.
SWITCH_FRACTION = 2.0**-8
#: Largest clock value: far below any state of the pendulum, so the clock never changes heyoka's steps.
CLOCK_MAX = 2.0**-30
#: Clock rate and end of a lane whose clock must never end it (an idle lane, or any lane of the stepped loop).
CLOCK_STILL = (0.0, 1.0)


def clock_settings(t_final: float) -> tuple[float, float]:
    """Clock rate (a power of two, so the clock's increments are exact) and end value for runs of horizon ``t_final`` [s].

    Parameters
    ----------
    t_final : float
        Horizon of every run [s], > 0.

    Returns
    -------
    (float, float)
        ``rate`` [1/s] with ``t_final * rate <= 2^-30``, and ``end = rate * t_final * (1 - 2^-8)``.
    """
    rate = math.ldexp(CLOCK_MAX, -math.frexp(t_final)[1])  # t_final < 2^e, so t_final * rate < 2^-30
    return rate, rate * (t_final * (1.0 - SWITCH_FRACTION))


def elapsed(hi: float, lo: float, hi0: float, lo0: float) -> tuple[float, float]:
    """``(hi + lo) - (hi0 + lo0)`` in double length.

    Knuth's two-sum keeps the subtraction's rounding error, so the result is the double nearest to the
    exact difference (the same double as a run timed from t = 0).

    Parameters
    ----------
    hi, lo : float
        Later time [s] in double length (heyoka's ``dtime``).
    hi0, lo0 : float
        Earlier time [s] in double length.

    Returns
    -------
    (float, float)
        The difference rounded to a double [s], and the remainder [s].
    """
    s = hi - hi0
    bb = s - hi
    err = (hi - (s - bb)) + (-hi0 - bb) + (lo - lo0)
    t = s + err
    return t, err - (t - s)


class Terminal:
    """Callback of one terminal event: hands the event to the chunk's :class:`Stream`, if one is attached.

    Without a stream (the stepped loop) it returns False, so the event stops the batch as a terminal event
    without a callback does.

    Parameters
    ----------
    event : int
        Index of the event in the ensemble's event plan (or an internal index: clock, spring collapse).
    """

    def __init__(self, event: int) -> None:
        self.event = event
        self.stream: Stream | None = None

    def __call__(self, ta: Any, d_sgn: Any, lane: int) -> bool:
        stream = self.stream
        return False if stream is None else stream.on_event(ta, lane, self.event)


class Stream:
    """Lane bookkeeping of the streaming phase of one chunk.

    Parameters
    ----------
    ta : heyoka.taylor_adaptive_batch
        The chunk's integrator (state rows: the model's ``nx`` states, then the clock).
    x0 : ndarray, shape (m, nx)
        Initial states of the chunk's runs.
    pars : ndarray, shape (n_par, m)
        heyoka parameters of each run (the clock's rate and end are set here).
    t_final : float
        Horizon [s].
    record : callable
        ``record(run, event, t, x)`` for a run ended by a terminal event at elapsed time ``t`` in state
        ``x`` (a view of the integrator's state: the callee copies what it keeps).
    """

    def __init__(self, ta: Any, x0: np.ndarray, pars: np.ndarray, t_final: float, record: Callable[..., None]) -> None:
        self.ta = ta
        self.m, self.nx = x0.shape
        rate, end = clock_settings(t_final)
        # Whole lane columns (the model's state, then the clock; the run's parameters, then the clock's
        # rate and end), so a refill inside a callback is two assignments.
        self.x0 = np.column_stack([x0, np.zeros(self.m)])
        self.pars = np.vstack([pars, np.full((2, self.m), [[rate], [end]])]).T.copy()
        self.idle = (self.x0[0], np.concatenate([pars[:, 0], CLOCK_STILL]))  # benign, and its clock stands still
        self.record = record
        S = ta.batch_size
        self.runs = [-1] * S
        self.t0 = [(0.0, 0.0)] * S
        self.steps = [0] * S  # batch steps charged to the lane's run (whole slices)
        self.next_run = 0
        #: Runs that reached the clock's end: (run, state, elapsed hi, elapsed lo, steps charged).
        self.finish: list[tuple[int, np.ndarray, float, float, int]] = []

    def active(self) -> bool:
        """Whether a lane still holds a run.

        Returns
        -------
        bool
        """
        return any(r >= 0 for r in self.runs)

    def fill(self, lane: int, hi: float, lo: float) -> bool:
        """Start the next run in ``lane`` at lane time (hi, lo), or idle the lane.

        Parameters
        ----------
        lane : int
            SIMD lane.
        hi, lo : float
            The lane's current time [s] in double length: the new run's start.

        Returns
        -------
        bool
            True while a lane holds a run (False tells heyoka to stop the batch).
        """
        ta = self.ta
        r = self.next_run
        if r < self.m:
            self.next_run = r + 1
            self.runs[lane] = r
            self.t0[lane] = (hi, lo)
            self.steps[lane] = 0
            ta.state[:, lane] = self.x0[r]
            ta.pars[:, lane] = self.pars[r]
            return True
        # Idle: a benign finite state whose clock stands still; its events are ignored.
        self.runs[lane] = -1
        ta.state[:, lane], ta.pars[:, lane] = self.idle
        return self.active()

    def run_elapsed(self, lane: int, hi: float, lo: float) -> tuple[float, float]:
        """Elapsed time of the lane's run at lane time (hi, lo).

        Parameters
        ----------
        lane : int
            SIMD lane.
        hi, lo : float
            The lane's time [s] in double length.

        Returns
        -------
        (float, float)
            Elapsed time [s] rounded to a double, and the remainder (:func:`elapsed`).
        """
        return elapsed(hi, lo, *self.t0[lane])

    def on_event(self, ta: Any, lane: int, event: int) -> bool:
        """A terminal event in ``lane``: record the run's end and start the next run.

        Parameters
        ----------
        ta : heyoka.taylor_adaptive_batch
            The integrator, stopped at the event in this lane.
        lane : int
            SIMD lane.
        event : int
            Event index (:data:`CLOCK_EVENT` for the run clock's end).

        Returns
        -------
        bool
            True to go on; False when no lane holds a run any more.
        """
        hi_all, lo_all = ta.dtime
        hi, lo = float(hi_all[lane]), float(lo_all[lane])
        r = self.runs[lane]
        if r >= 0:
            t, t_lo = self.run_elapsed(lane, hi, lo)
            if event == CLOCK_EVENT:
                self.finish.append((r, np.array(ta.state[: self.nx, lane]), t, t_lo, self.steps[lane]))
            else:
                self.record(r, event, t, ta.state[: self.nx, lane])
        return self.fill(lane, hi, lo)

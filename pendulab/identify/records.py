"""Measured records of a double-pendulum robot: reading, column mapping and validation.

A record is a table of samples in joint coordinates (``q2`` relative to link 1, as robots and
RealAIGym write them): time stamps, the two joint angles, optionally the measured joint rates, and
the two joint torques the user names as the *input* (a measured torque, or the commanded one).
RealAIGym's CSV columns are :data:`REALAIGYM_COLUMNS` (the measured torque as the input; its
commanded torque: :data:`REALAIGYM_COMMAND_COLUMNS`; its 2022 ``*_measured.csv`` files, which hold only
the command: :data:`REALAIGYM_2022_COLUMNS`); anyone's data maps its own names with :class:`ColumnMap`.
Time stamps need not be uniform (the robot's loop runs at 1.2-5.8 ms), but
they must increase strictly: a repeated or backwards stamp is an error, not something to guess
around. Every check raises :class:`RecordError` (a ``ValueError``) naming the record and the column.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "RecordError",
    "ColumnMap",
    "REALAIGYM_COLUMNS",
    "REALAIGYM_COMMAND_COLUMNS",
    "REALAIGYM_2022_COLUMNS",
    "Record",
    "read_record",
    "make_record",
]

#: Fewest samples a record may have: differentiation and filtering need a few filter lengths.
MIN_SAMPLES = 50


class RecordError(ValueError):
    """A measured record that cannot be used (missing column, non-finite value, bad time stamps, ...).

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.identify import ColumnMap, RecordError, read_record
    >>> t = np.arange(60) * 0.002
    >>> np.savetxt("log.csv", np.column_stack([t, 0.1 + 0 * t, 0 * t, 0 * t]), delimiter=",", header="t,q1,q2,tau1", comments="")
    >>> columns = ColumnMap(time="t", angles=("q1", "q2"), torques=("tau1", "tau2"))
    >>> try:
    ...     read_record("log.csv", columns)  # the file has no column tau2
    ... except RecordError as err:  # a ValueError
    ...     print(err)
    record 'log' (log.csv): missing columns ['tau2']; the file has ['t', 'q1', 'q2', 'tau1']
    """


@dataclass(frozen=True)
class ColumnMap:
    """Which columns of a table hold what.

    Attributes
    ----------
    time : str
        Time stamps [s].
    angles : tuple of str
        Joint angles ``q1`` (absolute, from hanging) and ``q2`` (relative to link 1) [rad].
    torques : tuple of str
        The input: joint torques [N.m] (``tau2`` between the links). Say which one is the input:
        a measured torque (``tau_meas*``) or the commanded one (``tau_con*``).
    rates : tuple of str or None, default None
        Measured joint rates [rad/s], if the table has them (kept for reference; the identification
        differentiates the angles itself).

    Examples
    --------
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from pendulab.identify import REALAIGYM_COLUMNS, ColumnMap, read_record
    >>> REALAIGYM_COLUMNS.angles, REALAIGYM_COLUMNS.torques  # RealAIGym's CSV: measured torque as the input
    (('pos_meas1', 'pos_meas2'), ('tau_meas1', 'tau_meas2'))
    >>> ours = ColumnMap(time="time_s", angles=("shoulder", "elbow"), torques=("u_shoulder", "u_elbow"))
    >>> t = np.arange(100) * 0.005
    >>> rows = np.column_stack([t, 0.1 * np.cos(3 * t), 0.2 * np.sin(3 * t), 0.5 + 0 * t, 0 * t])
    >>> np.savetxt("lab.csv", rows, delimiter=",", header="time_s,shoulder,elbow,u_shoulder,u_elbow", comments="")
    >>> record = read_record("lab.csv", ours)
    >>> record.q.shape, record.tau[0].tolist(), record.qd is None  # no rate columns mapped
    ((100, 2), [0.5, 0.0], True)
    """

    time: str
    angles: tuple[str, str]
    torques: tuple[str, str]
    rates: tuple[str, str] | None = None

    def required(self) -> list[str]:
        """Column names the table must have.

        Returns
        -------
        list of str
            Time, angles, torques and (if set) rates.
        """
        return [self.time, *self.angles, *self.torques, *(self.rates or ())]


#: RealAIGym's record columns with the measured torque as the input.
REALAIGYM_COLUMNS = ColumnMap(
    time="time", angles=("pos_meas1", "pos_meas2"), torques=("tau_meas1", "tau_meas2"), rates=("vel_meas1", "vel_meas2")
)

#: RealAIGym's record columns with the commanded torque as the input.
REALAIGYM_COMMAND_COLUMNS = ColumnMap(
    time="time", angles=("pos_meas1", "pos_meas2"), torques=("tau_con1", "tau_con2"), rates=("vel_meas1", "vel_meas2")
)

#: RealAIGym's 2022 ``*_measured.csv`` layout (design A.0's runs of 2022-08-12): one torque per joint,
#: the *commanded* one (continuous values, not a reading's steps; it matches ``tau_con`` of the same
#: excitation recorded again in the later layout).
REALAIGYM_2022_COLUMNS = ColumnMap(time="time", angles=("pos1", "pos2"), torques=("tau1", "tau2"), rates=("vel1", "vel2"))


@dataclass(frozen=True)
class Record:
    """One validated measured record, joint coordinates.

    Attributes
    ----------
    name : str
        Where it came from (file stem or a given name).
    t : numpy.ndarray, shape (n,)
        Strictly increasing time stamps [s], starting where the record starts.
    q : numpy.ndarray, shape (n, 2)
        Joint angles ``q1`` (absolute) and ``q2`` (relative) [rad].
    tau : numpy.ndarray, shape (n, 2)
        Input joint torques [N.m].
    qd : numpy.ndarray or None, shape (n, 2)
        Measured joint rates [rad/s], if the record has them.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.identify.datasets import C1_EXCITATION, c1_record
    >>> record = c1_record(C1_EXCITATION[0])  # a shipped measured record of RealAIGym's C.1 robot
    >>> record.name, record.q.shape, record.tau.shape, round(record.duration, 2)
    ('20230629-143339', (4998, 2), (4998, 2), 10.0)
    >>> print(f"median sample interval {np.median(np.diff(record.t)) * 1e3:.1f} ms")
    median sample interval 2.0 ms
    >>> np.round(np.abs(record.tau).max(axis=0), 2)  # largest measured torques [N.m]
    array([0.41, 0.82])
    """

    name: str
    t: np.ndarray
    q: np.ndarray
    tau: np.ndarray
    qd: np.ndarray | None = field(default=None)

    @property
    def duration(self) -> float:
        """Time spanned [s]."""
        return float(self.t[-1] - self.t[0])


def make_record(
    name: str, t: np.ndarray, q: np.ndarray, tau: np.ndarray, qd: np.ndarray | None = None, *, columns: ColumnMap | None = None
) -> Record:
    """Validate arrays and make a :class:`Record` of them.

    Parameters
    ----------
    name : str
        The record's name in messages.
    t : array_like, shape (n,)
        Time stamps [s].
    q : array_like, shape (n, 2)
        Joint angles [rad].
    tau : array_like, shape (n, 2)
        Input joint torques [N.m].
    qd : array_like, shape (n, 2), optional
        Measured joint rates [rad/s].
    columns : ColumnMap, optional
        Column names to quote in messages.

    Returns
    -------
    Record
        The validated record.

    Raises
    ------
    RecordError
        Wrong shapes, fewer than :data:`MIN_SAMPLES` samples, a non-finite value (the column and the
        first bad row named), or time stamps that repeat or go backwards.
    """
    cols = columns or ColumnMap(time="t", angles=("q1", "q2"), torques=("tau1", "tau2"), rates=("qd1", "qd2"))
    arrays = {"t": np.asarray(t, dtype=float), "q": np.asarray(q, dtype=float), "tau": np.asarray(tau, dtype=float)}
    if qd is not None:
        arrays["qd"] = np.asarray(qd, dtype=float)
    n = arrays["t"].shape[0] if arrays["t"].ndim == 1 else -1
    if n < 0:
        raise RecordError(f"record {name!r}: time must be one-dimensional, got shape {arrays['t'].shape}")
    if n < MIN_SAMPLES:
        raise RecordError(f"record {name!r}: {n} samples; at least {MIN_SAMPLES} are needed to differentiate and filter")
    labels = {"t": (cols.time,), "q": cols.angles, "tau": cols.torques, "qd": cols.rates or ("qd1", "qd2")}
    for key, a in arrays.items():
        if key != "t" and a.shape != (n, 2):
            raise RecordError(f"record {name!r}: {key} must have shape ({n}, 2) like the time stamps, got {a.shape}")
        bad = ~np.isfinite(a.reshape(n, -1))
        if bad.any():
            row, col = np.argwhere(bad)[0]
            raise RecordError(
                f"record {name!r}: column {labels[key][col]!r} is not finite at row {row} ({a.reshape(n, -1)[row, col]!r})"
            )
    dt = np.diff(arrays["t"])
    if (dt <= 0).any():
        i = int(np.argmax(dt <= 0))
        kind = "repeats" if dt[i] == 0 else "goes backwards"
        raise RecordError(
            f"record {name!r}: time {kind} at row {i + 1} ({arrays['t'][i]!r} s then {arrays['t'][i + 1]!r} s); "
            "time stamps must increase strictly"
        )
    return Record(name=name, t=arrays["t"] - arrays["t"][0], q=arrays["q"], tau=arrays["tau"], qd=arrays.get("qd"))


def read_record(path: str | os.PathLike[str], columns: ColumnMap = REALAIGYM_COLUMNS, *, name: str | None = None) -> Record:
    """Read a CSV record (header row, then numbers) through a column map.

    Parameters
    ----------
    path : path-like
        The CSV file.
    columns : ColumnMap, default :data:`REALAIGYM_COLUMNS`
        Which columns hold time, angles, the input torques and (optionally) rates.
    name : str, optional
        The record's name; default: the file's parent folder name if the file is RealAIGym's
        ``<stamp>/trajectory.csv``, else the file stem.

    Returns
    -------
    Record
        The validated record.

    Raises
    ------
    FileNotFoundError
        No such file.
    RecordError
        An empty file, a missing column (all missing ones named, with the columns the file has), a
        value that is not a number, and every check of :func:`make_record`.

    Examples
    --------
    A record written as CSV, here from a simulated swing of the identified robot:

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.identify import ColumnMap, read_record
    >>> traj = pl.simulate(pl.rigid(plant="c1"), [0.5, 0.5, 0.0, 0.0], 1.0, dt=0.002, method="cvodes")
    >>> q1, q2 = traj["theta1"], traj["theta2"] - traj["theta1"]  # joint angles: q2 relative to link 1
    >>> table = np.column_stack([traj.t, q1, q2, traj["tau1"], traj["tau2"]])
    >>> np.savetxt("swing.csv", table, delimiter=",", header="t,q1,q2,tau1,tau2", comments="")
    >>> record = read_record("swing.csv", ColumnMap(time="t", angles=("q1", "q2"), torques=("tau1", "tau2")))
    >>> record.name, record.q.shape, round(record.duration, 3)
    ('swing', (501, 2), 1.0)
    >>> bool(np.allclose(record.q, np.column_stack([q1, q2])))
    True
    """
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"record file not found: {p}")
    label = name or (p.parent.name if p.stem == "trajectory" else p.stem)
    with p.open(newline="") as fh:
        reader = csv.reader(fh)
        header = next(reader, None)
        if not header:
            raise RecordError(f"record {label!r} ({p}): the file is empty; expected a header row and samples")
        header = [h.strip() for h in header]
        missing = [c for c in columns.required() if c not in header]
        if missing:
            raise RecordError(f"record {label!r} ({p}): missing columns {missing}; the file has {header}")
        idx = [header.index(c) for c in columns.required()]
        rows = []
        for k, row in enumerate(reader, start=2):
            if not row:
                continue
            try:
                rows.append([float(row[i]) for i in idx])
            except (ValueError, IndexError):
                raise RecordError(f"record {label!r} ({p}): line {k} is not a row of numbers in the needed columns") from None
    data = np.array(rows, dtype=float).reshape(-1, len(idx))
    rates = data[:, 5:7] if columns.rates else None
    return make_record(label, data[:, 0], data[:, 1:3], data[:, 3:5], rates, columns=columns)

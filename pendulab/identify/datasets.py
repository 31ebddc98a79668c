"""Measured records shipped with pendulab: RealAIGym's design C.1 and A.0 robots (DFKI, BSD-3-Clause).

Both archives (``data/LICENSE-DFKI.txt`` says where from) store RealAIGym's columns
:data:`SHIPPED_COLUMNS` as float32 (the readings step by 3.8e-4 rad and 5.9e-3 N.m, far above
float32's resolution).

Design C.1, ten records of 2023-06-29:

* :data:`C1_EXCITATION`: eight 10 s excitation runs, the only ones identification may fit,
  cross-validate or choose structure on;
* :data:`C1_BLIND`: two 6 s swing-up-sized runs an hour later, **the blind test**: used only to
  judge a finished model, never to fit, tune or choose anything.

Design A.0 (the second robot: link lengths 0.3 / 0.2 m against C.1's 0.2 / 0.3 m), twelve records:

* :data:`A0_SYSID`: the nine readable system-identification runs of 2022-08-15 (``trajectory_00``
  to ``_05``, ``_11``, ``_12``, ``_13``; ``_06`` to ``_10`` are not in the upstream repository):
  eight 10 s excitation runs at 2 ms (in ``_12`` and ``_13`` only the elbow is driven) and one 6 s
  tracked swing-up at 1.5 ms (``_11``). The only records A.0's identification fits, cross-validates
  or chooses anything on.
* :data:`A0_SWINGUP`: three 20 s pendubot swing-ups of 2022-08-19 (TVLQR, then LQR balancing at the
  top; only the shoulder is driven, the elbow motor gets friction compensation up to 0.172 N.m),
  2.5 ms: the validation, never fitted or tuned on.

**The input of A.0 is the commanded torque** (:data:`A0_COLUMNS`), not the measured one as for
C.1: refitted leave-one-record-out on the sys-id records, the model driven by the command predicted
the held-out angles better at every horizon and on both joints (0.25 s: 0.0245 / 0.0672 rad against
0.0273 / 0.0744 rad; ``benchmarks/results/identify_a0.md``). A.0's torque reading lags the command by
about 6-20 ms and reads up to 0.57 N.m on a joint commanded zero (the shoulder of ``_12`` and ``_13``).

The 2022-08-12 sys-id runs of A.0 (``*_measured.csv``, :data:`~pendulab.identify.records.REALAIGYM_2022_COLUMNS`)
are not shipped or fitted: they hold only the commanded torque (continuous values, not a reading's
5.9e-3 N.m steps; they match ``tau_con`` of the same excitation repeated on 2022-08-15), so the
input could not be chosen on them; they are sampled at 2, 3.3 and 5 ms (fitted together, every
record would go onto a 5 ms grid); and they would add 0.7-0.9 MB to the 1.5 MB the nine and the
swing-ups take.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

import numpy as np

from .records import REALAIGYM_COLUMNS, REALAIGYM_COMMAND_COLUMNS, ColumnMap, Record, make_record

__all__ = ["SHIPPED_COLUMNS", "C1_EXCITATION", "C1_BLIND", "c1_record", "A0_SYSID", "A0_SWINGUP", "A0_COLUMNS", "a0_record"]

#: Columns of every shipped record (RealAIGym's names).
SHIPPED_COLUMNS: tuple[str, ...] = (
    "time", "pos_meas1", "pos_meas2", "vel_meas1", "vel_meas2", "tau_meas1", "tau_meas2", "tau_con1", "tau_con2",
)  # fmt: skip

#: Stamps of the excitation records (fit, cross-validation, structure choice).
C1_EXCITATION: tuple[str, ...] = (
    "20230629-143339", "20230629-143524", "20230629-143601", "20230629-143704",
    "20230629-143747", "20230629-143906", "20230629-144003", "20230629-144115",
)  # fmt: skip

#: Stamps of the blind-test records (judging only).
C1_BLIND: tuple[str, ...] = ("20230629-154220", "20230629-154548")

#: A.0's system-identification records (fit, cross-validation, structure choice): day and upstream file stem.
A0_SYSID: tuple[str, ...] = (
    "20220815-trajectory_00", "20220815-trajectory_01", "20220815-trajectory_02", "20220815-trajectory_03",
    "20220815-trajectory_04", "20220815-trajectory_05", "20220815-trajectory_11", "20220815-trajectory_12",
    "20220815-trajectory_13",
)  # fmt: skip

#: A.0's pendubot swing-up records (validation only): day and upstream stamp.
A0_SWINGUP: tuple[str, ...] = ("20220819-174435", "20220819-174932", "20220819-175617")

#: A.0's input: the commanded torque (see the module docstring).
A0_COLUMNS: ColumnMap = REALAIGYM_COMMAND_COLUMNS


@cache
def _archive(file: str) -> dict[str, np.ndarray]:
    with resources.files(__package__).joinpath(f"data/{file}").open("rb") as fh, np.load(fh) as z:
        return {k: z[k] for k in z.files}


def _shipped(robot: str, file: str, stamps: tuple[str, ...], stamp: str, columns: ColumnMap) -> Record:
    if stamp not in stamps:
        raise KeyError(f"unknown {robot} record {stamp!r}; expected one of {list(stamps)}")
    z = _archive(file)
    names = [str(c) for c in z["columns"]]
    missing = [c for c in columns.required() if c not in names]
    if missing:
        raise KeyError(f"the shipped {robot} records have no columns {missing}; they have {names}")
    data = z["r" + stamp.replace("-", "_")].astype(float)
    col = {c: data[:, names.index(c)] for c in columns.required()}
    rates = np.column_stack([col[c] for c in columns.rates]) if columns.rates else None
    return make_record(
        stamp, col[columns.time], np.column_stack([col[c] for c in columns.angles]),
        np.column_stack([col[c] for c in columns.torques]), rates, columns=columns,
    )  # fmt: skip


def c1_record(stamp: str, columns: ColumnMap = REALAIGYM_COLUMNS) -> Record:
    """One shipped C.1 record.

    Parameters
    ----------
    stamp : str
        One of :data:`C1_EXCITATION` or :data:`C1_BLIND`.
    columns : ColumnMap, default :data:`~pendulab.identify.records.REALAIGYM_COLUMNS`
        Which columns to take (e.g. ``tau_con*`` as the input instead of ``tau_meas*``).

    Returns
    -------
    Record
        The record.

    Raises
    ------
    KeyError
        An unknown stamp, or a column the archive does not have.
    """
    return _shipped("C.1", "realaigym_c1.npz", C1_EXCITATION + C1_BLIND, stamp, columns)


def a0_record(stamp: str, columns: ColumnMap = A0_COLUMNS) -> Record:
    """One shipped A.0 record.

    Parameters
    ----------
    stamp : str
        One of :data:`A0_SYSID` or :data:`A0_SWINGUP`.
    columns : ColumnMap, default :data:`A0_COLUMNS`
        Which columns to take: by default the commanded torque as the input (A.0's choice);
        :data:`~pendulab.identify.records.REALAIGYM_COLUMNS` for the measured one.

    Returns
    -------
    Record
        The record: time [s], joint angles [rad], input torques [N.m], measured rates [rad/s].

    Raises
    ------
    KeyError
        An unknown stamp, or a column the archive does not have.
    """
    return _shipped("A.0", "realaigym_a0.npz", A0_SYSID + A0_SWINGUP, stamp, columns)

"""Measured records shipped with pendulab: RealAIGym's design C.1 robot (DFKI, BSD-3-Clause).

Ten records of 2023-06-29 (``data/LICENSE-DFKI.txt`` says where from), stored as float32 columns
(the readings step by 3.8e-4 rad and 5.9e-3 N.m, far above float32's resolution):

* :data:`C1_EXCITATION`: eight 10 s excitation runs, the only ones identification may fit,
  cross-validate or choose structure on;
* :data:`C1_BLIND`: two 6 s swing-up-sized runs an hour later, **the blind test**: used only to
  judge a finished model, never to fit, tune or choose anything.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

import numpy as np

from .records import REALAIGYM_COLUMNS, ColumnMap, Record, make_record

__all__ = ["C1_EXCITATION", "C1_BLIND", "c1_record"]

#: Stamps of the excitation records (fit, cross-validation, structure choice).
C1_EXCITATION: tuple[str, ...] = (
    "20230629-143339", "20230629-143524", "20230629-143601", "20230629-143704",
    "20230629-143747", "20230629-143906", "20230629-144003", "20230629-144115",
)  # fmt: skip

#: Stamps of the blind-test records (judging only).
C1_BLIND: tuple[str, ...] = ("20230629-154220", "20230629-154548")


@cache
def _archive() -> dict[str, np.ndarray]:
    with resources.files(__package__).joinpath("data/realaigym_c1.npz").open("rb") as fh, np.load(fh) as z:
        return {k: z[k] for k in z.files}


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
    if stamp not in C1_EXCITATION + C1_BLIND:
        raise KeyError(f"unknown C.1 record {stamp!r}; expected one of {list(C1_EXCITATION + C1_BLIND)}")
    z = _archive()
    names = [str(c) for c in z["columns"]]
    missing = [c for c in columns.required() if c not in names]
    if missing:
        raise KeyError(f"the shipped C.1 records have no columns {missing}; they have {names}")
    data = z["r" + stamp.replace("-", "_")].astype(float)
    col = {c: data[:, names.index(c)] for c in columns.required()}
    rates = np.column_stack([col[c] for c in columns.rates]) if columns.rates else None
    return make_record(
        stamp, col[columns.time], np.column_stack([col[c] for c in columns.angles]),
        np.column_stack([col[c] for c in columns.torques]), rates, columns=columns,
    )  # fmt: skip

"""Judging an identified model on held-out measured motion, beside other parameter sets.

Two measures per record and joint: the inverse-dynamics **torque residual** (measured torque
minus the model's, RMS over the usable samples) and the **open-loop prediction error** of the
angles after 0.1, 0.25, 0.5 and 1 s, started from the measured state every 0.1 s along the
record under the measured torques (:func:`pendulab.identify.simulate.prediction_errors`).
:func:`leave_one_out` refits pendulab's model without each record in turn and judges it on that
record, so no number comes from data the model saw.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .fit import normals
from .pipeline import identify
from .preprocess import DEFAULT_CUTOFF_HZ, Prepared, prepare
from .records import Record
from .regressor import STANDARD_NAMES, robot_to_standard
from .simulate import HORIZONS, prediction_errors

__all__ = ["RecordScore", "score_record", "standard_vector", "leave_one_out"]


@dataclass(frozen=True)
class RecordScore:
    """One model on one record.

    Attributes
    ----------
    record : str
        The record.
    model : str
        The model's name.
    torque_rms : numpy.ndarray, shape (2,)
        Torque residual RMS per joint [N.m].
    torque_n : int
        Samples behind it.
    prediction : numpy.ndarray, shape (len(horizons), n_starts, 2)
        Angle errors per horizon, start and joint [rad].
    """

    record: str
    model: str
    torque_rms: np.ndarray
    torque_n: int
    prediction: np.ndarray


def standard_vector(params: Mapping[str, float], offset: Sequence[float] = (0.0, 0.0)) -> np.ndarray:
    """Standard parameters of a robot parameter set.

    Parameters
    ----------
    params : mapping of str to float
        Values of :data:`pendulab.model.robot.ROBOT_PARAM_NAMES`.
    offset : sequence of float, default (0, 0)
        Torque-reading offsets [N.m].

    Returns
    -------
    numpy.ndarray, shape (13,)
        Values of :data:`~pendulab.identify.regressor.STANDARD_NAMES`.
    """
    pi = robot_to_standard(params)
    pi["o1"], pi["o2"] = float(offset[0]), float(offset[1])
    return np.array([pi[n] for n in STANDARD_NAMES])


def score_record(prep: Prepared, model: str, pi: np.ndarray, fixed: Mapping[str, float]) -> RecordScore:
    """Torque residual and prediction errors of one model on one prepared record.

    Parameters
    ----------
    prep : Prepared
        The record.
    model : str
        The model's name.
    pi : numpy.ndarray, shape (13,)
        Its standard parameters.
    fixed : mapping of str to float
        Known geometry.

    Returns
    -------
    RecordScore
        The measures.
    """
    nrm = normals(prep, fixed)
    return RecordScore(prep.name, model, nrm.rms(pi), nrm.n, prediction_errors(prep, pi, fixed, HORIZONS))


def leave_one_out(
    records: Sequence[Record],
    fixed: Mapping[str, float],
    prior: Mapping[str, float],
    others: Mapping[str, Mapping[str, float]],
    *,
    cutoff_hz: float = DEFAULT_CUTOFF_HZ,
    structure: str = "auto",
    done: Mapping[str, Sequence[RecordScore]] | None = None,
    on_fold: Callable[[str, list[RecordScore]], None] | None = None,
) -> dict[str, list[RecordScore]]:
    """Leave-one-record-out validation of pendulab's identification beside fixed parameter sets.

    Parameters
    ----------
    records : sequence of Record
        The records (at least three: each fold fits on the others and compares structures on them).
    fixed : mapping of str to float
        Known geometry.
    prior : mapping of str to float
        Prior standard parameters.
    others : mapping of str to mapping
        Named robot parameter sets judged on the same records (e.g. DFKI's).
    cutoff_hz : float, default :data:`~pendulab.identify.preprocess.DEFAULT_CUTOFF_HZ`
        Low-pass cutoff [Hz].
    structure : str, default "auto"
        Passed to :func:`~pendulab.identify.pipeline.identify`.
    done : mapping of str to sequence of RecordScore, optional
        Folds already finished (by held-out record), skipped (resume).
    on_fold : callable, optional
        Called with (record, its scores) after each finished fold (to journal it).

    Returns
    -------
    dict of str to list of RecordScore
        By held-out record: pendulab's score (model ``"pendulab"``) and each other set's.

    Raises
    ------
    ValueError
        Fewer than three records.
    """
    if len(records) < 3:
        raise ValueError(f"leave-one-out needs at least three records, got {len(records)}")
    out: dict[str, list[RecordScore]] = {k: list(v) for k, v in (done or {}).items()}
    for k, held in enumerate(records):
        if held.name in out:
            continue
        rest = [r for i, r in enumerate(records) if i != k]
        ident = identify(rest, fixed, prior, cutoff_hz=cutoff_hz, structure=structure)
        prep = prepare(held, cutoff_hz)
        scores = [score_record(prep, "pendulab", ident.vector(), fixed)]
        scores += [score_record(prep, name, standard_vector(p), fixed) for name, p in others.items()]
        out[held.name] = scores
        if on_fold is not None:
            on_fold(held.name, scores)
    return out

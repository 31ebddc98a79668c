"""Argument checks of :func:`pendulab.ensemble.ensemble`: per-run parameters, initial states, output
times, and the ``progress`` argument turned into one report function.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .._checks import bounded_int, check_spring_lengths
from ..model.model import Model

__all__ = ["check_params", "check_x0", "MAX_RUNS"]

#: Largest number of runs of one ensemble (a (n, nx) float array of 10**8 runs is already 6 GB).
MAX_RUNS = 10**8


# -- argument checks ----------------------------------------------------------------
def check_params(model: Model, params: Any) -> np.ndarray | None:
    """Per-run parameter vectors (n, np) from ``params`` (None stays None).

    Parameters
    ----------
    model : Model
    params : mapping of str to array_like (n,), array_like (n, np), or None

    Returns
    -------
    ndarray, shape (n, np), or None

    Raises
    ------
    ValueError
        Unknown names, mismatched lengths, empty, non-finite or inadmissible values.
    """
    if params is None:
        return None
    names = model.param_names
    if isinstance(params, Mapping):
        if not params:
            raise ValueError("params must name at least one parameter, got an empty mapping")
        unknown = [k for k in params if k not in names]
        if unknown:
            raise ValueError(
                f"params: unknown parameter names {unknown} for the {model.kind} model; expected some of {list(names)}"
            )
        cols = {}
        for k, v in params.items():
            try:
                a = np.asarray(v, dtype=float)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"params[{k!r}] must be an array of numbers, got {v!r}") from exc
            if a.ndim != 1:
                raise ValueError(f"params[{k!r}] must have shape (n,), got shape {a.shape}")
            cols[k] = a
        lengths = {k: len(a) for k, a in cols.items()}
        if len(set(lengths.values())) != 1:
            raise ValueError(f"params: every array must have the same length n, got lengths {lengths}")
        n = next(iter(lengths.values()))
        P = np.tile(model.p, (n, 1))
        for k, a in cols.items():
            P[:, names.index(k)] = a
    else:
        try:
            P = np.array(params, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"params must be a mapping name -> array (n,) or an array (n, {len(names)}), got {params!r}"
            ) from exc
        if P.ndim != 2 or P.shape[1] != len(names):
            raise ValueError(f"params must have shape (n, {len(names)}) in param_names order {list(names)}, got shape {P.shape}")
    if len(P) == 0:
        raise ValueError("params: the ensemble is empty (n = 0 runs); give at least one run")
    bounded_int("number of runs (rows of params)", len(P), high=MAX_RUNS, why="memory of the result arrays")
    bad = np.flatnonzero(~np.all(np.isfinite(P), axis=1))
    if bad.size:
        raise ValueError(f"params must be finite; run {int(bad[0])} has {dict(zip(names, P[bad[0]].tolist(), strict=True))}")
    # Each distinct run is validated as a whole by the model's own parameter checks: some rules join
    # parameters (m2 lc2^2 + I2 > 0), so mixing columns of different runs would refuse valid runs.
    uniq, first = np.unique(P, axis=0, return_index=True)
    for row, i in zip(uniq, first, strict=True):
        try:
            model.params.replace(**dict(zip(names, row.tolist(), strict=True)))
        except (ValueError, TypeError) as exc:
            raise ValueError(f"params: run {int(i)} is inadmissible ({exc})") from exc
    return P


def check_x0(model: Model, x0: Any, n: int | None) -> np.ndarray:
    """Initial states (n, nx) from ``x0`` (broadcast one state to ``n`` runs).

    Parameters
    ----------
    model : Model
    x0 : array_like, shape (n, nx) or (nx,)
    n : int or None
        Number of runs set by ``params`` (None: ``x0`` sets it).

    Returns
    -------
    ndarray, shape (n, nx)

    Raises
    ------
    ValueError
        Wrong shape, empty, a mismatch with ``n`` or a non-finite state (naming the run).
    """
    nx = model.nx
    try:
        X = np.array(x0, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"x0 must be an array of shape (n, {nx}) or ({nx},), got {x0!r}") from exc
    if X.ndim == 1:
        if X.shape != (nx,):
            raise ValueError(f"x0 must have shape (n, {nx}) or ({nx},) {list(model.state_names)}, got shape {X.shape}")
        if n is None:
            raise ValueError(
                f"x0 has shape ({nx},): one state needs params to define the number of runs; give x0 of shape (n, {nx})"
            )
        X = np.tile(X, (n, 1))
    elif X.ndim != 2 or X.shape[1] != nx:
        raise ValueError(f"x0 must have shape (n, {nx}) in state order {list(model.state_names)}, got shape {X.shape}")
    if len(X) == 0:
        raise ValueError(f"x0: the ensemble is empty (shape {X.shape}); give at least one run")
    bounded_int("number of runs (rows of x0)", len(X), high=MAX_RUNS, why="memory of the result arrays")
    if n is not None and len(X) != n:
        raise ValueError(f"x0 has {len(X)} runs but params has {n}; they must match")
    bad = np.flatnonzero(~np.all(np.isfinite(X), axis=1))
    if bad.size:
        raise ValueError(f"x0 must be finite; run {int(bad[0])} has {X[bad[0]].tolist()}")
    check_spring_lengths(model.kind, X, "x0")
    return X


def _check_t_eval(t_eval: Any, tf: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    try:
        te = np.array(t_eval, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"t_eval must be an array of times [s], got {t_eval!r}") from exc
    if te.size == 0 or not np.all(np.isfinite(te)) or np.any(np.diff(te) <= 0) or te[0] < 0 or te[-1] > tf:
        raise ValueError(f"t_eval must be non-empty, finite, strictly increasing and within [0, t_final={tf}], got {t_eval!r}")
    return te


def _progress(progress: Any, total: int) -> Callable[[int | None], None]:
    """``report(k)``: k more runs done; ``report(None)``: finished."""
    if progress is None or progress is False:
        return lambda k: None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, unit="run", desc="ensemble")

        def report(k: int | None) -> None:
            if k is None:
                bar.close()
            else:
                bar.update(k)

        return report
    if not callable(progress):
        raise ValueError(f"progress must be a callable progress(done, total), True or None, got {progress!r}")
    done = [0]

    def report_cb(k: int | None) -> None:
        if k is not None:
            done[0] += k
            progress(done[0], total)

    return report_cb

"""Compiled Taylor integrators, cached per structure key (compiled once per key and process)."""

from __future__ import annotations

import copy
import threading
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...model.builders import build_elastic, build_rigid
from ...model.model import model_functions
from .availability import check_tolerance_floor, heyoka_module
from .translate import TaylorSystem, translate


# -- compilation cache ------------------------------------------------------------
@dataclass(frozen=True)
class StructureKey:
    """What a compiled Taylor integrator depends on (never a non-zero parameter value).

    Attributes
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    zero_params : tuple of int
        Indices of the parameters specialised to 0.
    zero_inputs : tuple of int
        Indices of the inputs specialised to 0.
    tol : float
        heyoka tolerance (it sets the Taylor order).
    compact_mode, high_accuracy : bool
        heyoka options.
    """

    kind: str
    zero_params: tuple[int, ...]
    zero_inputs: tuple[int, ...]
    tol: float
    compact_mode: bool = False
    high_accuracy: bool = False


def structure_key(
    kind: str, p: np.ndarray, zero_inputs: Sequence[int], tol: float, compact_mode: bool = False, high_accuracy: bool = False
) -> StructureKey:
    """The :class:`StructureKey` of a run: the parameters that are exactly 0 are specialised.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
    p : ndarray, shape (np,)
        Parameter vector of the model.
    zero_inputs : sequence of int
        Inputs identically zero over the run.
    tol : float
        heyoka tolerance.
    compact_mode, high_accuracy : bool
        heyoka options.

    Returns
    -------
    StructureKey

    Raises
    ------
    ValueError
        ``tol`` below double-precision epsilon (:func:`.availability.check_tolerance_floor`): every heyoka
        integrator is built from a key, so no path compiles an unbounded Taylor order.
    """
    check_tolerance_floor("tol", tol)
    zp = tuple(int(i) for i in np.flatnonzero(np.asarray(p) == 0.0))
    return StructureKey(kind, zp, tuple(sorted(int(i) for i in zero_inputs)), float(tol), bool(compact_mode), bool(high_accuracy))


@dataclass
class _Entry:
    system: TaylorSystem
    template: Any
    pool: list
    lock: threading.Lock


_CACHE: dict[StructureKey, _Entry] = {}
_CACHE_LOCK = threading.Lock()
_COMPILE_COUNT = 0


def compile_count() -> int:
    """Number of Taylor integrators compiled in this process.

    Returns
    -------
    int
        Compilations (translation + JIT) since the process started; a run that reuses a
        cached integrator does not count.
    """
    return _COMPILE_COUNT


def is_compiled(key: StructureKey) -> bool:
    """Whether the Taylor integrator of ``key`` is already compiled in this process (no compilation on its next run).

    Parameters
    ----------
    key : StructureKey
        From :func:`structure_key`.

    Returns
    -------
    bool
    """
    return key in _CACHE


def clear_cache() -> None:
    """Forget every compiled integrator (the next run of each structure compiles again)."""
    with _CACHE_LOCK:
        _CACHE.clear()
        _PREPARED.clear()


#: Runs prepared before, by (kind, parameter bytes, zero inputs, tol, options): the cache entry and the
#: runtime parameter vector. A repeated run then skips building its key and evaluating the hoisted
#: coefficients (~25 us of a ~250 us run of the rigid chaotic case). Bounded: parameter sweeps pass through.
_PREPARED: dict[tuple, tuple[_Entry, np.ndarray]] = {}
_PREPARED_MAX = 256


def prepared(
    kind: str, p: np.ndarray, zero_inputs: tuple[int, ...], tol: float, compact_mode: bool = False, high_accuracy: bool = False
) -> tuple[_Entry, np.ndarray]:
    """The cache entry of a run (compiled on first use) and its runtime parameters with zero torques.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
    p : ndarray, shape (np,)
        Parameter vector of the model.
    zero_inputs : tuple of int
        Inputs identically zero over the run.
    tol : float
        heyoka tolerance.
    compact_mode, high_accuracy : bool
        heyoka options.

    Returns
    -------
    entry : _Entry
        The compiled integrator's entry (:func:`structure_key`, then the compilation cache).
    pars : ndarray, shape (n_pars,)
        ``system.pars(0, p)``, read-only (copy it into the integrator's ``pars``).
    """
    p = np.asarray(p, dtype=float)
    memo = (kind, p.tobytes(), zero_inputs, tol, compact_mode, high_accuracy)
    hit = _PREPARED.get(memo)
    if hit is not None:
        return hit
    key = structure_key(kind, p, zero_inputs, tol, compact_mode, high_accuracy)
    entry = _entry(key)
    pars = entry.system.pars(np.zeros(entry.system.n_inputs), p)
    pars.setflags(write=False)
    with _CACHE_LOCK:
        if len(_PREPARED) >= _PREPARED_MAX:
            _PREPARED.clear()
        _PREPARED[memo] = (entry, pars)
    return entry, pars


def _entry(key: StructureKey) -> _Entry:
    global _COMPILE_COUNT
    entry = _CACHE.get(key)
    if entry is not None:
        return entry
    with _CACHE_LOCK:
        entry = _CACHE.get(key)
        if entry is None:
            hy = heyoka_module()
            f = model_functions(key.kind)["rhs"]
            names = _state_names(key.kind)
            system = translate(f, zero_params=key.zero_params, zero_inputs=key.zero_inputs, state_names=names)
            ta = hy.taylor_adaptive(
                system.sys,
                [0.0] * len(names),
                pars=[0.0] * system.n_pars,
                tol=key.tol,
                compact_mode=key.compact_mode,
                high_accuracy=key.high_accuracy,
            )
            _COMPILE_COUNT += 1
            entry = _Entry(system, ta, [ta], threading.Lock())
            _CACHE[key] = entry
    return entry


def _state_names(kind: str) -> tuple[str, ...]:
    return (build_rigid() if kind == "rigid" else build_elastic()).state_names


def compiled_integrator(key: StructureKey) -> tuple[TaylorSystem, Any]:
    """The translated system of ``key`` and a copy of its cached integrator (compiled on first use).

    Parameters
    ----------
    key : StructureKey

    Returns
    -------
    system : TaylorSystem
    integrator : heyoka.taylor_adaptive
        A copy (no recompilation): set its ``time``, ``state`` and ``pars`` (``system.pars(u, p)``)
        and propagate it freely.
    """
    entry = _entry(key)
    return entry.system, copy.copy(entry.template)


class _Borrowed:
    """Take an integrator of ``entry`` out of its pool (copy the template when the pool is empty)."""

    def __init__(self, entry: _Entry) -> None:
        self.entry = entry
        self.ta: Any = None

    def __enter__(self) -> Any:
        with self.entry.lock:
            self.ta = self.entry.pool.pop() if self.entry.pool else None
        if self.ta is None:
            self.ta = copy.copy(self.entry.template)
        return self.ta

    def __exit__(self, *exc: object) -> None:
        with self.entry.lock:
            self.entry.pool.append(self.ta)

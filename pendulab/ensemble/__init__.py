"""Ensembles: many runs of one model at once (heyoka SIMD batches, threads or Dask).

:func:`ensemble` integrates n runs, each with its own initial state and parameters, with
per-run events (:class:`Event`, built-in ``"flip"``), and returns an :class:`EnsembleResult`.
heyoka is the optional extra ``pendulab[taylor]``; Dask is ``pendulab[dask]``.
"""

from .engine import ensemble
from .events import FLIP, Event
from .result import EnsembleResult

__all__ = ["ensemble", "Event", "EnsembleResult", "FLIP"]

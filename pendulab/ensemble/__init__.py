"""Ensembles: many runs of one model at once (heyoka SIMD batches, threads or Dask).

:func:`ensemble` integrates n runs, each with its own initial state and parameters, with
per-run events (:class:`Event`, built-in ``"flip"``), and returns an :class:`EnsembleResult`;
:func:`map_runs` runs any per-item function on forked worker processes (the scorecard's runs).
heyoka is the optional extra ``pendulab[taylor]``; Dask is ``pendulab[dask]``.
"""

from .engine import ensemble
from .events import FLIP, Event
from .pool import map_runs
from .result import EnsembleResult

__all__ = ["ensemble", "Event", "EnsembleResult", "FLIP", "map_runs"]

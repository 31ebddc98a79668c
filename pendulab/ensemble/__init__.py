"""Ensembles: many runs of one model at once (heyoka SIMD batches, threads or Dask).

:func:`ensemble` integrates n runs, each with its own initial state and parameters, with
per-run events (:class:`Event`, built-in ``"flip"``), and returns an :class:`EnsembleResult`;
:func:`map_runs` runs any per-item function on forked worker processes (the scorecard's runs).
heyoka is the optional extra ``pendulab[taylor]``; Dask is ``pendulab[dask]``.
"""

from __future__ import annotations

from .. import _lazy
from .events import FLIP, Event
from .pool import map_runs
from .result import EnsembleResult

# The engine imports the integrators (SciPy, CasADi): loaded when ensemble() is first asked for.
_lazy.install(__name__, {"ensemble": ".engine"})

__all__ = ["ensemble", "Event", "EnsembleResult", "FLIP", "map_runs"]

"""Deprecated module, kept for one release: use :mod:`pendulab.control.tracking` (the one TVLQR design)
and :class:`pendulab.control.tracking.TVLQRTracker`."""

from __future__ import annotations

import importlib
import warnings
from typing import Any

_MOVED = {
    "TVLQRTracker": "tracking",
    "tvlqr_tracker": "tracking",
    "resample_reference": "tracking",
    "swingup_reference": "tracking",
    "load_reference_csv": "tracking",
}


def __getattr__(name: str) -> Any:
    if name not in _MOVED:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module = _MOVED[name]
    warnings.warn(
        f"pendulab.control.tracking_sampled.{name} is deprecated; use pendulab.control.{module}.{name}",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(importlib.import_module(f"pendulab.control.{module}"), name)

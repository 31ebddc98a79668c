"""Argument checks shared across the package (one wording for every positive-number error)."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["positive_float"]


def positive_float(name: str, value: Any, unit: str = "") -> float:
    """``value`` as a positive finite float, else ``ValueError`` naming ``name``, the value and the expectation.

    Parameters
    ----------
    name : str
        Argument name used in the message.
    value : Any
        Received value.
    unit : str
        Optional unit appended to the expectation (e.g. ``"[s]"``).
    """
    suffix = f" {unit}" if unit else ""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a positive number{suffix}, got {value!r}") from exc
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a positive finite number{suffix}, got {value!r}")
    return v

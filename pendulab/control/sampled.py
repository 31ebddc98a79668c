"""Deprecated module, kept for one release: its names now live in :mod:`pendulab.control.feedback`,
:mod:`pendulab.control.controllers` and :mod:`pendulab.control.tracking`.

``sampled.lqr_balance`` is :func:`pendulab.control.feedback.balance_controller`
(the LQR design itself is :func:`pendulab.control.lqr.lqr_balance`).
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

_MOVED = {
    "lqr_balance": ("feedback", "balance_controller"),
    "CONTROLLERS": ("controllers", "CONTROLLERS"),
    "make_controller": ("controllers", "make_controller"),
    **{
        n: ("feedback", n)
        for n in (
            "SampledController",
            "LinearStateFeedback",
            "EnergySwingUp",
            "energy_swingup",
            "upright_state",
            "closed_loop_spectral_radius",
            "as_feedback",
            "full_input",
        )
    },
}


def __getattr__(name: str) -> Any:
    if name not in _MOVED:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, new = _MOVED[name]
    warnings.warn(
        f"pendulab.control.sampled.{name} is deprecated; use pendulab.control.{module}.{new}", DeprecationWarning, stacklevel=2
    )
    return getattr(importlib.import_module(f"pendulab.control.{module}"), new)

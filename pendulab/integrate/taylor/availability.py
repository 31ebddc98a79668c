"""heyoka is optional: its import, and the error that names the extra when it is missing."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from typing import Any

from ..._checks import MissingExtraError

__all__ = [
    "EXTRA_HINT",
    "MIN_TOL",
    "TaylorUnavailableError",
    "check_tolerance_floor",
    "heyoka_module",
    "taylor_unavailable_reason",
]

#: How to install heyoka with pendulab (the optional dependency group "taylor").
EXTRA_HINT = 'pip install "pendulab[taylor]"'


class TaylorUnavailableError(MissingExtraError):
    """heyoka is not importable; the message names the method and the extra to install (the CLI prints it as one line)."""


def heyoka_module() -> Any:
    """The heyoka module (imported on the first call).

    Returns
    -------
    module
        ``heyoka``.

    Raises
    ------
    TaylorUnavailableError
        heyoka is not importable; the message names ``method='taylor'`` and the extra to install.
    """
    module = sys.modules.get("heyoka")
    if module is not None:  # imported already (every run after the first): skip the import machinery
        return module
    try:
        return importlib.import_module("heyoka")
    except ImportError as exc:
        raise TaylorUnavailableError(
            f"method 'taylor' needs the heyoka package, which is not importable; "
            f"install it with: {EXTRA_HINT} (heyoka's wheels are Linux-only: x86-64, aarch64)"
        ) from exc


def taylor_unavailable_reason() -> str | None:
    """Why ``method="taylor"`` cannot run here, without importing heyoka.

    Returns
    -------
    str or None
        None when heyoka is installed, else a one-line reason naming the extra.
    """
    if importlib.util.find_spec("heyoka") is None:
        return f"heyoka is not installed ({EXTRA_HINT})"
    return None


#: Smallest heyoka tolerance accepted (double-precision epsilon): a smaller one adds no digit in double
#: precision but raises the Taylor order, and with it a JIT compilation that cannot be interrupted
#: (measured: tol 1e-60 compiles in 12 s, 1e-100 in 86 s).
MIN_TOL = sys.float_info.epsilon


def check_tolerance_floor(name: str, value: float) -> float:
    """``value`` when it is at least :data:`MIN_TOL`, else ``ValueError`` naming ``name`` and the floor.

    Parameters
    ----------
    name : str
        Argument name used in the message.
    value : float
        A positive tolerance (already checked by the shared layer).

    Returns
    -------
    float
        The tolerance.

    Raises
    ------
    ValueError
        ``value`` is below :data:`MIN_TOL`.
    """
    if value < MIN_TOL:
        raise ValueError(
            f"{name} must be at least {MIN_TOL:.3g} (double-precision epsilon) for heyoka, got {value!r}: "
            "a smaller tolerance adds no digit and only lengthens the Taylor order and its compilation"
        )
    return value

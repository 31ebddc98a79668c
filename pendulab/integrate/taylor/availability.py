"""heyoka is optional: its import, and the error that names the extra when it is missing."""

from __future__ import annotations

import importlib
import importlib.util
from typing import Any

from ..._checks import MissingExtraError

__all__ = ["EXTRA_HINT", "TaylorUnavailableError", "heyoka_module", "taylor_unavailable_reason"]

#: How to install heyoka with pendulab (the optional dependency group "taylor").
EXTRA_HINT = 'pip install "pendulab[taylor]"'


class TaylorUnavailableError(MissingExtraError):
    """heyoka is not importable; the message names the method and the extra to install (the CLI prints it as one line)."""


def heyoka_module() -> Any:
    """The heyoka module (imported on each call; cheap once imported).

    Returns
    -------
    module
        ``heyoka``.

    Raises
    ------
    TaylorUnavailableError
        heyoka is not importable; the message names ``method='taylor'`` and the extra to install.
    """
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

"""The console entry point (``pendulab``, ``python -m pendulab``): a Ctrl-C during start-up imports included.

The console script imports only this module (and the package's light ``__init__``) before :func:`run`
guards the rest: ``pendulab.cli`` and the command modules it loads (NumPy, CasADi) are imported inside,
so an interrupt landing there ends as ``pendulab: interrupted``, exit 130, never a traceback.
"""

from __future__ import annotations

import sys
from typing import NoReturn

__all__ = ["run"]


def run() -> NoReturn:
    """Import the CLI and run it; exit 130 with one line on a Ctrl-C while importing."""
    try:
        from .cli import run as cli_run
    except KeyboardInterrupt:
        print("pendulab: interrupted", file=sys.stderr)
        raise SystemExit(130) from None
    cli_run()

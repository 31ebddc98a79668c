"""The console entry point (``pendulab``, ``python -m pendulab``): a Ctrl-C during start-up imports included.

The console script imports only this module (and the package's light ``__init__``) before :func:`run`
guards the rest: ``pendulab.cli`` and the command modules it loads (NumPy, CasADi) are imported inside,
so an interrupt landing there ends as ``pendulab: interrupted``, exit 130, never a traceback.

The command's process runs no user code and pendulab never uses SymPy, so SymPy is marked absent there
(:data:`NOT_IMPORTED`): heyoka imports it when it is installed, for a SymPy bridge no command uses, and that
cost 0.33-0.5 s of every command that integrates with Taylor series (``benchmarks/results/ensemble.md``).
A library user's process is never touched.
"""

from __future__ import annotations

import sys
from typing import NoReturn

__all__ = ["run", "NOT_IMPORTED"]

#: Modules a command's process marks absent before anything imports them (see the module docstring).
NOT_IMPORTED = ("sympy",)


def run() -> NoReturn:
    """Import the CLI and run it; exit 130 with one line on a Ctrl-C while importing."""
    for name in NOT_IMPORTED:
        sys.modules.setdefault(name, None)  # None: "import name" raises ModuleNotFoundError, as if not installed
    try:
        from .cli import run as cli_run
    except KeyboardInterrupt:
        print("pendulab: interrupted", file=sys.stderr)
        raise SystemExit(130) from None
    cli_run()

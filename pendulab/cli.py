"""The ``pendulab`` command: a thin dispatcher over ``pendulab.commands.*``.

Each command lives in its own module exposing ``register(subparsers)``, which
adds a sub-parser whose ``func(args) -> int`` does the work. Library errors
become a one-line message on stderr and a non-zero exit status.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from .commands import CLIError

__all__ = ["main", "COMMAND_MODULES", "CLIError"]

#: Modules under ``pendulab.commands`` that each register one top-level command.
COMMAND_MODULES: tuple[str, ...] = ("simulate", "demo", "modes", "fmu", "cosim", "bench", "scene", "swingup", "ensemble")


def build_parser() -> argparse.ArgumentParser:
    """Build the ``pendulab`` parser with one sub-command per :data:`COMMAND_MODULES` entry.

    Returns
    -------
    argparse.ArgumentParser
        Parser whose parsed namespace carries ``command`` and ``func``.
    """
    parser = argparse.ArgumentParser(
        prog="pendulab",
        description="Rigid and elastic double pendulum: simulation, modes, FMU export, co-simulation, control.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"pendulab.commands.{name}").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Errors raised by a command (``ValueError``, ``KeyError``, ``TypeError``,
    ``FileNotFoundError``, ``RuntimeError``, ``OSError``) are printed as one
    line on stderr instead of a traceback.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success (or the command's own status), 2 after an error, 130 on
        ``KeyboardInterrupt``.

    Raises
    ------
    SystemExit
        From argparse, on invalid arguments (status 2) or ``--help`` (status 0).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("pendulab: interrupted", file=sys.stderr)
        return 130
    except (ValueError, KeyError, TypeError, FileNotFoundError, RuntimeError, OSError) as exc:
        message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f"pendulab {args.command}: error: {message}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

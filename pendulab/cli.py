"""The ``pendulab`` command: a thin dispatcher over ``pendulab.commands.*``.

Each command lives in its own module exposing ``register(subparsers)``, which
adds a sub-parser whose ``func(args) -> int`` does the work. Library errors
become a one-line message on stderr and a non-zero exit status.

Ctrl-C always stops a command: SIGINT raises ``KeyboardInterrupt`` as usual,
and because a native solver may catch it (CasADi turns it into a warning or a
``RuntimeError``, IPOPT or an integrator then carries on), the interrupt is
*sticky*: until it reaches :func:`main`, it is raised again every
:data:`_REINTERRUPT_S` seconds, and any error that ends a command after an
interrupt counts as the interrupt ("interrupted", exit status 130).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Iterator, Sequence
from typing import NoReturn

from ._checks import MissingExtraError, is_interrupt
from .commands import CLIError

__all__ = ["main", "run", "COMMAND_MODULES", "CLIError"]

#: Modules under ``pendulab.commands`` that each register one top-level command.
COMMAND_MODULES: tuple[str, ...] = (
    "simulate", "demo", "modes", "fmu", "cosim", "bench", "scene", "swingup", "ensemble", "score", "ssp", "identify",
)  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    """Build the ``pendulab`` parser with one sub-command per :data:`COMMAND_MODULES` entry.

    Returns
    -------
    argparse.ArgumentParser
        Parser whose parsed namespace carries ``command`` and ``func``.
    """
    from .commands import DOCS_URL

    parser = argparse.ArgumentParser(
        prog="pendulab",
        description="Rigid and elastic double pendulum: simulation, modes, FMU export, co-simulation, control.",
        epilog=f"Documentation: {DOCS_URL} (every command has --help).",
    )
    from ._version import __version__

    parser.add_argument("--version", action="version", version=f"pendulab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"pendulab.commands.{name}").register(sub)
    from .commands.options import declare_options

    declare_options(parser)
    _plain_text(parser)
    return parser


def _plain_text(parser: argparse.ArgumentParser) -> None:
    """Drop reST literal marks (````x````) from every description and help of the tree: ``--help`` is plain text.

    Command modules reuse their docstrings as descriptions; one pass here keeps every present and
    future command's help readable (tests/test_cli_json.py walks the tree).
    """

    def plain(text: str | None) -> str | None:
        return None if text is None else text.replace("``", "")

    parser.description, parser.epilog = plain(parser.description), plain(parser.epilog)
    for action in parser._actions:
        action.help = plain(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                choice.help = plain(choice.help)
            for child in action.choices.values():
                _plain_text(child)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Errors raised by a command (``ValueError``, ``KeyError``, ``TypeError``,
    ``FileNotFoundError``, ``RuntimeError``, ``OSError``, and a missing optional
    extra, :class:`pendulab._checks.MissingExtraError`) are printed as one
    line on stderr instead of a traceback.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; default ``sys.argv[1:]``.

    Returns
    -------
    int
        0 on success (or the command's own status), 2 after an error, 130 on
        ``KeyboardInterrupt`` (Ctrl-C), also when a native solver turned it
        into an error or swallowed it.

    Raises
    ------
    SystemExit
        From argparse, on invalid arguments (status 2) or ``--help`` (status 0).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    from .commands.options import check_options

    try:
        check_options(args)
    except ValueError as exc:  # InputError, BudgetError: one line, before any work
        print(f"pendulab {args.command}: error: {exc}", file=sys.stderr)
        return 2
    from .commands.outputs import forget_output_directories, mark_interrupted

    command = list(sys.argv[1:] if argv is None else argv)
    args.argv = command  # errors name the option spelling the user typed (commands._common.typed_flag)
    forget_output_directories()

    def _interrupted() -> int:
        status = _interrupted_status()
        for marker in mark_interrupted(command):
            print(f"pendulab: what the run finished is listed in {marker}", file=sys.stderr)
        return status

    with _sticky_interrupt() as guard, _journal_notices(args.command):
        try:
            try:
                status = int(args.func(args) or 0)
            finally:
                guard.stop()
            # An interrupt swallowed by a native solver still ends the command as interrupted.
            return _interrupted() if guard.interrupted else status
        except KeyboardInterrupt:
            return _interrupted()
        except (ValueError, KeyError, TypeError, FileNotFoundError, RuntimeError, OSError, MissingExtraError) as exc:
            if guard.interrupted or is_interrupt(exc):
                # A native layer (CasADi, IPOPT, SUNDIALS) turned the interrupt into an error.
                return _interrupted()
            message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            print(f"pendulab {args.command}: error: {message}", file=sys.stderr)
            return 2
        except Exception:
            if guard.interrupted:
                return _interrupted()
            raise


@contextlib.contextmanager
def _journal_notices(command: str) -> Iterator[None]:
    """Show every :class:`~pendulab._journal.JournalWarning` (a journal not trusted on resume) as one stderr line."""
    from ._journal import JournalWarning

    show = warnings.showwarning

    def one_line(message: Warning | str, category: type[Warning], *args: object, **kwargs: object) -> None:
        if issubclass(category, JournalWarning):
            print(f"pendulab {command}: {message}", file=sys.stderr)
        else:
            show(message, category, *args, **kwargs)  # type: ignore[arg-type]

    with warnings.catch_warnings():
        # Each notice names its file and records: every one is shown, not only the first per source line.
        warnings.simplefilter("always", JournalWarning)
        warnings.showwarning = one_line
        yield


#: Seconds between repeated interrupts while a SIGINT has not yet reached :func:`main`.
_REINTERRUPT_S = 0.5


def _interrupted_status() -> int:
    print("pendulab: interrupted", file=sys.stderr)
    return 130


class _InterruptGuard:
    """SIGINT handler of a running command: raise ``KeyboardInterrupt``, and again until it arrives."""

    def __init__(self) -> None:
        self.interrupted = False
        self._done = threading.Event()
        self._thread: threading.Thread | None = None

    def handler(self, signum: int, frame: object) -> None:
        if self._done.is_set():
            return
        self.interrupted = True
        if self._thread is None:
            self._thread = threading.Thread(target=self._repeat, name="pendulab-sigint", daemon=True)
            self._thread.start()
        raise KeyboardInterrupt

    def _repeat(self) -> None:
        # A native solver may have swallowed the first KeyboardInterrupt: interrupt again until
        # main() has seen one (stop() ends this), so Ctrl-C always ends the command.
        while not self._done.wait(_REINTERRUPT_S):
            signal.raise_signal(signal.SIGINT)

    def stop(self) -> None:
        self._done.set()


@contextlib.contextmanager
def _sticky_interrupt() -> Iterator[_InterruptGuard]:
    """Install :class:`_InterruptGuard` for SIGINT (main thread only), restore the old handler after."""
    guard = _InterruptGuard()
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        yield guard
        return
    previous = signal.signal(signal.SIGINT, guard.handler)
    try:
        yield guard
    finally:
        guard.stop()
        signal.signal(signal.SIGINT, previous)


def _drop_interrupt_unraisable(unraisable: sys.UnraisableHookArgs) -> None:
    """``sys.unraisablehook`` that drops a ``KeyboardInterrupt`` raised inside a finalizer (e.g. a progress bar's
    ``__del__`` hit by the guard's repeated SIGINT): the command is ending as interrupted anyway."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        return
    sys.__unraisablehook__(unraisable)


def run() -> NoReturn:
    """Console entry point (``pendulab``, ``python -m pendulab``): :func:`main`, then exit with its status.

    An interrupted command (status 130) leaves at once through ``os._exit``: everything it wrote is complete
    (atomic writes) and its workers are stopped, and the interpreter's teardown (freeing cached solvers and
    JIT-compiled modules) took 0.5-2.5 s, which a user who pressed Ctrl-C should not wait for.
    """
    sys.unraisablehook = _drop_interrupt_unraisable
    try:
        status = main()
    except KeyboardInterrupt:
        # Before main() guards the command: building the parser imports every command module (NumPy,
        # CasADi), which a Ctrl-C at start-up lands in.
        status = _interrupted_status()
    # The command has ended and its outputs are written: a Ctrl-C now stops nothing, and landing in the
    # interpreter's teardown (worker pools, atexit) it killed the process by SIGINT, exit -2, after a
    # complete run (measured by benchmarks/bench_interrupts.py).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if status == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(status)


if __name__ == "__main__":
    run()

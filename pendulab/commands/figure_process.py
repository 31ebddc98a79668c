"""A forked process that imports matplotlib while a command computes, then draws the figures it is sent.

Importing matplotlib.pyplot costs ~0.3 s of one core, a sixth of the whole 400 x 400 flip-map command
(2.3 s). The command is single-threaded while it starts and sets up its runs, so a second process can
import matplotlib meanwhile on the other core; the figures are drawn there once the results exist. A
thread would not do: an import holds the GIL. Where fork is unavailable, or the process fails, the
figure is drawn in the command's own process (the same function, so the same figure).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable
from typing import Any

from ..ensemble.pool import ignore_sigint, sigint_blocked

__all__ = ["FigureProcess"]


def _serve(conn: Any) -> None:
    """Child: import matplotlib, then draw ``fn(*args)`` for every message until None."""
    ignore_sigint()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    while (message := conn.recv()) is not None:
        fn, args = message
        try:
            plt.close(fn(*args))
        except Exception as exc:  # reported to the parent, which draws the figure itself
            conn.send(f"{type(exc).__name__}: {exc}")
        else:
            conn.send(None)


class FigureProcess:
    """Draw figures in a forked process that imported matplotlib in advance.

    Use as a context manager around the command's work: :meth:`start` a figure, do other work, :meth:`finish`.
    """

    def __init__(self) -> None:
        self._proc: Any = None
        self._conn: Any = None
        self._pending: list[tuple[Callable[..., Any], tuple]] = []
        if "fork" not in multiprocessing.get_all_start_methods():
            return
        ctx = multiprocessing.get_context("fork")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_serve, args=(child,), daemon=True, name="pendulab-figures")
        with sigint_blocked():
            self._proc.start()
        child.close()

    def __enter__(self) -> FigureProcess:
        return self

    def __exit__(self, exc_type: object, *_: object) -> None:
        self.close(at_once=exc_type is not None)

    def start(self, fn: Callable[..., Any], *args: Any) -> None:
        """Have ``fn(*args)`` drawn (a module-level function that draws, saves and returns a figure).

        Returns at once when the figure process draws it; :meth:`finish` waits for it. Without a figure
        process the figure is drawn here and now.
        """
        if self._proc is not None:
            try:
                self._conn.send((fn, args))
                self._pending.append((fn, args))
                return
            except OSError:
                self.close(at_once=True)
        self._draw_here(fn, args)

    def finish(self) -> None:
        """Wait until every started figure is written; the ones the figure process failed are drawn here."""
        pending, self._pending = self._pending, []
        failed = []
        for fn, args in pending:
            try:
                if self._proc is not None and self._conn.recv() is None:
                    continue
            except (EOFError, OSError):
                pass
            failed.append((fn, args))
        if failed:
            self.close(at_once=True)
        for fn, args in failed:
            self._draw_here(fn, args)

    @staticmethod
    def _draw_here(fn: Callable[..., Any], args: tuple) -> None:
        import matplotlib.pyplot as plt

        plt.close(fn(*args))

    def close(self, *, at_once: bool = False) -> None:
        """End the figure process; ``at_once`` (an error or Ctrl-C) terminates it without waiting."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if not at_once:
            try:
                self._conn.send(None)
            except OSError:
                at_once = True
        proc.join(timeout=0.0 if at_once else 5.0)
        if proc.is_alive():
            proc.terminate()
            proc.join()
        self._conn.close()

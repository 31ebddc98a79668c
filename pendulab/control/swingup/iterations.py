"""IPOPT iteration hooks: progress reports, wall-time budgets and prompt interrupts of every swing-up NLP.

Each compiled NLP (:mod:`.transcription`) carries one CasADi ``iteration_callback``
(:class:`IterationCallback`), called by IPOPT after every iteration. It runs the
hooks installed with :func:`iteration_hook` (innermost last); a hook returning
True asks IPOPT to stop (status ``User_Requested_Stop``, a failed solve).

The NLPs are cached across calls, so the callback is part of the cached solver
and the hooks are module state, installed and removed by the context manager.
The callback is also a point where Python runs during a long IPOPT solve, so a
Ctrl-C there raises at once (CasADi reports it as a failed solve naming
``KeyboardInterrupt``, which :func:`pendulab.control.swingup.solve.solve_transcription` re-raises).
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import casadi as ca

__all__ = [
    "IterationCallback", "iteration_hook", "wall_time_budget", "build_hook", "notify_build", "observe",
    "SigintWatch", "watch_sigint",
]  # fmt: skip

#: Installed hooks, outermost first. Each is called with no argument after every IPOPT iteration.
_HOOKS: list[Callable[[], bool | None]] = []
#: Installed build listeners: called with a one-line description before an NLP is built (not on a cache hit).
_BUILD_HOOKS: list[Callable[[str], None]] = []


def notify_build(description: str) -> None:
    """Tell the build listeners that an NLP is about to be built (a single CasADi call of seconds to a minute).

    Parameters
    ----------
    description : str
        One line, e.g. ``"radau N=100 degree 3, elastic model"``.
    """
    for hook in tuple(_BUILD_HOOKS):
        hook(description)


@contextlib.contextmanager
def build_hook(hook: Callable[[str], None]) -> Iterator[None]:
    """Call ``hook(description)`` before each swing-up NLP built inside the block (progress of the NLP build).

    Parameters
    ----------
    hook : callable
        ``hook(description) -> None``.

    Yields
    ------
    None

    Raises
    ------
    TypeError
        ``hook`` is not callable.
    """
    with _registered(_BUILD_HOOKS, hook):
        yield


class IterationCallback(ca.Callback):
    """The ``iteration_callback`` of one NLP: runs the installed hooks, returns 1 (stop) if one asks for it.

    Parameters
    ----------
    name : str
        Function name.
    nx, ng, np_ : int
        Sizes of the NLP's decision vector, constraints and parameters.
    """

    def __init__(self, name: str, nx: int, ng: int, np_: int) -> None:
        ca.Callback.__init__(self)
        self._sizes = {"x": nx, "lam_x": nx, "g": ng, "lam_g": ng, "lam_p": np_, "f": 1}
        self.construct(name, {})

    def get_n_in(self) -> int:
        """Number of inputs: the NLP solver's outputs (CasADi ``Callback`` protocol).

        Returns
        -------
        int
            ``casadi.nlpsol_n_out()``.
        """
        return ca.nlpsol_n_out()

    def get_n_out(self) -> int:
        """Number of outputs (one: the stop flag).

        Returns
        -------
        int
            1.
        """
        return 1

    def get_name_in(self, i: int) -> str:
        """Name of input ``i`` (the NLP solver's output of that index).

        Parameters
        ----------
        i : int
            Input index.

        Returns
        -------
        str
            ``casadi.nlpsol_out(i)``.
        """
        return ca.nlpsol_out(i)

    def get_name_out(self, i: int) -> str:
        """Name of the output.

        Parameters
        ----------
        i : int
            Output index (0).

        Returns
        -------
        str
            ``"ret"``.
        """
        return "ret"

    def get_sparsity_in(self, i: int) -> Any:
        """Dense vectors of the NLP's sizes (empty for the inputs IPOPT does not pass).

        Parameters
        ----------
        i : int
            Input index.

        Returns
        -------
        casadi.Sparsity
            Dense column of the input's size.
        """
        n = self._sizes.get(ca.nlpsol_out(i))
        return ca.Sparsity(0, 0) if n is None else ca.Sparsity.dense(n)

    def eval(self, arg: Any) -> list[int]:
        """Run the installed hooks after an IPOPT iteration.

        Parameters
        ----------
        arg : list
            The current iterate (x, f, g, multipliers); not used by the hooks.

        Returns
        -------
        list of int
            ``[1]`` when a hook asks to stop, else ``[0]``.
        """
        stop = False
        for hook in tuple(_HOOKS):
            stop = bool(hook()) or stop
        return [1 if stop else 0]


@contextlib.contextmanager
def iteration_hook(hook: Callable[[], bool | None]) -> Iterator[None]:
    """Run ``hook()`` after every IPOPT iteration of the swing-up NLPs solved inside the block.

    Parameters
    ----------
    hook : callable
        ``hook() -> bool | None``; True stops the running solve (a failed solve,
        status ``User_Requested_Stop``). Used for progress bars and budgets.

    Yields
    ------
    None

    Raises
    ------
    TypeError
        ``hook`` is not callable.
    """
    with _registered(_HOOKS, hook):
        yield


class _Budget:
    def __init__(self, seconds: float) -> None:
        self.deadline = time.perf_counter() + seconds
        self.exceeded = False

    def __call__(self) -> bool:
        if time.perf_counter() > self.deadline:
            self.exceeded = True
        return self.exceeded


@contextlib.contextmanager
def wall_time_budget(seconds: float | None) -> Iterator[Any]:
    """Stop every IPOPT solve inside the block once ``seconds`` of wall time have passed (None: no budget).

    Parameters
    ----------
    seconds : float or None
        Budget [s] from entering the block.

    Yields
    ------
    object
        Has ``exceeded`` (bool): whether the budget stopped a solve.
    """
    if seconds is None:
        yield _Budget(float("inf"))
        return
    budget = _Budget(seconds)
    with iteration_hook(budget):
        yield budget


@contextlib.contextmanager
def observe(on_iteration: Callable[[], Any], on_build: Callable[[str], Any]) -> Iterator[None]:
    """Progress of the swing-up NLPs inside the block: ``on_build(description)``, then ``on_iteration()`` per iteration.

    Parameters
    ----------
    on_iteration : callable
        Called after each IPOPT iteration (its return value is ignored: it never stops a solve).
    on_build : callable
        Called with a one-line description before an NLP is built.

    Yields
    ------
    None
    """

    def tick() -> bool:
        on_iteration()
        return False

    with iteration_hook(tick), build_hook(on_build):
        yield


class SigintWatch:
    """Whether a SIGINT arrived while a solve ran (set by :func:`watch_sigint`)."""

    def __init__(self) -> None:
        self.hit = False

    def handler(self, previous: Any) -> Any:
        """A SIGINT handler that records the signal and raises ``KeyboardInterrupt`` (through ``previous`` if callable).

        Parameters
        ----------
        previous : callable or signal constant
            The handler in force before the solve.

        Returns
        -------
        callable
            The handler to install for the solve.
        """

        def on_sigint(signum: int, frame: Any) -> None:
            if not callable(previous):  # SIG_DFL: would end the process; interrupt instead
                self.hit = True
                raise KeyboardInterrupt
            try:
                previous(signum, frame)  # the caller's handler (Python's default raises KeyboardInterrupt)
            except KeyboardInterrupt:
                self.hit = True
                raise

        return on_sigint

    def check(self, message: str = "") -> None:
        """Raise ``KeyboardInterrupt`` when a SIGINT arrived or CasADi's message names one.

        IPOPT's own status does not tell: CasADi reports an interrupted run as
        ``NonIpopt_Exception_Thrown``, like any other exception in a callback.

        Parameters
        ----------
        message : str
            CasADi's error message of the failed solve ("" when none).

        Raises
        ------
        KeyboardInterrupt
            A SIGINT arrived during the solve, or the message names one.
        """
        if self.hit or "KeyboardInterrupt" in message:
            raise KeyboardInterrupt


@contextlib.contextmanager
def watch_sigint() -> Iterator[SigintWatch]:
    """Watch SIGINT while a solve runs (main thread only: signal handlers cannot be installed elsewhere).

    Yields
    ------
    SigintWatch
        Its ``hit`` is set when a SIGINT arrived; ``check(message)`` raises ``KeyboardInterrupt`` then.
    """
    # Signal handlers can only be installed from the main thread; elsewhere only CasADi's message tells.
    flag = SigintWatch()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous in (signal.SIG_IGN, None):
        yield flag
        return
    signal.signal(signal.SIGINT, flag.handler(previous))
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _registered(hooks: list[Callable[..., Any]], hook: Callable[..., Any]) -> Iterator[None]:
    """Keep ``hook`` in ``hooks`` for the block (``TypeError`` when it is not callable)."""
    if not callable(hook):
        raise TypeError(f"hook must be callable, got {type(hook).__name__}")
    hooks.append(hook)
    try:
        yield
    finally:
        hooks.remove(hook)

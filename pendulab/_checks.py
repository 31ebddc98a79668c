"""Argument checks shared across the package (one wording for each kind of error)."""

from __future__ import annotations

import math
import os
import sys
from contextvars import ContextVar
from typing import Any, NamedTuple

__all__ = [
    "positive_float",
    "relative_tolerance",
    "bounded_int",
    "check_model",
    "check_spring_lengths",
    "is_interrupt",
    "MissingExtraError",
    "BudgetError",
    "BUDGETS",
    "check_budget",
    "require_extra",
    "ENTRY_DEPTH",
]

#: How many public entry points (functions and classes decorated with :func:`pendulab._inputs.checked`) are
#: running in this context. The outermost one (depth 1) checks its inputs where they enter; an entry point or a
#: model check reached from inside another (depth 2 and more) trusts what it receives. A thread starts at 0, so
#: work handed to a thread pool is checked again (harmless); a forked worker inherits its parent's depth.
ENTRY_DEPTH: ContextVar[int] = ContextVar("pendulab_entry_depth", default=0)


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


def check_model(model: Any, name: str = "model") -> Any:
    """``model`` itself when it is a pendulab ``Model``, else ``TypeError`` naming ``name`` and the type received.

    The one check of every public function that takes a model (analysis,
    linearization, python-control bridge, LQR, simulation), so that a wrong
    argument (a kind name such as ``"rigid"``, ``None``, a parameter object)
    fails with ``TypeError("model must be a pendulab Model, got str")`` instead
    of an ``AttributeError`` deep inside. Reached from inside an entry point
    (:data:`ENTRY_DEPTH` of 2 or more) it trusts the model, checked where it entered.

    Parameters
    ----------
    model : Any
        Received value.
    name : str
        Argument name used in the message.

    Returns
    -------
    Model
        The same object.

    Raises
    ------
    TypeError
        ``model`` is not a :class:`pendulab.model.model.Model`.
    """
    if ENTRY_DEPTH.get() >= 2:  # reached from inside an entry point, which checked it where it entered
        return model
    if not _is_model(model):
        hint = ""
        if isinstance(model, str):
            hint = f"; build one with pendulab.rigid() or pendulab.elastic() (or make_model({model!r}))"
        raise TypeError(f"{name} must be a pendulab Model, got {type(model).__name__}{hint}")
    return model


#: Where the Model class lives; _checks sits in the same layer as model/ and may not import it.
_MODEL_CLASS = ("pendulab.model.model", "Model")


#: Types found to be Model (sub)classes: the walk of the MRO is done once per type, not on every simulate call.
_MODEL_TYPES: set[type] = set()


def _is_model(obj: Any) -> bool:
    """True for an instance of ``pendulab.model.model.Model`` (or a subclass), checked without importing it."""
    kind = type(obj)
    if kind in _MODEL_TYPES:
        return True
    if any((c.__module__, c.__qualname__) == _MODEL_CLASS for c in kind.__mro__):
        _MODEL_TYPES.add(kind)
        return True
    return False


def is_interrupt(exc: BaseException) -> bool:
    """True when ``exc``, or an exception in its cause/context chain, is a Ctrl-C in disguise.

    CasADi, IPOPT and fmpy turn a ``KeyboardInterrupt`` raised inside their callbacks into their own
    errors; loops that keep going after a failed point must not keep going after an interrupt.

    Parameters
    ----------
    exc : BaseException
        The exception caught.

    Returns
    -------
    bool
        ``KeyboardInterrupt`` in the chain, or a message naming it.
    """
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        if isinstance(e, KeyboardInterrupt) or "KeyboardInterrupt" in str(e):
            return True
        e = e.__cause__ or e.__context__
    return False


def relative_tolerance(name: str, value: Any) -> float:
    """``value`` as a relative tolerance in the open interval (0, 1), else ``ValueError`` naming ``name``.

    A relative tolerance of 1 or more asks for no correct digit at all: every error-controlled
    integrator then takes steps as large as its stability allows and returns a silently wrong
    answer. Every public entry point with an ``rtol`` (or ``tolerance``) checks it here.

    Parameters
    ----------
    name : str
        Argument name used in the message.
    value : Any
        Received value.

    Returns
    -------
    float
        The tolerance.

    Raises
    ------
    ValueError
        Not a number, not finite, or outside (0, 1).
    """
    v = positive_float(name, value)
    if v >= 1.0:
        raise ValueError(f"{name} must be a relative tolerance in (0, 1), got {value!r}: a value >= 1 asks for no correct digit")
    return v


def bounded_int(name: str, value: Any, *, low: int = 1, high: int, why: str) -> int:
    """``value`` as an integer in ``[low, high]``, else ``ValueError`` naming ``name``, the limit and ``why``.

    Sizes a user passes (grid points, horizons, run counts, mesh intervals) are bounded so that a
    typo cannot allocate gigabytes or run for days; ``why`` tells the user what the limit protects.

    Parameters
    ----------
    name : str
        Argument name used in the message.
    value : Any
        Received value (an ``int`` or an integral float such as ``1e3``).
    low, high : int
        Inclusive bounds.
    why : str
        Reason for the upper bound, e.g. ``"each horizon step is a block of the NLP"``.

    Returns
    -------
    int
        The value.

    Raises
    ------
    ValueError
        Not an integer, or outside the bounds.
    """
    if isinstance(value, bool):
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    try:
        as_float = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}") from exc
    if not math.isfinite(as_float) or as_float != int(as_float):
        raise ValueError(f"{name} must be an integer in [{low}, {high}], got {value!r}")
    v = int(as_float)
    if v < low:
        raise ValueError(f"{name} must be an integer >= {low}, got {value!r}")
    if v > high:
        raise ValueError(f"{name} must be at most {high} ({why}), got {value!r}")
    return v


def check_spring_lengths(kind: str, x: Any, name: str = "x0") -> None:
    """Raise ``ValueError`` when an elastic state (or batch of states) has a spring length <= 0.

    The one physical-state check shared by :func:`pendulab.simulate`, ensembles, Lyapunov
    exponents and the Gymnasium env: a spring of zero or negative length is not a state of the
    elastic pendulum (the link direction is undefined), whatever the integrator would return.

    Parameters
    ----------
    kind : str
        The model kind (``"rigid"`` or ``"elastic"``); rigid states pass unchanged.
    x : ndarray, shape (8,) or (N, 8)
        State(s), already shape-checked, in the elastic state order (r1, r2 at columns 2, 3) [m].
    name : str
        Argument name used in the message.

    Raises
    ------
    ValueError
        Some r1 or r2 is not > 0; the message names the first offending row.
    """
    if kind != "elastic":
        return
    import numpy as np  # local: keep this module importable without NumPy's start-up cost

    arr = np.asarray(x, dtype=float)
    r = arr[..., 2:4]
    if arr.ndim == 1 and r[0] > 0.0 and r[1] > 0.0:  # one state (every simulate call): no temporary array
        return
    bad = ~(r > 0.0)
    if not bad.any():
        return
    if arr.ndim == 1:
        raise ValueError(f"{name}: spring lengths r1, r2 must be > 0 m, got {r.tolist()}")
    row = int(np.argwhere(bad.any(axis=-1))[0][0])
    raise ValueError(f"{name}[{row}]: spring lengths r1, r2 must be > 0 m, got {r[row].tolist()}")


class BudgetError(ValueError):
    """A request whose size (points, runs, repetitions) is beyond its budget, refused before any work."""


def within_budget(what: str, size: float, budget_name: str, default: int) -> int:
    """Check a resource size against its budget before anything is allocated or run.

    The budget is ``default`` unless the environment variable ``budget_name`` sets another (a
    positive integer): a deliberate large run names it, a typo (``dt = 1e-12``) does not get it.

    Parameters
    ----------
    what : str
        What is counted, for the message (e.g. ``"output points (t_final / dt + 1)"``).
    size : float
        The requested size (may be huge or inf).
    budget_name : str
        Environment variable overriding the budget, named in the message.
    default : int
        The default budget.

    Returns
    -------
    int
        ``size`` as an int.

    Raises
    ------
    BudgetError
        ``size`` beyond the budget (or the variable is not a positive integer).
    """
    budget = budget_limit(budget_name, default)
    if not size <= budget:
        raise BudgetError(
            f"{what}: {size:.4g} is beyond the budget of {budget:.4g}; set the environment variable {budget_name} "
            "to a larger number for a deliberately large run"
        )
    return int(size)


def budget_limit(budget_name: str, default: int) -> int:
    """The budget in force: the environment variable ``budget_name`` (a positive integer) if set, else ``default``.

    Parameters
    ----------
    budget_name : str
        Environment variable overriding the budget.
    default : int
        The default budget.

    Returns
    -------
    int
        The budget.

    Raises
    ------
    BudgetError
        The variable is set but is not a positive integer.
    """
    raw = os.environ.get(budget_name)
    if raw is None:
        return default
    try:
        budget = int(raw)
    except ValueError:
        budget = 0
    if budget < 1:
        raise BudgetError(f"{budget_name} must be a positive integer, got {raw!r}")
    return budget


class Budget(NamedTuple):
    """One resource budget: the variable overriding it, its default, what it counts and what the limit costs."""

    env: str
    default: int
    counts: str
    cost: str


#: The one table of resource budgets (docs/reliability.md lists it): every size a user passes that multiplies
#: into memory or work is checked against one of these before anything is allocated or run. The defaults are
#: generous (a deliberate run is never near them); the environment variable raises (or lowers) a budget.
BUDGETS: dict[str, Budget] = {
    "output_points": Budget(
        "PENDULAB_MAX_OUTPUT_POINTS", 5_000_000, "output points (t_final / dt + 1)",
        "5e6 rows of states, inputs and outputs of one run: about 0.7 GB for the elastic model",
    ),
    "repeats": Budget(
        "PENDULAB_MAX_REPEATS", 100, "timed repetitions of each benchmark point",
        "every timed point run 100 times: about 33x the time of the default 3 repetitions",
    ),
    "runs": Budget(
        "PENDULAB_MAX_RUNS", 10_000_000, "runs of one ensemble or benchmark workload",
        "1e7 initial states and results (about 1 GB) and hours of integration on one core",
    ),
    "sweep_points": Budget(
        "PENDULAB_MAX_SWEEP_POINTS", 10_000, "points of a sweep, each a full run (co-simulation at one step)",
        "10,000 co-simulation runs per model kind: hours",
    ),
    "frames": Budget(
        "PENDULAB_MAX_FRAMES", 2_000, "animation frames (shown duration x fps)",
        "2,000 frames of 960 x 540 px held in memory before writing: about 3 GB, and minutes of rendering",
    ),
    "image_pixels": Budget(
        "PENDULAB_MAX_IMAGE_PIXELS", 100_000_000, "pixels of one rendered image (width x height x dpi^2)",
        "a 10,000 x 10,000 px canvas: 400 MB of RGBA buffer",
    ),
}  # fmt: skip


def check_budget(key: str, name: str, value: Any, size: float | None = None) -> int:
    """Check the size that input ``name = value`` asks for against budget ``key`` of :data:`BUDGETS`, before any work.

    Parameters
    ----------
    key : str
        Key of :data:`BUDGETS` (e.g. ``"repeats"``).
    name : str
        The input as the user typed it: the CLI option (``"--repeats"``) or the keyword (``"repeats"``).
    value : Any
        The value received, shown in the message (a string as it is, e.g. ``"1e+12 / 0.001"``).
    size : float, optional
        The size ``value`` asks for (may be huge or inf); default ``value`` itself.

    Returns
    -------
    int
        The size as an int.

    Raises
    ------
    BudgetError
        The size is beyond the budget (the message names the input, the value, the budget, what it costs and
        the variable that raises it), or the variable is not a positive integer.

    Examples
    --------
    >>> from pendulab._checks import check_budget
    >>> check_budget("repeats", "repeats", 5)
    5
    >>> check_budget("repeats", "--repeats", 10**9)
    Traceback (most recent call last):
        ...
    pendulab._checks.BudgetError: --repeats = 1000000000: timed repetitions of each benchmark point 1e+09 ...
    """
    b = BUDGETS[key]
    n = float(value if size is None else size)
    budget = budget_limit(b.env, b.default)
    if not n <= budget:
        shown = value if isinstance(value, str) else repr(value)
        raise BudgetError(
            f"{name} = {shown}: {b.counts} {n:.4g} is beyond the budget of {budget:.4g} (at the default limit: {b.cost}); "
            f"set the environment variable {b.env} to a larger number for a deliberately large run"
        )
    return int(n)


class MissingExtraError(ImportError):
    """An optional dependency is not installed; the message names the pendulab extra that installs it.

    The CLI turns it into a one-line message and exit status 2.
    """


def require_extra(module: str, extra: str, purpose: str) -> Any:
    """Import ``module`` or raise :class:`MissingExtraError` naming ``pendulab[extra]``.

    Parameters
    ----------
    module : str
        Module to import, e.g. ``"heyoka"`` or ``"dask.distributed"``.
    extra : str
        The pendulab extra that installs it, e.g. ``"taylor"``.
    purpose : str
        What needs it, e.g. ``"method='taylor'"``.

    Returns
    -------
    module
        The imported module.

    Raises
    ------
    MissingExtraError
        The module cannot be imported.
    """
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise MissingExtraError(
            f'{purpose} needs {module.split(".")[0]}, which is not installed: pip install "pendulab[{extra}]"'
        ) from exc


#: The pendulab package folder: a warning points at the first frame outside it (the user's call).
_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep


def stacklevel_outside_package() -> int:
    """``stacklevel`` for a ``warnings.warn`` in the caller that names the first frame outside pendulab.

    Returns
    -------
    int
        1 for the caller itself, plus one per enclosing frame inside the package.
    """
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level

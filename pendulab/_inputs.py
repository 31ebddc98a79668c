"""The one declaration of every public input: its type, unit, range and budget.

An input is declared once here (:data:`INPUTS`) and checked once, where it enters: the CLI checks
each option against its declaration right after parsing (:mod:`pendulab.commands.options`), the
scene reader checks its keys against it, public entry points check their keyword arguments with
:func:`checked`, and the reference page ``docs/inputs.md`` is generated from it
(:func:`markdown_table`). Inner layers trust what came through.

Every real input is also kept inside ``[1e-100, 1e100]`` in magnitude (zero allowed where the range
allows it), so that a square, a product of two inputs or an inverse stays a finite, non-zero double:
``k = 1e300`` or ``sample_time = 1e-300`` is refused where it enters instead of overflowing to ``inf`` or
underflowing to ``0`` (and a singular matrix) deep inside. Declarations narrow these bounds further.
"""

from __future__ import annotations

import functools
import inspect
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from ._checks import ENTRY_DEPTH, check_budget

__all__ = ["Input", "InputError", "INPUTS", "MAGNITUDE", "check_input", "checked", "markdown_table"]

#: Magnitude bounds of every real input (see the module docstring).
MAGNITUDE: tuple[float, float] = (1e-100, 1e100)

#: Strings longer than this are refused (a name, a list, a path): no input of pendulab is longer.
MAX_TEXT = 4096

KINDS = ("real", "integer", "text", "choice", "file_in", "file_out", "dir_out", "items", "reals", "names")


class InputError(ValueError):
    """A public input of the wrong type, non-finite, or outside its declared range (the message names all three)."""


@dataclass(frozen=True)
class Input:
    """The declaration of one public input.

    Attributes
    ----------
    name : str
        The keyword name (``t_final``); the CLI option is ``--t-final``, the scene key ``t_final``.
    kind : str
        One of :data:`KINDS`: ``real``, ``integer``; ``text`` (a non-empty string), ``choice`` (one of
        ``choices``); ``file_in`` (an existing file), ``file_out`` / ``dir_out`` (a path pendulab may
        write: not the other kind, its nearest existing folder writable); ``items`` (``NAME=VALUE`` with a
        finite real value), ``reals`` / ``names`` (comma-separated reals / names).
    unit : str
        SI unit of a real input (``""`` for dimensionless or not a number).
    low, high : float or None
        Range of a real or integer input (``None``: the magnitude bound only).
    open_low, open_high : bool
        The range excludes ``low`` / ``high``.
    choices : tuple of str
        Admissible values of a ``choice`` input.
    budget : str or None
        Key of :data:`pendulab._checks.BUDGETS` the value is counted against.
    doc : str
        One line: what the input means.
    """

    name: str
    kind: str
    doc: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    open_low: bool = False
    open_high: bool = False
    choices: tuple[str, ...] = ()
    budget: str | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"input {self.name!r}: kind must be one of {KINDS}, got {self.kind!r}")
        if self.kind == "choice" and not self.choices:
            raise ValueError(f"input {self.name!r}: a choice needs its choices")

    def interval(self) -> str:
        """The range of a real or integer input with its unit, e.g. ``(0, 1e+12] s``."""
        fmt = "{:g}" if self.kind == "real" else "{:d}"
        lo = "-inf" if self.low is None else fmt.format(self.low)
        hi = "inf" if self.high is None else fmt.format(self.high)
        left = "(" if self.open_low or self.low is None else "["
        right = ")" if self.open_high or self.high is None else "]"
        return f"{left}{lo}, {hi}{right}" + (f" {self.unit}" if self.unit else "")

    def expected(self) -> str:
        """What the declaration admits, in words (the end of every error message)."""
        unit = f" {self.unit}" if self.unit else ""
        if self.kind in ("real", "integer"):
            what = "a finite number" if self.kind == "real" else "an integer"
            text = f"{what} in {self.interval()}"
            tiny, huge = MAGNITUDE
            unbounded = self.low is None or self.high is None or self.low < -huge or self.high > huge
            has_tiny = not ((self.low is not None and self.low >= tiny) or (self.high is not None and self.high <= -tiny))
            if self.kind == "real" and (unbounded or has_tiny):
                text += f", |x| in [{tiny:g}, {huge:g}] or 0"
            return text
        return {
            "text": "a non-empty string",
            "choice": f"one of {list(self.choices)}",
            "file_in": "an existing file",
            "file_out": "a file path in a writable folder (not a folder)",
            "dir_out": "a folder path that is writable (not a file)",
            "items": "NAME=VALUE with a finite real VALUE",
            "reals": f"comma-separated finite numbers{unit}, |x| in [{MAGNITUDE[0]:g}, {MAGNITUDE[1]:g}] or 0",
            "names": "comma-separated names",
        }[self.kind]

    def check(self, value: Any, label: str | None = None) -> Any:
        """``value`` converted to this input's type, or :class:`InputError` naming the input, value and range.

        Parameters
        ----------
        value : Any
            The value received (a string from the CLI is parsed).
        label : str, optional
            How the user spelt the input (``"--t-final"``, ``"[simulation] t_final"``); default :attr:`name`.

        Returns
        -------
        Any
            ``float`` (real), ``int`` (integer), ``str`` (text, choice, items, reals, names) or ``Path``.

        Raises
        ------
        InputError
            A wrong type, a non-finite value, a value out of range or beyond the magnitude bounds, a
            path of the wrong kind or not writable, a malformed item or list.
        BudgetError
            A value beyond its resource budget (the message names the variable that raises it).
        """
        label = label or self.name
        converted = _CONVERT[self.kind](self, value, label)
        if self.budget is not None:
            check_budget(self.budget, label, value, converted)
        return converted

    def error(self, label: str, value: Any, why: str = "") -> InputError:
        """The one wording of a refused value: input, value, (reason,) expected range."""
        return InputError(f"{label} = {value!r}: {why + '; ' if why else ''}expected {self.expected()}")


def _number(spec: Input, value: Any, label: str) -> float:
    if type(value) is float:  # the common case, first: simulate's hot path checks five of them per call
        v = value
    else:
        if isinstance(value, bool) or (not isinstance(value, str) and not _is_number(value)):
            raise spec.error(label, value, f"a {type(value).__name__}, not a number")
        if isinstance(value, str) and len(value) > MAX_TEXT:
            raise spec.error(label, value[:40] + "...", "too long")
        try:
            v = float(value)
        except (TypeError, ValueError, OverflowError):
            raise spec.error(label, value, "not a number") from None
    if not math.isfinite(v):
        raise spec.error(label, value, "not finite")
    return v


def _is_number(value: Any) -> bool:
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - numpy is a dependency
        return isinstance(value, (int, float))
    return isinstance(value, (int, float, np.integer, np.floating)) or (
        isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iuf"
    )


def _in_range(spec: Input, v: float, value: Any, label: str) -> None:
    lo, hi = spec.low, spec.high
    below = lo is not None and (v < lo or (spec.open_low and v == lo))
    above = hi is not None and (v > hi or (spec.open_high and v == hi))
    if below or above:
        raise spec.error(label, value, "out of range")


def _real(spec: Input, value: Any, label: str) -> float:
    v = _number(spec, value, label)
    _in_range(spec, v, value, label)
    if v != 0.0 and not MAGNITUDE[0] <= abs(v) <= MAGNITUDE[1]:
        raise spec.error(label, value, "its square or inverse would overflow or underflow")
    return v


def _integer(spec: Input, value: Any, label: str) -> int:
    if isinstance(value, str):
        try:
            n = int(value.strip())
        except ValueError:
            raise spec.error(label, value, "not an integer") from None
    else:
        v = _number(spec, value, label)
        if v != int(v):
            raise spec.error(label, value, "not an integer")
        n = int(v) if not isinstance(value, int) else value
    _in_range(spec, float(n), value, label)
    return n


def _text(spec: Input, value: Any, label: str) -> str:
    if not isinstance(value, str):
        raise spec.error(label, value, f"a {type(value).__name__}, not a string")
    if not value.strip() or len(value) > MAX_TEXT or "\x00" in value:
        raise spec.error(label, value[:40], "empty, too long or with a NUL character")
    return value


def _choice(spec: Input, value: Any, label: str) -> str:
    text = _text(spec, value, label)
    if text not in spec.choices:
        raise spec.error(label, value, "not a known value")
    return text


def _file_in(spec: Input, value: Any, label: str) -> Path:
    path = Path(_text(spec, os.fspath(value) if isinstance(value, os.PathLike) else value, label))
    if not path.is_file():
        raise spec.error(label, str(path), "a folder" if path.is_dir() else "no such file")
    return path


def _writable(spec: Input, value: Any, label: str, *, folder: bool) -> Path:
    path = Path(_text(spec, os.fspath(value) if isinstance(value, os.PathLike) else value, label))
    if path.exists() and path.is_dir() != folder:
        raise spec.error(label, str(path), "is a directory, not a file" if path.is_dir() else "is a file, not a directory")
    if path.exists() and not os.access(path, os.W_OK):
        raise spec.error(label, str(path), "not writable")
    parent = path if folder and path.exists() else path.absolute().parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise spec.error(label, str(path), f"{str(parent)!r} is a file, not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise spec.error(label, str(path), f"its folder {str(parent)!r} is not writable")
    return path


def _file_out(spec: Input, value: Any, label: str) -> Path:
    return _writable(spec, value, label, folder=False)


def _dir_out(spec: Input, value: Any, label: str) -> Path:
    return _writable(spec, value, label, folder=True)


def _items(spec: Input, value: Any, label: str) -> str:
    text = _text(spec, value, label)
    name, sep, number = text.partition("=")
    if not sep or not name.strip():
        raise spec.error(label, value, "not NAME=VALUE")
    try:
        _real(dataclass_replace(spec, kind="real"), number, label)
    except InputError:
        raise spec.error(label, value, f"{name.strip()}: {number!r} is not a finite number of admissible magnitude") from None
    return text


def _reals(spec: Input, value: Any, label: str) -> str:
    text = _text(spec, value, label)
    item = dataclass_replace(spec, kind="real")
    for part in text.split(","):
        try:
            _real(item, part, label)
        except InputError:
            raise spec.error(label, value, f"{part.strip()!r} is not admissible") from None
    return text


def _names(spec: Input, value: Any, label: str) -> str:
    text = _text(spec, value, label)
    if not all(part.strip() for part in text.split(",")):
        raise spec.error(label, value, "an empty name in the list")
    if spec.choices:
        unknown = [p.strip() for p in text.split(",") if p.strip() not in spec.choices]
        if unknown:
            raise spec.error(label, value, f"unknown {unknown}; known: {list(spec.choices)}")
    return text


def dataclass_replace(spec: Input, **changes: Any) -> Input:
    """``spec`` with ``changes`` (the element declaration of a list or item input)."""
    import dataclasses

    return dataclasses.replace(spec, **changes)


_CONVERT: Mapping[str, Callable[[Input, Any, str], Any]] = {
    "real": _real,
    "integer": _integer,
    "text": _text,
    "choice": _choice,
    "file_in": _file_in,
    "file_out": _file_out,
    "dir_out": _dir_out,
    "items": _items,
    "reals": _reals,
    "names": _names,
}


def _r(name: str, doc: str, unit: str = "", low: float | None = None, high: float | None = None, **kw: Any) -> Input:
    return Input(name, "real", doc, unit, low, high, **kw)


def _i(name: str, doc: str, low: int, high: int, **kw: Any) -> Input:
    return Input(name, "integer", doc, "", low, high, **kw)


#: Longest horizon of a run [s]: any finite time a run may end by an event (ensembles); the output-points and
#: step budgets bound the work a long horizon asks for.
MAX_HORIZON = 1e12

_DECLARED: tuple[Input, ...] = (
    # Simulation settings (CLI, scene [simulation], pendulab.simulate)
    _r("t_final", "horizon of a run", "s", 0.0, MAX_HORIZON, open_low=True),
    _r("dt", "output step (sampling of the returned trajectory)", "s", 1e-9, MAX_HORIZON),
    # Below the double epsilon (2.22e-16) no step meets a relative tolerance; at 1 or more no digit is asked for.
    _r("rtol", "relative tolerance of an error-controlled integrator", "", 2.22e-16, 1.0, open_high=True),
    _r("atol", "absolute tolerance of an error-controlled integrator", "", 1e-30, None),
    _r("tolerance", "accuracy asked of a result: integration, NLP or output tolerance", "", 2.22e-16, 1.0, open_high=True),
    _r("max_step", "largest integrator step", "s", 0.0, MAX_HORIZON, open_low=True),
    _r("max_wall_time", "wall-clock budget of a long job", "s", 0.0, 30 * 86_400.0, open_low=True),
    # Control and co-simulation
    _r("sample_time", "controller sample time", "s", 1e-5, 10.0),
    _r("comm_step", "co-simulation communication step", "s", 1e-6, 10.0),
    _r("u_max", "torque limit of the actuated joint(s)", "N.m", 0.0, 1e4, open_low=True),
    _r("state", "an initial-state value: angle [rad], rate [rad/s], spring length [m] or its rate [m/s]", "", -1e6, 1e6),
    _r("torque", "a joint torque (an input's value or amplitude)", "N.m", -1e4, 1e4),
    # = pendulab.evaluate.realai.v3_hardware.PASSIVE_ALLOWANCE: the hardware rules' motor-friction allowance.
    _r("passive_allowance", "torque the controller may put on the passive joint (hardware rules)", "N.m", 0.0, 0.5),
    # 0 is the v3 simulation rule; upstream's simulator clipped entries only to the plant's 6 N.m (published runs).
    _r("passive_limit", "torque a v3 entry may put on the passive joint (0: the rules; 6: upstream simulator)", "N.m", 0.0, 6.0),
    _r("frequency", "frequency of a sinusoidal input", "Hz", 0.0, 1e4, open_low=True),
    _r("horizon", "prediction or planning horizon", "s", 0.0, 30.0, open_low=True),
    _r("measurement_noise", "standard deviation of the measurement noise (angles rad, rates rad/s)", "", 0.0, 100.0),
    _i("measurement_delay", "measurement delay in controller samples", 0, 10_000),
    _i("measurement_seed", "seed of the measurement noise", 0, 2**32 - 1),
    _r("delay", "a delay", "s", 0.0, 10.0),
    _r("velocity_scale", "rate that maps to 1 in a normalized observation", "rad/s", 0.0, 1e4, open_low=True),
    _r("reset_noise", "spread of the random initial state of an episode", "rad", 0.0, 10.0),
    _i("render_size", "side of a rendered frame", 32, 4096),
    _i("max_episode_steps", "steps after which an episode is truncated", 1, 10**9),
    # = pendulab.control.swingup.problem.MAX_INTERVALS (tests/reliability/test_input_battery.py keeps them equal):
    # each interval adds a block of the NLP; an elastic NLP of 600 intervals needs ~6 GB to build.
    # = pendulab.control.nmpc.controller.MAX_HORIZON (kept equal by the battery test).
    _i("horizon_intervals", "shooting intervals of an NMPC prediction (N; the horizon is N sample times)", 1, 500),
    _i("N", "collocation or shooting intervals of a trajectory optimization", 2, 1000),
    _i("intervals", "intervals of a trajectory optimization", 2, 1000),
    _i("starts", "initial guesses tried by a multi-start optimization", 1, 1000),
    _i("tracking_starts", "randomized starts the plan is also tracked from (0: none)", 0, 1000),
    _i("gif_fps", "frames per second of an animation", 1, 120),
    _r("velocity_limit", "bound on the joint rates omega1, omega2 - omega1 of a plan", "rad/s", 0.0, 1e4, open_low=True),
    _r(
        "angle_limit",
        "largest joint angle a controller steers to (a farther goal moves whole turns nearer)",
        "rad",
        0.0,
        1e4,
        open_low=True,
    ),
    _r("plan_delay", "time a plan takes to arrive (simulated planning latency)", "s", 0.0, 10.0),
    _r("max_solve_time", "wall-time cap of one solve", "s", 0.0, 60.0, open_low=True),
    _i("max_iter", "iteration cap of one solve", 1, 10_000),
    _i("substeps", "RK4 steps per interval of a prediction (unrolled into the NLP)", 1, 1000),
    _i("n_sub", "integration sub-steps per controller sample", 1, 10_000),
    _i("max_halvings", "halvings of a rejected co-simulation step", 0, 60),
    # Controller design: gains, weights and levels of the swing-up and balance laws
    _r("k_energy", "energy-pumping gain (its unit is the controller's: N.m/(J.rad/s) or 1/(J.s))", "", 0.0, 1e4, open_low=True),
    _r("kp", "proportional gain of a joint PD law (N.m/rad, or 1/s^2 for an acceleration law)", "", 0.0, 1e6),
    _r("kd", "derivative gain of a joint PD law (N.m.s/rad, or 1/s for an acceleration law)", "", 0.0, 1e6),
    _r("alpha", "amplitude of the acrobot's elbow target alpha (2/pi) atan(omega1)", "rad", 0.0, 10.0),
    _r("catch_cost", "LQR cost-to-go below which the balance controller takes over", "", 0.0, None, open_low=True),
    _r("release_factor", "cost-to-go, in multiples of catch_cost, at which a failed catch is released", "", 1.0, 1e6),
    _r("level", "a cost-to-go level of a catch or release (LQR cost x'Px)", "", 0.0, None, open_low=True),
    _r("weight", "a weight of an optimal-control cost (state, torque, torque rate, time or slack)", "", 0.0, 1e12, open_low=True),
    _r("slack_tol", "slack on the soft state bounds above which a solve counts as infeasible", "", 0.0, 1e3, open_low=True),
    _r("error_level", "tracking cost e'e above which a plan is abandoned", "", 0.0, 1e6, open_low=True),
    _r("retry", "time between two attempts of a failed plan", "s", 0.0, 60.0, open_low=True),
    _r("window", "length of an estimator's likelihood window", "s", 0.0, 1e4, open_low=True),
    _r("accel_std", "model-error allowance of an estimator (acceleration standard deviation)", "rad/s^2", 0.0, 1e6),
    _r("spread", "half-width of a box of random initial angles [rad] or rates [rad/s]", "", 0.0, 1e4),
    _r("settle_tol", "convergence threshold on angles [rad] and rates [rad/s]", "", 0.0, 1e3, open_low=True),
    _r("torque_margin", "fraction of the torque limit a plan may use", "", 0.0, 1.0, open_low=True),
    _r("response", "ratio of applied to commanded torque (a torque-response hypothesis)", "", 0.0, 2.0, open_low=True),
    _r("amplitude_max", "largest amplitude a region-of-attraction search tries", "rad", 0.0, 1e6, open_low=True),
    _i("degree", "degree of the collocation polynomial", 1, 9),
    _i("max_refinements", "mesh refinements of a trajectory optimization", 0, 50),
    # Protocols and metrics
    _r("threshold", "tip height above which the pendulum counts as up", "m", -100.0, 100.0),
    _r("gap", "time without a controller call after which the controller is reset (a new episode)", "s", 0.0, 60.0),
    _r("deadtime", "shortest time between two counted swing-ups", "s", 0.0, 60.0),
    _i("n_resets", "resets of a global-protocol run", 1, 1000),
    _i("repetitions", "repetitions of each level of a robustness category", 1, 5000),
    _i("n_steps", "fixed steps of a rollout or protocol run", 1, 10**9),
    # Environments and rendering
    _i("num_envs", "environments of a vector environment", 1, 4096),
    _r("bonus", "reward added while the tip is above the goal height", "", 0.0, 1e6),
    _r("extent", "half-width of the rendered scene", "m", 0.0, 1e3, open_low=True),
    _r("goal_fraction", "goal height as a fraction of the reach", "", 0.0, 1.0),
    # Ensembles: batching and chunking (= pendulab.ensemble.batch.MAX_BATCH_SIZE and engine_checks.MAX_RUNS)
    _i("batch_size", "SIMD lanes of one batch integrator", 1, 64),
    _i("chunk_size", "runs per chunk handed to a worker", 1, 10**8),
    _i("block_size", "runs per recorded block of a long ensemble", 1, 10**8),
    _i("chunks_per_worker", "chunks each worker receives (load balancing)", 1, 10_000),
    _i("max_steps", "step budget of each run", 1, 2**31 - 1),
    _i("step_budget", "integrator steps of one long estimate (a Lyapunov exponent)", 1, 2**62),
    # Models
    _r("k", "spring stiffness of both elastic links", "N/m", 0.0, 1e12, open_low=True),
    _r("cutoff", "low-pass cut-off frequency of the identification filter", "Hz", 0.0, 1e4, open_low=True),
    # Workloads and budgets
    _i("repeats", "timed repetitions of each benchmark point", 1, 10**9, budget="repeats"),
    _i("runs", "runs of a workload (ensemble runs, runs per level)", 1, 10**12, budget="runs"),
    # = pendulab.evaluate.scorecard.MAX_RUNS (kept equal by the battery test).
    _i("runs_per_level", "runs per level of each stochastic category of a scorecard", 1, 5000),
    _i("hand_runs", "runs of the hand-written reference loop", 1, 10**12, budget="runs"),
    _i("grid", "points per axis of a square grid of initial states", 1, 20_000),
    _i("elastic_grid", "points per axis of the elastic grid (0: no elastic timing)", 0, 4000),
    _r("t_max", "longest time a run of an ensemble lasts", "s", 0.0, MAX_HORIZON, open_low=True),
    _i("threads", "threads of a local ensemble", 1, 256),
    _i("workers", "worker processes (each a forked process)", 1, 256),
    _i("seed", "seed of a random generator", 0, 2**63 - 1),
    _i("legacy_seed", "seed of numpy's legacy RandomState (upstream RealAIGym's generator)", 0, 2**32 - 1),
    _i("fmi_version", "FMI major version", 2, 3),
    _i("fmu_index", "index of the FMU whose outputs feed the controller (below the number of FMUs)", 0, 10_000),
    # Text, choices, lists and paths (CLI)
    Input("name", "text", "a name: scene, controller, task, method, estimator, dataset, structure"),
    Input("set_item", "items", "parameter or initial-state value NAME=VALUE (SI units)"),
    Input("steps", "text", "co-simulation steps [s]: a comma-separated list or START:STOP:STEP"),
    Input("reals", "reals", "comma-separated numbers (e.g. torques TAU1,TAU2 in N.m, steps in s)"),
    Input("names", "names", "comma-separated names (controllers, categories, kinds, columns)"),
    Input("file_in", "file_in", "a file pendulab reads (FMU, records, reference trajectory)"),
    Input("file_out", "file_out", "a file pendulab writes (its folder is created)"),
    Input("dir_out", "dir_out", "a folder pendulab writes into (created if missing)"),
    Input("address", "text", "address of a Dask scheduler (host:port)"),
)

#: Every declared input by name.
INPUTS: Mapping[str, Input] = {spec.name: spec for spec in _DECLARED}


def check_input(name: str, value: Any, label: str | None = None) -> Any:
    """Check ``value`` against the declaration of input ``name`` (see :meth:`Input.check`).

    Raises
    ------
    KeyError
        ``name`` is not declared (a programming error: declare it in :data:`INPUTS`).
    InputError, BudgetError
        As :meth:`Input.check`.

    Examples
    --------
    >>> from pendulab._inputs import check_input
    >>> check_input("t_final", "2.5")
    2.5
    >>> check_input("rtol", float("nan"))
    Traceback (most recent call last):
        ...
    pendulab._inputs.InputError: rtol = nan: not finite; expected a finite number in [1e-16, 1), ...
    """
    return INPUTS[name].check(value, label)


F = TypeVar("F", bound=Callable[..., Any])


def checked(forward: Callable[..., Any] | None = None, /, **aliases: str) -> Callable[[F], F]:
    """Decorate a public entry point: its keyword inputs are checked against :data:`INPUTS` before its body runs.

    Every parameter whose name is a declared number is checked (``None`` passes: it means "the default");
    ``aliases`` maps a parameter to the declaration it uses under another name
    (``@checked(tol="tolerance")``). The checked value replaces the argument (an ``int`` for a real input
    becomes a ``float``); a string for a number is refused (only the CLI parses text).
    A decorated class (a dataclass of settings or a controller) has its ``__init__`` checked. Keywords a
    ``**options`` parameter forwards are checked too: as ``forward`` (the checked callable they are passed to)
    declares them, else by their names (``aliases`` may name them).

    Values are checked once, where they enter: only the outermost entry point checks
    (:data:`pendulab._checks.ENTRY_DEPTH`); an entry point called from inside another trusts its arguments.
    The decorated function keeps its signature and records what it checks in ``__pendulab_inputs__``.

    Parameters
    ----------
    forward : callable, optional
        Where a ``**options`` parameter sends its keywords (a checked function or class): they are checked as
        it declares them (``NMPCOptions``'s ``horizon`` is a count of intervals, not seconds).
    **aliases : str
        Parameter name to declared input name.

    Returns
    -------
    callable
        The decorator.
    """

    def decorate(func: F) -> F:
        if inspect.isclass(func):
            func.__init__ = decorate(func.__init__)  # type: ignore[misc]
            return func
        sig = inspect.signature(func)
        # By name only numbers: a parameter called ``name`` or ``out`` is the function's own (text and path
        # declarations are the CLI's); anything else is checked when an alias names it.
        plan = {
            p: aliases.get(p, p)
            for p in sig.parameters
            if p in aliases or (p in INPUTS and INPUTS[p].kind in ("real", "integer"))
        }
        # Keywords a ``**options`` parameter forwards are checked too (as ``forward`` declares them, else by name or
        # alias): the inner layer they reach trusts them.
        forwards = any(q.kind is q.VAR_KEYWORD for q in sig.parameters.values())
        target = getattr(forward, "__init__", None) if inspect.isclass(forward) else forward
        target_plan = getattr(target, "__pendulab_inputs__", None)
        if forward is not None and (not forwards or target_plan is None):
            raise TypeError(f"@checked on {func.__qualname__}: forward needs **options and a @checked target")
        forwarded = {p: INPUTS[n] for p, n in {**(target_plan or {}), **aliases}.items() if p not in sig.parameters}
        unknown = sorted(set(aliases.values()) - set(INPUTS))
        if unknown or set(aliases) - set(plan) - set(forwarded):
            raise TypeError(f"@checked on {func.__qualname__}: unknown inputs {unknown} or parameters {sorted(aliases)}")

        # Where each checked parameter sits when passed by position (no Signature.bind per call: simulate is hot).
        positional = [p.name for p in sig.parameters.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
        slots = sorted((positional.index(p), p, INPUTS[n]) for p, n in plan.items() if p in positional)
        keywords = [(p, INPUTS[n]) for p, n in plan.items()]

        def check(args: tuple[Any, ...], kwargs: dict[str, Any]) -> tuple[Any, ...]:
            if slots and len(args) > slots[0][0]:
                listed = list(args)
                for index, param, spec in slots:
                    if index < len(listed) and listed[index] is not None:
                        listed[index] = _check_argument(spec, listed[index], param)
                args = tuple(listed)
            for param, spec in keywords:
                value = kwargs.get(param)
                if value is not None:
                    kwargs[param] = _check_argument(spec, value, param)
            if forwards:
                for param, value in kwargs.items():
                    spec = forwarded.get(param)
                    if spec is None and target_plan is None and param not in sig.parameters:
                        spec = INPUTS.get(param)
                    if spec is not None and spec.kind in ("real", "integer") and value is not None:
                        kwargs[param] = _check_argument(spec, value, param)
            return args

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            depth = ENTRY_DEPTH.get()
            if depth == 0:
                args = check(args, kwargs)
            token = ENTRY_DEPTH.set(depth + 1)
            try:
                return func(*args, **kwargs)
            finally:
                ENTRY_DEPTH.reset(token)

        wrapper.__pendulab_inputs__ = dict(plan)  # type: ignore[attr-defined]
        wrapper.__pendulab_forwards__ = forwards  # type: ignore[attr-defined]
        return wrapper  # type: ignore[return-value]

    return decorate


def _check_argument(spec: Input, value: Any, param: str) -> Any:
    """One keyword argument checked: a string for a number is refused (only the CLI parses text)."""
    if isinstance(value, str) and spec.kind in ("real", "integer"):
        raise spec.error(param, value, "a str, not a number")
    return spec.check(value, param)


def markdown_table() -> str:
    """The reference table of every declared input (``docs/inputs.md`` embeds it; a test keeps it current).

    Returns
    -------
    str
        A Markdown table: name, kind, unit, what it admits, budget, meaning.
    """
    rows = ["| input | kind | unit | admits | budget | meaning |", "|---|---|---|---|---|---|"]
    for spec in sorted(_DECLARED, key=lambda s: s.name.lower()):
        budget = f"`{spec.budget}`" if spec.budget else ""
        rows.append(f"| `{spec.name}` | {spec.kind} | {spec.unit} | {spec.expected()} | {budget} | {spec.doc} |")
    return "\n".join(rows) + "\n"


if __name__ == "__main__":  # pragma: no cover - regenerates the table of docs/inputs.md
    import sys

    sys.stdout.write(markdown_table())

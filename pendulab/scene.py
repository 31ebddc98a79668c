"""Scenes: a pendulum, an initial state, a horizon and what the user cares about, as TOML.

A scene file has the sections ``[scene]``, ``[model]`` (with ``[model.params]``),
``[initial]`` (state values by name, and ``start``: how unstated spring
lengths are set), ``[simulation]``, ``[outputs]`` and ``[input]`` (constant
torques, plus an optional ``[input.sine]``); any other
top-level section (e.g. ``[task]``) is kept verbatim in ``Scene.extra`` for the
feature that uses it. Every key of the known sections is validated: a typo is
an error naming the file, the section, the key, the value and what was
expected, never a silently ignored setting. See ``docs/scenes.md``.

Shipped scenes live in ``pendulab/scenes/*.toml`` and are loaded by name:
``load_scene("seed_paper")``. Two groups sit in subdirectories: the cases of
the work-precision study (``"bench/rigid_chaotic_10s"``) and the FMU
validation scenes (``"validation/rigid_forced"``); ``list_scenes("bench")``
lists a group. Every scene of the project -- user scenes, benchmark cases,
validation scenes and swing-up tasks -- is this one type.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from .integrate import METHODS, simulate, time_grid
from .integrate.trajectory import Trajectory
from .model.model import Model, make_model
from .model.params import ElasticParams, RigidParams
from .model.quasistatic import quasi_static_state

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["Scene", "load_scene", "list_scenes", "default_scene", "scene_path", "initial_state", "SCENE_DIR", "STARTS", "GROUPS"]

#: Directory of the scenes shipped with the package.
SCENE_DIR = Path(__file__).resolve().parent / "scenes"

_PARAM_CLASSES = {"rigid": RigidParams, "elastic": ElasticParams}
_SIMULATION_DEFAULTS: Mapping[str, Any] = MappingProxyType(
    {"t_final": 10.0, "dt": 0.01, "method": "auto", "rtol": 1e-8, "atol": 1e-8}
)
_DEFAULT_OUTPUTS = ("theta1", "theta2")
_KNOWN_SECTIONS = ("scene", "model", "initial", "simulation", "outputs", "input")
#: How unstated spring lengths are set at t = 0: static hanging length, rest length L (excites
#: the spring mode), or quasi-static (zero radial acceleration at the initial angles and rates).
STARTS: tuple[str, ...] = ("static", "rest-length", "quasi-static")
#: Groups of shipped scenes in subdirectories of ``SCENE_DIR``.
GROUPS: tuple[str, ...] = ("bench", "validation")


@dataclass(frozen=True)
class Scene:
    """A validated scene (see ``docs/scenes.md``).

    Attributes
    ----------
    name : str
        Scene name (``[scene] name``, default: the file stem).
    description : str
        Free text; provenance of the parameters.
    model : Model
        The pendulum with the scene's parameters.
    initial : mapping of str to float
        The initial state values the file states explicitly, by name.
    x0 : ndarray, shape (nx,)
        Full initial state: the stated values, unstated entries at rest and
        unstated spring lengths as ``start`` says.
    t_final, dt : float
        Horizon and output step [s].
    method : str
        Integration method: ``"auto"`` or a key of ``pendulab.METHODS``.
    rtol, atol : float
        Integrator tolerances.
    outputs : tuple of str
        Signals of interest (state, input or output names of the model).
    tolerance : float or None
        Acceptable error on those outputs, in their units (None: not stated).
    u : ndarray, shape (2,), or None
        Constant torques (tau1, tau2) [N.m]; None when the scene has no ``[input]``.
    start : {"static", "rest-length", "quasi-static"}
        How unstated spring lengths are set (elastic; "static" for rigid).
    u_amplitude : ndarray, shape (2,), or None
        Amplitudes [N.m] of a sine torque added to ``u`` (``[input.sine]``).
    u_frequency : float
        Its frequency [Hz].
    extra : mapping
        Other top-level sections, unvalidated, for the feature that uses them.
    path : Path or None
        The file the scene came from.
    """

    name: str
    description: str
    model: Model
    initial: Mapping[str, float]
    x0: np.ndarray
    t_final: float
    dt: float
    method: str
    rtol: float
    atol: float
    outputs: tuple[str, ...]
    tolerance: float | None = None
    u: np.ndarray | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    path: Path | None = None
    start: str = "static"
    u_amplitude: np.ndarray | None = None
    u_frequency: float = 0.0

    @property
    def kind(self) -> str:
        """Model kind, ``"rigid"`` or ``"elastic"``."""
        return self.model.kind

    def grid(self) -> np.ndarray:
        """The output grid of :func:`pendulab.simulate` for this scene.

        Returns
        -------
        ndarray, shape (N,)
            Equally spaced times [s] from 0 to ``t_final`` with step at most
            ``dt``, ``N = ceil(t_final / dt) + 1``.
        """
        return time_grid(self.t_final, self.dt)

    def inputs(self, t: np.ndarray | None = None) -> np.ndarray:
        """Torques (tau1, tau2) [N.m] at times ``t`` (default :meth:`grid`), shape (N, 2).

        Constant ``u`` (zero without ``[input]``) plus the ``[input.sine]`` term
        ``u_amplitude * sin(2 pi u_frequency t)``; :meth:`simulate` holds row k
        over ``[t_k, t_k+1)``.

        Parameters
        ----------
        t : array_like, shape (N,), optional
            Times [s]; default the scene's output grid :meth:`grid`.

        Returns
        -------
        ndarray, shape (N, 2)
            Torques (tau1, tau2) [N.m], one row per time.
        """
        t = self.grid() if t is None else np.asarray(t, dtype=float)
        u = np.zeros((len(t), self.model.nu)) + (0.0 if self.u is None else self.u)
        if self.u_amplitude is not None:
            u = u + np.outer(np.sin(2 * np.pi * self.u_frequency * t), self.u_amplitude)
        return u

    def with_settings(self, **settings: float) -> Scene:
        """Return a copy with parameters and/or initial-state values changed by name.

        Parameter changes rebuild the model; the initial state is rebuilt from
        the explicit values, so unstated spring lengths follow a changed
        stiffness (static hanging length).

        Parameters
        ----------
        **settings : float
            Parameter values in SI units (e.g. ``k1=1e4`` [N/m]) and/or initial
            state values (e.g. ``theta1=2.0`` [rad]) by name.

        Returns
        -------
        Scene
            Copy with the new model, ``initial`` and ``x0``; other settings kept.

        Raises
        ------
        ValueError
            A name that is neither a parameter nor a state of the model, or an
            invalid value.
        """
        params = {k: v for k, v in settings.items() if k in self.model.param_names}
        states = {k: v for k, v in settings.items() if k in self.model.state_names}
        unknown = sorted(set(settings) - set(params) - set(states))
        if unknown:
            raise ValueError(
                f"unknown name(s) {unknown} for the {self.model.kind} model of scene {self.name!r}; expected a "
                f"parameter {list(self.model.param_names)} or a state {list(self.model.state_names)}"
            )
        for name, value in states.items():
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float, np.floating, np.integer))
                or not math.isfinite(value)
            ):
                raise ValueError(f"initial state {name!r} must be a finite number, got {value!r}")
        model = self.model.with_params(**params) if params else self.model
        initial = {**self.initial, **{k: float(v) for k, v in states.items()}}
        x0 = _frozen(initial_state(model, initial, self.start))
        return dataclasses.replace(self, model=model, initial=MappingProxyType(initial), x0=x0)

    def simulate(self, **overrides: Any) -> Trajectory:
        """Run the scene with :func:`pendulab.simulate`.

        Parameters
        ----------
        **overrides
            Any keyword of :func:`pendulab.simulate` (``x0``, ``t_final``,
            ``dt``, ``method``, ``rtol``, ``atol``, ``u``, ``max_step``,
            ``options``); defaults come from the scene.

        Returns
        -------
        Trajectory
            States, inputs and outputs on the output grid.

        Raises
        ------
        ValueError
            An override that is not one of the keywords above, or bad
            arguments (from :func:`pendulab.simulate`).
        SimulationError
            The integrator failed (from :func:`pendulab.simulate`).
        """
        kwargs: dict[str, Any] = {
            "x0": self.x0,
            "t_final": self.t_final,
            "dt": self.dt,
            "method": self.method,
            "rtol": self.rtol,
            "atol": self.atol,
            "u": self.inputs() if self.u_amplitude is not None else self.u,
        }
        allowed = set(kwargs) | {"max_step", "options"}
        unknown = sorted(set(overrides) - allowed)
        if unknown:
            raise ValueError(f"unknown simulate override(s) {unknown}; expected some of {sorted(allowed)}")
        kwargs.update(overrides)
        return simulate(self.model, **kwargs)


def initial_state(model: Model, initial: Mapping[str, float], start: str = "static") -> np.ndarray:
    """Full initial state from the stated values and the spring-length rule.

    Parameters
    ----------
    model : Model
        The pendulum.
    initial : mapping of str to float
        Stated state values by name; the others at rest.
    start : {"static", "rest-length", "quasi-static"}
        Unstated spring lengths (elastic): static hanging length, rest length L,
        or quasi-static (zero radial acceleration; stated lengths are then
        overridden, so state none).

    Returns
    -------
    ndarray, shape (nx,)
        Initial state in ``model.state_names`` order.

    Raises
    ------
    ValueError
        Unknown state name or start rule.
    """
    if start not in STARTS:
        raise ValueError(f"start must be one of {list(STARTS)}, got {start!r}")
    values = dict(initial)
    if model.kind == "elastic" and start == "rest-length":
        values.setdefault("r1", model.params.L1)
        values.setdefault("r2", model.params.L2)
    x = model.state(**values)
    if model.kind == "elastic" and start == "quasi-static":
        x = quasi_static_state(model, x[0:2], x[4:6])
    return x


def _frozen(a: np.ndarray) -> np.ndarray:
    """A read-only copy: a frozen Scene must not change through its arrays."""
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


def default_scene(kind: str) -> Scene:
    """A scene of the given model kind with default parameters, at rest, and default settings.

    Used when a model is chosen without a scene file (``pendulab simulate --model rigid``);
    set the initial state with :meth:`Scene.with_settings`.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    Scene
        Named ``"<kind>_default"``: hanging at rest, ``t_final`` = 10 s,
        ``dt`` = 0.01 s, method ``"auto"``, ``rtol = atol = 1e-8``, outputs
        theta1, theta2, no input.

    Raises
    ------
    ValueError
        Unknown ``kind`` (from :func:`~pendulab.model.model.make_model`).
    """
    model = make_model(kind)
    d = _SIMULATION_DEFAULTS
    return Scene(
        name=f"{kind}_default",
        description=f"{kind} double pendulum with default parameters",
        model=model,
        initial=MappingProxyType({}),
        x0=_frozen(model.state()),
        t_final=d["t_final"],
        dt=d["dt"],
        method=d["method"],
        rtol=d["rtol"],
        atol=d["atol"],
        outputs=_DEFAULT_OUTPUTS,
    )


def list_scenes(group: str | None = None) -> tuple[str, ...]:
    """Names of the scenes shipped with the package, sorted.

    Parameters
    ----------
    group : {None, "bench", "validation"}
        None: the user-facing scenes (top level); a group: its scenes, named ``"<group>/<stem>"``.

    Returns
    -------
    tuple of str
        Names accepted by :func:`load_scene`.

    Raises
    ------
    ValueError
        Unknown group.
    """
    if group is None:
        return tuple(sorted(p.stem for p in SCENE_DIR.glob("*.toml")))
    if group not in GROUPS:
        raise ValueError(f"unknown scene group {group!r}; expected one of {list(GROUPS)}")
    return tuple(sorted(f"{group}/{p.stem}" for p in (SCENE_DIR / group).glob("*.toml")))


def scene_path(path_or_name: str | Path) -> Path:
    """Resolve a file path or the name of a shipped scene to an existing file.

    Parameters
    ----------
    path_or_name : str or Path
        An existing file, or a shipped scene name with or without ``.toml``,
        e.g. ``"seed_paper"`` or ``"bench/rigid_chaotic_10s"``.

    Returns
    -------
    Path
        ``path_or_name`` itself when it is a file, else the file in ``SCENE_DIR``.

    Raises
    ------
    FileNotFoundError
        Neither an existing file nor a shipped scene name.
    """
    candidate = Path(path_or_name)
    if candidate.is_file():
        return candidate
    text = str(path_or_name)
    stem = text[:-5] if text.endswith(".toml") else text
    group, _, leaf = stem.rpartition("/")
    if group in ("", *GROUPS) and leaf and "\\" not in leaf and (SCENE_DIR / f"{stem}.toml").is_file():
        return SCENE_DIR / f"{stem}.toml"
    raise FileNotFoundError(f"scene {text!r}: no such file and no shipped scene of that name; shipped: {list(list_scenes())}")


class _Reader:
    """Validates one parsed file, building messages that name file, section and key."""

    def __init__(self, path: Path, data: Mapping[str, Any]) -> None:
        self.path = path
        self.data = data

    def error(self, section: str, key: str | None, value: Any, expected: str) -> ValueError:
        where = f"[{section}] {key}" if key is not None else f"[{section}]"
        shown = "missing" if value is _MISSING else repr(value)
        return ValueError(f"scene file {str(self.path)!r}: {where} = {shown}: expected {expected}")

    def table(self, section: str, required: bool = False) -> Mapping[str, Any]:
        keys = section.split(".")
        node: Any = self.data
        for part in keys:
            node = node.get(part, _MISSING) if isinstance(node, Mapping) else _MISSING
            if node is _MISSING:
                if required:
                    raise self.error(section, None, _MISSING, "a table (section)")
                return {}
        if not isinstance(node, Mapping):
            raise self.error(section, None, node, "a table (section)")
        return node

    def only(self, section: str, table: Mapping[str, Any], allowed: tuple[str, ...], what: str) -> None:
        for key in table:
            if key not in allowed:
                raise self.error(section, key, table[key], f"one of the {what} {list(allowed)}")

    def real(self, section: str, key: str, value: Any, *, positive: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.error(section, key, value, "a finite number" + (" > 0" if positive else ""))
        if positive and value <= 0:
            raise self.error(section, key, value, "a finite number > 0")
        return float(value)

    def string(self, section: str, key: str, value: Any, choices: tuple[str, ...] | None = None) -> str:
        if not isinstance(value, str) or (choices is not None and value not in choices):
            raise self.error(section, key, value, "a string" if choices is None else f"one of {list(choices)}")
        return value


_MISSING = object()


def load_scene(path_or_name: str | Path) -> Scene:
    """Load and validate a scene from a TOML file or the name of a shipped scene.

    Parameters
    ----------
    path_or_name : str or Path
        A file path, or a shipped scene name such as ``"seed_paper"``
        (see :func:`list_scenes`).

    Returns
    -------
    Scene
        The validated scene.

    Raises
    ------
    FileNotFoundError
        No such file or shipped scene.
    ValueError
        Malformed TOML, an unknown key in a known section, a wrong type, an
        unknown parameter or state name, a non-positive horizon, step or
        tolerance, an unknown method or output. The message names the file,
        the section, the key, the value and what was expected.
    """
    path = scene_path(path_or_name)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"scene file {str(path)!r}: malformed TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"scene file {str(path)!r}: not UTF-8 text: {exc}") from None
    rd = _Reader(path, data)

    head = rd.table("scene")
    rd.only("scene", head, ("name", "description"), "keys")
    name = rd.string("scene", "name", head.get("name", path.stem))
    description = rd.string("scene", "description", head.get("description", ""))

    model_table = rd.table("model", required=True)
    rd.only("model", model_table, ("kind", "params"), "keys")
    kind = rd.string("model", "kind", model_table.get("kind", _MISSING), tuple(_PARAM_CLASSES))
    params_table = rd.table("model.params")
    rd.only("model.params", params_table, _PARAM_CLASSES[kind].names(), f"{kind} parameters")
    params = {k: rd.real("model.params", k, v) for k, v in params_table.items()}
    try:
        model = make_model(kind, **params)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"scene file {str(path)!r}: [model.params]: {exc}") from None

    init_table = dict(rd.table("initial"))
    start = rd.string("initial", "start", init_table.pop("start", "static"), STARTS if kind == "elastic" else ("static",))
    rd.only("initial", init_table, model.state_names, f"{kind} state names (or 'start')")
    initial = {k: rd.real("initial", k, v) for k, v in init_table.items()}
    if start == "quasi-static" and ({"r1", "r2"} & set(initial)):
        raise rd.error("initial", "start", start, "no stated r1, r2 with a quasi-static start (it sets them)")
    x0 = initial_state(model, initial, start)
    if kind == "elastic" and np.any(x0[2:4] <= 0):
        raise rd.error("initial", "r1/r2", x0[2:4].tolist(), "spring lengths > 0 m")

    sim = rd.table("simulation")
    rd.only("simulation", sim, tuple(_SIMULATION_DEFAULTS), "keys")
    settings = {**_SIMULATION_DEFAULTS, **sim}
    method = rd.string("simulation", "method", settings["method"], ("auto", *METHODS))
    t_final, dt, rtol, atol = (rd.real("simulation", k, settings[k], positive=True) for k in ("t_final", "dt", "rtol", "atol"))
    if dt > t_final:
        raise rd.error("simulation", "dt", dt, f"an output step <= t_final = {t_final}")

    out_table = rd.table("outputs")
    rd.only("outputs", out_table, ("names", "tolerance"), "keys")
    names = out_table.get("names", list(_DEFAULT_OUTPUTS))
    signals = model.state_names + model.input_names + model.output_names
    if not isinstance(names, list) or not names or any(n not in signals for n in names):
        raise rd.error("outputs", "names", names, f"a non-empty list of signal names of the {kind} model {list(signals)}")
    tolerance = out_table.get("tolerance")
    if tolerance is not None:
        tolerance = rd.real("outputs", "tolerance", tolerance, positive=True)

    u = None
    amplitude, frequency = None, 0.0
    if "input" in data:
        in_table = dict(rd.table("input"))
        sine = rd.table("input.sine") if "sine" in in_table else {}
        in_table.pop("sine", None)
        rd.only("input", in_table, model.input_names, "input names (or the table 'sine')")
        u = np.array([rd.real("input", k, in_table.get(k, 0.0)) for k in model.input_names])
        if sine:
            rd.only("input.sine", sine, ("amplitude", "frequency"), "keys")
            amp = sine.get("amplitude", _MISSING)
            if not isinstance(amp, list) or len(amp) != model.nu:
                raise rd.error(
                    "input.sine", "amplitude", amp, f"a list of {model.nu} amplitudes [N.m] for {list(model.input_names)}"
                )
            amplitude = np.array([rd.real("input.sine", "amplitude", a) for a in amp])
            frequency = rd.real("input.sine", "frequency", sine.get("frequency", _MISSING), positive=True)

    extra = {k: v for k, v in data.items() if k not in _KNOWN_SECTIONS}
    return Scene(
        name=name,
        description=description,
        model=model,
        initial=MappingProxyType(initial),
        x0=_frozen(x0),
        t_final=t_final,
        dt=dt,
        method=method,
        rtol=rtol,
        atol=atol,
        outputs=tuple(names),
        tolerance=tolerance,
        u=None if u is None else _frozen(u),
        extra=MappingProxyType(extra),
        path=path,
        start=start,
        u_amplitude=None if amplitude is None else _frozen(amplitude),
        u_frequency=frequency,
    )

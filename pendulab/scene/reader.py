"""Reading and validating scene files (TOML): :func:`load_scene`."""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from .._checks import check_budget
from .._inputs import INPUTS, InputError
from ..integrate import METHODS
from ..model.model import make_model
from ..model.plant_file import load_plant
from .core import (
    _DEFAULT_OUTPUTS,
    _KNOWN_SECTIONS,
    _PARAM_CLASSES,
    _SIMULATION_DEFAULTS,
    FEATURE_SECTIONS,
    STARTS,
    Scene,
    _frozen,
    initial_state,
    scene_path,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["load_scene"]


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

    def declared(self, section: str, key: str, value: Any, name: str | None = None) -> Any:
        """``value`` checked against the declaration of input ``name`` (default ``key``), see pendulab._inputs."""
        spec = INPUTS[name or key]
        if value is _MISSING or isinstance(value, str) and spec.kind in ("real", "integer"):  # TOML is typed: "1.0" is a string
            raise self.error(section, key, value, spec.expected())
        try:
            return spec.check(value, f"[{section}] {key}")
        except InputError as exc:
            raise ValueError(f"scene file {str(self.path)!r}: {exc}") from None

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
        Malformed TOML, an unknown top-level section (e.g. a misspelt
        ``[simulaton]``), an unknown key in a known section, a wrong type, an
        unknown parameter or state name, a non-positive horizon, step or
        tolerance, an unknown method or output. The message names the file,
        the section, the key, the value and what was expected.

    Notes
    -----
    Top-level sections are those the reader validates (``scene``, ``model``,
    ``initial``, ``simulation``, ``outputs``, ``input``) plus the feature
    sections listed in :data:`pendulab.scene.core.FEATURE_SECTIONS`
    (``task``, ``validation``), which are kept unvalidated in
    ``Scene.extra`` for their feature. A new feature that stores settings in
    scene files adds its section name to ``FEATURE_SECTIONS``.

    Examples
    --------
    >>> from pathlib import Path
    >>> from pendulab.scene import load_scene
    >>> scene = load_scene("seed_paper")  # a shipped scene by name
    >>> scene.kind, scene.t_final, scene.method, scene.outputs
    ('elastic', 10.0, 'cvodes', ('theta1', 'theta2', 'x2', 'y2'))

    A scene file of your own (unstated settings take their defaults):

    >>> _ = Path("light.toml").write_text('''
    ... [model]
    ... kind = "rigid"
    ... [model.params]
    ... m2 = 0.5
    ... [initial]
    ... theta1 = 0.3
    ... ''')
    >>> mine = load_scene("light.toml")
    >>> mine.name, mine.model.params.m2, mine.x0, mine.t_final
    ('light', 0.5, array([0.3, 0. , 0. , 0. ]), 10.0)

    A misspelt section is refused, not ignored:

    >>> _ = Path("typo.toml").write_text('''
    ... [model]
    ... kind = "rigid"
    ... [simulaton]
    ... t_final = 5.0
    ... ''')
    >>> load_scene("typo.toml")
    Traceback (most recent call last):
        ...
    ValueError: scene file 'typo.toml': unknown section [simulaton] = {'t_final': 5.0}: expected one of the sections [...]
    """
    path = scene_path(path_or_name)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"scene file {str(path)!r}: malformed TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ValueError(f"scene file {str(path)!r}: not UTF-8 text: {exc}") from None
    rd = _Reader(path, data)
    allowed = (*_KNOWN_SECTIONS, *FEATURE_SECTIONS)
    for section, value in data.items():
        if section not in allowed:
            shown = repr(dict(value)) if isinstance(value, Mapping) else repr(value)
            raise ValueError(
                f"scene file {str(path)!r}: unknown section [{section}] = {shown}: expected one of the sections "
                f"{list(_KNOWN_SECTIONS)} or a feature section {list(FEATURE_SECTIONS)}"
            )

    head = rd.table("scene")
    rd.only("scene", head, ("name", "description"), "keys")
    name = rd.string("scene", "name", head.get("name", path.stem))
    description = rd.string("scene", "description", head.get("description", ""))

    model_table = rd.table("model", required=True)
    rd.only("model", model_table, ("kind", "params", "plant"), "keys")
    kind = rd.string("model", "kind", model_table.get("kind", _MISSING), tuple(_PARAM_CLASSES))
    params_table = rd.table("model.params")
    rd.only("model.params", params_table, _PARAM_CLASSES[kind].names(), f"{kind} parameters")
    params = {k: rd.real("model.params", k, v) for k, v in params_table.items()}
    if "plant" in model_table:
        # An identified robot (pendulab identify's plant.json, relative to the scene file); [model.params] override it.
        plant = rd.string("model", "plant", model_table["plant"])
        if kind != "rigid":
            raise rd.error("model", "plant", plant, "kind = 'rigid' (a plant file describes a rigid robot)")
        try:
            params = {**load_plant(path.parent / plant).rigid_kwargs(), **params}
        except (OSError, ValueError, KeyError) as exc:
            raise rd.error("model", "plant", plant, f"a valid plant file ({exc.args[0] if exc.args else exc})") from None
    try:
        model = make_model(kind, **params)
    except (ValueError, TypeError) as exc:
        raise ValueError(f"scene file {str(path)!r}: [model.params]: {exc}") from None

    init_table = dict(rd.table("initial"))
    start = rd.string("initial", "start", init_table.pop("start", "static"), STARTS if kind == "elastic" else ("static",))
    rd.only("initial", init_table, model.state_names, f"{kind} state names (or 'start')")
    initial = {k: rd.declared("initial", k, v, "state") for k, v in init_table.items()}
    if start == "quasi-static" and ({"r1", "r2"} & set(initial)):
        raise rd.error("initial", "start", start, "no stated r1, r2 with a quasi-static start (it sets them)")
    x0 = initial_state(model, initial, start)
    if kind == "elastic" and np.any(x0[2:4] <= 0):
        raise rd.error("initial", "r1/r2", x0[2:4].tolist(), "spring lengths > 0 m")

    sim = rd.table("simulation")
    rd.only("simulation", sim, tuple(_SIMULATION_DEFAULTS), "keys")
    settings = {**_SIMULATION_DEFAULTS, **sim}
    method = rd.string("simulation", "method", settings["method"], ("auto", *METHODS))
    t_final, dt, rtol, atol = (rd.declared("simulation", k, settings[k]) for k in ("t_final", "dt", "rtol", "atol"))
    if dt > t_final:
        raise rd.error("simulation", "dt", dt, f"an output step <= t_final = {t_final}")
    # The output grid every run of the scene allocates, budgeted when the file is read (not at the first run).
    where = f"scene file {str(rd.path)!r}: [simulation] t_final / dt"
    check_budget("output_points", where, f"{t_final:g} / {dt:g}", t_final / dt + 1.0)

    out_table = rd.table("outputs")
    rd.only("outputs", out_table, ("names", "tolerance"), "keys")
    names = out_table.get("names", list(_DEFAULT_OUTPUTS))
    signals = model.state_names + model.input_names + model.output_names
    if not isinstance(names, list) or not names or any(n not in signals for n in names):
        raise rd.error("outputs", "names", names, f"a non-empty list of signal names of the {kind} model {list(signals)}")
    tolerance = out_table.get("tolerance")
    if tolerance is not None:
        tolerance = rd.declared("outputs", "tolerance", tolerance)

    u = None
    amplitude, frequency = None, 0.0
    if "input" in data:
        in_table = dict(rd.table("input"))
        sine = rd.table("input.sine") if "sine" in in_table else {}
        in_table.pop("sine", None)
        rd.only("input", in_table, model.input_names, "input names (or the table 'sine')")
        u = np.array([rd.declared("input", k, in_table.get(k, 0.0), "torque") for k in model.input_names])
        if sine:
            rd.only("input.sine", sine, ("amplitude", "frequency"), "keys")
            amp = sine.get("amplitude", _MISSING)
            if not isinstance(amp, list) or len(amp) != model.nu:
                raise rd.error(
                    "input.sine", "amplitude", amp, f"a list of {model.nu} amplitudes [N.m] for {list(model.input_names)}"
                )
            amplitude = np.array([rd.declared("input.sine", "amplitude", a, "torque") for a in amp])
            frequency = rd.declared("input.sine", "frequency", sine.get("frequency", _MISSING))

    extra = {k: v for k, v in data.items() if k in FEATURE_SECTIONS}
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

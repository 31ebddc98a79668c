"""The one scene type: :class:`Scene`, its initial-state rule and the catalogue of shipped scenes."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from ..integrate import simulate, time_grid
from ..integrate.simulate import InputSpec, TimeInput
from ..integrate.trajectory import Trajectory
from ..model.model import Model, make_model
from ..model.params import ElasticParams, RigidParams
from ..model.quasistatic import quasi_static_state

__all__ = [
    "Scene",
    "list_scenes",
    "default_scene",
    "scene_path",
    "initial_state",
    "SCENE_DIR",
    "STARTS",
    "GROUPS",
    "FEATURE_SECTIONS",
    "SINE_HOLDS_PER_PERIOD",
]

#: Directory of the scenes shipped with the package.
SCENE_DIR = Path(__file__).resolve().parent.parent / "scenes"

_PARAM_CLASSES = {"rigid": RigidParams, "elastic": ElasticParams}
_SIMULATION_DEFAULTS: Mapping[str, Any] = MappingProxyType(
    {"t_final": 10.0, "dt": 0.01, "method": "auto", "rtol": 1e-8, "atol": 1e-8}
)
_DEFAULT_OUTPUTS = ("theta1", "theta2")
#: Top-level sections the reader itself validates.
_KNOWN_SECTIONS = ("scene", "model", "initial", "simulation", "outputs", "input")
#: Top-level sections owned by a feature, kept unvalidated in ``Scene.extra`` for it (the feature
#: checks their keys): ``task`` (swing-up tasks, :mod:`pendulab.control.swingup.tasks`) and
#: ``validation`` (FMU validation scenes, :mod:`pendulab.fmu.validate`). A new feature that reads
#: its own section from scene files registers the section name here; any other top-level section
#: is an error (a misspelt ``[simulaton]`` must not be silently ignored).
FEATURE_SECTIONS: tuple[str, ...] = ("task", "validation")
#: How unstated spring lengths are set at t = 0: static hanging length, rest length L (excites
#: the spring mode), or quasi-static (zero radial acceleration at the initial angles and rates).
STARTS: tuple[str, ...] = ("static", "rest-length", "quasi-static")
#: A scene's ``[input.sine]`` is held at most 1 / (SINE_HOLDS_PER_PERIOD f) [s] when simulated: the held sine's
#: fundamental is sinc(pi / 100) = 1 - 1.6e-4 of the true amplitude, whatever the output step.
SINE_HOLDS_PER_PERIOD = 100
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
        The feature sections (:data:`FEATURE_SECTIONS`: ``task``, ``validation``)
        present in the file, unvalidated, for the feature that uses them.
    path : Path or None
        The file the scene came from.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.scene import load_scene
    >>> scene = load_scene("seed_paper")
    >>> scene.name, scene.kind, scene.start
    ('seed_paper', 'elastic', 'static')
    >>> scene.x0  # stated: both angles 1.2 rad, springs at their rest length 1 m
    array([1.2, 1.2, 1. , 1. , 0. , 0. , 0. , 0. ])
    >>> stiffer = scene.with_settings(k1=2000.0, k2=2000.0)  # parameters and initial values by name
    >>> traj = stiffer.simulate(t_final=2.0)  # pendulab.simulate with the scene's settings
    >>> float(traj.t[-1]), traj.method
    (2.0, 'cvodes')
    >>> e = stiffer.model.energy(traj.x)
    >>> bool(np.ptp(e) < 1e-6)  # undamped: energy conserved to the scene's tolerances [J]
    True
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
        ``u_amplitude * sin(2 pi u_frequency t)``: the values at ``t`` (a
        co-simulation master, e.g. ``pendulab fmu validate``, holds row k over
        ``[t_k, t_k+1)``; :meth:`simulate` uses :meth:`input_spec` instead).

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

    def input_spec(self) -> InputSpec:
        """The scene's torques as :func:`pendulab.simulate` takes them: defined in time, not on a grid.

        Returns
        -------
        None, ndarray of shape (nu,), or TimeInput
            None without ``[input]``; the constant torques [N.m] without
            ``[input.sine]``; with a sine, a
            :class:`~pendulab.integrate.simulate.TimeInput` of :meth:`inputs`
            held at most ``1 / (SINE_HOLDS_PER_PERIOD * u_frequency)`` s, so that
            any horizon, output step or method runs the same input.
        """
        if self.u_amplitude is None:
            return self.u
        return TimeInput(self.inputs, 1.0 / (SINE_HOLDS_PER_PERIOD * self.u_frequency))

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
            ``options``); defaults come from the scene. The scene's input is
            defined in time (:meth:`input_spec`), so it follows a changed
            ``t_final``, ``dt`` or ``method``.

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
            "u": self.input_spec(),
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

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.scene import initial_state
    >>> model = pl.elastic()  # k1 = k2 = 500 N/m
    >>> for start in ("static", "rest-length", "quasi-static"):  # how the unstated spring lengths are set
    ...     print(start, np.round(initial_state(model, {"theta1": 1.0}, start)[2:4], 4))
    static [1.0392 1.0196]
    rest-length [1. 1.]
    quasi-static [1.0124 1.0034]
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

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.scene import default_scene
    >>> scene = default_scene("elastic")
    >>> scene.name, scene.t_final, scene.dt, scene.method
    ('elastic_default', 10.0, 0.01, 'auto')
    >>> np.round(scene.x0[:4], 5)  # hanging at rest, springs at their static lengths [rad, m]
    array([0.     , 0.     , 1.03924, 1.01962])
    >>> traj = scene.with_settings(theta1=0.5, k1=2000.0).simulate(t_final=2.0)
    >>> traj.x.shape
    (201, 8)
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

    Examples
    --------
    >>> from pendulab.scene import list_scenes, load_scene
    >>> names = list_scenes()
    >>> len(names), names[:4]
    (15, ('elastic_soft', 'elastic_stiff', 'rigid_chaotic', 'rigid_regular'))
    >>> list_scenes("validation")  # a group: the FMU validation scenes
    ('validation/elastic_soft_forced', 'validation/elastic_stiff_forced',
     'validation/rigid_chaotic_forced', 'validation/rigid_forced')
    >>> load_scene(names[2]).kind
    'rigid'
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

    Examples
    --------
    >>> from pendulab.scene import scene_path
    >>> scene_path("seed_paper").name
    'seed_paper.toml'
    >>> scene_path("bench/rigid_chaotic_10s.toml").parent.name
    'bench'
    >>> scene_path("no_such_scene")
    Traceback (most recent call last):
        ...
    FileNotFoundError: scene 'no_such_scene': no such file and no shipped scene of that name; shipped: [...]
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

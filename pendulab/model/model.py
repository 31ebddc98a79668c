"""The ``Model``: compiled CasADi functions of one symbolic pendulum plus its parameters.

Every downstream tool (integrators, linearization, optimal control, FMU code
generation, plots) consumes a ``Model``. Its CasADi Functions take the
parameter vector ``p`` as an explicit input so that parameters stay tunable
(FMU, optimal control); the NumPy conveniences evaluate them at
``model.params``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cache, cached_property
from typing import Any

import casadi as ca
import numpy as np

from .builders import SymbolicModel, build_elastic, build_rigid
from .params import ElasticParams, ParamInfo, RigidParams, param_table
from .statics import static_spring_lengths

__all__ = ["Model", "rigid", "elastic", "make_model", "model_functions", "INPUT_NAMES", "ACTUATIONS"]

INPUT_NAMES: tuple[str, ...] = ("tau1", "tau2")
#: Which of (tau1, tau2) each actuation drives.
ACTUATIONS: Mapping[str, tuple[int, ...]] = {"full": (0, 1), "pendubot": (0,), "acrobot": (1,)}

_STATE_UNITS = {"theta": "rad", "omega": "rad/s", "r": "m", "v": "m/s"}
_STATE_DESCRIPTIONS = {
    "theta1": "absolute angle of link 1 from the downward vertical",
    "theta2": "absolute angle of link 2 from the downward vertical",
    "omega1": "angular velocity of link 1",
    "omega2": "angular velocity of link 2",
    "r1": "length of spring 1",
    "r2": "length of spring 2",
    "v1": "rate of change of spring 1 length",
    "v2": "rate of change of spring 2 length",
}
_OUTPUT_INFO = {
    "x1": ("m", "horizontal position of the end of link 1 (bob 1)"),
    "y1": ("m", "vertical position of the end of link 1 (bob 1), up positive"),
    "x2": ("m", "horizontal position of the end of link 2 (bob 2)"),
    "y2": ("m", "vertical position of the end of link 2 (bob 2), up positive"),
    "energy": ("J", "total mechanical energy (kinetic + gravity + springs)"),
    "stretch1": ("m", "extension of spring 1 beyond its rest length"),
    "stretch2": ("m", "extension of spring 2 beyond its rest length"),
}
_INPUT_INFO = {
    "tau1": ("N.m", "torque between ground and link 1"),
    "tau2": ("N.m", "torque between link 1 and link 2"),
}


@dataclass(frozen=True)
class SignalInfo:
    """Name, unit and description of a state, input or output."""

    name: str
    unit: str
    description: str


def _state_unit(name: str) -> str:
    return _STATE_UNITS[name.rstrip("0123456789")]


@cache
def model_functions(kind: str) -> dict[str, ca.Function]:
    """CasADi Functions of one model kind, built once per process."""
    sym: SymbolicModel = build_rigid() if kind == "rigid" else build_elastic()
    x, u, p = sym.x, sym.u, sym.p
    energy = sym.kinetic + sym.potential
    outputs = [sym.positions, energy]
    if kind == "elastic":
        outputs.append(sym.stretch)
    y = ca.vertcat(*outputs)
    xdot = sym.xdot
    return {
        "rhs": ca.Function("rhs", [x, u, p], [xdot], ["x", "u", "p"], ["xdot"]),
        "outputs": ca.Function("outputs", [x, u, p], [y], ["x", "u", "p"], ["y"]),
        "jac_rhs": ca.Function(
            "jac_rhs",
            [x, u, p],
            [ca.jacobian(xdot, x), ca.jacobian(xdot, u)],
            ["x", "u", "p"],
            ["A", "B"],
        ),
        "mass_matrix": ca.Function("mass_matrix", [x, p], [sym.eom.M], ["x", "p"], ["M"]),
        "bias": ca.Function("bias", [x, p], [sym.eom.bias], ["x", "p"], ["bias"]),
        "kinetic": ca.Function("kinetic", [x, p], [sym.kinetic], ["x", "p"], ["T"]),
        "potential": ca.Function("potential", [x, p], [sym.potential], ["x", "p"], ["V"]),
        "spring_energy": ca.Function("spring_energy", [x, p], [sym.spring], ["x", "p"], ["V_spring"]),
        "energy": ca.Function("energy", [x, p], [energy], ["x", "p"], ["E"]),
        "positions": ca.Function("positions", [x, p], [sym.positions], ["x", "p"], ["pos"]),
        "stretch": ca.Function("stretch", [x, p], [sym.stretch], ["x", "p"], ["stretch"]),
        "dissipation": ca.Function("dissipation", [x, p], [sym.dissipation], ["x", "p"], ["P_diss"]),
        "power_in": ca.Function("power_in", [x, u, p], [sym.power_in], ["x", "u", "p"], ["P_in"]),
    }


@dataclass(frozen=True)
class Model:
    """A rigid or elastic double pendulum with numeric parameters.

    Use the factories :func:`rigid` and :func:`elastic`. Change parameters with
    :meth:`with_params` (the CasADi functions are shared, not rebuilt).

    Attributes
    ----------
    kind : {"rigid", "elastic"}
    params : RigidParams or ElasticParams
    functions : dict of casadi.Function
        ``rhs(x, u, p) -> xdot``, ``outputs(x, u, p) -> y``,
        ``jac_rhs(x, u, p) -> (A, B)``, ``mass_matrix(x, p)``, ``bias(x, p)``,
        ``kinetic``/``potential``/``spring_energy``/``energy(x, p)`` [J],
        ``positions(x, p)`` [m], ``stretch(x, p)`` [m],
        ``dissipation(x, p)`` [W], ``power_in(x, u, p)`` [W].
    """

    kind: str
    params: RigidParams | ElasticParams
    functions: Mapping[str, ca.Function] = field(repr=False, compare=False)

    # -- names ---------------------------------------------------------------
    @property
    def symbolic(self) -> SymbolicModel:
        """The symbolic expressions (read-only; do not create new physics symbols)."""
        return build_rigid() if self.kind == "rigid" else build_elastic()

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.symbolic.state_names

    @property
    def input_names(self) -> tuple[str, ...]:
        return INPUT_NAMES

    @property
    def output_names(self) -> tuple[str, ...]:
        base = ("x1", "y1", "x2", "y2", "energy")
        return base + (("stretch1", "stretch2") if self.kind == "elastic" else ())

    @property
    def param_names(self) -> tuple[str, ...]:
        return type(self.params).names()

    @property
    def param_info(self) -> tuple[ParamInfo, ...]:
        return param_table(self.params)

    @property
    def state_info(self) -> tuple[SignalInfo, ...]:
        return tuple(SignalInfo(n, _state_unit(n), _STATE_DESCRIPTIONS[n]) for n in self.state_names)

    @property
    def input_info(self) -> tuple[SignalInfo, ...]:
        return tuple(SignalInfo(n, *_INPUT_INFO[n]) for n in self.input_names)

    @property
    def output_info(self) -> tuple[SignalInfo, ...]:
        return tuple(SignalInfo(n, *_OUTPUT_INFO[n]) for n in self.output_names)

    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def nq(self) -> int:
        return self.nx // 2

    @property
    def nu(self) -> int:
        return len(INPUT_NAMES)

    @property
    def ny(self) -> int:
        return len(self.output_names)

    @cached_property
    def p(self) -> np.ndarray:
        """Parameter vector, shape (np,), in ``param_names`` order."""
        return self.params.as_vector()

    def with_params(self, **changes: float) -> Model:
        """Return a model with some parameters changed (validated)."""
        return Model(self.kind, self.params.replace(**changes), self.functions)

    def signal_index(self, name: str) -> tuple[str, int]:
        """Locate a named signal: ("state"|"input"|"output", index)."""
        for group, names in (("state", self.state_names), ("input", self.input_names), ("output", self.output_names)):
            if name in names:
                return group, names.index(name)
        raise KeyError(
            f"unknown signal {name!r} for the {self.kind} model; states {list(self.state_names)}, "
            f"inputs {list(self.input_names)}, outputs {list(self.output_names)}"
        )

    # -- argument checks -------------------------------------------------------
    def check_state(self, x: Any, name: str = "x") -> np.ndarray:
        """Return x as float array of shape (nx,) or (N, nx); raise ValueError otherwise."""
        return _check_array(x, self.nx, name, self.state_names)

    def check_input(self, u: Any, name: str = "u") -> np.ndarray:
        """Return u as float array of shape (nu,) or (N, nu); ``None`` means zero torque."""
        if u is None:
            return np.zeros(self.nu)
        return _check_array(u, self.nu, name, self.input_names)

    # -- numeric conveniences -------------------------------------------------
    def _eval(self, fname: str, x: Any, u: Any = None, with_u: bool = False) -> np.ndarray:
        X = self.check_state(x)
        f = self.functions[fname]
        if with_u:
            U = self.check_input(u)
            if X.ndim == 1 and U.ndim == 1:
                return np.asarray(f(X, U, self.p)).ravel()
            N = X.shape[0] if X.ndim == 2 else U.shape[0]
            Xb = np.broadcast_to(X, (N, self.nx)).T
            Ub = np.broadcast_to(U, (N, self.nu)).T
            return np.asarray(f.map(N)(Xb, Ub, self.p)).T
        if X.ndim == 1:
            return np.asarray(f(X, self.p)).squeeze()
        return np.asarray(f.map(X.shape[0])(X.T, self.p)).T

    def rhs(self, x: Any, u: Any = None) -> np.ndarray:
        """State derivative f(x, u), shape (nx,) or (N, nx)."""
        return self._eval("rhs", x, u, with_u=True)

    def outputs(self, x: Any, u: Any = None) -> np.ndarray:
        """Outputs y(x, u) in ``output_names`` order, shape (ny,) or (N, ny)."""
        return self._eval("outputs", x, u, with_u=True)

    def mass_matrix(self, x: Any) -> np.ndarray:
        """Mass matrix M(q), shape (nq, nq) (x must be a single state)."""
        return np.asarray(self.functions["mass_matrix"](self.check_state(x), self.p))

    def energy(self, x: Any) -> float | np.ndarray:
        """Total mechanical energy incl. springs [J]; float, or shape (N,) for a batch."""
        e = self._eval("energy", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def kinetic_energy(self, x: Any) -> float | np.ndarray:
        """Kinetic energy [J]."""
        e = self._eval("kinetic", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def potential_energy(self, x: Any) -> float | np.ndarray:
        """Gravitational plus spring potential energy [J]."""
        e = self._eval("potential", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def spring_energy(self, x: Any) -> float | np.ndarray:
        """Spring potential energy [J] (zero for the rigid model)."""
        e = self._eval("spring_energy", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def positions(self, x: Any) -> np.ndarray:
        """x1, y1, x2, y2 [m], shape (4,) or (N, 4)."""
        return self._eval("positions", x)

    def stretch(self, x: Any) -> np.ndarray:
        """Spring extensions r - L [m], shape (2,) or (N, 2)."""
        return self._eval("stretch", x)

    def dissipation(self, x: Any) -> float | np.ndarray:
        """Power dissipated by all dampers [W]."""
        e = self._eval("dissipation", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def power_in(self, x: Any, u: Any = None) -> float | np.ndarray:
        """Power delivered by the torques tau1 w1 + tau2 (w2 - w1) [W]."""
        e = self._eval("power_in", x, u, with_u=True)
        return float(e[0]) if e.size == 1 else e.ravel()

    def rest_state(self) -> np.ndarray:
        """Hanging straight down at rest, springs at their static length, shape (nx,)."""
        x = np.zeros(self.nx)
        if self.kind == "elastic":
            x[2:4] = static_spring_lengths(self.params)
        return x

    def state(self, **values: float) -> np.ndarray:
        """Build a state by name; unspecified entries come from :meth:`rest_state`.

        For the elastic model, unspecified spring lengths default to the static
        hanging lengths.
        """
        x = self.rest_state()
        for name, value in values.items():
            if name not in self.state_names:
                raise ValueError(
                    f"unknown state name {name!r} for the {self.kind} model; expected one of {list(self.state_names)}"
                )
            x[self.state_names.index(name)] = float(value)
        return self.check_state(x)


def _check_array(a: Any, n: int, name: str, names: tuple[str, ...]) -> np.ndarray:
    try:
        arr = np.asarray(a, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric with {n} entries {list(names)}, got {a!r}") from exc
    if arr.ndim not in (1, 2) or arr.shape[-1] != n:
        raise ValueError(f"{name} must have shape ({n},) or (N, {n}) with entries {list(names)}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name} must be finite, got non-finite value {arr[tuple(bad)]!r} at index {tuple(bad.tolist())}")
    return arr


def make_model(kind: str, **params: float) -> Model:
    """Build a ``Model`` of kind ``"rigid"`` or ``"elastic"`` with parameters by name."""
    classes = {"rigid": RigidParams, "elastic": ElasticParams}
    if kind not in classes:
        raise ValueError(f"unknown model kind {kind!r}; expected one of {sorted(classes)}")
    cls = classes[kind]
    unknown = sorted(set(params) - set(cls.names()))
    if unknown:
        raise ValueError(f"unknown parameter name(s) {unknown} for the {kind} model; expected one of {list(cls.names())}")
    return Model(kind, cls(**params), model_functions(kind))


def rigid(**params: float) -> Model:
    """Rigid double pendulum (2 DOF); parameters as in :class:`RigidParams`."""
    return make_model("rigid", **params)


def elastic(**params: float) -> Model:
    """Elastic (spring-link) double pendulum (4 DOF); parameters as in :class:`ElasticParams`."""
    return make_model("elastic", **params)

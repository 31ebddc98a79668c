"""The ``Model``: compiled CasADi functions of one symbolic pendulum plus its parameters.

Every downstream tool (integrators, linearization, optimal control, FMU code
generation, plots) consumes a ``Model``. Its CasADi Functions take the
parameter vector ``p`` as an explicit input so that parameters stay tunable
(FMU, optimal control); the NumPy conveniences evaluate them at
``model.params``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from .._checks import check_spring_lengths
from .builders import SymbolicModel, build_elastic, build_rigid
from .functions import _scalar, _vectorized, model_functions
from .params import ElasticParams, ParamInfo, RigidParams, param_table
from .plant_file import load_plant
from .signals import _INPUT_INFO, _OUTPUT_INFO, _STATE_DESCRIPTIONS, ACTUATIONS, INPUT_NAMES, SignalInfo, _state_unit
from .statics import static_spring_lengths

__all__ = ["Model", "rigid", "elastic", "make_model", "model_functions", "INPUT_NAMES", "ACTUATIONS"]


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

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid(m2=0.5)
    >>> model.kind, model.state_names, model.input_names
    ('rigid', ('theta1', 'theta2', 'omega1', 'omega2'), ('tau1', 'tau2'))
    >>> x = model.state(theta1=np.pi / 3)  # link 1 raised by 60 degrees, link 2 hanging, at rest
    >>> np.round(model.positions(x), 3)  # x1, y1, x2, y2 [m]
    array([ 0.866, -0.5  ,  0.866, -1.5  ])
    >>> lift = model.potential_energy(x) - model.potential_energy(model.rest_state())
    >>> print(f"{lift:.4f} J, analytic {(1.0 + 0.5) * 9.81 * (1 - np.cos(np.pi / 3)):.4f} J")  # (m1 + m2) g L1 (1 - cos 60)
    7.3575 J, analytic 7.3575 J
    >>> heavier = model.with_params(m2=2.0)  # a copy sharing the CasADi functions
    >>> heavier.params.m2, heavier.functions is model.functions
    (2.0, True)
    """

    kind: str
    params: RigidParams | ElasticParams
    functions: Mapping[str, ca.Function] = field(repr=False, compare=False)

    # -- names ---------------------------------------------------------------
    @property
    def symbolic(self) -> SymbolicModel:
        """The symbolic expressions (read-only; do not create new physics symbols)."""
        return build_rigid() if self.kind == "rigid" else build_elastic()

    # Names and sizes are cached: the hot paths (simulate, the controllers' checks) read them on every call.
    @cached_property
    def state_names(self) -> tuple[str, ...]:
        return self.symbolic.state_names

    @property
    def input_names(self) -> tuple[str, ...]:
        return INPUT_NAMES

    @cached_property
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

    @cached_property
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
        """Return a copy of the model with some parameters changed.

        The CasADi functions are shared with ``self``, not rebuilt.

        Parameters
        ----------
        **changes : float
            New parameter values by name, in SI units (see :attr:`param_info`).

        Returns
        -------
        Model
            Model of the same kind with the changed, validated parameters.

        Raises
        ------
        ValueError
            An unknown parameter name, or a value that is non-finite or out of
            its admissible range.
        TypeError
            A value that is not a real number.
        """
        return Model(self.kind, self.params.replace(**changes), self.functions)

    def signal_index(self, name: str) -> tuple[str, int]:
        """Locate a named state, input or output signal.

        Parameters
        ----------
        name : str
            Signal name, e.g. ``"theta1"``, ``"tau2"`` or ``"energy"``.

        Returns
        -------
        group : {"state", "input", "output"}
            Which vector the signal belongs to (searched in that order).
        index : int
            Position in ``state_names``, ``input_names`` or ``output_names``.

        Raises
        ------
        KeyError
            ``name`` is not a state, input or output of this model.
        """
        for group, names in (("state", self.state_names), ("input", self.input_names), ("output", self.output_names)):
            if name in names:
                return group, names.index(name)
        raise KeyError(
            f"unknown signal {name!r} for the {self.kind} model; states {list(self.state_names)}, "
            f"inputs {list(self.input_names)}, outputs {list(self.output_names)}"
        )

    # -- argument checks -------------------------------------------------------
    def check_state(self, x: Any, name: str = "x") -> np.ndarray:
        """Validate a state or a batch of states.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order [rad, m, rad/s, m/s].
        name : str, default "x"
            Argument name used in error messages.

        Returns
        -------
        ndarray of float, shape (nx,) or (N, nx)
            ``x`` as a float array.

        Raises
        ------
        ValueError
            ``x`` is not numeric, has the wrong shape or a non-finite entry.
        """
        return _check_array(x, self.nx, name, self.state_names)

    def check_start(self, x: Any, name: str = "x0") -> np.ndarray:
        """Validate a start state (or a batch of them) as :func:`pendulab.simulate` does before any run.

        The one start-state check of every entry point that integrates (simulate, ensembles,
        Lyapunov exponents, the Gymnasium env): shape and finiteness (:meth:`check_state`), spring
        lengths > 0 for the elastic model, and a finite right-hand side at the state (a spring length
        or stiffness so close to zero that the dynamics overflow is refused here, naming the state,
        instead of failing deep inside a solver).

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order [rad, m, rad/s, m/s].
        name : str, default "x0"
            Argument name used in error messages.

        Returns
        -------
        ndarray of float, shape (nx,) or (N, nx)
            ``x`` as a float array.

        Raises
        ------
        ValueError
            Bad shape, a non-finite entry, a spring length <= 0, or a non-finite right-hand side.
        """
        X = self.check_state(x, name)
        check_spring_lengths(self.kind, X, name)
        if X.ndim == 1:
            # One state (every simulate call): the straight-line Python of the same graph costs ~4 us against
            # ~40 us for a CasADi call; there an overflow or a division by zero raises instead of giving inf.
            try:
                f = _scalar(self.kind, "rhs")(X.tolist(), [0.0] * self.nu, self.p.tolist()).tolist()
            except (ArithmeticError, ValueError):
                f = [math.nan]
            if all(map(math.isfinite, f)):  # one point: ~1 us of plain Python against ~5 us of NumPy reductions
                return X
            raise self.not_finite_error(X, name)
        with np.errstate(all="ignore"):
            f = self.rhs(X)
        bad = ~np.isfinite(f).all(axis=-1)
        if np.any(bad):
            k = int(np.argmax(bad))
            raise self.not_finite_error(X[k], f"{name}[{k}]")
        return X

    def not_finite_error(self, x: np.ndarray, name: str, what: str = "the equations of motion are") -> ValueError:
        """The error of a state where the dynamics (or their linearization) overflow, naming the state.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            The state.
        name : str
            How the caller names it (``"x0"``, ``"x0[3]"``).
        what : str
            What is not finite there.

        Returns
        -------
        ValueError
            To raise.
        """
        state = ", ".join(f"{n}={v:.6g}" for n, v in zip(self.state_names, x, strict=True))
        return ValueError(
            f"{name}: {what} not finite at this state ({state}) with the model's parameters; expected spring lengths "
            "and stiffnesses well away from zero"
        )

    def check_input(self, u: Any, name: str = "u") -> np.ndarray:
        """Validate an input or a batch of inputs.

        Parameters
        ----------
        u : array_like, shape (nu,) or (N, nu), or None
            Torques (tau1, tau2) [N.m]; ``None`` means zero torque.
        name : str, default "u"
            Argument name used in error messages.

        Returns
        -------
        ndarray of float, shape (nu,) or (N, nu)
            ``u`` as a float array (zeros of shape (nu,) for ``None``).

        Raises
        ------
        ValueError
            ``u`` is not numeric, has the wrong shape or a non-finite entry.
        """
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
            # Many points: element-wise NumPy from the same graph (a mapped CasADi call costs ~10x more).
            return _vectorized(self.kind, fname)(Xb, Ub, self.p).T
        if X.ndim == 1:
            return np.asarray(f(X, self.p)).squeeze()
        return _vectorized(self.kind, fname)(X.T, self.p).T

    def rhs(self, x: Any, u: Any = None) -> np.ndarray:
        """Evaluate the state derivative dx/dt = f(x, u) at ``model.params``.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.
        u : array_like, shape (nu,) or (N, nu), optional
            Torques (tau1, tau2) [N.m] (default zero); broadcast against ``x``.

        Returns
        -------
        ndarray, shape (nx,) or (N, nx)
            State derivative(s) [rad/s, m/s, rad/s2, m/s2].
        """
        return self._eval("rhs", x, u, with_u=True)

    def outputs(self, x: Any, u: Any = None) -> np.ndarray:
        """Evaluate the outputs y(x, u) at ``model.params``.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.
        u : array_like, shape (nu,) or (N, nu), optional
            Torques (tau1, tau2) [N.m] (default zero); broadcast against ``x``.

        Returns
        -------
        ndarray, shape (ny,) or (N, ny)
            Outputs in ``output_names`` order: x1, y1, x2, y2 [m], energy [J]
            and, for the elastic model, stretch1, stretch2 [m].
        """
        return self._eval("outputs", x, u, with_u=True)

    def mass_matrix(self, x: Any) -> np.ndarray:
        """Evaluate the mass matrix M(q) of ``M(q) q'' = rhs``.

        Parameters
        ----------
        x : array_like, shape (nx,)
            A single state (only q is used).

        Returns
        -------
        ndarray, shape (nq, nq)
            Symmetric mass matrix in SI units (kg.m2 on angle entries, kg on
            spring-length entries).
        """
        return np.asarray(self.functions["mass_matrix"](self.check_state(x), self.p))

    def energy(self, x: Any) -> float | np.ndarray:
        """Total mechanical energy: kinetic + gravity + springs.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        float or ndarray, shape (N,)
            Energy [J]; a float for a single state. Gravity potential is zero
            at the pivot height.
        """
        e = self._eval("energy", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def kinetic_energy(self, x: Any) -> float | np.ndarray:
        """Kinetic energy.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        float or ndarray, shape (N,)
            Kinetic energy [J]; a float for a single state.
        """
        e = self._eval("kinetic", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def potential_energy(self, x: Any) -> float | np.ndarray:
        """Gravitational plus spring potential energy.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        float or ndarray, shape (N,)
            Potential energy [J], zero gravity potential at the pivot height;
            a float for a single state.
        """
        e = self._eval("potential", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def spring_energy(self, x: Any) -> float | np.ndarray:
        """Spring potential energy ``k1 (r1 - L1)**2 / 2 + k2 (r2 - L2)**2 / 2``.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        float or ndarray, shape (N,)
            Spring energy [J] (zero for the rigid model); a float for a single
            state.
        """
        e = self._eval("spring_energy", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def positions(self, x: Any) -> np.ndarray:
        """Cartesian positions of the link ends (bobs), y up, origin at the pivot.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        ndarray, shape (4,) or (N, 4)
            x1, y1, x2, y2 [m].
        """
        return self._eval("positions", x)

    def stretch(self, x: Any) -> np.ndarray:
        """Spring extensions beyond the rest lengths.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        ndarray, shape (2,) or (N, 2)
            ``r1 - L1, r2 - L2`` [m] (zeros for the rigid model).
        """
        return self._eval("stretch", x)

    def dissipation(self, x: Any) -> float | np.ndarray:
        """Power dissipated by all dampers (joints, and springs when elastic).

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.

        Returns
        -------
        float or ndarray, shape (N,)
            Dissipated power [W], non-negative; a float for a single state.
        """
        e = self._eval("dissipation", x)
        return float(e) if e.ndim == 0 else e.ravel()

    def power_in(self, x: Any, u: Any = None) -> float | np.ndarray:
        """Power delivered by the torques, ``tau1 omega1 + tau2 (omega2 - omega1)``.

        Parameters
        ----------
        x : array_like, shape (nx,) or (N, nx)
            State(s) in ``state_names`` order.
        u : array_like, shape (nu,) or (N, nu), optional
            Torques (tau1, tau2) [N.m] (default zero); broadcast against ``x``.

        Returns
        -------
        float or ndarray, shape (N,)
            Input power [W]; a float when there is a single value.
        """
        e = self._eval("power_in", x, u, with_u=True)
        return float(e[0]) if e.size == 1 else e.ravel()

    def rest_state(self) -> np.ndarray:
        """Equilibrium hanging straight down at rest.

        Returns
        -------
        ndarray, shape (nx,)
            Zero angles and rates; for the elastic model the spring lengths
            r1, r2 [m] carry the static gravity load.
        """
        x = np.zeros(self.nx)
        if self.kind == "elastic":
            x[2:4] = static_spring_lengths(self.params)
        return x

    def state(self, **values: float) -> np.ndarray:
        """Build a state by name; unspecified entries come from :meth:`rest_state`.

        For the elastic model, unspecified spring lengths default to the static
        hanging lengths.

        Parameters
        ----------
        **values : float
            State entries by name, e.g. ``theta1=3.0`` [rad], ``omega2=0.5``
            [rad/s], ``r1=1.02`` [m].

        Returns
        -------
        ndarray, shape (nx,)
            State in ``state_names`` order.

        Raises
        ------
        ValueError
            An unknown state name, or a non-finite value.
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
    if arr.ndim == 1 and all(map(math.isfinite, arr.tolist())):  # one state (every simulate call): no NumPy reduction
        return arr
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name} must be finite, got non-finite value {arr[tuple(bad)]!r} at index {tuple(bad.tolist())}")
    return arr


def make_model(kind: str, **params: float) -> Model:
    """Build a ``Model`` of the given kind with parameters by name.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    **params : float
        Parameter values by name in SI units (see :class:`RigidParams` and
        :class:`ElasticParams`); others keep their defaults.

    Returns
    -------
    Model
        The model, sharing the per-process cached CasADi functions of ``kind``.

    Raises
    ------
    ValueError
        An unknown ``kind`` or parameter name, or an invalid parameter value.
    TypeError
        A parameter value that is not a real number.

    Examples
    --------
    >>> import pendulab as pl
    >>> model = pl.make_model("elastic", k1=2000.0, k2=2000.0)  # as pl.elastic(k1=2000.0, k2=2000.0)
    >>> model.kind, model.nx, model.params.k1, model.params.m1
    ('elastic', 8, 2000.0, 1.0)
    >>> model.functions["rhs"] is pl.make_model("elastic").functions["rhs"]  # built once per process
    True
    >>> pl.make_model("rigid", k1=1.0)
    Traceback (most recent call last):
        ...
    ValueError: unknown parameter name(s) ['k1'] for the rigid model; expected one of ['m1', 'm2', ...]
    """
    classes = {"rigid": RigidParams, "elastic": ElasticParams}
    if kind not in classes:
        raise ValueError(f"unknown model kind {kind!r}; expected one of {sorted(classes)}")
    cls = classes[kind]
    unknown = sorted(set(params) - set(cls.names()))
    if unknown:
        raise ValueError(f"unknown parameter name(s) {unknown} for the {kind} model; expected one of {list(cls.names())}")
    return Model(kind, cls(**params), model_functions(kind))


def rigid(plant: str | os.PathLike[str] | None = None, **params: float) -> Model:
    """Rigid double pendulum (2 DOF), state (theta1, theta2, omega1, omega2).

    Parameters
    ----------
    plant : path-like, optional
        A plant file (``pendulab identify --out DIR`` writes ``DIR/plant.json``,
        :mod:`pendulab.model.plant_file`): the identified robot's links, friction and rotor
        inertia are the starting values, ``params`` override them.
    **params : float
        Parameter values by name in SI units, as in :class:`RigidParams`.

    Returns
    -------
    Model
        Model of kind ``"rigid"``.

    Raises
    ------
    ValueError
        An unknown parameter name or an invalid value (via :func:`make_model`), or a plant
        file that is not valid (:func:`pendulab.model.plant_file.load_plant`).
    FileNotFoundError
        No plant file at ``plant``.
    KeyError
        A plant file with a parameter missing or unknown.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid(m1=0.6, L1=0.3)
    >>> model.params.L1, model.params.m2  # the others keep their defaults
    (0.3, 1.0)
    >>> lift = model.energy(model.state(theta1=np.pi, theta2=np.pi)) - model.energy(model.rest_state())
    >>> round(lift, 4), round(2 * 9.81 * (0.6 * 0.3 + 1.0 * 1.3), 4)  # raising both links upright [J]
    (29.0376, 29.0376)
    >>> robot = pl.rigid(plant="c1")  # RealAIGym's C.1 robot as pendulab identified it (shipped plant)
    >>> robot.params.L1, robot.params.L2, robot.params.gr, robot.params.Ir > 0
    (0.2, 0.3, 6.0, True)
    """
    if plant is not None:
        params = {**load_plant(plant).rigid_kwargs(), **params}
    return make_model("rigid", **params)


def elastic(**params: float) -> Model:
    """Elastic (spring-link) double pendulum (4 DOF).

    The state is (theta1, theta2, r1, r2, omega1, omega2, v1, v2).

    Parameters
    ----------
    **params : float
        Parameter values by name in SI units, as in :class:`ElasticParams`.

    Returns
    -------
    Model
        Model of kind ``"elastic"``.

    Raises
    ------
    ValueError
        An unknown parameter name or an invalid value (via :func:`make_model`).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.elastic(k1=500.0, k2=500.0)
    >>> model.state_names
    ('theta1', 'theta2', 'r1', 'r2', 'omega1', 'omega2', 'v1', 'v2')
    >>> x0 = model.rest_state()  # hanging at rest: each spring carries the weight below it
    >>> print(np.round(x0[2:4], 5), round(1 + 2 * 9.81 / 500, 5), round(1 + 9.81 / 500, 5))
    [1.03924 1.01962] 1.03924 1.01962
    """
    return make_model("elastic", **params)

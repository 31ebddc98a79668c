"""Physical parameters of the double pendulum as validated, frozen dataclasses.

Every field carries its unit, a description and its admissible range as
metadata; that table (``param_table``) is the single source for CasADi parameter
vectors, FMU variables, CSV headers and plot labels.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._inputs import MAGNITUDE

__all__ = [
    "ParamInfo",
    "RigidParams",
    "ElasticParams",
    "param_table",
    "ordered_values",
]


@dataclass(frozen=True)
class ParamInfo:
    """Description of one physical parameter.

    Attributes
    ----------
    name : str
        Identifier, as used in ``--set name=value``, FMU variables and CSV.
    unit : str
        SI unit.
    description : str
        One-line meaning.
    positive : bool
        True when the value must be strictly positive, False when it must be
        non-negative.
    optional : bool
        True when ``None`` is accepted (meaning "derived from another value").
    """

    name: str
    unit: str
    description: str
    positive: bool
    optional: bool = False


def _p(default: Any, unit: str, description: str, *, positive: bool) -> Any:
    return field(
        default=default,
        metadata={"unit": unit, "description": description, "positive": positive},
    )


def param_table(params_or_cls: Any) -> tuple[ParamInfo, ...]:
    """Return the name/unit/description table of a parameter class or instance.

    Parameters
    ----------
    params_or_cls : RigidParams or ElasticParams, or either class
        Parameter dataclass (instance or type) whose fields carry the metadata.

    Returns
    -------
    tuple of ParamInfo
        One entry per field, in parameter-vector order.
    """
    out = []
    for f in dataclasses.fields(params_or_cls):
        out.append(
            ParamInfo(
                name=f.name,
                unit=f.metadata["unit"],
                description=f.metadata["description"],
                positive=f.metadata["positive"],
                optional=f.default is None,
            )
        )
    return tuple(out)


def ordered_values(params_cls: type, values: dict[str, Any]) -> list[Any]:
    """Values by name (numbers or CasADi expressions) in the class's vector order, defaults filled in.

    Code that builds a parameter vector (e.g. a symbolic one for a CasADi Function) goes through
    this, never by position, so a parameter added to a class cannot shift what it means.

    Parameters
    ----------
    params_cls : type
        :class:`RigidParams` or :class:`ElasticParams`.
    values : dict of str to Any
        Values by parameter name; the others take the class's defaults.

    Returns
    -------
    list
        One entry per ``params_cls.names()``.

    Raises
    ------
    ValueError
        An unknown name, or a missing one whose default is derived (``None``, e.g. ``lc1``).
    """
    unknown = sorted(set(values) - set(params_cls.names()))
    if unknown:
        raise ValueError(f"unknown parameter name(s) {unknown} for {params_cls.__name__}; expected {list(params_cls.names())}")
    out = []
    for f in dataclasses.fields(params_cls):
        value = values.get(f.name, f.default)
        if value is None:
            raise ValueError(f"{params_cls.__name__}.{f.name} has a derived default; give its value")
        out.append(value)
    return out


class _ParamsBase:
    """Validation and vector conversion shared by the parameter classes."""

    def __post_init__(self) -> None:
        for info in param_table(self):
            value = getattr(self, info.name)
            if value is None and info.optional:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise TypeError(
                    f"parameter {info.name!r} must be a real number [{info.unit}], got {value!r} of type {type(value).__name__}"
                )
            value = float(value)
            if not math.isfinite(value):
                raise ValueError(f"parameter {info.name!r} must be finite, got {value!r}")
            if value != 0.0 and not MAGNITUDE[0] <= abs(value) <= MAGNITUDE[1]:
                # pendulab._inputs: squares, products and inverses of parameters must stay finite and non-zero.
                raise ValueError(
                    f"parameter {info.name!r} = {value!r} [{info.unit}]: its square or inverse would overflow or underflow; "
                    f"expected a magnitude in [{MAGNITUDE[0]:g}, {MAGNITUDE[1]:g}] or 0"
                )
            if info.positive and value <= 0.0:
                raise ValueError(f"parameter {info.name!r} must be > 0 [{info.unit}] ({info.description}), got {value!r}")
            if not info.positive and value < 0.0:
                raise ValueError(f"parameter {info.name!r} must be >= 0 [{info.unit}] ({info.description}), got {value!r}")
            object.__setattr__(self, info.name, value)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """Parameter names in vector order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    def resolved(self) -> dict[str, float]:
        """Values with optional (``None``) entries replaced by their derived value."""
        return {name: getattr(self, name) for name in self.names()}

    def as_vector(self) -> np.ndarray:
        """Parameter values in ``names()`` order, shape (np,), SI units."""
        values = self.resolved()
        return np.array([values[n] for n in self.names()], dtype=float)

    @classmethod
    def from_vector(cls, p: np.ndarray) -> _ParamsBase:
        """Build parameters from a vector in ``names()`` order."""
        p = np.asarray(p, dtype=float).ravel()
        names = cls.names()
        if p.shape != (len(names),):
            raise ValueError(f"parameter vector must have shape ({len(names)},), got {p.shape}")
        return cls(**dict(zip(names, p.tolist(), strict=True)))

    def replace(self, **changes: float) -> _ParamsBase:
        """Return a copy with some values changed (validated); unknown names raise."""
        unknown = sorted(set(changes) - set(self.names()))
        if unknown:
            raise ValueError(
                f"unknown parameter name(s) {unknown} for {type(self).__name__}; expected one of {list(self.names())}"
            )
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class RigidParams(_ParamsBase):
    """Parameters of the rigid double pendulum (SI units).

    Point masses at the link ends by default. Published acrobot/pendubot
    parameter sets use distributed mass: set the pivot-to-centre-of-mass
    distances ``lc1, lc2`` and the inertias ``I1, I2`` about the centres of mass.
    ``lc1 = None`` means ``lc1 = L1`` (likewise for ``lc2``).

    Attributes
    ----------
    m1, m2 : float, default 1.0
        Masses of links 1 and 2 [kg] (> 0).
    L1, L2 : float, default 1.0
        Lengths of links 1 and 2 [m] (> 0).
    g : float, default 9.81
        Gravitational acceleration [m/s2] (>= 0).
    b1 : float, default 0.0
        Viscous damping of joint 1, ground-link 1 [N.m.s/rad] (>= 0).
    b2 : float, default 0.0
        Viscous damping of joint 2, link 1-link 2 [N.m.s/rad] (>= 0).
    lc1 : float or None, default None
        Distance from the pivot to the centre of mass of link 1 [m]; ``None``
        means ``L1``.
    lc2 : float or None, default None
        Distance from joint 2 to the centre of mass of link 2 [m]; ``None``
        means ``L2``.
    I1, I2 : float, default 0.0
        Inertias of links 1 and 2 about their centres of mass [kg.m2] (>= 0).
    Ir : float, default 0.0
        Rotor inertia of each joint's geared motor about its own axis [kg.m2] (>= 0); a real
        robot's (RealAIGym's ``Ir``), zero for ideal links.
    gr : float, default 1.0
        Gear ratio of the motors [1] (> 0); it only matters when ``Ir > 0``.
    cf1, cf2 : float, default 0.0
        Coulomb friction of joints 1 and 2 [N.m] (>= 0), smoothed as
        ``cf atan(100 q')`` (:data:`pendulab.model.builders.COULOMB_SHARPNESS`).

    Raises
    ------
    TypeError
        On construction, a value that is not a real number.
    ValueError
        On construction, a non-finite value or one out of its range.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> rods = dict(lc1=0.5, lc2=0.5, I1=1 / 12, I2=1 / 12)  # two uniform 1 kg, 1 m rods
    >>> pl.RigidParams(**rods).lc1, pl.RigidParams().resolved()["lc1"]  # default: point masses, lc1 = L1
    (0.5, 1.0)
    >>> w = [mode.omega_n for mode in pl.modes(pl.rigid(**rods))]
    >>> np.round(w, 4), np.round(np.sqrt(9.81 * (3 + np.array([-1, 1]) * 6 / np.sqrt(7))), 4)  # (g / L)(3 -+ 6 / sqrt 7)
    (array([2.6801, 7.1887]), array([2.6801, 7.1887]))
    >>> pl.RigidParams(m1=-1.0)
    Traceback (most recent call last):
        ...
    ValueError: parameter 'm1' must be > 0 [kg] (mass of link 1), got -1.0
    """

    m1: float = _p(1.0, "kg", "mass of link 1", positive=True)
    m2: float = _p(1.0, "kg", "mass of link 2", positive=True)
    L1: float = _p(1.0, "m", "length of link 1", positive=True)
    L2: float = _p(1.0, "m", "length of link 2", positive=True)
    g: float = _p(9.81, "m/s2", "gravitational acceleration", positive=False)
    b1: float = _p(0.0, "N.m.s/rad", "viscous damping of joint 1 (ground-link 1)", positive=False)
    b2: float = _p(0.0, "N.m.s/rad", "viscous damping of joint 2 (link 1-link 2)", positive=False)
    lc1: float | None = _p(None, "m", "pivot to centre of mass of link 1 (None: L1)", positive=False)
    lc2: float | None = _p(None, "m", "joint to centre of mass of link 2 (None: L2)", positive=False)
    I1: float = _p(0.0, "kg.m2", "inertia of link 1 about its centre of mass", positive=False)
    I2: float = _p(0.0, "kg.m2", "inertia of link 2 about its centre of mass", positive=False)
    # The drivetrain of a real robot (pendulab.model.robot); appended so the ideal links' vector indices stay.
    Ir: float = _p(0.0, "kg.m2", "rotor inertia of each geared motor", positive=False)
    gr: float = _p(1.0, "1", "gear ratio of the motors", positive=True)
    cf1: float = _p(0.0, "N.m", "Coulomb friction of joint 1 (ground-link 1)", positive=False)
    cf2: float = _p(0.0, "N.m", "Coulomb friction of joint 2 (link 1-link 2)", positive=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        lc2 = self.L2 if self.lc2 is None else self.lc2
        if self.m2 * lc2 * lc2 + self.I2 == 0.0:  # lc2 * lc2, not lc2**2: a huge lc2 overflows to inf, not OverflowError
            # The mass matrix is singular: the elbow torque would give link 2 an infinite acceleration.
            raise ValueError(
                f"link 2 has no inertia about the elbow (m2 lc2^2 + I2 = 0 with lc2 = {lc2!r} m, I2 = {self.I2!r} kg.m2): "
                "the mass matrix is singular; expected lc2 > 0 or I2 > 0"
            )

    def resolved(self) -> dict[str, float]:
        """Parameter values with ``lc1, lc2 = None`` replaced by ``L1, L2``.

        Returns
        -------
        dict of str to float
            Every parameter by name, in SI units.
        """
        values = super().resolved()
        values["lc1"] = self.L1 if self.lc1 is None else self.lc1
        values["lc2"] = self.L2 if self.lc2 is None else self.lc2
        return values


@dataclass(frozen=True)
class ElasticParams(_ParamsBase):
    """Parameters of the elastic double pendulum (SI units).

    Point masses on massless Hooke springs whose rest lengths are ``L1, L2``.

    Attributes
    ----------
    m1, m2 : float, default 1.0
        Masses of bobs 1 and 2 [kg] (> 0).
    L1, L2 : float, default 1.0
        Rest lengths of springs 1 and 2 [m] (> 0).
    g : float, default 9.81
        Gravitational acceleration [m/s2] (>= 0).
    b1 : float, default 0.0
        Viscous damping of joint 1, ground-spring 1 [N.m.s/rad] (>= 0).
    b2 : float, default 0.0
        Viscous damping of joint 2, spring 1-spring 2 [N.m.s/rad] (>= 0).
    k1, k2 : float, default 500.0
        Stiffnesses of springs 1 and 2 [N/m] (> 0).
    c1, c2 : float, default 0.0
        Damping of springs 1 and 2 along their axes [N.s/m] (>= 0).

    Raises
    ------
    TypeError
        On construction, a value that is not a real number.
    ValueError
        On construction, a non-finite value or one out of its range.

    Examples
    --------
    >>> import pendulab as pl
    >>> params = pl.ElasticParams(k1=1e4, k2=1e4, c1=0.5)
    >>> params.k1, params.L1, params.c2
    (10000.0, 1.0, 0.0)
    >>> pl.elastic(k1=1e4, k2=1e4, c1=0.5).params == params  # what the factory builds
    True
    >>> pl.ElasticParams(k1=0.0)
    Traceback (most recent call last):
        ...
    ValueError: parameter 'k1' must be > 0 [N/m] (stiffness of spring 1), got 0.0
    """

    m1: float = _p(1.0, "kg", "mass of bob 1", positive=True)
    m2: float = _p(1.0, "kg", "mass of bob 2", positive=True)
    L1: float = _p(1.0, "m", "rest length of spring 1", positive=True)
    L2: float = _p(1.0, "m", "rest length of spring 2", positive=True)
    g: float = _p(9.81, "m/s2", "gravitational acceleration", positive=False)
    b1: float = _p(0.0, "N.m.s/rad", "viscous damping of joint 1 (ground-spring 1)", positive=False)
    b2: float = _p(0.0, "N.m.s/rad", "viscous damping of joint 2 (spring 1-spring 2)", positive=False)
    k1: float = _p(500.0, "N/m", "stiffness of spring 1", positive=True)
    k2: float = _p(500.0, "N/m", "stiffness of spring 2", positive=True)
    c1: float = _p(0.0, "N.s/m", "damping of spring 1 along its axis", positive=False)
    c2: float = _p(0.0, "N.s/m", "damping of spring 2 along its axis", positive=False)

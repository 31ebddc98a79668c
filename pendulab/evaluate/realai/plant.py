"""The RealAIGym robustness-v2 plant: pendulab's rigid model with upstream's parameters, rotor inertia and Coulomb friction.

RealAIGym's ``DoublePendulumPlant`` adds rotor inertia and joint friction to the rigid links; the
equations are pendulab's robot model, derived once in :mod:`pendulab.model.robot` (where the
identified plant of :mod:`pendulab.identify` comes from too).

The parameter vector is upstream's (:data:`PARAM_NAMES`); :func:`nominal_params` gives design
C.1 / model 1.0 as ``leaderboard/{pendubot,acrobot}/robustness_v2/sim_parameters.py`` sets it
(motor inertia, damping and Coulomb friction zero, torque limit 6 N.m on the actuated joint),
:func:`vary` applies one of the ten model-parameter variations the benchmark sweeps.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping
from functools import cache

import casadi as ca
import numpy as np

from ...control.realai.spec import TASKS, check_task, leaderboard_model
from ...identify.published import DFKI_C1
from ...model.model import Model, rigid
from ...model.plant_file import IdentifiedPlant
from ...model.pycode import to_python
from ...model.robot import ROBOT_PARAM_NAMES, robot_rhs, robot_to_rigid

__all__ = [
    "PARAM_NAMES",
    "MODEL_1_0",
    "plant_label",
    "protocol_model",
    "protocol_params",
    "MODEL_VARIATIONS",
    "nominal_params",
    "vary",
    "protocol_rhs",
    "protocol_rhs_python",
]

#: Upstream parameter vector (:data:`pendulab.model.robot.ROBOT_PARAM_NAMES`).
PARAM_NAMES: tuple[str, ...] = ROBOT_PARAM_NAMES

#: Design C.1, model 1.0 (:data:`pendulab.identify.published.DFKI_C1`).
MODEL_1_0: Mapping[str, float] = DFKI_C1["1.0"]

#: The ten model parameters the benchmark varies, in its order (``mpar_vars``).
MODEL_VARIATIONS: tuple[str, ...] = ("Ir", "m1r1", "I1", "b1", "cf1", "m2r2", "m2", "I2", "b2", "cf2")


def nominal_params(task: str) -> dict[str, float]:
    """The robustness-v2 plant of a task: model 1.0 with ``Ir = b = cf = 0`` (``sim_parameters.py``).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (the torque limit [6, 0] or [0, 6] is the task's, not a parameter here).

    Returns
    -------
    dict of str to float
        Values of :data:`PARAM_NAMES`.

    Raises
    ------
    ValueError
        Unknown ``task``.
    """
    check_task(task)
    return {**MODEL_1_0, "Ir": 0.0, "b1": 0.0, "b2": 0.0, "cf1": 0.0, "cf2": 0.0}


def protocol_params(task: str, plant: IdentifiedPlant | None = None) -> dict[str, float]:
    """The robot a protocol simulates: the task's nominal plant, or an identified one.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    plant : IdentifiedPlant, optional
        An identified robot (``pendulab identify``; :func:`pendulab.model.plant_file.load_plant`):
        its links, friction and rotor inertia replace the nominal plant. The controllers keep
        the model they were designed on, as on the real robot.

    Returns
    -------
    dict of str to float
        Values of :data:`PARAM_NAMES`.

    Raises
    ------
    ValueError
        Unknown ``task``.
    TypeError
        ``plant`` is not an :class:`~pendulab.model.plant_file.IdentifiedPlant`.
    """
    check_task(task)
    if plant is None:
        return nominal_params(task)
    if not isinstance(plant, IdentifiedPlant):
        raise TypeError(f"plant must be an IdentifiedPlant (pendulab.model.plant_file.load_plant), got {type(plant).__name__}")
    return dict(plant.params)


def protocol_model(task: str, plant: IdentifiedPlant | None = None) -> Model:
    """:func:`protocol_params` as a pendulab model (absolute angles; the rigid model carries the drivetrain).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    plant : IdentifiedPlant, optional
        An identified robot (see :func:`protocol_params`).

    Returns
    -------
    Model
        The task's leaderboard model, or the identified robot.
    """
    if plant is None:
        return leaderboard_model(task)
    return rigid(**robot_to_rigid(protocol_params(task, plant)))


def plant_label(plant: IdentifiedPlant | None) -> str:
    """How a result names its plant: ``"nominal"`` or ``"identified (<robot>, <sha256 prefix of the parameters>)"``.

    Parameters
    ----------
    plant : IdentifiedPlant, optional
        The plant simulated.

    Returns
    -------
    str
        A label that differs whenever a parameter differs (journals compare it).
    """
    if plant is None:
        return "nominal"
    digest = hashlib.sha256(json.dumps(plant.params, sort_keys=True).encode()).hexdigest()[:12]
    return f"identified ({plant.meta.get('robot', 'robot')}, {digest})"


def vary(params: Mapping[str, float], name: str, value: float) -> dict[str, float]:
    """One model-parameter variation as the benchmark applies it (``benchmarker.check_modelpar_robustness``).

    ``m1r1`` and ``m2r2`` change the centre of mass (``r_i = value / m_i``) and keep the mass
    and the joint inertia; ``m2`` changes the mass only (centre of mass and joint inertia
    kept); the others set the parameter of that name.

    Parameters
    ----------
    params : mapping of str to float
        Parameters (:data:`PARAM_NAMES`).
    name : str
        One of :data:`MODEL_VARIATIONS`.
    value : float
        The new value (``m1r1``, ``m2r2``: the product m r [kg.m]).

    Returns
    -------
    dict of str to float
        A new parameter dict.

    Raises
    ------
    ValueError
        Unknown ``name``.
    """
    out = dict(params)
    v = float(value)
    if name == "m1r1":
        out["r1"] = v / out["m1"]
    elif name == "m2r2":
        out["r2"] = v / out["m2"]
    elif name in MODEL_VARIATIONS:
        out[name] = v
    else:
        raise ValueError(f"name must be one of {list(MODEL_VARIATIONS)}, got {name!r}")
    return out


def protocol_rhs() -> ca.Function:
    """The plant's right-hand side as a CasADi Function, absolute angles (:func:`pendulab.model.robot.robot_rhs`).

    Returns
    -------
    casadi.Function
        ``rhs(x, tau, p) -> xdot``: ``x = (theta1, theta2, omega1, omega2)`` (absolute angles
        from hanging [rad, rad/s]), ``tau = (tau1, tau2)`` joint torques [N.m] (``tau2`` between
        the links), ``p`` the values of :data:`PARAM_NAMES`.
    """
    return robot_rhs()


@cache
def protocol_rhs_python() -> Callable[[np.ndarray, np.ndarray, list[float]], np.ndarray]:
    """:func:`protocol_rhs` translated to plain Python (:func:`pendulab.model.pycode.to_python`): ~10x faster per call.

    Returns
    -------
    callable
        ``f(x, tau, p) -> ndarray, shape (4,)`` with the arguments of :func:`protocol_rhs`.
    """
    return to_python(protocol_rhs())


def actuated_joint(task: str) -> int:
    """Index of the driven joint (0 pendubot, 1 acrobot).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.

    Returns
    -------
    int
        0 or 1.
    """
    return TASKS[check_task(task)]

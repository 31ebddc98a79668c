"""Names, units and descriptions of the states, inputs and outputs (the one table behind every label).

State *names* come from :data:`pendulab.model.builders.STATE_NAMES`; this module adds their units and
descriptions, the input and output tables and the actuation names.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

__all__ = ["INPUT_NAMES", "ACTUATIONS", "SignalInfo"]

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
    """Name, unit and description of a state, input or output.

    Attributes
    ----------
    name : str
        Signal name, e.g. ``"theta1"``.
    unit : str
        SI unit, e.g. ``"rad"``.
    description : str
        One line.
    """

    name: str
    unit: str
    description: str


def _state_unit(name: str) -> str:
    return _STATE_UNITS[name.rstrip("0123456789")]

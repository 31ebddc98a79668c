"""The identified plant as a file: what ``pendulab identify`` writes and every study reads (``--plant FILE``).

A JSON file (:data:`FORMAT`) with the robot's parameters in RealAIGym's names
(:data:`pendulab.model.robot.ROBOT_PARAM_NAMES`), their standard errors, the torque reading's
offsets, the chosen structure and where it came from. :func:`load_plant` validates everything on
reading (unknown format, missing or unknown names, non-finite or unphysical values all raise), so
a study never runs on a plant it misread.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._io import atomic_write_text
from .robot import ROBOT_PARAM_NAMES, ROBOT_PARAM_UNITS, check_robot_params, robot_to_rigid

__all__ = ["FORMAT", "SHIPPED_PLANTS", "IdentifiedPlant", "load_plant", "save_plant"]

#: The file format's name and version.
FORMAT = "pendulab.identified-plant/1"

#: Plant files shipped with pendulab, by name (``load_plant("c1")``, ``--plant c1``; a file of that name wins).
#: ``c1``: RealAIGym's design C.1 as ``pendulab identify --dataset c1 --out DIR`` identifies it from the robot's
#: eight measured excitation records (validated in ``benchmarks/results/identify.md``); regenerate it with that
#: command and copy ``DIR/plant.json`` to ``pendulab/model/plants/c1.json``.
SHIPPED_PLANTS: Mapping[str, Path] = {"c1": Path(__file__).parent / "plants" / "c1.json"}


@dataclass(frozen=True)
class IdentifiedPlant:
    """An identified robot.

    Attributes
    ----------
    params : dict of str to float
        Values of :data:`~pendulab.model.robot.ROBOT_PARAM_NAMES` (validated).
    stderr : dict of str to float
        Standard error per fitted parameter (``nan`` where only the prior sets it).
    torque_offset : tuple of float
        Constant offsets of the torque readings [N.m] (``reading = torque + offset``).
    structure : tuple of str
        The fitted standard parameters.
    meta : dict
        Provenance: robot, records, preprocessing, validation numbers.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.identify import load_plant
    >>> plant = load_plant("c1")  # the shipped identification of RealAIGym's C.1 robot
    >>> plant.structure[-3:], plant.torque_offset
    (('cf1', 'cf2', 'Ir'), (0.0, 0.0))
    >>> print(f"rotor inertia {plant.params['Ir']:.2e} +- {plant.stderr['Ir']:.1e} kg.m2")
    rotor inertia 4.74e-05 +- 2.2e-05 kg.m2
    >>> model = pl.rigid(**plant.rigid_kwargs())  # the links and viscous damping as RigidParams
    >>> model.params == pl.rigid(plant="c1").params
    True
    """

    params: dict[str, float]
    stderr: dict[str, float] = field(default_factory=dict)
    torque_offset: tuple[float, float] = (0.0, 0.0)
    structure: tuple[str, ...] = ()
    meta: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", check_robot_params(self.params, "plant params"))
        off = tuple(float(v) for v in self.torque_offset)
        if len(off) != 2 or not all(math.isfinite(v) for v in off):
            raise ValueError(f"torque_offset must be two finite numbers [N.m], got {self.torque_offset!r}")
        object.__setattr__(self, "torque_offset", off)

    def rigid_kwargs(self) -> dict[str, float]:
        """Arguments of :func:`pendulab.rigid` for this robot: links, friction and rotor inertia.

        Returns
        -------
        dict of str to float
            Values of :class:`~pendulab.model.params.RigidParams` (:func:`pendulab.model.robot.robot_to_rigid`).
        """
        return robot_to_rigid(self.params)

    def with_params(self, **changes: float) -> IdentifiedPlant:
        """A what-if copy of this robot with some parameters replaced (a sensitivity study's plant).

        The copy keeps the standard errors, offsets and structure; its ``meta["what_if"]`` records
        every replaced parameter with the identified value it replaced, so a saved what-if plant is
        never mistaken for the identified one.

        Parameters
        ----------
        **changes : float
            New values by name (:data:`~pendulab.model.robot.ROBOT_PARAM_NAMES`, SI units as
            ``params``).

        Returns
        -------
        IdentifiedPlant
            The changed robot (validated as every plant).

        Raises
        ------
        ValueError
            An unknown name, no change at all, or a non-finite or unphysical value.

        Examples
        --------
        >>> from pendulab.identify import load_plant
        >>> c1 = load_plant("c1")
        >>> smooth = c1.with_params(cf1=0.033)  # the shoulder's Coulomb friction of DFKI's model 3.0
        >>> smooth.params["cf1"], smooth.meta["what_if"]["cf1"]["identified"] == c1.params["cf1"]
        (0.033, True)
        """
        if not changes:
            raise ValueError("with_params needs at least one NAME=value change")
        unknown = sorted(set(changes) - set(ROBOT_PARAM_NAMES))
        if unknown:
            raise ValueError(f"unknown plant parameters {unknown}; expected some of {list(ROBOT_PARAM_NAMES)}")
        params = check_robot_params({**self.params, **changes}, "plant params")  # validated before it is recorded
        previous = dict(self.meta.get("what_if", {}))
        what_if = {
            name: {"value": params[name], "identified": previous.get(name, {}).get("identified", self.params[name])}
            for name in changes
        }
        return IdentifiedPlant(
            params=params,
            stderr=self.stderr,
            torque_offset=self.torque_offset,
            structure=self.structure,
            meta={**self.meta, "what_if": {**previous, **what_if}},
        )


def save_plant(plant: IdentifiedPlant, path: str | os.PathLike[str]) -> Path:
    """Write a plant file atomically.

    Parameters
    ----------
    plant : IdentifiedPlant
        The plant.
    path : path-like
        The JSON file.

    Returns
    -------
    Path
        The file written.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.identify import load_plant, save_plant
    >>> plant = load_plant("c1")
    >>> path = save_plant(plant, "robot/plant.json")  # what ``pendulab identify --out robot`` writes
    >>> path.as_posix(), load_plant(path).params == plant.params
    ('robot/plant.json', True)
    >>> pl.rigid(plant=path).params == pl.rigid(plant="c1").params  # a plant file feeds every study
    True
    """
    doc = {
        "format": FORMAT,
        "params": plant.params,
        "units": dict(ROBOT_PARAM_UNITS),
        "stderr": {k: (None if math.isnan(v) else v) for k, v in plant.stderr.items()},
        "torque_offset": list(plant.torque_offset),
        "structure": list(plant.structure),
        "meta": plant.meta,
    }
    target = Path(path)
    atomic_write_text(target, json.dumps(doc, indent=2) + "\n")
    return target


def load_plant(path: str | os.PathLike[str]) -> IdentifiedPlant:
    """Read and validate a plant file.

    Parameters
    ----------
    path : path-like
        A file written by :func:`save_plant` (``pendulab identify --out``), or the name of a
        shipped plant (:data:`SHIPPED_PLANTS`) when no file of that name exists.

    Returns
    -------
    IdentifiedPlant
        The plant.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not JSON, another format, or a parameter that is not finite or not physical.
    KeyError
        A parameter missing or unknown.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.identify import load_plant
    >>> plant = load_plant("c1")  # a shipped plant by name, or the path of a plant file
    >>> plant.params["l1"], plant.params["l2"], plant.meta["robot"]
    (0.2, 0.3, 'C.1')
    >>> robot = pl.rigid(plant="c1")  # the same file read by the model factory
    >>> print(f"m2 = {robot.params.m2:.3f} kg, cf2 = {robot.params.cf2:.3f} N.m")
    m2 = 0.534 kg, cf2 = 0.117 N.m
    """
    p = Path(path)
    if not p.exists() and str(path) in SHIPPED_PLANTS:
        p = SHIPPED_PLANTS[str(path)]
    if not p.is_file():
        raise FileNotFoundError(f"plant file not found: {p} (shipped plants: {sorted(SHIPPED_PLANTS)})")
    try:
        doc = json.loads(p.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ValueError(f"plant file {p} is not JSON: {exc}") from None
    if not isinstance(doc, Mapping) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, Mapping) else type(doc).__name__
        raise ValueError(f"plant file {p}: format must be {FORMAT!r}, got {got!r}")
    params = doc.get("params")
    if not isinstance(params, Mapping):
        raise ValueError(f"plant file {p}: 'params' must be a table of {list(ROBOT_PARAM_NAMES)}")
    stderr = {k: (float("nan") if v is None else float(v)) for k, v in (doc.get("stderr") or {}).items()}
    return IdentifiedPlant(
        params=dict(params), stderr=stderr, torque_offset=tuple(doc.get("torque_offset", (0.0, 0.0))),
        structure=tuple(doc.get("structure", ())), meta=dict(doc.get("meta", {})),
    )  # fmt: skip

"""The robustness scorecard's categories: which perturbation each sweeps, over which levels.

Ranges after RealAIGym's robustness benchmark (``docs/scorecard.md``). A
category turns a level into the :class:`~pendulab.evaluate.perturb.Perturbation`
of one run.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .perturb import Perturbation

if TYPE_CHECKING:
    from ..control.swingup.tasks import Task

__all__ = ["Category", "CATEGORIES", "categories_for"]


@dataclass(frozen=True)
class Category:
    """One perturbation swept over levels.

    Attributes
    ----------
    name : str
        Category name (CLI ``--categories``).
    description : str
        What is perturbed, in one line.
    unit : str
        Unit of the levels.
    levels : tuple of float
        Default levels.
    stochastic : bool
        True: ``runs`` seeded episodes per level; False: one episode per level.
    kinds : tuple of str
        Model kinds the category applies to.

    Examples
    --------
    >>> from pendulab.evaluate import CATEGORIES
    >>> delay = CATEGORIES["delay"]
    >>> delay.description, delay.unit, delay.levels, delay.stochastic
    ('measurement delay', 's', (0.0, 0.01, 0.02, 0.03, 0.04), False)
    >>> [c.name for c in CATEGORIES.values() if c.stochastic]  # these run several seeded episodes per level
    ['measurement_noise', 'torque_noise', 'pushes']
    """

    name: str
    description: str
    unit: str
    levels: tuple[float, ...]
    stochastic: bool
    kinds: tuple[str, ...] = ("rigid", "elastic")

    def perturbation(self, task: Task, level: float, seed: tuple[int, ...]) -> Perturbation:
        """The perturbation of one run.

        Parameters
        ----------
        task : Task
            Gives the nominal parameters that factors scale.
        level : float
            The level [``unit``].
        seed : tuple of int
            Seed of the run.

        Returns
        -------
        Perturbation
            What differs from the nominal closed loop.
        """
        par = task.model.params.resolved()
        scaled = {
            "mass": ("m1", "m2"),
            "length": ("L1", "L2", "lc1", "lc2") if task.model.kind == "rigid" else ("L1", "L2"),
            "inertia": ("I1", "I2"),
            "stiffness": ("k1", "k2"),
        }
        if self.name in scaled:
            return Perturbation(params={n: par[n] * level for n in scaled[self.name]}, seed=seed)
        if self.name == "damping":
            return Perturbation(params={"b1": par["b1"] + level, "b2": par["b2"] + level}, seed=seed)
        kw: dict[str, Any] = {
            "friction": {"friction": (level, level)},
            "measurement_noise": {"meas_noise": level},
            "torque_noise": {"torque_noise": level},
            "torque_response": {"response": level},
            "delay": {"delay": level},
            "pushes": {"push_amplitude": level},
        }[self.name]
        return Perturbation(seed=seed, **kw)


#: The categories, in report order. Ranges after RealAIGym's robustness benchmark (docs/scorecard.md).
CATEGORIES: Mapping[str, Category] = {
    c.name: c
    for c in (
        Category("mass", "masses m1, m2 scaled by the factor", "x", (0.75, 0.875, 1.0, 1.125, 1.25), False),
        Category("length", "lengths L1, L2 (and lc1, lc2) scaled by the factor", "x", (0.75, 0.875, 1.0, 1.125, 1.25), False),
        Category("inertia", "inertias I1, I2 scaled by the factor", "x", (0.75, 0.875, 1.0, 1.125, 1.25), False, ("rigid",)),
        Category("damping", "joint damping b1, b2 increased by", "N.m.s/rad", (0.0, 0.025, 0.05, 0.075, 0.1), False),
        Category("friction", "Coulomb friction on both joints", "N.m", (0.0, 0.05, 0.1, 0.15, 0.2), False),
        Category(
            "stiffness", "spring stiffnesses k1, k2 scaled by the factor", "x", (0.5, 0.75, 1.0, 1.25, 1.5), False, ("elastic",)
        ),
        Category("measurement_noise", "Gaussian noise on omega1, omega2 (std)", "rad/s", (0.0, 0.1, 0.2, 0.3, 0.5), True),
        Category("torque_noise", "Gaussian noise on the driven torques (std)", "N.m", (0.0, 0.25, 0.5, 0.75, 1.0), True),
        Category("torque_response", "torque responsiveness factor per sample", "-", (0.1, 0.5, 1.0, 1.5, 2.0), False),
        Category("delay", "measurement delay", "s", (0.0, 0.01, 0.02, 0.03, 0.04), False),
        Category("pushes", "3 Gaussian torque pulses per joint, amplitude up to", "N.m", (0.5, 1.0, 2.0, 3.0, 5.0), True),
    )
}


def categories_for(kind: str) -> tuple[str, ...]:
    """Names of the categories that apply to a model kind.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    tuple of str
        In :data:`CATEGORIES` order (no ``inertia`` for the point-mass elastic
        model, no ``stiffness`` for the rigid one).

    Examples
    --------
    >>> from pendulab.evaluate import categories_for
    >>> categories_for("elastic")
    ('mass', 'length', 'damping', 'friction', 'stiffness',
     'measurement_noise', 'torque_noise', 'torque_response', 'delay', 'pushes')
    >>> sorted(set(categories_for("rigid")) ^ set(categories_for("elastic")))  # link inertia (rigid), stiffness (elastic)
    ['inertia', 'stiffness']
    """
    return tuple(name for name, c in CATEGORIES.items() if kind in c.kinds)

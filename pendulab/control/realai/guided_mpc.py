"""The goal-regulating MPC, led out of the hanging well by the rate-bounded plan library (``controller="mpc_library"``).

On the simulated hardware protocol the goal-regulating MPC (:func:`~.mpc.goal_mpc`) loses most of its acrobot uptime
in one place: from a hand-over near the bottom with little energy its 0.5 s prediction sees no way up, and it
chatters the elbow at full torque (+-6 N m, +-18 rad/s) for seconds with no energy gained
(``benchmarks/results/v3_hardware.md``, "Plan-guided MPC for the acrobot"). :class:`GuidedMPC` keeps the goal MPC
everywhere else and, while the robot's energy is below a fraction of the way from hanging to upright
(:data:`GUIDED_LOW_ENERGY`), hands the same compiled real-time iteration the nearest plan of the rate-bounded library
(:func:`~pendulab.control.plan_library.library_controller` with the hardware protocol's joint-rate bound) as its
reference: the MPC tracks the plan with its own prediction, torque and rate bounds, and the goal MPC takes over when
the plan ends or the robot leaves its tube (:data:`GUIDED_TUBE`). Both settings were chosen on training seeds 30-45
(acrobot, allowance 0.5 N m) and checked on validation seeds 70-85; the scored seeds were run once, after. On the
pendubot, whose goal MPC does not get stuck, the plans gained nothing on its training seeds: its entry stays ``mpc``.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

import numpy as np

from ..._checks import positive_float
from ..lqr import wrap_state_error
from ..nmpc.rti import RTIController, rti_controller
from .mpc import goal_mpc, mpc_options
from .spec import PLAN_VELOCITY_LIMIT_HW, check_task

if TYPE_CHECKING:
    from ...model.plant_file import IdentifiedPlant
    from ..plan_library import PlanLibrary

__all__ = ["GuidedMPC", "guided_mpc", "GUIDED_LOW_ENERGY", "GUIDED_TUBE"]

#: Below this fraction of the energy between hanging and upright at rest, a plan leads [-].
GUIDED_LOW_ENERGY = 0.10
#: A plan is left when the squared tracking error in the library's lookup metric (wrapped angles [rad^2] plus
#: ``velocity_scale^2`` times the rates' [(rad/s)^2]) exceeds this.
GUIDED_TUBE = 6.0


class GuidedMPC:
    """Goal MPC with a plan-tracking mode below a low energy (see the module docstring).

    Parameters
    ----------
    goal : RTIController
        The goal-regulating MPC.
    track : RTIController
        The same problem without a winding limit, whose reference :meth:`RTIController.set_reference` replaces.
    library : PlanLibrary
        The plans (absolute angles, driven torque, on the controllers' 2 ms grid).
    low_energy : float
        Energy fraction below which a plan is looked up, in (0, 1).
    tube : float
        Squared tracking error at which a plan is left (lookup metric), > 0.
    accept : float
        Largest lookup distance of a plan's knot, > 0.
    min_left : float
        A knot with less than this of its plan left is not taken [s], >= 0.

    Raises
    ------
    ValueError
        Settings out of range, or controllers that differ in sample time or driven inputs.
    """

    def __init__(
        self,
        goal: RTIController,
        track: RTIController,
        library: PlanLibrary,
        *,
        low_energy: float = GUIDED_LOW_ENERGY,
        tube: float = GUIDED_TUBE,
        accept: float = 1.0,
        min_left: float = 0.15,
    ) -> None:
        if goal.sample_time != track.sample_time or goal.input_names != track.input_names:
            raise ValueError("goal and track must share their sample time and driven inputs")
        low_energy = positive_float("low_energy", low_energy)
        if not low_energy < 1.0:
            raise ValueError(f"low_energy must be a fraction in (0, 1) of the upright's energy, got {low_energy!r}")
        self.goal, self.track, self.library = goal, track, library
        self.low_energy = low_energy
        self.tube = positive_float("tube", tube)
        self.accept = positive_float("accept", accept)
        self.min_left = float(min_left)
        if not (math.isfinite(self.min_left) and self.min_left >= 0.0):
            raise ValueError(f"min_left must be a finite time >= 0 [s], got {min_left!r}")
        model = goal.model
        self._e_down = float(model.energy(np.zeros(model.nx)))
        self._e_up = float(model.energy(goal.goal))
        self._plan: tuple[int, int, float] | None = None  # (plan, knot at take-over, time of take-over)
        self._last_t: float | None = None
        self.n_plans = 0
        self.plan_calls = 0
        self.solve_times: list[float] = []

    @property
    def sample_time(self) -> float:
        """Sample period [s]."""
        return self.goal.sample_time

    @property
    def input_names(self) -> tuple[str, ...]:
        """Driven torques."""
        return self.goal.input_names

    def reset(self) -> None:
        """Forget the plan, the warm starts and the statistics."""
        self.goal.reset()
        self.track.reset()
        self._plan, self._last_t = None, None
        self.n_plans = self.plan_calls = 0
        self.solve_times = []

    def low(self, x: np.ndarray) -> bool:
        """Whether the state's energy is below :attr:`low_energy` of the way from hanging to upright at rest.

        Parameters
        ----------
        x : ndarray, shape (4,)
            State (absolute angles) [rad, rad/s].

        Returns
        -------
        bool
        """
        e = float(self.goal.model.energy(x))
        return e - self._e_down < self.low_energy * (self._e_up - self._e_down)

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """Torques now: the tracked plan's MPC while a plan leads, else the goal MPC.

        Parameters
        ----------
        t : float
            Time [s].
        x : array_like, shape (4,)
            Measured state (absolute angles) [rad, rad/s].

        Returns
        -------
        ndarray, shape (m,)
            Driven torques [N.m].

        Raises
        ------
        ValueError
            A bad ``t`` or ``x`` (as :class:`RTIController`).
        """
        start = time.perf_counter()
        x = self.goal.model.check_state(x, "x")
        t = float(t)
        if self._last_t is not None and t - self._last_t > 10.0 * self.sample_time:
            self._plan = None  # a gap in the calls: the robot was moved (a reset)
        self._last_t = t
        if self._plan is not None and not self._on_plan(t, x):
            self._plan = None
            self.goal.reset_warm_start()
        if self._plan is None and self.low(x):
            self._take_plan(t, x)
        if self._plan is not None:
            self.plan_calls += 1
            u = self.track(t - self._plan[2], x)
        else:
            u = self.goal(t, x)
        self.solve_times.append(time.perf_counter() - start)
        return u

    def _on_plan(self, t: float, x: np.ndarray) -> bool:
        """Whether the plan still leads: not finished, and the robot within the tube about its knot now."""
        i, k0, t0 = self._plan  # type: ignore[misc]
        ref = self.library.x_ref[i]
        k = k0 + int(round((t - t0) / self.sample_time))
        if k >= len(ref) - 1:
            return False
        return self.library.tube_error(wrap_state_error(x - ref[k], self.goal.model.state_names)) <= self.tube

    def _take_plan(self, t: float, x: np.ndarray) -> None:
        i, k, _ = self.library.nearest(x, within=self.accept)
        if i < 0:
            return
        ref = self.library.x_ref[i]
        if (len(ref) - 1 - k) * self.sample_time < self.min_left:
            return
        end = ref[-1].copy()
        end[2:] = 0.0
        self.track.set_reference(ref[k:], np.asarray(self.library.u_ref[i][k:], dtype=float)[:, None], end)
        self._plan = (i, k, t)
        self.n_plans += 1


def guided_mpc(
    task: str, plant: IdentifiedPlant | None = None, *, velocity_limit: float = PLAN_VELOCITY_LIMIT_HW, build: bool = True
) -> GuidedMPC:
    """The goal MPC of a leaderboard task guided by its rate-bounded plan library (see the module docstring).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    plant : IdentifiedPlant, optional
        The robot the MPC predicts (as :func:`~.mpc.goal_mpc`).
    velocity_limit : float
        Rate bound of the library's plans [rad/s].
    build : bool
        Solve missing plans first (False: the cached ones only; ``./pendulab-out/plan_library``).

    Returns
    -------
    GuidedMPC

    Raises
    ------
    ValueError
        Unknown task, or no plan in the library.
    CompilerNotFoundError (RuntimeError)
        The RTI step is not cached and no C compiler is found.
    """
    from ..plan_library import library_controller  # builds (or completes) the cached library

    task = check_task(task)
    goal = goal_mpc(task, plant)
    track = rti_controller(goal.model, **{**mpc_options(task), "angle_limit": None})
    library = library_controller(task, velocity_limit=velocity_limit, build=build).library
    return GuidedMPC(goal, track, library)

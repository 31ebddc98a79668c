"""The swing-up problem statement, independent of how it is transcribed.

A :class:`SwingUpProblem` says *what* is asked (model, actuation, limits, start,
goal, horizon, objective); :mod:`pendulab.control.swingup.transcription` says *how* it
becomes a nonlinear program (collocation or multiple shooting), in the spirit
of rockit.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..._checks import bounded_int, positive_float
from ..._inputs import checked
from ...model.model import ACTUATIONS, Model
from ..feedback import upright_state

__all__ = ["SwingUpProblem", "OBJECTIVES", "DEFAULT_MARGINS", "DEFAULT_INTERVALS", "MAX_INTERVALS"]

#: Intervals of the first mesh when neither the caller nor the task says: the one default of the Python
#: front door and the CLI alike (a task's ``N`` is carried by its problem, ``intervals``).
DEFAULT_INTERVALS = 100
#: Largest number of intervals of one NLP (elastic NLPs of 600 degree-3 intervals took minutes and ~6 GB to build).
MAX_INTERVALS = 1000
INTERVALS_WHY = "each interval adds a block of the NLP; an elastic NLP of 600 intervals needs ~6 GB to build"

#: Default torque margin per objective (fraction of the torque limit the plan may use).
DEFAULT_MARGINS: dict[str, float] = {"effort": 1.0, "time": 0.9, "mix": 0.9}
#: Objectives: ``effort`` = integral of tau^2; ``time`` = horizon T (free horizon);
#: ``mix`` = time_weight * T + integral of tau^2.
OBJECTIVES: tuple[str, ...] = ("effort", "time", "mix")


@checked(torque_limit="u_max", time_weight="weight", torque_margin="torque_margin")
@dataclass(frozen=True)
class SwingUpProblem:
    """Swing the double pendulum from ``x0`` to ``goal`` under torque limits.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum (its parameters are used as given).
    actuation : {"pendubot", "acrobot", "full"}
        Which joint torques are available: pendubot = tau1 (shoulder) only,
        acrobot = tau2 (elbow) only, full = both. Passive torques are zero.
    torque_limit : float
        Bound abs(tau) <= torque_limit on each actuated joint [N.m].
    velocity_limit : float or None
        Optional bound on both *joint* rates, abs(omega1) and abs(omega2 - omega1) <= velocity_limit [rad/s]
        (a robot's limits are on its joints: RealAIGym's hardware resets above 20 rad/s of either); the shoulder's
        is a state bound (:meth:`state_bounds`), the elbow's a constraint of the transcription.
    stretch_limits : (float, float) or None
        Elastic model only: bounds (min, max) on the spring stretch r - L [m]
        (min < 0 < max). None: the springs are unbounded.
    x0 : array_like, shape (nx,), or None
        Start state; None = hanging at rest (:meth:`Model.rest_state`).
    goal : array_like, shape (nx,), or None
        Goal state reached exactly at the end of the horizon; None = up-up at
        rest (:func:`pendulab.control.feedback.upright_state`; elastic springs statically compressed).
    horizon : float
        Fixed horizon T [s]; with ``free_horizon`` the initial guess of T.
    free_horizon : bool
        Let the solver choose T within ``horizon_bounds``.
    horizon_bounds : (float, float)
        Bounds on a free horizon [s].
    objective : {"effort", "time", "mix"}
        ``effort``: minimise the integral of tau^2 [N^2.m^2.s];
        ``time``: minimise T (needs a free horizon; a 1e-3 effort term keeps
        the bang-bang optimum regular); ``mix``: time_weight * T + effort.
    time_weight : float
        Weight on T in the ``mix`` objective [N^2.m^2].
    torque_margin : float or None
        The plan uses at most ``torque_margin * torque_limit`` on each actuated
        joint, leaving the rest of the actuator to the tracking controller
        (which saturates at ``torque_limit`` itself). In (0, 1]. None (default)
        = :data:`DEFAULT_MARGINS` of the objective: 0.9 for ``time`` and
        ``mix`` (their optima ride the bound, bang-bang, and a tracker with no
        authority left cannot correct anything), 1.0 for ``effort`` (its
        optimum stays mostly inside the limit; today's behaviour).
    intervals : int
        Intervals of the first mesh a solve uses when not told otherwise (a task's ``N``;
        the mesh is refined from there to meet the tolerance). Not compared for equality.
    name : str
        Label of the problem (e.g. the task name); not compared for equality.

    Raises
    ------
    ValueError
        On a negative or zero limit, unknown actuation or objective, a start
        or goal of the wrong size, spring bounds on a rigid model, etc.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import SwingUpProblem
    >>> problem = SwingUpProblem(pl.rigid(), "acrobot", torque_limit=10.0, horizon=4.0)
    >>> problem.start, np.round(problem.target, 3)  # default: hanging at rest to upright at rest
    (array([0., 0., 0., 0.]), array([3.142, 3.142, 0.   , 0.   ]))
    >>> problem.torque_bounds()[1]  # upper bounds on (tau1, tau2) [N.m]: the shoulder is passive
    array([ 0., 10.])
    >>> fastest = problem.replace(objective="time", free_horizon=True, horizon_bounds=(1.0, 6.0))
    >>> fastest.plan_torque_limit  # minimum time plans within 90 % of the limit
    9.0
    """

    model: Model
    actuation: str = "pendubot"
    torque_limit: float = 6.0
    velocity_limit: float | None = None
    stretch_limits: tuple[float, float] | None = None
    x0: tuple[float, ...] | None = None
    goal: tuple[float, ...] | None = None
    horizon: float = 4.0
    free_horizon: bool = False
    horizon_bounds: tuple[float, float] = (0.5, 10.0)
    objective: str = "effort"
    time_weight: float = 1.0
    torque_margin: float | None = None
    intervals: int = field(default=DEFAULT_INTERVALS, compare=False)
    name: str = field(default="swingup", compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.model, Model):
            raise ValueError(f"model must be a pendulab Model, got {type(self.model).__name__}")
        if self.actuation not in ACTUATIONS:
            raise ValueError(f"actuation must be one of {sorted(ACTUATIONS)}, got {self.actuation!r}")
        if self.objective not in OBJECTIVES:
            raise ValueError(f"objective must be one of {list(OBJECTIVES)}, got {self.objective!r}")
        set_ = lambda k, v: object.__setattr__(self, k, v)  # noqa: E731 - frozen dataclass normalisation
        set_("torque_limit", positive_float("torque_limit", self.torque_limit))
        set_("intervals", bounded_int("intervals", self.intervals, low=2, high=MAX_INTERVALS, why=INTERVALS_WHY))
        if self.velocity_limit is not None:
            set_("velocity_limit", positive_float("velocity_limit", self.velocity_limit))
        set_("horizon", positive_float("horizon", self.horizon))
        set_("time_weight", positive_float("time_weight", self.time_weight))
        if self.torque_margin is not None:
            margin = positive_float("torque_margin", self.torque_margin)
            if margin > 1.0:
                raise ValueError(f"torque_margin must lie in (0, 1] (fraction of torque_limit the plan may use), got {margin!r}")
            set_("torque_margin", margin)
        lo, hi = (
            positive_float("horizon_bounds[0]", self.horizon_bounds[0]),
            positive_float("horizon_bounds[1]", self.horizon_bounds[1]),
        )
        if lo >= hi:
            raise ValueError(f"horizon_bounds must satisfy min < max, got {self.horizon_bounds!r}")
        set_("horizon_bounds", (lo, hi))
        if self.free_horizon and not lo <= self.horizon <= hi:
            raise ValueError(
                f"horizon (initial guess of a free horizon) must lie in horizon_bounds {self.horizon_bounds}, got {self.horizon}"
            )
        if self.objective in ("time", "mix") and not self.free_horizon:
            raise ValueError(f"objective {self.objective!r} needs free_horizon=True (a fixed horizon cannot be minimised)")
        if self.stretch_limits is not None:
            if self.model.kind != "elastic":
                raise ValueError(f"stretch_limits apply to the elastic model only, got model kind {self.model.kind!r}")
            smin, smax = (float(v) for v in self.stretch_limits)
            if not (smin < 0.0 < smax):
                raise ValueError(f"stretch_limits must be (min, max) with min < 0 < max [m], got {self.stretch_limits!r}")
            set_("stretch_limits", (smin, smax))
        x0 = self.model.rest_state() if self.x0 is None else self.model.check_state(self.x0, "x0")
        goal = upright_state(self.model) if self.goal is None else self.model.check_state(self.goal, "goal")
        for label, vec in (("x0", x0), ("goal", goal)):
            if vec.ndim != 1:
                raise ValueError(f"{label} must be a single state of shape ({self.model.nx},), got shape {vec.shape}")
            self._check_within_bounds(label, vec)
        set_("x0", tuple(float(v) for v in x0))
        set_("goal", tuple(float(v) for v in goal))

    def _check_within_bounds(self, label: str, x: np.ndarray) -> None:
        lb, ub = self.state_bounds()
        bad = np.flatnonzero((x < lb - 1e-12) | (x > ub + 1e-12))
        if bad.size:
            i = int(bad[0])
            name = self.model.state_names[i]
            raise ValueError(f"{label} violates the state bounds: {name} = {x[i]:.6g} not in [{lb[i]:.6g}, {ub[i]:.6g}]")

    # -- derived quantities ------------------------------------------------------
    @property
    def actuated(self) -> tuple[int, ...]:
        """Indices into (tau1, tau2) of the actuated joints."""
        return ACTUATIONS[self.actuation]

    @property
    def start(self) -> np.ndarray:
        """Start state as an array, shape (nx,)."""
        return np.array(self.x0)

    @property
    def target(self) -> np.ndarray:
        """Goal state as an array, shape (nx,)."""
        return np.array(self.goal)

    @property
    def margin(self) -> float:
        """The torque margin in effect: ``torque_margin``, or the objective's default (:data:`DEFAULT_MARGINS`)."""
        return DEFAULT_MARGINS[self.objective] if self.torque_margin is None else self.torque_margin

    @property
    def plan_torque_limit(self) -> float:
        """Largest torque the plan may use, ``margin * torque_limit`` [N.m]."""
        return self.margin * self.torque_limit

    def torque_bounds(self, passive_fraction: float = 0.0, limit_scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """Lower/upper bounds on (tau1, tau2).

        Parameters
        ----------
        passive_fraction : float
            Fraction of the limit the passive joint may carry (0: passive;
            used by homotopies only).
        limit_scale : float
            Factor on ``torque_limit`` (> 1 loosens it; used by homotopies only).

        Returns
        -------
        lb, ub : ndarray, shape (2,)
            ``-ub`` and ``ub`` [N.m]: ``plan_torque_limit * limit_scale``
            (the torque limit times the margin) on the actuated joints,
            ``passive_fraction`` times that on the others.
        """
        limit = self.plan_torque_limit * limit_scale
        ub = np.full(2, passive_fraction * limit)
        ub[list(self.actuated)] = limit
        return -ub, ub

    def state_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower/upper bounds on the state.

        Returns
        -------
        lb, ub : ndarray, shape (nx,)
            +-``velocity_limit`` [rad/s] on omega1 when set (the elbow joint rate
            omega2 - omega1 is a constraint of the transcription); for the
            elastic model spring lengths in ``L + stretch_limits`` [m] (lower
            bound at least 1e-3 L); +-inf elsewhere.
        """
        nx, nq = self.model.nx, self.model.nq
        lb, ub = np.full(nx, -np.inf), np.full(nx, np.inf)
        if self.velocity_limit is not None:
            lb[nq], ub[nq] = -self.velocity_limit, self.velocity_limit
        if self.model.kind == "elastic":
            pr = self.model.params
            rest = np.array([pr.L1, pr.L2])
            smin, smax = self.stretch_limits if self.stretch_limits is not None else (-np.inf, np.inf)
            # A spring length must stay positive whatever the stretch limits say.
            lb[2:4] = np.maximum(rest + smin, 1e-3 * rest)
            ub[2:4] = rest + smax
        return lb, ub

    def replace(self, **changes: Any) -> SwingUpProblem:
        """A validated copy with some fields changed.

        Parameters
        ----------
        **changes
            New field values by name (as for the constructor).

        Returns
        -------
        SwingUpProblem
            The copy, validated again by the constructor.
        """
        from dataclasses import replace

        return replace(self, **changes)

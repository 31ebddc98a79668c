"""Initial guesses for swing-up NLPs that need no hand-tuning.

* :func:`linear_guess` - straight line in state space from start to goal, zero torque;
* :func:`energy_guess` - a simulated energy-pumping feedback (the actuated
  joint pushes with its rate while the total energy is below the goal's,
  saturated at the torque limit), a physically consistent trajectory that
  already swings;
* :func:`rigid_counterpart_problem` / :func:`lift_to_elastic` - solve the elastic task
  first on the rigid point-mass pendulum with the same masses and lengths, then
  lift it with quasi-static spring lengths;
* :func:`lift_plan` - a rigid plan lifted to elastic states for a planning level
  of :mod:`.planning` (springs rigid at rest length, or at their exact
  quasi-static lengths under the plan's torques).

The homotopies (full -> under-actuated, loose -> real torque limit) re-solve
the same compiled NLP with changed bounds and live in :mod:`.swingup`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..._inputs import checked
from ...integrate import simulate
from ...model import counterpart
from ...model.model import Model
from ...model.quasistatic import quasi_static_lengths
from ...model.statics import static_spring_lengths, static_spring_rates
from .problem import SwingUpProblem

__all__ = ["Guess", "linear_guess", "energy_guess", "rigid_counterpart_problem", "lift_to_elastic", "lift_plan"]


@dataclass(frozen=True)
class Guess:
    """A trajectory used as an initial guess.

    Attributes
    ----------
    t : ndarray, shape (K,)
        Times [s], increasing, starting at 0.
    x : ndarray, shape (K, nx)
        States.
    u : ndarray, shape (K, 2) or (K-1, 2)
        Torques (tau1, tau2) held from t[k] to t[k+1] [N.m].

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import Guess, swing_up
    >>> from pendulab.control.swingup.tasks import load_task
    >>> problem = load_task("pendubot").problem
    >>> first = swing_up(problem, N=40)
    >>> guess = Guess(first.t, first.x, first.u)  # grid, states, held torques (= first.as_guess())
    >>> guess.horizon, guess.x.shape
    (3.0, (51, 4))
    >>> np.round(guess.states_at([1.25], horizon=2.5), 3)  # time-stretched: 1.25 s of 2.5 s is 1.5 s of 3 s
    array([[ 3.195,  2.08 , -0.493,  5.745]])
    >>> swing_up(problem.replace(horizon=2.5), N=40, guess=guess).success  # warm start of a faster swing-up
    True
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray

    @property
    def horizon(self) -> float:
        return float(self.t[-1])

    def states_at(self, ts: np.ndarray, horizon: float) -> np.ndarray:
        """States at times ``ts`` of a horizon ``horizon`` (time rescaled).

        Parameters
        ----------
        ts : array_like, shape (n,)
            Query times [s] on the new horizon.
        horizon : float
            New horizon [s]; the guess is stretched from ``t[-1]`` to it.

        Returns
        -------
        ndarray, shape (n, nx)
            Linearly interpolated states (held constant outside the guess).
        """
        s = np.asarray(ts) * (self.horizon / horizon)
        return np.column_stack([np.interp(s, self.t, self.x[:, i]) for i in range(self.x.shape[1])])

    def inputs_at(self, ts: np.ndarray, horizon: float) -> np.ndarray:
        """Held torques at times ``ts`` (time rescaled).

        Parameters
        ----------
        ts : array_like, shape (n,)
            Query times [s] on the new horizon.
        horizon : float
            New horizon [s]; the guess is stretched from ``t[-1]`` to it.

        Returns
        -------
        ndarray, shape (n, 2)
            Torques (tau1, tau2) [N.m] of the last knot at or before each
            rescaled time (first/last held outside the guess).
        """
        s = np.asarray(ts) * (self.horizon / horizon)
        k = np.clip(np.searchsorted(self.t, s, side="right") - 1, 0, len(self.u) - 1)
        return self.u[k]


def linear_guess(problem: SwingUpProblem) -> Guess:
    """Straight line from start to goal over the horizon, zero torque.

    Parameters
    ----------
    problem : SwingUpProblem
        Gives the start, target and horizon.

    Returns
    -------
    Guess
        Two knots, ``(0, start)`` and ``(horizon, target)``, with zero torques.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import SwingUpProblem, linear_guess
    >>> guess = linear_guess(SwingUpProblem(pl.rigid(), "pendubot", torque_limit=6.0, horizon=4.0))
    >>> guess.t, guess.u.shape  # two knots: start and goal, zero torque
    (array([0., 4.]), (2, 2))
    >>> np.round(guess.states_at([2.0], 4.0), 3)  # halfway from hanging to upright: both links horizontal
    array([[1.571, 1.571, 0.   , 0.   ]])
    """
    t = np.linspace(0.0, problem.horizon, 2)
    x = np.vstack([problem.start, problem.target])
    return Guess(t, x, np.zeros((2, 2)))


@checked()
def energy_guess(problem: SwingUpProblem, dt: float = 0.01) -> Guess:
    """Simulate saturated energy pumping over the horizon.

    The actuated joint applies ``tau = sat(k (E_goal - E) * joint_rate)`` with
    a gain ``k`` that saturates the torque once the joint moves at 0.1 rad/s
    with 10 % of the energy still missing: effectively bang-bang pumping, no
    tuning per task. The trajectory does not end at the goal; it gives the
    NLP a swing with the right timing and energy scale.

    Parameters
    ----------
    problem : SwingUpProblem
        Model, actuation, torque limit, start, target and horizon.
    dt : float
        Output and feedback sample step [s] of the simulation (CVODES, 1e-6).

    Returns
    -------
    Guess
        The simulated trajectory with its held torques (tau1, tau2) [N.m].

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control import energy_guess, swing_up
    >>> from pendulab.control.swingup.tasks import load_task
    >>> problem = load_task("pendubot").problem  # 6 N.m on the shoulder, 3 s
    >>> guess = energy_guess(problem)  # simulated bang-bang energy pumping, 10 ms steps
    >>> guess.x.shape, guess.u.shape
    ((301, 4), (301, 2))
    >>> e_up, e0 = problem.model.energy(problem.target), problem.model.energy(problem.start)
    >>> print(f"energy gained: {(max(map(problem.model.energy, guess.x)) - e0) / (e_up - e0):.0%} of the swing-up")
    energy gained: 106% of the swing-up
    >>> at_limit = np.mean(np.abs(guess.u[:, 0]) == problem.torque_limit)  # bang-bang pumping
    >>> print(f"shoulder at the limit {at_limit:.0%} of the time, elbow torque {np.abs(guess.u[:, 1]).max()}")
    shoulder at the limit 93% of the time, elbow torque 0.0
    """
    model = problem.model
    e_goal = float(model.energy(problem.target))
    e_gap = max(abs(e_goal - float(model.energy(problem.start))), 1e-6)
    k = problem.torque_limit / (0.1 * e_gap * 0.1)
    act = problem.actuated
    nq = model.nq

    def pump(t: float, x: np.ndarray) -> np.ndarray:
        w1, w2 = x[nq], x[nq + 1]
        joint_rate = np.array([w1, w2 - w1])
        deficit = e_goal - float(model.energy(x))
        u = np.zeros(2)
        for i in act:
            u[i] = np.clip(k * deficit * joint_rate[i], -problem.torque_limit, problem.torque_limit)
        if not np.any(u) and deficit > 0:
            # At rest every rate is zero: kick to start the swing.
            u[act[0]] = problem.torque_limit
        return u

    traj = simulate(model, problem.start, problem.horizon, dt=dt, method="cvodes", rtol=1e-6, atol=1e-6, u=pump)
    return Guess(traj.t, traj.x, traj.u)


def rigid_counterpart_problem(problem: SwingUpProblem) -> SwingUpProblem:
    """The same task on the rigid point-mass pendulum with the elastic model's masses and lengths.

    The model is :func:`pendulab.model.counterpart.rigid_counterpart`; start
    and goal are mapped to rigid states; spring bounds are dropped.

    Parameters
    ----------
    problem : SwingUpProblem
        An elastic swing-up problem.

    Returns
    -------
    SwingUpProblem
        Same actuation, limits (and torque margin), horizon settings and objective, named
        ``problem.name + "-rigid"``.

    Raises
    ------
    ValueError
        ``problem`` is not on the elastic model.
    """
    if problem.model.kind != "elastic":
        raise ValueError(f"rigid_counterpart_problem needs an elastic problem, got model kind {problem.model.kind!r}")
    model = counterpart.rigid_counterpart(problem.model)
    return SwingUpProblem(
        model=model,
        actuation=problem.actuation,
        torque_limit=problem.torque_limit,
        velocity_limit=problem.velocity_limit,
        x0=counterpart.rigid_state(problem.model, problem.start),
        goal=counterpart.rigid_state(problem.model, problem.target),
        horizon=problem.horizon,
        free_horizon=problem.free_horizon,
        horizon_bounds=problem.horizon_bounds,
        objective=problem.objective,
        time_weight=problem.time_weight,
        torque_margin=problem.torque_margin,
        name=problem.name + "-rigid",
    )


def lift_to_elastic(problem: SwingUpProblem, t: np.ndarray, x_rigid: np.ndarray, u: np.ndarray) -> Guess:
    """Lift a rigid trajectory to the elastic state with quasi-static springs.

    Spring lengths carry the gravity load along each link
    (:func:`pendulab.model.statics.static_spring_lengths`, exact at the hanging
    and the inverted equilibrium); v = dr/dt.

    Parameters
    ----------
    problem : SwingUpProblem
        The elastic problem (its model's parameters give the springs).
    t : ndarray, shape (K,)
        Times [s].
    x_rigid : ndarray, shape (K, 4)
        Rigid states (theta1, theta2, omega1, omega2).
    u : ndarray, shape (K, 2) or (K-1, 2)
        Torques (tau1, tau2) [N.m], passed through.

    Returns
    -------
    Guess
        Elastic states (theta1, theta2, r1, r2, omega1, omega2, v1, v2),
        shape (K, 8).
    """
    pr = problem.model.params
    theta, omega = x_rigid[:, 0:2], x_rigid[:, 2:4]
    r = static_spring_lengths(pr, theta)
    v = static_spring_rates(pr, theta, omega)
    return Guess(np.asarray(t), np.column_stack([theta, r, omega, v]), np.asarray(u))


def lift_plan(model: Model, level: str, t: np.ndarray, x_rigid: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Lift a rigid plan to elastic states for one planning level.

    Parameters
    ----------
    model : Model
        The elastic model.
    level : {"rigid", "rigid+quasi-static"}
        ``rigid``: springs at rest length, v = 0. ``rigid+quasi-static``:
        quasi-static lengths under the mean of the torques held before and after
        each node (the torque jumps there), v = dr/dt by second-order differences.
    t : ndarray, shape (K,)
        Grid times [s].
    x_rigid : ndarray, shape (K, 4)
        Rigid states (theta1, theta2, omega1, omega2).
    u : ndarray, shape (K - 1, 2)
        Torques held on the intervals [N.m].

    Returns
    -------
    ndarray, shape (K, 8)
        Elastic states (theta1, theta2, r1, r2, omega1, omega2, v1, v2).

    Raises
    ------
    ValueError
        Not an elastic model, an unknown level, or mismatched shapes.
    RuntimeError
        No quasi-static lengths at some node (springs too soft for the motion).
    """
    if not isinstance(model, Model) or model.kind != "elastic":
        raise ValueError("model must be an elastic pendulab Model to lift a rigid plan onto")
    t, x_rigid, u = np.asarray(t, float), np.asarray(x_rigid, float), np.asarray(u, float)
    K = t.size
    if x_rigid.shape != (K, 4) or u.shape != (K - 1, 2):
        raise ValueError(f"x_rigid must have shape ({K}, 4) and u ({K - 1}, 2), got {x_rigid.shape} and {u.shape}")
    theta, omega = x_rigid[:, :2], x_rigid[:, 2:]
    if level == "rigid":
        r = np.tile([model.params.L1, model.params.L2], (K, 1))
        v = np.zeros((K, 2))
    elif level == "rigid+quasi-static":
        u_node = np.vstack([u[:1], 0.5 * (u[1:] + u[:-1]), u[-1:]])
        r = np.array([quasi_static_lengths(model, theta[k], omega[k], u_node[k]) for k in range(K)])
        v = np.gradient(r, t, axis=0)
    else:
        raise ValueError(f"level must be 'rigid' or 'rigid+quasi-static' to lift a rigid plan, got {level!r}")
    return np.column_stack([theta, r, omega, v])

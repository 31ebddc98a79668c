"""A swing-up designed for the RealAIGym v2 score: optimize the criteria themselves, track at 2 ms, balance.

Transcription (multiple shooting on the leaderboard's own integrator): nodes
every ``H = 10 ms``; inside an interval five classic RK4 steps of 2 ms
(exactly the leaderboard's step) with the torque of step ``j`` interpolated
linearly between the node torques, ``u_k + j/5 (u_k+1 - u_k)``. The 2 ms
torque sequence is therefore piecewise linear, which is what keeps the
smoothness criterion small. The NLP minimises

``sum_i tanh(pi c_i / n_i)`` over energy, torque cost, smoothness and velocity cost,

each ``c_i`` an auxiliary variable equal to its 2 ms sum (so the Hessian stays
sparse): torque cost ``sum u^2 dt``; velocity cost ``sum (dq1^2 + dq2^2) dt``
with ``dq2`` relative; energy ``sum sqrt((dq u)^2 + eps)`` (smoothed absolute
value); smoothness ``sqrt(sum du^2 / (N - 1))`` (the std of the 2 ms torque
increments; their mean is ~0). The swing-up time is fixed per solve: the
end effector must stay 1 cm above the 0.9 (L1 + L2) line on every node from
``t_up`` on, and the plan ends upright at rest with zero torque at
``t_end``. A small sweep over ``t_up`` picks the best closed-loop score.

Closed loop: TVLQR at 2 ms along the 2 ms reference
(:func:`pendulab.control.tracking.tvlqr_tracker`), handing over to discrete
LQR balance, saturated at 6 N.m. Plans are cached in ``plans/<task>.npz``
(regenerate with ``python benchmarks/bench_realai.py --regenerate``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from ...model.model import Model
from ..tracking import TVLQRTracker, tvlqr_tracker
from .spec import DT, HEIGHT_FRACTION, N_STEPS, NORMS, TASKS, TORQUE_LIMIT, check_task, leaderboard_model, leaderboard_task

__all__ = [
    "SUBSTEPS",
    "PLAN_DIR",
    "LeaderboardPlan",
    "design_plan",
    "load_plan",
    "save_plan",
    "best_controller",
    "tracker_for_plan",
    "sweep",
    "default_guess",
]

#: 2 ms RK4 steps per shooting interval (interval H = 10 ms).
SUBSTEPS: int = 5
#: Where the shipped plans live.
PLAN_DIR: Path = Path(__file__).parent / "plans"
#: TVLQR weights of the tracker: angles, rates; the input weight is per N.m^2.
Q_TRACK: tuple[float, ...] = (10.0, 10.0, 1.0, 1.0)
R_TRACK: float = 1.0 / TORQUE_LIMIT**2
_EPS_ENERGY = 1e-10  # J^2 per step: smoothing of |dq u|, adds at most ~1e-5 J * steps
_EPS_STD = 1e-12  # N^2 m^2: keeps sqrt differentiable at zero
_MARGIN = 0.01  # m above the success line on nodes after t_up (the line is checked every 2 ms, nodes every 10 ms)


@dataclass(frozen=True)
class LeaderboardPlan:
    """An optimized swing-up on the 2 ms grid.

    Attributes
    ----------
    task : str
        "pendubot" or "acrobot".
    t : ndarray, shape (M + 1,)
        Times [s], 2 ms apart, from 0 to ``t_end``.
    x : ndarray, shape (M + 1, 4)
        States (theta1, theta2, omega1, omega2), absolute [rad, rad/s].
    u : ndarray, shape (M + 1, 2)
        Torques (tau1, tau2) [N.m] held over each step (last row: 0).
    t_up : float
        Designed swing-up time [s].
    objective : float
        NLP objective (sum of the four tanh terms).
    """

    task: str
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    t_up: float
    objective: float


def _interval(model: Model, joint: int) -> ca.Function:
    """One 10 ms interval: (x0, u0, u1) -> (x1, [torque cost, velocity cost, energy], substep states (4, SUBSTEPS))."""
    x0, u0, u1 = ca.SX.sym("x0", 4), ca.SX.sym("u0"), ca.SX.sym("u1")
    rhs = model.functions["rhs"]
    p = ca.DM(model.p)
    x, cost_u, cost_v, work, states = x0, 0, 0, 0, []
    for j in range(SUBSTEPS):
        uj = u0 + (j / SUBSTEPS) * (u1 - u0)
        tau = ca.vertcat(uj, 0) if joint == 0 else ca.vertcat(0, uj)
        states.append(x)
        k1 = rhs(x, tau, p)
        k2 = rhs(x + 0.5 * DT * k1, tau, p)
        k3 = rhs(x + 0.5 * DT * k2, tau, p)
        k4 = rhs(x + DT * k3, tau, p)
        xn = x + DT * (k1 + 2 * (k2 + k3) + k4) / 6
        # Criteria in RealAIGym's joint coordinates: q2 and dq2 relative to link 1.
        cost_u += uj**2 * DT
        cost_v += (x[2] ** 2 + (x[3] - x[2]) ** 2) * DT
        dq = xn[0] - x[0] if joint == 0 else (xn[1] - xn[0]) - (x[1] - x[0])
        work += ca.sqrt((dq * uj) ** 2 + _EPS_ENERGY)
        x = xn
    return ca.Function("interval", [x0, u0, u1], [x, ca.vertcat(cost_u, cost_v, work), ca.horzcat(*states)])


def _height(model: Model) -> ca.Function:
    x = ca.SX.sym("x", 4)
    prm = model.params
    return ca.Function("height", [x], [-prm.L1 * ca.cos(x[0]) - prm.L2 * ca.cos(x[1])])


def design_plan(
    task: str,
    t_up: float,
    t_end: float,
    guess: tuple[np.ndarray, np.ndarray] | None = None,
    *,
    u_bound: float = 5.5,
    max_iter: int = 3000,
) -> LeaderboardPlan:
    """Optimize a swing-up for the v2 score with the swing-up time fixed at ``t_up``.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    t_up : float
        Swing-up time [s]: the end effector stays above the line from then on.
    t_end : float
        End of the plan [s] (> ``t_up``), upright at rest with zero torque.
    guess : (x, u), optional
        Node guess: x shape (N + 1, 4), u shape (N + 1,) on the 10 ms grid
        (e.g. a previous plan's nodes); default: a straight line in the angles.
    u_bound : float
        Torque bound of the plan [N.m] (below 6 leaves the feedback some room).
    max_iter : int
        IPOPT iteration limit.

    Returns
    -------
    LeaderboardPlan
        The optimized plan on the 2 ms grid.

    Raises
    ------
    ValueError
        Unknown task, times not ``0 < t_up < t_end`` on the 10 ms grid, a guess
        of the wrong shape, or an NLP that IPOPT did not solve.
    """
    check_task(task)
    H = SUBSTEPS * DT
    N = int(round(t_end / H))
    if not (0 < t_up < t_end) or abs(N * H - t_end) > 1e-9:
        raise ValueError(f"need 0 < t_up < t_end with t_end a multiple of {H} s, got t_up={t_up!r}, t_end={t_end!r}")
    joint = TASKS[task]
    model = leaderboard_model(task)
    F = _interval(model, joint).map(N)
    height = _height(model).map(N + 1)
    X = ca.MX.sym("X", 4, N + 1)
    U = ca.MX.sym("U", 1, N + 1)
    C = ca.MX.sym("C", 4)  # torque cost, velocity cost, energy, sum of squared 2 ms increments
    X_next, costs, _ = F(X[:, :N], U[:, :N], U[:, 1:])
    du2 = ca.sumsqr(U[:, 1:] - U[:, :N]) / SUBSTEPS
    g = [ca.vec(X_next - X[:, 1:]), C[:3] - ca.sum2(costs), C[3] - du2]
    n_def = 4 * N + 4
    k_up = int(np.ceil(t_up / H - 1e-9))
    g.append(ca.vec(height(X)[:, k_up:]))
    # fmax: IPOPT may step a hair outside the bound C >= 0 (bound relaxation); the root must stay real.
    std = ca.sqrt(ca.fmax(C[3], 0) / (N_STEPS - 1) + _EPS_STD)
    f = (
        ca.tanh(np.pi * C[0] / NORMS["torque_cost"])
        + ca.tanh(np.pi * C[1] / NORMS["velocity_cost"])
        + ca.tanh(np.pi * C[2] / NORMS["energy"])
        + ca.tanh(np.pi * std / NORMS["torque_smoothness"])
    )
    w = ca.vertcat(ca.vec(X), ca.vec(U), C)
    x_goal = np.array([np.pi, np.pi, 0.0, 0.0])
    lbx = np.full(w.shape[0], -np.inf)
    ubx = np.full(w.shape[0], np.inf)
    nX = 4 * (N + 1)
    lbx[nX : nX + N + 1], ubx[nX : nX + N + 1] = -u_bound, u_bound
    for idx, val in ((slice(0, 4), np.zeros(4)), (slice(4 * N, 4 * N + 4), x_goal)):
        lbx[idx], ubx[idx] = val, val
    lbx[nX + N], ubx[nX + N] = 0.0, 0.0  # zero torque at the end: the balance LQR takes over at rest
    lbx[nX + N + 1 :] = 0.0  # the costs are non-negative
    line = HEIGHT_FRACTION * (model.params.L1 + model.params.L2) + _MARGIN
    lbg = np.concatenate([np.zeros(n_def), np.full(N + 1 - k_up, line)])
    ubg = np.concatenate([np.zeros(n_def), np.full(N + 1 - k_up, np.inf)])
    if guess is None:
        s = np.minimum(np.arange(N + 1) * H / t_up, 1.0)[:, None]
        xg = s * x_goal
        ug = np.zeros(N + 1)
    else:
        xg, ug = np.asarray(guess[0], dtype=float), np.asarray(guess[1], dtype=float).ravel()
        if xg.shape != (N + 1, 4) or ug.shape != (N + 1,):
            raise ValueError(f"guess must be x of shape ({N + 1}, 4) and u of shape ({N + 1},), got {xg.shape}, {ug.shape}")
    w0 = np.concatenate([xg.ravel(), ug, np.ones(4)])
    solver = ca.nlpsol(
        "realai", "ipopt", {"x": w, "f": f, "g": ca.vertcat(*g)},
        {"expand": True, "print_time": False, "ipopt": {"print_level": 0, "max_iter": max_iter, "tol": 1e-9, "sb": "yes"}},
    )  # fmt: skip
    sol = solver(x0=w0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    stats = solver.stats()
    if not stats["success"]:
        raise ValueError(f"the RealAI swing-up NLP of {task} (t_up={t_up}, t_end={t_end}) failed: {stats['return_status']}")
    wopt = np.asarray(sol["x"]).ravel()
    xn = wopt[:nX].reshape(N + 1, 4)
    un = wopt[nX : nX + N + 1]
    return _refine(task, model, joint, xn, un, t_up, float(sol["f"]))


def _refine(
    task: str, model: Model, joint: int, xn: np.ndarray, un: np.ndarray, t_up: float, objective: float
) -> LeaderboardPlan:
    """The 2 ms reference of node values: each interval's substeps from its own start node."""
    N = len(un) - 1
    _, _, sub = _interval(model, joint).map(N)(xn[:N].T, un[:N][None, :], un[1:][None, :])
    sub = np.asarray(sub)  # (4, N * SUBSTEPS): interval k's substep states, in order
    x = np.vstack([sub.T, xn[-1]])
    s = np.arange(SUBSTEPS) / SUBSTEPS
    ua = np.concatenate([un[k] + s * (un[k + 1] - un[k]) for k in range(N)] + [[un[-1]]])
    u = np.zeros((len(ua), 2))
    u[:, joint] = ua
    return LeaderboardPlan(task, np.arange(len(ua)) * DT, x, u, float(t_up), objective)


def save_plan(plan: LeaderboardPlan, path: str | Path | None = None) -> Path:
    """Store a plan as ``.npz`` (default ``plans/<task>.npz`` in the package).

    Parameters
    ----------
    plan : LeaderboardPlan
        The plan.
    path : str or Path, optional
        Target file.

    Returns
    -------
    Path
        The file written.
    """
    p = Path(path) if path is not None else PLAN_DIR / f"{plan.task}.npz"
    p.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(p, task=plan.task, t=plan.t, x=plan.x, u=plan.u, t_up=plan.t_up, objective=plan.objective)
    return p


def load_plan(task: str, path: str | Path | None = None) -> LeaderboardPlan:
    """Load a stored plan (default: the shipped ``plans/<task>.npz``).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    path : str or Path, optional
        Plan file.

    Returns
    -------
    LeaderboardPlan
        The stored plan.

    Raises
    ------
    ValueError
        Unknown task, or a file that holds another task's plan.
    FileNotFoundError
        No plan file (regenerate with ``python benchmarks/bench_realai.py --regenerate``).
    """
    check_task(task)
    p = Path(path) if path is not None else PLAN_DIR / f"{task}.npz"
    if not p.is_file():
        raise FileNotFoundError(f"no RealAI plan at {str(p)!r}; run `python benchmarks/bench_realai.py --regenerate`")
    with np.load(p) as d:
        if str(d["task"]) != task:
            raise ValueError(f"plan file {str(p)!r} holds a {str(d['task'])!r} plan, not {task!r}")
        return LeaderboardPlan(task, d["t"], d["x"], d["u"], float(d["t_up"]), float(d["objective"]))


def tracker_for_plan(plan: LeaderboardPlan) -> TVLQRTracker:
    """TVLQR at 2 ms along a plan, then discrete LQR balance; saturated at 6 N.m.

    Parameters
    ----------
    plan : LeaderboardPlan
        The reference.

    Returns
    -------
    TVLQRTracker
        Drives only the task's actuated torque.
    """
    model = leaderboard_model(plan.task)
    return tvlqr_tracker(
        model, plan.t, plan.x, plan.u[:-1], DT, u_max=TORQUE_LIMIT, actuation=plan.task, Q=np.diag(Q_TRACK), R=R_TRACK
    )


def best_controller(task: str) -> TVLQRTracker:
    """The project's best-scoring leaderboard controller: TVLQR along the shipped score-designed plan.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.

    Returns
    -------
    TVLQRTracker
        2 ms sample time.

    Raises
    ------
    ValueError
        Unknown task.
    FileNotFoundError
        The plan is missing.
    """
    return tracker_for_plan(load_plan(task))


def sweep(
    task: str,
    steps: Iterable[tuple[float, float]],
    evaluate: Callable[[LeaderboardPlan], float],
    guess: tuple[np.ndarray, np.ndarray] | None = None,
    progress: Callable[[list[tuple[float, float]]], Iterable[tuple[float, float]]] = iter,
) -> tuple[LeaderboardPlan, float]:
    """Continuation over ``(t_up, t_end)`` pairs: each solve starts from the previous plan; keep the best score.

    A guess shorter than the next plan is extended by holding its last node
    (upright at rest, zero torque).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    steps : iterable of (float, float)
        Swing-up time and plan end [s] of each solve.
    evaluate : callable
        ``evaluate(plan) -> score`` (closed loop).
    guess : (x, u), optional
        First guess on the 10 ms nodes, shapes (N + 1, 4) and (N + 1,).
    progress : callable
        Wraps the list of steps (e.g. ``tqdm``).

    Returns
    -------
    plan : LeaderboardPlan
        The best plan.
    score : float
        Its score.

    Raises
    ------
    ValueError
        No step gave a solved NLP.
    """
    best: tuple[LeaderboardPlan, float] | None = None
    for t_up, t_end in progress(list(steps)):
        if guess is not None:
            n = int(round(t_end / (SUBSTEPS * DT))) + 1
            xg, ug = guess
            pad = max(0, n - len(xg))
            guess = (np.vstack([xg, np.tile(xg[-1], (pad, 1))])[:n], np.concatenate([ug, np.zeros(pad)])[:n])
        try:
            plan = design_plan(task, float(t_up), float(t_end), guess)
        except ValueError:
            continue
        guess = (plan.x[::SUBSTEPS], plan.u[::SUBSTEPS, TASKS[task]])
        s = evaluate(plan)
        if best is None or s > best[1]:
            best = (plan, s)
    if best is None:
        raise ValueError(f"no step of the continuation solved for {task}")
    return best


def default_guess(task: str, t_end: float) -> tuple[np.ndarray, np.ndarray]:
    """Node guess from the task's effort-optimal plan (:meth:`~pendulab.control.swingup.tasks.Task.plan`), upright after it.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    t_end : float
        Plan end [s].

    Returns
    -------
    x : ndarray, shape (N + 1, 4)
        Node states.
    u : ndarray, shape (N + 1,)
        Node torques of the actuated joint [N.m].

    Raises
    ------
    ValueError
        The swing-up did not solve.
    """
    res = leaderboard_task(task).plan().result
    if not res.success:
        raise ValueError(f"the shipped swing-up of {task} did not solve: {res.message}")
    tn = np.arange(int(round(t_end / (SUBSTEPS * DT))) + 1) * SUBSTEPS * DT
    tc = np.minimum(tn, res.horizon)
    x = res.x_at(tc)
    u = res.u_at(np.minimum(tn, res.horizon - 1e-9))[:, TASKS[task]]
    u[tn >= res.horizon] = 0.0
    return x, u

"""Swing-ups that minimise the time to ENTER the scored height band (RealAIGym v3 counts time above 0.9 (l1 + l2)).

A time-optimal swing-up to upright at rest spends its last ~0.1-0.2 s decelerating inside the band; the v3
score counts uptime from the band's edge. This plan has two phases (RK4 multiple shooting, piecewise-constant
torque, free durations): phase 1 from the start until the end effector enters the band, phase 2 staying in the
band (height >= band + margin on every knot) until upright at rest, where the catch LQR holds it. The objective
is the duration of phase 1 (plus a small weight on phase 2 and on effort). It is warm-started from a time-optimal
plan (the re-planner's), whose in-band tail gives the initial split.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.model import INPUT_NAMES, Model
from ..model.robot import joint_rates

__all__ = ["band_entry_plan", "band_entry_refine", "within_joint_limit", "JOINT_RATE_SLACK"]


def band_entry_plan(
    model: Model,
    actuation: str,
    x_guess: np.ndarray,
    u_guess: np.ndarray,
    sample_time: float,
    *,
    band: float,
    u_max: float,
    margin: float = 0.01,
    n1: int = 30,
    n2: int = 12,
    max_iter: int = 300,
    velocity_limit: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float] | None:
    """Solve the band-entry swing-up warm-started from a plan ``(x_guess, u_guess)`` on the ``sample_time`` grid.

    Parameters
    ----------
    model : Model
        Rigid design model (absolute angles).
    actuation : {"pendubot", "acrobot"}
        Driven joint.
    x_guess : ndarray, shape (N, 4)
        Warm start, from the start state to upright at rest [rad, rad/s]; its first and last states are kept.
    u_guess : ndarray, shape (N - 1,)
        Driven torque of the warm start [N.m].
    sample_time : float
        Grid of the warm start [s].
    band : float
        Scored height of the end effector [m].
    u_max : float
        Torque bound of the plan [N.m].
    margin : float
        Height above ``band`` required of the in-band phase [m].
    n1, n2 : int
        Shooting intervals of the two phases.
    max_iter : int
        IPOPT iteration cap.
    velocity_limit : float, optional
        Bound on both *joint* rates ``omega1`` and ``omega2 - omega1`` at every knot [rad/s] (None: unbounded): the
        robot's limits are on its joints (the hardware protocol resets above 20 rad/s of either, as the RTI's
        ``rate_limit``); raised to the start's and goal's joint rates when they exceed it (the plan must still start
        where it starts).

    Returns
    -------
    (t, x, u, t_enter) or None
        Knot times (n1 + n2 + 1,) [s], states (n1 + n2 + 1, 4), full torques (n1 + n2, 2) held from each knot
        [N.m], and the band-entry time [s]; None when IPOPT fails.
    """
    import casadi as ca

    f = model.functions["rhs"]
    p = ca.DM([float(v) for v in model.p])
    prm = model.params
    j = INPUT_NAMES.index("tau1" if actuation == "pendubot" else "tau2")
    xg = np.asarray(x_guess, dtype=float)
    ug = np.asarray(u_guess, dtype=float)
    tg = np.arange(len(xg)) * sample_time

    def height(x: ca.MX) -> ca.MX:
        return -prm.L1 * ca.cos(x[0]) - prm.L2 * ca.cos(x[1])

    hg = -prm.L1 * np.cos(xg[:, 0]) - prm.L2 * np.cos(xg[:, 1])
    inb = hg > band + margin
    k = len(inb) - 1
    while k > 0 and inb[k - 1]:
        k -= 1
    T = tg[-1]
    t_split = tg[k] if 0.2 * T < tg[k] < T - 0.05 else 0.85 * T

    opti = ca.Opti()
    t1, t2 = opti.variable(), opti.variable()
    X1, X2 = opti.variable(4, n1 + 1), opti.variable(4, n2 + 1)
    U1, U2 = opti.variable(1, n1), opti.variable(1, n2)

    def step(x: ca.MX, u: ca.MX, h: ca.MX) -> ca.MX:
        uu = ca.vertcat(u, 0) if j == 0 else ca.vertcat(0, u)
        for _ in range(2):  # two RK4 substeps per interval
            k1 = f(x, uu, p)
            k2 = f(x + 0.25 * h * k1, uu, p)
            k3 = f(x + 0.25 * h * k2, uu, p)
            k4 = f(x + 0.5 * h * k3, uu, p)
            x = x + h * (k1 + 2 * k2 + 2 * k3 + k4) / 12.0
        return x

    effort = 0
    for X, U, T_, n in ((X1, U1, t1, n1), (X2, U2, t2, n2)):
        h = T_ / n
        for i in range(n):
            opti.subject_to(X[:, i + 1] == step(X[:, i], U[0, i], h))
            effort += h * U[0, i] ** 2
        opti.subject_to(opti.bounded(-u_max, U, u_max))
    opti.subject_to(X1[:, 0] == xg[0])
    opti.subject_to(X2[:, 0] == X1[:, n1])
    opti.subject_to(X2[:, n2] == xg[-1])
    for i in range(n2 + 1):
        opti.subject_to(height(X2[:, i]) >= band + margin)
    if velocity_limit is not None:
        vmax = max(float(velocity_limit), float(np.max(np.abs(joint_rates(xg[[0, -1]])))))
        for X in (X1, X2):
            opti.subject_to(opti.bounded(-vmax, ca.vertcat(X[2, :], X[3, :] - X[2, :]), vmax))
    opti.subject_to(opti.bounded(0.1, t1, 2.0))
    opti.subject_to(opti.bounded(0.04, t2, 1.0))
    opti.minimize(t1 + 0.05 * t2 + 1e-3 * effort)
    # Warm start: the guess plan split at its last band entry.
    s1 = np.linspace(0.0, t_split, n1 + 1)
    s2 = np.linspace(t_split, T, n2 + 1)
    for X, s in ((X1, s1), (X2, s2)):
        opti.set_initial(X, np.array([np.interp(s, tg, xg[:, c]) for c in range(4)]))
    uk = np.append(ug, ug[-1])
    opti.set_initial(U1, np.interp(s1[:-1], tg, uk)[None, :])
    opti.set_initial(U2, np.interp(s2[:-1], tg, uk)[None, :])
    opti.set_initial(t1, t_split)
    opti.set_initial(t2, max(T - t_split, 0.05))
    opti.solver("ipopt", {"print_time": False}, {"print_level": 0, "sb": "yes", "max_iter": max_iter})
    try:
        sol = opti.solve()
    except RuntimeError:
        return None
    a, b = float(sol.value(t1)), float(sol.value(t2))
    x = np.vstack([np.asarray(sol.value(X1)).T, np.asarray(sol.value(X2)).T[1:]])
    ud = np.concatenate([np.atleast_1d(sol.value(U1)), np.atleast_1d(sol.value(U2))])
    t = np.concatenate([np.linspace(0.0, a, n1 + 1), a + np.linspace(0.0, b, n2 + 1)[1:]])
    u = np.zeros((len(ud), 2))
    u[:, j] = ud
    if not (np.all(np.isfinite(x)) and math.isfinite(a)):
        return None
    return t, x, u, a


def _closed_loop_entry(model: Model, j: int, x_ref: np.ndarray, u_ref: np.ndarray, K: np.ndarray, band: float, u_max: float):
    """Band-entry time [s] of the TVLQR-tracked plan simulated on ``model`` (RK4 at the plan's grid), and whether its
    last 0.2 s (holding ``u_ref[-1]`` feedback past the end) stay in the band; None if it never settles in the band."""
    from ..model.pycode import to_python

    f = to_python(model.functions["rhs"])
    p = [float(v) for v in model.p]
    prm = model.params
    h, x, hs = 0.002, np.array(x_ref[0], dtype=float), []
    n = len(K)
    for k in range(n + 100):
        i = min(k, n - 1)
        e = x - x_ref[min(k, len(x_ref) - 1)]
        e[:2] = (e[:2] + math.pi) % (2.0 * math.pi) - math.pi
        u = [0.0, 0.0]
        u[j] = float(np.clip(u_ref[i] - K[i] @ e, -u_max, u_max))
        k1 = f(x, u, p)
        k2 = f(x + 0.5 * h * k1, u, p)
        k3 = f(x + 0.5 * h * k2, u, p)
        k4 = f(x + h * k3, u, p)
        x = x + h * (k1 + 2.0 * (k2 + k3) + k4) / 6.0
        hs.append(-prm.L1 * math.cos(x[0]) - prm.L2 * math.cos(x[1]))
    inb = np.asarray(hs) > band
    if not inb[-100:].all():
        return None
    k = len(inb) - 1
    while k > 0 and inb[k - 1]:
        k -= 1
    return (k + 1) * h


def band_entry_refine(
    model: Model,
    actuation: str,
    entry: dict[str, np.ndarray],
    *,
    band: float,
    u_max: float,
    sample_time: float = 0.002,
    velocity_limit: float | None = None,
) -> dict[str, np.ndarray]:
    """A library entry re-planned for band entry, with TVLQR gains, where its closed loop enters the band sooner.

    Parameters
    ----------
    model : Model
        Design model.
    actuation : {"pendubot", "acrobot"}
        Driven joint.
    entry : dict
        A solved library entry (``x_ref`` (N, 4), ``u_ref`` (N-1,), ``K`` (N-1, 4)) on the ``sample_time`` grid.
    band : float
        Scored height [m].
    u_max : float
        Actuator limit [N.m] (the plan uses 90 % of it).
    sample_time : float
        [s].
    velocity_limit : float, optional
        Bound on both joint rates of the re-planned plan [rad/s] (:func:`band_entry_plan`); None: unbounded. With a
        bound, ``entry`` competes only if it keeps the bound itself (:func:`within_joint_limit`).

    Returns
    -------
    dict
        The re-planned entry when its closed loop enters the band sooner than ``entry``'s, else ``entry`` itself;
        either with ``refined`` (bool) and ``t_enter``, the band-entry time of its closed loop [s] (``inf`` when it
        never settles in the band), so that entries toward different goals can be ranked. ``{"ok": False}`` when
        neither keeps ``velocity_limit``.
    """
    from .tracking import tvlqr_tracker

    j = INPUT_NAMES.index("tau1" if actuation == "pendubot" else "tau2")
    base = _closed_loop_entry(model, j, entry["x_ref"], entry["u_ref"], entry["K"], band, u_max)
    if within_joint_limit(entry["x_ref"], velocity_limit):
        kept = dict(entry, refined=np.array(False), t_enter=np.array(math.inf if base is None else base))
    else:  # the time-optimal plan bounds link rates only: it may not stand in for a joint-bounded one
        kept, base = {"ok": np.array(False), "refined": np.array(False), "t_enter": np.array(math.inf)}, None
    res = band_entry_plan(
        model, actuation, entry["x_ref"], entry["u_ref"], sample_time, band=band, u_max=0.9 * u_max, velocity_limit=velocity_limit
    )
    if res is None:
        return kept
    t, x, u, _ = res
    try:
        tr = tvlqr_tracker(model, t, x, u, sample_time, u_max=u_max, actuation=actuation)
    except ValueError:
        return kept
    m = min(len(tr.K), len(tr.u_ref), len(tr.x_ref) - 1)
    new = {"ok": np.array(True), "x_ref": tr.x_ref[: m + 1], "u_ref": tr.u_ref[:m, 0], "K": tr.K[:m, 0, :]}
    if not within_joint_limit(new["x_ref"], velocity_limit):
        return kept
    t_new = _closed_loop_entry(model, j, new["x_ref"], new["u_ref"], new["K"], band, u_max)
    if t_new is None or (base is not None and t_new >= base):
        return kept
    return dict(new, refined=np.array(True), t_enter=np.array(t_new))


#: Slack of :func:`within_joint_limit` [-]: the bound holds on the plan's knots, and the 2 ms resampling between
#: them overshoots it by up to ~2 % on the measured libraries (16.2-16.3 rad/s under 16).
JOINT_RATE_SLACK = 1.05


def within_joint_limit(x_ref: np.ndarray, velocity_limit: float | None) -> bool:
    """Whether a plan keeps a joint-rate bound (raised to its start's joint rates, where it must start).

    Parameters
    ----------
    x_ref : ndarray, shape (N, 4)
        The plan's states (absolute angles) [rad, rad/s].
    velocity_limit : float or None
        The bound on both joint rates [rad/s] (:func:`joint_rates`), with :data:`JOINT_RATE_SLACK`; None: any
        plan keeps it.

    Returns
    -------
    bool

    Examples
    --------
    >>> x = [[0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 10.0, 28.0]]  # links at 10 and 28 rad/s: the elbow joint at 18
    >>> within_joint_limit(x, 16.0), within_joint_limit(x, 20.0)
    (False, True)
    """
    if velocity_limit is None:
        return True
    w = np.abs(joint_rates(x_ref))
    bound = max(float(velocity_limit), float(w[0].max()))
    return bool(w.max() <= JOINT_RATE_SLACK * bound)

"""Real-time-iteration NMPC (controller ``rti``): compiled step = graph, LQ/QP exactness, swing-up, bad input, cache."""

from __future__ import annotations

import os

import casadi as ca
import numpy as np
import pytest

from pendulab.control.feedback import upright_state
from pendulab.control.lqr import lqr_balance
from pendulab.control.nmpc.rti import RTIOptions, joint_wrapped_error, rti_controller, rti_for_task
from pendulab.control.nmpc.rti_build import build_step_library, compiled_step
from pendulab.control.nmpc.rti_step import rk4_interval, rti_step_function
from pendulab.control.realai.spec import leaderboard_task
from pendulab.model.model import elastic
from pendulab.native import CacheRebuildWarning, compiler_unavailable_reason
from pendulab.native.cache import seal, sealed_key, verify_cached

pytestmark = pytest.mark.skipif(compiler_unavailable_reason() is not None, reason="needs a C compiler")

N_SMALL = 8  # a short horizon: the LQ/QP checks need no long prediction, and it compiles quickly


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("rti-cache")


@pytest.fixture(scope="module")
def model():
    return leaderboard_task("pendubot").model


@pytest.fixture(scope="module")
def small(model, cache):
    """Regulation about upright, compiled (short horizon)."""
    return rti_controller(model, actuation="pendubot", u_max=6.0, horizon=N_SMALL, cache_directory=cache)


def _inputs(ctrl, rng, x0):
    """Step inputs in CasADi shapes: a perturbed guess about the goal and the goal as reference."""
    N, nx = ctrl.options.horizon, ctrl.model.nx
    X = ctrl.goal[:, None] + 0.05 * rng.standard_normal((nx, N + 1))
    U = 0.5 * rng.standard_normal((1, N))
    XR = np.tile(ctrl.goal[:, None], (1, N + 1))
    return [x0, X, U, XR, np.zeros((1, N))]


def _condensed(model, ctrl, dx0):
    """Independent numpy condensing of the LQ problem linearized at upright rest (guess = goal, U = 0)."""
    H, g, P, _, _ = _condensed_parts(model, ctrl, dx0)
    return H, g, P


def _condensed_parts(model, ctrl, dx0):
    """:func:`_condensed` and its prediction: ``Gam`` (N, N+1, 4), the state response to each torque, and the free one."""
    o = ctrl.options
    n = model.nx // 2
    Q = np.diag([o.q_angle] * n + [o.q_rate] * n)
    R = np.eye(1) / ctrl.u_max**2
    P = lqr_balance(model, ("tau1",), Q, R, o.interval, at=ctrl.goal).P
    F = rk4_interval(model, [0], o.interval, o.steps_per_interval)
    xs, us = ca.SX.sym("x", 4), ca.SX.sym("u", 1)
    jac = ca.Function("linearized", [xs, us], [ca.jacobian(F(xs, us), xs), ca.jacobian(F(xs, us), us)])
    A, B = (np.asarray(v) for v in jac(ctrl.goal, 0))
    N = o.horizon

    def rollout(dU, d0):
        xs_, x = [d0], d0
        for k in range(N):
            x = A @ x + B[:, 0] * dU[k]
            xs_.append(x)
        return xs_

    free = rollout(np.zeros(N), dx0)
    Gam = np.array([rollout(np.eye(N)[j], np.zeros(4)) for j in range(N)])  # (N, N+1, 4)
    W = [Q] * N + [P]
    H = R[0, 0] * np.eye(N) + np.einsum("jka,kab,ikb->ij", Gam, np.array(W), Gam)
    g = np.einsum("jka,kab,kb->j", Gam, np.array(W), np.array(free))
    return H, g, P, Gam, np.array(free)


def test_compiled_step_equals_graph(small, model):
    # Same inputs through the CasADi graph and the generated, compiled C: equal to round-off.
    rng = np.random.default_rng(1)
    inp = _inputs(small, rng, small.goal + np.array([0.3, -0.2, 0.5, 0.0]))
    a, b = small.graph(*inp), small.step(*inp)
    assert small.step is not small.graph  # the compiled library was loaded
    for name, u, v in zip(small.graph.name_out(), a, b, strict=True):
        scale = max(1.0, float(ca.norm_inf(u)))
        # round-off only: the C code evaluates the same operations in the same order
        assert float(ca.norm_inf(u - v)) <= 1e-12 * scale, name


def test_one_iteration_on_lq_is_the_exact_qp_solution(small, model):
    # Linearized at upright rest (guess = goal): one compiled step solves the LQ problem exactly.
    dx0 = np.array([0.05, -0.03, 0.1, 0.0])
    N = small.options.horizon
    X = np.tile(small.goal[:, None], (1, N + 1))
    out = small.step(small.goal + dx0, X, np.zeros((1, N)), X, np.zeros((1, N)))
    H, g, _ = _condensed(model, small, dx0)
    z = np.linalg.solve(H, -g)  # the exact unconstrained QP solution (no bound active at this small lean)
    assert np.all(np.abs(z) < small.u_max)
    # 1e-9 [N.m]: a linear solve of a well-conditioned 8 x 8 system, against the same solve done by numpy
    np.testing.assert_allclose(np.asarray(out[2]).ravel(), z, atol=1e-9)
    assert float(out[5][0]) == 1.0  # a KKT point (no bound held)


def test_one_iteration_on_lq_is_lqr(small, model):
    # With the Riccati cost-to-go of the RK4 linearization as terminal cost, the finite-horizon LQ optimum is
    # the infinite-horizon LQR: every torque is -K x of the linear closed loop, and one step finds it.
    import scipy.linalg

    o = small.options
    Q, R = np.diag([o.q_angle] * 2 + [o.q_rate] * 2), np.eye(1) / small.u_max**2
    F = rk4_interval(model, [0], o.interval, o.steps_per_interval)
    xs, us = ca.SX.sym("x", 4), ca.SX.sym("u", 1)
    A, B = (
        np.asarray(v)
        for v in ca.Function("lin", [xs, us], [ca.jacobian(F(xs, us), xs), ca.jacobian(F(xs, us), us)])(small.goal, 0)
    )
    P = scipy.linalg.solve_discrete_are(A, B, Q, R)
    K = np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    N = 12
    step = rti_step_function(
        model, ("tau1",), N=N, interval=o.interval, substeps=o.steps_per_interval, shift=0.2, Q=Q, R=R, P=P,
        u_max=6.0, qp_iterations=3,
    )  # fmt: skip
    dx = np.array([0.04, -0.02, 0.1, -0.1])
    X = np.tile(small.goal[:, None], (1, N + 1))
    out = step(small.goal + dx, X, np.zeros((1, N)), X, np.zeros((1, N)))
    us_lqr, x = [], dx
    for _ in range(N):
        us_lqr.append((-K @ x)[0])
        x = (A - B @ K) @ x
    # 1e-8 [N.m]: the DARE solution (scipy) is accurate to ~1e-12 relative; torques are O(1)
    np.testing.assert_allclose(np.asarray(out[2]).ravel(), us_lqr, atol=1e-8)
    np.testing.assert_allclose(np.asarray(out[1])[:, -1] - small.goal, x, atol=1e-8)


def test_one_iteration_with_active_bounds_is_the_box_qp_solution(small, model):
    # A lean large enough to saturate the torque: the active-set solve meets the exact box-QP optimum.
    dx0 = np.array([0.6, -0.4, 0.0, 0.0])
    N = small.options.horizon
    X = np.tile(small.goal[:, None], (1, N + 1))
    out = small.step(small.goal + dx0, X, np.zeros((1, N)), X, np.zeros((1, N)))
    H, g, _ = _condensed(model, small, dx0)
    z = np.asarray(out[2]).ravel()
    assert float(out[5][1]) >= 1  # at least one bound active
    assert float(out[5][0]) == 1.0  # the iterate is a KKT point
    lo, hi = -small.u_max * np.ones(N), small.u_max * np.ones(N)
    # Optimality of a box QP: z is its own projected gradient step (any positive step length).
    step = 1.0 / np.linalg.eigvalsh(H).max()
    # 1e-9 [N.m]: equal to round-off of the two condensings
    np.testing.assert_allclose(np.clip(z - step * (H @ z + g), lo, hi), z, atol=1e-9)
    assert np.any(np.isclose(np.abs(z), small.u_max))


def test_swingup_pendubot_succeeds(cache):
    from pendulab.evaluate.realai.simulate import run_leaderboard

    ctrl, x0 = rti_for_task(leaderboard_task("pendubot"), cache_directory=cache)
    assert ctrl.sample_time == pytest.approx(0.002)
    res = run_leaderboard("pendubot", ctrl, "rti")
    assert res.success  # RealAIGym rule: end effector above 0.9 (L1 + L2) from swing-up time on
    err = (res.x[-1] - upright_state(ctrl.model) + np.pi) % (2 * np.pi) - np.pi
    # task tolerance of the robustness rule: (0.35, 0.35, 1.0, 1.0) from upright
    assert np.all(np.abs(res.x[-1][2:]) < 1.0) and np.all(np.abs(err[:2]) < 0.35)
    st = ctrl.stats()
    assert st["failures"] == 0 and st["n_calls"] == 5000


def test_rti_is_a_protocol_controller_name():
    from pendulab.evaluate.realai.controllers import CONTROLLERS

    assert CONTROLLERS["rti"].__name__ == "_rti"  # `pendulab score --protocol ... --controller rti` builds it


@pytest.mark.parametrize(
    ("x", "match"),
    [(np.zeros(3), "x"), (np.array([0.0, np.nan, 0.0, 0.0]), "x"), (np.zeros((2, 4)), "one state")],
)
def test_bad_state_raises(small, x, match):
    with pytest.raises(ValueError, match=match):
        small(0.0, x)


def test_bad_time_and_options_raise(small, model):
    with pytest.raises(ValueError, match="t must be"):
        small(-0.1, small.goal)
    with pytest.raises(ValueError, match="t must be"):
        small(float("nan"), small.goal)
    with pytest.raises(ValueError, match="horizon"):
        RTIOptions(horizon=0)
    with pytest.raises(ValueError, match="sample_time must be at most interval"):
        RTIOptions(sample_time=0.02, interval=0.01)
    with pytest.raises(TypeError, match="unknown RTI option"):
        rti_controller(model, actuation="pendubot", u_max=6.0, horizn=5)


def test_cache_survives_a_corrupted_entry(small, tmp_path):
    meta = {"test": "corrupt"}
    path = build_step_library(small.graph, meta, directory=tmp_path)
    # Damaged bytes (digest no longer matches): rebuilt with a warning, then loaded and correct.
    tmp = path.with_name("garbage.tmp")
    tmp.write_bytes(b"\x7fELF garbage" * 10)
    os.replace(tmp, path)  # a new file: the (never loaded) library is replaced, not edited in place
    with pytest.warns(CacheRebuildWarning, match="does not match"):
        fn = compiled_step(small.graph, meta, directory=tmp_path)
    x0 = small.goal + np.array([0.1, 0.0, 0.0, 0.0])
    N = small.options.horizon
    X = np.tile(small.goal[:, None], (1, N + 1))
    ref = small.graph(x0, X, np.zeros((1, N)), X, np.zeros((1, N)))[0]
    assert float(fn(x0, X, np.zeros((1, N)), X, np.zeros((1, N)))[0]) == pytest.approx(float(ref), abs=1e-12)


def test_cache_rebuilds_an_entry_that_fails_to_load(small, tmp_path):
    meta = {"test": "unloadable"}
    path = build_step_library(small.graph, meta, directory=tmp_path)
    tmp = path.with_name("garbage.tmp")
    tmp.write_bytes(b"not a shared library")
    key = sealed_key(path)
    os.replace(tmp, path)
    seal(path, key)  # intact by its seal, yet unloadable
    with pytest.warns(CacheRebuildWarning, match="failed to load"):
        fn = compiled_step(small.graph, meta, directory=tmp_path)
    assert fn.name() == small.graph.name()


def test_cache_refuses_the_step_of_another_entry(small, tmp_path):
    # Two steps of other build parameters (same C symbol): swapped, seals and all, each is intact but the other's.
    a, b = (build_step_library(small.graph, {"test": t}, directory=tmp_path) for t in ("a", "b"))
    key_a = sealed_key(a)
    assert key_a.startswith(f"{small.graph.name()}-") and key_a != sealed_key(b)
    for x, y in ((a, b), (a.with_name(a.name + ".sha256"), b.with_name(b.name + ".sha256"))):
        os.replace(x, tmp_path / "swap")
        os.replace(y, x)
        os.replace(tmp_path / "swap", y)
    with pytest.warns(CacheRebuildWarning, match="built for another entry"):
        fn = compiled_step(small.graph, {"test": "a"}, directory=tmp_path)
    assert fn.name() == small.graph.name() and sealed_key(a) == key_a and verify_cached(a, key_a) is None


def test_nonuniform_grid_options(model, cache):
    """A grid of equal intervals is the uniform controller; a non-uniform one validates, shifts per interval."""
    x = upright_state(model) + np.array([0.1, -0.1, 0.2, 0.0])
    uni = rti_controller(model, actuation="pendubot", u_max=6.0, horizon=4, interval=0.02, compiled=False)
    grid = rti_controller(model, actuation="pendubot", u_max=6.0, intervals=(0.02,) * 4, compiled=False)
    for t in (0.0, 0.002, 0.01):
        np.testing.assert_allclose(grid(t, x), uni(t, x), rtol=0, atol=1e-12)
    opts = RTIOptions(intervals=[0.004, 0.004, 0.016], sample_time=0.002, terminal_weights=(1.0, 2.0, 3.0, 4.0))
    assert (opts.horizon, opts.interval, opts.grid_steps, opts.prediction) == (3, 0.004, (1, 1, 2), pytest.approx(0.024))
    ctrl = rti_controller(model, actuation="pendubot", u_max=6.0, options=opts, cost_per_second=True, cache_directory=cache)
    assert ctrl._offsets.tolist() == [0, 2, 4, 12]
    assert np.all(np.isfinite(ctrl(0.0, x))) and np.all(np.isfinite(ctrl(0.004, x)))
    np.testing.assert_allclose(
        ctrl.step(*[a.T if a.ndim == 2 else a for a in ctrl._in])[0],
        ctrl.graph(*[a.T if a.ndim == 2 else a for a in ctrl._in])[0],
        atol=1e-10,
    )
    with pytest.raises(ValueError, match="sample_time must be at most interval"):
        RTIOptions(intervals=(0.004, 0.001), sample_time=0.002)
    with pytest.raises(ValueError, match="intervals"):
        RTIOptions(intervals=(0.004, -0.01))
    with pytest.raises(TypeError, match="intervals"):
        RTIOptions(intervals=0.01)
    with pytest.raises(ValueError, match="terminal_weights"):
        rti_controller(model, actuation="pendubot", u_max=6.0, horizon=4, terminal_weights=(1.0, 2.0), compiled=False)


def test_rate_bound_step_is_the_penalized_qp_minimum(small, model):
    # Linearized at upright rest with a fast start: the soft joint-rate bound w (|v| - v_max)_+^2 makes a convex,
    # piecewise-quadratic QP; one step must meet its minimum, found here independently by L-BFGS-B on the
    # numpy condensing (the joint rates are omega1 and omega2 - omega1).
    import scipy.optimize

    o = small.options
    N, vmax, w = o.horizon, 0.8, 30.0
    dx0 = np.array([0.05, -0.03, 1.0, -0.5])
    H, g, P, Gam, free = _condensed_parts(model, small, dx0)
    Q, R = np.diag([o.q_angle] * 2 + [o.q_rate] * 2), np.eye(1) / small.u_max**2
    step = rti_step_function(
        model, ("tau1",), N=N, interval=o.interval, substeps=o.steps_per_interval, shift=0.2, Q=Q, R=R, P=P,
        u_max=6.0, qp_iterations=30, rate_limit=vmax, rate_weight=w,
    )  # fmt: skip
    X = np.tile(small.goal[:, None], (1, N + 1))
    out = step(small.goal + dx0, X, np.zeros((1, N)), X, np.zeros((1, N)))
    J = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, -1.0, 1.0]])  # state -> joint rates

    def f(z):
        v = (free + np.einsum("j,jka->ka", z, Gam)) @ J.T
        over = np.maximum(np.abs(v) - vmax, 0.0)
        grad_v = w * over * np.sign(v)
        return 0.5 * z @ H @ z + g @ z + 0.5 * w * np.sum(over**2), H @ z + g + np.einsum("jka,kb,ba->j", Gam, grad_v, J)

    best = scipy.optimize.minimize(f, np.zeros(N), jac=True, method="L-BFGS-B", bounds=[(-6.0, 6.0)] * N, tol=1e-14)
    rates = (free + np.einsum("j,jka->ka", best.x, Gam)) @ J.T
    assert np.abs(rates).max() > vmax  # the bound is active at the optimum (soft: met only approximately)
    assert float(out[5][0]) == 1.0  # the step reports a KKT point
    z = np.asarray(out[2]).ravel()
    # the step's torques do at least as well as L-BFGS-B's (1e-12: round-off of an objective of ~1e1)
    assert f(z)[0] <= best.fun + 1e-12
    # 1e-5 [N.m]: L-BFGS-B stops ~1e-6 from the minimum on this problem (curvature ~1e1-1e3)
    np.testing.assert_allclose(z, best.x, atol=1e-5)


def test_rate_bound_pulls_a_swing_up_prediction_to_the_bound(model, cache):
    # The hanging robot regulated to upright over 0.5 s: unbounded, the first step's prediction asks for joint
    # rates far past 16 rad/s; with the soft bound the same step's prediction stays near it.
    grid = (0.004,) * 13 + (0.064,) * 7
    common = dict(actuation="pendubot", u_max=6.0, intervals=grid, q_angle=2000.0, q_rate=200.0, r=500.0,
                  terminal_weights=(2e5, 2e5, 2e4, 2e4), cost_per_second=True, compiled=False)  # fmt: skip
    peaks = {}
    for vmax in (None, 16.0):
        ctrl = rti_controller(model, rate_limit=vmax, rate_weight=1e3, **common)
        ctrl(0.0, np.zeros(4))
        X = ctrl._out[1]
        peaks[vmax] = np.abs(np.column_stack([X[:, 2], X[:, 3] - X[:, 2]])).max()
    assert peaks[None] > 50.0
    assert peaks[16.0] < 30.0  # soft: a weight of 1e3 leaves some excess, but a fraction of the unbounded one


def test_cold_start_is_the_rollout_from_the_measured_state(small, model):
    # A cold call starts from the states the reference torques lead to from the measurement (no gap between the
    # shooting nodes), not from the reference states; computed here by an independent loop of RK4 intervals.
    small.reset()
    x = small.goal + np.array([2.5, -1.0, 3.0, -2.0])
    small(0.0, x)
    X = small._in[1]
    F = rk4_interval(model, [0], small.options.interval, small.options.steps_per_interval)
    xk, expected = X[0], [X[0]]
    for k in range(small.options.horizon):
        xk = np.asarray(F(xk, small._in[2][k])).ravel()
        expected.append(xk)
    np.testing.assert_allclose(X, np.array(expected), atol=1e-12)  # the same RK4 operations: round-off only
    # the first node is the measurement: its joint angles moved by whole turns, its rates as measured
    turns = (np.array([X[0][0], X[0][1] - X[0][0]]) - np.array([x[0], x[1] - x[0]])) / (2 * np.pi)
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-12)
    np.testing.assert_array_equal(X[0][2:], x[2:])


@pytest.mark.parametrize(
    ("q", "limit", "target"),
    [
        ((0.001, -0.001), None, (np.pi, 0.0)),  # hanging: the elbow's target is 0, not a whole turn away
        ((2 * np.pi + 3.0, 0.0), None, (3 * np.pi, 0.0)),  # the nearest upright
        ((2 * np.pi + 3.0, 0.0), 2 * np.pi, (np.pi, 0.0)),  # wound past the limit: steered back a turn
        ((-3.0, 0.1), 2 * np.pi, (-np.pi, 0.0)),
        ((3 * np.pi, 7 * np.pi), 2 * np.pi, (np.pi, 2 * np.pi)),  # elbow targets 0 or +-2 pi within the limit
        ((3 * np.pi, 7 * np.pi), np.pi, (np.pi, 0.0)),
    ],
)
def test_joint_wrap_targets(q, limit, target):
    ref = np.array([np.pi, np.pi, 0.0, 0.0])  # upright: joints (pi, 0)
    x = np.array([q[0], q[0] + q[1], 0.3, -0.2])
    e = joint_wrapped_error(x - ref, ref, limit)
    tx = x - e  # the target the controller steers to, absolute angles
    np.testing.assert_allclose([tx[0], tx[1] - tx[0]], target, atol=1e-12)
    np.testing.assert_array_equal(e[2:], x[2:] - ref[2:])  # rates are not wrapped


def test_joint_wrap_is_a_whole_turn_shift_within_half_a_turn():
    rng = np.random.default_rng(7)
    ref = np.array([np.pi, np.pi, 0.0, 0.0])
    for _ in range(200):
        x = np.concatenate([rng.uniform(-20, 20, 2), rng.normal(size=2)])
        e = joint_wrapped_error(x - ref, ref)
        shift = np.array([(x - e - ref)[0], (x - e - ref)[1] - (x - e - ref)[0]]) / (2 * np.pi)
        np.testing.assert_allclose(shift, np.round(shift), atol=1e-9)  # the target is the reference a whole turn on
        assert np.all(np.abs([e[0], e[1] - e[0]]) <= np.pi + 1e-12)  # and the nearest such target


@pytest.mark.parametrize(
    ("option", "value"), [("rate_limit", 0.0), ("rate_limit", float("nan")), ("rate_weight", -1.0), ("angle_limit", float("inf"))]
)
def test_bad_rate_and_angle_options_name_the_option(option, value):
    from pendulab._inputs import InputError

    with pytest.raises(InputError, match=option):
        RTIOptions(**{option: value})


def test_elastic_rti_regulates_the_spring_pendulum_upright(cache):
    # The 8-state elastic prediction (soft springs, k = 1000 N/m): the compiled step equals its graph, and 50 Hz
    # regulation from a lean brings the undamped spring pendulum upright, its springs near their static lengths.
    import pendulab as pl
    from pendulab.control.feedback import as_feedback

    model = elastic(m1=0.52, m2=0.63, L1=0.2, L2=0.3, k1=1000.0, k2=1000.0, b1=0.001, b2=0.001)
    ctrl = rti_controller(model, actuation="pendubot", u_max=6.0, horizon=10, interval=0.02, sample_time=0.02,
                          cache_directory=cache)  # fmt: skip
    assert ctrl.options.substeps >= 2  # at most 10 ms per RK4 step
    rng = np.random.default_rng(3)
    inp = _inputs(ctrl, rng, ctrl.goal + np.r_[0.1, -0.05, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0])
    for name, u, v in zip(ctrl.graph.name_out(), ctrl.graph(*inp), ctrl.step(*inp), strict=True):
        assert float(ca.norm_inf(u - v)) <= 1e-12 * max(1.0, float(ca.norm_inf(u))), name  # round-off only
    x0 = ctrl.goal + np.r_[0.15, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    tr = pl.simulate(model, x0, 4.0, dt=0.02, u=as_feedback(ctrl, model))
    end = tr.x[-1]
    # 1e-3 rad: held upright (measured 1e-5; the undamped springs keep ringing and couple into the angles)
    np.testing.assert_allclose(end[:2], ctrl.goal[:2], atol=1e-3)
    # 5 mm: the spring lengths about their static values upright (measured 2 mm: the undamped spring modes ring on)
    np.testing.assert_allclose(end[2:4], ctrl.goal[2:4], atol=5e-3)
    assert ctrl.stats()["failures"] == 0

"""Real-time-iteration NMPC (controller ``rti``): compiled step = graph, LQ/QP exactness, swing-up, bad input, cache."""

from __future__ import annotations

import os

import casadi as ca
import numpy as np
import pytest

from pendulab.control.feedback import upright_state
from pendulab.control.lqr import lqr_balance
from pendulab.control.nmpc.rti import RTIOptions, rti_controller, rti_for_task
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
    return H, g, P


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
    with pytest.raises(ValueError, match="rigid"):
        rti_controller(elastic(), u_max=6.0)


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

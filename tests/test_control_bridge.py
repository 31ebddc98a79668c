"""python-control bridge, controllability report and LQR balancing (linear and nonlinear checks)."""

import math

import control as ct
import numpy as np
import pytest

import pendulab as pl
from pendulab.control import (
    UncontrollableError,
    balanced,
    controllability_report,
    lqr_balance,
    region_of_attraction,
    simulate_balance,
    to_nlsys,
    to_statespace,
)


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_python_control_fd_linearize_agrees_with_exact(kind):
    model = pl.make_model(kind, m2=1.4, b1=0.1)
    eq = pl.equilibrium(model, "up-up")
    sys = to_nlsys(model, "pendubot", outputs="positions")
    fd = ct.linearize(sys, eq.x, [0.0], copy_names=True)
    exact = to_statespace(model, eq, actuation="pendubot", outputs="positions")
    # python-control differentiates with eps = 1e-6 (one-sided): error ~ eps |f''| ~ 1e-6 of the largest entry.
    for name in "ABCD":
        a, b = getattr(fd, name), getattr(exact, name)
        np.testing.assert_allclose(a, b, atol=1e-4 * max(1.0, np.abs(b).max()), err_msg=name)
    assert fd.state_labels == list(model.state_names) == exact.state_labels
    assert exact.input_labels == ["tau1"] and exact.output_labels == ["x1", "y1", "x2", "y2"]


def test_nlsys_params_and_operating_point():
    model = pl.rigid()
    sys = to_nlsys(model, "full")
    assert sys.params["m2"] == 1.0 and set(sys.params) == set(model.param_names)
    # find_operating_point from a perturbed guess recovers the Newton equilibrium (root-finder tolerance).
    op = ct.find_operating_point(sys, [3.0, 3.3, 0.0, 0.0], [0.0, 0.0])
    np.testing.assert_allclose(op.states, [math.pi, math.pi, 0, 0], atol=1e-6)
    # Simulation with changed params agrees with pendulab's own integrator on the changed model.
    T = np.linspace(0.0, 2.0, 21)
    x0 = [0.3, -0.2, 0.0, 0.0]
    resp = ct.input_output_response(
        sys, T, np.zeros((2, T.size)), x0, params={"m2": 2.0}, solve_ivp_kwargs={"rtol": 1e-10, "atol": 1e-10}
    )
    ref = pl.simulate(model.with_params(m2=2.0), x0, 2.0, dt=0.1, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(resp.states.T, ref.x, atol=1e-7)  # two integrators at 1e-10 over a non-chaotic 2 s
    with pytest.raises(ValueError, match=r"unknown parameter name\(s\) \['mass'\]"):
        ct.input_output_response(sys, T, 0.0, x0, params={"mass": 2.0})
    with pytest.raises(ValueError, match="parameter 'm2' must be > 0"):
        ct.input_output_response(sys, T, 0.0, x0, params={"m2": -1.0})


def test_named_signals_survive_lqr_feedback_interconnect():
    model = pl.rigid()
    plant = to_statespace(model, "up-up", actuation="acrobot")
    K, _, _ = ct.lqr(plant, np.eye(4), np.eye(1))
    ctrl = ct.ss([], [], [], -K, inputs=plant.output_labels, outputs=plant.input_labels, name="lqr")
    loop = ct.interconnect([plant, ctrl], inputs=[], outputs=["theta1", "theta2", "tau2"])
    # ct.feedback (0.10.2) numbers signals generically unless given names; the plant's labels carry over as-is.
    gain = ct.ss([], [], [], K, inputs=plant.output_labels, outputs=["tau2"])
    fb = ct.feedback(plant, gain, inputs=plant.input_labels, outputs=plant.output_labels, states=plant.state_labels)
    expected = np.sort_complex(np.linalg.eigvals(plant.A - plant.B @ K))
    for closed in (loop, fb):
        np.testing.assert_allclose(np.sort_complex(closed.poles()), expected, rtol=1e-9)  # same matrices
        assert all(p.real < 0 for p in closed.poles())
    assert loop.output_labels == ["theta1", "theta2", "tau2"]
    assert fb.state_labels == list(model.state_names) and fb.input_labels == ["tau2"]
    # Our subspace LQR equals python-control's when the pair is controllable.
    np.testing.assert_allclose(lqr_balance(model, "acrobot").K, K, rtol=1e-8)


def test_controllability_report_rigid_and_elastic():
    rigid_rows = controllability_report(pl.rigid())
    assert len(rigid_rows) == 12 and all(r.ctrb_rank == 4 and r.obsv_rank == 4 for r in rigid_rows)
    model = pl.elastic(m1=0.8, m2=1.5, k1=900.0, k2=400.0)
    rows = controllability_report(model, actuations=("pendubot",), outputs=("theta1", "theta2"))
    positions = controllability_report(model, actuations=("acrobot",), outputs="positions")
    for r in rows:
        # Radial motion decouples at vertical equilibria: torques cannot reach it, encoders cannot see it.
        assert (r.ctrb_rank, r.obsv_rank) == (4, 4) and r.ctrb_min_sv < 1e-12
        assert set(r.ctrb_weakest) == set(r.obsv_weakest) == {"r1", "r2", "v1", "v2"}
        wn = np.sort(np.abs(r.uncontrollable_eigenvalues))
        c = 1.0 if r.equilibrium in ("down-down", "up-up") else -1.0  # e1.e2 (see test_modes)
        M = np.array([[2.3, 1.5 * c], [1.5 * c, 1.5]])
        radial = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, np.diag([900.0, 400.0]))).real))
        np.testing.assert_allclose(wn, np.repeat(radial, 2), rtol=1e-8)  # +-i omega of the two spring modes
    assert all(r.obsv_rank == 8 for r in positions)  # bob positions do see the springs
    # A holding torque tilts the links: gravity then couples radial and angular motion, so all 8 states are reachable.
    tilted = controllability_report(model, at=pl.equilibria(model, [3.0, 2.0]), actuations=("acrobot",))
    assert all(r.ctrb_rank == 8 and r.obsv_rank == 8 and r.ctrb_min_sv > 0 for r in tilted)


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("actuation", ["full", "pendubot", "acrobot"])
def test_lqr_balances_nonlinear_model(kind, actuation):
    model = pl.make_model(kind)
    design = lqr_balance(model, actuation)
    cl = design.closed_loop_eigenvalues
    if kind == "rigid":
        assert cl.real.max() < -0.5
    else:
        # Controllable part stable; the 4 spring eigenvalues stay on the imaginary axis (undamped, unreachable).
        assert np.sum(cl.real < -0.5) == 4 and np.allclose(np.sort(np.abs(cl.real))[:4], 0, atol=1e-9)
    x0 = design.x_eq.copy()
    x0[:2] += [0.08, -0.06]
    u_max = 40.0
    traj = simulate_balance(model, design, x0, t_final=6.0, u_max=u_max)
    assert np.abs(traj.u).max() <= u_max  # saturation honoured
    unact = [i for i in (0, 1) if i not in design.input_indices]
    assert np.all(traj.u[:, unact] == 0.0)
    late = traj.t > 4.0
    if kind == "rigid":
        assert balanced(design, traj.x[-1], tol=1e-3)  # slowest closed-loop mode ~0.5 s: 6 s leaves < 1e-3
    else:
        # Undamped springs keep ringing after the transient and shake the angles at second order; still upright.
        assert all(balanced(design, x, tol=5e-2) for x in traj.x[late])


def test_lqr_elastic_acrobot_settles_with_spring_damping():
    model = pl.elastic(c1=6.0, c2=6.0)
    design = lqr_balance(model, "acrobot")
    assert design.closed_loop_eigenvalues.real.max() < 0  # damped springs: every mode now decays
    x0 = design.x_eq.copy()
    x0[:2] += [0.08, -0.06]
    traj = simulate_balance(model, design, x0, t_final=6.0, u_max=40.0)
    np.testing.assert_allclose(
        traj.x[-1], design.x_eq, atol=1e-3
    )  # slowest spring mode: -Re(lambda) ~ 1.1/s, so 6 s divides 0.05 m by ~700


def test_discrete_lqr_matches_c2d_dlqr_and_balances():
    model = pl.rigid()
    dt = 0.02
    design = lqr_balance(model, "pendubot", dt=dt)
    plant = ct.c2d(to_statespace(model, "up-up", actuation="pendubot"), dt, method="zoh")
    Kd, _, _ = ct.dlqr(plant.A, plant.B, np.eye(4), np.eye(1))
    np.testing.assert_allclose(design.K, Kd, rtol=1e-7)  # same Riccati problem, two discretizations (expm both)
    assert np.abs(design.closed_loop_eigenvalues).max() < 1
    x0 = design.x_eq + [0.05, 0.05, 0.0, 0.0]
    traj = simulate_balance(model, design, x0, t_final=6.0)
    assert np.allclose(np.diff(traj.t), dt) and balanced(design, traj.x[-1], tol=1e-3)


def test_saturation_shrinks_region_of_attraction():
    model = pl.rigid()
    design = lqr_balance(model, "pendubot")
    kw = {"directions": {"theta1": (1.0, 0.0)}, "t_final": 4.0, "tol": 0.05, "amplitude_max": 1.2}
    strong = region_of_attraction(model, design, u_max=30.0, **kw)[0]
    weak = region_of_attraction(model, design, u_max=8.0, **kw)[0]
    assert 0.05 < weak.amplitude < strong.amplitude  # less torque, smaller basin
    # Bisection bracket: the returned amplitude converges, amplitude + tol does not.
    x0 = design.x_eq.copy()
    x0[0] += weak.amplitude + 0.05
    assert not balanced(design, simulate_balance(model, design, x0, 4.0, u_max=8.0).x[-1])


@pytest.mark.parametrize(
    ("call", "exc", "fragment"),
    [
        (lambda: lqr_balance(pl.rigid(), "monobot"), ValueError, "unknown actuation 'monobot'"),
        (lambda: lqr_balance(pl.rigid(), at="upright"), ValueError, "unknown equilibrium name 'upright'"),
        (lambda: lqr_balance(pl.rigid(lc2=0.0, I2=0.1), "pendubot"), UncontrollableError, "uncontrollable configuration"),
        (lambda: lqr_balance(pl.rigid(), Q=np.eye(3)), ValueError, r"Q must be a finite \(4, 4\)"),
        (lambda: lqr_balance(pl.rigid(), "pendubot", R=[[-1.0]]), ValueError, "R must be positive definite"),
        (lambda: lqr_balance(pl.rigid(), dt=-0.1), ValueError, r"dt = -0.1: out of range; expected a finite number in \[1e-09"),
        (lambda: to_statespace(pl.rigid(), [0.0, 0.0]), ValueError, r"x must have shape \(4,\)"),
        (lambda: to_statespace(pl.rigid(), [0.0, np.nan, 0.0, 0.0]), ValueError, "x must be finite"),
        (lambda: to_nlsys(pl.rigid(), "both"), ValueError, "unknown actuation 'both'"),
        (lambda: to_statespace(pl.rigid(), "up-up", outputs="stretch"), ValueError, "needs the elastic model"),
    ],
)
def test_bad_input(call, exc, fragment):
    with pytest.raises(exc, match=fragment):
        call()


def test_uncontrollable_error_is_a_value_error_naming_the_modes():
    # Pendubot with link 2's centre of mass on its joint: link 2 is a free flywheel the motor cannot reach.
    with pytest.raises(ValueError, match=r"rank 2 of 4.*\[0\.0, 0\.0\]"):
        lqr_balance(pl.rigid(lc2=0.0, I2=0.1), "pendubot")

"""The shared control building blocks: ZOH, LQR cost-to-go, upright equilibrium, argument checks."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import solve_discrete_are
from scipy.signal import cont2discrete

import pendulab as pl
from pendulab._checks import positive_float
from pendulab.control import LinearStateFeedback, SampledController, TVLQRTracker, actuation_name, lqr_balance, upright_state, zoh


def test_zoh_matches_scipy_cont2discrete():
    lin = pl.linearize(pl.elastic(), pl.equilibrium(pl.elastic(), "up-up"))
    Ad, Bd = zoh(lin.A, lin.B, 0.02)
    Ad2, Bd2, *_ = cont2discrete((lin.A, lin.B, np.eye(8), np.zeros((8, 2))), 0.02, method="zoh")
    # Both are matrix exponentials of the same augmented matrix; round-off only.
    np.testing.assert_allclose(Ad, Ad2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(Bd, Bd2, rtol=0, atol=1e-12)


def test_discrete_cost_to_go_equals_full_state_riccati_for_the_elastic_model():
    """The design works on the controllable subspace; its P adds the decay cost of the (damped) spring modes."""
    model = pl.elastic(c1=2.0, c2=2.0)
    Q = np.diag([10.0, 10.0, 100.0, 100.0, 1.0, 1.0, 0.1, 0.1])
    R = np.eye(2) * 0.03
    design = lqr_balance(model, "full", Q, R, dt=0.01)
    lin = pl.linearize(model, pl.equilibrium(model, "up-up"))
    Ad, Bd = zoh(lin.A, lin.B, 0.01)
    P = solve_discrete_are(Ad, Bd, Q, R)  # independent path: the full (stabilizable) system at once
    K = np.linalg.solve(R + Bd.T @ P @ Bd, Bd.T @ P @ Ad)
    # Two Riccati/Lyapunov solvers on a system with ~1e4-sized entries in P: relative round-off.
    np.testing.assert_allclose(design.P, P, rtol=1e-6, atol=1e-6 * np.abs(P).max())
    np.testing.assert_allclose(design.K, K, rtol=1e-6, atol=1e-6 * np.abs(K).max())


def test_goal_state_design_equals_named_equilibrium_design():
    model = pl.rigid()
    named = lqr_balance(model, "pendubot", dt=0.01)
    by_state = lqr_balance(model, ("tau1",), dt=0.01, at=upright_state(model))
    # Same linearization point (Newton converged to round-off): same gain.
    np.testing.assert_allclose(by_state.K, named.K, rtol=1e-10)
    assert by_state.input_names == ("tau1",)


def test_upright_state_has_the_analytic_compressed_springs():
    model = pl.elastic(k1=800.0, k2=600.0)
    p = model.params
    x = upright_state(model)
    # Newton-solved vs the closed form of the static spring balance at the vertical.
    np.testing.assert_allclose(x[2:4], [p.L1 - (p.m1 + p.m2) * p.g / p.k1, p.L2 - p.m2 * p.g / p.k2], rtol=0, atol=1e-12)
    np.testing.assert_allclose(x[:2], [np.pi, np.pi], rtol=0, atol=1e-12)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), "x", None])
def test_positive_float_names_argument_and_value(bad):
    with pytest.raises(ValueError, match=r"sample_time must be a positive"):
        positive_float("sample_time", bad)


def test_actuation_name_from_input_names():
    assert actuation_name(("tau2",)) == "acrobot"
    assert actuation_name(["tau2", "tau1"]) == "full"
    with pytest.raises(ValueError, match="non-empty subset"):
        actuation_name(("tau3",))
    with pytest.raises(ValueError, match="unknown actuation 'both'"):
        actuation_name("both")


def test_swingup_tracking_controller_is_a_sampled_controller():
    model = pl.rigid()
    goal = upright_state(model)
    K_top = lqr_balance(model, "pendubot", dt=0.02).K
    K_full = np.vstack([K_top, np.zeros_like(K_top)])  # passive elbow: a zero row
    final = LinearStateFeedback(model, K_full, goal, np.zeros(2), 0.02, ("tau1", "tau2"), 5.0)
    ctrl = TVLQRTracker(model, [0.0, 0.02], np.vstack([goal, goal]), np.zeros((1, 2)), K_full[None], 0.02, final=final, u_max=5.0)
    assert isinstance(ctrl, SampledController)
    assert ctrl.sample_time == 0.02 and ctrl.input_names == ("tau1", "tau2")
    x = goal + np.array([0.01, 0.0, 0.0, 0.0])
    # Passive elbow gets exactly zero; the shoulder torque is the LQR law on the 0.01 rad error,
    # on the reference (t = 0.01 s) and after it (t = 0.1 s, the final controller).
    for t in (0.01, 0.1):
        np.testing.assert_allclose(ctrl(t, x), [-(K_top @ (x - goal))[0], 0.0], rtol=1e-12, atol=0)

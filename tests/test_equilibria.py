"""Equilibria: analytic angles and static spring stretch, stability counts, torque-held arms, bad input."""

import math

import numpy as np
import pytest

import pendulab as pl

VERTICAL = {"down-down": (0.0, 0.0), "down-up": (0.0, math.pi), "up-down": (math.pi, 0.0), "up-up": (math.pi, math.pi)}
UNSTABLE = {"down-down": 0, "down-up": 1, "up-down": 1, "up-up": 2}


@pytest.mark.parametrize("model", [pl.rigid(m1=0.7, m2=1.3, L1=0.8, L2=1.1), pl.rigid(lc1=0.4, I1=0.05, lc2=0.6, I2=0.02)])
def test_rigid_vertical_equilibria(model):
    eqs = pl.equilibria(model)
    assert [e.name for e in eqs] == list(VERTICAL)
    for e in eqs:
        # Newton converges to round-off on O(1) accelerations.
        np.testing.assert_allclose(e.x, [*VERTICAL[e.name], 0.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(model.rhs(e.x), 0.0, atol=1e-10)
        assert e.n_unstable == UNSTABLE[e.name]
        assert e.stable == (e.name == "down-down")


def test_elastic_static_stretch_matches_force_balance():
    m1, m2, L1, L2, k1, k2, g = 0.7, 1.3, 0.8, 1.1, 300.0, 800.0, 9.81
    model = pl.elastic(m1=m1, m2=m2, L1=L1, L2=L2, k1=k1, k2=k2)
    for e in pl.equilibria(model):
        c1, c2 = (math.cos(a) for a in VERTICAL[e.name])
        # Vertical chain: spring 2 carries bob 2's weight, spring 1 both weights (signs flip when a link points up).
        r1 = L1 + (m1 + m2) * g * c1 / k1
        r2 = L2 + m2 * g * c2 / k2
        np.testing.assert_allclose(e.x[:4], [*VERTICAL[e.name], r1, r2], atol=1e-12)
        assert e.n_unstable == UNSTABLE[e.name]


def test_soft_springs_cannot_hold_upright():
    model = pl.elastic(k1=5.0, k2=500.0)  # (m1 + m2) g / k1 = 3.9 m > L1: spring 1 cannot carry the chain upright
    names = [e.name for e in pl.equilibria(model)]
    assert names == ["down-down", "down-up"]
    with pytest.raises(ValueError, match="too soft"):
        pl.equilibrium(model, "up-up")


def test_rigid_torque_held_angles_analytic():
    m1, m2, L1, L2, g = 1.2, 0.8, 0.9, 0.6, 9.81
    model = pl.rigid(m1=m1, m2=m2, L1=L1, L2=L2)
    u = np.array([4.0, 1.5])
    # Static balance on absolute angles: (m1 + m2) g L1 sin(th1) = tau1 - tau2, m2 g L2 sin(th2) = tau2.
    s1 = (u[0] - u[1]) / ((m1 + m2) * g * L1)
    s2 = u[1] / (m2 * g * L2)
    expected = {
        "down-down": (math.asin(s1), math.asin(s2)),
        "down-up": (math.asin(s1), math.pi - math.asin(s2)),
        "up-down": (math.pi - math.asin(s1), math.asin(s2)),
        "up-up": (math.pi - math.asin(s1), math.pi - math.asin(s2)),
    }
    for e in pl.equilibria(model, u):
        np.testing.assert_allclose(e.x[:2], expected[e.name], atol=1e-12)  # Newton to round-off
        np.testing.assert_allclose(e.u, u)
        assert e.n_unstable == UNSTABLE[e.name]


def test_torque_held_elastic_arm_decays_back_at_the_modal_rate():
    model = pl.elastic(k1=200.0, k2=200.0, b1=3.0, b2=1.0, c1=3.0, c2=3.0)
    u = np.array([3.0, 2.0])
    eq = pl.equilibrium(model, "down-down", u)
    assert eq.stable and abs(eq.x[0]) > 0.02 and abs(eq.x[1]) > 0.1  # visibly tilted
    np.testing.assert_allclose(model.rhs(eq.x, u), 0.0, atol=1e-10)
    tau = max(m.time_constant for m in pl.modes(model, eq))
    x0 = eq.x + np.array([0.05, -0.05, 0.01, 0.0, 0, 0, 0, 0])
    traj = pl.simulate(model, x0, 6 * tau, dt=0.1, u=u, rtol=1e-9, atol=1e-9)
    # After 6 slowest time constants a 0.05 perturbation shrinks to ~0.05 e^-6 (x mode-shape factors) ~ 2e-4.
    np.testing.assert_allclose(traj.x[-1], eq.x, atol=1e-3)
    err = np.abs(traj.x - eq.x).max(axis=1)
    assert err[traj.t > 3 * tau].max() > 1e-4  # ...and not much faster: the slowest mode really is that slow


def test_equilibrium_eigenvalues_are_those_of_the_linearization():
    model = pl.elastic()
    eq = pl.equilibrium(model, "up-down")
    ev = np.sort_complex(np.linalg.eigvals(pl.linearize(model, eq).A))
    np.testing.assert_allclose(np.sort_complex(eq.eigenvalues), ev, atol=1e-9)  # same matrix, same LAPACK call


@pytest.mark.parametrize(
    ("call", "exc", "fragment"),
    [
        (lambda: pl.equilibrium(pl.rigid(), "sideways"), ValueError, "unknown equilibrium name 'sideways'"),
        (lambda: pl.equilibrium(pl.rigid(), "up-up", [1.0, 2.0, 3.0]), ValueError, "u must have shape"),
        (lambda: pl.equilibrium(pl.rigid(), "up-up", [np.nan, 0.0]), ValueError, "u must be finite"),
        (lambda: pl.equilibria(pl.rigid(), [0.0, 50.0]), ValueError, "exceeds the largest gravity torque"),
        (lambda: pl.equilibria(pl.rigid(g=0.0)), ValueError, "without gravity"),
    ],
)
def test_bad_input(call, exc, fragment):
    with pytest.raises(exc, match=fragment):
        call()

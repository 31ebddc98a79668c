"""Energy conservation and the power balance dE/dt = P_in - P_diss.

The total energy E = T + V (gravity and springs, pivot at height 0) is the
invariant that does not suffer the chaotic amplification of trajectory
errors, so it tests both the derivation and the integrators.
"""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

import pendulab as pl

CHAOTIC = {"theta1": 2.0, "theta2": 2.0}


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_energy_conserved_chaotic_20s(kind):
    model = pl.make_model(kind)
    x0 = model.state(**CHAOTIC)  # elastic: springs at their static hanging length
    # CVODES Adams (orders up to 12) at 1e-13 is the cheapest tight method here:
    # it measures ~6e-11 drift on both models, 15x under the bound.
    traj = pl.simulate(model, x0, 20.0, dt=0.01, method="cvodes-adams", rtol=1e-13, atol=1e-13)
    e = traj["energy"]
    drift = np.max(np.abs(e - e[0])) / abs(e[0])
    assert abs(e[0] - model.energy(x0)) < 1e-14 * abs(e[0])  # output channel = energy function
    assert drift < 1e-9  # the bound for a tight-tolerance run


def _power_expected(model, x, u):
    """tau1 w1 + tau2 (w2 - w1) - b1 w1^2 - b2 (w2 - w1)^2 [- c1 v1^2 - c2 v2^2] [- cf_i atan(100 q_i') q_i'],
    typed here from the conventions."""
    pr = model.params
    w1, w2 = x[model.nq], x[model.nq + 1]
    p = u[0] * w1 + u[1] * (w2 - w1) - pr.b1 * w1**2 - pr.b2 * (w2 - w1) ** 2
    if model.kind == "elastic":
        v1, v2 = x[6], x[7]
        p -= pr.c1 * v1**2 + pr.c2 * v2**2
    else:
        p -= pr.cf1 * np.arctan(100.0 * w1) * w1 + pr.cf2 * np.arctan(100.0 * (w2 - w1)) * (w2 - w1)
    return p


def _dE_dt_function(model):
    """dE/dt = grad E(x) . f(x, u, p), formed symbolically from the model's own Functions."""
    f = model.functions
    x = ca.SX.sym("x", model.nx)
    u = ca.SX.sym("u", 2)
    p = ca.SX.sym("p", len(model.p))
    dE = ca.jtimes(f["energy"](x, p), x, f["rhs"](x, u, p))
    return ca.Function("dE_dt", [x, u, p], [dE])


DAMPED = {
    "rigid": dict(b1=0.3, b2=0.2, lc1=0.6, lc2=0.45, I1=0.05, I2=0.02),
    "elastic": dict(b1=0.3, b2=0.2, c1=1.5, c2=0.8, k1=200.0, k2=300.0),
    # a robot's drivetrain: geared rotors (their kinetic energy is part of E) and Coulomb friction
    "robot": dict(b1=0.3, b2=0.2, lc1=0.6, lc2=0.45, I1=0.05, I2=0.02, Ir=0.002, gr=6.0, cf1=0.2, cf2=0.1),
}
KINDS = ["rigid", "elastic", "robot"]


def _damped_model(kind):
    return pl.make_model("elastic" if kind == "elastic" else "rigid", **DAMPED[kind])


@pytest.mark.parametrize("kind", KINDS)
def test_power_identity_pointwise(kind):
    model = _damped_model(kind)
    dE = _dE_dt_function(model)
    rng = np.random.default_rng(11)
    for _ in range(50):
        x = model.state(theta1=rng.uniform(-np.pi, np.pi), theta2=rng.uniform(-np.pi, np.pi))
        x[model.nq :] = rng.uniform(-4.0, 4.0, model.nq)
        if kind == "robot" and _ < 10:  # near rest, where the smoothed Coulomb friction is not yet saturated
            x[model.nq :] *= 1e-3
        if kind == "elastic":
            x[2:4] *= rng.uniform(0.8, 1.2, 2)
        u = rng.uniform(-2.0, 2.0, 2)
        expected = _power_expected(model, x, u)
        scale = 1.0 + abs(expected) + model.dissipation(x)
        # An identity in exact arithmetic; measured round-off ~1e-14 of terms of order 10-100 W.
        assert abs(float(dE(x, u, model.p)) - expected) < 1e-11 * scale
        # The model's own power channels agree with the expression typed here.
        assert abs(model.power_in(x, u) - model.dissipation(x) - expected) < 1e-12 * scale


@pytest.mark.parametrize("kind", KINDS)
def test_power_balance_along_trajectory(kind):
    """E(t) - E(0) equals the integral of P_in - P_diss along a damped, driven trajectory."""
    model = _damped_model(kind)
    u = np.array([0.8, -0.5])  # constant torques: the power is smooth, Simpson's rule applies
    x0 = model.state(theta1=1.2, theta2=-0.7, omega2=1.0)
    traj = pl.simulate(model, x0, 5.0, dt=2e-3, method="cvodes-adams", rtol=1e-12, atol=1e-12, u=u)
    power = model.power_in(traj.x, u) - model.dissipation(traj.x)
    injected = cumulative_simpson(power, x=traj.t, initial=0.0)
    change = traj["energy"] - traj["energy"][0]
    scale = np.max(np.abs(injected))
    assert scale > 1.0  # the dampers and torques do exchange joules over the run
    # Simpson's rule at h = 2 ms leaves 5e-8 (rigid) / 5e-9 (elastic) of the exchange; halving h
    # divides it by 16, so it is quadrature error, not physics: 1e-6 keeps a 20x margin.
    assert np.max(np.abs(change - injected)) < 1e-6 * scale


# Not the robot: its Coulomb friction switches within ~0.01 rad/s of each rate reversal, a kink Simpson's
# rule at 2 ms resolves only to ~5e-7; this test is about the zero-order hold, the two above cover friction.
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_power_balance_with_time_varying_torque(kind):
    """Sampled torques (zero-order hold): balance per hold block, each block spanning two output steps."""
    model = _damped_model(kind)
    dt, t_final = 2e-3, 3.0
    n_blocks = round(t_final / dt) // 2
    tb = np.arange(n_blocks) * 2 * dt
    u_blocks = np.column_stack([1.5 * np.sin(2.0 * tb), 0.8 * np.cos(3.0 * tb)])
    u_grid = np.repeat(u_blocks, 2, axis=0)  # one row per output interval, constant over each block
    traj = pl.simulate(model, model.state(theta1=0.4, theta2=-0.2), t_final, dt=dt, method="cvodes-adams",
                       rtol=1e-12, atol=1e-12, u=u_grid)  # fmt: skip
    x, e = traj.x, traj["energy"]
    injected = 0.0
    worst, scale = 0.0, 0.0
    for j, uj in enumerate(u_blocks):
        # Simpson's rule on one block, the block's torque at all three points (including its end point).
        xs = x[2 * j : 2 * j + 3]
        p = model.power_in(xs, uj) - model.dissipation(xs)
        injected += dt / 3.0 * (p[0] + 4.0 * p[1] + p[2])
        worst = max(worst, abs(e[2 * j + 2] - e[0] - injected))
        scale = max(scale, abs(injected))
    assert scale > 0.5  # the torques do exchange energy
    # Measured 3e-9 of the exchange (quadrature); a CVODES run that carried its multistep history
    # across the torque jumps was 2.5e-7 off, so 1e-7 separates the two.
    assert worst < 1e-7 * scale

"""Analytic limits: static equilibria, the rigid limit k -> inf, small oscillations."""

import numpy as np
import pytest

import pendulab as pl


def _elastic_hanging(model, up=False):
    """Static lengths computed here: spring 1 carries (m1 + m2) g, spring 2 carries m2 g
    (stretched when hanging, compressed when balanced upright)."""
    pr = model.params
    sign = -1.0 if up else 1.0
    r1 = pr.L1 + sign * (pr.m1 + pr.m2) * pr.g / pr.k1
    r2 = pr.L2 + sign * pr.m2 * pr.g / pr.k2
    angle = np.pi if up else 0.0
    return np.array([angle, angle, r1, r2, 0.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("up", [False, True])
def test_elastic_static_equilibrium(up):
    rng = np.random.default_rng(5)
    for _ in range(10):
        model = pl.elastic(
            m1=rng.uniform(0.2, 3.0), m2=rng.uniform(0.2, 3.0), L1=rng.uniform(0.5, 2.0), L2=rng.uniform(0.5, 2.0),
            g=rng.uniform(1.0, 12.0), k1=rng.uniform(200.0, 5000.0), k2=rng.uniform(200.0, 5000.0),
            b1=0.1, b2=0.1, c1=0.5, c2=0.5,
        )  # fmt: skip
        x = _elastic_hanging(model, up)
        # Forces of order m g ~ 10 N balance to round-off.
        np.testing.assert_allclose(model.rhs(x), 0.0, atol=1e-12)
        if not up:
            np.testing.assert_allclose(model.rest_state(), x, rtol=1e-15)  # the model's rest state is this one

        # Stretch spring 1 by d: only r1 and r2 accelerate. With theta1 = theta2 the radial
        # mass matrix is [[m1 + m2, m2], [m2, m2]], so r1'' = -k1 d / m1 and r2'' = +k1 d / m1.
        d = 1e-3
        pr = model.params
        xp = x.copy()
        xp[2] += d
        a = model.rhs(xp)
        np.testing.assert_allclose(a[6:8], [-pr.k1 * d / pr.m1, pr.k1 * d / pr.m1], rtol=1e-9)  # exact linear in d
        np.testing.assert_allclose(a[4:6], 0.0, atol=1e-12)  # a radial push makes no torque

        # Tilting link 1 alone (link 2 stays vertical): to first order in d, as for a rigid double
        # pendulum of lengths r, theta1'' = -+(m1 + m2) g d / (m1 r1), restoring when hanging.
        xt = x.copy()
        xt[0] += d
        expected = (1.0 if up else -1.0) * (pr.m1 + pr.m2) * pr.g * d / (pr.m1 * x[2])
        assert abs(model.rhs(xt)[4] - expected) < 1e-2 * abs(expected)  # O(d) nonlinear remainder


@pytest.mark.parametrize("angles", [(0.0, 0.0), (np.pi, np.pi), (0.0, np.pi), (np.pi, 0.0)])
def test_rigid_equilibria(angles):
    model = pl.rigid(m1=1.3, m2=0.7, L1=0.9, L2=1.4, lc1=0.5, lc2=0.8, I1=0.05, I2=0.1, b1=0.2, b2=0.1)
    x = model.state(theta1=angles[0], theta2=angles[1])
    np.testing.assert_allclose(model.rhs(x), 0.0, atol=1e-13)  # sin(pi) ~ 1e-16 times g ~ 10
    x[1] += 1e-3
    assert np.max(np.abs(model.rhs(x))) > 1e-3  # a tilted link 2 is not at rest


def test_rigid_limit_as_k_grows():
    """Elastic angle trajectories converge to the rigid ones, with error ~ 1/k."""
    start = {"theta1": 0.5, "theta2": 0.3}
    rigid = pl.rigid()
    ref = pl.simulate(rigid, rigid.state(**start), 2.0, dt=0.01, method="cvodes-adams", rtol=1e-12, atol=1e-12)
    errors = []
    for k in (1e2, 1e3, 1e4, 1e5):
        model = pl.elastic(k1=k, k2=k)
        # Integration error (~1e-9 at these tolerances) stays far below the model error (>= 1e-4).
        traj = pl.simulate(model, model.state(**start), 2.0, dt=0.01, method="cvodes-adams", rtol=1e-11, atol=1e-11)
        errors.append(np.max(np.abs(traj.x[:, :2] - ref.x[:, :2])))
    errors = np.array(errors)
    assert np.all(np.diff(errors) < 0), errors
    ratios = errors[:-1] / errors[1:]
    # Measured 4.4, 9.3, 10.1: the asymptotic 1/k regime is reached from k = 1e3 on.
    assert np.all((ratios[1:] > 7.0) & (ratios[1:] < 14.0)), ratios
    assert errors[-1] < 1e-3  # static stretch 2 g / k = 2e-4 m at k = 1e5


CASES = [(1.0, 1.0, 9.81), (0.5, 2.0, 9.81), (3.0, 0.7, 1.62)]


@pytest.mark.parametrize(("m", "L", "g"), CASES)
def test_small_oscillation_frequencies_from_jacobian(m, L, g):
    model = pl.rigid(m1=m, m2=m, L1=L, L2=L, g=g)
    A, _ = model.functions["jac_rhs"](model.rest_state(), [0.0, 0.0], model.p)
    eig = np.linalg.eigvals(np.asarray(A))
    # Undamped: purely imaginary pairs (round-off ~1e-15 on entries of order g / L).
    assert np.max(np.abs(eig.real)) < 1e-9 * g / L
    omega2 = np.sort(np.abs(eig.imag))[::2] ** 2
    expected = np.array([2 - np.sqrt(2), 2 + np.sqrt(2)]) * g / L
    np.testing.assert_allclose(omega2, expected, rtol=1e-12)  # eigenvalues of a 4x4 matrix, round-off only


@pytest.mark.parametrize(("mode", "shape"), [(-1, np.sqrt(2)), (+1, -np.sqrt(2))])
def test_small_oscillation_period_from_simulation(mode, shape):
    """Start in a normal mode (theta2 = +-sqrt(2) theta1) and measure the period."""
    g, L = 9.81, 1.0
    model = pl.rigid(g=g, L1=L, L2=L)
    omega = np.sqrt((2 + mode * np.sqrt(2)) * g / L)
    period = 2 * np.pi / omega
    eps = 1e-4  # rad: the measured nonlinear period shift is ~1.9 eps^2 (fast mode), 2e-8 here
    x0 = model.state(theta1=eps, theta2=shape * eps)
    traj = pl.simulate(model, x0, 6 * period, dt=1e-3, method="cvodes-adams", rtol=1e-12, atol=1e-12)
    th1, th2 = traj["theta1"], traj["theta2"]
    # Downward zero crossings of theta1, located by linear interpolation (theta1 is nearly
    # linear at a crossing of a sinusoid: interpolation error ~ (omega h)^3 / 12 rad).
    i = np.nonzero((th1[:-1] > 0) & (th1[1:] <= 0))[0]
    crossings = traj.t[i] + th1[i] / (th1[i] - th1[i + 1]) * (traj.t[i + 1] - traj.t[i])
    measured = np.diff(crossings)
    assert len(measured) >= 5
    # Integration at 1e-12 and crossing interpolation at h = 1 ms (~1e-7 s) leave the period good to ~1e-7.
    np.testing.assert_allclose(measured, period, rtol=1e-6)
    # A pure mode keeps its shape: the other mode is not excited.
    np.testing.assert_allclose(th2, shape * th1, atol=1e-6 * eps)

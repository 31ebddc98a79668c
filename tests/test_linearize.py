"""Exact linearization against central finite differences of the nonlinear model."""

import numpy as np
import pytest

import pendulab as pl

H = 1e-6


def _central_fd(f, z0):
    cols = []
    for i in range(z0.size):
        dz = np.zeros_like(z0)
        dz[i] = H
        cols.append((f(z0 + dz) - f(z0 - dz)) / (2 * H))
    return np.array(cols).T


@pytest.fixture(params=["rigid", "elastic"])
def case(request):
    model = pl.make_model(request.param, m1=0.9, m2=1.4, L1=0.7, L2=1.2, b1=0.1, b2=0.2)
    rng = np.random.default_rng(3)
    x = model.rest_state() + rng.normal(scale=0.5, size=model.nx)  # generic, non-equilibrium point
    u = np.array([0.7, -0.4])
    return model, x, u


def test_A_B_match_central_differences(case):
    model, x, u = case
    lin = pl.linearize(model, x, u)
    A_fd = _central_fd(lambda z: model.rhs(z, u), x)
    B_fd = _central_fd(lambda w: model.rhs(x, w), u)
    # Central differences with h = 1e-6: truncation ~h^2 |f'''| and round-off ~1e-16/h, both < 1e-7 here.
    np.testing.assert_allclose(lin.A, A_fd, atol=1e-6 * max(1.0, np.abs(A_fd).max()))
    np.testing.assert_allclose(lin.B, B_fd, atol=1e-6 * max(1.0, np.abs(B_fd).max()))


def test_C_D_for_model_outputs_match_central_differences(case):
    model, x, u = case
    lin = pl.linearize(model, x, u, outputs="outputs")
    assert lin.output_names == model.output_names
    C_fd = _central_fd(lambda z: model.outputs(z, u), x)
    np.testing.assert_allclose(lin.C, C_fd, atol=1e-6 * max(1.0, np.abs(C_fd).max()))  # as above
    np.testing.assert_allclose(lin.D, 0.0, atol=0)  # no output feeds through the torques
    np.testing.assert_allclose(lin.y0, model.outputs(x, u), rtol=1e-14)


def test_actuation_selects_columns_and_output_selection():
    model = pl.elastic()
    eq = pl.equilibrium(model, "up-up")
    full = pl.linearize(model, eq)
    pend = pl.linearize(model, eq, inputs="pendubot", outputs=["theta2", "y2", "stretch1"])
    acro = pl.linearize(model, eq, inputs="acrobot", outputs="stretch")
    np.testing.assert_array_equal(pend.B[:, 0], full.B[:, 0])
    np.testing.assert_array_equal(acro.B[:, 0], full.B[:, 1])
    assert pend.input_names == ("tau1",) and acro.input_names == ("tau2",)
    # theta2 is a state: its C row is a unit vector; stretch1 = r1 - L1 has dr1 = 1.
    np.testing.assert_array_equal(pend.C[0], np.eye(model.nx)[1])
    np.testing.assert_array_equal(pend.C[2], np.eye(model.nx)[2])
    # y2 = -r1 cos th1 - r2 cos th2 at (pi, pi): dy2/dr1 = dy2/dr2 = 1, angles do not move it to first order.
    np.testing.assert_allclose(pend.C[1, :4], [0, 0, 1, 1], atol=1e-15)
    np.testing.assert_array_equal(acro.C, np.eye(model.nx)[2:4])


def test_energy_gradient_vanishes_at_equilibria():
    model = pl.elastic(k1=300.0)
    for eq in pl.equilibria(model):
        lin = pl.linearize(model, eq, outputs="energy")
        # Equilibria are stationary points of the total energy (zero velocity, zero potential gradient).
        np.testing.assert_allclose(lin.C, 0.0, atol=1e-10)


def test_linearize_along_matches_pointwise():
    model = pl.rigid()
    traj = pl.simulate(model, [1.0, 2.0, 0.0, 0.0], 1.0, dt=0.25)
    U = np.tile([0.3, -0.2], (traj.t.size, 1))
    A, B = pl.analysis.linearize.linearize_along(model, traj.x, U, inputs="acrobot")
    for k in range(traj.t.size):
        lin = pl.linearize(model, traj.x[k], U[k], inputs="acrobot")
        np.testing.assert_array_equal(A[k], lin.A)
        np.testing.assert_array_equal(B[k], lin.B)


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"x": np.zeros(3)}, r"x must have shape \(4,\)"),
        ({"x": [0.0, np.inf, 0.0, 0.0]}, "x must be finite"),
        ({"x": np.zeros((2, 4))}, "single state"),
        ({"inputs": "monobot"}, "unknown actuation 'monobot'"),
        ({"outputs": "stretch"}, "needs the elastic model"),
        ({"outputs": ["theta1", "z9"]}, r"unknown signal\(s\) \['z9'\]"),
        ({"u": [1.0]}, r"u must have shape \(2,\)"),
    ],
)
def test_bad_input(kwargs, fragment):
    args = {"x": np.zeros(4)} | kwargs
    with pytest.raises(ValueError, match=fragment):
        pl.linearize(pl.rigid(), **args)

"""Fixed-step Butcher-tableau methods: orders, grid handling, symplecticity, errors."""

import numpy as np
import pytest

import pendulab as pl
from pendulab.integrate.fixed_step import FIXED_METHODS, integrate_fixed


@pytest.fixture(scope="module")
def rigid_case():
    m = pl.rigid()
    x0 = m.state(theta1=0.3, theta2=0.3)
    ref = pl.simulate(m, x0, 1.0, dt=0.1, method="DOP853", rtol=1e-13, atol=1e-13).x[-1]
    return m, x0, ref


@pytest.mark.parametrize("name", list(FIXED_METHODS))
def test_convergence_order_matches_tableau(rigid_case, name):
    m, x0, ref = rigid_case
    errs = [np.max(np.abs(pl.simulate(m, x0, 1.0, dt=0.1, method=name, max_step=h).x[-1] - ref)) for h in (0.02, 0.01)]
    order = np.log2(errs[0] / errs[1])
    # Asymptotic regime at h = 0.02 s (h * w = 0.1): measured order within 0.3 of the tableau's.
    assert abs(order - FIXED_METHODS[name].order) < 0.3, (name, errs, order)


def test_simulate_uses_exact_substeps_when_h_divides_dt():
    m = pl.elastic(k1=1e4, k2=1e4)
    x0 = m.state(theta1=0.2)
    tr = pl.simulate(m, x0, 0.5, dt=0.05, method="rk4", max_step=1e-3)
    X = integrate_fixed(m, "rk4", x0, 1e-3, 500, record_every=50)
    # Same steps in the same order: identical up to the rounding of h = dt / n_sub.
    np.testing.assert_allclose(tr.x, X, rtol=0, atol=1e-12)
    assert tr.stats["n_steps"] == 500


def test_step_rounded_down_to_fit_output_interval():
    m = pl.rigid()
    tr = pl.simulate(m, m.state(theta1=0.1), 0.1, dt=0.1, method="rk4", max_step=0.03)
    # ceil(0.1 / 0.03) = 4 steps of 0.025 s: the step never exceeds max_step.
    assert tr.stats["n_steps"] == 4 and tr.stats["step"] == pytest.approx(0.025)


def test_gauss_is_symplectic_rk4_drifts():
    m = pl.rigid()
    x0 = m.state(theta1=2.0, theta2=2.0)
    drift = {}
    for name in ("gauss4", "rk4"):
        X = integrate_fixed(m, name, x0, 0.02, 2500, record_every=25)
        E = m.energy(X)
        drift[name] = np.max(np.abs(E - E[0]))
    # Symplectic Gauss keeps energy bounded (chaotic 50 s run); RK4 at the same step drifts far more.
    assert drift["gauss4"] < 0.05 * drift["rk4"], drift


def test_feedback_input_runs_interval_by_interval():
    m = pl.rigid(b1=0.0)
    x0 = m.state(theta1=0.5)
    tr = pl.simulate(m, x0, 1.0, dt=0.01, method="rk4", max_step=1e-3, u=lambda t, x: [-5.0 * x[2], 0.0])
    E = m.energy(tr.x)
    # A damping feedback only removes energy (beyond RK4's 1e-8-level error).
    assert np.all(np.diff(E) < 1e-8) and E[-1] < E[0] - 0.1


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "nope"}, "unknown fixed-step method"),
        ({"h": -1.0}, "h must be a positive"),
        ({"n_steps": 0}, "n_steps must be a positive integer"),
        ({"n_steps": 10, "record_every": 3}, "multiple of record_every"),
    ],
)
def test_integrate_fixed_bad_input(kwargs, match):
    m = pl.rigid()
    args = {"method": "rk4", "h": 0.01, "n_steps": 10, **kwargs}
    with pytest.raises(ValueError, match=match):
        integrate_fixed(m, args.pop("method"), m.rest_state(), args.pop("h"), args.pop("n_steps"), **args)


def test_options_rejected_for_fixed_methods():
    m = pl.rigid()
    with pytest.raises(ValueError, match="not supported by the fixed-step method"):
        pl.simulate(m, m.rest_state(), 0.1, method="gauss4", options={"foo": 1})

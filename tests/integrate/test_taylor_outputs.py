"""The Taylor family's compiled outputs on the grid, its cached run set-up and the start-state check."""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl

pytest.importorskip("heyoka")

from pendulab.integrate import taylor  # noqa: E402
from pendulab.integrate.taylor import outputs as taylor_outputs  # noqa: E402


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_compiled_outputs_equal_model_outputs(kind):
    model = pl.make_model(kind)
    rng = np.random.default_rng(3)
    X = np.tile(model.rest_state(), (257, 1))
    X[:, :2] = rng.uniform(-np.pi, np.pi, (257, 2))
    X[:, model.nx // 2 :] = rng.normal(0.0, 3.0, (257, model.nx // 2))
    U = rng.normal(0.0, 1.0, (257, model.nu))
    evaluate = taylor_outputs.output_evaluator(kind)
    assert evaluate is not None
    got = evaluate(X, U, model.p)
    want = model.outputs(X, U)
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
    # Parameters are runtime values: another parameter set needs no new evaluator.
    heavy = model.with_params(m2=2.5)
    np.testing.assert_allclose(evaluate(X, U, heavy.p), heavy.outputs(X, U), rtol=1e-13, atol=1e-13)


def test_simulate_outputs_first_and_later_calls_agree():
    model = pl.rigid(L2=0.7)
    x0 = model.state(theta1=2.0, theta2=1.0)
    first = pl.simulate(model, x0, 2.0, method="taylor", rtol=1e-12, atol=1e-12, u=[0.3, -0.2])
    again = pl.simulate(model, x0, 2.0, method="taylor", rtol=1e-12, atol=1e-12, u=[0.3, -0.2])
    np.testing.assert_array_equal(first.x, again.x)
    np.testing.assert_allclose(again.y, model.outputs(again.x, again.u), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(first.y, again.y, rtol=1e-13, atol=1e-13)


def test_prepared_runs_follow_the_compilation_cache_and_parameters():
    model = pl.rigid()
    x0 = model.state(theta1=1.0)
    a = pl.simulate(model, x0, 1.0, method="taylor")
    taylor.clear_cache()
    before = taylor.compile_count()
    b = pl.simulate(model, x0, 1.0, method="taylor")
    assert taylor.compile_count() == before + 1  # the cached set-up was forgotten with the integrators
    assert b.stats["compiled"]
    np.testing.assert_array_equal(a.x, b.x)
    longer = model.with_params(L2=1.5)  # same structure, new parameter values: new runtime parameters
    c = pl.simulate(longer, x0, 1.0, method="taylor")
    assert not c.stats["compiled"]
    assert not np.allclose(c.x[-1], b.x[-1])


def test_check_start_single_state_refuses_non_finite_dynamics():
    model = pl.elastic()
    with pytest.raises(ValueError, match="not finite at this state"):
        model.check_start(model.state(omega1=1e200))  # r1 omega1^2 overflows
    # A spring of 1e-300 m at rest: finite, well-defined dynamics since the accelerations are solved through the
    # bobs' Jacobian (the old solve with M ~ r1^2 underflowed to a singular matrix and returned NaN).
    assert np.all(np.isfinite(model.rhs(model.state(r1=1e-300))))
    np.testing.assert_array_equal(model.check_start(model.rest_state()), model.rest_state())


def test_unforced_parameter_array_never_serves_another_run():
    """The parameter array kept between unforced calls must follow the parameters, the grid size and any torque."""
    model = pl.rigid()
    evaluate = taylor_outputs.output_evaluator("rigid")
    assert evaluate is not None
    rng = np.random.default_rng(5)
    X = rng.normal(0.0, 2.0, (257, 4))
    zero = np.zeros((257, 2))
    # Interleaved as a sweep would call: the same parameters and size again, then another of each, then torques.
    for m, rows, U in [
        (model, 257, zero),
        (model, 257, zero),
        (model.with_params(L1=0.3, m2=4.0), 257, zero),
        (model, 100, zero[:100]),
        (model, 257, rng.normal(0.0, 1.0, (257, 2))),
        (model, 257, zero),
    ]:
        # Tolerance: the same graph through heyoka's sin/cos against NumPy's, a few ulp on values of order 10.
        np.testing.assert_allclose(evaluate(X[:rows], U, m.p), m.outputs(X[:rows], U), rtol=1e-13, atol=1e-13)


def test_ctrl_c_in_a_taylor_run_is_an_interrupt_not_a_failure():
    """Taylor runs without simulate's SIGINT watch: Ctrl-C must still surface as KeyboardInterrupt, handler intact."""
    import signal

    model = pl.rigid()
    before = signal.getsignal(signal.SIGINT)
    calls = []

    def feedback(t, x):
        calls.append(t)
        if len(calls) == 3:
            signal.raise_signal(signal.SIGINT)  # as a Ctrl-C between two heyoka propagations
        return [0.0, 0.0]

    with pytest.raises(KeyboardInterrupt):
        pl.simulate(model, model.state(theta1=1.0), 1.0, method="taylor", u=feedback)
    assert len(calls) == 3  # stopped at once, not after the run
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.parametrize(("t_final", "dt"), [(10.0, 0.01), (1.0, 0.3), (3.7, 0.01), (1e-3, 1e-5), (123.456, 0.1)])
def test_output_grid_is_linspace_to_the_bit_and_never_shared(t_final, dt):
    """The hot path's grid (and the copy of the last one it keeps) is np.linspace's, and every run owns its own."""
    model = pl.rigid()
    n = max(1, int(np.ceil(t_final / dt - 1e-9)))
    want = np.linspace(0.0, t_final, n + 1)
    np.testing.assert_array_equal(pl.integrate.time_grid(t_final, dt), want)
    if t_final > 10.0:
        return  # the grid is the point; a long run adds nothing
    first = pl.simulate(model, [1.0, 0.5, 0.0, 0.0], t_final, dt=dt, method="taylor")
    first.t[:] = -1.0  # a caller may write into its trajectory...
    first.x[:] = np.nan
    again = pl.simulate(model, [1.0, 0.5, 0.0, 0.0], t_final, dt=dt, method="taylor")
    np.testing.assert_array_equal(again.t, want)  # ...without reaching the next run's grid or states
    assert np.all(np.isfinite(again.x)) and again.x.flags.writeable and again.t.flags.writeable
    np.testing.assert_array_equal(pl.integrate.time_grid(t_final, dt), want)


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_single_state_checks_refuse_what_the_batch_checks_refuse(kind):
    """check_start's one-state shortcuts (plain-Python finiteness, spring lengths, right-hand side) and the
    batch path refuse the same states for the same reason; simulate refuses them before running."""
    model = pl.make_model(kind)
    rest = model.rest_state()
    cases = []  # (state, words of the reason)
    for j in range(model.nx):
        for value in (np.nan, np.inf, -np.inf):
            x = rest.copy()
            x[j] = value
            cases.append((x, "must be finite"))
    if kind == "elastic":
        for j, value in ((2, 0.0), (3, -0.1)):
            x = rest.copy()
            x[j] = value
            cases.append((x, "spring lengths r1, r2 must be > 0 m"))
    cases.append((model.state(omega1=1e200), "not finite at this state"))  # finite, but the dynamics overflow
    for x, reason in cases:
        with pytest.raises(ValueError, match=reason):
            model.check_start(x)
        with pytest.raises(ValueError, match=reason):
            model.check_start(np.vstack([rest, x]))
        with pytest.raises(ValueError, match=reason):
            pl.simulate(model, x, 0.1, method="taylor")
    np.testing.assert_array_equal(model.check_start(rest), rest)


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_no_torque_given_equals_zero_torque_given(kind):
    """u=None marks the request unforced (the runner skips scanning the schedule); explicit zeros take the scan.
    Both must give the same run to the bit, and a torque must still change it."""
    model = pl.make_model(kind)
    x0 = model.state(theta1=2.0, theta2=1.0)
    runs = [pl.simulate(model, x0, 2.0, method="taylor", u=u) for u in (None, [0.0, 0.0], np.zeros((201, 2)))]
    for other in runs[1:]:
        np.testing.assert_array_equal(runs[0].x, other.x)
        np.testing.assert_array_equal(runs[0].u, other.u)
        np.testing.assert_array_equal(runs[0].y, other.y)
    pushed = pl.simulate(model, x0, 2.0, method="taylor", u=[0.1, 0.0])
    assert np.max(np.abs(pushed.x[-1] - runs[0].x[-1])) > 1e-3

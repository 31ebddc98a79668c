"""Largest Lyapunov exponent (Benettin) and equal-energy initial states: physics, agreement, bad inputs."""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl
from pendulab.ensemble.lyapunov import (
    energy_matched_state,
    energy_matched_states,
    largest_lyapunov,
    variational_taylor_system,
)
from pendulab.model.statics import static_spring_lengths

hy = pytest.importorskip("heyoka")

UPRIGHT = np.array([np.pi, np.pi, 0.0, 0.0])


@pytest.fixture(scope="module")
def rigid() -> pl.Model:
    return pl.rigid()


@pytest.fixture(scope="module")
def chaotic_energy(rigid: pl.Model) -> float:
    return float(rigid.energy(rigid.state(theta1=2.0, theta2=2.0)))


def test_regular_small_oscillation_has_zero_exponent(rigid: pl.Model) -> None:
    # Quasi-periodic motion: the tangent grows at most linearly, so lambda(T) ~ ln(T)/T -> 0
    # (0.0015 /s at 200 s); 0.05 /s is the brief's bound, ~30x below the chaotic value.
    est = largest_lyapunov(rigid, rigid.state(theta1=0.1, theta2=0.1), 200.0, renorm_interval=0.5)
    assert abs(est.value) < 0.05
    assert est.n_renorm == 400
    assert est.running.shape == est.t.shape == (400,)
    assert est.t[-1] == pytest.approx(200.0)


def test_chaotic_release_has_positive_exponent(rigid: pl.Model) -> None:
    # theta1 = theta2 = 2 rad is the project's chaotic case (errors grow 1e4-1e6 in 10 s): lambda ~ 1.2-1.5 /s.
    est = largest_lyapunov(rigid, rigid.state(theta1=2.0, theta2=2.0), 100.0, t_transient=5.0)
    assert 0.7 < est.value < 2.5
    # The state part is accurate: energy conserved to ~1e-10 J (tol 1e-12, 21 000 Taylor steps).
    assert est.energy_drift < 1e-8


@pytest.mark.parametrize("method", ["taylor", "cvodes"])
def test_upright_equilibrium_exponent_is_largest_eigenvalue(rigid: pl.Model, method: str) -> None:
    # At an equilibrium the tangent equations are linear with constant A: the exponent is the largest
    # real part of eig(A). The transient (2 s) damps the second unstable direction by
    # exp(-(5.79 - 2.40) 2) ~ 1e-3, leaving a bias ~1e-3/T in the rate; rounding of sin(pi) moves
    # the state by ~1e-7 rad in 4 s, a relative change of A ~1e-7.
    lam = float(np.max(pl.linearize(rigid, UPRIGHT).eigenvalues.real))
    est = largest_lyapunov(rigid, UPRIGHT, 2.0, t_transient=2.0, renorm_interval=0.25, method=method)
    assert est.value == pytest.approx(lam, rel=1e-4)
    # The final tangent is the unstable eigenvector of A.
    w, V = np.linalg.eig(pl.linearize(rigid, UPRIGHT).A)
    v = np.real(V[:, np.argmax(w.real)])
    assert abs(abs(np.dot(v / np.linalg.norm(v), est.tangent_final)) - 1.0) < 1e-5


def test_elastic_upright_matches_linearisation() -> None:
    # Same check through the elastic model's exact Jacobian (spring lengths at the inverted static load).
    # CVODES: no JIT compilation of the 16-equation Taylor system (~30 s without heyoka's disk cache);
    # the elastic Taylor equations are checked against jac_rhs below.
    model = pl.elastic(k1=1e3, k2=1e3)
    eq = pl.equilibrium(model, "up-up")
    lam = float(np.max(pl.linearize(model, eq).eigenvalues.real))
    est = largest_lyapunov(model, eq.x, 2.0, t_transient=2.0, renorm_interval=0.25, method="cvodes")
    assert est.value == pytest.approx(lam, rel=1e-3)


def test_taylor_and_cvodes_agree_on_a_short_chaotic_run(rigid: pl.Model) -> None:
    # Two independent routes (heyoka var_ode_sys on the translated graph; CasADi jtimes + CVODES):
    # over 8 s, tolerance-level differences grow by ~exp(1.3 * 8) ~ 3e4, so the exponents agree to ~1e-5.
    x0 = rigid.state(theta1=2.0, theta2=2.0)
    a = largest_lyapunov(rigid, x0, 8.0, renorm_interval=0.5, method="taylor")
    b = largest_lyapunov(rigid, x0, 8.0, renorm_interval=0.5, method="cvodes")
    assert a.value == pytest.approx(b.value, abs=1e-4)
    np.testing.assert_allclose(a.running, b.running, atol=1e-3)


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_variational_system_is_the_casadi_jacobian(kind: str) -> None:
    # heyoka's symbolic derivative of the translated rhs must equal CasADi's jac_rhs times delta.
    model = pl.rigid(m2=0.7, L1=1.3) if kind == "rigid" else pl.elastic(k1=800.0, k2=300.0, m1=1.4)
    sys, pars = variational_taylor_system(model)
    f = hy.cfunc([e for _, e in sys], [v for v, _ in sys])
    rng = np.random.default_rng(3)
    nx = model.nx
    for _ in range(3):
        x = model.rest_state() + rng.normal(0.0, 0.5, nx)
        if kind == "elastic":
            x[2:4] = model.rest_state()[2:4] + rng.normal(0.0, 0.05, 2)  # spring lengths near 1 m
        d = rng.normal(size=nx)
        out = f(np.r_[x, d], pars=pars)
        A = np.asarray(model.functions["jac_rhs"](x, np.zeros(2), model.p)[0])
        # Reassociated arithmetic: agreement to rounding relative to the entries' size.
        np.testing.assert_allclose(out[:nx], model.rhs(x), rtol=1e-11, atol=1e-11 * np.abs(model.rhs(x)).max())
        np.testing.assert_allclose(out[nx:], A @ d, rtol=1e-10, atol=1e-10 * np.abs(A @ d).max())


@pytest.mark.parametrize("springs", ["quasi-static", "static"])
def test_energy_matched_states_have_the_energy(chaotic_energy: float, springs: str) -> None:
    models = [pl.rigid(), pl.elastic(k1=1e4, k2=1e4), pl.elastic(k1=1e2, k2=1e2)]
    states = energy_matched_states(models, chaotic_energy, 4, seed=7, springs=springs)
    for model, X in zip(models, states, strict=True):
        assert X.shape == (4, model.nx)
        # Requested to 1e-12 J (12 J: ~100 ulps; brentq + one Newton step along the rates).
        np.testing.assert_allclose(model.energy(X), chaotic_energy, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(X[:, :2], states[0][:, :2])  # same angles for every model
    soft = states[2]
    if springs == "quasi-static":
        # Zero radial acceleration at the start: the fast spring mode is not excited.
        acc = models[2].rhs(soft)[:, 6:8]
        assert np.abs(acc).max() < 1e-7
    else:
        np.testing.assert_allclose(soft[:, 2:4], static_spring_lengths(models[2].params, soft[:, :2]), rtol=1e-15)
        assert np.all(soft[:, 6:8] == 0.0)


def test_energy_matched_state_direction_and_reachability(rigid: pl.Model, chaotic_energy: float) -> None:
    x = energy_matched_state(rigid, chaotic_energy, [0.5, -1.0], [1.0, -2.0])
    assert x[2:] @ np.array([2.0, 1.0]) == pytest.approx(0.0, abs=1e-12)  # rates along (1, -2)
    assert x[2] > 0
    with pytest.raises(ValueError, match="energy"):
        energy_matched_state(rigid, chaotic_energy, [np.pi, np.pi], [1.0, 0.0])  # upright is above 12 J
    with pytest.raises(ValueError, match="direction"):
        energy_matched_state(rigid, chaotic_energy, [0.5, 0.5], [0.0, 0.0])
    with pytest.raises(ValueError, match="springs"):
        energy_matched_state(rigid, chaotic_energy, [0.5, 0.5], [1.0, 0.0], springs="loose")
    with pytest.raises(ValueError, match="n must"):
        energy_matched_states([rigid], chaotic_energy, 0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"t_total": 0.0}, "t_total"),
        ({"t_total": -1.0}, "t_total"),
        ({"t_total": float("nan")}, "t_total"),
        ({"t_total": 1.0, "renorm_interval": 2.0}, "renorm_interval"),
        ({"t_total": 1.0, "renorm_interval": 0.0}, "renorm_interval"),
        ({"t_total": 1.0, "t_transient": -0.5}, "t_transient"),
        ({"t_total": 1.0, "rtol": 0.0}, "rtol"),
        ({"t_total": 1.0, "method": "rk4"}, "method"),
        ({"t_total": 1.0, "tangent0": np.zeros(4)}, "tangent0"),
        ({"t_total": 1.0, "x0": [0.1, 0.2, np.nan, 0.0]}, "x0"),
        ({"t_total": 1.0, "x0": [0.1, 0.2, np.inf, 0.0]}, "x0"),
        ({"t_total": 1.0, "x0": [0.1, 0.2]}, "x0"),
    ],
)
def test_bad_inputs_raise_value_error(rigid: pl.Model, kwargs: dict, match: str) -> None:
    kw = {"x0": rigid.state(theta1=0.1), **kwargs}
    x0 = kw.pop("x0")
    t_total = kw.pop("t_total")
    with pytest.raises(ValueError, match=match):
        largest_lyapunov(rigid, x0, t_total, **kw)


def test_not_a_model_raises() -> None:
    with pytest.raises(TypeError, match="model must be a pendulab Model, got str"):
        largest_lyapunov("rigid", np.zeros(4), 1.0)  # type: ignore[arg-type]


def test_collapsed_spring_and_rtol_one_are_refused() -> None:
    el = pl.elastic()
    x0 = el.rest_state()
    x0[2] = 0.0
    with pytest.raises(ValueError, match=r"x0: spring lengths r1, r2 must be > 0"):
        largest_lyapunov(el, x0, 1.0)
    with pytest.raises(ValueError, match=r"rtol = 1.0: out of range; expected a finite number in \[2.22e-16, 1\)"):
        largest_lyapunov(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 1.0, rtol=1.0)


def test_renormalisation_count_is_bounded_before_any_allocation() -> None:
    # 1e9 renormalisations used to grow memory without limit; now a clear error naming the limit.
    with pytest.raises(ValueError, match=r"renorm_interval.*MAX_RENORM = 10000000"):
        largest_lyapunov(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 1.0, renorm_interval=1e-9)


def test_step_budget_ends_a_long_estimate() -> None:
    # 10 s of the chaotic release needs far more than 100 Taylor steps: the budget names itself.
    with pytest.raises(RuntimeError, match=r"step budget exhausted \(max_steps = 100\)"):
        largest_lyapunov(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 10.0, max_steps=100)

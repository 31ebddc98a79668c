"""The a priori model rule of scenes (pendulab.scene.choose_model): picks, predicted vs measured, horizons, bad input."""

import dataclasses
import json
import math
from types import MappingProxyType

import numpy as np
import pytest

import pendulab as pl
from pendulab.analysis.model_error import (
    C_QUASI_STATIC,
    C_RIGID,
    error_growth,
    frequency_split,
    lyapunov_exponent,
    mode_ratio_errors,
    validity_horizon,
)
from pendulab.bench.hierarchy import measure_levels
from pendulab.cli import main
from pendulab.scene import Scene, initial_state, load_scene
from pendulab.scene.choice import choose_model


def _scene(kind="elastic", k=1e6, a=(0.5, 0.5), t_final=3.0, tol=1e-3, rtol=1e-10, **kw):
    model = pl.rigid() if kind == "rigid" else pl.elastic(k1=k, k2=k)
    initial = {"theta1": a[0], "theta2": a[1]}
    return Scene(
        name=f"{kind} k={k:g} a={a}",
        description="test",
        model=model,
        initial=MappingProxyType(initial),
        x0=initial_state(model, initial, kw.pop("start", "static")),
        t_final=t_final,
        dt=0.01,
        method="cvodes",
        rtol=rtol,
        atol=rtol,
        outputs=("theta1", "theta2", "x2", "y2"),
        tolerance=tol,
        **kw,
    )


# -- picks on clear cases -----------------------------------------------------------
def test_stiff_moderate_amplitude_picks_a_rigid_level():
    c = choose_model(_scene(k=1e7, a=(0.5, 0.5)))
    # Springs stretch by ~2 um under the load: the rigid links are within 1e-3 rad / m, the swing is not linear.
    assert c.chosen in ("rigid", "rigid+quasi-static"), c.table()
    assert c.levels[0].name == "linearized" and not c.levels[0].within


def test_soft_springs_pick_elastic():
    c = choose_model(_scene(k=1e2, a=(0.5, 0.5)))
    # Soft springs (static stretch 0.2 m) exchange energy with the swing: no cheaper model comes near 1e-3.
    assert c.chosen == "elastic", c.table()
    assert all(lv.error > 10 * c.tolerance for lv in c.levels[:-1])


def test_small_amplitude_picks_linearized():
    for kind in ("rigid", "elastic"):
        c = choose_model(_scene(kind=kind, k=1e5, a=(0.03, 0.03)))
        # 2-degree swings: the cubic terms the linearization drops are ~1e-5 rad over 3 s.
        assert c.chosen == "linearized", c.table()


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_sine_forced_linearization_matches_the_linear_ode_and_is_chosen_for_small_forcing(kind):
    from scipy.integrate import solve_ivp

    from pendulab.scene.levels import linear_solution

    m = pl.rigid() if kind == "rigid" else pl.elastic(k1=1e4, k2=1e4)
    base = _scene(kind=kind, k=1e4, a=(0.0, 0.0), t_final=3.0, tol=1e-4, start="static")
    scene = dataclasses.replace(base, x0=m.rest_state(), u_amplitude=np.array([0.02, 0.0]), u_frequency=0.7)
    lin = linear_solution(scene)
    # Independent path: the same linear ODE, dx/dt = A dx + b + B u_sine(t), with the same held sine, by RK45.
    spec = scene.input_spec()
    tg = spec.hold_grid(np.linspace(0.0, 3.0, len(lin.x)))
    held = np.asarray(spec.func(0.5 * (tg[:-1] + tg[1:])))

    dx, X = np.zeros(m.nx), [np.zeros(m.nx)]
    for k, u in enumerate(held):  # hold by hold: the ODE is smooth within each
        dx = solve_ivp(
            lambda t, y, u=u: lin.A @ y + lin.b + lin.B @ u, (tg[k], tg[k + 1]), dx, method="DOP853", rtol=1e-12, atol=1e-15
        ).y[:, -1]
        X.append(dx)
    # DOP853 at rtol 1e-12 over 300 holds: round-off level of a ~1e-3 rad response.
    np.testing.assert_allclose(lin.x - lin.x_eq, np.array(X)[:: (len(tg) - 1) // (len(lin.x) - 1)], rtol=1e-8, atol=1e-13)
    assert np.max(np.abs(lin.x[:, 0] - lin.x_eq[0])) > 1e-4  # the forcing does move the pendulum
    c = choose_model(scene, verify=True)
    # A 0.02 N.m sine swings the pendulum by ~1e-3 rad: the neglected terms are ~1e-9, far below 1e-4.
    assert c.chosen == "linearized", c.table()
    assert c.verification.measured_error <= c.tolerance


def test_chaotic_long_horizon_has_a_short_validity_horizon():
    c = choose_model(_scene(kind="rigid", a=(2.0, 2.0), t_final=20.0, tol=1e-6, rtol=1e-8))
    # lambda_1 ~ 1.4 /s at this energy (docs/lyapunov.md); 1e-8 errors reach 1e-6 within a few seconds.
    assert 1.0 < c.lyapunov < 2.0
    assert c.reference_horizon < c.t_final / 2 and c.trusted_until <= c.reference_horizon
    assert c.needed_rtol < 1e-14  # no double-precision tolerance holds 20 s at 1e-6
    assert "chaotic" in c.verdict and "beyond double precision" in c.verdict


# -- predicted against measured --------------------------------------------------------
@pytest.mark.parametrize(
    "scene",
    [
        _scene(kind="rigid", a=(0.05, 0.05)),
        _scene(k=1e6, a=(0.5, 0.5)),
        _scene(k=1e4, a=(0.05, 0.05)),
        _scene(k=1e5, a=(0.7, -0.2), start="rest-length"),
    ],
    ids=["rigid-small", "stiff-moderate", "k1e4-small", "asymmetric-rest-length"],
)
def test_predicted_bounds_measured_within_a_factor(scene):
    c = choose_model(scene)
    measured = measure_levels(scene)
    for lv in c.levels[:-1]:
        m = measured[lv.name]["error"]
        if "screened" in lv.note:  # a screen only says "hopeless": both far beyond the tolerance, same order
            assert lv.error > 10 * c.tolerance and m > 10 * c.tolerance and 0.2 < lv.error / m < 10, (lv.name, lv.error, m)
            continue
        # The rule is calibrated to err on the safe side by 1-5x (docs/model_choice.md); 0.8 leaves rounding room.
        assert 0.8 * m <= lv.error <= 10 * m, (lv.name, lv.error, m)
    # The chosen level meets the tolerance on the full dynamics.
    assert measured[c.chosen]["error"] <= c.tolerance


@pytest.mark.parametrize(
    "scene",
    [
        dataclasses.replace(_scene(kind="rigid", a=(0.2, 0.02), tol=1e-2), outputs=("energy",)),
        dataclasses.replace(_scene(k=1e5, a=(0.5, 0.5), tol=1e-2, start="rest-length"), outputs=("omega1", "omega2")),
        dataclasses.replace(_scene(k=1e6, a=(1.2, 1.2), tol=1e-3), outputs=("energy",)),
        dataclasses.replace(_scene(k=1e5, a=(0.5, 0.5), tol=1e-5), outputs=("r1", "r2")),
    ],
    ids=["rigid-energy", "rest-length-rates", "stiff-energy", "spring-lengths"],
)
def test_rate_energy_and_length_outputs_are_predicted_on_the_safe_side(scene):
    c = choose_model(scene)
    measured = measure_levels(scene)
    for lv in c.levels[:-1]:
        if "screened" in lv.note:
            continue
        # These gains bound the error (ringing springs in the rates, k delta^2 in the energy) rather than
        # estimate it: only the safe side is asserted; 0.8 leaves rounding room.
        assert lv.error >= 0.8 * measured[lv.name]["error"], (lv.name, lv.error, measured[lv.name]["error"])
    assert measured[c.chosen]["error"] <= c.tolerance


def test_verify_reports_measured_error_of_the_chosen_level():
    scene = _scene(k=1e6, a=(0.5, 0.5), t_final=2.0)
    c = choose_model(scene, verify=True)
    v = c.verification
    assert v is not None and v.level == c.chosen
    # Same levels, same integrator: the verification's measurement is the one measure_levels makes.
    assert v.measured_error == pytest.approx(measure_levels(scene)[c.chosen]["error"], rel=1e-9)
    assert v.within and v.measured_error <= v.predicted_error
    assert "verify:" in c.table()


def test_linearized_trajectory_is_the_rules_own_linear_solution():
    scene = _scene(kind="rigid", a=(0.05, 0.05))
    c = choose_model(scene)
    assert c.chosen == "linearized"
    traj = c.simulate(scene)
    ref = scene.simulate()
    # 3-degree swings over 3 s: the linear solution follows the rigid model to ~1e-4 rad (cubic terms).
    assert np.max(np.abs(traj["theta1"] - ref["theta1"])) < 1e-3


def test_reference_horizon_on_a_chaotic_scene_within_factor_two():
    scene = _scene(kind="rigid", a=(2.0, 2.0), t_final=10.0, tol=1e-3, rtol=1e-8)
    c = choose_model(scene, verify=True)
    v = c.verification
    assert v.reference_horizon is not None
    p, m = min(c.reference_horizon, 10.0), min(v.reference_horizon, 10.0)
    # The target for the horizon of validity on chaotic scenes: within a factor of 2.
    assert max(p, m) / min(p, m) <= 2.0, (p, m)


def test_start_load_amplitude_period_and_envelope():
    from scipy.special import ellipk

    from pendulab.model.quasistatic import quasi_static_lengths
    from pendulab.scene.prediction import _features

    hanging = _features(_scene(k=1e5, a=(0.05, 0.05), start="quasi-static"))
    raised = _features(_scene(k=1e5, a=(2.0, 2.0), start="quasi-static"))
    s = _scene(k=1e5, a=(2.0, 2.0), start="quasi-static")
    p = s.model.params
    r_qs = quasi_static_lengths(s.model, s.x0[:2], s.x0[4:6])
    # The start's stretch is the quasi-static one at the start, exactly (same formula, same state).
    np.testing.assert_allclose(raised.stretch_start, np.abs(r_qs - [p.L1, p.L2]), rtol=1e-12)
    # Near hanging a link carries its weight, (m1 + m2) g / k; raised to 2 rad only cos(2) ~ -0.42 of it.
    assert hanging.stretch_start[0] == pytest.approx((p.m1 + p.m2) * p.g / p.k1, rel=0.01)
    assert raised.stretch_start[0] < 0.5 * hanging.stretch_start[0]
    # Quarter of the slow period: pi / (2 w) for small swings, x 2 K(sin^2(A / 2)) / pi for amplitude A.
    assert hanging.quarter == pytest.approx(math.pi / 2 / hanging.w_slow, rel=1e-3)
    slower = 2 / math.pi * ellipk(math.sin(raised.amplitude / 2) ** 2)
    assert raised.quarter == pytest.approx(math.pi / 2 / raised.w_slow * slower)
    # Started at rest, a phase error shows in the angle only as the mode moves: envelope 0 at t = 0, w t after.
    t = np.array([0.0, 0.1, 10.0])
    np.testing.assert_allclose(raised.envelope(t), [0.0, 0.1 * raised.w_slow, 1.0])
    moving = _features(dataclasses.replace(_scene(kind="rigid", a=(0.0, 0.0)), x0=np.array([0.0, 0.0, 1.0, 0.0])))
    assert moving.kinetic_share == pytest.approx(1.0) and moving.envelope(np.array([0.0]))[0] == 1.0


def test_reduced_level_horizon_on_a_chaotic_elastic_scene_within_factor_two():
    # The scene of the benchmark whose rigid-level horizon was predicted 2.3x too short before the start's own
    # load and the amplitude-lengthened fall entered the prediction (measured 0.65 s).
    scene = _scene(k=1e5, a=(2.0, 2.0), t_final=2.0, tol=1e-3, rtol=1e-9, start="quasi-static")
    c = choose_model(scene)
    measured = measure_levels(scene)
    for name in ("rigid", "rigid+quasi-static"):
        p = next(lv.horizon for lv in c.levels if lv.name == name)
        m = measured[name]["horizon"]
        # The target for the horizon of validity on chaotic scenes: within a factor of 2.
        assert 0.5 <= p / m <= 2.0, (name, p, m)


# -- shared formulas -----------------------------------------------------------------
def test_mode_ratio_errors_are_the_planning_rule():
    pred = mode_ratio_errors(5.0, 500.0)
    assert pred["rigid"] == pytest.approx(C_RIGID * 0.01) and pred["rigid+quasi-static"] == pytest.approx(C_QUASI_STATIC * 1e-4)


def test_frequency_split_and_lyapunov_table():
    m = pl.elastic(k1=1e4, k2=1e4)
    A = np.asarray(m.functions["jac_rhs"](m.rest_state(), np.zeros(2), m.p)[0])
    w_p, w_s = frequency_split(np.linalg.eigvals(A), "elastic")
    # Pendular modes ~2.4 and ~5.8 rad/s, spring modes ~0.618 sqrt(k) = 62 rad/s (DESIGN.md).
    assert 5.0 < w_p < 6.5 and 55 < w_s < 70
    # The 12.25 J row reproduces the 300 s study's 1.351 /s for the rigid pendulum to its spread (0.1 /s).
    assert lyapunov_exponent(41.68 / 58.86, math.sqrt(9.81), math.inf) == pytest.approx(1.351, abs=0.1)
    assert lyapunov_exponent(0.05, math.sqrt(9.81)) == 0.0  # small swings are regular


def test_validity_horizon_and_growth():
    t = np.linspace(0, 10, 101)
    assert validity_horizon(t, 1e-6 * np.exp(t), 1e-3) == pytest.approx(math.log(1e3), abs=0.01)
    assert validity_horizon(t, np.zeros_like(t), 1e-3) == 10.0
    assert validity_horizon(t, np.ones_like(t), 1e-3) == 0.0
    g = error_growth(t, 2.0, 0.0)
    assert g[-1] == pytest.approx(10.0)  # secular: phase_rate * t / 2


# -- bad input -------------------------------------------------------------------------
def test_bad_input():
    scene = _scene()
    with pytest.raises(TypeError, match="scene must be a pendulab Scene"):
        choose_model("seed_paper")
    with pytest.raises(ValueError, match="tolerance"):
        choose_model(dataclasses.replace(scene, tolerance=None))
    with pytest.raises(ValueError, match=r"tolerance = .*expected a finite number in \[2.22e-16, 1\)"):
        choose_model(scene, tolerance=-1.0)
    with pytest.raises(TypeError, match="verify"):
        choose_model(scene, verify="yes")
    with pytest.raises(ValueError, match="frequencies must be positive"):
        mode_ratio_errors(0.0, 10.0)


def test_cli_scene_check_json_and_errors(capsys, tmp_path):
    assert main(["scene", "check", "stiff_moderate_amplitude", "--json", "--out", str(tmp_path)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert json.loads((tmp_path / "check.json").read_text()) == data  # --out keeps what --json prints
    assert "chosen:" in (tmp_path / "check.md").read_text()
    assert data["a_priori"] and data["chosen"] in ("rigid", "rigid+quasi-static")
    assert [lv["name"] for lv in data["levels"]] == ["linearized", "rigid", "rigid+quasi-static", "elastic"]
    assert data["verification"] is None and data["trusted_until_s"] == 5.0
    assert main(["scene", "check", "stiff_moderate_amplitude", "--repeats", "2"]) == 2
    assert "--repeats applies to --measure only" in capsys.readouterr().err
    assert main(["simulate", "--scene", "elastic_stiff", "--verify", "--t-final", "0.2"]) == 2
    assert "--verify applies to --model auto only" in capsys.readouterr().err


def test_cli_simulate_auto_verify(tmp_path, capsys):
    out = tmp_path / "t.csv"
    args = ["simulate", "--scene", "stiff_moderate_amplitude", "--model", "auto", "--verify", "--json", "--out", str(out)]
    assert main([*args, "--t-final", "1"]) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert summary["model_level"] in ("rigid", "rigid+quasi-static") and "verify:" in captured.err
    v = summary["verification"]
    # Predicted errors bound the measured one, which meets the scene's 1e-3 tolerance.
    assert v["measured_error"] <= v["predicted_error"] and v["within_tolerance"]


def test_shipped_scenes_choice_is_within_tolerance():
    for name in ("stiff_small_amplitude", "elastic_stiff"):
        scene = load_scene(name)
        c = choose_model(scene, verify=True)
        # The target: the a priori choice meets the scene's tolerance on the full dynamics.
        assert c.verification.within, c.table()

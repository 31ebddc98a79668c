"""Scene inputs are defined in time: every override works, a fast sine is not aliased, every shipped scene runs.

Issue 20: a scene with ``[input.sine]`` was sampled on its own output grid, so ``t_final`` / ``dt`` overrides
failed ("sampled u must have one row per output time") and a 50 Hz sine at dt = 0.01 s was held at its zeros.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pendulab.cli import main
from pendulab.commands._common import summarize
from pendulab.integrate.methods import METHODS
from pendulab.integrate.simulate import TimeInput, energy_flows
from pendulab.scene import SCENE_DIR, list_scenes, load_scene

SHIPPED = [*list_scenes(), *(name for group in ("bench", "validation") for name in list_scenes(group))]
FORCED = list_scenes("validation")


def _usable(name: str) -> bool:
    spec = METHODS.get(name)
    available = spec.settings.get("available") if spec is not None else None
    return spec is not None and (available is None or available() is None)


def test_every_shipped_scene_file_is_listed():
    assert len(SHIPPED) == len(list(SCENE_DIR.rglob("*.toml")))


@pytest.mark.parametrize("name", FORCED)
def test_forced_scene_honours_t_final_and_dt_overrides(name):
    scene = load_scene(name)
    full = scene.simulate()
    short = scene.simulate(t_final=1.0)
    coarse = scene.simulate(dt=2 * scene.dt)
    assert short.t[-1] == 1.0 and coarse.t[1] == pytest.approx(2 * scene.dt)
    n = len(short.t)
    # Same input in time and the same solver: the shortened run is the start of the full one (tolerance 1e-8, 1 s).
    np.testing.assert_allclose(short.x, full.x[:n], rtol=0, atol=1e-6)
    # Another output step holds the sine 0.02 s instead of 0.01 s (50 holds per period of 2 s, not 100+): its
    # fundamental is within 7e-4 of the true amplitude, the swing (~1 rad) agrees to a few 1e-4 rad.
    np.testing.assert_allclose(coarse.x, full.x[::2], rtol=0, atol=2e-3)


def test_scene_method_override_runs_the_same_input():
    scene = load_scene("validation/rigid_forced")
    a = scene.simulate(t_final=1.0, method="cvodes", rtol=1e-10, atol=1e-10)
    b = scene.simulate(t_final=1.0, method="rk4", max_step=1e-3)
    # RK4 at h = 1e-3 s on a ~3 rad/s motion: local error ~ (h w)^5, below 1e-8 rad over 1 s.
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-7)


def test_cli_simulate_and_demo_with_overrides(tmp_path, capsys):
    assert main(["simulate", "--scene", "validation/rigid_forced", "--t-final", "1", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["t_final_s"] == 1.0 and summary["forced"]
    assert main(["simulate", "--scene", "validation/rigid_forced", "--dt", "0.02", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["n_points"] == 251  # 5 s at 0.02 s
    out = tmp_path / "demo"
    assert (
        main(["demo", "--scene", "validation/elastic_soft_forced", "--t-final", "1", "--no-gif", "--out", str(out), "--json"])
        == 0
    )
    report = json.loads(capsys.readouterr().out)
    rigid, elastic = report["runs"]
    # Both runs of the demo get the scene's sine (the rigid counterpart too): they receive work.
    assert abs(rigid["input_work_J"]) > 1e-2 and abs(elastic["input_work_J"]) > 1e-2


def _fast_sine_scene(tmp_path):
    path = tmp_path / "sine50.toml"
    path.write_text(
        '[model]\nkind = "rigid"\n[model.params]\nb1 = 0.2\n[initial]\ntheta1 = 0.5\n'
        "[simulation]\nt_final = 0.4\ndt = 0.01\n[input.sine]\namplitude = [40.0, 0.0]\nfrequency = 50.0\n"
    )
    return load_scene(path)


@pytest.fixture(scope="module")
def fast_sine(tmp_path_factory):
    """A 50 Hz, 40 N.m sine on tau1 with output step 0.01 s, and an independent SciPy run with the sine in the RHS."""
    scene = _fast_sine_scene(tmp_path_factory.mktemp("sine"))
    model = scene.model

    def rhs(t, x):
        return model.rhs(x, scene.inputs(np.array([t]))[0])

    t = np.linspace(0.0, scene.t_final, 40001)
    ref = solve_ivp(rhs, (0.0, scene.t_final), scene.x0, method="DOP853", rtol=1e-11, atol=1e-11, t_eval=t, max_step=1e-3)
    assert ref.success
    X = ref.y.T
    work = np.trapezoid(model.power_in(X, scene.inputs(t)), t)
    free = scene.simulate(u=None, method="cvodes")
    return scene, X[::1000], work, free


@pytest.mark.parametrize("method", ["cvodes", "rk4", "RK45", "compiled-dopri5", "taylor"])
def test_fast_sine_is_not_aliased_away(fast_sine, method):
    if not _usable(method):
        pytest.skip(f"{method} is not available here")
    scene, ref, work_ref, free = fast_sine
    # CVODES restarts at each of the 2000 holds (order 1 after each restart): at 1e-8 it ends 3e-5 rad/s off, which
    # its energy balance error (6e-4 J against 4e-7 J for the one-step methods) reports; run it at 1e-11.
    tol = 1e-11 if method == "cvodes" else 1e-8
    traj = scene.simulate(method=method, rtol=tol, atol=tol)
    forced = np.abs(ref[:, 2] - free.x[:, 2]).max()
    # The sine moves omega1 by ~0.2 rad/s (tau / (I w)); sampled at the output times it would be exactly zero.
    assert forced > 0.1
    # Holds of 1 / (100 f) keep the fundamental within 1.6e-4 of its amplitude: the forced motion agrees to 1e-3.
    assert np.abs(traj.x[:, 2] - ref[:, 2]).max() < 1e-3 * forced
    summary = summarize("sine", scene.model, traj)
    # Input work from the run's own input grid (the output grid aliases it); 1e-3: the held sine's amplitude.
    assert summary["input_work_J"] == pytest.approx(work_ref, rel=1e-3)
    assert traj.stats["input_hold"] == pytest.approx(1.0 / 5000)
    # Measured 3.5e-7 J (quadrature of the dissipated power on the 2e-4 s input grid) for every method.
    assert summary["energy_balance_error_J"] < 1e-5


def test_time_input_refuses_an_absurd_input_grid():
    scene = load_scene("validation/rigid_forced")
    tiny = TimeInput(scene.inputs, 1e-9)
    with pytest.raises(ValueError, match="number of input holds"):
        scene.simulate(u=tiny)


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_scene_runs_shorter_and_finer_with_its_energy_balance(name):
    scene = load_scene(name)
    horizon = min(scene.t_final, 0.3)
    traj = scene.simulate(t_final=horizon, dt=scene.dt / 2)
    assert traj.t[-1] == horizon and traj.t[1] == pytest.approx(min(scene.dt / 2, horizon))
    summary = summarize(name, scene.model, traj)
    # rtol = atol <= 1e-8 over 0.3 s: the energy balance (change - work + dissipated) closes to well below 1e-6.
    assert summary["energy_balance_error_rel"] is None or summary["energy_balance_error_rel"] < 1e-6


def test_damped_forced_run_reports_a_small_balance_error_and_a_large_energy_change(tmp_path, capsys):
    path = tmp_path / "damped_forced.toml"
    path.write_text(
        '[model]\nkind = "elastic"\n[model.params]\nk1 = 300\nk2 = 300\nb1 = 0.5\nb2 = 0.3\nc1 = 2.0\nc2 = 2.0\n'
        "[initial]\ntheta1 = 0.8\n[simulation]\nt_final = 5.0\n[input]\ntau1 = 0.2\n"
        "[input.sine]\namplitude = [1.5, 0.5]\nfrequency = 1.0\n"
    )
    assert main(["simulate", "--scene", str(path), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["forced"] and s["damped"]
    assert abs(s["energy_change_J"]) > 1.0 and s["dissipated_J"] > 1.0  # the dampers take ~4 J of ~24 J
    # Integration at 1e-8 plus O(h^4) quadrature of the dissipated power at h = 0.01 s: the balance closes to 1e-4 J.
    assert s["energy_balance_error_J"] < 1e-4
    assert main(["simulate", "--scene", str(path)]) == 0
    table = capsys.readouterr().out
    assert "energy balance error [J]" in table and "energy drift" not in table


def test_energy_flows_are_exact_for_held_torques():
    import pendulab as pl

    model = pl.rigid(b1=0.3, b2=0.2)
    u = np.array([[0.5, -0.2]])
    traj = pl.simulate(model, model.state(theta1=1.0), 2.0, dt=0.01, method="cvodes", rtol=1e-12, atol=1e-12, u=u[0])
    work, dissipated = energy_flows(model, traj.t, traj.x, traj.u)
    energy = traj["energy"]
    # Work of a held torque is exact (tau . dtheta); dissipation: O(h^4) quadrature, measured 2.4e-6 J at h = 0.01 s
    # (1.4e-3 at 0.05, 3.8e-5 at 0.02: x16 per halving) on a swing to 3 rad at ~2.6 rad/s.
    np.testing.assert_allclose(energy - energy[0], work - dissipated, rtol=0, atol=1e-5)
    d1, d2 = traj["theta1"][-1] - 1.0, traj["theta2"][-1] - 0.0
    assert work[-1] == pytest.approx(0.5 * d1 - 0.2 * (d2 - d1), rel=1e-12)  # power = tau1 w1 + tau2 (w2 - w1)

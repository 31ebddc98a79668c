"""NMPC (pendulab.control.nmpc): balance, limits, warm start, solver agreement, bad input, and the cosim CLI."""

import json

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.feedback import SampledController, as_feedback, upright_state
from pendulab.control.nmpc import NMPCOptions, nmpc_controller
from pendulab.control.swingup.tasks import load_task


@pytest.fixture(scope="module")
def pendubot():
    return load_task("swingup_pendubot").model


def _run(model, ctrl, x0, t_final):
    ctrl.reset()
    return pl.simulate(model, x0, t_final, dt=ctrl.sample_time, u=as_feedback(ctrl, model), rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("actuation", ["pendubot", "full"])
def test_catches_upright_perturbation_within_torque_limit(pendubot, actuation):
    ctrl = nmpc_controller(pendubot, actuation=actuation, u_max=6.0, horizon=15)
    assert isinstance(ctrl, SampledController)
    x0 = upright_state(pendubot) + np.array([0.15, -0.1, 0.3, 0.0])
    traj = _run(pendubot, ctrl, x0, 3.0)
    err = np.abs(traj.x[-1] - upright_state(pendubot))
    # 3 s is ~10 closed-loop time constants of the terminal LQR: the error is down by orders of magnitude.
    assert err.max() < 1e-3
    assert np.abs(traj.u).max() <= 6.0 + 1e-12  # hard torque bound (plus float rounding)
    st = ctrl.stats()
    assert st["failures"] == 0 and st["infeasible"] == 0 and st["n_calls"] == 150
    assert 0 < st["solve_time_median"] <= st["solve_time_max"]
    if actuation == "pendubot":
        assert np.all(traj.u[:, 1] == 0.0)  # the passive elbow gets no torque


def test_tiny_torque_limit_is_reported_not_raised(pendubot):
    # 0.01 N.m cannot hold a 0.3 rad lean: the soft rate bound must be violated, and said so.
    ctrl = nmpc_controller(pendubot, actuation="pendubot", u_max=0.01, horizon=10, velocity_limit=2.0)
    x0 = upright_state(pendubot) + np.array([0.3, 0.0, 0.0, 0.0])
    traj = _run(pendubot, ctrl, x0, 2.0)
    st = ctrl.stats()
    assert st["infeasible"] > 0 and st["n_calls"] == 100
    assert np.abs(traj.u[:, 0]).max() <= 0.01 + 1e-15  # torques stay within the tiny limit
    assert np.abs(traj.x[-1, 0] - np.pi) > 0.5  # it falls: nothing is caught with 0.01 N.m


@pytest.mark.parametrize(("rates", "over"), [((-4.0, 7.0), True), ((2.0, 5.0), False)])
def test_soft_rate_bound_is_on_the_joint_rates(pendubot, rates, over):
    # Links at -4 and 7 rad/s keep a 10 rad/s bound on each link but turn the elbow joint at 11 rad/s: the start
    # needs slack (the robot's limits are on its joints, as the RTI's); links at 2 and 5 (elbow joint 3) do not.
    ctrl = nmpc_controller(pendubot, actuation="pendubot", u_max=6.0, horizon=10, velocity_limit=10.0)
    ctrl(0.0, upright_state(pendubot) + np.array([0.0, 0.0, *rates]))
    assert (ctrl.stats()["infeasible"] == 1) is over


def test_failed_solve_falls_back_without_raising(pendubot):
    # One interior-point iteration cannot converge from a cold start: counted as a failure, loop continues.
    ctrl = nmpc_controller(pendubot, actuation="pendubot", u_max=6.0, horizon=10, solver="ipopt", max_iter=1)
    x0 = upright_state(pendubot) + np.array([0.1, 0.0, 0.0, 0.0])
    u = ctrl(0.0, x0)
    assert ctrl.stats()["failures"] == 1 and np.isfinite(u).all() and abs(u[0]) <= 6.0


def test_warm_start_reduces_iterations(pendubot):
    ctrl = nmpc_controller(pendubot, actuation="pendubot", u_max=6.0, horizon=15, solver="ipopt")
    x0 = upright_state(pendubot) + np.array([0.2, -0.1, 0.0, 0.0])
    traj = _run(pendubot, ctrl, x0, 0.4)
    warm = ctrl.iterations[1:]
    cold = []
    for k in range(1, len(warm) + 1):
        ctrl.reset()  # forget the previous solution: start from the reference window
        ctrl(traj.t[k], traj.x[k])
        cold.append(ctrl.iterations[0])
    assert np.mean(warm) < np.mean(cold)


def test_solvers_agree_on_first_move(pendubot):
    x0 = upright_state(pendubot) + np.array([0.1, -0.05, 0.0, 0.2])
    moves = {}
    for solver, max_iter in (("ipopt", 100), ("sqp", 30), ("fatrop", 100)):
        ctrl = nmpc_controller(pendubot, actuation="full", u_max=6.0, horizon=10, solver=solver, max_iter=max_iter)
        moves[solver] = ctrl(0.0, x0)
        assert ctrl.stats()["failures"] == 0, solver
    # Converged solutions of one NLP: agreement to the solvers' tolerances (1e-6 on optimality).
    np.testing.assert_allclose(moves["sqp"], moves["ipopt"], atol=1e-4)
    np.testing.assert_allclose(moves["fatrop"], moves["ipopt"], atol=1e-4)


def test_rti_iterations_converge_to_full_solve(pendubot):
    x0 = upright_state(pendubot) + np.array([0.05, 0.0, 0.0, 0.0])
    rti = nmpc_controller(pendubot, actuation="pendubot", u_max=6.0, horizon=10)
    full = nmpc_controller(pendubot, actuation="pendubot", u_max=6.0, horizon=10, max_iter=30)
    u_full = full(0.0, x0)
    # Near upright the NLP is almost a QP: one Gauss-Newton step from the cold guess lands within 10 %.
    np.testing.assert_allclose(rti(0.0, x0), u_full, rtol=0.1)
    for _ in range(5):  # same sample again: each call is one more SQP iteration from the previous iterate
        u = rti(0.0, x0)
    np.testing.assert_allclose(u, u_full, rtol=1e-6)  # converged to the full solve's tolerance


def test_elastic_plant_prediction_models():
    model = pl.elastic(k1=2000.0, k2=2000.0)
    x = upright_state(model)
    rigid = nmpc_controller(model, actuation="full", u_max=20.0, horizon=5, planning="rigid", state_map="project")
    assert rigid.plan_model.kind == "rigid" and rigid.ocp.nx == 4
    np.testing.assert_array_equal(rigid.plan_state(x), x[[0, 1, 4, 5]])  # angles and link rates kept
    # The elastic model itself, tracking a rigid reference lifted to quasi-static spring lengths.
    ref = (np.array([0.0, 0.5]), np.array([[np.pi, np.pi, 0.0, 0.0]] * 2), np.zeros((2, 2)))
    own = nmpc_controller(model, actuation="full", u_max=20.0, horizon=5, reference=ref, sample_time=0.02, planning="model")
    assert own.plan_model is model and own.ocp.nx == 8
    np.testing.assert_allclose(own.x_ref[0], x, atol=1e-9)  # quasi-static at rest upright = the equilibrium
    assert own.ocp.step.numel_out() == 8
    assert own.stats()["prediction_level"] == "elastic" and own.stats()["state_map"] == "none"


@pytest.fixture(scope="module")
def stiff():
    return load_task("pendubot_elastic")


def test_auto_prediction_follows_the_planning_rule(stiff):
    from pendulab.control.nmpc.prediction import LENGTH_PARAMS
    from pendulab.control.swingup.rule import planning_rule

    # Stiff springs (w_s / w_p = 10): the rule predicts rigid 0.40, quasi-static 0.15 -> quasi-static within 0.2.
    ctrl = nmpc_controller(stiff.model, actuation="pendubot", u_max=6.0, horizon=5)
    st = ctrl.stats()
    d = planning_rule(stiff.model, 0.2)
    assert st["prediction_level"] == "rigid+quasi-static" == d.chosen
    assert ctrl.plan_model.kind == "rigid" and ctrl.ocp.nx == 4 and st["prediction_states"] == 4
    assert st["prediction_predicted_error"] == pytest.approx(d.predicted["rigid+quasi-static"])  # the rule's number
    assert st["state_map"] == "average" and "quasi-static" in st["prediction_reason"]
    assert ctrl.ocp.stage_params == LENGTH_PARAMS
    # After the reference every stage predicts with the upright static lengths (compressed by the weight above).
    up = upright_state(stiff.model)
    np.testing.assert_allclose(ctrl.window(0)[2], [[up[2], up[3], up[2], up[3]]] * 5, rtol=1e-12)
    # A tolerance below every reduced level's predicted error leaves the elastic model.
    strict = nmpc_controller(stiff.model, actuation="pendubot", u_max=6.0, horizon=2, prediction_tolerance=0.1)
    assert strict.stats()["prediction_level"] == "elastic" and strict.ocp.nx == 8
    # Soft springs (w_s / w_p = 2): no reduced level is predicted within 0.2.
    soft = load_task("pendubot_elastic_soft").model
    assert nmpc_controller(soft, actuation="pendubot", u_max=6.0, horizon=2).stats()["prediction_level"] == "elastic"


def test_momentum_map_is_exact_on_the_quasi_static_manifold(stiff):
    from pendulab.control.nmpc.prediction import SlowStateMap
    from pendulab.model.quasistatic import quasi_static_state

    model = stiff.model
    smap = SlowStateMap(model, quasi_static=True)
    for theta, omega in (([1.0, 2.0], [3.0, -2.0]), ([np.pi, 2.5], [-8.0, 12.0]), ([0.0, 0.0], [0.0, 0.0])):
        x = quasi_static_state(model, theta, omega)
        # On r = r*, v = 0 the rigid mass matrix at r* is the angle block of the elastic one: rates unchanged.
        np.testing.assert_allclose(smap(x), np.concatenate([theta, omega]), rtol=0, atol=1e-10)
    # A radial spring velocity is not a link rate: the projection keeps the measured rates, the map the momenta.
    x = quasi_static_state(model, [0.3, 0.3], [0.0, 0.0])
    x[6] = 0.5  # spring 1 moving along link 1 (aligned links: it carries no angular momentum)
    np.testing.assert_allclose(smap(x)[2:], 0.0, atol=1e-12)


def test_averaged_map_removes_the_spring_oscillation(stiff):
    from pendulab.control.nmpc.prediction import SlowStateMap
    from pendulab.model.quasistatic import quasi_static_state

    model = stiff.model
    periods = tuple(sorted(2 * np.pi / np.array([126.37, 345.7])))  # the task's spring modes at hanging [s]
    avg = SlowStateMap(model, quasi_static=False, average=periods)
    mom = SlowStateMap(model, quasi_static=True)
    np.testing.assert_allclose(avg(upright_state(model)), [np.pi, np.pi, 0.0, 0.0], atol=1e-12)  # an equilibrium stays
    # A swinging pendulum with ringing springs (3 mm stretch, 0.3 m/s): 0.1 s of it, every 1 ms.
    x = quasi_static_state(model, [2.0, 0.5], [12.0, 8.0])
    x[2:4] += 0.003
    x[6] = 0.3
    traj = pl.simulate(model, x, 0.1, dt=0.001, rtol=1e-10, atol=1e-10)

    def fast_part(rates):  # what a quartic fit over 0.1 s (the slow motion) leaves
        return max(np.abs(r - np.polyval(np.polyfit(traj.t, r, 4), traj.t)).max() for r in rates.T)

    measured = fast_part(traj.x[:, 4:6])
    momentum = fast_part(np.array([mom(xk)[2:] for xk in traj.x]))
    averaged = fast_part(np.array([avg(xk)[2:] for xk in traj.x]))
    # Measured: the rates ring by ~3 rad/s; the momentum map leaves ~10 %, the window ~1 % (generous bounds).
    assert measured > 1.0 and momentum < 0.2 * measured and averaged < 0.03 * measured and averaged < 0.3 * momentum


def test_stiff_swingup_through_elastic_plant_on_the_reduced_model(stiff):
    from pendulab.control.nmpc import nmpc_for_task
    from pendulab.control.swingup.check import height_success

    ctrl, x0 = nmpc_for_task(stiff)
    assert ctrl.plan_model.nx == 4  # the rule's quasi-static level
    traj = pl.simulate(stiff.model, x0, stiff.t_final, dt=stiff.dt, u=as_feedback(ctrl, stiff.model), rtol=1e-8, atol=1e-8)
    check = height_success(traj, stiff.rest_lengths, stiff.success_fraction)
    # The task's success rule (end effector above 0.9 (L1 + L2) over the last second), reached within the 3 s plan.
    assert check.success and check.t_up < 3.0
    assert ctrl.stats()["failures"] == 0
    # Held near upright: the springs keep ringing (~0.3 J from the swing-up, undamped) and shift the balance
    # point by up to ~0.3 rad, which the 4-state prediction does not see (docs/nmpc.md).
    assert np.abs(traj.x[-1, :2] - np.pi).max() < 0.5


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"solver": "nope"}, ValueError, "solver"),
        ({"horizon": 0}, ValueError, "horizon"),
        ({"sample_time": -0.02}, ValueError, "sample_time"),
        ({"u_max": float("nan")}, ValueError, "u_max"),
        ({"actuation": "both"}, ValueError, "actuation"),
        ({"wibble": 1}, TypeError, "wibble"),
        ({"planning": "cheap"}, ValueError, "planning"),
        ({"prediction_tolerance": 1.5}, ValueError, "prediction_tolerance"),
        ({"state_map": "filter"}, ValueError, "state_map"),
        ({"torque_rate": -1.0}, ValueError, "torque_rate"),
        ({"reference": (np.arange(3.0), np.zeros((3, 3)), np.zeros((3, 2)))}, ValueError, "reference states"),
        ({"reference": (np.arange(3.0), np.zeros((3, 4)), np.zeros((3, 1)))}, ValueError, "reference torques"),
    ],
)
def test_bad_input(pendubot, kwargs, exc, match):
    with pytest.raises(exc, match=match):
        nmpc_controller(pendubot, **kwargs)


def test_bad_measurement_raises(pendubot):
    ctrl = nmpc_controller(pendubot, actuation="pendubot", horizon=5)
    with pytest.raises(ValueError, match="finite state"):
        ctrl(0.0, np.array([np.nan, 0.0, 0.0, 0.0]))
    with pytest.raises(ValueError, match="shape"):
        ctrl(0.0, np.zeros(3))


def test_bad_model_and_options():
    with pytest.raises(TypeError, match="model"):
        nmpc_controller("rigid")
    with pytest.raises(ValueError, match="max_iter"):
        NMPCOptions(max_iter=0)


@pytest.mark.needs_cc
def test_cosim_cli_swingup_through_fmu(tmp_path):
    from pendulab.cli import main

    out = tmp_path / "nmpc"
    status = main(["cosim", "--task", "swingup_acrobot", "--controller", "nmpc", "--t-final", "4", "--no-gif", "--out", str(out)])
    s = json.loads((out / "summary.json").read_text())
    # The long name is an alias: the summary uses the one task-name scheme (short names).
    assert status == 0 and s["controller"] == "nmpc" and s["task"] == "acrobot" and s["actuation"] == "acrobot"
    assert s["success"] is True and s["t_up"] < 3.0  # the 3 s plan is tracked, then held upright
    assert s["x0"] == {"theta1": 0.0, "theta2": 0.0, "omega1": 0.0, "omega2": 0.0}  # from hanging at rest
    assert abs(s["x_final"]["theta1"] - np.pi) < 1e-2 and abs(s["x_final"]["theta2"] - np.pi) < 1e-2  # held upright
    assert s["max_abs_torque"] <= 6.0 + 1e-12  # the task's torque limit
    assert 0 < s["solve_time_median"] <= s["solve_time_max"]
    assert s["iterations"] == {"median": 1.0, "max": 1}  # real-time iteration: one SQP step per sample
    assert s["failures"] == 0 and s["controller_stats"]["n_calls"] == 200 and s["sample_time"] == 0.02


def test_cosim_cli_unknown_task_exits_2(tmp_path, capsys):
    from pendulab.cli import main

    assert main(["cosim", "--task", "nope", "--controller", "nmpc", "--out", str(tmp_path)]) == 2
    assert "--task" in capsys.readouterr().err

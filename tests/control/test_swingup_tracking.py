"""Closed loop: TVLQR along the optimum, LQR at the top, torque saturation, height criterion."""

import numpy as np
import pytest

import pendulab as pl
from pendulab.control import swing_up
from pendulab.control.swingup.check import height_success
from pendulab.control.swingup.tasks import load_task, task_names
from pendulab.control.tracking import tvlqr


@pytest.mark.parametrize("name", ["acrobot", "pendubot"])
def test_tracked_closed_loop_succeeds_from_perturbed_starts(name):
    task = load_task(name)
    res = swing_up(task.problem, "radau", 60)
    assert res.success, res.message
    ctrl = tvlqr(res, dt=task.dt)
    rng = np.random.default_rng(1)
    for _ in range(3):
        x0 = task.problem.start + rng.normal(0.0, [0.05, 0.05, 0.2, 0.2])
        cl = pl.simulate(task.model, x0, task.t_final, dt=task.dt, u=ctrl, rtol=1e-8, atol=1e-8)
        hc = height_success(cl, task.rest_lengths, task.success_fraction)
        assert hc.success and hc.t_up < res.horizon
        # Saturation honoured exactly; passive joint exactly unactuated.
        assert np.max(np.abs(cl.u)) <= task.problem.torque_limit
        passive = 1 - task.problem.actuated[0]
        assert np.all(cl.u[:, passive] == 0.0)
        # Balanced at the top at the end (LQR converges; tolerance: 10 s is many closed-loop time constants).
        dx = cl.x[-1] - task.problem.target
        dx[:2] = (dx[:2] + np.pi) % (2 * np.pi) - np.pi
        assert np.max(np.abs(dx)) < 1e-3


def test_height_criterion_rejects_falling_pendulum():
    task = load_task("pendubot")
    # Released slightly off upright without control: falls, so the criterion must fail.
    traj = pl.simulate(task.model, task.problem.target + [0.05, 0, 0, 0], 5.0, dt=0.01)
    assert not height_success(traj, task.rest_lengths).success


def test_all_shipped_tasks_load_with_documented_limits():
    names = task_names()
    assert {"acrobot", "pendubot", "acrobot_elastic", "pendubot_elastic"} <= set(names)
    assert "pendubot_pointmass" in names
    for name in names:
        task = load_task(name)
        # RealAIGym tasks: 6 N.m; the textbook point-mass pendubot: 10 N.m.
        assert task.problem.torque_limit == (10.0 if name == "pendubot_pointmass" else 6.0) and task.t_final == 10.0
        assert task.tolerance == 1e-3 and task.planning == "auto"
        lo, hi = task.problem.torque_bounds()
        assert np.count_nonzero(hi) == 1  # exactly one actuated joint


def test_elastic_tasks_springs_ten_times_faster():
    # Stiff variant: lowest spring frequency about 10x the highest pendular one (point-mass rigid counterpart).
    task = load_task("pendubot_elastic")
    m = task.model
    A, _ = m.functions["jac_rhs"](m.rest_state(), [0, 0], m.p)
    w = np.sort(np.unique(np.round(np.abs(np.linalg.eigvals(np.array(A)).imag), 6)))
    w = w[w > 0]
    assert 9.5 < w[2] / w[1] < 11.0  # pendular: w[0], w[1]; springs: w[2], w[3]


def test_bad_task_inputs_raise(tmp_path):
    with pytest.raises(FileNotFoundError, match="unknown task"):
        load_task("nope")
    bad = tmp_path / "bad.toml"
    bad.write_text('[model]\nkind = "rigid"\n[task]\nactuation = "pendubot"\ntorque = 3\n')
    with pytest.raises(ValueError, match="unknown key"):
        load_task(bad)

"""Robustness scorecard: the perturbed plant, perturbation semantics, failing controllers, re-runs, one-joint swing-up."""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.feedback import as_feedback, balance_controller, energy_swingup, upright_state
from pendulab.control.swingup.tasks import load_task
from pendulab.ensemble.pool import map_runs
from pendulab.evaluate import CATEGORIES, categories_for, rerun, score
from pendulab.evaluate.perturb import Perturbation, run_perturbed_episode, substeps


@pytest.fixture(scope="module")
def pendubot():
    return load_task("pendubot")


def _balance_factory(task):
    """Pendubot LQR balance started 0.05 rad off upright: succeeds nominally, so success rates are informative."""
    ctrl = balance_controller(task.model, task.dt, design="discrete", actuation=task.problem.actuation, u_max=6.0)
    x0 = upright_state(task.model)
    x0[0] += 0.05
    return ctrl, x0


class _Recorder:
    """Zero torque; records what it was shown."""

    sample_time = 0.01
    input_names = ("tau1",)

    def __init__(self) -> None:
        self.seen: list[np.ndarray] = []

    def reset(self) -> None:
        self.seen = []

    def __call__(self, t, x):
        self.seen.append(np.array(x, dtype=float))
        return np.zeros(1)


def test_plant_matches_simulate(pendubot):
    ctrl, x0 = _balance_factory(pendubot)
    ep = run_perturbed_episode(ctrl, pendubot, x0, t_final=2.0)
    ref = pl.simulate(pendubot.model, x0, 2.0, dt=ctrl.sample_time, u=as_feedback(ctrl, pendubot.model), rtol=1e-11, atol=1e-11)
    # RK4 at 2 ms on a stable closed loop (pendular modes < 20 rad/s): global error ~ (h w)^4 ~ 1e-6 of the state.
    assert np.max(np.abs(ep.x - ref.x)) < 1e-5
    assert ep.success and ep.reason == ""


def test_plant_matches_simulate_elastic():
    task = load_task("pendubot_elastic_soft")
    ctrl, x0 = _balance_factory(task)
    ep = run_perturbed_episode(ctrl, task, x0, t_final=1.0)
    ref = pl.simulate(task.model, x0, 1.0, dt=ctrl.sample_time, u=as_feedback(ctrl, task.model), rtol=1e-11, atol=1e-11)
    # Substep from the fastest spring mode (h w <= 0.5): RK4 phase error of the spring oscillation stays ~1e-4 of its
    # amplitude (~1e-3 m) over 1 s.
    assert substeps(task.model, ctrl.sample_time, x0) >= 2
    assert np.max(np.abs(ep.x - ref.x)) < 1e-5


def test_zero_perturbation_is_nominal(pendubot):
    ctrl, x0 = _balance_factory(pendubot)
    a = run_perturbed_episode(ctrl, pendubot, x0, t_final=1.0)
    b = run_perturbed_episode(ctrl, pendubot, x0, Perturbation(meas_noise=0.0, torque_noise=0.0, delay=0.0, seed=7), t_final=1.0)
    # Same arithmetic, no random numbers drawn: bit-identical.
    assert np.array_equal(a.x, b.x)


def test_delay_shows_the_past_state(pendubot):
    rec = _Recorder()
    x0 = pendubot.model.state(theta1=1.0)
    ep = run_perturbed_episode(rec, pendubot, x0, Perturbation(delay=0.03), t_final=0.5)
    seen = np.array(rec.seen)
    assert np.array_equal(seen[3:], ep.x[: len(seen) - 3])  # exactly x(t - 0.03 s)
    assert np.array_equal(seen[:3], np.tile(x0, (3, 1)))  # before t = 0: the start state
    assert not np.array_equal(seen[3], ep.x[3])  # the pendulum moves, so the delay matters


def test_measurement_noise_only_on_rates(pendubot):
    rec = _Recorder()
    ep = run_perturbed_episode(rec, pendubot, pendubot.model.state(theta1=1.0), Perturbation(meas_noise=0.3, seed=1), t_final=0.5)
    err = np.array(rec.seen) - ep.x[: len(rec.seen)]
    assert np.all(err[:, :2] == 0.0)
    # 50 samples x 2 rates of N(0, 0.3): the sample std lies within 30 % of 0.3 (5 sigma of the std's spread).
    assert 0.2 < np.std(err[:, 2:]) < 0.4


@pytest.mark.parametrize(
    ("output", "reason"),
    [
        (lambda t, x: np.array([np.nan]), "non-finite"),
        (lambda t, x: np.array([7.0]), "above the limit"),
        (lambda t, x: np.array([1.0, 2.0]), "torque(s)"),
        (lambda t, x: 1 / 0, "raised ZeroDivisionError"),
    ],
)
def test_failing_controller_fails_the_run_with_reason(pendubot, output, reason):
    class Bad(_Recorder):
        def __call__(self, t, x):
            return output(t, x) if t >= 0.05 else np.zeros(1)

    card = score(
        lambda task: (Bad(), task.problem.start), pendubot, runs=1, categories=["delay"], levels={"delay": [0.0]}, workers=1
    )
    (rec,) = card.records
    assert not rec.success and reason in rec.reason and "t = 0.050 s" in rec.reason
    assert card.overall == 0.0


def test_passive_joint_torque_fails(pendubot):
    class Acro(_Recorder):
        input_names = ("tau2",)

        def __call__(self, t, x):
            return np.array([0.5])

    ep = run_perturbed_episode(Acro(), pendubot, pendubot.problem.start, t_final=0.1)
    assert not ep.success and "passive" in ep.reason


def test_success_rates_equal_direct_reruns(pendubot):
    levels = {"measurement_noise": [0.0, 0.5, 2.0], "delay": [0.0, 0.04], "pushes": [1.0]}
    card = score(_balance_factory, pendubot, runs=3, categories=list(levels), levels=levels, seed=3, workers=2)
    assert len(card.records) == 3 * 3 + 2 + 3
    for cat in card.categories:
        for li, rate in enumerate(cat.success_rates):
            recs = [r for r in card.records if r.category == cat.name and r.level_index == li]
            assert rate == sum(r.success for r in recs) / len(recs)
    assert card.category("measurement_noise").success_rates[0] == 1.0  # nominal balance holds
    assert 0.0 < card.overall < 1.0  # some levels break it: the scorecard discriminates
    rng = np.random.default_rng(0)
    for k in rng.choice(len(card.records), size=4, replace=False):
        again = rerun(_balance_factory, pendubot, card.records[k], n_sub=card.n_sub)
        assert (again.success, again.reason) == (card.records[k].success, card.records[k].reason)


def test_scorecard_json_and_table(pendubot):
    card = score(_balance_factory, pendubot, runs=2, categories=["torque_noise"], levels={"torque_noise": [0.0, 5.0]}, workers=1)
    import json

    d = json.loads(card.to_json())
    assert d["categories"][0]["levels"] == [0.0, 5.0] and d["categories"][0]["runs"] == [2, 2]
    assert d["overall"] == pytest.approx(card.overall)
    assert "| torque_noise |" in card.table()


def test_bad_arguments(pendubot):
    with pytest.raises(ValueError, match="unknown category"):
        score("lqr", pendubot, categories=["gravity"])
    with pytest.raises(ValueError, match="does not apply"):
        score("lqr", pendubot, categories=["stiffness"])
    with pytest.raises(ValueError, match="runs"):
        score("lqr", pendubot, runs=0)
    with pytest.raises(ValueError, match="controller must be one of"):
        score("pid", pendubot)
    with pytest.raises(ValueError, match="meas_noise"):
        Perturbation(meas_noise=-1.0)
    with pytest.raises(ValueError, match="response"):
        Perturbation(response=float("nan"))
    assert "stiffness" in categories_for("elastic") and "inertia" not in categories_for("elastic")
    assert set(categories_for("rigid")) | {"stiffness"} == set(CATEGORIES)


def test_map_runs_forked_equals_inline():
    offset = np.arange(3.0)  # a closure over an unpicklable-by-reference local

    def fn(k):
        return float(k * k + offset[k % 3])

    inline = map_runs(fn, range(23), workers=1)
    forked = map_runs(fn, range(23), workers=2, progress=lambda done, total: None)
    assert forked == inline == [float(k * k + k % 3) for k in range(23)]
    with pytest.raises(ValueError, match="workers"):
        map_runs(fn, range(3), workers=0)


@pytest.mark.parametrize("name", ["pendubot", "acrobot"])
def test_one_joint_pumping_never_removes_energy_below_the_top(name):
    task = load_task(name)
    model = task.model
    ctrl = energy_swingup(model, task.dt, u_max=task.problem.torque_limit, actuation=task.problem.actuation)
    assert ctrl.input_names == (("tau1",) if name == "pendubot" else ("tau2",))

    class Watch:
        """The swing-up, noting after each sample whether it was pumping (no catch yet or a released one)."""

        sample_time, input_names = ctrl.sample_time, ctrl.input_names

        def __init__(self) -> None:
            self.pumping: list[bool] = []

        def reset(self) -> None:
            ctrl.reset()

        def __call__(self, t, x):
            u = ctrl(t, x)
            self.pumping.append(ctrl.caught_at is None)
            return u

    watch = Watch()
    ep = run_perturbed_episode(watch, task, task.problem.start, t_final=4.0)
    pumping = np.array(watch.pumping)
    X, U = ep.x[:-1][pumping], ep.u[pumping]
    power = np.array([float(model.functions["power_in"](x, u, model.p)) for x, u in zip(X, U, strict=True)])
    deficit = ctrl.e_up - np.array([model.energy(x) for x in X])
    below = deficit > 0
    # The pumping power is k (E_up - E) rate^2 >= 0 below the top; the start kick is u_max at |rate| < 1e-3 rad/s.
    assert np.all(power[below] >= -task.problem.torque_limit * 1e-3)
    assert np.mean(power[below] > 0) > 0.9  # it does pump
    # It gets there: the energy reaches the upright's.
    assert np.max(deficit) > 0 and np.min(deficit) < 0.05 * (ctrl.e_up - model.energy(X[0]))
    # The passive torque is zero all along.
    passive = 1 if name == "pendubot" else 0
    assert np.all(ep.u[:, passive] == 0.0)

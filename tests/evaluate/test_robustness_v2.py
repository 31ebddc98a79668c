"""RealAIGym robustness v2: the plant against the lecture formulas, the runner against an independent restatement of
upstream's benchmark (same seed, same draws), the score formula on the published rows, journal/resume, CLI wiring."""

from __future__ import annotations

import json

import numpy as np
import pytest
from upstream import reference as ref  # tests/evaluate/upstream (pytest puts tests/evaluate on sys.path)

from pendulab.cli import main
from pendulab.evaluate.realai.controllers import CONTROLLERS, resolve_controller
from pendulab.evaluate.realai.plant import MODEL_VARIATIONS, PARAM_NAMES, nominal_params, protocol_rhs_python, vary
from pendulab.evaluate.realai.robustness import (
    CATEGORIES,
    PUBLISHED_ROBUSTNESS,
    category_rates,
    plan_runs,
    protocol_grid,
    random_gauss_perturbation,
    robustness_score,
    robustness_v2,
)

#: The reduced grid of the side-by-side test: the hardest level of every category (outcomes differ there).
LEVEL = 20


def _lecture_plant(task: str, name: str, value: float) -> ref.LecturePlant:
    kw = {name: value}
    return ref.plant_for(task, **kw)


@pytest.mark.parametrize("task", ["pendubot", "acrobot"])
def test_plant_matches_the_lecture_formulas_for_every_variation(task):
    """pendulab's Lagrangian plant (absolute angles) = upstream's lecture formulas (joint coordinates), every grid value."""
    f = protocol_rhs_python()
    grid = protocol_grid(task)["model"]
    rng = np.random.default_rng(0)
    worst = 0.0
    for name in MODEL_VARIATIONS:
        for value in grid[name]:
            p = vary(nominal_params(task), name, value)
            lecture = _lecture_plant(task, name, value)
            lecture.B = np.eye(2)  # both torques through, to check the torque terms of both joints
            for _ in range(5):
                q = rng.uniform(-4, 4, 4)
                u = rng.uniform(-6, 6, 2)
                x_abs = np.array([q[0], q[0] + q[1], q[2], q[2] + q[3]])
                qd = lecture.rhs(q, u)
                want = np.array([qd[0], qd[0] + qd[1], qd[2], qd[2] + qd[3]])
                got = f(x_abs, u, [p[n] for n in PARAM_NAMES])
                worst = max(worst, float(np.max(np.abs(got - want)) / max(1.0, np.max(np.abs(want)))))
    # Two exact formulations of the same equations: only round-off separates them.
    assert worst < 1e-12


def test_variations_move_what_upstream_moves():
    p = nominal_params("pendubot")
    # m1 r1 changes the centre of mass, keeps mass and joint inertia; m2 keeps r2 and I2.
    q = vary(p, "m1r1", 1.25 * p["m1"] * p["r1"])
    assert q["r1"] == pytest.approx(1.25 * p["r1"], rel=1e-15) and q["m1"] == p["m1"] and q["I1"] == p["I1"]
    q = vary(p, "m2", 0.5)
    assert (q["m2"], q["r2"], q["I2"]) == (0.5, p["r2"], p["I2"])
    assert (p["Ir"], p["b1"], p["cf2"]) == (0.0, 0.0, 0.0)  # sim_parameters.py zeroes them
    with pytest.raises(ValueError, match="'l1'"):
        vary(p, "l1", 0.3)


def test_grid_and_plan_sizes_are_the_benchmarks():
    g = protocol_grid("acrobot")
    np.testing.assert_array_equal(g["delay"], np.linspace(0.0, 0.04, 21))
    # get_par_list: 0.75 ... 1.25 times the nominal value, 21 points.
    assert g["model"]["I2"][0] == pytest.approx(0.75 * nominal_params("acrobot")["I2"], rel=1e-15)
    plan = plan_runs("pendubot")
    counts = {c: sum(s.category == c for s in plan) for c in CATEGORIES}
    assert counts == {
        "model": 210, "measurement_noise": 210, "u_noise": 210, "u_responsiveness": 21, "delay": 21, "perturbation": 50,
    }  # fmt: skip
    assert len(plan) == 722 and [s.index for s in plan] == list(range(722))
    with pytest.raises(ValueError, match="levels"):
        plan_runs("pendubot", levels=[21])
    with pytest.raises(ValueError, match="categories"):
        plan_runs("pendubot", categories=["gravity"])


def test_perturbation_draws_equal_the_global_generator_calls():
    np.random.seed(11)
    want = ref.gauss_pulses(10.0, 0.002, 3, 1.0, [0.05, 0.1], [0.5, 5.0])
    after = np.random.get_state()
    rng = np.random.RandomState(11)
    got = random_gauss_perturbation(rng)
    for a, b in zip(got, want, strict=True):
        np.testing.assert_array_equal(a, b)  # same calls on the same generator: bit for bit
    assert np.array_equal(rng.get_state()[1], after[1]) and rng.get_state()[2:] == after[2:]
    mu, amp = got[1], got[3]
    assert np.all(np.diff(np.sort(mu.ravel())) >= 1.0) and np.all((np.abs(amp) >= 0.5) & (np.abs(amp) <= 5.0))


def test_runner_reproduces_the_reference_benchmark_run_for_run():
    """Same seed, same controller, reduced grid of all six categories: identical successes and final states."""
    task, seed = "acrobot", 5
    _, ctrl = resolve_controller(task, "swingup")  # energy pumping + LQR: designed in milliseconds, mixed outcomes here
    params = ("m2r2",)
    mine = robustness_v2(
        task, ctrl, seed=seed, workers=1, levels=[LEVEL], repetitions=1, u_noise_repetitions=1,
        perturbation_repetitions=1, model_params=params,
    )  # fmt: skip
    g = protocol_grid(task)
    np.random.seed(seed)
    succ, finals = ref.benchmark(
        task, ref.UpstreamStyle(ctrl), model_lists={p: [g["model"][p][LEVEL]] for p in params},
        meas_levels=[g["measurement_noise"][LEVEL]], u_levels=[g["u_noise"][LEVEL]],
        resp_levels=[g["u_responsiveness"][LEVEL]], delay_levels=[g["delay"][LEVEL]], reps=1, u_reps=1, pert_reps=1,
    )  # fmt: skip
    got = [r["success"] for r in mine.records]
    assert got == succ
    assert 0 < sum(got) < len(got)  # the reduced grid has both outcomes (else it would check little)
    for r, xf in zip(mine.records, finals, strict=True):
        if r["success"]:
            # Stabilized runs contract round-off (the two plants differ by ~1e-16 per step); failed runs are
            # chaotic (spinning) and amplify it without bound, so only their success is compared. A success caught after
            # a long pumping phase keeps some of the amplification (u_noise run: 2.9e-9 after ~7 turns of link 1).
            np.testing.assert_allclose(r["final"], xf, rtol=0, atol=1e-8)
    assert not mine.complete and mine.score == robustness_score(mine.rates)


def test_real_upstream_benchmarker_side_by_side():
    """The original benchmarker (when a local checkout is named by $PENDULAB_UPSTREAM_DOUBLE_PENDULUM) on a reduced grid."""
    bench = ref.real_upstream()
    if bench is None:
        pytest.skip("PENDULAB_UPSTREAM_DOUBLE_PENDULUM does not name upstream's src/python")
    from double_pendulum.model.model_parameters import model_parameters

    task, seed = "acrobot", 3
    _, ctrl = resolve_controller(task, "swingup")
    finals = []

    class Ben(bench.benchmarker):
        def compute_success_measure(self, x_traj, u_traj):
            finals.append(np.asarray(x_traj)[-1])
            return super().compute_success_measure(x_traj, u_traj)

    mpar = model_parameters()
    p = ref.MODEL_1_0
    mpar.m, mpar.l, mpar.r, mpar.I, mpar.g, mpar.gr = p["m"], p["l"], p["r"], p["I"], p["g"], p["gr"]
    mpar.Ir, mpar.b, mpar.cf, mpar.tl = 0.0, [0.0, 0.0], [0.0, 0.0], [0.0, 6.0]
    g = protocol_grid(task)
    ben = Ben(ref.UpstreamStyle(ctrl), [0.0] * 4, 0.002, 10.0, [np.pi, 0, 0, 0], [0.35, 0.35, 1.0, 1.0], True)
    ben.set_model_parameter(model_pars=mpar)
    np.random.seed(seed)
    res = ben.benchmark(
        compute_perturbation_robustness=True, mpar_vars=["m2r2"], modelpar_var_lists={"m2r2": g["model"]["m2r2"][[LEVEL]]},
        repetitions=1, meas_noise_sigma_list=g["measurement_noise"][[LEVEL]], u_noise_sigma_list=g["u_noise"][[LEVEL]],
        u_responses=g["u_responsiveness"][[LEVEL]], delay_mode="posvel", delays=g["delay"][[LEVEL]],
        perturbation_repetitions=1, perturbation_sigma_minmax=[0.05, 0.1], perturbation_amp_minmax=[0.5, 5.0],
    )  # fmt: skip
    # Upstream runs 10 torque-noise repetitions whatever `repetitions` says (u_noise_repetitions=10, the default).
    mine = robustness_v2(
        task, ctrl, seed=seed, workers=1, levels=[LEVEL], repetitions=1, perturbation_repetitions=1, model_params=["m2r2"]
    )
    theirs = [*res["model_robustness"]["m2r2"]["successes"], *res["meas_noise_robustness"]["None"]["successes"][0]]
    theirs += [*res["u_noise_robustness"]["successes"][0], *res["u_responsiveness_robustness"]["successes"]]
    theirs += [*res["delay_robustness"]["successes"], *res["perturbation_robustness"]["successes"]]
    assert [r["success"] for r in mine.records] == [bool(s) for s in theirs]
    for r, xf in zip(mine.records, finals, strict=True):
        if r["success"]:
            np.testing.assert_allclose(r["final"], xf, rtol=0, atol=1e-9)  # as in the reference test


@pytest.mark.parametrize("task", ["pendubot", "acrobot"])
def test_score_formula_reproduces_the_published_scores(task):
    """Published rows (RealAIGym leaderboard pages v2): mean of the six rates = the published overall score."""
    for name, (rates, score) in PUBLISHED_ROBUSTNESS[task].items():
        got = robustness_score({c: r / 100 for c, r in zip(CATEGORIES, rates, strict=True)})
        # Rates are published to 0.1 %, scores to 0.001: rounding of both, at most 0.0005 + 0.0005.
        assert got == pytest.approx(score, abs=1e-3), name


def test_noise_levels_pass_only_with_a_majority():
    succ = {
        "model": {"Ir": [True, False], "m2": [True, True]},
        "measurement_noise": [[True] * 5 + [False] * 5, [True] * 6 + [False] * 4],
        "u_noise": [[True] * 10],
        "u_responsiveness": [True, False, False, False],
        "delay": [False],
        "perturbation": [True, True],
    }
    rates = category_rates(succ)
    # 5/10 is not more than half (upstream: mean > 0.5); model: 3 of 4 runs.
    assert rates == {
        "model": 0.75,
        "measurement_noise": 0.5,
        "u_noise": 1.0,
        "u_responsiveness": 0.25,
        "delay": 0.0,
        "perturbation": 1.0,
    }
    assert robustness_score(rates) == pytest.approx(3.5 / 6, rel=1e-15)


class _Counting:
    """lqr balance that counts its resets (one per run)."""

    def __init__(self, ctrl):
        self.c, self.sample_time, self.input_names, self.resets = ctrl, ctrl.sample_time, ctrl.input_names, 0

    def reset(self):
        self.resets += 1
        self.c.reset()

    def __call__(self, t, x):
        return self.c(t, x)


def test_journal_resume_and_figure(tmp_path):
    _, lqr = resolve_controller("acrobot", "lqr")
    ctrl = _Counting(lqr)
    kw = {"levels": [0, 20], "categories": ["u_responsiveness", "delay"], "journal": tmp_path / "runs.json", "workers": 1}
    first = robustness_v2("acrobot", ctrl, **kw)
    assert ctrl.resets == 4 and len(json.loads((tmp_path / "runs.json").read_text())["records"]) == 4
    again = robustness_v2("acrobot", ctrl, resume=True, **kw)
    assert ctrl.resets == 4  # every run came from the journal
    assert again.rates == first.rates == {"u_responsiveness": 0.0, "delay": 0.0}  # LQR from hanging never swings up
    with pytest.raises(ValueError, match="seed 0 there, 1 now"):
        robustness_v2("acrobot", ctrl, resume=True, seed=1, **kw)
    from pendulab.viz.robustness import plot_robustness

    assert plot_robustness(first, tmp_path / "r.png").stat().st_size > 20_000


def test_controller_resolution_and_bad_input():
    assert {"best", "tvlqr", "lqr", "swingup", "nmpc"} <= set(CONTROLLERS)
    with pytest.raises(ValueError, match="'pid'"):
        resolve_controller("pendubot", "pid")
    with pytest.raises(TypeError, match="controller"):
        resolve_controller("pendubot", 3)
    name, ctrl = resolve_controller("pendubot", lambda task: CONTROLLERS["lqr"](task))
    assert name == "<lambda>" and ctrl.sample_time > 0
    with pytest.raises(ValueError, match="task"):
        robustness_v2("cartpole", "lqr")
    with pytest.raises(ValueError, match="seed"):
        robustness_v2("pendubot", "lqr", seed=-1)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--quick", "--controller", "lqr", "--task", "pendubot"], "--quick applies to --protocol robustness-v2"),
        (["--protocol", "v3", "--controller", "best", "--task", "pendubot", "--workers", "2"], "--workers does not apply"),
        (["--protocol", "robustness-v2", "--controller", "best", "--task", "pendubot", "--runs", "3"], "--runs does not apply"),
        (["--protocol", "robustness-v2", "--controller", "pid", "--task", "acrobot"], "--controller 'pid'"),
        (["--protocol", "robustness-v2", "--controller", "best", "--task", "pendubot_elastic"], "pendubot or acrobot"),
        (["--protocol", "v3", "--realai", "--controller", "best", "--task", "pendubot"], "does not combine"),
        (["--protocol", "v2", "--controller", "best", "--task", "pendubot", "--seed", "1"], "--seed does not apply"),
        (["--protocol", "robustness-v2", "--task", "pendubot"], "needs --controller and --task"),
    ],
)
def test_cli_protocol_errors(argv, message, capsys):
    assert main(["score", *argv]) == 2
    assert message in capsys.readouterr().err


def test_controller_on_its_grid_or_every_step():
    _, lqr = resolve_controller("pendubot", "lqr")  # 10 ms sample time
    kw = {"levels": [0], "categories": ["delay"], "workers": 1}
    held = robustness_v2("pendubot", lqr, **kw).records[0]
    fresh = robustness_v2("pendubot", lqr, every_step=True, **kw).records[0]
    # 5000 steps of 2 ms: 1000 calls on a 10 ms grid, 5000 when called every step as upstream calls its controllers.
    assert (held["calls"], fresh["calls"]) == (1000, 5000)

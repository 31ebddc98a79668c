"""``plant=``: the protocols and the scorecard simulate an identified robot instead of the nominal plant.

Two checks per path: the nominal plant written as a plant file reproduces the nominal run exactly
(the plumbing changes nothing else), and the shipped identified C.1 robot (friction, rotor inertia)
is what the episodes actually integrate.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.swingup.tasks import load_task
from pendulab.evaluate import score
from pendulab.evaluate.realai import realai_score, robustness_v2
from pendulab.evaluate.realai.plant import nominal_params, plant_label, protocol_model, protocol_params
from pendulab.evaluate.realai.robustness_grid import protocol_grid
from pendulab.evaluate.realai.v3 import run_v3
from pendulab.model.plant_file import IdentifiedPlant, load_plant, save_plant
from pendulab.model.robot import robot_to_rigid

C1 = load_plant("c1")


def _as_plant(params: dict) -> IdentifiedPlant:
    return IdentifiedPlant(params=dict(params), meta={"robot": "test"})


def _robot_of(model: pl.Model) -> dict:
    """A rigid model's parameters in RealAIGym's names (inertias about the joints): the inverse of robot_to_rigid."""
    r = model.params.resolved()
    return {
        "m1": r["m1"], "m2": r["m2"], "l1": r["L1"], "l2": r["L2"], "r1": r["lc1"], "r2": r["lc2"], "b1": r["b1"],
        "b2": r["b2"], "cf1": r["cf1"], "cf2": r["cf2"], "g": r["g"], "I1": r["I1"] + r["m1"] * r["lc1"] ** 2,
        "I2": r["I2"] + r["m2"] * r["lc2"] ** 2, "Ir": r["Ir"], "gr": r["gr"],
    }  # fmt: skip


def test_protocol_model_is_the_identified_robot_with_its_drivetrain():
    m = protocol_model("pendubot", C1)
    assert m.params.cf1 == C1.params["cf1"] and m.params.Ir == C1.params["Ir"] and m.params.gr == C1.params["gr"]
    assert protocol_params("acrobot", C1) == C1.params
    assert protocol_params("pendubot") == nominal_params("pendubot")
    assert plant_label(None) == "nominal" and plant_label(C1) != plant_label(_as_plant({**C1.params, "cf1": 0.1}))
    with pytest.raises(TypeError, match="IdentifiedPlant"):
        protocol_params("pendubot", C1.params)  # a dict is not a validated plant


def test_v2_on_the_nominal_plant_as_a_file_is_the_nominal_run_and_the_identified_robot_is_another():
    nominal = realai_score("pendubot", _sine())
    same = realai_score("pendubot", _sine(), plant=_as_plant(nominal_params("pendubot")))
    assert np.array_equal(same.x, nominal.x) and same.score == nominal.score  # bit for bit: the same plant
    robot = realai_score("pendubot", _sine(), plant=C1)
    assert robot.plant.startswith("identified (C.1") or robot.plant.startswith("identified (")
    assert robot.to_dict()["simulation"]["plant"] == robot.plant
    # the identified run integrates the robot: replaying its torques on pl.rigid(plant="c1") gives its states
    m = pl.rigid(plant="c1")
    ref = pl.simulate(m, robot.x[0], 0.5, 0.002, "cvodes", 1e-10, 1e-10, robot.u[:250])
    # The protocol's RK4 at 2 ms against CVODES at 1e-10 over 0.5 s: the friction atan(100 q') is stiff near rest
    # (100 cf / I ~ 300 1/s, h lambda ~ 0.6), measured up to 3e-4 rad; the plant without a drivetrain is > 1e-2 off.
    assert np.max(np.abs(ref.x[:, :2] - robot.x[:251, :2])) < 1e-3
    bare = pl.simulate(pl.rigid(**{**C1.rigid_kwargs(), "cf1": 0.0, "cf2": 0.0, "Ir": 0.0}), robot.x[0], 0.5, 0.002,
                       "cvodes", 1e-10, 1e-10, robot.u[:250])  # fmt: skip
    assert np.max(np.abs(bare.x[:, :2] - robot.x[:251, :2])) > 1e-2


def test_v3_and_robustness_take_the_plant():
    steps = 3000  # 6 s of the 60 s protocol: the first reset (3.75 +- 1 s) drives the arm to a random pose
    nominal = run_v3("pendubot", _zero(), "zero", n_steps=steps)
    robot = run_v3("pendubot", _zero(), "zero", n_steps=steps, plant=C1)
    assert robot.to_dict()["simulation"]["plant"] == plant_label(C1)
    k = int(np.argmax(np.abs(robot.u[:, 0]) > 0))  # the reset PID's first torque
    assert np.max(np.abs(robot.x[: k + 1])) == 0.0  # hanging at rest until then, on both plants
    assert np.max(np.abs(robot.x[k:, :2] - nominal.x[k:, :2])) > 1e-2  # then the friction shows
    m = pl.rigid(plant="c1")
    ref = pl.simulate(m, robot.x[k], 0.5, 0.002, "cvodes", 1e-10, 1e-10, robot.u[k : k + 250])
    # RK4 at 2 ms against CVODES over 0.5 s of PID drive: measured 2.5e-4 rad (the stiff friction near rest, see the v2 test)
    assert np.max(np.abs(ref.x[:, :2] - robot.x[k : k + 251, :2])) < 1e-3
    rob = robustness_v2("pendubot", "lqr", plant=C1, categories=["model"], model_params=["cf1"], levels=[0], workers=1)
    assert rob.plant == plant_label(C1) and rob.to_dict()["plant"] == plant_label(C1)
    assert rob.levels["model"]["cf1"][0] == pytest.approx(-0.2)  # upstream's absolute grid for cf1 ...
    assert protocol_grid("pendubot", C1)["model"]["m2r2"][10] == pytest.approx(
        C1.params["m2"] * C1.params["r2"]
    )  # ... m r: the plant's


def _open_loop(torque):
    """A pendubot "controller" that applies ``torque(t)`` [N.m] at the shoulder whatever the state (deterministic)."""

    class OpenLoop:
        sample_time = 0.002
        input_names = ("tau1",)

        def reset(self):
            pass

        def __call__(self, t, x):
            return np.array([torque(t)])

    return OpenLoop()


def _sine():
    return _open_loop(lambda t: 1.5 * np.sin(5.0 * t))  # the arm swings


def _zero():
    return _open_loop(lambda t: 0.0)


def test_robustness_journal_of_another_plant_is_refused(tmp_path):
    journal = tmp_path / "runs.json"
    kw = dict(categories=["model"], model_params=["b2"], levels=[0], workers=1, journal=journal)
    robustness_v2("pendubot", "lqr", **kw)
    with pytest.raises(ValueError, match="plant"):
        robustness_v2("pendubot", "lqr", resume=True, plant=C1, **kw)
    settings = json.loads(journal.read_text())["settings"]
    assert settings["plant"] == "nominal"


def test_scorecard_runs_on_the_plant_and_designs_on_the_task():
    task = load_task("pendubot")
    seen: list[np.ndarray] = []

    class Watch:
        sample_time = task.dt
        input_names = ("tau1",)

        def reset(self):
            seen.clear()

        def __call__(self, t, x):
            seen.append(np.array(x, dtype=float))
            return np.zeros(1)

    x0 = task.problem.start.copy()
    x0[0] = 0.4  # released from 0.4 rad with no torque: the plant's own free motion
    heavy = _as_plant({**_robot_of(task.model), "b1": 0.5, "b2": 0.2, "cf1": 0.3, "Ir": 1e-3, "gr": 6.0})
    card = score(lambda tk: (Watch(), x0), task, runs=1, categories=["delay"], levels={"delay": [0.0]}, workers=1, plant=heavy)
    assert len(card.records) == 1
    xs = np.array(seen)
    ref = pl.simulate(pl.rigid(**robot_to_rigid(heavy.params)), x0, task.dt * (len(xs) - 1), task.dt, "cvodes", 1e-10, 1e-10)
    # RK4 substeps of the scorecard's plant against CVODES: ~1e-7 rad measured; the nominal task model
    # (light damping, no friction) would be off by > 1e-2 rad within the run.
    assert np.max(np.abs(xs[:, :2] - ref.x[:, :2])) < 1e-4
    free = pl.simulate(task.model, x0, task.dt * (len(xs) - 1), task.dt, "cvodes", 1e-10, 1e-10)
    assert np.max(np.abs(xs[:, :2] - free.x[:, :2])) > 1e-2
    with pytest.raises(ValueError, match="elastic"):
        score("lqr", "pendubot_elastic_soft", plant=heavy, runs=1, categories=["delay"])


def test_plant_files_round_trip_through_pl_rigid_and_scenes(tmp_path):
    path = save_plant(C1, tmp_path / "plant.json")
    a, b = pl.rigid(plant=path), pl.rigid(plant="c1", b1=0.02)
    assert a.params == pl.rigid(**C1.rigid_kwargs()).params and b.params.b1 == 0.02 and b.params.cf2 == C1.params["cf2"]
    scene = tmp_path / "robot.toml"
    scene.write_text('[model]\nkind = "rigid"\nplant = "plant.json"\n[model.params]\nb2 = 0.01\n')
    from pendulab.scene import load_scene

    s = load_scene(scene)
    assert s.model.params.cf1 == C1.params["cf1"] and s.model.params.b2 == 0.01
    for bad, message in (
        ('kind = "elastic"\nplant = "plant.json"', "kind = 'rigid'"),
        ('kind = "rigid"\nplant = "no.json"', "not found"),
    ):
        scene.write_text(f"[model]\n{bad}\n")
        with pytest.raises(ValueError, match=message):
            load_scene(scene)
    with pytest.raises(FileNotFoundError, match="shipped plants"):
        pl.rigid(plant=tmp_path / "missing.json")


def test_a_task_moves_to_another_model_of_its_kind():
    task = load_task("pendubot")
    moved = task.with_model(pl.rigid(plant="c1"))
    assert moved.model.params.cf1 == C1.params["cf1"] and moved.problem.actuation == task.problem.actuation
    assert task.model.params.cf1 == 0.0  # the original task is untouched
    with pytest.raises(ValueError, match="rigid"):
        task.with_model(pl.elastic())
    with pytest.raises(TypeError, match="Model"):
        task.with_model(C1)

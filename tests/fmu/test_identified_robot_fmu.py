"""An FMU of the identified C.1 robot replays a real record's measured torques (issue 29, item 4).

The exported C code and pendulab's native CasADi model are independent paths through the same
Lagrangian (drivetrain included); driven by the robot's own measured torques from its measured start
state they must agree to the solvers' tolerance, and both must follow the measured angles far better
than the frictionless plant the leaderboards simulate.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest

import pendulab as pl
from pendulab.cosim.replay import TorqueReplay, replay_record
from pendulab.fmu import export
from pendulab.identify.datasets import C1_EXCITATION, c1_record
from pendulab.identify.published import DFKI_C1
from pendulab.model.plant_file import load_plant
from pendulab.model.robot import robot_to_rigid

pytestmark = pytest.mark.needs_cc

STARTS = (1.0, 3.0, 5.0)  # three 1 s windows of the first excitation record


@pytest.fixture(scope="module")
def robot_fmu(tmp_path_factory):
    model = pl.rigid(plant="c1")
    return model, export(model, tmp_path_factory.mktemp("robot") / "c1.fmu", 2)


def test_the_fmu_carries_the_identified_drivetrain(robot_fmu):
    model, fmu = robot_fmu
    with zipfile.ZipFile(fmu) as zf:
        root = ET.fromstring(zf.read("modelDescription.xml"))
    start = {v.get("name"): float(v[0].get("start")) for v in root.iter("ScalarVariable") if v.get("causality") == "parameter"}
    plant = load_plant("c1").params
    for fmu_name, robot_name in (("cf1", "cf1"), ("cf2", "cf2"), ("Ir", "Ir"), ("gr", "gr"), ("lc2", "r2")):
        assert start[fmu_name] == pytest.approx(plant[robot_name], rel=1e-15)  # written with repr: exact
    assert start["cf1"] > 0.1 and start["Ir"] > 0.0  # the identified robot does have friction and a rotor


def test_fmu_and_native_model_replay_a_real_record_alike_and_follow_it(robot_fmu):
    model, fmu = robot_fmu
    record = c1_record(C1_EXCITATION[0])
    leaderboard = pl.rigid(**robot_to_rigid({**DFKI_C1["1.0"], "Ir": 0.0, "b1": 0.0, "b2": 0.0, "cf1": 0.0, "cf2": 0.0}))
    err_id, err_lb = [], []
    for start in STARTS:
        rep = replay_record(fmu, model, record, start=start, duration=1.0)
        # Both solvers at rtol 1e-10; measured gap ~1e-7 rad over 1 s (the smoothed Coulomb friction's
        # kinks near rate reversals cost the adaptive steps most); 1e-5 keeps a 100x margin.
        assert rep.fmu_native_gap() < 1e-5
        assert np.ptp(rep.tau[:, 0]) > 0.2  # the measured excitation torques were played, not zeros
        err_id.append(np.abs(rep.prediction_error("native")[250]))  # 0.5 s into the window
        lb = replay_record(fmu, leaderboard, record, start=start, duration=1.0)
        err_lb.append(np.abs(lb.prediction_error("fmu")[250]))
    rms_id, rms_lb = np.sqrt(np.mean(np.square(err_id))), np.sqrt(np.mean(np.square(err_lb)))
    # Measured 0.018 rad (identified) against 0.30 rad (leaderboard plant) at 0.5 s: the identified robot
    # must be at least 5x closer to the real motion.
    assert rms_id < 0.2 * rms_lb, (rms_id, rms_lb)
    assert rms_id < 0.05  # and close in absolute terms: 3 degrees after half a second of open loop


@pytest.mark.parametrize(
    ("table", "dt", "message"),
    [
        (np.zeros((3, 3)), 0.002, "(n, 2) table"),
        (np.full((3, 2), np.nan), 0.002, "finite"),
        (np.zeros((0, 2)), 0.002, "(n, 2) table"),
        (np.zeros((3, 2)), 0.0, "positive sample time"),
        (np.zeros((3, 2)), float("nan"), "positive sample time"),
    ],
)
def test_torque_replay_refuses_bad_tables(table, dt, message):
    with pytest.raises(ValueError, match=re.escape(message)):
        TorqueReplay(table, dt)


def test_replay_refuses_windows_outside_the_record_and_elastic_models(robot_fmu):
    model, fmu = robot_fmu
    record = c1_record(C1_EXCITATION[0])
    with pytest.raises(ValueError, match="outside record"):
        replay_record(fmu, model, record, start=9.5, duration=1.0)
    with pytest.raises(ValueError, match="whole number"):
        replay_record(fmu, model, record, duration=0.0031)
    with pytest.raises(ValueError, match="rigid model"):
        replay_record(fmu, pl.elastic(), record)

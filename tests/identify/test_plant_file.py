"""The plant file round-trips exactly, and a bad one is refused with the reason."""

from __future__ import annotations

import json
import math

import pytest

from pendulab.identify.published import DFKI_C1
from pendulab.model.plant_file import FORMAT, IdentifiedPlant, load_plant, save_plant
from pendulab.model.robot import ROBOT_PARAM_NAMES, robot_inverse_dynamics, robot_params_vector


def test_round_trip(tmp_path):
    plant = IdentifiedPlant(params=dict(DFKI_C1["1.0"]), stderr={"I1": 0.003, "m1": math.nan}, torque_offset=(0.01, -0.02),
                            structure=("m1", "h1"), meta={"records": ["a", "b"]})  # fmt: skip
    back = load_plant(save_plant(plant, tmp_path / "p.json"))
    assert back.params == plant.params and back.torque_offset == plant.torque_offset
    assert back.stderr["I1"] == 0.003 and math.isnan(back.stderr["m1"])
    assert back.meta == {"records": ["a", "b"]}


def test_rigid_kwargs_give_the_same_links(tmp_path):
    """pl.rigid from the plant file: same gravity torque and link inertia about the joint as the robot model."""
    import pendulab as pl

    plant = IdentifiedPlant(params={**DFKI_C1["1.0"], "Ir": 0.0, "cf1": 0.0, "cf2": 0.0})
    model = pl.rigid(**plant.rigid_kwargs())
    # Held horizontal at rest (theta = pi/2, pi/2 absolute): the shoulder torque is the gravity moment of both links.
    tau_robot = robot_inverse_dynamics()([1.5707963267948966, 0.0], [0.0, 0.0], [0.0, 0.0], robot_params_vector(plant.params))
    p = plant.params
    moment = (p["m1"] * p["r1"] + p["m2"] * (p["l1"] + p["r2"])) * p["g"]
    assert float(tau_robot[0]) == pytest.approx(moment, rel=1e-12)
    x = model.state(theta1=1.5707963267948966, theta2=1.5707963267948966)
    acc = model.rhs(x, [moment, float(tau_robot[1])])[2:]
    assert acc == pytest.approx([0.0, 0.0], abs=1e-9)  # the same torques hold pl.rigid's arm still


@pytest.mark.parametrize(
    ("doc", "error", "message"),
    [
        ({"format": "other/1", "params": {}}, ValueError, "format must be"),
        ({"format": FORMAT, "params": {**DFKI_C1["1.0"], "m1": -1.0}}, ValueError, "must be > 0"),
        (
            {"format": FORMAT, "params": {k: v for k, v in DFKI_C1["1.0"].items() if k != "g"}},
            KeyError,
            "missing names \\['g'\\]",
        ),
        ({"format": FORMAT, "params": dict(DFKI_C1["2.0"])}, ValueError, "negative inertia"),
        ({"format": FORMAT, "params": dict(DFKI_C1["1.0"]), "torque_offset": [0.0, float("inf")]}, ValueError, "torque_offset"),
    ],
    ids=["format", "negative-mass", "missing", "inconsistent-inertia", "offset"],
)
def test_bad_plant_files(tmp_path, doc, error, message):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(error, match=message):
        load_plant(path)


def test_not_json(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text("{not json")
    with pytest.raises(ValueError, match="not JSON"):
        load_plant(path)


def test_the_parameter_vector_refuses_unphysical_values_unless_a_protocol_asks():
    bad = {**DFKI_C1["1.0"], "cf1": -0.2}  # a level of RealAIGym's robustness grid
    with pytest.raises(ValueError, match="cf1"):
        robot_params_vector(bad)
    assert robot_params_vector(bad, validate=False)[ROBOT_PARAM_NAMES.index("cf1")] == -0.2

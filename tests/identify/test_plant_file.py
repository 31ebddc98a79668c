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


def test_what_if_plant_changes_only_the_named_friction_and_remembers_the_identified_value(tmp_path):
    """with_params: the shoulder's Coulomb friction replaced shifts the shoulder torque by exactly the friction change."""
    from pendulab.model.robot import COULOMB_SHARPNESS

    c1 = load_plant("c1")
    what_if = c1.with_params(cf1=0.033)
    q, qd, qdd = [0.3, -0.2], [1.5, 0.0], [0.4, -0.1]  # shoulder turning, elbow at rest
    tau = [robot_inverse_dynamics()(q, qd, qdd, robot_params_vector(p.params)).full().ravel() for p in (c1, what_if)]
    shift = (0.033 - c1.params["cf1"]) * math.atan(COULOMB_SHARPNESS * 1.5)
    assert tau[1][0] - tau[0][0] == pytest.approx(shift, rel=1e-12)  # rel: one subtraction of ~1 N.m torques
    assert tau[1][1] == pytest.approx(tau[0][1], abs=1e-15)  # the elbow does not feel the shoulder's friction
    # Chained changes keep the identified value, and the record survives the file.
    twice = load_plant(save_plant(what_if.with_params(cf1=0.0, cf2=0.05), tmp_path / "w.json"))
    assert twice.meta["what_if"] == {
        "cf1": {"value": 0.0, "identified": c1.params["cf1"]},
        "cf2": {"value": 0.05, "identified": c1.params["cf2"]},
    }
    assert {k: v for k, v in twice.params.items() if k not in ("cf1", "cf2")} == {
        k: v for k, v in c1.params.items() if k not in ("cf1", "cf2")
    }


@pytest.mark.parametrize(
    ("changes", "message"),
    [({}, "at least one"), ({"zz": 1.0}, "unknown plant parameters"), ({"cf1": math.nan}, "finite"), ({"cf1": -0.1}, ">= 0")],
)
def test_what_if_plant_refuses_bad_changes(changes, message):
    with pytest.raises(ValueError, match=message):
        load_plant("c1").with_params(**changes)

"""``--plant FILE``: one option, one wording, one loader, in every command that simulates the robot."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
import zipfile

import pytest

from pendulab.cli import main
from pendulab.model.plant_file import SHIPPED_PLANTS, load_plant

C1 = load_plant("c1").params


def test_modes_of_the_identified_robot_carry_its_friction(capsys):
    assert main(["modes", "--model", "rigid", "--plant", "c1", "--set", "cf1=0", "--equilibrium", "down-down", "--json"]) == 0
    params = json.loads(capsys.readouterr().out)["params"]
    assert params["cf2"] == C1["cf2"] and params["Ir"] == C1["Ir"] and params["lc2"] == C1["r2"]
    assert params["cf1"] == 0.0  # --set overrides the plant file


def test_simulate_with_a_plant_file(tmp_path, capsys):
    plant = tmp_path / "plant.json"
    plant.write_text(SHIPPED_PLANTS["c1"].read_text())
    out = tmp_path / "run.csv"
    assert main(["simulate", "--model", "rigid", "--plant", str(plant), "--set", "theta1=1", "--t-final", "1",
                 "--out", str(out), "--json"]) == 0  # fmt: skip
    summary = json.loads(capsys.readouterr().out)
    assert summary["params"]["cf1"] == C1["cf1"]
    # Coulomb friction of 0.16 N.m and a rotor take energy out: the identified robot loses some in 1 s.
    rows = out.read_text().splitlines()
    header = rows[0].split(",")
    e = [float(r.split(",")[header.index("energy")]) for r in rows[1:]]
    assert e[-1] < e[0] - 1e-3


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["modes", "--model", "elastic", "--plant", "c1"], "does not apply to the elastic model"),
        (["modes", "--model", "rigid", "--plant", "/no/such/plant.json"], "shipped plants: ['c1']"),
        (["score", "--leaderboard", "--plant", "c1"], "--plant does not apply to --leaderboard"),
        (["score", "--realai", "--task", "pendubot", "--controller", "best", "--plant", "nope"], "--plant nope"),
        (["simulate", "--model", "elastic", "--plant", "c1"], "does not apply to the elastic model"),
    ],
)
def test_bad_plant_options_are_one_line_errors(argv, fragment, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert fragment in err and "Traceback" not in err


def test_bad_plant_file_content_is_named(tmp_path, capsys):
    bad = tmp_path / "plant.json"
    bad.write_text(json.dumps({"format": "pendulab.identified-plant/1", "params": {**C1, "I2": 0.0}}))
    assert main(["modes", "--model", "rigid", "--plant", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"--plant {bad}" in err and "below m2 r2^2" in err


@pytest.mark.needs_cc
def test_fmu_export_of_the_identified_robot(tmp_path, capsys):
    fmu = tmp_path / "robot.fmu"
    assert main(["fmu", "export", "--model", "rigid", "--plant", "c1", "--set", "b1=0.02", "--out", str(fmu)]) == 0
    with zipfile.ZipFile(fmu) as zf:
        root = ET.fromstring(zf.read("modelDescription.xml"))
    start = {v.get("name"): float(v[0].get("start")) for v in root.iter("ScalarVariable") if v.get("causality") == "parameter"}
    assert start["cf1"] == C1["cf1"] and start["gr"] == C1["gr"] and start["b1"] == 0.02


@pytest.mark.needs_cc
def test_cosim_of_the_identified_robot_under_lqr(tmp_path):
    out = tmp_path / "cosim"
    argv = ["cosim", "--plant", "c1", "--controller", "lqr", "--t-final", "1", "--no-gif", "--no-progress",
            "--init", "theta1=3.0", "theta2=3.0", "--out", str(out)]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["plant"] == "c1" and summary["params"]["cf1"] == C1["cf1"] and "identified" in summary["fmu"]
    # LQR designed on the identified robot catches it from 0.14 rad off upright; the Coulomb friction
    # stops it within a few hundredths of a radian of the top (measured 0.022 / 0.025 rad)
    assert abs(summary["x_final"]["theta1"] - 3.141592653589793) < 0.1
    assert abs(summary["x_final"]["theta2"] - 3.141592653589793) < 0.1


def test_one_cli_vocabulary_across_commands():
    """Parameters, initial state and model kind have one name in every command that takes them, old names kept."""
    import argparse

    from pendulab.cli import build_parser
    from pendulab.commands._common import VOCABULARY

    def parsers(parser, name="pendulab"):
        yield name, parser
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for key, child in action.choices.items():
                    yield from parsers(child, f"{name} {key}")

    takes = {concept: [] for concept in VOCABULARY}
    for name, parser in parsers(build_parser()):
        flags = {o: a for a in parser._actions for o in a.option_strings}
        for concept, (primary, *aliases) in VOCABULARY.items():
            given = [f for f in (primary, *aliases) if f in flags]
            if given:
                # Every spelling, the old ones kept as aliases: a user's habit from one command works in all.
                assert given == [primary, *aliases], f"{name}: {concept} spelt {given}, expected {[primary, *aliases]}"
                takes[concept].append(name)
    assert {"pendulab simulate", "pendulab modes", "pendulab fmu export", "pendulab cosim"} <= set(takes["parameters"])
    assert {"pendulab simulate", "pendulab fmu export", "pendulab cosim"} <= set(takes["initial state"])
    assert {"pendulab simulate", "pendulab fmu export", "pendulab cosim", "pendulab ssp export"} <= set(takes["model kind"])

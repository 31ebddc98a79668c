"""``scene check --verify`` says plainly when a prediction missed, by how much, and exits 1 on request (issue 31)."""

from __future__ import annotations

import dataclasses
import json

import pytest

from pendulab.cli import main
from pendulab.scene import choose_model, load_scene
from pendulab.scene.choice_result import Verification


@pytest.fixture(scope="module")
def choice():
    c = choose_model(load_scene("stiff_small_amplitude"))  # a priori only: milliseconds
    assert c.chosen == "linearized"  # a reduced level with a non-zero predicted error
    return c


def _verified(choice, measured_error: float, measured_horizon: float, ref_horizon: float | None = None):
    pred = next(p for p in choice.levels if p.name == choice.chosen)
    v = Verification(choice.chosen, pred.error, measured_error, pred.horizon, measured_horizon, True, 0.1, 0.1, None, ref_horizon)
    return dataclasses.replace(choice, verification=v)


def test_a_shorter_measured_horizon_is_a_named_miss(choice):
    pred = next(p for p in choice.levels if p.name == choice.chosen)
    missed = _verified(choice, 0.0, pred.horizon - 2.0)
    lines = missed.misses()
    assert len(lines) == 1 and "MISSED" in lines[0] and "(2 s short)" in lines[0]
    assert lines[0] in missed.table() and missed.to_dict()["missed"] == lines


def test_a_larger_measured_error_and_a_shorter_reference_horizon_are_misses_too(choice):
    pred = next(p for p in choice.levels if p.name == choice.chosen)
    worse = _verified(choice, pred.error * 4, pred.horizon, ref_horizon=choice.reference_horizon - 1.0)
    lines = worse.misses()
    assert len(lines) == 2 and "(4x)" in lines[0] and "the reference holds until" in lines[1]


def test_held_predictions_say_so_and_nothing_verified_has_no_misses(choice):
    held = _verified(choice, 0.0, next(p for p in choice.levels if p.name == choice.chosen).horizon)
    assert held.misses() == [] and "every prediction held" in held.table()
    assert choice.misses() == [] and "no level and no reference were run" in choice.table()


def test_fail_on_miss_sets_the_exit_status(tmp_path, monkeypatch, capsys, choice):
    import pendulab.scene.choice as rule

    monkeypatch.setattr(rule, "_verified", lambda scene, c: _verified(c, 0.0, c.t_final - 2.5))
    assert main(["scene", "check", "stiff_small_amplitude", "--verify", "--json"]) == 0  # reported, status unchanged
    assert json.loads(capsys.readouterr().out)["missed"]
    assert main(["scene", "check", "stiff_small_amplitude", "--verify", "--fail-on-miss"]) == 1
    assert "prediction(s) missed" in capsys.readouterr().err
    assert main(["scene", "check", "stiff_small_amplitude", "--fail-on-miss"]) == 2  # nothing verified: a usage error
    assert "--fail-on-miss applies to --verify" in capsys.readouterr().err

"""Model hierarchy on scenes: the cheapest model within tolerance, errors measured."""

import json

import numpy as np
import pytest

from pendulab.bench.hierarchy import check_scene, choose_model
from pendulab.cli import main
from pendulab.scene import load_scene as load


def _report(name):
    return check_scene(load(name), repeats=1)


def test_very_stiff_springs_pick_rigid():
    rep = _report("stiff_moderate_amplitude")
    levels = {lv.name: lv for lv in rep.levels}
    assert rep.chosen == "rigid", rep.table()
    # 1 rad swings are far from linear: the linearization misses by more than 10x the tolerance.
    assert levels["linearized"].error > 10 * rep.tolerance
    assert levels["elastic"].error == 0.0 and levels["elastic"].note == "reference"


def test_soft_springs_pick_elastic():
    rep = _report("soft_large_amplitude")
    assert rep.chosen == "elastic", rep.table()
    # Soft springs stretch by ~0.1 m and exchange energy with the swing: no cheaper model comes close.
    assert all(lv.error > 10 * rep.tolerance for lv in rep.levels[:-1])


@pytest.mark.parametrize(("scene", "expected"), [("elastic_stiff", "rigid"), ("elastic_soft", "elastic")])
def test_shared_scenes(scene, expected):
    try:
        sc = load(scene)
    except FileNotFoundError:
        pytest.skip(f"shipped scene {scene!r} not present yet")
    assert check_scene(sc, repeats=1).chosen == expected


def test_chosen_level_trajectory_reproduces_reported_error():
    sc = load("stiff_moderate_amplitude")
    level, rep = choose_model(sc, repeats=1)
    traj, ref = level.simulate(sc), sc.simulate()
    assert level.model.kind == "rigid" and traj.state_names == ref.state_names
    err = max(float(np.max(np.abs(traj[n] - ref[n]))) for n in sc.outputs)
    # Deterministic integrators: recomputing the chosen level gives the reported error to rounding.
    assert err == pytest.approx(next(lv.error for lv in rep.levels if lv.name == rep.chosen), rel=1e-9)


def test_scene_check_measure_cli_json(capsys):
    # --measure: the a posteriori check (every level run and timed), kept as the rule's benchmark.
    assert main(["scene", "check", "stiff_small_amplitude", "--json", "--measure", "--repeats", "1"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [lv["name"] for lv in data["levels"]] == ["linearized", "rigid", "rigid+quasi-static", "elastic"]
    assert data["chosen"] in ("linearized", "rigid")
    # 3-degree swings: the linearization about the hanging equilibrium is within the 1e-3 tolerance.
    assert data["levels"][0]["within_tolerance"]


def test_scene_check_bad_file(capsys):
    assert main(["scene", "check", "no_such_scene_xyz"]) == 2
    assert "no_such_scene_xyz" in capsys.readouterr().err

"""Model hierarchy on scenes: the cheapest model within tolerance, errors measured."""

import json

import numpy as np
import pytest

from pendulab.bench.hierarchy import check_scene, choose_model
from pendulab.cli import main
from pendulab.scenes import load_scene as load


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


def test_chosen_level_reproduces_its_reported_error():
    sc = load("stiff_moderate_amplitude")
    level, rep = choose_model(sc, repeats=1)
    traj = level.simulate(sc)
    ref = load("stiff_moderate_amplitude").model
    assert level.model.kind == "rigid" and traj.x.shape[1] == ref.nx
    err = max(
        np.max(np.abs(traj[n] - rep_traj)) for n, rep_traj in zip(("theta1", "theta2"), _reference_angles(sc), strict=False)
    )
    # Same computation as inside check_scene: the error on the angles is at most the reported max.
    assert err <= next(lv.error for lv in rep.levels if lv.name == rep.chosen) * (1 + 1e-12)


def _reference_angles(sc):
    from pendulab import simulate

    tr = simulate(sc.model, sc.x0, sc.t_final, sc.dt, sc.method, sc.rtol, sc.atol)
    return tr["theta1"], tr["theta2"]


def test_scene_check_cli_json(capsys):
    assert main(["scene", "check", "stiff_small_amplitude", "--json", "--repeats", "1"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [lv["name"] for lv in data["levels"]] == ["linearized", "rigid", "rigid+quasi-static", "elastic"]
    assert data["chosen"] in ("linearized", "rigid")
    # 3-degree swings: the linearization about the hanging equilibrium is within the 1e-3 tolerance.
    assert data["levels"][0]["within_tolerance"]


def test_scene_check_bad_file(capsys):
    assert main(["scene", "check", "no_such_scene_xyz"]) == 2
    assert "no_such_scene_xyz" in capsys.readouterr().err

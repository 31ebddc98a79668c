"""Model hierarchy on scenes: the cheapest model within tolerance, errors measured."""

import json

import numpy as np
import pytest

from pendulab.bench.hierarchy import check_scene, measure_model_choice
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
    level, rep = measure_model_choice(sc, repeats=1)
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


def _bench_module():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_model_choice.py"
    spec = importlib.util.spec_from_file_location("bench_model_choice", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_model_choice_benchmark_family_covers_the_issue():
    fam = _bench_module().family(24, 2027, quick=False)
    scenes = [s for _, _, s in fam]
    ks = [s.model.params.k1 for s in scenes if s.model.kind == "elastic"]
    # Issue 24: >= 40 scenes, rigid and elastic, k from 1e2 to 1e8 N/m, forced and free, random ones not fitted on.
    assert len(fam) >= 40 and {s.model.kind for s in scenes} == {"rigid", "elastic"}
    assert min(ks) <= 1e2 and max(ks) >= 1e8
    assert any(s.u_amplitude is not None for s in scenes) and any(s.u is not None for s in scenes)
    assert sum(g == "random" for _, g, _ in fam) >= 16
    assert max(float(s.initial["theta1"]) for s in scenes) >= 2.0 and min(float(s.initial["theta1"]) for s in scenes) <= 0.05


def test_measure_levels_gives_error_and_horizon():
    from pendulab.bench.hierarchy import measure_levels

    sc = load("stiff_small_amplitude")
    m = measure_levels(sc)
    assert list(m) == ["elastic", "linearized", "rigid", "rigid+quasi-static"]
    assert m["elastic"]["error"] == 0.0
    # 3-degree swings with 1e6 N/m springs: every cheaper level is within the scene's 1e-3 over the whole 5 s.
    assert all(m[n]["error"] <= sc.tolerance and m[n]["horizon"] == sc.t_final for n in ("linearized", "rigid"))

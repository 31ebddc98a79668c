"""The model rule's "cheapest" is the estimated cost in this process, compilation still owed included (issue 33).

Found: on a stiff elastic scene (k = 1e5, angles only, 5 s, tolerance 1e-2, method auto) the rule chose
rigid as "cheapest", and the rigid run took 1.27 s (heyoka's first compile) against 0.104 s for the elastic
reference it replaced (its native library already built).
"""

from __future__ import annotations

import pytest

from pendulab.scene import choose_model, load_scene
from pendulab.scene import cost as scene_cost
from pendulab.scene.levels import levels_for

heyoka = pytest.importorskip("heyoka", reason="the rigid level's auto method is taylor with the [taylor] extra")

SCENE = """
[scene]
name = "stiff_auto"
[model]
kind = "elastic"
[model.params]
k1 = 1e5
k2 = 1e5
[initial]
theta1 = 0.5
[simulation]
t_final = 5.0
dt = 0.01
method = "auto"
rtol = 1e-8
atol = 1e-8
[outputs]
names = ["theta1", "theta2"]
tolerance = 1e-2
"""


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "stiff_auto.toml"
    path.write_text(SCENE)
    return load_scene(path)


def _caches(monkeypatch, *, taylor_compiled: bool, native: str) -> None:
    import pendulab.integrate.taylor.cache as taylor_cache
    import pendulab.native.loader as loader

    monkeypatch.setattr(taylor_cache, "is_compiled", lambda key: taylor_compiled)
    monkeypatch.setattr(loader, "library_state", lambda kind: native)


def test_an_owed_compile_makes_the_reference_the_cheapest(scene, monkeypatch):
    _caches(monkeypatch, taylor_compiled=False, native="loaded")
    c = choose_model(scene)
    costs = {lv.name: lv.cost for lv in c.levels if lv.cost is not None}
    assert costs["rigid"].method == "taylor" and costs["elastic"].method == "compiled-dopri5"  # auto, per level
    assert costs["rigid"].preparation == scene_cost.PREPARATION_S["taylor"]["rigid"] and costs["elastic"].preparation == 0
    assert c.chosen == "elastic"  # rigid is within tolerance too, but owes its compile
    assert "compilation still owed included" in c.table() and "heyoka compile" in c.table()


def test_with_everything_compiled_the_reduced_model_is_the_cheapest(scene, monkeypatch):
    _caches(monkeypatch, taylor_compiled=True, native="loaded")
    c = choose_model(scene)
    assert c.chosen == "rigid"
    costs = {lv.name: lv.cost.total for lv in c.levels if lv.cost is not None}
    assert costs["rigid"] == min(costs.values())
    assert costs["rigid"] < costs["rigid+quasi-static"]  # the same run, plus the quasi-static lengths at every output


def test_a_native_library_not_built_counts_its_build(scene, monkeypatch):
    _caches(monkeypatch, taylor_compiled=True, native="not built")
    elastic = scene_cost.level_cost(scene, "elastic")
    assert elastic.preparation == scene_cost.PREPARATION_S["native build"]["elastic"] and "not built" in elastic.note


def test_the_cost_model_sees_the_compile_the_run_left_behind(scene):
    """The structure key the estimate checks is the runner's own: after one rigid run nothing is owed."""
    rigid = next(lv for lv in levels_for(scene.model) if lv.name == "rigid")
    rigid.run(scene)
    after = scene_cost.level_cost(scene, "rigid")
    assert after.method == "taylor" and after.preparation == 0.0 and "compiled in this process" in after.note


def test_levels_the_rule_does_not_run_cost_nothing_and_unknown_levels_are_refused(scene):
    assert scene_cost.level_cost(scene, "linearized").total == 0.0
    with pytest.raises(ValueError, match="unknown level 'quantum'"):
        scene_cost.level_cost(scene, "quantum")

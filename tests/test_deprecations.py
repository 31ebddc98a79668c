"""Names removed by the restructuring keep working for one release, with a DeprecationWarning naming the new place."""

from __future__ import annotations

import importlib

import numpy as np
import pytest

import pendulab as pl


def test_sampled_lqr_balance_is_balance_controller():
    sampled = importlib.import_module("pendulab.control.sampled")
    from pendulab.control.feedback import balance_controller

    with pytest.warns(DeprecationWarning, match="feedback.balance_controller"):
        old = sampled.lqr_balance
    assert old is balance_controller
    with pytest.warns(DeprecationWarning, match="controllers.make_controller"):
        assert callable(sampled.make_controller)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        _ = sampled.nope


def test_tracking_sampled_names_moved():
    old = importlib.import_module("pendulab.control.tracking_sampled")
    from pendulab.control import TVLQRTracker, tvlqr_tracker

    with pytest.warns(DeprecationWarning, match="control.tracking.tvlqr_tracker"):
        assert old.tvlqr_tracker is tvlqr_tracker
    with pytest.warns(DeprecationWarning, match="control.tracking.TVLQRTracker"):
        assert old.TVLQRTracker is TVLQRTracker
    with pytest.warns(DeprecationWarning, match="TVLQRTracker"):
        assert pl.control.TrackingController is TVLQRTracker


def test_fmu_cosim_moved_to_cosim_package():
    import pendulab.cosim
    import pendulab.fmu

    with pytest.warns(DeprecationWarning, match="pendulab.cosim.cosim_many"):
        assert pendulab.fmu.cosim_many is pendulab.cosim.cosim_many


def test_method_rk_is_rk4():
    model = pl.rigid()
    with pytest.warns(DeprecationWarning, match="'rk' is deprecated; use 'rk4'"):
        old = pl.simulate(model, [1.0, 0.5, 0.0, 0.0], 0.5, dt=0.05, method="rk", max_step=0.01)
    new = pl.simulate(model, [1.0, 0.5, 0.0, 0.0], 0.5, dt=0.05, method="rk4", max_step=0.01)
    assert old.method == "rk4"
    np.testing.assert_array_equal(old.x, new.x)


def test_control_tasks_restored_as_alias_module():
    tasks = importlib.import_module("pendulab.control.tasks")
    from pendulab.control.swingup.tasks import load_task

    with pytest.warns(DeprecationWarning, match="pendulab.control.swingup.tasks.load_task"):
        assert tasks.load_task is load_task
    with pytest.raises(AttributeError):
        _ = tasks.nope


def test_evaluation_moved_to_evaluate_package():
    import pendulab.control
    import pendulab.evaluate

    with pytest.warns(DeprecationWarning, match="pendulab.evaluate.score"):
        assert pendulab.control.score is pendulab.evaluate.score
    scorecard = importlib.import_module("pendulab.control.scorecard")
    with pytest.warns(DeprecationWarning, match="pendulab.evaluate.scorecard.rerun"):
        assert scorecard.rerun is pendulab.evaluate.rerun
    perturb = importlib.import_module("pendulab.control.perturb")
    with pytest.warns(DeprecationWarning, match="run_perturbed_episode"):
        assert perturb.run_episode is pendulab.evaluate.run_perturbed_episode
    criteria = importlib.import_module("pendulab.control.realai.criteria")
    from pendulab.evaluate.realai.criteria import score_v2

    with pytest.warns(DeprecationWarning, match="score_v2"):
        assert criteria.score is score_v2
    with pytest.warns(DeprecationWarning, match="pendulab.evaluate.realai.realai_score"):
        assert pendulab.control.realai.realai_score is pendulab.evaluate.realai_score


def test_one_name_per_concept_old_names_warn():
    """The six names that meant two things each: the renamed side keeps its old name for one release."""
    from pendulab.bench.fmu_methods import fmu_bench_runner
    from pendulab.control.realai.design import LeaderboardPlan
    from pendulab.control.swingup.errors import PlanTrajectory
    from pendulab.control.swingup.guess import rigid_counterpart_problem
    from pendulab.control.swingup.solve import solve_transcription
    from pendulab.integrate.compiled import compiled_unavailable_reason
    from pendulab.integrate.taylor.availability import taylor_unavailable_reason
    from pendulab.native.loader import native_library

    cases = [
        ("pendulab.control.realai.design", "Plan", LeaderboardPlan),
        ("pendulab.control.swingup.errors", "Plan", PlanTrajectory),
        ("pendulab.control.swingup.guess", "rigid_counterpart", rigid_counterpart_problem),
        ("pendulab.control.swingup.solve", "swing_up", solve_transcription),
        ("pendulab.bench.fmu_methods", "fmu_runner", fmu_bench_runner),
        ("pendulab.integrate.compiled", "unavailable_reason", compiled_unavailable_reason),
        ("pendulab.integrate.taylor.availability", "unavailable_reason", taylor_unavailable_reason),
        ("pendulab.native.library", "native_library", native_library),  # the loader got its own module
    ]
    for module, old, new in cases:
        with pytest.warns(DeprecationWarning, match=new.__name__):
            assert getattr(importlib.import_module(module), old) is new


def test_no_package_reaches_up_with_importlib():
    """Old names are served by pendulab._aliases (above every layer): no package loads another one dynamically."""
    import re
    from pathlib import Path

    pkg = Path(pl.__file__).parent
    reaching = []
    for path in pkg.rglob("*.py"):
        rel = path.relative_to(pkg)
        for target in re.findall(r"import_module\(f?\"pendulab\.(\w+)", path.read_text()):
            if target != rel.parts[0]:
                reaching.append(rel.as_posix())
    # The CLI's command dispatch and the alias table are the only dynamic imports across packages.
    assert sorted(set(reaching)) == ["cli.py"]


def test_measured_model_choice_has_its_own_name():
    """One name, one concept: scene.choose_model is the a priori rule; the measured study is measure_model_choice."""
    hierarchy = importlib.import_module("pendulab.bench.hierarchy")
    from pendulab.scene import choose_model

    with pytest.warns(DeprecationWarning, match="hierarchy.measure_model_choice"):
        old = hierarchy.choose_model
    assert old is hierarchy.measure_model_choice and old is not choose_model

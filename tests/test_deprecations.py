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

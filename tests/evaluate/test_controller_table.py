"""One table of controller names serves the three RealAIGym protocols (leaderboard v2, robustness v2, v3)."""

from __future__ import annotations

import pytest

from pendulab.evaluate.realai import CONTROLLER_NAMES, CONTROLLERS, realai_score, robustness_v2, v3_score


@pytest.mark.parametrize("protocol", [realai_score, robustness_v2, v3_score])
def test_every_protocol_refuses_an_unknown_name_listing_the_one_table(protocol):
    with pytest.raises(ValueError) as exc:
        protocol("pendubot", "no_such_controller")
    for name in ("best", "robust", "global", "replan"):  # estimator-fed and global controllers are in the same table
        assert repr(name) in str(exc.value)


def test_names_are_the_table():
    assert CONTROLLER_NAMES == tuple(CONTROLLERS)
    names = {
        "best", "tvlqr", "lqr", "swingup", "nmpc", "robust", "global", "replan", "replan_delayed", "library", "rti", "mpc",
        "mpc_library",
    }  # fmt: skip
    assert names == set(CONTROLLERS)

"""A non-finite or wrongly sized controller command is an error in every runner, never a torque a plant integrates.

Issue 31 ("numerics that cannot lie"): each runner used to check commands its own way (or not at all:
the RealAIGym runners clipped a NaN and integrated it). They all pass :func:`full_input` now; this test
runs one bad controller through each of them.
"""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl
from pendulab.control.feedback import ControllerOutputError, as_feedback, full_input


class Bad:
    """A controller of the SampledController shape that returns ``value`` from its third call on."""

    def __init__(self, value, sample_time=0.002, input_names=("tau1",)):
        self.value, self.sample_time, self.input_names, self.calls = value, sample_time, input_names, 0

    def reset(self):
        self.calls = 0

    def __call__(self, t, x):
        self.calls += 1
        return np.zeros(len(self.input_names)) if self.calls < 3 else self.value


BAD_VALUES = [np.array([np.nan]), np.array([np.inf]), np.array([1.0, 2.0]), "torque"]


@pytest.mark.parametrize("value", BAD_VALUES, ids=["nan", "inf", "wrong-size", "not-numbers"])
def test_the_gate_names_the_controller_the_time_and_the_value(value):
    with pytest.raises(ControllerOutputError, match=r"Bad returned .* at t = 0.25 s"):
        full_input(Bad(value), value, 0.25)
    assert np.array_equal(full_input(Bad(None), [1.5], 0.0), [1.5, 0.0])  # a good command is scattered


def _simulate(ctrl):
    model = pl.rigid()
    pl.simulate(model, model.rest_state(), 0.02, dt=ctrl.sample_time, u=as_feedback(ctrl, model))


def _realai_v2(ctrl):
    from pendulab.evaluate.realai.simulate import run_leaderboard

    run_leaderboard("pendubot", ctrl)


def _realai_v3(ctrl):
    from pendulab.evaluate.realai.v3 import run_v3

    run_v3("pendubot", ctrl, seed=0)


def _robustness_episode(ctrl):
    from pendulab.evaluate.realai.robustness import robustness_v2

    robustness_v2("pendubot", ctrl, categories=("delay",), levels=(0,))


@pytest.mark.parametrize("runner", [_simulate, _realai_v2, _realai_v3, _robustness_episode])
@pytest.mark.parametrize("value", BAD_VALUES[:2], ids=["nan", "inf"])
def test_every_runner_refuses_a_non_finite_command(runner, value):
    with pytest.raises(ValueError, match="finite torque"):
        runner(Bad(value))


def test_robustness_levels_must_be_a_sequence():
    from pendulab.evaluate.realai.robustness import robustness_v2

    with pytest.raises(TypeError, match="levels must be a sequence of grid indices"):
        robustness_v2("pendubot", Bad(None), categories=("delay",), levels=1)

"""Every kind of entry enters the v3 protocols one way: its torques clipped to the rules, its calls timed.

Found (``benchmarks/results/upstream_entries.md``, finding 1): ``run_v3`` and ``run_v3_hardware`` used any object with
``get_control_output_`` -- every upstream ``AbstractController`` has it -- as it was: no clip to the task's limits
(the passive joint got up to the plant's 6 N.m under v3's rule of 0; AR-EAPO's hardware entry scored 0.759 so
instead of 0.301) and no call times. The class: each kind of entry (upstream raw entry, upstream public interface,
pendulab controller, a protocol wrapper built with wider limits) in both runners.
"""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.control.feedback import ControllerOutputError
from pendulab.evaluate.realai.v3 import ProtocolController, RawEntry, protocol_entry, run_v3
from pendulab.evaluate.realai.v3_hardware import run_v3_hardware
from pendulab.identify.sensing import c1_sensing

FULL = (6.0, 6.0)  # every kind below asks for 6 N.m on both joints


class Raw:
    """Upstream's wrapper calls this: relative state in, (tau1, tau2) out."""

    def get_control_output_(self, x, t):
        return np.array(FULL)


class Public:
    """Only upstream's public interface (``init``, ``get_control_output``, ``reset``)."""

    def init(self):
        pass

    def reset(self):
        pass

    def get_control_output(self, x, t=None):
        return np.array(FULL)


class Sampled:
    """A pendulab controller driving both inputs."""

    sample_time = 0.002
    input_names = ("tau1", "tau2")

    def reset(self):
        pass

    def __call__(self, t, x):
        return np.array(FULL)


def _wide_wrapper(task: str) -> ProtocolController:
    proto = ProtocolController(task, Sampled())
    proto.limit[:] = 6.0  # a wrapper built elsewhere with wider limits than the rules
    return proto


KINDS = {"raw": lambda task: Raw(), "public": lambda task: Public(), "sampled": lambda task: Sampled(), "wide": _wide_wrapper}


def _entry_samples(res) -> np.ndarray:
    """Samples the entry controlled: before the first reset (every episode starts with the entry)."""
    return res.t < res.reset_times[0] - 0.01


@pytest.mark.parametrize("kind", list(KINDS))
@pytest.mark.parametrize("task, driven", [("pendubot", 0), ("acrobot", 1)])
def test_v3_clips_every_kind_of_entry_to_the_rules_and_times_it(kind, task, driven):
    res = run_v3(task, KINDS[kind](task), kind, seed=0, n_steps=250)
    u = res.u[_entry_samples(res)]
    assert len(u) == 250 and np.all(u[:, 1 - driven] == 0.0)  # the passive joint: the rule's 0 N.m, exactly
    assert np.all(np.abs(u[:, driven]) == 6.0)  # the driven joint keeps its 6 N.m
    assert len(res.call_times) > 0 and res.to_dict()["simulation"]["entry_torque_limit"][1 - driven] == 0.0


@pytest.mark.parametrize("kind", list(KINDS))
def test_v3_hardware_clips_every_kind_of_entry_to_the_allowance_and_times_it(kind):
    sensing = c1_sensing()
    res = run_v3_hardware("pendubot", KINDS[kind]("pendubot"), kind, seed=0, passive_allowance=0.5, duration=0.5)
    u = res.u[_entry_samples(res)]
    # Applied = the command on the motor's torque grid plus the reading's noise: 6 sigma and one grid step of room.
    room = 6.0 * sensing.torque_noise[1] + sensing.torque_step
    passive = u[:, 1]
    if kind == "public":  # from_realai keeps the driven joint only: nothing commanded on the passive joint
        assert np.all(np.abs(passive) <= room)
    else:
        assert np.all(np.abs(passive - 0.5) <= room)
    assert len(res.call_times) > 0


def test_upstream_simulator_mode_passes_the_plant_limit():
    """``passive_limit=6`` reproduces upstream's simulator, which clipped entries only to the plant's 6 N.m."""
    res = run_v3("pendubot", Raw(), "raw", seed=0, n_steps=100, passive_limit=6.0)
    assert np.all(res.u[_entry_samples(res)] == 6.0)
    assert res.to_dict()["simulation"]["entry_torque_limit"] == [6.0, 6.0]
    with pytest.raises(ValueError, match="passive_limit"):
        run_v3("pendubot", Raw(), seed=0, n_steps=10, passive_limit=6.5)


@pytest.mark.parametrize("bad", [[1.0], [np.nan, 0.0], "ab", None, [[1.0, 2.0]] * 2])
@pytest.mark.parametrize("kind", ["raw", "sampled"])
def test_an_entry_returning_anything_but_its_finite_torques_is_named(bad, kind):
    class BadRaw:
        def get_control_output_(self, x, t):
            return bad

    class BadSampled(Sampled):
        def __call__(self, t, x):
            return bad

    entry = BadRaw() if kind == "raw" else BadSampled()
    with pytest.raises(ControllerOutputError, match=rf"{type(entry).__name__} returned .* at t = 0 s[:;]"):
        run_v3("pendubot", entry, seed=0, n_steps=10)


def test_protocol_entry_keeps_wrappers_and_wraps_the_rest():
    wrapper = ProtocolController("pendubot", Sampled())
    assert protocol_entry("pendubot", wrapper) is wrapper
    assert isinstance(protocol_entry("pendubot", Raw()), RawEntry)
    assert isinstance(protocol_entry("pendubot", Sampled()), ProtocolController)
    with pytest.raises(TypeError, match="SampledController"):
        protocol_entry("pendubot", object())


def test_a_diverged_state_is_the_runs_failure_not_the_entrys():
    """The class of tests/integrate/test_feedback_divergence.py in the protocol loop: the entry never sees NaN."""
    from pendulab.evaluate.realai.v3 import _entry_limits, _entry_torque

    seen: list[np.ndarray] = []

    class Echo:
        def get_control_output_(self, x, t):
            seen.append(np.array(x))
            return np.array([x[0], 0.0])

    proto = protocol_entry("pendubot", Echo())
    limit = _entry_limits("pendubot", 0.0)
    assert np.array_equal(_entry_torque(proto, np.array([0.5, 0.0, 0.0, 0.0]), 0.1, limit), [0.5, 0.0])
    with pytest.raises(ValueError, match=r"non-finite state at t = 0.2 s \(before the entry was called\)"):
        _entry_torque(proto, np.array([np.nan, 0.0, 0.0, 0.0]), 0.2, limit)
    assert len(seen) == 1

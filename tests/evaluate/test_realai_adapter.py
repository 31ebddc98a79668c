"""RealAIGym controllers (upstream's ``AbstractController`` shape) in every pendulab protocol, via ``from_realai``.

CI has no upstream package: the stand-ins below have upstream's public interface (``init()``,
``get_control_output(x, t)`` in joint coordinates returning ``(u1, u2)``, ``reset()``) and log every call.
"""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.control.feedback import ControllerOutputError, full_input
from pendulab.control.realai import TORQUE_LIMIT, from_realai, to_joint
from pendulab.control.swingup.tasks import resolve_task
from pendulab.evaluate.realai import realai_score
from pendulab.evaluate.realai.controllers import resolve_controller
from pendulab.evaluate.realai.robustness import robustness_v2
from pendulab.evaluate.realai.v3 import run_v3
from pendulab.evaluate.scorecard import score

#: The stand-in's law in joint coordinates: u_driven = GAIN . (q - GOAL); the passive entry is PASSIVE (dropped).
GAIN = np.array([-3.0, 2.0, -0.5, 0.25])
GOAL = np.array([np.pi, 0.0, 0.0, 0.0])
PASSIVE = 123.0


class JointLaw:
    """A stand-in of upstream's shape: a linear law on the joint-coordinate state, every call logged."""

    def __init__(self, joint: int = 0) -> None:
        self.joint = joint  # 0: shoulder (pendubot), 1: elbow (acrobot)
        self.log: list[str] = []
        self.seen: list[tuple[np.ndarray, float]] = []
        self.out: list[float] = []

    def init(self) -> None:
        self.log.append("init")

    def reset(self) -> None:
        self.log.append("reset")

    def get_control_output(self, x, t=None):
        assert isinstance(t, float) and np.shape(x) == (4,)
        self.log.append("call")
        self.seen.append((np.array(x, dtype=float), t))
        u = float(GAIN @ (np.asarray(x) - GOAL))
        self.out.append(u)
        v = np.full(2, PASSIVE)
        v[self.joint] = u
        return v


class NoInit:
    def reset(self) -> None:
        pass

    def get_control_output(self, x, t=None):
        return np.zeros(2)


class NaNOut(JointLaw):
    def get_control_output(self, x, t=None):
        return np.array([np.nan, 0.0])


class WrapsPendulab:
    """Upstream-shaped wrapper of a pendulab controller: joint coordinates -> absolute angles, (u1, u2) out."""

    def __init__(self, ctrl, joint: int = 0) -> None:
        self.ctrl, self.joint = ctrl, joint

    def init(self) -> None:
        pass

    def reset(self) -> None:
        self.ctrl.reset()

    def get_control_output(self, x, t=None):
        q1, q2, dq1, dq2 = x
        u = np.zeros(2)
        u[self.joint] = np.asarray(self.ctrl(t, np.array([q1, q1 + q2, dq1, dq1 + dq2])))[0]
        return u


def _runs(log: list[str]) -> list[list[str]]:
    """The log split at each init: every run must be reset, then init, then calls."""
    return [chunk.split() for chunk in " ".join(log).split("init")[1:]]


@pytest.mark.parametrize(("task", "joint"), [("pendubot", 0), ("acrobot", 1)])
def test_state_converted_and_torque_on_the_driven_input(task, joint):
    law = JointLaw(joint)
    ctrl = from_realai(law, task=task)
    assert ctrl.input_names == (("tau1",) if joint == 0 else ("tau2",)) and ctrl.sample_time == 0.002
    x = np.array([3.0, 3.5, 0.2, -0.4])  # absolute: link 2 bent 0.5 rad from link 1, relative rate -0.6 rad/s
    ctrl.reset()
    full = full_input(ctrl, ctrl(1.25, x), 1.25)
    q, t = law.seen[-1]
    np.testing.assert_allclose(q, [3.0, 0.5, 0.2, -0.6], rtol=0, atol=1e-15)
    assert t == 1.25
    want = -3.0 * (3.0 - np.pi) + 2.0 * 0.5 - 0.5 * 0.2 + 0.25 * -0.6
    assert full[joint] == pytest.approx(want, abs=1e-14) and full[1 - joint] == 0.0  # the passive 123 is dropped
    assert law.log == ["reset", "init", "call"]
    ctrl(1.252, x)
    assert law.log.count("init") == 1  # once per run
    # the elastic state (theta1, theta2, r1, r2, omega1, omega2, v1, v2): springs dropped
    np.testing.assert_allclose(to_joint([3.0, 3.5, 1.0, 1.0, 0.2, -0.4, 0.0, 0.0]), q, atol=1e-15)
    clipped = from_realai(JointLaw(joint), task=task, torque_limit=0.1)
    assert abs(clipped(0.0, np.array([0.0, 2.0, 0.0, 0.0]))[0]) == 0.1


def test_bad_controllers_are_clear_errors():
    with pytest.raises(TypeError, match="NoInit is not a RealAIGym controller: it lacks init"):
        from_realai(NoInit())
    with pytest.raises(TypeError, match="lacks init"):
        realai_score("pendubot", NoInit())
    with pytest.raises(ValueError, match="unknown actuation"):
        from_realai(JointLaw(), task="cartpole")
    with pytest.raises(ControllerOutputError, match=r"NaNOut.get_control_output returned \[nan, 0.0\] at t = 0 s"):
        realai_score("pendubot", NaNOut())
    with pytest.raises(ControllerOutputError, match="expected 2 finite torques"):
        from_realai(type("Short", (JointLaw,), {"get_control_output": lambda self, x, t=None: [1.0]})())(0.0, np.zeros(4))


def test_leaderboard_v2_applies_the_driven_output():
    law = JointLaw(1)
    res = realai_score("acrobot", law)  # the raw upstream object: resolve_controller adapts it at 2 ms
    assert res.controller == "JointLaw"
    assert _runs(law.log) == [["call"] * 5000] and law.log[0] == "reset"  # one run: reset, init, 5000 calls
    u = np.clip(law.out, -TORQUE_LIMIT, TORQUE_LIMIT)
    np.testing.assert_array_equal(res.u[:, 1], u)  # the command applied is the stand-in's elbow output
    assert np.all(res.u[:, 0] == 0.0)
    for (q, t), x, tk in zip(law.seen[::500], res.x[::500], res.t[::500], strict=True):
        np.testing.assert_allclose(q, to_joint(x), rtol=0, atol=1e-12)
        assert t == pytest.approx(tk, abs=1e-12)


def test_v2_score_of_a_wrapped_pendulab_controller_equals_the_native_one():
    """Independent path: pendulab's TVLQR through upstream's interface (joint coordinates both ways) scores the same."""
    native = realai_score("pendubot", "best")
    _, ctrl = resolve_controller("pendubot", "best")
    wrapped = realai_score("pendubot", from_realai(WrapsPendulab(ctrl), task="pendubot"))
    assert wrapped.success == native.success
    # the round trip theta2 -> q2 -> theta2 costs ~1 ulp per sample; the stabilized run keeps it at round-off
    assert wrapped.score == pytest.approx(native.score, rel=1e-9)
    np.testing.assert_allclose(wrapped.x, native.x, rtol=0, atol=1e-8)


def test_robustness_v2_resets_and_inits_every_run():
    law = JointLaw(0)
    res = robustness_v2(
        "pendubot", law, workers=1, levels=[0], categories=["delay", "u_noise"], repetitions=1, u_noise_repetitions=1
    )
    n = len(res.records)
    assert n >= 2 and res.controller == "JointLaw"
    runs = _runs(law.log)
    assert len(runs) == n  # init once per run
    assert all(r[-1] == "reset" for r in runs[:-1])  # and a reset before the next run's init
    assert all(set(r[:-1]) == {"call"} for r in runs[:-1]) and len(runs[0]) > 1


def test_v3_runs_the_adapted_entry():
    law = JointLaw(0)
    res = run_v3("pendubot", law, "JointLaw", n_steps=500)  # 1 s: before the first reset of seed 0
    assert law.log[:2] == ["reset", "init"] and law.log.count("init") == 1 and law.log.count("call") == 500
    np.testing.assert_array_equal(res.u[:, 0], np.clip(law.out, -TORQUE_LIMIT, TORQUE_LIMIT))
    assert np.all(res.u[:, 1] == 0.0)
    adapted = run_v3("pendubot", from_realai(JointLaw(0)), n_steps=500)  # the adapted object, as v3_score resolves it
    np.testing.assert_array_equal(adapted.u, res.u)


def test_scorecard_runs_a_realai_controller_from_the_task_start():
    law = JointLaw(0)
    card = score(law, "pendubot", runs=2, categories=["torque_noise"], levels={"torque_noise": [0.0, 1.0]}, workers=1)
    assert card.controller == "JointLaw"
    n = len(card.records)
    runs = _runs(law.log)
    assert n >= 2 and len(runs) == n + 1  # the scorecard's one-sample warm-up episode, then every run
    assert runs[0] == ["call", "reset"] and all(r[-1] == "reset" for r in runs[:-1])
    start = to_joint(resolve_task("pendubot").problem.start)
    for q, t in law.seen[:2]:  # every run starts at the task's start state
        np.testing.assert_array_equal(q, start)
        assert t == 0.0


@pytest.mark.needs_cc  # export compiles the FMU
def test_cosim_applies_the_driven_output(tmp_path):
    pytest.importorskip("fmpy")
    import pendulab as pl
    from pendulab.cosim import cosim
    from pendulab.fmu import export

    fmu = export(pl.rigid(), tmp_path / "rigid.fmu", 2, timestamp=False)
    law = JointLaw(0)
    ctrl = from_realai(law, task="pendubot", sample_time=0.01)
    x0 = np.array([np.pi + 0.05, np.pi, 0.0, 0.0])
    res = cosim(fmu, ctrl, 0.01, 0.5, x0=x0)
    assert law.log.count("init") == 1
    k = len(law.out)
    np.testing.assert_array_equal(res.u[:k, 0], law.out)
    assert np.all(res.u[:, 1] == 0.0)
    np.testing.assert_allclose(law.seen[0][0], to_joint(x0), atol=1e-12)

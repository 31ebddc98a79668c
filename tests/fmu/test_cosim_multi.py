"""Several FMUs in one master, and the step-retry protocol (save state, reject, restore, halve)."""

from __future__ import annotations

import numpy as np
import pytest
from fmpy.fmi2 import FMU2Slave

import pendulab as pl
from pendulab.control.feedback import balance_controller, energy_swingup, upright_state
from pendulab.cosim import StepRejectedError, cosim, cosim_many


def _starts(k: float):
    rigid, elastic = pl.rigid(), pl.elastic(k1=k, k2=k)
    xr, xe = upright_state(rigid), upright_state(elastic)
    xr[0] += 0.1
    xe[0] += 0.1
    return rigid, xr, xe


def test_rigid_and_elastic_side_by_side(cosim_fmu):
    """Same torques into both plants: the elastic response approaches the rigid one as 1/k."""
    fmus = [cosim_fmu("rigid", 2), cosim_fmu("elastic", 2)]
    dev = []
    for k in (5e3, 5e4):
        rigid, xr, xe = _starts(k)
        ctrl = balance_controller(rigid, 0.01)
        trs = cosim_many(fmus, ctrl, 0.01, 1.0, x0=[xr, xe], params=[None, {"k1": k, "k2": k}], solver="rodas4", tolerance=1e-9)
        assert np.array_equal(trs[0].u, trs[1].u)  # one input sequence for both plants
        assert trs[1].state_names[2:4] == ("r1", "r2")
        dev.append(np.max(np.abs(trs[0].x[:, :2] - trs[1].x[:, :2])))
    single = cosim(fmus[0], ctrl, 0.01, 1.0, x0=xr, solver="rodas4", tolerance=1e-9)
    # The rigid plant in the shared master is an independent instance: bit-identical to a run on its own.
    assert np.array_equal(single.x, trs[0].x)
    # Spring compliance ~ g m / k: ten times stiffer, ten times closer (measured ratio 10.1); 8 leaves room for
    # the quadratic terms. Both deviations are real (not zero), the plants differ.
    assert dev[1] > 0 and dev[0] / dev[1] > 8.0


@pytest.mark.parametrize("version", [2, 3])
def test_step_retry_restores_state(cosim_fmu, version):
    """A master-side bound rejects big steps; restored and halved, the run equals the plain run."""
    model = pl.rigid()
    fmu = cosim_fmu("rigid", version)
    ctrl = energy_swingup(model, 0.05)
    x0 = model.state(theta1=0.1)
    plain = cosim(fmu, ctrl, 0.05, 4.0, x0=x0, tolerance=1e-10)
    # Plain run: the angles move up to 0.31 rad in one 50 ms step; the bound 0.25 rad rejects those steps.
    assert np.abs(np.diff(plain.x[:, :2], axis=0)).max() > 0.25

    def small_angle_steps(t, x_before, x_after):
        return bool(np.abs(x_after[:2] - x_before[:2]).max() < 0.25)

    retried = cosim(fmu, ctrl, 0.05, 4.0, x0=x0, tolerance=1e-10, check=small_angle_steps, max_halvings=4)
    assert retried.stats["n_rejected"] > 0
    assert retried.stats["n_do_step"] > plain.stats["n_do_step"]
    # Restored state: had the rejected step been kept, the plant would be a whole step (up to 0.3 rad) ahead.
    # Splitting a step with held torque only changes the embedded solver's path: tolerance-level difference.
    assert np.max(np.abs(retried.x - plain.x)) < 1e-7


def test_step_retry_gives_up_clearly(cosim_fmu, monkeypatch):
    freed = []
    real = FMU2Slave.freeInstance
    monkeypatch.setattr(FMU2Slave, "freeInstance", lambda self: (freed.append(1), real(self))[1])
    model = pl.rigid()
    with pytest.raises(StepRejectedError, match=r"rejected at the smallest step h = 0.0025 s"):
        cosim(
            cosim_fmu("rigid", 2),
            balance_controller(model, 0.01),
            0.01,
            0.1,
            x0=model.state(theta1=0.1),
            check=lambda t, a, b: False,
            max_halvings=2,
        )
    assert freed == [1]


def test_cosim_many_retries_steps_like_cosim(cosim_fmu):
    """cosim is cosim_many of one plant: the same retry protocol runs for every plant of a shared master."""
    model = pl.rigid()
    fmu = cosim_fmu("rigid", 2)
    ctrl = energy_swingup(model, 0.05)
    x0 = model.state(theta1=0.1)

    def small_angle_steps(t, x_before, x_after):
        return bool(np.abs(x_after[:2] - x_before[:2]).max() < 0.25)

    kw = {"tolerance": 1e-10, "check": small_angle_steps, "max_halvings": 4}
    single = cosim(fmu, ctrl, 0.05, 4.0, x0=x0, **kw)
    pair = cosim_many([fmu, fmu], ctrl, 0.05, 4.0, x0=[x0, x0], **kw)
    assert single.stats["n_rejected"] > 0
    for tr in pair:
        # Same plant, same inputs, same retries: bit-identical to the one-plant master.
        assert tr.stats["n_rejected"] == single.stats["n_rejected"]
        assert np.array_equal(tr.x, single.x)
    with pytest.raises(ValueError, match=r"max_halvings = -1: out of range; expected an integer in \[0, 60\]"):
        cosim_many([fmu], ctrl, 0.05, 1.0, max_halvings=-1)

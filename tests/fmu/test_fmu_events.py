"""Events where the physics has them: a spring length approaching zero (elastic model).

Event indicators z_i = r_i - 0.1 L_i (ME: the importer locates the crossing, the FMU asks to terminate);
CS: the step ends at the last of 64 sub-steps before the limit with Discard / terminateSimulation, never a
failed step. The rigid model has no event indicators.
"""

from __future__ import annotations

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException

import pendulab as pl
from pendulab.fmu import export
from pendulab.fmu.codegen import SPRING_LIMIT

SOFT = {"k1": 50.0, "k2": 50.0}
H = 0.01  # communication step [s]


@pytest.fixture(scope="module")
def collapse(tmp_path_factory):
    """FMUs (FMI 2, 3) of a soft elastic pendulum started with spring 1 compressing fast, and the native crossing time."""
    model = pl.elastic(**SOFT)
    x0 = model.state(theta1=0.0, v1=-10.0)
    root = tmp_path_factory.mktemp("events")
    fmus = {v: export(model, root / f"soft{v}.fmu", v, timestamp=False, x0=x0) for v in (2, 3)}
    limit = SPRING_LIMIT * model.params.L1
    ref = pl.simulate(model, x0, 0.15, dt=1e-4, rtol=1e-12, atol=1e-12)  # r1 reaches 0.1 m at ~0.17 s
    tail = pl.simulate(model, ref.x[-1], 0.03, dt=1e-6, rtol=1e-12, atol=1e-12)
    r1 = tail["r1"]
    k = int(np.argmax(r1 <= limit))
    assert k > 0
    t_star = 0.15 + np.interp(limit, [r1[k], r1[k - 1]], [tail.t[k], tail.t[k - 1]])
    return fmus, t_star


@pytest.mark.parametrize("version", [2, 3])
def test_model_exchange_stops_at_the_spring_limit(collapse, version, capsys):
    fmus, t_star = collapse
    res = simulate_fmu(fmus[version], fmi_type="ModelExchange", stop_time=1.0, output_interval=H, relative_tolerance=1e-10,
                       output=["r1", "spring_margin1"])  # fmt: skip
    assert "spring 1 reached" in capsys.readouterr().out  # the FMU says why it asks to terminate
    assert res["time"][-1] < 0.2  # stopped long before the stop time, instead of failing
    if version == 3:  # fmpy records the event point for FMI 3: the importer's root finder located it
        assert abs(res["time"][-1] - t_star) < 1e-6  # CVode root finding at rtol 1e-10
        assert abs(res["spring_margin1"][-1]) < 1e-9


def test_co_simulation_fmi2_ends_the_step_with_discard_and_terminated(collapse, capsys):
    fmus, t_star = collapse
    res = simulate_fmu(fmus[2], fmi_type="CoSimulation", stop_time=1.0, output_interval=H, output=["r1", "spring_margin1"])
    assert "the FMU stops at t =" in capsys.readouterr().out
    t_end = res["time"][-1]
    # located to one of 64 sub-steps of the communication step, at the last one before the limit
    assert t_star - H / 64 - 1e-9 <= t_end <= t_star
    assert 0.0 < res["spring_margin1"][-1] < 0.02  # r1 moves ~10 m/s x H / 64


def test_co_simulation_fmi3_returns_early_or_discards(collapse, capsys):
    fmus, t_star = collapse
    res = simulate_fmu(fmus[3], fmi_type="CoSimulation", stop_time=1.0, output_interval=H, early_return_allowed=True,
                       output=["r1", "spring_margin1"])  # fmt: skip
    t_end = res["time"][-1]
    assert t_star - H / 64 - 1e-9 <= t_end <= t_star  # early return at the last sub-step before the limit
    assert res["spring_margin1"][-1] > 0.0
    # without early return the step is discarded (terminateSimulation), and the FMU stays stopped
    with pytest.raises(FMICallException, match="discard"):
        simulate_fmu(fmus[3], fmi_type="CoSimulation", stop_time=1.0, output_interval=H)
    assert "spring 1 reached" in capsys.readouterr().out


@pytest.mark.parametrize("version", [2, 3])
def test_after_the_stop_steps_are_refused_until_an_earlier_state_is_restored(collapse, version, tmp_path):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave, fmi2Terminated
    from fmpy.fmi3 import FMU3Slave

    fmu = collapse[0][version]
    md = read_model_description(str(fmu))
    cls = FMU3Slave if version == 3 else FMU2Slave
    s = cls(guid=md.guid, unzipDirectory=extract(str(fmu), str(tmp_path)), modelIdentifier="pendulab_elastic", instanceName="e")
    s.instantiate()
    if version == 3:
        s.enterInitializationMode(tolerance=1e-10, startTime=0.0)
    else:
        s.setupExperiment(tolerance=1e-10, startTime=0.0)
        s.enterInitializationMode()
    s.exitInitializationMode()
    early = s.getFMUState() if version == 3 else s.getFMUstate()
    t = 0.0
    with pytest.raises(FMICallException, match="discard"):
        for _ in range(100):
            s.doStep(t, H)
            t += H
    if version == 2:
        assert s.getBooleanStatus(fmi2Terminated)
    with pytest.raises(FMICallException, match="discard"):  # stays stopped: no step into the singularity
        s.doStep(t, H)
    (s.setFMUState if version == 3 else s.setFMUstate)(early)  # restart from before the event
    s.doStep(0.0, H)
    s.terminate()
    s.freeInstance()


def test_indicators_are_the_spring_margins_and_the_rigid_model_has_none(fmu_builds):
    from fmu_driver import started

    for version in (2, 3):
        assert len(fmu_builds[("rigid", 3)].md.eventIndicators) == 0 and len(fmu_builds[("elastic", 3)].md.eventIndicators) == 2
        assert fmu_builds[("rigid", 2)].md.numberOfEventIndicators == 0
        assert fmu_builds[("elastic", 2)].md.numberOfEventIndicators == 2
        d = started(fmu_builds[("elastic", version)], {"theta1": 0.4, "r1": 0.8, "r2": 1.3}, interface="ME")
        margins = [0.8 - SPRING_LIMIT, 1.3 - SPRING_LIMIT]  # L1 = L2 = 1 m
        np.testing.assert_array_equal(d.get("spring_margin1", "spring_margin2"), margins)
        import ctypes

        z = (ctypes.c_double * 2)()
        d.fmu.getEventIndicators(z, 2)
        np.testing.assert_array_equal(list(z), margins)
        with pytest.raises(FMICallException):  # the wrong count is an error, not a buffer overrun
            d.fmu.getEventIndicators(z, 3)
        d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_flip_events_are_located_where_the_native_run_crosses_upright(tmp_path, version):
    model = pl.rigid()
    x0 = model.state(theta1=2.0, theta2=2.0, omega2=6.0)
    fmu = export(model, tmp_path / "flip.fmu", version, timestamp=False, x0=x0, flip_events=True)
    res = simulate_fmu(fmu, fmi_type="ModelExchange", stop_time=3.0, output_interval=H, relative_tolerance=1e-10,
                       output=["theta1", "theta2", "flip_margin1", "flip_margin2"])  # fmt: skip
    ref = pl.simulate(model, x0, 3.0, dt=1e-5, rtol=1e-12, atol=1e-12)
    z = np.pi - np.abs(ref["theta2"])
    k = np.nonzero(np.sign(z[1:]) != np.sign(z[:-1]))[0]
    native = ref.t[k] + z[k] / (z[k] - z[k + 1]) * (ref.t[k + 1] - ref.t[k])  # linear interpolation of the crossing
    assert len(native) == 3  # link 2 passes upright three times in 3 s (0.21 s, 2.04 s, 2.69 s)
    # fmpy records each state event (before and after it): the rows where the importer stopped at the flip
    at_event = np.unique(np.round(res["time"][np.abs(res["flip_margin2"]) < 1e-8], 12))
    # CVode's root finding at rtol 1e-10 against CVODES at 1e-12 (non-chaotic over 3 s: the error is ~1e-8)
    np.testing.assert_allclose(at_event, native, atol=1e-6)
    assert np.all(np.abs(res["flip_margin1"]) > 1e-3)  # link 1 does not flip: no spurious event
    # the flip changes nothing in the model: the trajectory equals the run without flip events
    plain = simulate_fmu(export(model, tmp_path / "plain.fmu", version, timestamp=False, x0=x0), fmi_type="ModelExchange",
                         stop_time=3.0, output_interval=H, relative_tolerance=1e-10, output=["theta2"])  # fmt: skip
    assert abs(res["theta2"][-1] - plain["theta2"][-1]) < 1e-6  # only the importer's step sequence differs


def test_flip_events_option_is_validated(tmp_path):
    with pytest.raises(TypeError, match="flip_events must be True or False"):
        export(pl.rigid(), tmp_path / "x.fmu", 3, flip_events="yes")


def test_cli_flip_events(tmp_path, capsys):
    from fmpy import read_model_description

    from pendulab.cli import main

    out = tmp_path / "f.fmu"
    assert main(["fmu", "export", "--model", "elastic", "--fmi-version", "2", "--flip-events", "--out", str(out)]) == 0
    md = read_model_description(str(out))
    assert md.numberOfEventIndicators == 4  # two spring margins, two flip margins
    assert {"flip_margin1", "flip_margin2"} <= {v.name for v in md.modelVariables}


def test_fmi3_co_simulation_event_mode_stops_at_each_flip(tmp_path):
    from fmpy import read_model_description

    model = pl.rigid()
    x0 = model.state(theta1=2.0, theta2=2.0, omega2=6.0)
    fmu = export(model, tmp_path / "flip3.fmu", 3, timestamp=False, x0=x0, flip_events=True)
    cs = read_model_description(str(fmu)).coSimulation
    assert cs.hasEventMode and cs.mightReturnEarlyFromDoStep
    res = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=3.0, output_interval=H, use_event_mode=True,
                       early_return_allowed=True, output=["theta2", "flip_margin2"])  # fmt: skip
    ref = pl.simulate(model, x0, 3.0, dt=1e-5, rtol=1e-12, atol=1e-12)
    z = np.pi - np.abs(ref["theta2"])
    k = np.nonzero(np.sign(z[1:]) != np.sign(z[:-1]))[0]
    native = ref.t[k] + z[k] / (z[k] - z[k + 1]) * (ref.t[k + 1] - ref.t[k])
    # early return at each flip, located by bisection to 1e-12 s; fmpy records the event point before and after
    at_event = np.unique(np.round(res["time"][np.abs(res["flip_margin2"]) < 1e-9], 9))
    # embedded dopri5 at the default 1e-8 tolerance against CVODES at 1e-12 (non-chaotic 3 s: error ~1e-8 rad)
    np.testing.assert_allclose(at_event, native, atol=1e-6)
    # the flips change nothing: the end state equals the run without event mode within the solver tolerance
    plain = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=3.0, output_interval=H, output=["theta2"])
    assert abs(res["theta2"][-1] - plain["theta2"][-1]) < 1e-7  # different internal step sequences, tolerance 1e-8
    # without early return the step runs to its end and only flags the event
    late = simulate_fmu(fmu, fmi_type="CoSimulation", stop_time=3.0, output_interval=H, use_event_mode=True, output=["theta2"])
    assert late["theta2"][-1] == plain["theta2"][-1]  # bit-identical: flagging an event changes no step
    assert len(np.unique(late["time"])) == len(plain)  # fmpy samples each event point twice, no extra points


@pytest.mark.parametrize("version_kind", ["rigid", "elastic"])
def test_event_mode_is_refused_without_flip_events(fmu_builds, version_kind, capsys):
    from fmpy.fmi3 import FMU3Slave

    built = fmu_builds[(version_kind, 3)]
    s = FMU3Slave(guid=built.md.guid, unzipDirectory=built.unzipdir, modelIdentifier=f"pendulab_{version_kind}", instanceName="x")
    with pytest.raises(Exception, match="instantiate|Failed"):
        s.instantiate(eventModeUsed=True)
    assert "eventModeUsed is not supported" in capsys.readouterr().out

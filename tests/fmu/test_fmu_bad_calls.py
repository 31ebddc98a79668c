"""The bad-call table: every misuse returns Error (or Discard) with a logged message, never a crash.

Driven through fmpy's low-level classes (FMU2Slave/FMU2Model, FMU3Slave/FMU3Model)
and, for NULL pointers, through the raw ctypes entry points they wrap.
"""

from __future__ import annotations

import ctypes
import math

import pytest
from fmpy.fmi1 import FMICallException
from fmu_driver import Driver, started

ERROR, DISCARD = 3, 2


def status_of(call) -> int:
    """Status of an fmpy call: 0 on success, else the FMI status carried by FMICallException."""
    try:
        res = call()
    except FMICallException as exc:
        return exc.status
    return res if isinstance(res, int) else 0


def raw(d: Driver, name: str, *args):
    """Call the raw FMI function ``fmi{2,3}<name>`` on the driver's instance."""
    prefix = "fmi3" if d.v3 else "fmi2"
    return lambda: getattr(d.fmu, prefix + name)(d.fmu.component, *args)


def dll_call(d: Driver, name: str, argtypes, *args):
    """Call an entry point straight from the shared library (fmpy only wraps those of the interface in use)."""
    f = getattr(d.fmu.dll, ("fmi3" if d.v3 else "fmi2") + name)
    f.argtypes = [ctypes.c_void_p, *argtypes]
    f.restype = ctypes.c_int
    return lambda: f(d.fmu.component, *args)


def _vr_array(vrs):
    return (ctypes.c_uint * len(vrs))(*vrs)


def _real_array(vals):
    return (ctypes.c_double * len(vals))(*vals)


def _do_step(d: Driver, t: float, h: float):
    return lambda: d.fmu.doStep(t, h)


# (case id, when: "instantiated" | "step", call factory, expected status, expected message fragment)
def _cases():
    return [
        ("dostep_before_init", "instantiated", lambda d: _do_step(d, 0.0, 0.01), ERROR, "not allowed in state Instantiated"),
        (
            "unknown_vr_get",
            "step",
            lambda d: lambda: d.fmu.getReal([12345]) if not d.v3 else d.fmu.getFloat64([12345]),
            ERROR,
            "unknown value reference 12345",
        ),
        (
            "unknown_vr_set",
            "step",
            lambda d: lambda: (d.fmu.setFloat64 if d.v3 else d.fmu.setReal)([777], [1.0]),
            ERROR,
            "unknown value reference 777",
        ),
        ("nan_input", "step", lambda d: lambda: d.set(tau1=math.nan), ERROR, "not finite"),
        ("inf_input", "step", lambda d: lambda: d.set(tau2=-math.inf), ERROR, "not finite"),
        ("inf_parameter", "instantiated", lambda d: lambda: d.set(m1=math.inf), ERROR, "not finite"),
        ("negative_mass", "instantiated", lambda d: lambda: d.set(m1=-1.0), ERROR, "m1 must be > 0"),
        ("negative_damping", "instantiated", lambda d: lambda: d.set(b1=-0.1), ERROR, "b1 must be >= 0"),
        ("fixed_param_after_init", "step", lambda d: lambda: d.set(m1=2.0), ERROR, "fixed after initialization"),
        ("state_after_init", "step", lambda d: lambda: d.set(theta1=0.1), ERROR, "not allowed in state StepMode"),
        ("output_is_not_settable", "step", lambda d: lambda: d.set(x1=0.1), ERROR, "cannot be set"),
        ("zero_step", "step", lambda d: _do_step(d, 0.0, 0.0), ERROR, "must be positive and finite"),
        ("negative_step", "step", lambda d: _do_step(d, 0.0, -0.01), ERROR, "must be positive and finite"),
        ("nan_step", "step", lambda d: _do_step(d, 0.0, math.nan), ERROR, "must be positive and finite"),
        ("inf_step", "step", lambda d: _do_step(d, 0.0, math.inf), ERROR, "must be positive and finite"),
        ("wrong_communication_point", "step", lambda d: _do_step(d, 0.5, 0.01), ERROR, "does not match the FMU time"),
        (
            "bad_solver",
            "instantiated",
            lambda d: lambda: (d.fmu.setInt32 if d.v3 else d.fmu.setInteger)([d.vr["solver"]], [7]),
            ERROR,
            "solver must be 0 (dopri5) or 1 (rodas4)",
        ),
        ("bad_tolerance", "instantiated", lambda d: lambda: d.set(solver_tolerance=0.0), ERROR, "solver_tolerance"),
        (
            "null_get_arrays",
            "step",
            lambda d: raw(d, "GetFloat64" if d.v3 else "GetReal", *((None, 1, None, 1) if d.v3 else (None, 1, None))),
            ERROR,
            "NULL value reference",
        ),
        ("null_fmu_state", "step", lambda d: raw(d, "GetFMUState" if d.v3 else "GetFMUstate", None), ERROR, "is NULL"),
        ("garbage_serialized_state", "step", lambda d: lambda: d.deserialize(b"\x00" * 17), ERROR, "expected"),
        (
            "me_call_on_cs_instance",
            "step",
            lambda d: dll_call(d, "SetTime", [ctypes.c_double], 0.5),
            ERROR,
            "only available for Model Exchange",
        ),
        (
            "directional_wrt_parameter",
            "step",
            lambda d: lambda: d.fmu.getDirectionalDerivative([d.vr["der(omega1)"]], [d.vr["g"]], [1.0]),
            ERROR,
            "not a state or input",
        ),
        ("terminate_twice", "terminated", lambda d: lambda: d.fmu.terminate(), ERROR, "not allowed in state Terminated"),
    ]


CASES = _cases()


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_call_returns_error_with_message(fmu_builds, version, case, capsys):
    _, when, factory, expected, fragment = case
    built = fmu_builds[("rigid", version)]
    d = Driver(built) if when == "instantiated" else started(built, {"theta1": 0.5})
    if when == "terminated":
        d.fmu.terminate()
    capsys.readouterr()
    assert status_of(factory(d)) == expected
    log = capsys.readouterr().out
    assert fragment in log, log
    if when == "step":
        # a rejected call leaves the instance usable (bad arguments are not solver failures)
        before = d.get("theta1")
        d.step(0.01)
        assert d.get("theta1") != before
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_rejected_multi_set_changes_nothing(fmu_builds, version):
    d = started(fmu_builds[("rigid", version)], {"theta1": 0.5})
    assert status_of(lambda: d.set(tau1=1.0, tau2=math.nan)) == ERROR
    assert d.get("tau1", "tau2").tolist() == [0.0, 0.0]  # the valid first value was rolled back
    assert status_of(lambda: d.set(g=3.0)) == 0  # g is tunable in step mode
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_null_instance_is_an_error_not_a_crash(fmu_builds, version):
    d = started(fmu_builds[("rigid", version)], {"theta1": 0.5})
    prefix = "fmi3" if d.v3 else "fmi2"
    args = (_vr_array([1]), 1, _real_array([0.0])) + ((1,) if d.v3 else ())
    assert status_of(lambda: getattr(d.fmu, f"{prefix}{'GetFloat64' if d.v3 else 'GetReal'}")(None, *args)) == ERROR
    assert status_of(lambda: getattr(d.fmu, f"{prefix}DoStep")(None, 0.0, 0.01, 1, *((None,) * 4 if d.v3 else ()))) == ERROR
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_wrong_token_refuses_to_instantiate(fmu_builds, version, capsys):
    from fmpy import fmi2, fmi3

    built = fmu_builds[("rigid", version)]
    cls = fmi3.FMU3Slave if version == 3 else fmi2.FMU2Slave
    fmu = cls(guid="{not-the-token}", unzipDirectory=built.unzipdir, modelIdentifier="pendulab_rigid", instanceName="x")
    with pytest.raises(Exception, match="(?i)instantiate"):
        fmu.instantiate()
    assert "does not match" in capsys.readouterr().out
    fmu.freeLibrary()


@pytest.mark.parametrize("version", [2, 3])
def test_model_exchange_rejects_nan_states_and_wrong_sizes(fmu_builds, version, capsys):
    d = started(fmu_builds[("rigid", version)], {"theta1": 0.5}, interface="ME")
    d.fmu.enterContinuousTimeMode()
    capsys.readouterr()
    n_bad = _real_array([0.1, math.nan, 0.0, 0.0])
    assert status_of(raw(d, "SetContinuousStates", n_bad, 4)) == ERROR
    assert "finite" in capsys.readouterr().out
    assert status_of(raw(d, "SetContinuousStates", _real_array([0.1, 0.2]), 2)) == ERROR
    assert "expected 4 states" in capsys.readouterr().out
    name = "GetContinuousStateDerivatives" if d.v3 else "GetDerivatives"
    assert status_of(raw(d, name, None, 4)) == ERROR
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_solver_failure_is_an_error_and_the_instance_stays_in_error_state(fmu_builds, version, capsys):
    built = fmu_builds[("rigid", version)]
    d = Driver(built)
    d.set(theta1=2.0, solver_tolerance=1e-300)  # unreachable accuracy: the step size underflows
    if d.v3:
        d.fmu.enterInitializationMode(startTime=0.0)  # no master tolerance: the parameter applies
    else:
        d.fmu.setupExperiment(startTime=0.0)
        d.fmu.enterInitializationMode()
    d.fmu.exitInitializationMode()
    capsys.readouterr()
    assert status_of(_do_step(d, 0.0, 0.1)) == ERROR
    assert "solver failed" in capsys.readouterr().out
    assert status_of(_do_step(d, 0.0, 0.1)) == ERROR
    assert "not allowed in state Error" in capsys.readouterr().out
    d.fmu.freeInstance()


@pytest.mark.parametrize("version", [2, 3])
def test_spring_length_must_stay_positive(fmu_builds, version, capsys):
    """The elastic model is singular at r = 0: a setter with r <= 0 is an Error with a log line and changes nothing."""
    d = Driver(fmu_builds[("elastic", version)])  # start values are set before initialization
    capsys.readouterr()
    assert status_of(lambda: d.set(r1=0.0)) == ERROR
    assert "spring length r1" in capsys.readouterr().out
    assert status_of(lambda: d.set(r1=-0.5)) == ERROR
    d.initialize()
    assert d.get("r1")[0] > 0.5  # the start value stayed (the static length, ~1 m), not 0 or -0.5
    d.step(0.01)  # still usable: a rejected argument is not a solver failure
    d.close()

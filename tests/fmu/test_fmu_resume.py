"""SetFMUState restores the saved life-cycle state (as the Reference FMUs do): fmusim's resume-from-file flow.

A fresh instance (Instantiated) restored from a serialized FMU state taken in step mode is in step mode:
GetReal and DoStep are legal and continue the trajectory bit-identically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fmu_driver import Driver, started

NAMES = ["theta1", "theta2", "omega1", "x2", "energy"]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("solver", [0, 1])
def test_fresh_instance_resumes_from_a_serialized_state(fmu_builds, version, kind, solver):
    built = fmu_builds[(kind, version)]
    a = started(built, {"theta1": 1.1, "theta2": -0.4}, solver=solver, tolerance=1e-9)
    for _ in range(15):
        a.step(0.02)
    state = a.get_state()
    blob = a.serialize(state)
    a.free_state(state)
    t_saved = a.t
    first = []
    for k in range(25):
        a.set(tau1=0.05 * k)
        a.step(0.02)
        first.append(a.get(*NAMES))
    a.close()

    # fmusim: instantiate -> deserialize + set state -> get / step, without any initialization calls
    b = Driver(built, "CS", name="resumed")
    restored = b.deserialize(blob)
    b.set_state(restored)
    b.free_state(restored)
    b.t = t_saved
    assert np.isfinite(b.get(*NAMES)).all()  # GetReal is legal in the restored step mode
    second = []
    for k in range(25):
        b.set(tau1=0.05 * k)
        b.step(0.02)
        second.append(b.get(*NAMES))
    b.close()
    assert np.array_equal(np.array(first), np.array(second))  # bit-identical continuation


@pytest.mark.parametrize("version", [2, 3])
def test_restoring_a_state_taken_before_initialization_returns_to_instantiated(fmu_builds, version):
    built = fmu_builds[("rigid", version)]
    d = Driver(built)
    d.set(theta1=0.3)
    early = d.get_state()  # Instantiated
    d.initialize(1e-10)
    d.step(0.01)
    d.set_state(early)
    d.free_state(early)
    # back in Instantiated: the initialization sequence is legal again and starts from theta1 = 0.3
    d.t = 0.0
    d.initialize(1e-10)
    assert d.get("theta1")[0] == 0.3
    d.step(0.01)
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_state_of_the_other_interface_is_refused(fmu_builds, capsys, version):
    from fmpy.fmi1 import FMICallException

    built = fmu_builds[("rigid", version)]
    me = started(built, {"theta1": 0.5}, interface="ME", name="me")  # ends in event mode
    blob = me.serialize(me.get_state())
    me.close()
    cs = started(built, {"theta1": 0.2}, name="cs")
    before = cs.get("theta1")
    state = cs.deserialize(blob)  # a valid state of this model
    capsys.readouterr()
    with pytest.raises(FMICallException):
        cs.set_state(state)
    assert "cannot resume" in capsys.readouterr().out
    assert cs.get("theta1")[0] == before[0]  # unchanged and usable
    cs.step(0.01)
    cs.close()


@pytest.mark.parametrize("version", [2, 3])
def test_free_with_the_state_instead_of_its_address_frees_it_without_a_crash(fmu_builds, capsys, version):
    """fmusim 0.0.39 calls FreeFMUState(instance, state) after (de)serializing a state file, not (instance, &state)."""
    import ctypes

    built = fmu_builds[("rigid", version)]
    d = started(built, {"theta1": 0.5})
    state = d.get_state()
    lib = ctypes.CDLL(str(next(Path(built.unzipdir, "binaries").glob("*/*.so"))))
    free = getattr(lib, "fmi3FreeFMUState" if version == 3 else "fmi2FreeFMUstate")
    free.argtypes, free.restype = [ctypes.c_void_p, ctypes.c_void_p], ctypes.c_int
    capsys.readouterr()
    assert free(d.fmu.component, state) == 0  # OK: the state is freed (no leak, no crash)
    assert "instead of a pointer to it" in capsys.readouterr().out
    d.step(0.01)  # the instance is unaffected
    d.close()

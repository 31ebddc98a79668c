"""min/max in modelDescription.xml agree with what the FMU accepts: a value is rejected exactly when it is out of range."""

from __future__ import annotations

import math

import pytest
from fmpy.fmi1 import FMICallException
from fmu_driver import Driver

PROBES = (-1.0, -5e-324, 0.0, 5e-324, 0.5, 0.9999999999999999, 1.0, 2.0, 1e300)


def _accepted(d: Driver, vr: int, value, integer: bool) -> bool:
    try:
        if integer:
            (d.fmu.setInt32 if d.v3 else d.fmu.setInteger)([vr], [int(value)])
        else:
            (d.fmu.setFloat64 if d.v3 else d.fmu.setReal)([vr], [value])
    except FMICallException:
        return False
    return True


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_rejected_values_are_exactly_those_outside_min_max(fmu_builds, kind, version):
    built = fmu_builds[(kind, version)]
    settable = [
        v
        for v in built.md.modelVariables
        if v.causality in ("parameter", "input") or (v.causality == "local" and v.initial == "exact")
    ]
    assert len(settable) >= 10
    d = Driver(built, "CS", name="bounds")  # Instantiated: every one of them may be set
    checked = 0
    for var in settable:
        integer = var.type in ("Integer", "Int32")
        lo = -math.inf if var.min is None else float(var.min)
        hi = math.inf if var.max is None else float(var.max)
        probes = (-1, 0, 1, 2, 3) if integer else PROBES
        for value in probes:
            inside = lo <= value <= hi
            assert _accepted(d, var.valueReference, value, integer) == inside, (var.name, value, var.min, var.max)
            checked += 1
    d.fmu.freeInstance()
    assert checked > 90


@pytest.mark.parametrize("version", [2, 3])
def test_bounded_variables_carry_min_and_max(fmu_builds, version):
    md = fmu_builds[("elastic", version)].md
    by = {v.name: v for v in md.modelVariables}
    for name in ("m1", "m2", "L1", "L2", "k1", "k2", "r1", "r2", "solver_tolerance"):
        assert float(by[name].min) == 5e-324  # > 0: the smallest positive double (FMI has no exclusive min)
    for name in ("b1", "b2", "c1", "c2", "g", "max_step"):
        assert float(by[name].min) == 0.0
    assert float(by["solver_tolerance"].max) < 1.0 and (by["solver"].min, by["solver"].max) == ("0", "1")
    assert by["tau1"].min is None and by["theta1"].min is None  # unlimited: no bound is invented


@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_validation_passes_with_the_bounds(fmu_builds, version):
    from fmpy.validation import validate_fmu

    for kind in ("rigid", "elastic"):
        assert validate_fmu(str(fmu_builds[(kind, version)].path)) == []

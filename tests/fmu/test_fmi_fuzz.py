"""FMI call-sequence fuzzing through fmpy's low-level classes (engine: benchmarks/fuzz_fmi.py).

FMI 2 and 3, CS and ME, rigid and elastic; each batch runs in a subprocess, so a crash or a hang is
reported with the seed, the call sequence and the command that replays it. A short campaign runs in the
normal suite; ``pytest --fuzz-long`` runs a long one.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_fmi.py"


def _engine():
    spec = importlib.util.spec_from_file_location("fuzz_fmi", _PATH)
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("fuzz_fmi", mod)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def fuzz():
    return _engine()


def _dirs(fmu_builds):
    return {key: built.unzipdir for key, built in fmu_builds.items()}


def test_sequences_are_reproducible_from_the_seed(fuzz):
    assert fuzz.generate(7, "elastic", 3, "ME", 40) == fuzz.generate(7, "elastic", 3, "ME", 40)
    assert fuzz.generate(7, "elastic", 3, "ME", 40) != fuzz.generate(8, "elastic", 3, "ME", 40)


@pytest.mark.parametrize("interface", ["CS", "ME"])
@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_short_fuzz_campaign(fmu_builds, fuzz, request, kind, version, interface):
    long = request.config.getoption("--fuzz-long")
    n = 1500 if long else 24
    summary = fuzz.run_campaign(
        _dirs(fmu_builds),
        n,
        length=60,
        seed=1000 if long else 0,
        batch=n if not long else 250,
        jobs=1,
        timeout=900 if long else 60,
        configs=[(kind, version, interface)],
    )
    report = "\n".join([summary.table(), *(f.report() for f in summary.findings)])
    assert not summary.findings, report
    assert summary.sequences == n and summary.calls == 60 * n, report
    assert summary.statuses["OK"] > 0 and summary.statuses["Error"] > 0, report


def test_fuzzer_detects_a_crash_and_reports_the_sequence(fmu_builds, fuzz, monkeypatch):
    """The subprocess isolation works: a worker killed by a signal becomes a finding with seed and calls."""
    spec = {
        "unzipdir": str(fmu_builds[("rigid", 2)].unzipdir),
        "kind": "rigid",
        "version": 2,
        "interface": "CS",
        "seeds": [5],
        "length": 10,
    }
    monkeypatch.setattr(fuzz, "__file__", str(Path(__file__).parent / "c" / "_crash_worker.py"))
    result, finding = fuzz._run_batch(spec, timeout=60)
    assert result is None and finding.kind == "crash" and finding.seed == 5
    assert len(finding.calls) == 10 and "--replay 5" in finding.report()


# ------------------------------------------------------------------ targeted checks of issue 15's C fixes
def _status(call) -> int:
    from fmpy.fmi1 import FMICallException

    try:
        call()
    except FMICallException as exc:
        return exc.status
    return 0


def _time(d) -> float:
    """The FMU's time (value reference 0, read by the core although not a model variable)."""
    return (d.fmu.getFloat64 if d.v3 else d.fmu.getReal)([0])[0]


def _edit(blob: bytes, offset: int, value: float) -> bytes:
    import struct

    data = bytearray(blob)
    struct.pack_into("<d", data, offset, value)
    return bytes(data)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize(
    ("kind", "field", "value", "fragment"),
    [
        ("rigid", "p0", -1.0, "m1 must be > 0"),
        ("rigid", "p0", float("nan"), "m1: value nan is not finite"),
        ("rigid", "p5", -0.5, "b1 must be >= 0"),
        ("rigid", "x1", float("inf"), "is not finite"),
        ("rigid", "time", float("nan"), "time nan is not finite"),
        ("rigid", "u0", float("nan"), "input 0"),
        ("rigid", "tolerance", 2.0, "solver_tolerance must be in (0, 1)"),
        ("rigid", "max_step", -1.0, "max_step must be finite and >= 0"),
        ("rigid", "ode_h", float("nan"), "solver settings"),
        ("elastic", "x2", float("nan"), "state 2 (value reference 102) is not finite"),
        ("elastic", "p7", 0.0, "k1 must be > 0"),
    ],
)
def test_edited_fmu_state_is_rejected_like_a_set_value(fmu_builds, fuzz, capsys, version, kind, field, value, fragment):
    from fmu_driver import started

    d = started(fmu_builds[(kind, version)], {"theta1": 0.5})
    d.step(0.01)
    state = d.get_state()
    blob = d.serialize(state)
    d.free_state(state)
    offsets = fuzz.field_offsets(fuzz.NX[kind], 2, fuzz.NP[kind])
    bad = _edit(blob, offsets[field][0], value)
    before = d.get("theta1", "m1", "tau1")
    capsys.readouterr()
    assert _status(lambda: d.deserialize(bad)) == 3  # Error, and a log line naming the field
    assert fragment in capsys.readouterr().out
    # an FMU state edited in memory (no deserialization) is refused by SetFMUState the same way
    state = d.deserialize(blob)
    import ctypes

    ctypes.memmove(state, bad, len(bad))
    assert _status(lambda: d.set_state(state)) == 3
    assert fragment in capsys.readouterr().out
    d.free_state(state)
    assert (d.get("theta1", "m1", "tau1") == before).all()  # the instance is unchanged and still steps
    d.step(0.01)
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_wrong_size_and_garbage_fmu_states_are_errors(fmu_builds, capsys, version):
    import random

    from fmu_driver import started

    d = started(fmu_builds[("elastic", version)], {"theta1": 0.5})
    state = d.get_state()
    blob = d.serialize(state)
    d.free_state(state)
    rng = random.Random(1)
    for bad in (b"", blob[:-1], blob + b"\0", bytes(len(blob)), bytes(rng.getrandbits(8) for _ in range(len(blob)))):
        capsys.readouterr()
        assert _status(lambda bad=bad: d.deserialize(bad)) == 3
        assert "FMU state" in capsys.readouterr().out
    d.step(0.01)
    d.close()


@pytest.mark.parametrize("version", [2, 3])
def test_restart_from_a_stored_state_after_a_solver_failure(fmu_builds, capsys, version):
    """FMI: after Error, SetFMUState with a state stored before it resumes the simulation."""
    from fmu_driver import Driver

    d = Driver(fmu_builds[("rigid", version)])
    d.set(theta1=2.0)
    d.initialize(1e-10)
    good = d.get_state()
    # a 1e12 s step needs more than the internal-step limit: solver failure, Error state
    assert _status(lambda: d.fmu.doStep(0.0, 1e12)) == 3
    assert "too many internal steps" in capsys.readouterr().out
    assert _status(lambda: d.fmu.doStep(0.0, 0.01)) == 3  # the Error state holds
    d.set_state(good)
    d.t = 0.0
    d.step(0.01)
    assert _time(d) == pytest.approx(0.01)
    d.free_state(good)
    d.close()


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("h", [1e-300, 5e-324, 1e-15])
def test_steps_below_the_solver_resolution_advance_time(fmu_builds, version, h):
    """Decision (issue 15): a positive step below 1e-14 max(1, |t|) is legal: one Euler step, status OK."""
    from fmu_driver import started

    d = started(fmu_builds[("rigid", version)], {"theta1": 0.5, "omega1": 2.0})
    th0 = d.get("theta1")[0]
    d.fmu.doStep(0.0, h)  # raises on any status above Warning
    assert _time(d) == h
    assert d.get("theta1")[0] == th0 + h * 2.0  # x += h * f(x): exact to rounding for such h
    d.t = h
    d.step(0.01)  # the instance stays usable and the solver continues
    # at a later time a step may round away completely: time and state stay, status OK
    t = d.t
    before = d.get("theta1", "omega1")
    d.fmu.doStep(t, 1e-300)
    assert _time(d) == t and (d.get("theta1", "omega1") == before).all()
    d.close()

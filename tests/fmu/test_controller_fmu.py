"""Controllers as FMUs: generated C (CasADi laws, plan data as constant arrays), FMI 2 and 3 Co-Simulation.

The FMU's torques must equal the Python controller's (pendulab.control) at the same inputs, sample by
sample along a closed-loop run that exercises every branch (pumping and catch, tracking and hand-over).
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

import pendulab as pl
from pendulab.control.feedback import as_feedback
from pendulab.fmu.controller_export import (
    controller_law,
    design_controller,
    export_controller,
    generate_controller_sources,
)
from pendulab.native.build import find_compiler

# name -> (controller, task, closed-loop horizon [s]) covering every branch of the laws
CASES = {
    "lqr": ("lqr", None, 2.0),
    "swingup": ("swingup", None, 6.0),  # pumps, then catches (caught_at checked below)
    "tvlqr_pendubot": ("tvlqr", "pendubot", 6.0),  # tracks the optimized plan (~4 s), then the final LQR
    "swingup_acrobot": ("swingup", "acrobot", 3.0),  # one-joint pumping (tau2 only)
    "lqr_elastic": ("lqr", None, 1.0),
    "swingup_elastic": ("swingup", None, 6.0),  # the pumping law with the spring energy; catches at ~3 s
}


@pytest.fixture(scope="module")
def designs():
    out = {}
    for key, (name, task, horizon) in CASES.items():
        kind = "elastic" if key.endswith("elastic") else "rigid"
        ctrl, x0, model = design_controller(name, task, kind=kind)
        out[key] = (ctrl, x0, model, horizon)
    return out


@pytest.fixture(scope="module")
def built(designs, tmp_path_factory):
    root = tmp_path_factory.mktemp("controller_fmus")
    out = {}
    for key, (ctrl, *_rest) in designs.items():
        for version in (2, 3):
            out[(key, version)] = export_controller(ctrl, root / f"{key}{version}.fmu", version, timestamp=False)
    return out


class Instance:
    """An initialized controller FMU instance through fmpy."""

    def __init__(self, path: Path, tmp: Path, sample_time: float | None = None) -> None:
        self.md = read_model_description(str(path))
        self.v3 = self.md.fmiVersion.startswith("3")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        cls = FMU3Slave if self.v3 else FMU2Slave
        self.fmu = cls(
            guid=self.md.guid,
            unzipDirectory=extract(str(path), str(tmp)),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName="ctrl",
        )
        self.fmu.instantiate()
        if sample_time is not None:
            self.set(sample_time=sample_time)
        if self.v3:
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def set(self, **values: float) -> None:
        (self.fmu.setFloat64 if self.v3 else self.fmu.setReal)([self.vr[n] for n in values], list(values.values()))

    def get(self, names) -> np.ndarray:
        return np.array((self.fmu.getFloat64 if self.v3 else self.fmu.getReal)([self.vr[n] for n in names]))

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def _closed_loop(ctrl, x0, model, horizon):
    """States at the samples of the Python closed loop (the native integrator, sample-and-hold)."""
    h = ctrl.sample_time
    n = round(horizon / h)
    traj = pl.simulate(model, x0, n * h, dt=h, u=as_feedback(ctrl, model), rtol=1e-10, atol=1e-10)
    return traj.t, traj.x


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("key", list(CASES))
def test_outputs_equal_the_python_controller(designs, built, tmp_path, key, version):
    ctrl, x0, model, horizon = designs[key]
    t, X = _closed_loop(ctrl, x0, model, horizon)
    inst = Instance(built[(key, version)], tmp_path)
    ctrl.reset()
    err = 0.0
    for k, (tk, xk) in enumerate(zip(t, X, strict=True)):
        inst.set(**dict(zip(model.state_names, xk, strict=True)))
        u_fmu = inst.get(ctrl.input_names)
        u_py = np.asarray(ctrl(float(tk), xk.copy()))
        err = max(err, float(np.max(np.abs(u_fmu - u_py))))
        inst.fmu.doStep(k * ctrl.sample_time, ctrl.sample_time)
    inst.close()
    # the same expression graph compiled to C vs CasADi's VM and NumPy: rounding only (torques up to ~20 N.m)
    assert err <= 1e-12, err
    if key.startswith("swingup") and key != "swingup_acrobot":
        assert ctrl.caught_at is not None  # the run covered the switch to the LQR catch
    if key.startswith("tvlqr"):
        assert t[-1] > ctrl.horizon  # ... and the hand-over to the final LQR


@pytest.mark.parametrize("version", [2, 3])
def test_sample_and_hold_between_samples(designs, built, tmp_path, version):
    """Comm step = sample time / 4: the torques change only at the samples, to the law at the inputs then."""
    ctrl, x0, model, _ = designs["swingup"]
    h = ctrl.sample_time
    inst = Instance(built[("swingup", version)], tmp_path, sample_time=4 * h)  # the parameter: samples at 0, 4h, 8h, ...
    ctrl.reset()
    rng = np.random.default_rng(1)
    held = None
    for j in range(40):
        x = x0 + 0.3 * rng.normal(size=model.nx)
        inst.set(**dict(zip(model.state_names, x, strict=True)))
        u = inst.get(ctrl.input_names)
        if j % 4 == 0:  # a sample instant: the law at the current inputs
            held = np.asarray(ctrl(j * h, x.copy()))
            np.testing.assert_allclose(u, held, rtol=0, atol=1e-12)  # rounding only
        else:  # between samples: held, whatever the inputs do
            np.testing.assert_array_equal(u, held)
        inst.fmu.doStep(j * h, h)
    inst.close()


@pytest.mark.parametrize("version", [2, 3])
def test_fmu_state_restores_the_mode_and_the_held_torque(designs, built, tmp_path, version):
    ctrl, x0, model, horizon = designs["swingup"]
    t, X = _closed_loop(ctrl, x0, model, horizon)
    inst = Instance(built[("swingup", version)], tmp_path)
    names = dict.fromkeys(model.state_names)
    get_state = inst.fmu.getFMUState if inst.v3 else inst.fmu.getFMUstate
    set_state = inst.fmu.setFMUState if inst.v3 else inst.fmu.setFMUstate
    saved, outs = None, []
    for k, xk in enumerate(X):
        inst.set(**dict(zip(names, xk, strict=True)))
        if k == 10:
            saved = get_state()
        outs.append(inst.get(ctrl.input_names))
        inst.fmu.doStep(k * ctrl.sample_time, ctrl.sample_time)
    set_state(saved)  # back to sample 10 (pumping), then replay
    for k in range(10, len(X)):
        inst.set(**dict(zip(names, X[k], strict=True)))
        np.testing.assert_array_equal(inst.get(ctrl.input_names), outs[k])  # deterministic replay
        inst.fmu.doStep(k * ctrl.sample_time, ctrl.sample_time)
    inst.close()


@pytest.mark.parametrize("version", [2, 3])
def test_bad_values_are_refused(built, tmp_path, version):
    inst = Instance(built[("lqr", version)], tmp_path)
    with pytest.raises(FMICallException):  # sample_time is fixed after initialization
        inst.set(sample_time=0.02)
    with pytest.raises(FMICallException):  # non-finite measurement
        inst.set(theta1=float("nan"))
    with pytest.raises(FMICallException):  # outputs are read-only
        inst.set(tau1=1.0)
    assert np.isfinite(inst.get(["tau1", "tau2"])).all()  # still usable
    inst.close()
    md = read_model_description(str(built[("lqr", version)]))
    fresh = (FMU3Slave if version == 3 else FMU2Slave)(
        guid=md.guid, unzipDirectory=extract(str(built[("lqr", version)]), str(tmp_path / "b")),
        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="b",
    )  # fmt: skip
    fresh.instantiate()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    for bad in (0.0, -0.01, float("inf")):
        with pytest.raises(FMICallException):  # sample_time must be a positive finite period
            (fresh.setFloat64 if version == 3 else fresh.setReal)([vr["sample_time"]], [bad])
    fresh.freeInstance()


@pytest.mark.parametrize("version", [2, 3])
def test_do_step_of_size_zero_negative_or_not_finite_is_an_error(built, tmp_path, version, capsys):
    """As the plant FMUs and the Reference FMUs: DoStep(h <= 0 or non-finite) returns Error with a log line, changes nothing."""
    inst = Instance(built[("lqr", version)], tmp_path)
    h = float(inst.get(["sample_time"])[0])
    inst.fmu.doStep(0.0, h)
    for bad in (0.0, -0.0, -h, float("nan"), float("inf"), -float("inf")):
        capsys.readouterr()
        with pytest.raises(FMICallException):
            inst.fmu.doStep(h, bad)
        log = capsys.readouterr().out
        assert "communication step size must be positive and finite" in log, (bad, log)
    inst.fmu.doStep(h, h)  # the instance is still usable at its time
    if inst.v3:
        assert inst.get(["time"])[0] == 2 * h
    inst.close()
    # a defined tolerance must be in (0, 1), as for the plant (the controller has no solver and ignores a valid one)
    md = read_model_description(str(built[("lqr", version)]))
    fresh = (FMU3Slave if version == 3 else FMU2Slave)(
        guid=md.guid, unzipDirectory=extract(str(built[("lqr", version)]), str(tmp_path / "t")),
        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t",
    )  # fmt: skip
    fresh.instantiate()
    capsys.readouterr()
    with pytest.raises(FMICallException):
        fresh.enterInitializationMode(tolerance=0.0) if version == 3 else fresh.setupExperiment(tolerance=0.0)
    assert "tolerance must be in (0, 1)" in capsys.readouterr().out
    fresh.freeInstance()


def test_fmpy_validate_and_the_interface(built, designs):
    for (key, _version), path in built.items():
        assert validate_fmu(str(path)) == [], (key, _version)
        md = read_model_description(str(path))
        ctrl, _x0, model, _ = designs[key]
        assert md.modelExchange is None and md.coSimulation is not None
        by = {v.name: v for v in md.modelVariables}
        assert all(by[n].causality == "input" for n in model.state_names)
        assert [u.variable.name for u in md.outputs] == list(ctrl.input_names)  # ModelStructure
        assert all(by[n].causality == "output" for n in ctrl.input_names)
        assert by["sample_time"].causality == "parameter" and float(by["sample_time"].start) == ctrl.sample_time


@pytest.mark.parametrize("version", [2, 3])
def test_generated_c_compiles_warning_free(designs, tmp_path, version):
    """-std=c99 -Wall -Wextra -pedantic -Werror on every translation unit, for each kind of law."""
    cc = find_compiler()
    for key in ("lqr", "swingup_acrobot", "tvlqr_pendubot"):
        sources, _ = generate_controller_sources(controller_law(designs[key][0]), version)
        d = tmp_path / key
        d.mkdir()
        for name, data in sources.items():
            (d / name).write_bytes(data)
        for unit in (f"ctrl_fmi{version}.c", "ctrl_core.c", "controller_functions.c", "controller_data.c"):
            cmd = [
                cc,
                "-std=c99",
                "-Wall",
                "-Wextra",
                "-pedantic",
                "-Werror",
                "-c",
                str(d / unit),
                "-I",
                str(d),
                "-o",
                "/dev/null",
            ]
            proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
            assert proc.returncode == 0, (key, unit, proc.stderr)


def test_nmpc_and_foreign_controllers_are_refused():
    with pytest.raises(ValueError, match="NMPC is not exported"):
        design_controller("nmpc")
    with pytest.raises(ValueError, match="controller must be one of"):
        design_controller("pid")
    with pytest.raises(TypeError, match="LinearStateFeedback"):
        controller_law(object())
    ctrl, _x0, _model = design_controller("lqr")
    ctrl.K = ctrl.K.copy()
    ctrl.K[0, 0] = np.nan  # a broken design is refused, never exported with a placeholder
    with pytest.raises(ValueError, match="K must be finite"):
        controller_law(ctrl)


def test_cli_export_controller(tmp_path, capsys):
    import json

    from pendulab.cli import main

    out = tmp_path / "c.fmu"
    assert main(["fmu", "export-controller", "--controller", "lqr", "--fmi-version", "3", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["outputs"] == ["tau1", "tau2"] and summary["inputs"][0] == "theta1" and out.exists()
    assert validate_fmu(str(out)) == []
    assert main(["fmu", "export-controller", "--controller", "nmpc", "--out", str(out)]) == 2
    assert "NMPC is not exported" in capsys.readouterr().err
    assert main(["fmu", "export-controller", "--controller", "lqr", "--task", "pendubot", "--kind", "rigid"]) == 2


HARNESS = Path(__file__).parent / "c" / "ctrl_harness.c"
SAN = ["-fsanitize=address,undefined", "-fno-omit-frame-pointer", "-g", "-O1"]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("key", ["lqr", "swingup_acrobot", "tvlqr_pendubot"])
def test_c_importer_and_random_calls_are_clean_under_asan_ubsan(designs, tmp_path, key, version):
    """tests/fmu/c/ctrl_harness.c linked with the sources: NULLs, bad values, wrong states, state round trips,
    garbage states and 20000 random calls; ASan/UBSan abort on any invalid access, leak or undefined behaviour."""
    cc = find_compiler()
    probe = tmp_path / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    if subprocess.run([cc, *SAN, str(probe), "-o", str(tmp_path / "probe")], capture_output=True, check=False).returncode:
        pytest.skip(f"{cc} cannot build with -fsanitize=address,undefined here")
    sources, _ = generate_controller_sources(controller_law(designs[key][0]), version)
    for name, data in sources.items():
        (tmp_path / name).write_bytes(data)
    units = [tmp_path / n for n in (f"ctrl_fmi{version}.c", "ctrl_core.c", "controller_functions.c", "controller_data.c")]
    exe = tmp_path / "harness"
    cmd = [cc, "-std=c99", "-Wall", "-Wextra", "-Werror", *SAN, f"-DFMI_VERSION={version}", "-I", str(tmp_path)]
    build = subprocess.run([*cmd, str(HARNESS), *map(str, units), "-lm", "-o", str(exe)], capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    env = {"ASAN_OPTIONS": "detect_leaks=1:abort_on_error=0:exitcode=86", "UBSAN_OPTIONS": "halt_on_error=1:exitcode=87"}
    run = subprocess.run([str(exe), "20000"], capture_output=True, text=True, env=env, timeout=120, check=False)
    assert run.returncode == 0 and run.stdout.startswith("ok"), run.stdout + run.stderr

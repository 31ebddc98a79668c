"""method="compiled-dopri5" / "compiled-rodas4": the FMU's C solvers as a native fast path.

They agree with CVODES at tight tolerance (rigid, stiff-ish elastic; constant, sampled and
feedback inputs), they are the same C implementation as the FMU (same sources, same numbers
through fmpy), and they fail loudly: non-finite states, bad tolerances, exhausted step budgets
and a missing C compiler each give a clear error.
"""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import pendulab as pl
from pendulab.integrate.auto import choose_method
from pendulab.integrate.methods import METHODS
from pendulab.integrate.registry import SimulationError
from pendulab.model.quasistatic import quasi_static_state
from pendulab.native import CompilerNotFoundError, native_library, native_sources
from pendulab.native import build as native_build
from pendulab.native.library import ERROR_CODES

pytestmark = pytest.mark.needs_cc

ROOT = Path(__file__).resolve().parents[2]
COMPILED = ("compiled-dopri5", "compiled-rodas4")
T_FINAL, DT = 2.0, 0.01
TOL = 1e-12


def _case(kind: str) -> tuple[pl.Model, np.ndarray]:
    if kind == "rigid":
        return pl.rigid(b1=0.05), np.array([1.0, 0.5, 0.0, 0.0])
    # k = 1e4: spring modes 62 and 162 rad/s; quasi-static start, so no fast spring oscillation is excited.
    model = pl.elastic(k1=1e4, k2=1e4)
    return model, quasi_static_state(model, (1.0, 0.5))


def _input(kind: str, t: np.ndarray):
    if kind == "none":
        return None
    if kind == "constant":
        return (0.3, -0.2)
    if kind == "sampled":
        tk = t[:-1]
        return np.column_stack([0.4 * np.sin(3.0 * tk), -0.3 * np.cos(2.0 * tk)])

    def feedback(tk: float, x: np.ndarray) -> np.ndarray:  # a PD law on the angles
        return np.array([-2.0 * (x[0] - 0.5) - 0.5 * x[-4], -1.0 * (x[1] - x[0]) - 0.3 * (x[-3] - x[-4])])

    return feedback


@pytest.mark.parametrize("method", COMPILED)
@pytest.mark.parametrize("inputs", ["none", "constant", "sampled", "feedback"])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_matches_cvodes_at_tight_tolerance(kind, inputs, method):
    model, x0 = _case(kind)
    t = np.linspace(0.0, T_FINAL, round(T_FINAL / DT) + 1)
    u = _input(inputs, t)
    ref = pl.simulate(model, x0, T_FINAL, dt=DT, method="cvodes", rtol=TOL, atol=TOL, u=u)
    got = pl.simulate(model, x0, T_FINAL, dt=DT, method=method, rtol=TOL, atol=TOL, u=u)
    err = np.max(np.abs(got.x - ref.x))
    # CVODES BDF's own global error at 1e-12 on these regular 2 s runs is 0.4-2e-8 (elastic) and 0.4-1.5e-9 (rigid):
    # measured against cvodes-adams and DOP853 the compiled runs differ by as much; 5x margin.
    assert err < (1e-7 if kind == "elastic" else 1e-8), err
    if inputs == "feedback":  # the feedback sees states that differ by err; its gains are O(1)
        np.testing.assert_allclose(got.u, ref.u, rtol=0, atol=10 * err)
    else:
        np.testing.assert_array_equal(got.u, ref.u)
    assert got.method == method and got.success
    s = got.stats
    assert s["n_steps"] > 0 and s["n_rhs"] > s["n_steps"] and s["n_rejected"] >= 0
    assert (s["n_jac"] > 0) == (method == "compiled-rodas4")
    assert s["c_calls"] == (len(t) - 1 if inputs == "feedback" else 1)  # the whole grid in one C call unless feedback


@pytest.mark.parametrize("method", COMPILED)
def test_per_interval_calls_equal_the_whole_grid_call_exactly(method):
    """Feedback runs the same C loop one interval per call, carrying the step size: a constant
    feedback reproduces the one-call constant-input run bit for bit (as an FMU across DoStep calls)."""
    model, x0 = _case("elastic")
    one = pl.simulate(model, x0, 1.0, dt=0.02, method=method, rtol=1e-9, atol=1e-9, u=(0.2, 0.1))
    per = pl.simulate(model, x0, 1.0, dt=0.02, method=method, rtol=1e-9, atol=1e-9, u=lambda t, x: np.array([0.2, 0.1]))
    np.testing.assert_array_equal(per.x, one.x)
    for key in ("n_steps", "n_rejected", "n_jac"):
        assert per.stats[key] == one.stats[key]


@pytest.mark.parametrize("method", COMPILED)
def test_max_step_limits_the_internal_step(method):
    model, x0 = _case("rigid")
    free = pl.simulate(model, x0, 1.0, dt=0.1, method=method, rtol=1e-6, atol=1e-6)
    capped = pl.simulate(model, x0, 1.0, dt=0.1, method=method, rtol=1e-6, atol=1e-6, max_step=1e-3)
    assert capped.stats["n_steps"] >= 1000 > free.stats["n_steps"]  # 1 s at h <= 1 ms
    assert np.max(np.abs(capped.x - free.x)) < 1e-4  # both within their tolerance of the same solution


# -- one C implementation, two front ends ------------------------------------------------------


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """FMI 2 FMUs of the rigid model and of the elastic model with k = 1e4 (unzipped)."""
    from fmpy import extract, read_model_description

    from pendulab.fmu import export

    out = {}
    root = tmp_path_factory.mktemp("fmus")
    for kind in ("rigid", "elastic"):
        model, x0 = _case(kind)
        path = export(model, root / f"{kind}.fmu", 2, timestamp=False, x0=x0)
        out[kind] = (path, extract(str(path), str(root / kind)), read_model_description(str(path)))
    return out


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_fmu_ships_the_same_solver_and_model_sources(exported, kind):
    path, _, _ = exported[kind]
    native = native_sources(kind)
    with zipfile.ZipFile(path) as zf:
        for name in ("ode_solver.c", "ode_solver.h", "model_casadi.c"):
            assert zf.read(f"sources/{name}") == native[name], name


@pytest.mark.parametrize("method", COMPILED)
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_native_and_fmu_cosimulation_give_the_same_numbers(exported, kind, method):
    """The FMU (fmpy, Co-Simulation, one DoStep per output interval, same solver and tolerance, the same
    held torques) and the native library reproduce each other to rounding."""
    from fmpy.fmi2 import FMU2Slave

    _, unzipdir, md = exported[kind]
    model, x0 = _case(kind)
    tol, dt, n = 1e-9, 0.02, 50
    t = np.linspace(0.0, n * dt, n + 1)
    u = _input("sampled", t)
    native = pl.simulate(model, x0, t[-1], dt=dt, method=method, rtol=tol, atol=tol, u=u)
    np.testing.assert_array_equal(native.t, t)

    vr = {v.name: v.valueReference for v in md.modelVariables}
    xr = [vr[name] for name in model.state_names]
    ur = [vr[name] for name in model.input_names]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="eq")
    fmu.instantiate()
    try:
        fmu.setInteger([vr["solver"]], [COMPILED.index(method)])
        fmu.setupExperiment(tolerance=tol, startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        X = [np.array(fmu.getReal(xr))]
        for k in range(n):
            fmu.setReal(ur, list(u[k]))
            fmu.doStep(t[k], t[k + 1] - t[k])
            X.append(np.array(fmu.getReal(xr)))
        fmu.terminate()
    finally:
        fmu.freeInstance()
    X = np.array(X)
    np.testing.assert_array_equal(X[0], x0)
    # Same C code, same flags, same settings, same step sequence: bit-identical (measured), provided the FMU's
    # interval ends t_k + (t_k+1 - t_k) are the grid points; otherwise the last step of an interval may
    # differ by one ulp of t, which moves the states by ~1e-16.
    if all(t[k] + (t[k + 1] - t[k]) == t[k + 1] for k in range(n)):
        np.testing.assert_array_equal(X, native.x)
    else:
        assert np.max(np.abs(X - native.x)) < 1e-12


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_native_c_compiles_warning_free(kind, tmp_path):
    """Every translation unit of the native library with the build flags plus -Werror -Wpedantic."""
    from pendulab.native.build import CFLAGS, find_compiler
    from pendulab.native.codegen import native_units

    for name, data in native_sources(kind).items():
        (tmp_path / name).write_bytes(data)
    for unit in native_units():
        cmd = [find_compiler(), *CFLAGS, "-Werror", "-Wpedantic", "-c", str(tmp_path / unit), "-o", str(tmp_path / f"{unit}.o")]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        assert proc.returncode == 0, proc.stderr


# -- clear errors ---------------------------------------------------------------------------------


@pytest.mark.parametrize("method", COMPILED)
def test_non_finite_start_and_overflowing_state_are_clear_errors(method):
    with pytest.raises(ValueError, match="x0"):
        pl.simulate(pl.rigid(), [np.nan, 0.0, 0.0, 0.0], 1.0, method=method)
    # omega^2 overflows: simulate's start check (Model.check_start) refuses it before the C loop runs ...
    with pytest.raises(ValueError, match="x0: the equations of motion are not finite"):
        pl.simulate(pl.rigid(), [0.0, 0.0, 1e200, 0.0], 1.0, method=method)
    # ... and the C loop itself reports the same state as a right-hand-side failure at t = 0.
    lib = native_library("rigid")
    _, res = lib.run_grid(method.removeprefix("compiled-"), np.array([0.0, 1.0]), np.array([0.0, 0.0, 1e200, 0.0]),
                          np.zeros(2), pl.rigid().p, rtol=1e-8, atol=1e-8)  # fmt: skip
    assert res.code == ERROR_CODES["rhs"] and res.t_reached == 0.0


@pytest.mark.parametrize("method", COMPILED)
@pytest.mark.parametrize("how", ["sampled", "feedback"])
def test_blow_up_reports_the_time_the_c_loop_reached(method, how):
    t = np.linspace(0.0, 2.0, 21)
    huge = np.where(t[:-1, None] >= 0.5, np.array([1e300, 0.0]), 0.0)  # absurd torque from t = 0.5 s on
    u = huge if how == "sampled" else (lambda tk, x: np.array([1e300, 0.0]) if tk >= 0.5 else np.zeros(2))
    with pytest.raises(SimulationError, match=rf"method '{method}' failed at t = 0.5 s of 2 s") as exc:
        pl.simulate(pl.rigid(), [1.0, 0.0, 0.0, 0.0], 2.0, dt=0.1, method=method, u=u)
    assert exc.value.t_reached == pytest.approx(0.5, abs=1e-12)


@pytest.mark.parametrize("method", COMPILED)
def test_step_budget(method):
    with pytest.raises(SimulationError, match=r"step budget exhausted \(50 step attempts") as exc:
        pl.simulate(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 10.0, method=method, rtol=1e-10, atol=1e-10, options={"max_steps": 50})
    assert 0.0 < exc.value.t_reached < 10.0 and "max_steps" in str(exc.value)
    with pytest.raises(SimulationError, match="step budget"):  # the budget spans the feedback's per-interval calls too
        pl.simulate(pl.rigid(), [2.0, 2.0, 0, 0], 10.0, method=method, u=lambda t, x: np.zeros(2), options={"max_steps": 50})


@pytest.mark.parametrize("method", COMPILED)
def test_bad_tolerances_and_options_are_rejected(method):
    x0 = [1.0, 0.0, 0.0, 0.0]
    for bad in (0.0, -1e-8, np.nan, np.inf):
        with pytest.raises(ValueError, match="rtol"):
            pl.simulate(pl.rigid(), x0, 1.0, method=method, rtol=bad)
        with pytest.raises(ValueError, match="atol"):
            pl.simulate(pl.rigid(), x0, 1.0, method=method, atol=bad)
    with pytest.raises(ValueError, match=r"rtol = 1e-17: out of range; expected a finite number in \[2.22e-16, 1\)"):
        pl.simulate(pl.rigid(), x0, 1.0, method=method, rtol=1e-17)
    with pytest.raises(ValueError, match=r"unknown option\(s\) \['first_step'\]"):
        pl.simulate(pl.rigid(), x0, 1.0, method=method, options={"first_step": 1e-3})
    for bad in (0, 2.5, True, "10"):
        with pytest.raises(ValueError, match="max_steps must be an integer"):
            pl.simulate(pl.rigid(), x0, 1.0, method=method, options={"max_steps": bad})


def test_c_loop_validates_its_arguments():
    """The C entry point checks values itself (it is callable without the Python front end)."""
    lib = native_library("rigid")
    model = pl.rigid()
    t = np.linspace(0.0, 1.0, 11)
    x0, u = np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(2)
    _, ok = lib.run_grid("dopri5", t, x0, u, model.p, rtol=1e-8, atol=1e-8)
    assert ok.ok and ok.n_points == 11 and ok.t_reached == 1.0
    cases = {
        "initial state is not finite": dict(x0=np.array([np.nan, 0.0, 0.0, 0.0])),
        "strictly increasing": dict(t=t[::-1].copy()),
        "input is not finite": dict(u=np.array([np.inf, 0.0])),
        "bad solver arguments": dict(rtol=0.0),
    }
    for message, change in cases.items():
        args = {"t": t, "x0": x0, "u": u, "rtol": 1e-8, **change}
        _, res = lib.run_grid("dopri5", args["t"], args["x0"], args["u"], model.p, rtol=args["rtol"], atol=1e-8)
        assert not res.ok and res.code < 0 and message in res.message, (message, res)
    _, res = lib.run_grid("dopri5", t, x0, u, model.p, rtol=1e-8, atol=1e-8, max_steps=0)
    assert res.message == "bad solver arguments"
    with pytest.raises(ValueError, match="u must have shape"):
        lib.run_grid("dopri5", t, x0, np.zeros((3, 2)), model.p, rtol=1e-8, atol=1e-8)


def test_missing_compiler_names_the_method_and_a_hint(monkeypatch, tmp_path):
    monkeypatch.setenv("PENDULAB_CACHE_DIR", str(tmp_path / "empty-cache"))  # nothing cached there
    monkeypatch.setattr(native_build.shutil, "which", lambda name: None)  # no compiler on PATH
    for method, fallback in (("compiled-rodas4", "cvodes"), ("compiled-dopri5", "cvodes-adams")):
        with pytest.raises(CompilerNotFoundError, match=rf"method '{method}' needs a C compiler") as exc:
            pl.simulate(pl.elastic(), pl.elastic().rest_state(), 0.1, method=method)
        msg = str(exc.value)
        assert "no C compiler was found" in msg and "hint: install gcc or clang" in msg and f"method='{fallback}'" in msg
        assert isinstance(exc.value, RuntimeError)
        assert "C compiler" in METHODS[method].settings["available"]()
    # method="auto" falls back to what needs no compiler
    model = pl.elastic(k1=1e6, k2=1e6)
    choice = choose_method(model, quasi_static_state(model, (0.3, 0.3)), np.zeros(2), 1e-8, 1e-8)
    assert choice.method == "cvodes" and "compiled-rodas4: needs a C compiler" in choice.reason


def test_import_compiles_nothing_and_the_disk_cache_needs_no_compiler(tmp_path):
    """Importing pendulab builds nothing; the first run builds into the cache; a later process with no
    compiler on PATH loads the cached library."""
    cache = tmp_path / "cache"
    env = {**os.environ, "PENDULAB_CACHE_DIR": str(cache)}
    code_import = "import pendulab, pendulab.integrate.compiled; print('imported')"
    code_run = (
        "import pendulab as pl; tr = pl.simulate(pl.rigid(), [1.0, 0, 0, 0], 1.0, method='compiled-dopri5'); print(tr.x[-1, 0])"
    )
    run = dict(cwd=ROOT, capture_output=True, text=True, timeout=300)
    proc = subprocess.run([sys.executable, "-c", code_import], env=env, **run)
    assert proc.returncode == 0, proc.stderr
    assert not cache.exists()
    first = subprocess.run([sys.executable, "-c", code_run], env=env, **run)
    assert first.returncode == 0, first.stderr
    libs = list((cache / "native").glob("pendulab_native_rigid-*.so"))
    assert len(libs) == 1 and not list((cache / "native").glob(".*"))  # renamed into place, no temporary left
    assert (cache / "native" / f"{libs[0].name}.sha256").is_file()  # its digest beside it
    no_cc = {**env, "PATH": str(tmp_path / "no-bin"), "CC": "no-such-compiler"}
    again = subprocess.run([sys.executable, "-c", code_run], env=no_cc, **run)
    assert again.returncode == 0, again.stderr
    assert again.stdout == first.stdout

"""The Reference FMUs' importer fmusim (C version 0.0.x) runs the FMUs and resumes from a state file.

fmusim is not installable from a package index: build it from the Reference FMUs sources (v0.0.39,
``fmusim/``; see docs/fmu.md) and point ``$PENDULAB_FMUSIM`` at the executable, or put ``fmusim`` on
PATH. Without it the tests skip with that reason.
"""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import pytest

import pendulab as pl

FMUSIM = os.environ.get("PENDULAB_FMUSIM") or shutil.which("fmusim")
pytestmark = pytest.mark.skipif(
    FMUSIM is None or not os.path.isfile(FMUSIM),
    reason="fmusim not available: build it from the Reference FMUs sources (v0.0.39) and set $PENDULAB_FMUSIM",
)
OUTPUTS = ("x1", "y1", "x2", "y2")


def _run(fmu, out, *args: str) -> np.ndarray:
    cmd = [FMUSIM, "--output-interval", "0.01", "--tolerance", "1e-10", *args, "--output-file", str(out), str(fmu)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return np.genfromtxt(out, delimiter=",", names=True)


@pytest.mark.parametrize("interface", ["cs", "me"])
@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_fmusim_agrees_with_the_native_run(fmu_builds, tmp_path, kind, version, interface):
    solver = ["--solver", "cvode"] if interface == "me" else []
    d = _run(fmu_builds[(kind, version)].path, tmp_path / "out.csv", "--interface-type", interface, *solver,
             "--start-value", "theta1", "1.0", "--stop-time", "2")  # fmt: skip
    model = pl.make_model(kind)
    ref = pl.simulate(model, model.state(theta1=1.0), 2.0, dt=0.01, rtol=1e-12, atol=1e-12)
    err = max(np.max(np.abs(np.interp(ref.t, d["time"], d[n]) - ref[n])) for n in OUTPUTS)
    # CS: embedded solver at 1e-10 (measured 1.9e-10); ME: fmusim's CVode at rtol 1e-10 (measured 1.6e-8)
    assert err < (1e-8 if interface == "cs" else 1e-6)


@pytest.mark.parametrize("version", [2, 3])
def test_fmusim_resumes_from_a_state_file(fmu_builds, tmp_path, version):
    fmu = fmu_builds[("elastic", version)].path
    full = _run(fmu, tmp_path / "full.csv", "--start-value", "theta1", "1.0", "--stop-time", "2")
    state = tmp_path / "state.bin"
    _run(fmu, tmp_path / "a.csv", "--start-value", "theta1", "1.0", "--stop-time", "1", "--final-fmu-state-file", str(state))
    # a fresh instance: instantiate -> restore the serialized state -> step (no initialization calls)
    resumed = _run(fmu, tmp_path / "b.csv", "--start-time", "1", "--stop-time", "2", "--initial-fmu-state-file", str(state))
    # same solver state and communication points; fmusim recomputes the time grid from 1 s (rounding of t only)
    np.testing.assert_allclose([resumed[n][-1] for n in OUTPUTS], [full[n][-1] for n in OUTPUTS], atol=1e-13)


@pytest.mark.parametrize("args", [["--interface-type", "me", "--solver", "cvode"], ["--interface-type", "cs", "--event-mode-used",
                                  "--early-return-allowed"]])  # fmt: skip
def test_fmusim_stops_at_the_flips(tmp_path, args):
    from pendulab.fmu import export

    model = pl.rigid()
    x0 = model.state(theta1=2.0, theta2=2.0, omega2=6.0)
    fmu = export(model, tmp_path / "flip.fmu", 3, timestamp=False, x0=x0, flip_events=True)
    d = _run(fmu, tmp_path / "out.csv", *args, "--stop-time", "3", "--output-variable", "flip_margin2")
    at_event = np.unique(d["time"][np.abs(d["flip_margin2"]) < 1e-8])
    ref = pl.simulate(model, x0, 3.0, dt=1e-5, rtol=1e-12, atol=1e-12)
    z = np.pi - np.abs(ref["theta2"])
    k = np.nonzero(np.sign(z[1:]) != np.sign(z[:-1]))[0]
    native = ref.t[k] + z[k] / (z[k] - z[k + 1]) * (ref.t[k + 1] - ref.t[k])
    np.testing.assert_allclose(at_event, native, atol=1e-6)  # CVode / embedded solver at 1e-10, non-chaotic 3 s


@pytest.mark.parametrize("interface", ["cs", "me"])
def test_fmusim_stops_at_a_collapsing_spring(tmp_path, interface):
    from pendulab.fmu import export

    model = pl.elastic(k1=50.0, k2=50.0)
    fmu = export(model, tmp_path / "soft.fmu", 3, timestamp=False, x0=model.state(theta1=0.0, v1=-10.0))
    extra = ["--solver", "cvode"] if interface == "me" else ["--early-return-allowed"]
    d = _run(fmu, tmp_path / "out.csv", "--interface-type", interface, *extra, "--stop-time", "1", "--output-variable", "r1")
    # spring 1 reaches 0.1 L1 at ~0.1586 s: the run ends there (ME at the located event, CS within h/64 before it)
    assert 0.158 < d["time"][-1] < 0.1587 and d["r1"][-1] >= 0.1 - 1e-9

"""Run the modes and LQR examples briefly."""

import importlib.util
import math
from pathlib import Path

import numpy as np

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_inspect_modes_example(tmp_path):
    result = _load("inspect_modes").run(names=("down-down",), out_dir=tmp_path)
    w = sorted(m.omega_n for m in result["modes"][("rigid", "down-down")])
    # Default rigid pendulum: m = L = 1, so omega^2 = (2 -+ sqrt 2) g.
    np.testing.assert_allclose(np.square(w), [(2 - math.sqrt(2)) * 9.81, (2 + math.sqrt(2)) * 9.81], rtol=1e-12)
    assert {p.name for p in result["figures"]} == {
        "modes_rigid_down-down.png",
        "modes_elastic_down-down.png",
        "modes_frequency_vs_stiffness.png",
    }


def test_balance_lqr_example(tmp_path):
    result = _load("balance_lqr").run(kinds=("rigid",), actuations=("pendubot",), t_final=4.0, roa=False, out_dir=tmp_path)
    traj = result["trajectories"][("rigid", "pendubot")]
    # From 0.1 rad off upright the LQR loop (slowest pole -2.3/s) is back within 1e-3 rad after 4 s.
    assert np.abs(traj.x[-1, :2] - np.pi).max() < 1e-3
    assert result["figure"].exists()

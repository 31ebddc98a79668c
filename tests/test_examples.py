"""Every script in examples/ runs briefly through its ``run()``.

Convention: ``run(*, ...)`` is called with the module's ``TEST_KWARGS`` (a dict)
when it defines one, otherwise with no arguments; the examples below also get
their returned data checked.
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.py"))


def load(path):
    spec = importlib.util.spec_from_file_location(f"example_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _param(path):
    # Examples that export an FMU need a C compiler (tests/conftest.py skips them without one).
    marks = [pytest.mark.needs_cc] if "pendulab.fmu" in path.read_text() else []
    return pytest.param(path, marks=marks, id=path.stem)


@pytest.mark.parametrize("path", [_param(p) for p in EXAMPLES])
def test_example_runs(path):
    module = load(path)
    assert module.__doc__ and callable(module.run) and callable(module.main)
    module.run(**getattr(module, "TEST_KWARGS", {}))


def test_simulate_seed_paper_result(tmp_path):
    result = load(Path(__file__).resolve().parent.parent / "examples" / "simulate_seed_paper.py").run(
        t_final=2.0, out_dir=tmp_path
    )
    assert len(list(tmp_path.glob("*.png"))) == 7
    (rigid, tr), (elastic, te) = result["rigid"], result["elastic"]
    # Identical start by construction (springs at rest length): positions agree to rounding.
    np.testing.assert_allclose(rigid.positions(tr.x[0]), elastic.positions(te.x[0]), rtol=0, atol=1e-14)
    assert result["energy_drift"] < 1e-7  # rtol = atol = 1e-10 over 2 s
    assert result["max_angle_gap"] > 1e-3  # the springs change the motion


def test_compare_stiffness_rigid_limit():
    result = load(Path(__file__).resolve().parent.parent / "examples" / "compare_stiffness.py").run(
        stiffnesses=(1e2, 1e3, 1e4), t_final=1.0
    )
    err = result["error"]
    # Stiffer springs, closer to rigid: the error falls roughly as 1/k, so at least 5x per decade.
    assert np.all(err[1:] < err[:-1] / 5.0)

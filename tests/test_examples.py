"""Every script in examples/ runs briefly through its ``run()``.

Convention: ``run(*, ...)`` is called with the brief settings of :data:`BRIEF` (smaller
horizons, fewer cases) when the example has an entry there, otherwise with its defaults; the
examples below also get their returned data checked. The settings live here, not in the
examples: the gallery shows an example's code as a user would write it (no test plumbing).
"""

import importlib.util
import runpy
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "examples").glob("*.py"))
#: Keyword arguments of each example's brief run in the suite (the full runs are the docs build's).
BRIEF = {
    "balance_lqr": {"kinds": ("rigid",), "actuations": ("pendubot",), "t_final": 2.0, "roa": False},
    "check_scene": {"repeats": 1},
    "inspect_modes": {"names": ("down-down",)},
    "gym_random_policy": {"episode_length": 2.0, "episodes": 1},
    "solve_swingup": {"N": 40},
}


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
    module.run(**BRIEF.get(path.stem, {}))


def test_examples_show_no_test_plumbing_and_write_where_the_gallery_looks():
    """The gallery renders each example's code and the PNGs its ``main()`` wrote into docs/_ext/gallery_hooks.py's
    ``EXAMPLE_OUTPUTS`` folders (tests/test_docs_site.py checks every page has a figure)."""
    outputs = runpy.run_path(str(ROOT / "docs" / "_ext" / "gallery_hooks.py"))["EXAMPLE_OUTPUTS"]
    assert set(BRIEF) <= {p.stem for p in EXAMPLES}
    for path in EXAMPLES:
        text = path.read_text()
        assert not [w for w in ("TEST_KWARGS", "PYTHONPATH", "tests/", "pytest") if w in text], path.name
        assert any(f'"{d}"' in text for d in outputs), f"{path.name} writes no figure into EXAMPLE_OUTPUTS"


def test_simulate_seed_paper_result(tmp_path):
    result = load(ROOT / "examples" / "simulate_seed_paper.py").run(t_final=2.0, out_dir=tmp_path)
    assert len(list(tmp_path.glob("*.png"))) == 7
    (rigid, tr), (elastic, te) = result["rigid"], result["elastic"]
    # Identical start by construction (springs at rest length): positions agree to rounding.
    np.testing.assert_allclose(rigid.positions(tr.x[0]), elastic.positions(te.x[0]), rtol=0, atol=1e-14)
    assert result["energy_drift"] < 1e-7  # rtol = atol = 1e-10 over 2 s
    assert result["max_angle_gap"] > 1e-3  # the springs change the motion


def test_compare_stiffness_rigid_limit():
    result = load(ROOT / "examples" / "compare_stiffness.py").run(stiffnesses=(1e2, 1e3, 1e4), t_final=1.0)
    err = result["error"]
    # Stiffer springs, closer to rigid: the error falls roughly as 1/k, so at least 5x per decade.
    assert np.all(err[1:] < err[:-1] / 5.0)

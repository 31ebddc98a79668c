"""The FMU example runs and its FMU passes validation."""

from __future__ import annotations

import importlib.util
from pathlib import Path


def test_export_fmu_example_runs(tmp_path):
    path = Path(__file__).parents[2] / "examples" / "export_fmu.py"
    spec = importlib.util.spec_from_file_location("export_fmu_example", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    result = mod.run(kind="rigid", fmi_version=2, scenes=("rigid_chaotic_forced",), out_dir=tmp_path)
    assert result["passed"] and result["max_error"] < 1e-5  # the scene's stated bound
    assert result["plot"].exists() and result["fmu"].exists()

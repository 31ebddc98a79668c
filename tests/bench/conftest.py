"""Fixtures of the benchmark scripts' tests."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="module")
def bench(request: pytest.FixtureRequest):
    """The benchmark script named by the test module's ``BENCHMARK`` (a file stem in ``benchmarks/``), imported."""
    name = request.module.BENCHMARK
    spec = importlib.util.spec_from_file_location(name, BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses of the script resolve their module
    spec.loader.exec_module(module)
    yield module
    sys.modules.pop(spec.name, None)

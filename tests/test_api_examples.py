"""Every function and class on the API reference pages has an ``Examples`` section, and its examples run.

The reference pages list each documented package's ``__all__`` (docs/conf.py, ``API_PACKAGES``); the
docstrings of the functions and classes listed there are run as doctests here (``ELLIPSIS`` and
``NORMALIZE_WHITESPACE``; the names ``pl`` = pendulab and ``np`` = numpy are predefined, as the examples
import them themselves too). Each example runs in a fresh temporary working directory, so an example may
write files into ``.``. Constants (strings, tuples, registries) are documented by their module, not here.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import runpy
from pathlib import Path

import numpy as np
import pytest

import pendulab

ROOT = Path(__file__).resolve().parents[1]


def _documented_objects() -> list[tuple[str, object]]:
    packages = runpy.run_path(str(ROOT / "docs" / "conf.py"), run_name="pendulab_docs_conf")["API_PACKAGES"]
    seen: set[int] = set()
    out = []
    for package in packages:
        module = importlib.import_module(package)
        for name in sorted(getattr(module, "__all__", []), key=str.lower):
            obj = getattr(module, name)
            if id(obj) in seen or not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            seen.add(id(obj))
            out.append((f"{package}.{name}", obj))
    return out


DOCUMENTED = _documented_objects()


def test_the_reference_lists_the_documented_api():
    names = {n for n, _ in DOCUMENTED}
    assert "pendulab.simulate" in names and "pendulab.fmu.export" in names  # the list is the reference, not empty
    assert len(DOCUMENTED) > 100


@pytest.mark.parametrize(("name", "obj"), DOCUMENTED, ids=[n for n, _ in DOCUMENTED])
def test_examples_section_runs(name, obj, tmp_path, monkeypatch):
    doc = inspect.getdoc(obj) or ""
    assert "\nExamples\n--------\n" in doc, f"{name}: no Examples section"
    tests = [t for t in doctest.DocTestFinder(recurse=False).find(obj, name, globs={"pl": pendulab, "np": np}) if t.examples]
    assert tests, f"{name}: the Examples section has no >>> example"
    monkeypatch.chdir(tmp_path)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report: list[str] = []
    for test in tests:
        runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)[-4000:]

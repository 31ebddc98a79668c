"""The public API is documented like python-control's: numpydoc sections checked by numpydoc's validator.

Public = every function and class named in the ``__all__`` of a public module
(no underscore in its path; the CLI's ``commands`` and the deprecation shims
excluded), and the public methods of those classes. Rules:

* a docstring (numpydoc GL08);
* every parameter documented, none unknown (PR01, PR02); for a dataclass the
  fields may be documented under ``Attributes`` instead of ``Parameters``;
* a ``Returns`` (or ``Yields``) section when the function returns a value (RT01);
* a ``Raises`` section when the function itself raises (a ``raise`` statement
  in its body, outside nested functions).
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pkgutil
import textwrap

import pytest

import pendulab

numpydoc_validate = pytest.importorskip("numpydoc.validate", reason="numpydoc is in the test extra: pip install -e '.[test]'")

SKIP_MODULES = ("pendulab.commands", "pendulab.control.sampled", "pendulab.control.tracking_sampled")
CODES = ("GL08", "PR01", "PR02", "RT01")


def _public_objects() -> list[tuple[str, object]]:
    out: dict[str, object] = {}
    for info in pkgutil.walk_packages(pendulab.__path__, "pendulab."):
        name = info.name
        if any(p.startswith("_") for p in name.split(".")[1:]) or name.startswith(SKIP_MODULES):
            continue
        module = importlib.import_module(name)
        for attr in getattr(module, "__all__", ()):
            obj = getattr(module, attr)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)) or obj.__module__ != name:
                continue
            out[f"{name}.{attr}"] = obj
            if inspect.isclass(obj):
                for meth, value in vars(obj).items():
                    if not meth.startswith("_") and inspect.isfunction(value):
                        out[f"{name}.{attr}.{meth}"] = value
    return sorted(out.items())


def _raises_itself(func: object) -> bool:
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return False
    body = tree.body[0]

    def walk(node: ast.AST) -> bool:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                continue
            if isinstance(child, ast.Raise) or walk(child):
                return True
        return False

    return walk(body)


def _problems(qualname: str, obj: object) -> list[str]:
    result = numpydoc_validate.validate(qualname)
    errors = [(code, msg) for code, msg in result["errors"] if code in CODES]
    doc = inspect.getdoc(obj) or ""
    if inspect.isclass(obj) and dataclasses.is_dataclass(obj) and "Attributes\n----------" in doc:
        # Fields documented as attributes count as documented parameters.
        section = doc.split("Attributes\n----------", 1)[1]
        documented = {
            name.strip()
            for line in section.splitlines()
            if line and not line.startswith(" ")
            for name in line.split(" :")[0].split(",")
        }
        missing = sorted(f.name for f in dataclasses.fields(obj) if f.init and f.name not in documented)
        errors = [(c, m) for c, m in errors if c != "PR01"]
        if missing:
            errors.append(("PR01", f"fields not documented under Attributes: {missing}"))
    if inspect.isfunction(obj) and _raises_itself(obj) and "Raises\n------" not in doc:
        errors.append(("RAISES", "raises but has no Raises section"))
    return [f"{code}: {msg}" for code, msg in errors]


OBJECTS = _public_objects()


def test_public_api_is_found():
    names = [n for n, _ in OBJECTS]
    # The anchors of the minimum public surface (DESIGN.md) are in the checked set.
    for anchor in ("pendulab.integrate.simulate.simulate", "pendulab.model.model.Model", "pendulab.analysis.linearize.linearize"):
        assert anchor in names
    assert len(names) > 150


@pytest.mark.parametrize(("qualname", "obj"), OBJECTS, ids=[n for n, _ in OBJECTS])
def test_numpydoc_sections(qualname, obj):
    assert _problems(qualname, obj) == []

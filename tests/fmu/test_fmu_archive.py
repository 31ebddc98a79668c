"""Every archive carries documentation/index.html (model, variables with units and ranges, solvers, limits) and a license."""

from __future__ import annotations

import zipfile
from html.parser import HTMLParser

import pytest


class _Table(HTMLParser):
    """Collects the rows of the page's tables (cell texts) and checks that tags balance."""

    VOID = {"meta", "br", "img", "hr", "link", "input"}

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[list[str]] = []
        self.stack: list[str] = []
        self.ids: set[str] = set()
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag not in self.VOID:
            self.stack.append(tag)
        self.ids.update(v for k, v in attrs if k == "id")
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        assert self.stack and self.stack[-1] == tag, f"unbalanced </{tag}> (open: {self.stack[-3:]})"
        self.stack.pop()
        if tag in ("td", "th") and self._cell is not None:
            self.rows[-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_documentation_lists_every_variable_with_unit_and_range(fmu_builds, kind, version):
    built = fmu_builds[(kind, version)]
    with zipfile.ZipFile(built.path) as zf:
        page = zf.read("documentation/index.html").decode()
        license_text = zf.read("documentation/licenses/license.txt").decode()
    parser = _Table()
    parser.feed(page)
    parser.close()
    assert parser.stack == []  # parseable, balanced HTML
    assert {"model", "variables", "solvers", "limits"} <= parser.ids
    header, *rows = parser.rows
    assert header[:3] == ["name", "value reference", "causality"]
    doc = {r[0]: dict(zip(header, r, strict=True)) for r in rows}
    variables = built.md.modelVariables
    assert set(doc) == {v.name for v in variables}  # every variable, nothing else
    for v in variables:
        row = doc[v.name]
        assert int(row["value reference"]) == v.valueReference
        assert row["unit"] == (v.unit or "") and row["min"] == (v.min or "") and row["max"] == (v.max or "")
    for word in ("dopri5", "rodas4", "solver_tolerance", "100,000 internal solver steps", "Lagrange"):
        assert word in page
    # the license file covers pendulab (MIT), the FMI headers (BSD-2) and CasADi's generated code
    assert "MIT License" in license_text and "2-Clause BSD License" in license_text and "CasADi" in license_text

"""docs/fmu.md's feature table is true for pendulab: each checkable row against an exported FMU.

Rows name a check in their second column: ``@Element.attr`` (an attribute of the FMI 3 plant FMU's
modelDescription.xml: "true" or a positive number is a yes, missing / "false" / 0 a no), ``file:path``
(an archive entry), ``element:Tag`` (a child of the root), ``version:N`` (export writes FMI N); an ``elastic:``
or ``flips:`` prefix checks the elastic FMU or the rigid one exported with flip events instead of the default
rigid one. The pendulab column must start with "yes" or "no" where there is a check.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

DOC = Path(__file__).parents[2] / "docs" / "fmu.md"
HEADER = "| feature | check | pendulab | Reference FMUs 0.0.39 | OpenModelica (C runtime) |"


def _rows() -> list[tuple[str, str, str]]:
    text = DOC.read_text()
    assert HEADER in text, "the feature table's header changed: update this test"
    rows = []
    for line in text[text.index(HEADER) :].splitlines()[2:]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip("|").split("|")]
        check = cells[1].strip("`")
        if check:
            rows.append((cells[0], check, cells[2]))
    return rows


ROWS = _rows()


def _claim(cell: str) -> bool:
    word = re.match(r"(yes|no)\b", cell)
    assert word, f"pendulab cell must start with yes or no where a check is given, got {cell!r}"
    return word.group(1) == "yes"


def _true(value: str | None) -> bool:
    if value is None or value == "false":
        return False
    if value == "true":
        return True
    return float(value) > 0


def test_the_table_has_checkable_rows():
    assert len(ROWS) >= 15  # the capability flags, interfaces, versions and archive entries


@pytest.fixture(scope="module")
def flips_fmu(tmp_path_factory) -> Path:
    import pendulab as pl
    from pendulab.fmu import export

    return export(pl.rigid(), tmp_path_factory.mktemp("flips") / "rigid_flips.fmu", 3, timestamp=False, flip_events=True)


@pytest.mark.parametrize(("feature", "check", "cell"), ROWS, ids=[r[0] for r in ROWS])
def test_pendulab_column_is_true(fmu_builds, flips_fmu, feature, check, cell):
    variant, sep, rest = check.partition(":")
    if sep and variant in ("elastic", "flips"):
        check = rest
    else:
        variant = "rigid"
    path = flips_fmu if variant == "flips" else fmu_builds[(variant, 3)].path
    with zipfile.ZipFile(path) as z:
        names = set(z.namelist())
        root = ET.fromstring(z.read("modelDescription.xml"))
    kind, _, what = check.partition(":")
    if check.startswith("@"):
        element, attr = check[1:].split(".")
        el = root.find(element)
        actual = el is not None and _true(el.get(attr))
    elif kind == "file":
        actual = what in names
    elif kind == "element":
        actual = root.find(what) is not None
    elif kind == "version":
        actual = fmu_builds[("rigid", int(what))].md.fmiVersion.startswith(what)
    else:
        raise AssertionError(f"unknown check {check!r} in docs/fmu.md's feature table")
    assert actual == _claim(cell), f"docs/fmu.md says pendulab {cell!r} for {feature!r}, the FMU says {actual}"

"""Linux binaries need at most the glibc their documentation states (manylinux2014's 2.17 when built with Zig).

``objdump -T`` lists the versioned symbols a shared library binds to (``pow`` is ``GLIBC_2.29`` when built by
the system gcc against glibc >= 2.29, ``GLIBC_2.2.5`` when built by ``zig cc -target x86_64-linux-gnu.2.17``).
The highest ``GLIBC_x.y`` must equal the requirement written into ``documentation/index.html`` (read from the
file at export), and with Zig installed (no ``$CC``) be at most 2.17, the baseline docs/fmu.md promises.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from pendulab.fmu.controller_export import design_controller, export_controller
from pendulab.fmu.platforms import GLIBC_BASELINE, glibc_versions, host_platform, portable_host_compiler

pytestmark = [
    pytest.mark.skipif(shutil.which("objdump") is None, reason="objdump (binutils) is not installed"),
    pytest.mark.skipif(not host_platform().endswith("-linux"), reason="glibc symbol versions: Linux binaries only"),
]

DOCS = Path(__file__).resolve().parents[2] / "docs" / "fmu.md"


def _objdump_glibc(lib: Path) -> tuple[int, ...]:
    out = subprocess.run(["objdump", "-T", str(lib)], capture_output=True, text=True, check=True).stdout
    versions = {tuple(int(p) for p in v.split(".")) for v in re.findall(r"\(?GLIBC_(\d+(?:\.\d+)+)\)?\s", out)}
    assert versions, out[:2000]
    return max(versions)


def _check_archive(path: Path, tmp: Path) -> tuple[int, ...]:
    with zipfile.ZipFile(path) as zf:
        names = [n for n in zf.namelist() if n.startswith("binaries/") and n.endswith(".so")]
        page = zf.read("documentation/index.html").decode()
        assert len(names) == 1, names
        data = zf.read(names[0])
    lib = tmp / Path(names[0]).name
    lib.write_bytes(data)
    highest = _objdump_glibc(lib)
    assert max(glibc_versions(data)) == highest  # pendulab's reader agrees with objdump
    documented = re.search(rf"<code>{re.escape(names[0])}</code>: needs glibc &gt;= ([\d.]+)", page)
    assert documented, page
    assert highest == tuple(int(p) for p in documented.group(1).split("."))  # the page states what the file needs
    if portable_host_compiler() is not None:  # built by zig cc -target x86_64-linux-gnu.2.17
        assert highest <= GLIBC_BASELINE, highest
    return highest


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_plant_binary_needs_at_most_the_documented_glibc(fmu_builds, kind, version, tmp_path):
    _check_archive(fmu_builds[(kind, version)].path, tmp_path)


@pytest.mark.parametrize(("name", "version"), [("swingup", 2), ("lqr", 3)])
def test_controller_binary_needs_at_most_the_documented_glibc(name, version, tmp_path):
    ctrl, _x0, _model = design_controller(name)
    path = export_controller(ctrl, tmp_path / f"{name}{version}.fmu", version, timestamp=False)
    _check_archive(path, tmp_path)


def test_docs_state_the_baseline():
    text = DOCS.read_text()
    assert "glibc 2.17" in text and "GLIBC_2.29" in text and "objdump -T" in text
    assert "api-ms-win-crt" in text and "KB2999226" in text  # the Windows runtime requirement

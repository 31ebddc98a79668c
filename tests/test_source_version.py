"""The code identity journals are stamped with: it changes with every file that runs, and with nothing else."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import pendulab
from pendulab._version import source_digest, source_version


def _tree(root: Path) -> Path:
    (root / "sub").mkdir(parents=True)
    (root / "__init__.py").write_text("X = 1\n")
    (root / "sub" / "model.py").write_text("K = 2.0\n")
    (root / "sub" / "plans.npz").write_bytes(b"\x00\x01\x02")
    (root / "sub" / "step.c").write_text("int f(void) { return 0; }\n")
    return root


@pytest.mark.parametrize(
    "change",
    [
        lambda r: (r / "sub" / "model.py").write_text("K = 2.5\n"),  # a constant edited
        lambda r: (r / "sub" / "plans.npz").write_bytes(b"\x00\x01\x03"),  # shipped data changed
        lambda r: (r / "sub" / "step.c").write_text("int f(void) { return 1; }\n"),  # the FMU's C source
        lambda r: (r / "sub" / "extra.py").write_text(""),  # a module added
        lambda r: (r / "sub" / "model.py").unlink(),  # a module removed
        lambda r: (r / "sub" / "model.py").rename(r / "model.py"),  # moved, same content
    ],
    ids=["edit", "data", "c-source", "add", "remove", "rename"],
)
def test_every_change_to_what_runs_changes_the_digest(tmp_path, change):
    root = _tree(tmp_path / "pkg")
    before = source_digest(root)
    assert source_digest(_tree(tmp_path / "twin")) == before  # the same files elsewhere: the same code
    change(root)
    assert source_digest(root) != before


def test_byte_code_and_stray_files_do_not_count(tmp_path):
    root = _tree(tmp_path / "pkg")
    before = source_digest(root)
    (root / "__pycache__").mkdir()
    (root / "__pycache__" / "model.cpython-311.pyc").write_bytes(b"\x00" * 8)
    (root / "__pycache__" / "stale.py").write_text("")  # even a .py under __pycache__ never runs as a module
    (root / "sub" / ".model.py.swp").write_bytes(b"editor")
    (root / "sub" / "model.py~").write_text("K = 9\n")
    assert source_digest(root) == before


def test_the_running_package_is_stamped_with_its_release_and_its_source(tmp_path):
    version = source_version()
    release, _, src = version.partition("+src.")
    assert release == pendulab.__version__ and len(src) == 16
    package = Path(pendulab.__file__).parent
    assert source_digest(package).startswith(src)
    # A copy of the installed package with one constant changed is other code under the same release number.
    copy = tmp_path / "pendulab"
    shutil.copytree(package, copy, ignore=shutil.ignore_patterns("__pycache__"))
    assert source_digest(copy) == source_digest(package)
    spec = copy / "control" / "realai" / "spec.py"
    edited = spec.read_text().replace("TORQUE_LIMIT: float = 6.0", "TORQUE_LIMIT: float = 5.0")
    assert edited != spec.read_text()  # the constant is there to edit
    spec.write_text(edited)
    assert source_digest(copy) != source_digest(package)


def test_a_study_case_of_other_code_reads_as_not_run(tmp_path, monkeypatch):
    # A benchmark resumed after an edit must run its cases again, never report the old code's results as this code's.
    import pendulab._journal as journal

    path = journal.write_case(tmp_path / "cases" / "acrobot-seed0.json", {"score": 0.61, "calls": [0.3, 0.4]})
    assert journal.read_case(path) == {"score": 0.61, "calls": [0.3, 0.4], "code_version": source_version()}
    monkeypatch.setattr(journal, "source_version", lambda: pendulab.__version__ + "+src.0123456789abcdef")
    assert journal.read_case(path) is None  # same release, other source
    monkeypatch.undo()
    path.write_text('{"score": 0.61')  # a torn write
    assert journal.read_case(path) is None
    assert journal.read_case(tmp_path / "missing.json") is None
    path.write_text('{"score": 0.61}')  # a case kept before cases were stamped
    assert journal.read_case(path) is None

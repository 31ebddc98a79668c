"""Docs that run: every ```python block in README.md and docs/**/*.md runs as written.

Rules (what a doc author needs to know):

* **What runs.** Every fenced block whose info string is ``python`` (also
  ``py`` / ``python3``) is a test, named ``FILE:LINE`` (the line of the opening
  fence). A block that is not meant to run (a sketch, shell commands, output,
  a directory listing) must not be marked python: use ```text, ```console,
  ```bash or a plain fence.
* **One file is one notebook.** The python blocks of one file run in order in
  one shared namespace (a fresh one per file, ``__name__ == "__main__"``), so a
  later block may use the names an earlier block defined. Blocks of different
  files never share anything. Under pytest-xdist a block may land on a worker
  that has not run the file's earlier blocks; it then replays them first, so
  the result does not depend on the distribution.
* **Where it runs.** In a temporary working directory, one per file (shared
  by that file's blocks, so a later block can read what an earlier one wrote),
  with matplotlib's non-interactive Agg backend; figures are closed after each block.
* **C compiler.** A block that uses ``pendulab.fmu`` (export builds C code;
  validation and co-simulation need the exported FMU), or that says so with a
  ``# needs-cc`` comment (e.g. one that drives an FMU an earlier step built
  without naming ``pendulab.fmu``), needs a C compiler. It
  carries the suite's ``needs_cc`` marker (see ``tests/conftest.py``) and is
  skipped, with the reason, when no compiler is found (``$CC``, ``cc``,
  ``gcc`` or ``clang`` on PATH, as :func:`pendulab.fmu.export.find_compiler`
  looks for one) or ``PENDULAB_TEST_NO_CC=1`` is set. A later block of the same
  file depends on the earlier ones, so it is skipped with them.
* **No deprecated names.** A pendulab ``DeprecationWarning`` ("... is
  deprecated; use ...") raised by a block is an error: docs show the current API.
* **Fast.** Keep every block short (a few seconds): fewer points, a shorter
  horizon, a coarser grid than a real study, while staying meaningful. The
  whole file runs in well under a minute with ``pytest -n 2``.
"""

from __future__ import annotations

import os
import re
import shutil
import textwrap
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC_FILES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
PYTHON_INFO = {"python", "py", "python3"}
# A block needs a C compiler when it uses the FMU package (export compiles C code) or says so.
NEEDS_CC = re.compile(r"\bpendulab\.fmu\b|#\s*needs-cc\b")

_FENCE_OPEN = re.compile(r"^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})(?P<info>.*)$")


@dataclass(frozen=True)
class Block:
    path: Path
    line: int  # 1-based line of the opening fence
    source: str
    index: int  # position among the python blocks of its file

    @property
    def name(self) -> str:
        path = self.path.relative_to(ROOT).as_posix() if self.path.is_relative_to(ROOT) else str(self.path)
        return f"{path}:{self.line}"

    @property
    def needs_cc(self) -> bool:
        return bool(NEEDS_CC.search(self.source))


def fenced_blocks(path: Path) -> list[tuple[int, str, str]]:
    """``(line, info word, source)`` of every fenced code block of a Markdown file (CommonMark fences)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    blocks: list[tuple[int, str, str]] = []
    i = 0
    while i < len(lines):
        m = _FENCE_OPEN.match(lines[i])
        if m is None or (m["fence"][0] == "`" and "`" in m["info"]):
            i += 1
            continue
        fence, indent = m["fence"], len(m["indent"])
        info = m["info"].strip().split()[0].lower() if m["info"].strip() else ""
        close = re.compile(rf"^ {{0,3}}{re.escape(fence[0])}{{{len(fence)},}}\s*$")
        j = i + 1
        while j < len(lines) and not close.match(lines[j]):
            j += 1
        if j == len(lines):
            raise ValueError(f"{path}:{i + 1}: code fence {fence!r} is never closed")
        body = [ln[min(indent, len(ln) - len(ln.lstrip(" "))) :] for ln in lines[i + 1 : j]]
        blocks.append((i + 1, info, "\n".join(body) + "\n"))
        i = j + 1
    return blocks


def python_blocks(path: Path) -> list[Block]:
    found = [(line, src) for line, info, src in fenced_blocks(path) if info in PYTHON_INFO]
    return [Block(path, line, textwrap.dedent(src), k) for k, (line, src) in enumerate(found)]


BLOCKS = {path: python_blocks(path) for path in DOC_FILES}
ALL_BLOCKS = [b for blocks in BLOCKS.values() for b in blocks]


def compiler_missing() -> str | None:
    """Why C code cannot be built here (None when a compiler is found); the rule of tests/conftest.py."""
    if os.environ.get("PENDULAB_TEST_NO_CC") == "1":
        return "PENDULAB_TEST_NO_CC=1 is set"
    tried = [c for c in (os.environ.get("CC"), "cc", "gcc", "clang") if c]
    if any(shutil.which(c) for c in tried):
        return None
    return f"no C compiler found (tried {tried})"


def _param(block: Block):
    cc = any(b.needs_cc for b in BLOCKS[block.path][: block.index + 1])
    return pytest.param(block, marks=[pytest.mark.needs_cc] if cc else [], id=block.name)


@dataclass
class Notebook:
    """The shared state of one file's blocks: namespace, working directory, blocks run so far."""

    namespace: dict
    workdir: Path
    done: int = 0
    failed: str | None = None


_NOTEBOOKS: dict[Path, Notebook] = {}


def _run(block: Block, nb: Notebook) -> None:
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    # Pad with newlines so that tracebacks point at the line in the Markdown file.
    code = compile("\n" * block.line + block.source, str(block.path), "exec")
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", message=r".*is deprecated; use", category=DeprecationWarning)
            exec(code, nb.namespace)  # noqa: S102 - running the documentation is the point
    finally:
        plt.close("all")


def run_in_notebook(
    block: Block,
    file_blocks: list[Block],
    notebooks: dict[Path, Notebook],
    new_workdir: Callable[[], Path],
    chdir: Callable[[Path], None],
) -> None:
    """Run ``block`` in its file's notebook, first replaying the file's earlier blocks if this process has not run them."""
    nb = notebooks.get(block.path)
    if nb is not None and nb.failed:
        pytest.skip(f"earlier block {nb.failed} failed")
    if nb is None or nb.done != block.index:
        # First block of the file in this process, or the earlier ones ran elsewhere: start the notebook over.
        nb = notebooks[block.path] = Notebook({"__name__": "__main__"}, new_workdir())
        chdir(nb.workdir)  # files the blocks write land here
        for b in file_blocks[: block.index]:
            try:
                _run(b, nb)
            except Exception as exc:  # reported as the failure of that block's own test
                nb.failed = b.name
                pytest.skip(f"earlier block {b.name} failed: {type(exc).__name__}: {exc}")
            nb.done += 1
    else:
        chdir(nb.workdir)
    try:
        _run(block, nb)
    except BaseException:
        nb.failed = block.name
        raise
    nb.done += 1


@pytest.mark.parametrize("block", [_param(b) for b in ALL_BLOCKS])
def test_doc_block_runs(block: Block, tmp_path_factory, monkeypatch):
    file_blocks = BLOCKS[block.path]
    reason = compiler_missing()
    if reason and any(b.needs_cc for b in file_blocks[: block.index + 1]):
        pytest.skip(f"needs a C compiler to build the FMU: {reason}")

    def new_workdir() -> Path:
        return tmp_path_factory.mktemp(re.sub(r"\W", "_", block.path.stem))

    run_in_notebook(block, file_blocks, _NOTEBOOKS, new_workdir, monkeypatch.chdir)


def test_docs_have_python_blocks():
    # The collector finds the blocks (a broken parser would silently test nothing).
    assert len(ALL_BLOCKS) >= 8, [b.name for b in ALL_BLOCKS]
    assert BLOCKS[ROOT / "README.md"], "README.md has no python block"


def test_fence_parser(tmp_path):
    src = "text\n```python\nx = 1\n```\n\n````markdown\n```python\nnot a block\n```\n````\n  ```py\n  y = 2\n  ```\n~~~\nz\n~~~\n"
    path = tmp_path / "sample.md"
    path.write_text(src, encoding="utf-8")
    assert fenced_blocks(path) == [
        (2, "python", "x = 1\n"),
        (6, "markdown", "```python\nnot a block\n```\n"),
        (11, "py", "y = 2\n"),
        (14, "", "z\n"),
    ]


def _sample_notebook(tmp_path: Path) -> list[Block]:
    doc = tmp_path / "doc.md"
    doc.write_text(
        "```python\nfrom pathlib import Path\nx = 41\nPath('out.txt').write_text('hi')\n```\n\nText.\n\n"
        "```python\nassert x + 1 == 42 and Path('out.txt').read_text() == 'hi'\n```\n",
        encoding="utf-8",
    )
    return python_blocks(doc)


def test_blocks_of_a_file_share_names_and_directory(tmp_path, monkeypatch):
    blocks = _sample_notebook(tmp_path)
    dirs = iter(tmp_path / d for d in ("a", "b", "c"))

    def new_workdir() -> Path:
        d = next(dirs)
        d.mkdir()
        return d

    notebooks: dict[Path, Notebook] = {}
    for b in blocks:  # in order, as on one worker
        run_in_notebook(b, blocks, notebooks, new_workdir, monkeypatch.chdir)
    assert notebooks[blocks[0].path].done == 2 and (tmp_path / "a" / "out.txt").exists()
    # The second block alone (as on a worker that did not run the first): the first one is replayed.
    notebooks = {}
    run_in_notebook(blocks[1], blocks, notebooks, new_workdir, monkeypatch.chdir)
    assert notebooks[blocks[0].path].done == 2 and (tmp_path / "b" / "out.txt").exists()
    # A fresh notebook (another file) does not see the names.
    with pytest.raises(NameError):
        _run(blocks[1], Notebook({"__name__": "__main__"}, tmp_path / "c"))


def test_needs_cc_marker(tmp_path):
    doc = tmp_path / "cc.md"
    doc.write_text(
        "```python\nfrom pendulab.fmu import export\n```\n```python\nx = 1  # needs-cc\n```\n```python\nx = 2\n```\n",
        encoding="utf-8",
    )
    assert [b.needs_cc for b in python_blocks(doc)] == [True, True, False]


def test_deprecated_name_in_a_block_is_an_error(tmp_path):
    doc = tmp_path / "old.md"
    doc.write_text("```python\nfrom pendulab.control import sampled\nsampled.make_controller\n```\n", encoding="utf-8")
    with pytest.raises(DeprecationWarning, match="is deprecated; use"):
        _run(python_blocks(doc)[0], Notebook({"__name__": "__main__"}, tmp_path))


# -- docs that count: the numbers the docs state match what ships --------------------------------------------
_WORDS = {"one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10}


def _shipped_scene_files(group: str | None = None) -> list[Path]:
    base = ROOT / "pendulab" / "scenes"
    return sorted((base / group if group else base).glob("*.toml"))


def test_scenes_doc_counts_the_shipped_scenes():
    """docs/scenes.md said 14 scenes while 15 shipped (issue 20): every count it states is the number of files."""
    text = (ROOT / "docs" / "scenes.md").read_text(encoding="utf-8")
    top = len(_shipped_scene_files())
    counts = [int(n) for n in re.findall(r"the (\d+) (?:shipped )?scenes", text)]
    assert counts and set(counts) == {top}, f"docs/scenes.md counts {counts}, {top} TOML files ship"
    for group in ("bench", "validation"):
        stated = re.search(rf"`{group}/` \((\d+) scenes", text)
        assert stated and int(stated.group(1)) == len(_shipped_scene_files(group)), group
    # ... and the table of shipped scenes names every one of them.
    table = text.split("## Shipped scenes", 1)[1]
    missing = [p.stem for p in _shipped_scene_files() if f"`{p.stem}`" not in table]
    assert not missing, f"docs/scenes.md does not list {missing}"


def test_docs_counting_scenes_elsewhere_agree():
    """Any 'N shipped scenes' / 'N scenes in pendulab/scenes' in README.md or docs/ is the number of top-level files."""
    top = len(_shipped_scene_files())
    pattern = re.compile(r"\b(\d+|" + "|".join(_WORDS) + r") (?:shipped scenes|scenes in `?pendulab/scenes/?`?)", re.I)
    wrong = []
    for path in DOC_FILES:
        for m in pattern.finditer(path.read_text(encoding="utf-8")):
            word = m.group(1).lower()
            n = _WORDS.get(word) if word in _WORDS else int(word)
            if n != top:
                wrong.append(f"{path.relative_to(ROOT)}: {m.group(0)!r}")
    assert not wrong, f"{top} scenes ship: {wrong}"

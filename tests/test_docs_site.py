"""The documentation site: API pages match the packages' ``__all__``, Sphinx builds with no warning, internal links resolve.

The build test needs the extra ``pendulab[docs]`` (in the test extra, so CI runs it) and builds a copy of
docs/ and examples/ in a temporary directory (nothing is written into the repository), with the gallery
as code only (``-D plot_gallery=0``: running the examples is the full build's job, see docs/conf.py).
"""

from __future__ import annotations

import html.parser
import importlib.util
import runpy
import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS_EXTRA = ("sphinx", "numpydoc", "pydata_sphinx_theme", "sphinx_gallery", "myst_parser")


def _api_pages() -> dict[str, str]:
    # runpy with a name other than __main__ and no Sphinx: conf.py's module level only imports pendulab.
    conf = runpy.run_path(str(ROOT / "docs" / "conf.py"), run_name="pendulab_docs_conf")
    return conf["api_pages"]()


def test_committed_api_pages_equal_the_packages_exports():
    expected = _api_pages()
    committed = {p.name: p.read_text() for p in (ROOT / "docs" / "api").glob("*.rst")}
    assert committed == expected, "docs/api/ is stale: run `python docs/conf.py` or a docs build and commit docs/api/"
    # Every name a documented package exports is listed once, so the reference is complete and has no duplicate.
    listed = [
        line.strip() for text in expected.values() for line in text.splitlines() if line.startswith("   ") and ":" not in line
    ]
    assert "simulate" in listed and "ensemble" in listed and "export" in listed
    assert listed.count("simulate") == 1 and listed.count("Trajectory") == 1  # re-exports listed once, where first exported


class _Links(html.parser.HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        d = dict(attrs)
        if d.get("id"):
            self.ids.add(d["id"])
        for key in ("href", "src"):
            if d.get(key):
                self.links.append(d[key])


def _parse(path: Path) -> _Links:
    parser = _Links()
    parser.feed(path.read_text(errors="replace"))
    return parser


@pytest.mark.skipif(
    any(importlib.util.find_spec(m) is None for m in DOCS_EXTRA), reason='needs the docs extra: pip install "pendulab[docs]"'
)
def test_sphinx_builds_without_warnings_and_internal_links_resolve(tmp_path):
    src = tmp_path / "src"
    shutil.copytree(ROOT / "docs", src / "docs", ignore=shutil.ignore_patterns("auto_examples", "_build", "generated"))
    shutil.copytree(ROOT / "examples", src / "examples", ignore=shutil.ignore_patterns("__pycache__"))
    out = tmp_path / "html"
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", "-D", "plot_gallery=0", "docs", str(out)]
    proc = subprocess.run(cmd, cwd=src, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-5000:]
    assert proc.stderr.strip() == "", proc.stderr[-5000:]  # -q prints warnings only: none

    # The theme's _static/ holds Jinja templates (*.html) that are copied, not rendered: not pages.
    pages = sorted(p for p in out.rglob("*.html") if "_static" not in p.relative_to(out).parts)
    api = out / "api" / "generated" / "pendulab.simulate.html"
    assert api.exists() and "t_final" in api.read_text()  # the numpydoc-rendered reference of simulate
    assert (out / "auto_examples" / "index.html").exists()

    parsed = {p: _parse(p) for p in pages}
    broken = []
    for page, links in parsed.items():
        for link in links.links:
            parts = urlsplit(link)
            if parts.scheme or link.startswith(("//", "mailto:", "javascript:")):
                continue  # external: not checked (no network in CI)
            target = page if not parts.path else (page.parent / unquote(parts.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{page.relative_to(out)} -> {link}")
            elif parts.fragment and target.suffix == ".html":
                ids = parsed[target].ids if target in parsed else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{page.relative_to(out)} -> {link} (no anchor)")
    assert not broken, "\n".join(broken[:40])

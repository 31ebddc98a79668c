"""The documentation site: API pages match the packages' ``__all__``; the README's docs command builds the site.

The build test does what a user does after reading the README: in a fresh virtual environment holding only
``pip install "<copy of the repository>[docs]"``, it runs the README's docs command (``python -m sphinx -W
...``, every gallery example executed) in that copy (nothing is written into the repository), then checks
the site: no warning, internal links and anchors resolve, the API reference renders, the landing page shows
its figure and leads to the four jobs' guides and the protocols, every gallery page shows a figure and no
test plumbing. It needs the package index (CI has it; pip's cache makes the install cheap) and skips,
saying so, only when a quick ``pip download`` probe cannot reach it. It prints the durations (the README
states them).
"""

from __future__ import annotations

import html.parser
import os
import re
import runpy
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What is copied of the repository for the build: everything but version control, caches and outputs.
_NOT_COPIED = (".*", "pendulab-out", "*.egg-info", "__pycache__", "auto_examples", "_build", "generated", "build", "dist")
#: The README's docs command: ``pip install ".[docs]" && python -m sphinx ...`` on one line of a bash block.
_README_DOCS = re.compile(r'^pip install "\.\[docs\]" && (python -m sphinx [^#\n]+?)\s*(#.*)?$', re.MULTILINE)
#: Each job the landing page leads to, by the guide pages it must link (docs/index.md).
LANDING_LINKS = {
    "modes": ("modes.html",),
    "swing-up": ("swingup.html",),
    "FMU co-simulation": ("fmu.html", "cosim.html"),
    "control studies with python-control": ("modes.html#python-control-bridge", "control_study.html"),
    "protocols and leaderboard": ("realai.html", "realai_v3.html", "leaderboard.html"),
}


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


def _run(cmd: list[str], timeout: float, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, **kw)


def _tail(proc: subprocess.CompletedProcess) -> str:
    return (proc.stdout + proc.stderr)[-5000:]


def readme_docs_command() -> list[str]:
    """The README's ``python -m sphinx ...`` docs command, as an argument list."""
    match = _README_DOCS.search((ROOT / "README.md").read_text())
    assert match, 'README.md lost its docs command (a bash line: pip install ".[docs]" && python -m sphinx ...)'
    return shlex.split(match.group(1))


def test_readme_docs_command_builds_with_warnings_as_errors_and_the_gallery_run():
    cmd = readme_docs_command()
    assert cmd[:3] == ["python", "-m", "sphinx"] and "-W" in cmd and "docs" in cmd
    assert not [a for a in cmd if "plot_gallery" in a]  # the gallery runs: no code-only build


@pytest.mark.needs_cc  # the FMU examples of the gallery export FMUs
def test_readme_docs_command_builds_the_site_in_a_fresh_venv(tmp_path, record_property):
    """``pip install "<copy>[docs]"`` in a new venv, then the README's command in the copy: the site, checked."""
    t0 = time.perf_counter()
    repo = tmp_path / "pendulab"
    shutil.copytree(ROOT, repo, ignore=shutil.ignore_patterns(*_NOT_COPIED))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "PYTHONSTARTUP")}
    env["PENDULAB_CACHE_DIR"] = str(tmp_path / "cache")  # a new user's caches: nothing compiled before
    venv = tmp_path / "venv"
    made = _run([sys.executable, "-m", "venv", str(venv)], 300, env=env)
    assert made.returncode == 0, _tail(made)
    python = str(venv / ("Scripts" if os.name == "nt" else "bin") / "python")

    # Package index reachable? A quick probe of one docs requirement; only its failure skips the test.
    probe = _run([python, "-m", "pip", "download", "--no-deps", "-d", str(tmp_path / "probe"), "numpydoc"], 120, env=env)
    if probe.returncode != 0:
        reason = (probe.stderr.strip().splitlines() or ["no output"])[-1]
        pytest.skip(f"no network to the package index (pip download numpydoc failed: {reason}); the docs build needs it")

    t_install = time.perf_counter()
    install = _run([python, "-m", "pip", "install", f"{repo}[docs]"], 1800, env=env)
    assert install.returncode == 0, _tail(install)
    t_build = time.perf_counter()
    cmd = readme_docs_command()
    build = _run([python, *cmd[1:]], 1800, cwd=repo, env=env)
    t_end = time.perf_counter()
    timing = (
        f"docs site: venv + copy {t_install - t0:.0f} s, pip install {t_build - t_install:.0f} s, "
        f"build ({' '.join(cmd)}) {t_end - t_build:.0f} s"
    )
    print(timing)
    record_property("docs_build_seconds", round(t_end - t_build, 1))
    record_property("docs_install_seconds", round(t_build - t_install, 1))
    assert build.returncode == 0, _tail(build)
    output = build.stdout + build.stderr
    assert "build succeeded" in output and "WARNING:" not in output and "ERROR:" not in output, _tail(build)
    assert "Sphinx-Gallery successfully executed" in output, _tail(build)
    # No silent minute: the examples' progress lines reach the console while the gallery runs them.
    assert "    region of attraction: rigid, acrobot" in output and "    planning the pendubot swing-up" in output, _tail(build)

    out = repo / cmd[-1]
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

    # The landing page: its figure, and a way into each job and the protocols.
    landing = parsed[out / "index.html"]
    images = [link for link in landing.links if link.startswith("_images/") and link.endswith(".png")]
    assert images and all((out / unquote(i)).is_file() for i in images), landing.links
    missing = {job: [h for h in hrefs if h not in landing.links] for job, hrefs in LANDING_LINKS.items()}
    assert not {job: m for job, m in missing.items() if m}, missing

    # The gallery: one page per example, each showing at least one figure its run wrote, and no test plumbing.
    gallery = out / "auto_examples"
    examples = sorted(p.stem for p in (repo / "examples").glob("*.py"))
    pages_of_examples = sorted(p.stem for p in gallery.glob("*.html") if p.stem not in ("index", "sg_execution_times"))
    assert examples and pages_of_examples == examples
    for name in examples:
        links = parsed[gallery / f"{name}.html"].links
        figures = [link for link in links if re.fullmatch(rf"\.\./_images/sphx_glr_{name}_\d+\.png", link)]
        assert figures, f"gallery page {name}.html shows no figure"
        text = (gallery / f"{name}.html").read_text()
        assert not [w for w in ("TEST_KWARGS", "PYTHONPATH", "sphinx_gallery_") if w in text], name

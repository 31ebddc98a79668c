"""Sphinx configuration of pendulab's documentation site: guides (Markdown), API reference, example gallery.

Build (extra ``pendulab[docs]``; tests/test_docs_site.py runs exactly this in a fresh venv)::

    python -m sphinx -W -b html docs pendulab-out/docs              # runs every example for the gallery
    python -m sphinx -W -b html -D plot_gallery=0 docs OUT          # code-only gallery (quick local preview)

The API pages are generated at build time from each public package's ``__all__`` (one source of truth:
what a package exports is what is documented); numpydoc renders the docstrings, which the suite already
validates (tests/test_docstrings.py).
"""

from __future__ import annotations

import importlib
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import pendulab  # noqa: E402

project = "pendulab"
author = "the pendulab developers"
copyright = "2026, the pendulab developers"  # noqa: A001 - Sphinx's name
release = version = pendulab.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
#: The model-hierarchy tables are data written by `pendulab bench hierarchy` (no title), linked as files.
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip", "benchmarks/hierarchy_*.md"]
templates_path = ["_templates"]

# -- API reference -----------------------------------------------------------------------------------------
#: Public packages documented, in the order of the layers (docs/architecture.md), with a one-line purpose.
API_PACKAGES = {
    "pendulab": "Models, simulation, equilibria and modes (the top-level API).",
    "pendulab.integrate": "simulate() and the one registry of integration methods.",
    "pendulab.scene": "Scenes: TOML files read by one Scene type.",
    "pendulab.ensemble": "Many runs at once: heyoka batch mode, forked processes, Dask.",
    "pendulab.identify": "The real robot: identification from measured records, plant files.",
    "pendulab.control": "Controller design: LQR, TVLQR, swing-up planning, NMPC.",
    "pendulab.evaluate": "Evaluation of controllers: robustness scorecard, RealAIGym leaderboard.",
    "pendulab.fmu": "FMU export (FMI 2.0 / 3.0, CS + ME) and validation.",
    "pendulab.cosim": "Co-simulation of FMUs under sampled controllers.",
    "pendulab.gym": "Gymnasium environment (extra pendulab[gym]).",
}
autosummary_generate = True
autosummary_imported_members = True
autodoc_default_options = {"members": True, "inherited-members": False, "show-inheritance": True}
autodoc_typehints = "none"  # numpydoc renders the types from the docstrings
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
suppress_warnings = ["myst.header", "autosummary.import_cycle"]


def api_pages() -> dict[str, str]:
    """The API pages, ``{file name under docs/api/: reST text}``: one page per package of ``API_PACKAGES``.

    Each page is an autosummary table of the package's ``__all__``; a name already documented by an
    earlier package (the same object re-exported, e.g. ``pendulab.simulate``) is listed once, where it is
    first exported. tests/test_docs_site.py checks that the committed pages equal these.
    """
    pages: dict[str, str] = {}
    index = ["API reference", "=============", "", ".. toctree::", "   :maxdepth: 1", ""]
    seen: set[int] = set()
    for name, purpose in API_PACKAGES.items():
        module = importlib.import_module(name)
        members = []
        for member in sorted(getattr(module, "__all__", []), key=str.lower):
            obj = getattr(module, member)
            if member.startswith("__") or (id(obj) in seen and not isinstance(obj, (str, int, float, tuple))):
                continue
            seen.add(id(obj))
            members.append(member)
        title = f"``{name}``"
        lines = [title, "=" * len(title), "", purpose, "", f".. automodule:: {name}", "   :no-members:", "   :no-index:", ""]
        lines += [f".. currentmodule:: {name}", "", ".. autosummary::", "   :toctree: generated", ""]
        lines += [f"   {m}" for m in members]
        pages[f"{name}.rst"] = "\n".join(lines) + "\n"
        index.append(f"   {name}")
    pages["index.rst"] = "\n".join(index) + "\n"
    return pages


def _write_api_pages() -> None:
    """Bring docs/api/ up to date (Sphinx lists the source files before it reads this configuration, so a
    page added here is seen from the next build on: the pages are committed and a test keeps them current)."""
    api = HERE / "api"
    api.mkdir(exist_ok=True)
    for fname, text in api_pages().items():
        page = api / fname
        if not page.exists() or page.read_text() != text:
            page.write_text(text)


_write_api_pages()

# -- Gallery (examples/) -----------------------------------------------------------------------------------
#: Every example runs at every full docs build (seconds each: their defaults are sized for it) and its page
#: shows the figures it wrote (gallery_hooks.scrape_written_pngs); while they run, their progress lines are
#: echoed to the console (gallery_hooks.echo_example_output, connected in setup() below).
sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/[^/_][^/]*\.py$",
    "image_scrapers": ("gallery_hooks.scrape_written_pngs",),
    "reset_modules": ("gallery_hooks.clean_example_outputs",),
    "reset_modules_order": "both",  # also after the last example: nothing it wrote stays in examples/
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "show_signature": False,
}

# -- HTML --------------------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"pendulab {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
}
html_static_path: list[str] = []
myst_heading_anchors = 3


def setup(app) -> None:  # Sphinx calls a configuration's setup() like an extension's
    """Echo the examples' output (their progress) to the console while the gallery runs them."""
    from gallery_hooks import echo_example_output

    echo_example_output(app)

"""The CLI's commands, one module each (``register(subparsers)``), the error they raise on bad input, and the
documentation site their ``--help`` texts link."""

from pathlib import Path

__all__ = ["CLIError", "DOCS_URL", "docs_page"]

#: The documentation site (the project's decided public home, as in pyproject.toml's ``[project.urls]``): ``--help``
#: texts link its pages, which a ``pip install`` user can open (the repository's docs/*.md files are not installed).
DOCS_URL = "https://pendulab.readthedocs.io/en/latest/"
#: The Markdown sources of the site's pages (present in a source checkout only, not in an installed wheel).
_DOCS_SOURCE = Path(__file__).resolve().parents[2] / "docs"


def docs_page(name: str) -> str:
    """The URL of the documentation page built from ``docs/<name>.md``, e.g. ``docs_page("scorecard")``.

    In a source checkout (docs/conf.py present) a name without its page is a programming error, raised when
    the parser is built; an installed package has no docs/ and trusts the name (tests/test_cli_json.py checks
    every URL of every help text against docs/).

    Parameters
    ----------
    name : str
        The page's source file name under docs/, without ``.md``.

    Returns
    -------
    str
        ``DOCS_URL + name + ".html"``.

    Raises
    ------
    ValueError
        The source tree is present and has no ``docs/<name>.md``.
    """
    if (_DOCS_SOURCE / "conf.py").is_file() and not (_DOCS_SOURCE / f"{name}.md").is_file():
        raise ValueError(f"no documentation page docs/{name}.md for docs_page({name!r})")
    return f"{DOCS_URL}{name}.html"


class CLIError(ValueError):
    """Bad command-line input (reported as one line, exit status 2)."""

"""``--json``: one summary object on stdout and nothing else (strict JSON: no NaN), for the commands of this area.

``fmu export`` / ``fmu validate`` are covered in tests/fmu/test_fmu_cli.py, ``demo`` in tests/test_scene_inputs.py.
"""

from __future__ import annotations

import json

import pytest

from pendulab.cli import main


def _strict(text: str) -> dict:
    def refuse(name: str) -> None:
        raise ValueError(f"non-standard JSON constant {name} on stdout")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize(
    "args, key",
    [
        (["simulate", "--scene", "validation/rigid_forced", "--t-final", "0.5", "--json"], "energy_balance_error_J"),
        (["simulate", "--scene", "elastic_stiff", "--model", "auto", "--t-final", "0.3", "--json"], "model_level"),
        (["modes", "--model", "elastic", "--torque", "1,0", "--json"], "equilibria"),
        (["scene", "check", "stiff_small_amplitude", "--json"], "chosen"),
    ],
)
def test_json_is_one_object_on_stdout(args, key, capsys):
    assert main(args) == 0
    out = capsys.readouterr().out
    data = _strict(out)  # the whole of stdout parses: nothing printed besides the object
    assert isinstance(data, dict) and key in data


def test_version_is_the_package_version(capsys):
    from pendulab import __version__
    from pendulab.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"pendulab {__version__}"


def test_every_help_text_is_plain():
    import argparse

    from pendulab.cli import build_parser

    def walk(parser):
        yield parser.description or ""
        for action in parser._actions:
            yield action.help or ""
            if isinstance(action, argparse._SubParsersAction):
                yield from (c.help or "" for c in action._choices_actions)
                for child in action.choices.values():
                    yield from walk(child)

    texts = list(walk(build_parser()))
    assert len(texts) > 200  # the whole tree was walked
    assert not [t for t in texts if "``" in t]


def test_every_command_has_out_and_json():
    import argparse

    from pendulab.cli import build_parser

    def leaves(parser, name="pendulab"):
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        for action in subs:
            for key, child in action.choices.items():
                yield from leaves(child, f"{name} {key}")
        if not subs or not any(isinstance(a, argparse._SubParsersAction) and a.required for a in subs):
            yield name, {o for a in parser._actions for o in a.option_strings}

    missing = {name: sorted({"--out", "--json"} - flags) for name, flags in leaves(build_parser()) if name != "pendulab"}
    assert {name: m for name, m in missing.items() if m} == {}


def _help_texts():
    import argparse

    from pendulab.cli import build_parser

    def walk(parser):
        yield parser.description or ""
        yield parser.epilog or ""
        for action in parser._actions:
            yield action.help or ""
            if isinstance(action, argparse._SubParsersAction):
                yield from (c.help or "" for c in action._choices_actions)
                for child in action.choices.values():
                    yield from walk(child)

    return list(walk(build_parser()))


def test_help_links_the_documentation_site_not_repository_files():
    """A ``pip install`` user has no docs/*.md: ``--help`` names pages of the documentation site, and each exists."""
    import re
    from pathlib import Path

    from pendulab.commands import DOCS_URL

    docs = Path(__file__).resolve().parents[1] / "docs"
    texts = _help_texts()
    assert len(texts) > 200  # the whole tree was walked
    assert not [t for t in texts if re.search(r"docs/[\w.-]+\.md", t)]
    urls = [u.rstrip(".,;)") for t in texts for u in re.findall(r"https?://\S+", t)]
    assert len(urls) >= 10 and f"{DOCS_URL}scorecard.html" in urls
    pages = [u[len(DOCS_URL) :] for u in urls if u != DOCS_URL]
    assert all(u.startswith(DOCS_URL) for u in urls), [u for u in urls if not u.startswith(DOCS_URL)]
    missing = sorted({p for p in pages if not p.endswith(".html") or not (docs / f"{p[: -len('.html')]}.md").is_file()})
    assert missing == []


def test_docs_page_refuses_a_page_the_source_tree_lacks():
    from pendulab.commands import DOCS_URL, docs_page

    assert docs_page("fmu") == f"{DOCS_URL}fmu.html"
    with pytest.raises(ValueError, match="no_such_page"):
        docs_page("no_such_page")

"""Every complete ``pendulab`` command the documentation quotes passes the CLI's option declarations as written.

The class of defect: an option whose meaning depends on a mode of its command, checked with one declaration
(``pendulab score --leaderboard --out docs/leaderboard.md`` regenerates a page, but ``score --out`` was declared a
folder: the documented command was refused once the page existed). Modes are declared in
:data:`pendulab.commands.options.MODE_INPUTS`; this test runs the documented commands' option checks (parsing and
:func:`~pendulab.commands.options.check_options`, nothing else) from the repository root.
"""

from __future__ import annotations

import argparse
import re
import shlex
from pathlib import Path

import pytest

from pendulab._inputs import InputError
from pendulab.cli import build_parser
from pendulab.commands.options import MODE_INPUTS, check_options

ROOT = Path(__file__).resolve().parents[2]
DOCUMENTS = sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]


def _quoted_commands() -> list[tuple[str, str]]:
    found = []
    for doc in DOCUMENTS:
        for m in re.finditer(r"`(pendulab [^`\n]+)`", doc.read_text()):
            found.append((doc.name, m.group(1)))
    return found


def _parsed(parser: argparse.ArgumentParser, command: str) -> argparse.Namespace | None:
    """The parsed namespace of a complete command; None for a fragment (``pendulab score --passive-allowance``)."""
    try:
        argv = shlex.split(command)[1:]
    except ValueError:
        return None
    if not argv or any(a in ("...", "…") or a.startswith("[") or a.isupper() for a in argv):
        return None  # a synopsis with placeholders, not a command
    try:
        return parser.parse_args(argv)
    except SystemExit:
        return None


def test_documented_commands_pass_their_option_declarations(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)  # the docs' paths are relative to the repository root
    parser = build_parser()
    checked, refused = 0, []
    for doc, command in _quoted_commands():
        args = _parsed(parser, command)
        capsys.readouterr()  # argparse's usage text of fragments
        if args is None:
            continue
        try:
            check_options(args)
        except InputError as exc:
            if "no such file" in str(exc):  # an input an earlier step of the guide writes (rigid.fmu)
                continue
            refused.append(f"{doc}: `{command}`: {exc}")
        checked += 1
    assert checked >= 30, checked  # the docs quote dozens of complete commands; the walk must not go blind
    assert not refused, "\n".join(refused)


@pytest.mark.parametrize("key", sorted(MODE_INPUTS))
def test_a_mode_option_takes_its_mode_meaning_only_in_that_mode(key, tmp_path):
    command, dest = key.rsplit(" ", 1)
    mode, _ = MODE_INPUTS[key]
    page = tmp_path / "page.md"
    page.write_text("# an existing page\n")
    parser = build_parser()
    flag = f"--{dest.replace('_', '-')}"
    # score --leaderboard --out PAGE: the page may exist (regenerating overwrites it); a folder is refused.
    check_options(parser.parse_args([*command.split(), f"--{mode}", flag, str(page)]))
    with pytest.raises(InputError, match="is a directory, not a file"):
        check_options(parser.parse_args([*command.split(), f"--{mode}", flag, str(tmp_path)]))
    # Without the mode the option keeps its common meaning (a folder): the same file is refused.
    with pytest.raises(InputError, match="is a file, not a directory"):
        check_options(parser.parse_args([*command.split(), flag, str(page)]))
    assert page.read_text() == "# an existing page\n"  # checking never writes

"""Regenerate some protocols' sections of an existing leaderboard page and keep the rest of it as it was.

A whole leaderboard is hours of cases; one protocol's cases are minutes. ``pendulab score --leaderboard --protocol
P --out PAGE`` over a page that also holds other sections replaces only P's section (matched by its ``## `` heading)
and keeps every other section, the page's header and its wall-time line; the replaced section says which command
regenerated it and when, so the page never claims one generation for numbers of two. Written over a page that holds
only P's sections (or no page), the page is written whole as before.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = [
    "LEADERBOARD_TITLE",
    "SCORECARD_HEADING",
    "UNFINISHED_HEADING",
    "is_leaderboard_page",
    "needs_splice",
    "splice_sections",
]

#: The first line of every leaderboard page.
LEADERBOARD_TITLE = "# Leaderboard"
#: The heading of the own scorecards' section (the last section of a whole page).
SCORECARD_HEADING = "## pendulab's own robustness scorecard"
#: The page-level section that lists a generation's unfinished cases (bullets ``* PROTOCOL / TASK / ...``).
UNFINISHED_HEADING = "## Cases not finished"
_WALL_PREFIX = "Wall time of this generation"

Block = tuple[str, list[str]]


def is_leaderboard_page(text: str) -> bool:
    """Whether ``text`` is a page written by :func:`~pendulab.commands.leaderboard.write_leaderboard`."""
    return text.split("\n", 1)[0].strip() == LEADERBOARD_TITLE


def _split(text: str) -> tuple[list[str], list[Block], list[str]]:
    """The page's preamble lines, its ``## `` blocks (heading, lines from the heading on) and its wall-time lines."""
    lines = text.rstrip("\n").split("\n")
    tail = [line for line in lines if line.startswith(_WALL_PREFIX)]
    lines = [line for line in lines if not line.startswith(_WALL_PREFIX)]
    preamble: list[str] = []
    blocks: list[Block] = []
    for line in lines:
        if line.startswith("## "):
            blocks.append((line, [line]))
        elif blocks:
            blocks[-1][1].append(line)
        else:
            preamble.append(line)
    return preamble, blocks, tail


def needs_splice(text: str, headings: Sequence[str]) -> bool:
    """Whether a page holds sections other than ``headings`` (and its unfinished-case list), which a rewrite would lose.

    Parameters
    ----------
    text : str
        The existing page.
    headings : sequence of str
        The ``## `` headings of the sections about to be written.
    """
    if not is_leaderboard_page(text):
        return False
    _, blocks, _ = _split(text)
    return any(heading not in headings and heading != UNFINISHED_HEADING for heading, _ in blocks)


def _keep_unfinished(block: list[str], protocols: Sequence[str]) -> list[str]:
    """The unfinished-case block without the bullets of ``protocols`` (empty when no bullet is left)."""
    kept = [line for line in block if not any(line.startswith(f"* {p} / ") for p in protocols)]
    return kept if any(line.startswith("* ") for line in kept) else []


def splice_sections(text: str, sections: Sequence[Block], protocols: Sequence[str], provenance: str) -> str:
    """The page ``text`` with ``sections`` replacing the blocks of the same heading.

    Parameters
    ----------
    text : str
        The existing page (:func:`is_leaderboard_page`).
    sections : sequence of (str, list of str)
        New sections: (``## `` heading, lines starting with that heading). A section the page lacks goes before the
        own-scorecard and unfinished-case sections, in the given order.
    protocols : sequence of str
        The protocols of the new sections' cases: their bullets leave the page's unfinished-case list (a new
        section lists its own unfinished cases).
    provenance : str
        A line put under each new section's heading (which command regenerated it, when).

    Returns
    -------
    str
        The new page, ending with a newline.

    Raises
    ------
    ValueError
        ``text`` is not a leaderboard page, or a new section does not start with its heading.
    """
    if not is_leaderboard_page(text):
        raise ValueError(f"not a leaderboard page (its first line is not {LEADERBOARD_TITLE!r}); nothing spliced")
    for heading, lines in sections:
        if not lines or lines[0] != heading or not heading.startswith("## "):
            raise ValueError(f"a section must start with its '## ' heading, got {heading!r} / {lines[:1]!r}")
    preamble, blocks, tail = _split(text)
    new = {heading: [lines[0], "", provenance, *lines[1:]] for heading, lines in sections}
    out: list[Block] = []
    for heading, lines in blocks:
        if heading == UNFINISHED_HEADING:
            lines = _keep_unfinished(lines, protocols)
        out.append((heading, new.pop(heading, lines)))
    first_later = next((i for i, (h, _) in enumerate(out) if h in (SCORECARD_HEADING, UNFINISHED_HEADING)), len(out))
    out[first_later:first_later] = list(new.items())
    body = [line for _, lines in out for line in lines]
    return "\n".join([*preamble, *body, *tail]).rstrip("\n") + "\n"

"""sphinx-gallery hooks of pendulab's docs (named by string in conf.py so the configuration stays cacheable).

pendulab's figure functions save and close their figures, so the matplotlib scraper would find none:
``scrape_written_pngs`` collects the PNG files an example wrote into its output folders during a code block,
and ``clean_example_outputs`` removes those folders from examples/ afterwards (the gallery keeps copies).
``echo_example_output`` shows the examples' output (their progress lines) in the build's console as they run.
"""

from __future__ import annotations

import logging
import shutil
import sys
import time
from pathlib import Path
from typing import Any

#: Output folders the examples write into (relative to examples/, their working directory under the gallery):
#: each example's ``main()`` default. tests/test_examples.py checks every example writes into one of them.
EXAMPLE_OUTPUTS = (
    "modes_figures",
    "balance_figures",
    "fmu_example",
    "scene_figures",
    "stiffness_figures",
    "seed_paper_figures",
    "cosim_figures",
    "gym_figures",
    "swingup_figures",
)
#: Files older than this (the start of the build) were not written by this build's examples.
_BUILD_START = time.time()


def scrape_written_pngs(block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
    """reST for the PNG files written during the block (copied to sphinx-gallery's image paths)."""
    from sphinx_gallery.scrapers import figure_rst

    src_dir = Path(block_vars["src_file"]).parent
    written = [p for d in EXAMPLE_OUTPUTS for p in (src_dir / d).glob("*.png") if p.stat().st_mtime >= _BUILD_START]
    found = sorted(written, key=lambda p: (p.stat().st_mtime_ns, p.name))  # in the order the example wrote them
    paths = []
    for png, target in zip(found, block_vars["image_path_iterator"], strict=False):
        shutil.copyfile(png, target)
        paths.append(target)
    return figure_rst(paths, gallery_conf["src_dir"])


def clean_example_outputs(gallery_conf: dict[str, Any], fname: str | None, when: str = "after") -> None:
    """Remove what the examples wrote into examples/ (before and after each example)."""
    dirs = gallery_conf["examples_dirs"]
    examples = Path(dirs[0] if isinstance(dirs, list) else dirs)
    for d in EXAMPLE_OUTPUTS:
        shutil.rmtree(examples / d, ignore_errors=True)


class _ExampleLines(logging.Handler):
    """Writes the example output lines sphinx-gallery logs at Sphinx's verbose level to the build's status stream."""

    def __init__(self, stream: Any) -> None:
        super().__init__(level=logging.DEBUG)
        self.stream = stream

    def emit(self, record: logging.LogRecord) -> None:
        # sphinx.util.logging.VERBOSE: the captured output of the running example (its header, "Output from
        # FILE", is left out: sphinx-gallery has just named the example it runs).
        if record.levelno != 15 or record.msg == "Output from %s":
            return
        self.stream.write(f"    {record.getMessage()}\n")
        self.stream.flush()


def echo_example_output(app: Any) -> None:
    """Show each example's output in the console while it runs: no silent minute in a plain build.

    sphinx-gallery captures an example's stdout and stderr for its page and logs every line at Sphinx's
    verbose level, which a build without ``-v`` does not show: a build would sit silent through all the
    examples. This echoes those lines (the examples print a line before every step longer than ~2 s) to the
    status stream; with ``-v`` Sphinx shows them itself, with ``-q`` nothing is shown.
    """
    if app.quiet or app.verbosity > 0:
        return
    logger = logging.getLogger("sphinx.sphinx-gallery")
    for handler in [h for h in logger.handlers if isinstance(h, _ExampleLines)]:
        logger.removeHandler(handler)  # a second application in the same process
    logger.addHandler(_ExampleLines(sys.stdout))  # the status stream: captured before an example replaces sys.stdout

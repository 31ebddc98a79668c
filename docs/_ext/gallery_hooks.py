"""sphinx-gallery hooks of pendulab's docs (named by string in conf.py so the configuration stays cacheable).

pendulab's figure functions save and close their figures, so the matplotlib scraper would find none:
``scrape_written_pngs`` collects the PNG files an example wrote into its output folders during a code block,
and ``clean_example_outputs`` removes those folders from examples/ afterwards (the gallery keeps copies).
"""

from __future__ import annotations

import shutil
import time
from pathlib import Path
from typing import Any

#: Output folders the examples write into (relative to examples/, their working directory under the gallery).
EXAMPLE_OUTPUTS = ("modes_figures", "balance_figures", "fmu_example")
#: Files older than this (the start of the build) were not written by this build's examples.
_BUILD_START = time.time()


def scrape_written_pngs(block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
    """reST for the PNG files written during the block (copied to sphinx-gallery's image paths)."""
    from sphinx_gallery.scrapers import figure_rst

    src_dir = Path(block_vars["src_file"]).parent
    found = sorted(p for d in EXAMPLE_OUTPUTS for p in (src_dir / d).glob("*.png") if p.stat().st_mtime >= _BUILD_START)
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

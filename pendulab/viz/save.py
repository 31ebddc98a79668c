"""Write a finished matplotlib figure to disk (one place for the save-and-close boilerplate)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .._checks import check_budget
from .._io import atomic_path

__all__ = ["save_figure"]


def save_figure(fig: Any, path: str | Path, dpi: int = 110) -> Path:
    """Save ``fig`` to ``path`` (parent directories created), close it and return the path.

    Closing matters: pyplot keeps every open figure alive, and sweeps draw many.
    The file is written atomically (a temporary file renamed over ``path``), so
    an interrupted run never leaves a truncated image; the figure is closed
    even when saving fails.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to save.
    path : str or Path
        Output file; the format follows its suffix.
    dpi : int, default 110
        Resolution [dots per inch].

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    BudgetError
        The image (figure size [in] x ``dpi``) has more pixels than the budget ``PENDULAB_MAX_IMAGE_PIXELS``;
        checked before rendering (the figure is closed).
    """
    import matplotlib.pyplot as plt

    path = Path(path)
    try:
        w, h = fig.get_size_inches()
        check_budget("image_pixels", "dpi", dpi, float(w * dpi) * float(h * dpi))
        with atomic_path(path) as tmp:
            # The temporary name ends in ".tmp<suffix>"; name the format so it never depends on it.
            fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".").lower() or plt.rcParams["savefig.format"])
    finally:
        plt.close(fig)
    return path

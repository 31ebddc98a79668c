"""Write a finished matplotlib figure to disk (one place for the save-and-close boilerplate)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["save_figure"]


def save_figure(fig: Any, path: str | Path, dpi: int = 110) -> Path:
    """Save ``fig`` to ``path`` (parent directories created), close it and return the path.

    Closing matters: pyplot keeps every open figure alive, and sweeps draw many.

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
    """
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path

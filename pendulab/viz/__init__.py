"""Figures and animations of simulated pendulums (matplotlib, Agg backend)."""

from .drawing import Run, as_runs
from .figures import FIGURES, save_figures

__all__ = ["FIGURES", "Run", "as_runs", "save_figures"]

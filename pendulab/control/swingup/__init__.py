"""Swing-up optimal control: the problem, its transcriptions, initial guesses, the solver, checks, tasks and episodes."""

from .problem import OBJECTIVES, SwingUpProblem
from .solve import GUESSES, SwingUpResult, swing_up
from .transcription import TRANSCRIPTIONS

__all__ = ["GUESSES", "OBJECTIVES", "TRANSCRIPTIONS", "SwingUpProblem", "SwingUpResult", "swing_up"]

"""Swing-up optimal control: the problem, its transcriptions, initial guesses, the solver, checks, tasks and episodes."""

from .planning import swing_up
from .problem import OBJECTIVES, SwingUpProblem
from .solve import GUESSES, SwingUpResult, solve_transcription
from .transcription import TRANSCRIPTIONS

__all__ = ["GUESSES", "OBJECTIVES", "TRANSCRIPTIONS", "SwingUpProblem", "SwingUpResult", "solve_transcription", "swing_up"]

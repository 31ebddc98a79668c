"""Control: swing-up trajectory optimization and tracking (python-control bridge and LQR live here too)."""

from .guess import Guess, energy_guess, linear_guess
from .problem import OBJECTIVES, SwingUpProblem, upright_state
from .swingup import GUESSES, SwingUpResult, swing_up
from .transcription import TRANSCRIPTIONS

__all__ = [
    "GUESSES",
    "Guess",
    "OBJECTIVES",
    "SwingUpProblem",
    "SwingUpResult",
    "TRANSCRIPTIONS",
    "energy_guess",
    "linear_guess",
    "swing_up",
    "upright_state",
]

"""Evaluation: how well a controller does on a task, never how it is designed.

* :mod:`.scorecard` (with :mod:`.categories`, :mod:`.card` and :mod:`.perturb`):
  the robustness scorecard, success rates under swept perturbations;
* :mod:`.realai`: the RealAIGym simulation leaderboard v2 (its run and criteria).

Evaluation takes controllers through the one controller protocol
(:class:`pendulab.control.feedback.SampledController`) from a factory
(:func:`pendulab.control.controllers.controller_for_task`, or any callable
``task -> (controller, x0)``); a task supplies its own plan
(:meth:`pendulab.control.swingup.tasks.Task.plan`). Nothing here plans,
designs or reaches into a controller's internals.
"""

from .card import CategoryScore, RunRecord, Scorecard
from .categories import CATEGORIES, Category, categories_for
from .perturb import EpisodeResult, Perturbation, run_perturbed_episode
from .realai import RealAIResult, realai_score
from .scorecard import rerun, score

__all__ = [
    "CATEGORIES",
    "Category",
    "CategoryScore",
    "EpisodeResult",
    "Perturbation",
    "RealAIResult",
    "RunRecord",
    "Scorecard",
    "categories_for",
    "realai_score",
    "rerun",
    "run_perturbed_episode",
    "score",
]

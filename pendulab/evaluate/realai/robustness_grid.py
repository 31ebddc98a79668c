"""Robustness v2's definition: categories, grids, repetitions, the run plan, upstream's random draws (:mod:`.robustness`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._checks import bounded_int
from ...control.realai.spec import DT
from ...model.plant_file import IdentifiedPlant
from .plant import MODEL_VARIATIONS, protocol_params

__all__ = [
    "CATEGORIES",
    "CATEGORY_LABELS",
    "PUBLISHED_ROBUSTNESS",
    "QUICK_LEVELS",
    "RunSpec",
    "plan_runs",
    "protocol_grid",
    "random_gauss_perturbation",
]

CATEGORIES: tuple[str, ...] = ("model", "measurement_noise", "u_noise", "u_responsiveness", "delay", "perturbation")
#: Axis labels of the categories' levels (with units).
CATEGORY_LABELS: Mapping[str, str] = {
    "model": "model parameter (grid point)",
    "measurement_noise": "velocity noise sigma [rad/s]",
    "u_noise": "torque noise sigma [N m]",
    "u_responsiveness": "torque responsiveness k [-]",
    "delay": "measurement delay [s]",
    "perturbation": "perturbation run",
}
#: Grid points per category and model parameter.
N_VAR: int = 21
#: Repetitions of each noise level.
REPETITIONS: int = 10
#: Runs of the perturbation category.
PERTURBATION_REPETITIONS: int = 50
#: Success box around the goal, (q1, q2, dq1, dq2), joint coordinates.
EPSILON: tuple[float, float, float, float] = (0.35, 0.35, 1.0, 1.0)
#: Goal (upright at rest), joint coordinates.
GOAL: tuple[float, float, float, float] = (math.pi, 0.0, 0.0, 0.0)
#: Episode length [s].
T_FINAL: float = 10.0
#: Perturbation pulses per joint, their minimum spacing [s], width sigma and amplitude ranges [s], [N.m].
PERTURBATION = {"n_per_joint": 3, "min_t_dist": 1.0, "sigma_minmax": (0.05, 0.1), "amplitude_minmax": (0.5, 5.0)}
#: Largest number of repetitions of a noise level or perturbation runs.
MAX_REPETITIONS: int = 1000

#: Published robustness-v2 rows (RealAIGym leaderboard pages ``{pendubot,acrobot}_simulation_robustness_leaderboard_v2``,
#: stored copies): the six category rates in percent, in :data:`CATEGORIES` order, and the overall score.
PUBLISHED_ROBUSTNESS: Mapping[str, Mapping[str, tuple[tuple[float, ...], float]]] = {
    "pendubot": {
        "ar_eapo": ((87.6, 81.0, 100.0, 100.0, 81.0, 98.0), 0.913),
        "evolsac": ((75.2, 57.1, 100.0, 100.0, 71.4, 68.0), 0.786),
        "history_sac": ((68.1, 47.6, 100.0, 100.0, 100.0, 46.0), 0.770),
        "tvlqr": ((62.9, 90.5, 100.0, 100.0, 42.9, 64.0), 0.767),
        "ilqr_mpc_stabilization": ((31.9, 90.5, 100.0, 100.0, 38.1, 44.0), 0.674),
        "mcpilco": ((24.8, 76.2, 61.9, 95.2, 28.6, 82.0), 0.614),
        "ilqr_riccati_gains": ((5.2, 38.1, 9.5, 85.7, 14.3, 0.0), 0.255),
    },
    "acrobot": {
        "history_sac": ((58.1, 23.8, 100.0, 100.0, 90.5, 78.0), 0.751),
        "ar_eapo": ((67.6, 28.6, 100.0, 100.0, 76.2, 64.0), 0.727),
        "evolsac": ((64.8, 23.8, 100.0, 100.0, 47.6, 76.0), 0.687),
        "tvlqr": ((48.1, 19.0, 100.0, 95.2, 23.8, 78.0), 0.607),
        "ilqr_mpc_stabilization": ((6.7, 9.5, 90.5, 52.4, 4.8, 42.0), 0.343),
        "mcpilco": ((9.0, 9.5, 19.0, 52.4, 4.8, 50.0), 0.241),
        "ilqr_riccati_gains": ((4.8, 9.5, 9.5, 52.4, 4.8, 2.0), 0.138),
    },
}


# -- grid, plan, random draws -------------------------------------------------------------------------------------


def _par_list(x0: float, min_rel: float, max_rel: float, n: int) -> np.ndarray:
    """``get_par_list`` of ``analysis/utils.py``: relative grid times the nominal value."""
    if x0 != 0:
        li = np.linspace(min_rel, max_rel, n + 1 if n % 2 == 0 else n)
    else:
        li = np.linspace(0, max_rel, n)
    return li * x0


def protocol_grid(task: str, plant: IdentifiedPlant | None = None) -> dict[str, Any]:
    """The levels of every category (``benchmark_controller.py``).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    plant : IdentifiedPlant, optional
        The varied robot: an identified one (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.

    Returns
    -------
    dict
        ``"model"``: dict parameter -> ndarray (21,) of values (units of :mod:`.plant`, ``m1r1``
        and ``m2r2`` in kg.m); the other categories -> ndarray (21,) of levels;
        ``"perturbation"``: None (runs, not levels).
    """
    p = protocol_params(task, plant)
    return {
        "model": {
            "Ir": np.linspace(0.0, 1e-4, N_VAR),
            "m1r1": _par_list(p["m1"] * p["r1"], 0.75, 1.25, N_VAR),
            "I1": _par_list(p["I1"], 0.75, 1.25, N_VAR),
            "b1": np.linspace(-0.1, 0.1, N_VAR),
            "cf1": np.linspace(-0.2, 0.2, N_VAR),
            "m2r2": _par_list(p["m2"] * p["r2"], 0.75, 1.25, N_VAR),
            "m2": _par_list(p["m2"], 0.75, 1.25, N_VAR),
            "I2": _par_list(p["I2"], 0.75, 1.25, N_VAR),
            "b2": np.linspace(-0.1, 0.1, N_VAR),
            "cf2": np.linspace(-0.2, 0.2, N_VAR),
        },
        "measurement_noise": np.linspace(0.0, 0.5, N_VAR),
        "u_noise": np.linspace(0.0, 1.1, N_VAR),
        "u_responsiveness": np.linspace(0.1, 2.0, N_VAR),
        "delay": np.linspace(0.0, 0.04, N_VAR),
        "perturbation": None,
    }


#: Level indices of ``--quick``: first, middle and last grid point of every category.
QUICK_LEVELS: tuple[int, ...] = (0, 10, 20)


@dataclass(frozen=True)
class RunSpec:
    """One run of the protocol.

    Attributes
    ----------
    index : int
        Position in the benchmark's order (the order of the random draws).
    category : str
        One of :data:`CATEGORIES`.
    param : str
        Model parameter (category ``model``), else "".
    level_index : int
        Index of the level in the category's (or parameter's) full 21-point grid; the run number for ``perturbation``.
    level : float
        The level (parameter value, sigma, k, delay [s]); ``nan`` for ``perturbation``.
    rep : int
        Repetition at this level (noise categories), else 0.
    """

    index: int
    category: str
    param: str
    level_index: int
    level: float
    rep: int


def plan_runs(
    task: str,
    *,
    levels: Sequence[int] | None = None,
    repetitions: int = REPETITIONS,
    perturbation_repetitions: int = PERTURBATION_REPETITIONS,
    categories: Sequence[str] | None = None,
    model_params: Sequence[str] | None = None,
    u_noise_repetitions: int = REPETITIONS,
    plant: IdentifiedPlant | None = None,
) -> list[RunSpec]:
    """Every run of the protocol in the benchmark's order.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    levels : sequence of int, optional
        Grid indices (0 ... 20) to keep in every category (a reduced grid); default all 21.
    repetitions : int
        Repetitions of each measurement-noise level (upstream: 10). The torque-noise levels
        always run 10 times: ``benchmarker.benchmark`` does not pass its ``repetitions`` on to
        ``check_unoise_robustness``, whose default is 10.
    perturbation_repetitions : int
        Runs of the perturbation category (upstream: 50).
    categories : sequence of str, optional
        Categories to run (upstream's ``compute_*_robustness`` flags); default all of :data:`CATEGORIES`.
    model_params : sequence of str, optional
        Model parameters to vary (upstream's ``mpar_vars``), in :data:`~.plant.MODEL_VARIATIONS` order; default all ten.
    u_noise_repetitions : int
        Repetitions of each torque-noise level (10 in upstream's protocol, whatever ``repetitions`` is).
    plant : IdentifiedPlant, optional
        The varied robot: an identified one (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.

    Returns
    -------
    list of RunSpec
        722 runs with the defaults.

    Raises
    ------
    ValueError
        Bad ``levels``, repetition counts, categories or model parameters.
    """
    grid = protocol_grid(task, plant)
    cats = _check_names("categories", categories, CATEGORIES)
    params = _check_names("model_params", model_params, MODEL_VARIATIONS)
    u_noise_repetitions = bounded_int("u_noise_repetitions", u_noise_repetitions, high=MAX_REPETITIONS, why="runs per level")
    repetitions = bounded_int("repetitions", repetitions, high=MAX_REPETITIONS, why="runs per noise level")
    perturbation_repetitions = bounded_int(
        "perturbation_repetitions", perturbation_repetitions, high=MAX_REPETITIONS, why="perturbation runs"
    )
    if levels is None:
        keep = list(range(N_VAR))
    else:
        if isinstance(levels, (str, bytes)) or not hasattr(levels, "__iter__"):
            raise TypeError(f"levels must be a sequence of grid indices in [0, {N_VAR - 1}], got {levels!r}")
        keep = sorted({bounded_int("levels[i]", v, low=0, high=N_VAR - 1, why="grid indices") for v in levels})
        if not keep:
            raise ValueError("levels must name at least one grid index in [0, 20], got an empty sequence")
    plan: list[RunSpec] = []

    def add(cat: str, param: str, li: int, level: float, rep: int) -> None:
        plan.append(RunSpec(len(plan), cat, param, li, float(level), rep))

    if "model" in cats:
        for name in params:
            for li in keep:
                add("model", name, li, grid["model"][name][li], 0)
    for cat, reps in (("measurement_noise", repetitions), ("u_noise", u_noise_repetitions)):
        if cat in cats:
            for li in keep:
                for r in range(reps):
                    add(cat, "", li, grid[cat][li], r)
    for cat in ("u_responsiveness", "delay"):
        if cat in cats:
            for li in keep:
                add(cat, "", li, grid[cat][li], 0)
    if "perturbation" in cats:
        for r in range(perturbation_repetitions):
            add("perturbation", "", r, math.nan, 0)
    return plan


def _check_names(what: str, names: Sequence[str] | None, known: tuple[str, ...]) -> tuple[str, ...]:
    """A selection of ``known`` names, in ``known``'s order (the benchmark's), checked."""
    if names is None:
        return known
    if isinstance(names, str) or not isinstance(names, Sequence):
        raise TypeError(f"{what} must be a sequence of names (some of {list(known)}), got {type(names).__name__}")
    bad = [n for n in names if n not in known]
    if bad or not names:
        raise ValueError(f"{what} must be a non-empty selection of {list(known)}, got {list(names)!r}")
    return tuple(n for n in known if n in names)


def random_gauss_perturbation(
    rng: np.random.RandomState,
    tmax: float = T_FINAL,
    dt: float = DT,
    n_per_joint: int = 3,
    min_t_dist: float = 1.0,
    sigma_minmax: Sequence[float] = (0.05, 0.1),
    amplitude_minmax: Sequence[float] = (0.5, 5.0),
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Random Gaussian torque pulses, with the draws of ``get_random_gauss_perturbation_array``.

    Pulse centres: ``2 n_per_joint`` increasing times at least ``min_t_dist`` apart (one
    ``rand()`` each), shuffled and split between the joints; widths ``rand(2, n)`` in
    ``sigma_minmax``; amplitudes ``uniform(-(a1 - a0), a1 - a0, (2, n))`` pushed out by ``a0``
    away from zero.

    Parameters
    ----------
    rng : numpy.random.RandomState
        Generator (legacy: the call sequence reproduces upstream's global ``np.random``).
    tmax, dt : float
        Horizon and step [s].
    n_per_joint : int
        Pulses per joint.
    min_t_dist : float
        Minimum spacing of pulse centres [s].
    sigma_minmax : sequence of 2 float
        Pulse width range [s].
    amplitude_minmax : sequence of 2 float
        Amplitude magnitude range [N.m].

    Returns
    -------
    array : ndarray, shape (2, len(arange(0, tmax, dt)))
        Torque added to each joint at step index ``int(t/dt)`` [N.m].
    mu, sigma, amplitude : ndarray, shape (2, n_per_joint)
        Centres [s], widths [s], amplitudes [N.m].
    """
    n = 2 * n_per_joint
    wiggle_room = (tmax - (n + 1) * min_t_dist) / n
    mu: list[float] = []
    for i in range(n):
        if i == 0:
            mu.append(min_t_dist + rng.rand() * wiggle_room)
        else:
            mu.append(mu[-1] + min_t_dist + rng.rand() * wiggle_room)
    rng.shuffle(mu)
    mu_a = np.reshape(mu, (2, n_per_joint))
    sigma = sigma_minmax[0] + rng.rand(2, n_per_joint) * (sigma_minmax[1] - sigma_minmax[0])
    amp_range = amplitude_minmax[1] - amplitude_minmax[0]
    amplitudes = rng.uniform(-amp_range, amp_range, size=(2, n_per_joint))
    amplitudes += amplitude_minmax[0] * np.sign(amplitudes)
    t = np.arange(0, tmax, dt)
    rows = []
    for j in range(2):
        pulses = [
            amplitudes[j][i] * np.exp(-np.power(t - mu_a[j][i], 2.0) / (2 * sigma[j][i] ** 2.0)) for i in range(n_per_joint)
        ]
        rows.append(np.sum(pulses, axis=0))
    return np.asarray(rows), mu_a, sigma, amplitudes


def _n_steps(t_final: float = T_FINAL, dt: float = DT) -> int:
    """Steps of ``while t < t_final: t += dt`` (upstream's loop; 5000 for 10 s at 2 ms)."""
    t, n = 0.0, 0
    while t < t_final:
        t += dt
        n += 1
    return n


#: Random normals each step draws: measurement (4), torque (2), process noise (4).
DRAWS_PER_STEP: int = 10


def _rng_states(plan: Sequence[RunSpec], seed: int, n_steps: int) -> list[tuple]:
    """Generator state at the start of each run, as upstream's global generator would have it (seeded with ``seed``)."""
    rng = np.random.RandomState(seed)
    states = []
    for spec in plan:
        states.append(rng.get_state())
        if spec.category == "perturbation":
            random_gauss_perturbation(rng, **_pert_kwargs())
        rng.standard_normal(DRAWS_PER_STEP * n_steps)
    return states


def _pert_kwargs() -> dict[str, Any]:
    return {
        "n_per_joint": PERTURBATION["n_per_joint"],
        "min_t_dist": PERTURBATION["min_t_dist"],
        "sigma_minmax": PERTURBATION["sigma_minmax"],
        "amplitude_minmax": PERTURBATION["amplitude_minmax"],
    }

"""RealAIGym robustness leaderboard v2: the owners' benchmark protocol, run on pendulab's plant with any controller.

What the protocol does (read in github.com/dfki-ric-underactuated-lab/double_pendulum, stored
copy at commit 1e8544e: ``leaderboard/{pendubot,acrobot}/robustness_v2/benchmark_controller.py``
and ``sim_parameters.py``, ``src/python/double_pendulum/analysis/benchmark.py`` (``benchmarker``),
``analysis/benchmark_scores.py``, ``analysis/utils.py`` (``get_par_list``),
``simulation/simulation.py`` (``Simulator``), ``simulation/perturbations.py``,
``leaderboard/*/robustness_v2/create_leaderboard.py``):

* plant: design C.1, model 1.0, motor inertia, damping and Coulomb friction 0, torque limit
  6 N.m on the actuated joint (:mod:`.plant`); classic RK4 at 2 ms from hanging at rest, while
  ``t < 10`` (5000 steps, ``t`` accumulated in floating point);
* every step: measurement (state ``n_delay = int(delay/dt) + 1`` records back, then
  ``normal(x, sigma)`` on the joint-coordinate state), controller at ``(t, x_meas)``, applied
  torque ``u = u_last + k (u_cmd - u_last)`` (``u_last``: the torque applied in the previous
  step), ``normal(u, sigma_u)``, clipped to the limits, plus the perturbation at
  ``int(t/dt)`` (after the clip; the plant's input matrix drops the passive joint's),
  one RK4 step, ``normal(x, 0)`` process noise;
* six categories (:data:`CATEGORIES`): 10 model parameters x 21 values; velocity measurement
  noise sigma = linspace(0, 0.5, 21) x 10 repetitions; torque noise sigma = linspace(0, 1.1, 21)
  x 10 repetitions; torque responsiveness k = linspace(0.1, 2, 21); delay linspace(0, 0.04, 21)
  (positions and velocities); 50 runs with 3 Gaussian torque pulses per joint
  (``get_random_gauss_perturbation_array(10, 0.002, 3, 1.0, [0.05, 0.1], [0.5, 5.0])``);
  722 runs in all;
* success: only the final state, angles wrapped (``wrap_angles_top``), within
  (0.35, 0.35, 1, 1) of (pi, 0, 0, 0) in joint coordinates;
* category rate: successes / runs (model, responsiveness, delay, perturbations); for the two
  noise categories a level succeeds when the mean of its 10 repetitions exceeds 0.5;
  score = the mean of the six rates (:func:`robustness_score`).

Random numbers: upstream draws everything from NumPy's global legacy generator (4 normals for
the measurement, 2 for the torque and 4 for the process noise every step, also at sigma 0;
``rand``, ``shuffle``, ``rand``, ``uniform`` for a perturbation). :func:`robustness_v2` makes the
same draws in the same order from ``np.random.RandomState(seed)``, so it reproduces an upstream
run seeded with ``np.random.seed(seed)`` draw for draw; each run's generator state is computed
up front, which lets the runs go to parallel workers in any order.
"""

from __future__ import annotations

import json
import math
import statistics
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..._checks import bounded_int
from ..._io import atomic_write_text
from ...control.feedback import SampledController, full_input
from ...control.realai.spec import DT, TORQUE_LIMIT, check_task
from ...control.swingup.tasks import short_name
from ...ensemble.pool import default_workers, map_runs
from .controllers import resolve_controller
from .plant import MODEL_VARIATIONS, actuated_joint, nominal_params, params_vector, protocol_rhs_python, vary

__all__ = [
    "CATEGORIES",
    "CATEGORY_LABELS",
    "PUBLISHED_ROBUSTNESS",
    "RobustnessResult",
    "RunSpec",
    "category_rates",
    "level_successes",
    "plan_runs",
    "protocol_grid",
    "random_gauss_perturbation",
    "robustness_score",
    "robustness_v2",
    "run_protocol_episode",
]

#: Categories in the benchmark's order (the keys of upstream's ``get_scores``).
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


def protocol_grid(task: str) -> dict[str, Any]:
    """The levels of every category (``benchmark_controller.py``).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.

    Returns
    -------
    dict
        ``"model"``: dict parameter -> ndarray (21,) of values (units of :mod:`.plant`, ``m1r1``
        and ``m2r2`` in kg.m); the other categories -> ndarray (21,) of levels;
        ``"perturbation"``: None (runs, not levels).
    """
    p = nominal_params(task)
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

    Returns
    -------
    list of RunSpec
        722 runs with the defaults.

    Raises
    ------
    ValueError
        Bad ``levels``, repetition counts, categories or model parameters.
    """
    grid = protocol_grid(task)
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


# -- one run --------------------------------------------------------------------------------------------------------


def _hold_ratio(controller: SampledController) -> int:
    h = float(controller.sample_time)
    ratio = round(h / DT) if math.isfinite(h) else 0
    if ratio < 1 or abs(ratio * DT - h) > 1e-9:
        raise ValueError(f"controller.sample_time must be a positive multiple of {DT} s, got {h!r}")
    return ratio


def _to_joint(x: np.ndarray) -> np.ndarray:
    """pendulab absolute state -> upstream joint coordinates (q2, dq2 relative)."""
    return np.array([x[0], x[1] - x[0], x[2], x[3] - x[2]])


def _to_absolute(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], q[0] + q[1], q[2], q[2] + q[3]])


def _wrap_top(q: np.ndarray) -> np.ndarray:
    y = np.copy(q)
    y[0] = q[0] % (2 * np.pi)
    y[1] = (q[1] + np.pi) % (2 * np.pi) - np.pi
    return y


def _is_success(q_final: np.ndarray) -> bool:
    lp = _wrap_top(q_final)
    return bool(all(abs(lp[i] - GOAL[i]) < EPSILON[i] for i in range(4)))


def run_protocol_episode(
    task: str,
    controller: SampledController,
    spec: RunSpec,
    rng_state: tuple | None = None,
    *,
    seed: int = 0,
    record: bool = False,
    every_step: bool = False,
) -> dict[str, Any]:
    """One run of the protocol: upstream's ``Simulator.simulate`` loop with the run's perturbation.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    controller : SampledController
        Reset first; called with ``(t, x)`` (pendulab absolute state, measured) every
        ``sample_time`` (a multiple of 2 ms) and held in between.
    spec : RunSpec
        What to perturb.
    rng_state : tuple, optional
        ``RandomState.get_state()`` at the start of the run; default ``RandomState(seed)``.
    seed : int
        Seed when ``rng_state`` is None.
    record : bool
        Also return the trajectory (``t``, ``x`` joint coordinates, ``u`` applied torques).
    every_step : bool
        Call the controller every 2 ms step, as upstream's simulator calls its controllers, whatever
        its ``sample_time`` (default: on its own sample grid, the output held in between).

    Returns
    -------
    dict
        ``index, category, param, level_index, level, rep, success``, ``final`` (joint
        coordinates (q1, q2, dq1, dq2), unwrapped), ``ctrl_median``, ``ctrl_max`` [s] per
        controller call, ``calls``, ``wall`` [s]; perturbation runs also ``mu``, ``sigma``,
        ``amplitude``; with ``record``: ``t``, ``x``, ``u`` arrays.

    Raises
    ------
    ValueError
        A sample time that is not a multiple of 2 ms, or a non-finite state.
    """
    w0 = time.perf_counter()
    act = actuated_joint(task)
    rng = np.random.RandomState(seed)
    if rng_state is not None:
        rng.set_state(rng_state)
    params = nominal_params(task)
    meas_sigma = np.zeros(4)
    u_sigma = np.zeros(2)
    k_resp = 1.0
    delay = 0.0
    pert = np.zeros((2, 0))
    extra: dict[str, Any] = {}
    if spec.category == "model":
        params = vary(params, spec.param, spec.level)
    elif spec.category == "measurement_noise":
        meas_sigma = np.array([0.0, 0.0, spec.level, spec.level])
    elif spec.category == "u_noise":
        u_sigma[act] = spec.level
    elif spec.category == "u_responsiveness":
        k_resp = spec.level
    elif spec.category == "delay":
        delay = spec.level
    elif spec.category == "perturbation":
        pert, mu, sig, amp = random_gauss_perturbation(rng, **_pert_kwargs())
        extra = {"mu": mu.tolist(), "sigma": sig.tolist(), "amplitude": amp.tolist()}
    else:
        raise ValueError(f"spec.category must be one of {list(CATEGORIES)}, got {spec.category!r}")
    n_steps = _n_steps()
    Z = rng.standard_normal((n_steps, DRAWS_PER_STEP))
    f = protocol_rhs_python()
    p = params_vector(params)
    limit = np.zeros(2)
    limit[act] = TORQUE_LIMIT
    drive = np.zeros(2)
    drive[act] = 1.0  # the plant's input matrix: the passive joint's torque (a perturbation there) does nothing
    ratio = 1 if every_step else _hold_ratio(controller)
    n_delay = int(delay / DT) + 1
    dt = DT
    x = np.zeros(4)
    hist = [x]
    last = np.zeros(2)
    held = np.zeros(2)
    t = 0.0
    times = []
    us = [] if record else None
    controller.reset()
    for k in range(n_steps):
        xm = hist[max(-n_delay, -len(hist))] if n_delay > 1 else x
        q_meas = _to_joint(xm) + meas_sigma * Z[k, 0:4]
        if k % ratio == 0:
            c0 = time.perf_counter()
            out = controller(t, _to_absolute(q_meas))
            times.append(time.perf_counter() - c0)
            held = full_input(controller, out)
        nu = last + k_resp * (held - last)
        nu = nu + u_sigma * Z[k, 4:6]
        nu[0] = np.clip(nu[0], -limit[0], limit[0])
        nu[1] = np.clip(nu[1], -limit[1], limit[1])
        idx = int(t / dt)
        if idx < pert.shape[1]:
            nu[0] += pert[0][idx]
            nu[1] += pert[1][idx]
        u = nu * drive
        k1 = f(x, u, p)
        k2 = f(x + 0.5 * dt * k1, u, p)
        k3 = f(x + 0.5 * dt * k2, u, p)
        k4 = f(x + dt * k3, u, p)
        x = x + dt * ((k1 + 2.0 * (k2 + k3) + k4) / 6.0)
        t += dt
        hist.append(x)
        last = nu
        if us is not None:
            us.append(nu)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"run {spec.index} ({spec.category} {spec.param} level {spec.level}) produced a non-finite state")
    q_final = _to_joint(x)
    res: dict[str, Any] = {
        "index": spec.index,
        "category": spec.category,
        "param": spec.param,
        "level_index": spec.level_index,
        "level": None if math.isnan(spec.level) else spec.level,
        "rep": spec.rep,
        "success": _is_success(q_final),
        "final": [float(v) for v in q_final],
        "ctrl_median": float(statistics.median(times)) if times else 0.0,
        "ctrl_max": float(max(times)) if times else 0.0,
        "calls": len(times),
        "wall": time.perf_counter() - w0,
        **extra,
    }
    if record:
        res["t"] = np.arange(n_steps + 1) * dt
        res["x"] = np.array([_to_joint(h) for h in hist])
        res["u"] = np.array(us)
    return res


# -- scores ---------------------------------------------------------------------------------------------------------


def robustness_score(rates: Mapping[str, float]) -> float:
    """The overall score: the mean of the six category rates (``create_leaderboard.py``).

    Parameters
    ----------
    rates : mapping of str to float
        Rate in [0, 1] of every category of :data:`CATEGORIES`.

    Returns
    -------
    float
        ``1/6 * model + 1/6 * measurement_noise + ... + 1/6 * perturbation``.

    Raises
    ------
    KeyError
        A category is missing.
    """
    return (
        1.0 / 6.0 * rates["model"]
        + 1.0 / 6.0 * rates["measurement_noise"]
        + 1.0 / 6.0 * rates["u_noise"]
        + 1.0 / 6.0 * rates["u_responsiveness"]
        + 1.0 / 6.0 * rates["delay"]
        + 1.0 / 6.0 * rates["perturbation"]
    )


def level_successes(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Successes per category and level from run records.

    Parameters
    ----------
    records : sequence of mapping
        Run records (:func:`run_protocol_episode`), any order.

    Returns
    -------
    dict
        ``"model"``: parameter -> [bool per level]; noise categories: [[bool per repetition] per level];
        the others: [bool per level or run] (the input of :func:`category_rates`).
    """
    out: dict[str, Any] = {c: {} for c in CATEGORIES}
    for r in sorted(records, key=lambda r: r["index"]):
        cat = r["category"]
        if cat == "model":
            out["model"].setdefault(r["param"], []).append(bool(r["success"]))
        elif cat in ("measurement_noise", "u_noise"):
            out[cat].setdefault(r["level_index"], []).append(bool(r["success"]))
        else:
            out[cat][r["level_index"]] = bool(r["success"])
    for cat in ("measurement_noise", "u_noise"):
        out[cat] = [out[cat][k] for k in sorted(out[cat])]
    for cat in ("u_responsiveness", "delay", "perturbation"):
        out[cat] = [out[cat][k] for k in sorted(out[cat])]
    return out


def category_rates(successes: Mapping[str, Any]) -> dict[str, float]:
    """Category rates from successes, as ``benchmark_scores.get_scores`` computes them.

    Parameters
    ----------
    successes : mapping
        ``"model"``: mapping parameter -> sequence of bool (one per value);
        ``"measurement_noise"``, ``"u_noise"``: sequence (levels) of sequences (repetitions) of bool;
        ``"u_responsiveness"``, ``"delay"``, ``"perturbation"``: sequence of bool.

    Returns
    -------
    dict of str to float
        Rate of each category present: model = all successes / all runs; noise: fraction of
        levels whose mean success exceeds 0.5; the others: successes / runs.
    """
    rates: dict[str, float] = {}
    if successes.get("model"):
        n = sum(len(v) for v in successes["model"].values())
        s = sum(int(np.sum(v)) for v in successes["model"].values())
        rates["model"] = float(s / n)
    for cat in ("measurement_noise", "u_noise"):
        if len(successes.get(cat, ())):
            lv = np.where(np.average(np.asarray(successes[cat], dtype=float), axis=1) > 0.5, True, False)
            rates[cat] = float(np.sum(lv) / len(lv))
    for cat in ("u_responsiveness", "delay", "perturbation"):
        if len(successes.get(cat, ())):
            rates[cat] = float(np.sum(successes[cat]) / len(successes[cat]))
    return rates


@dataclass
class RobustnessResult:
    """A robustness-v2 run of one controller on one task.

    Attributes
    ----------
    task, controller : str
        Leaderboard task and controller name.
    seed : int
        Seed of the legacy generator (upstream's ``np.random.seed``).
    rates : dict of str to float
        Category rates in [0, 1] (:data:`CATEGORIES`).
    score : float
        Mean of the six rates.
    successes : dict
        Per category and level (see :func:`category_rates`).
    levels : dict
        Levels of the runs (model: parameter -> values; perturbation: run numbers).
    records : list of dict
        Every run (:func:`run_protocol_episode` without trajectories), in the benchmark's order.
    wall_time : float
        Wall time of this call [s] (resumed runs not included).
    sample_time : float
        Controller sample time [s].
    complete : bool
        The full protocol (21 levels, 10 repetitions, 50 perturbation runs) was run.
    """

    task: str
    controller: str
    seed: int
    rates: dict[str, float]
    score: float
    successes: dict[str, Any] = field(repr=False)
    levels: dict[str, Any] = field(repr=False)
    records: list[dict[str, Any]] = field(repr=False)
    wall_time: float
    sample_time: float
    complete: bool

    @property
    def ctrl_time_median(self) -> float:
        """Median over runs of each run's median time per controller call [s]."""
        return float(statistics.median(r["ctrl_median"] for r in self.records)) if self.records else 0.0

    @property
    def ctrl_time_max(self) -> float:
        """Longest controller call of all runs [s]."""
        return float(max(r["ctrl_max"] for r in self.records)) if self.records else 0.0

    def level_rates(self) -> dict[str, Any]:
        """Success fraction per level, for figures.

        Returns
        -------
        dict
            ``"model"``: parameter -> list of 0/1; noise categories: mean over repetitions per
            level; others: 0/1 per level (perturbation: per run).
        """
        out: dict[str, Any] = {"model": {k: [float(b) for b in v] for k, v in self.successes["model"].items()}}
        for cat in ("measurement_noise", "u_noise"):
            out[cat] = [float(np.mean(v)) for v in self.successes.get(cat, [])]
        for cat in ("u_responsiveness", "delay", "perturbation"):
            out[cat] = [float(b) for b in self.successes.get(cat, [])]
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary.

        Returns
        -------
        dict
            protocol, task, controller, seed, score, rates, per-level successes and levels,
            wall time, controller timing (median/max per call, sample time, real-time flag),
            the published rows of the task and the best of them.
        """
        pub = PUBLISHED_ROBUSTNESS[self.task]
        best_name, (_, best) = max(pub.items(), key=lambda kv: kv[1][1])
        return {
            "protocol": "robustness-v2",
            "task": self.task,
            "controller": self.controller,
            "seed": self.seed,
            "complete": self.complete,
            "score": None if math.isnan(self.score) else float(self.score),
            "rates": {k: float(v) for k, v in self.rates.items()},
            "successes": self.successes,
            "level_rates": self.level_rates(),
            "levels": self.levels,
            "runs": len(self.records),
            "wall_time": float(self.wall_time),
            "controller_time": {
                "median_per_call": self.ctrl_time_median,
                "max_per_call": self.ctrl_time_max,
                "sample_time": self.sample_time,
                "real_time": self.ctrl_time_max <= self.sample_time,
            },
            "published": {k: {"rates": [v / 100 for v in r], "score": s} for k, (r, s) in pub.items()},
            "published_best": {"name": best_name, "score": best},
            "beats_published": bool(self.complete and self.score > best),
        }


# -- the protocol ---------------------------------------------------------------------------------------------------


def _levels(plan: Sequence[RunSpec]) -> dict[str, Any]:
    lv: dict[str, Any] = {"model": {}}
    for s in plan:
        if s.category == "model":
            lv["model"].setdefault(s.param, [])
            if s.level not in lv["model"][s.param]:
                lv["model"][s.param].append(s.level)
        else:
            seq = lv.setdefault(s.category, [])
            value = s.level_index if s.category == "perturbation" else s.level
            if value not in seq:
                seq.append(value)
    return lv


#: Settings a journal may lack (written before they existed): the full protocol's values.
_JOURNAL_DEFAULTS: Mapping[str, Any] = {
    "categories": list(CATEGORIES),
    "model_params": list(MODEL_VARIATIONS),
    "u_noise_repetitions": REPETITIONS,
    "every_step": False,
}


def _read_journal(path: Path, settings: Mapping[str, Any]) -> dict[int, dict[str, Any]]:
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text())
        recs = {int(r["index"]): r for r in data["records"]}
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"journal {path} is not a robustness-v2 journal ({exc})") from None
    stored = {**_JOURNAL_DEFAULTS, **data.get("settings", {})}
    differ = {k: (stored.get(k), v) for k, v in settings.items() if stored.get(k) != v}
    if differ:
        what = ", ".join(f"{k} {old!r} there, {new!r} now" for k, (old, new) in differ.items())
        raise ValueError(f"journal {path} was written with other settings ({what}); use another journal or resume=False")
    return recs


def robustness_v2(
    task: str,
    controller: str | SampledController | Callable[[str], Any] = "best",
    *,
    seed: int = 0,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    journal: str | Path | None = None,
    resume: bool = False,
    levels: Sequence[int] | None = None,
    repetitions: int = REPETITIONS,
    perturbation_repetitions: int = PERTURBATION_REPETITIONS,
    categories: Sequence[str] | None = None,
    model_params: Sequence[str] | None = None,
    u_noise_repetitions: int = REPETITIONS,
    every_step: bool = False,
) -> RobustnessResult:
    """Score a controller on the RealAIGym robustness leaderboard v2 protocol.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (``swingup_pendubot``, ``swingup_acrobot`` are aliases).
    controller : str, SampledController or callable
        See :func:`resolve_controller` (names: :data:`CONTROLLERS`).
    seed : int
        Seed of the legacy generator; the draws equal upstream's after ``np.random.seed(seed)``.
    workers : int, optional
        Worker processes (:func:`pendulab.ensemble.pool.map_runs`; default all cores).
    progress : callable, optional
        ``progress(done, total)`` in runs (journaled runs count as done).
    journal : str or Path, optional
        JSON file rewritten atomically after every batch of finished runs (settings and records).
    resume : bool
        Read ``journal`` first and run only the runs it lacks (same settings, else ValueError).
    levels : sequence of int, optional
        Reduced grid: the grid indices (0 ... 20) to run in every category (default all).
    repetitions : int
        Repetitions per measurement-noise level (upstream 10; torque noise: always 10, as upstream).
    perturbation_repetitions : int
        Perturbation runs (upstream 50).
    categories, model_params, u_noise_repetitions
        A reduced protocol (tests, comparisons): see :func:`plan_runs`. Without all six
        categories the score is NaN (``None`` in :meth:`RobustnessResult.to_dict`).
    every_step : bool
        Call the controller every 2 ms step (as upstream's simulator calls its controllers) instead of on
        its own sample grid with the output held. A 10 ms controller fed fresh noisy measurements every
        2 ms averages the velocity noise out; held, one noisy sample drives 10 ms.

    Returns
    -------
    RobustnessResult
        Rates, score, per-level successes, records, wall time, controller timing.

    Raises
    ------
    ValueError
        Unknown task or controller name, bad grid, seed out of range, a journal of other settings,
        a controller whose sample time is not a multiple of 2 ms.
    TypeError
        A controller that is neither a name, a controller nor a factory.
    KeyboardInterrupt
        Ctrl-C (the batches finished before it are in the journal).
    """
    if not isinstance(task, str):
        raise TypeError(f"task must be 'pendubot' or 'acrobot', got {type(task).__name__}")
    task = check_task(short_name(task))
    seed = bounded_int("seed", seed, low=0, high=2**32 - 1, why="a seed of numpy's legacy RandomState")
    if resume and journal is None:
        raise ValueError("resume=True needs a journal path")
    w0 = time.perf_counter()
    plan = plan_runs(
        task, levels=levels, repetitions=repetitions, perturbation_repetitions=perturbation_repetitions,
        categories=categories, model_params=model_params, u_noise_repetitions=u_noise_repetitions,
    )  # fmt: skip
    name, ctrl = resolve_controller(task, controller)
    if not every_step:
        _hold_ratio(ctrl)
    settings = {
        "protocol": "robustness-v2",
        "task": task,
        "controller": name,
        "seed": seed,
        "levels": None if levels is None else sorted({int(v) for v in levels}),
        "repetitions": int(repetitions),
        "perturbation_repetitions": int(perturbation_repetitions),
        "categories": list(_check_names("categories", categories, CATEGORIES)),
        "model_params": list(_check_names("model_params", model_params, MODEL_VARIATIONS)),
        "u_noise_repetitions": int(u_noise_repetitions),
        "every_step": bool(every_step),
    }
    jpath = None if journal is None else Path(journal)
    done: dict[int, dict[str, Any]] = _read_journal(jpath, settings) if (resume and jpath is not None) else {}
    total = len(plan)
    if progress is not None:
        progress(len(done), total)
    states = _rng_states(plan, seed, _n_steps())

    def one(i: int) -> dict[str, Any]:
        return run_protocol_episode(task, ctrl, plan[i], states[i], every_step=every_step)

    def save() -> None:
        if jpath is not None:
            jpath.parent.mkdir(parents=True, exist_ok=True)
            recs = [done[i] for i in sorted(done)]
            atomic_write_text(jpath, json.dumps({"settings": settings, "records": recs}) + "\n")

    todo = [s.index for s in plan if s.index not in done]
    n_work = default_workers() if workers is None else bounded_int("workers", workers, high=256, why="worker processes")
    per = max(8, 4 * n_work)
    for b in range(0, len(todo), per):
        batch = todo[b : b + per]
        base = len(done)

        def report(k: int, n: int, base: int = base) -> None:
            if progress is not None:
                progress(base + k, total)

        for rec in map_runs(one, batch, workers=n_work, progress=report, chunks_per_worker=1):
            done[rec["index"]] = rec
        save()
    records = [done[s.index] for s in plan]
    successes = level_successes(records)
    rates = category_rates(successes)
    complete = (
        levels is None and repetitions == REPETITIONS and perturbation_repetitions == PERTURBATION_REPETITIONS
        and categories is None and model_params is None and u_noise_repetitions == REPETITIONS
    )  # fmt: skip
    score = robustness_score(rates) if all(c in rates for c in CATEGORIES) else math.nan
    return RobustnessResult(
        task, name, seed, rates, score, successes, _levels(plan), records,
        time.perf_counter() - w0, DT if every_step else float(ctrl.sample_time), complete,
    )  # fmt: skip

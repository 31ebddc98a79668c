"""The published rows of RealAIGym's three simulation protocols, with where each number comes from.

Every number below is upstream's, as printed on its leaderboard page (rounded there); nothing is recomputed here.
The tests recompute each published score from its published criteria / category rates with the protocol's score
formula (:func:`~.criteria.score_v2`, :func:`~.robustness_scores.robustness_score`) to the pages' rounding.

* **v2 performance** (``pendulab score --protocol v2``): pages ``{pendubot,acrobot}_simulation_performance_leaderboard_v2``
  of the RealAIGym leaderboard site (stored copies); the entries are the controllers
  ``leaderboard/{task}/simulation_v2/con_<name>.py`` of ``github.com/dfki-ric-underactuated-lab/double_pendulum``
  (commit 1e8544e; the protocol as docs/realai.md cites it, ``simulation_v2`` at commit 699c934).
* **robustness v2**: pages ``{pendubot,acrobot}_simulation_robustness_leaderboard_v2``; entries
  ``leaderboard/{task}/robustness_v2/con_<name>.py`` (commit 1e8544e). Upstream publishes the six category rates and
  the overall score only, no per-level successes.
* **v3** (ICRA 2025 competition, simulation): every entry's one published run, score and swing-ups
  (``PUBLISHED_V3_RUNS``: ``real_ai_gym_leaderboard``, ``leaderboards/icra2025/ICRA_2025_<task>_simulation_results.csv``);
  the entries are upstream's ``leaderboard/{task}/simulation_v3/con_<name>.py`` (commit 1e8544e).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from .criteria import CRITERIA
from .robustness_grid import CATEGORIES, PUBLISHED_ROBUSTNESS
from .v3_definition import PUBLISHED_V3_RUNS

__all__ = [
    "PublishedRow",
    "PUBLISHED_V2_ROWS",
    "PUBLISHED_ROBUSTNESS_ROWS",
    "PUBLISHED_V3_ROWS",
    "PUBLISHED_HARDWARE",
    "SOURCES",
    "UPSTREAM_COMMIT",
]

#: The stored copy of upstream's repository that the protocols were read in.
UPSTREAM_COMMIT: str = "1e8544e67f3da72a51ee52fbbb278e131ce2a43f"


@dataclass(frozen=True)
class PublishedRow:
    """One published leaderboard entry.

    Attributes
    ----------
    name : str
        Upstream's controller id (``con_<name>.py``).
    label : str
        The name on the leaderboard page.
    score : float or None
        The published score (None: not in the stored sources).
    values : mapping of str to float
        v2: the five criteria (:data:`~.criteria.CRITERIA`); robustness v2: the six category rates in [0, 1]
        (:data:`~.robustness_grid.CATEGORIES`); v3: ``swingups`` and ``uptime_s`` [s] of the published run.
    source : str
        Where the row comes from.
    """

    name: str
    label: str
    score: float | None
    values: Mapping[str, float]
    source: str


def _v2(task: str, rows: list[tuple[str, str, tuple[float, ...], float]]) -> tuple[PublishedRow, ...]:
    src = (
        f"page {task}_simulation_performance_leaderboard_v2; controller leaderboard/{task}/simulation_v2/con_NAME.py "
        f"@ {UPSTREAM_COMMIT[:7]}"
    )
    return tuple(
        PublishedRow(name, label, score, dict(zip(CRITERIA, crit, strict=True)), src.replace("NAME", name))
        for name, label, crit, score in sorted(rows, key=lambda r: -r[3])
    )


#: Published v2 performance rows: swing-up time [s], energy [J], torque cost [N^2 m^2 s], torque smoothness [N m],
#: velocity cost [rad^2/s], score (pages ``{task}_simulation_performance_leaderboard_v2``), best first.
PUBLISHED_V2_ROWS: Mapping[str, tuple[PublishedRow, ...]] = {
    "pendubot": _v2(
        "pendubot",
        [
            ("mcpilco", "mcpilco", (1.14, 8.35, 2.42, 0.054, 114.26), 0.480),
            ("history_sac", "History SAC", (1.15, 7.67, 2.36, 0.007, 62.07), 0.682),
            ("ar_eapo", "AR-EAPO", (1.15, 7.72, 2.43, 0.01, 64.33), 0.659),
            ("ilqr_riccati_lqr", "iLQR Riccati Gains", (4.13, 9.53, 1.25, 0.005, 211.34), 0.536),
            ("evolsac", "evolsac", (0.71, 9.83, 4.37, 0.014, 58.15), 0.596),
            ("ilqr_tvlqr_lqr", "TVLQR", (4.13, 9.53, 1.26, 0.007, 211.12), 0.526),
            ("ilqr_ilqrmpc_lqr", "iLQR MPC stabilization", (4.12, 9.91, 1.77, 0.083, 211.98), 0.353),
        ],
    ),
    "acrobot": _v2(
        "acrobot",
        [
            ("mcpilco", "mcpilco", (1.45, 19.43, 3.22, 0.097, 253.59), 0.316),
            ("history_sac", "History SAC", (1.0, 8.08, 1.8, 0.01, 88.5), 0.655),
            ("ilqr_tvlqr", "TVLQR", (4.05, 10.43, 1.87, 0.016, 105.83), 0.504),
            ("ar_eapo", "AR-EAPO", (1.39, 8.32, 1.52, 0.008, 117.96), 0.633),
            ("ilqr_riccati_lqr", "iLQR Riccati Gains", (4.04, 10.55, 1.98, 0.067, 106.49), 0.396),
            ("evolsac", "evolsac", (0.96, 9.26, 2.71, 0.03, 96.56), 0.524),
            ("ilqr_ilqrmpc_lqr", "iLQR MPC stabilization", (4.86, 11.54, 2.68, 0.096, 110.4), 0.345),
        ],
    ),
}

_RV2_LABELS = {
    "ar_eapo": "AR-EAPO",
    "evolsac": "evolsac",
    "history_sac": "History SAC",
    "tvlqr": "TVLQR",
    "ilqr_mpc_stabilization": "iLQR MPC stabilization",
    "mcpilco": "mcpilco",
    "ilqr_riccati_gains": "iLQR Riccati Gains",
}


def _rv2(task: str) -> tuple[PublishedRow, ...]:
    page = f"{task}_simulation_robustness_leaderboard_v2"
    src = f"page {page}; controllers leaderboard/{task}/robustness_v2/ @ {UPSTREAM_COMMIT[:7]}"
    rows = [
        PublishedRow(name, _RV2_LABELS.get(name, name), score, {c: r / 100 for c, r in zip(CATEGORIES, rates, strict=True)}, src)
        for name, (rates, score) in PUBLISHED_ROBUSTNESS[task].items()
    ]
    return tuple(sorted(rows, key=lambda r: -(r.score or 0.0)))


#: Published robustness-v2 rows (the six category rates as fractions and the score), best first.
PUBLISHED_ROBUSTNESS_ROWS: Mapping[str, tuple[PublishedRow, ...]] = {t: _rv2(t) for t in ("pendubot", "acrobot")}

_V3_LABELS = {
    "vimppi": "VIMPPI",
    "ar_eapo": "AR-EAPO",
    "acados_mpc": "AcadosMpc",
    "mcpilco": "mcpilco",
    "prx_pendubot_analytical": "prx_analytical",
    "prx_acrobot_analytical": "prx_analytical",
}


def _v3(task: str) -> tuple[PublishedRow, ...]:
    src = (
        f"ICRA 2025 simulation results (real_ai_gym_leaderboard, ICRA_2025_{task}_simulation_results.csv); "
        f"controllers leaderboard/{task}/simulation_v3/ @ {UPSTREAM_COMMIT[:7]}"
    )
    return tuple(
        PublishedRow(name, _V3_LABELS.get(name, name), score, {"swingups": float(n), "uptime_s": up}, src)
        for name, (score, n, up) in PUBLISHED_V3_RUNS[task].items()
    )


#: v3 entries: every ICRA 2025 entry's published simulation run (score, swing-ups and uptime in ``values``).
PUBLISHED_V3_ROWS: Mapping[str, tuple[PublishedRow, ...]] = {t: _v3(t) for t in ("pendubot", "acrobot")}

#: ICRA 2025 hardware final, v3 score of each entry's best run on the real robot (issue 30; upstream
#: ``real_ai_gym_leaderboard``, ``leaderboards/icra2025/*_real_system_results.csv``).
PUBLISHED_HARDWARE: Mapping[str, Mapping[str, float]] = {
    "pendubot": {"acados_mpc": 0.721, "ar_eapo": 0.714, "mcpilco": 0.559, "vimppi": 0.401},
    "acrobot": {"acados_mpc": 0.775, "ar_eapo": 0.655, "mcpilco": 0.585, "vimppi": 0.408},
}

#: Where each protocol's published rows and definition come from (cited under each table).
SOURCES: Mapping[str, str] = {
    "v2": (
        "Published rows: RealAIGym leaderboard pages `pendubot_simulation_performance_leaderboard_v2` and "
        "`acrobot_simulation_performance_leaderboard_v2` (stored copies), criteria and score as printed there; entries "
        f"are upstream's `leaderboard/{{pendubot,acrobot}}/simulation_v2/con_<name>.py` "
        f"(github.com/dfki-ric-underactuated-lab/double_pendulum @ {UPSTREAM_COMMIT[:7]}). Protocol: "
        "`simulation_v2/sim_parameters.py`, `create_leaderboard.py` (commit 699c934), `analysis/leaderboard.py` "
        "(commit 03b4df7); docs/realai.md."
    ),
    "robustness-v2": (
        "Published rows: RealAIGym leaderboard pages `pendubot_simulation_robustness_leaderboard_v2` and "
        "`acrobot_simulation_robustness_leaderboard_v2` (stored copies): six category rates and the overall score only "
        "(no per-level data). Protocol: upstream's `leaderboard/{pendubot,acrobot}/robustness_v2/benchmark_controller.py`, "
        "`analysis/benchmark.py`, `analysis/benchmark_scores.py`, `create_leaderboard.py` "
        f"@ {UPSTREAM_COMMIT[:7]}; docs/realai.md."
    ),
    "v3": (
        "Published rows: every entry's run in the ICRA 2025 competition's simulation stage, score and swing-ups "
        "(`real_ai_gym_leaderboard`, `leaderboards/icra2025/ICRA_2025_{pendubot,acrobot}_simulation_results.csv`); the "
        "entries are upstream's `leaderboard/{pendubot,acrobot}/simulation_v3/con_<name>.py` "
        f"@ {UPSTREAM_COMMIT[:7]}. Upstream runs one unseeded episode per entry, so no per-seed scores are published "
        "(the hardware-final versions of four of these entries, run through pendulab's protocols: "
        "benchmarks/results/upstream_entries.md). Protocol: `simulation_v3/sim_parameters.py`, "
        "`calculate_leaderboard_score.py`, `controller/global_policy_testing_controller.py`; docs/realai_v3.md."
    ),
}

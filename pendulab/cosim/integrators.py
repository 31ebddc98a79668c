"""Does a controller's nominal episode depend on the integrator? The same run through every engine and tolerance.

A swing-up that succeeds with one integrator can fail with another when the closed loop amplifies
integration error (a chaotic pumping phase, a marginal catch). :func:`integrator_runs` runs the task's
nominal episode (no perturbation, the task's start, length and success rule ``y2 > 0.9 (L1 + L2)`` until
the end) through

* the native integrators (:func:`pendulab.simulate`, ``method`` x ``rtol = atol``; the controller as
  sampled feedback, :func:`~pendulab.control.feedback.as_feedback`),
* the exported FMU (:func:`pendulab.cosim.cosim`, embedded ``solver`` x ``tolerance``; communication
  step = the sample time), the path of ``pendulab cosim``,
* the scorecard's plant (:func:`~pendulab.evaluate.run_perturbed_episode`: fixed-step RK4 substeps),

so that a claim such as "nominal ok" (``docs/leaderboard.md``) says with which integrators it holds.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

__all__ = [
    "NATIVE_METHODS",
    "FMU_SOLVERS",
    "TOLERANCES",
    "IntegratorRun",
    "integrator_runs",
    "integrator_summary",
    "integrator_table",
]

#: Native integrators of the check (``pendulab.simulate`` methods).
NATIVE_METHODS: tuple[str, ...] = ("auto", "cvodes", "compiled-dopri5", "compiled-rodas4")
#: Embedded solvers of the FMU (``pendulab cosim --solver``).
FMU_SOLVERS: tuple[str, ...] = ("dopri5", "rodas4")
#: Relative (= absolute) tolerances of the check.
TOLERANCES: tuple[float, ...] = (1e-6, 1e-8, 1e-10, 1e-12)


@dataclass(frozen=True)
class IntegratorRun:
    """One nominal episode.

    Attributes
    ----------
    engine : {"native", "cosim", "scorecard"}
        ``pendulab.simulate``, the FMU through ``pendulab.cosim``, or the scorecard's RK4 plant.
    method : str
        Native method, FMU solver, or ``"rk4"`` (scorecard).
    tolerance : float or None
        ``rtol = atol`` (native), the FMU's tolerance; None for the fixed-step scorecard plant.
    success : bool
        The task's success rule.
    t_up : float
        Start of the final stretch above the line [s] (nan on failure).
    """

    engine: str
    method: str
    tolerance: float | None
    success: bool
    t_up: float

    @property
    def label(self) -> str:
        """e.g. ``cvodes 1e-10``, ``cosim dopri5 1e-08``, ``scorecard rk4``."""
        head = {"native": self.method, "cosim": f"cosim {self.method}", "scorecard": f"scorecard {self.method}"}[self.engine]
        return head if self.tolerance is None else f"{head} {self.tolerance:g}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields.

        Returns
        -------
        dict
            The attributes, ``t_up`` nan as None.
        """
        d = asdict(self)
        d["t_up"] = None if math.isnan(self.t_up) else self.t_up
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> IntegratorRun:
        """Inverse of :meth:`to_dict`."""
        t_up = d.get("t_up")
        return cls(str(d["engine"]), str(d["method"]), d.get("tolerance"), bool(d["success"]), math.nan if t_up is None else t_up)


def integrator_runs(
    factory: Callable[[], tuple[Any, Any]],
    task: Any,
    *,
    methods: Sequence[str] = NATIVE_METHODS,
    solvers: Sequence[str] = FMU_SOLVERS,
    tolerances: Sequence[float] = TOLERANCES,
    scorecard: bool = True,
    fmu: str | Path | None = None,
) -> tuple[IntegratorRun, ...]:
    """The task's nominal episode with each integrator and tolerance.

    Parameters
    ----------
    factory : callable
        ``factory() -> (controller, x0)``, e.g. ``lambda: controller_for_task("swingup", task)``; called once
        per run (a fresh controller: no state carried over).
    task : Task
        Model, start, episode length, success fraction.
    methods : sequence of str
        Native methods (empty: none).
    solvers : sequence of str
        FMU solvers (empty: no co-simulation, no FMU export).
    tolerances : sequence of float
        ``rtol = atol`` of every native method and FMU solver.
    scorecard : bool
        Also the scorecard's fixed-step RK4 plant.
    fmu : path-like, optional
        FMU of ``task.model`` (default: exported into a temporary folder when ``solvers`` is not empty).

    Returns
    -------
    tuple of IntegratorRun
        Native runs (methods x tolerances), then co-simulation (solvers x tolerances), then the scorecard's.
    """
    from ..control.feedback import as_feedback
    from ..control.swingup.check import height_success
    from ..evaluate.perturb import run_perturbed_episode
    from ..integrate import simulate

    out: list[IntegratorRun] = []
    for method in methods:
        for tol in tolerances:
            ctrl, x0 = factory()
            ctrl.reset()
            traj = simulate(task.model, x0, task.t_final, dt=ctrl.sample_time, method=method, rtol=tol, atol=tol,
                            u=as_feedback(ctrl, task.model))  # fmt: skip
            hs = height_success(traj, task.rest_lengths, task.success_fraction)
            out.append(IntegratorRun("native", method, float(tol), bool(hs.success), float(hs.t_up)))
    if solvers:
        from .master import cosim

        with tempfile.TemporaryDirectory(prefix="pendulab-integrators-") as tmp:
            path = fmu
            if path is None:
                from ..fmu import export

                path = export(task.model, Path(tmp) / "plant.fmu", 2, timestamp=False)
            for solver in solvers:
                for tol in tolerances:
                    ctrl, x0 = factory()
                    ctrl.reset()
                    traj = cosim(path, ctrl, ctrl.sample_time, task.t_final, x0=x0, solver=solver, tolerance=tol)
                    hs = height_success(traj, task.rest_lengths, task.success_fraction)
                    out.append(IntegratorRun("cosim", solver, float(tol), bool(hs.success), float(hs.t_up)))
    if scorecard:
        ctrl, x0 = factory()
        res = run_perturbed_episode(ctrl, task, x0)
        out.append(IntegratorRun("scorecard", "rk4", None, bool(res.success), float(res.t_up)))
    return tuple(out)


def integrator_summary(runs: Sequence[IntegratorRun]) -> str:
    """One phrase: with which integrators the nominal episode succeeds.

    Parameters
    ----------
    runs : sequence of IntegratorRun
        From :func:`integrator_runs`.

    Returns
    -------
    str
        ``"ok with every integrator (25 runs)"``, ``"fails with every integrator (25 runs)"`` or
        ``"ok in 24 of 25 integrator runs, fails with cvodes 1e-06"``.
    """
    bad = [r.label for r in runs if not r.success]
    if not bad:
        return f"ok with every integrator ({len(runs)} runs)"
    if len(bad) == len(runs):
        return f"fails with every integrator ({len(runs)} runs)"
    return f"ok in {len(runs) - len(bad)} of {len(runs)} integrator runs, fails with {', '.join(bad)}"


def integrator_table(results: dict[str, Sequence[IntegratorRun]]) -> list[str]:
    """Markdown table: one row per engine and method, one column per tolerance, one block per task.

    Parameters
    ----------
    results : dict of str to sequence of IntegratorRun
        Task name -> runs.

    Returns
    -------
    list of str
        Lines; a cell is ``ok (t_up s)`` or ``**fails**`` (the fixed-step scorecard plant: one run, first column).
    """
    tols = sorted({r.tolerance for runs in results.values() for r in runs if r.tolerance is not None}, reverse=True)
    lines = ["| task | integrator | " + " | ".join(f"tol {t:g}" for t in tols) + " |", "|---|---|" + "---|" * len(tols)]
    for task_name, runs in results.items():
        rows: dict[tuple[str, str], dict[float | None, IntegratorRun]] = {}
        for r in runs:
            rows.setdefault((r.engine, r.method), {})[r.tolerance] = r
        for (engine, method), cells in rows.items():
            names = {
                "native": f"`{method}`",
                "cosim": f"cosim (FMU `{method}`)",
                "scorecard": f"scorecard plant ({method}, fixed step)",
            }
            name = names[engine]

            def cell(r: IntegratorRun | None) -> str:
                if r is None:
                    return ""
                return f"ok ({r.t_up:.2f} s)" if r.success else "**fails**"

            if None in cells:  # fixed step: one run, in the first column
                texts = [cell(cells[None])] + [""] * (len(tols) - 1)
            else:
                texts = [cell(cells.get(t)) for t in tols]
            lines.append(f"| {task_name} | {name} | " + " | ".join(texts) + " |")
    return lines

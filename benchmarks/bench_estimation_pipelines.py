"""State estimation in the three pipelines: the scorecard, co-simulation and the Gymnasium env (docs/estimation.md).

Measures (1) the scorecard of ``tvlqr`` on pendubot and acrobot without an estimator, with the EKF and with the
delay-identifying bank (``--runs`` per level, seed 0, one worker); (2) the RMS error of the link rates the controller
(or agent) is given, the raw measurement against the EKF's estimate, in each pipeline; (3) the co-simulated acrobot
swing-up under velocity noise over seeds, with and without the EKF. Writes benchmarks/results/estimation_pipelines.md.

Usage::

    nice python benchmarks/bench_estimation_pipelines.py             # ~15 min on a loaded 2-core machine
    nice python benchmarks/bench_estimation_pipelines.py --runs 2 --seeds 2 --out /tmp/pipelines.md   # a smoke run
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).parent / "results" / "estimation_pipelines.md"


class Recorder:
    """A controller that keeps the states it is given."""

    def __init__(self, ctrl):
        self.ctrl, self.sample_time, self.input_names = ctrl, ctrl.sample_time, ctrl.input_names
        self.u_max = getattr(ctrl, "u_max", None)
        self.seen: list[np.ndarray] = []

    def reset(self):
        self.ctrl.reset()
        self.seen = []

    def __call__(self, t, x):
        self.seen.append(np.array(x, dtype=float))
        return self.ctrl(t, x)


def _rms(seen, x, nq):
    s = np.array(seen)
    return float(np.sqrt(np.mean((s[:, nq : nq + 2] - x[: len(s), nq : nq + 2]) ** 2)))


def _rates(cat) -> str:
    return f"{cat.score:.2f} ({', '.join(f'{r:.0%}' for r in cat.success_rates)})"


def scorecards(runs: int) -> list[str]:
    from pendulab.evaluate import score

    lines = [
        "| task | estimator | measurement_noise | delay | overall | wall [s] |",
        "|---|---|---|---|---|---|",
    ]
    for task in ("pendubot", "acrobot"):
        for est in (None, "ekf", "mmae"):
            card = score("tvlqr", task, runs=runs, workers=1, estimator=est)
            cells = {c.name: c for c in card.categories}
            lines.append(
                f"| {task} | {est or 'none'} | {_rates(cells['measurement_noise'])} | {_rates(cells['delay'])} | "
                f"{card.overall:.3f} | {card.wall_time:.0f} |"
            )
            print(lines[-1], flush=True)
    return lines


def rms_rows(sigma: float = 0.3) -> list[str]:
    import gymnasium as gym

    import pendulab as pl
    import pendulab.gym  # noqa: F401
    from pendulab.control.controllers import controller_for_task
    from pendulab.control.feedback import balance_controller, upright_state
    from pendulab.control.robust import EstimatedController, build_estimator
    from pendulab.control.swingup.tasks import load_task
    from pendulab.cosim import cosim
    from pendulab.evaluate import Perturbation, run_perturbed_episode
    from pendulab.evaluate.measurement import MeasurementModel
    from pendulab.fmu import export

    rows = ["| pipeline | run | measurement RMS [rad/s] | EKF estimate RMS [rad/s] |", "|---|---|---|---|"]
    task = load_task("pendubot")
    ctrl, x0 = controller_for_task("tvlqr", task)
    out = []
    for est in (None, "ekf"):
        rec = Recorder(ctrl)
        lim = task.problem.torque_limit
        c = (
            rec
            if est is None
            else EstimatedController(rec, build_estimator(est, task.model, task.dt, x0=x0, torque_limit=(lim, 0.0)), u_max=lim)
        )
        res = run_perturbed_episode(c, task, x0, Perturbation(meas_noise=sigma, seed=(0, 6, 3, 0)))
        out.append(_rms(rec.seen, res.x, 2))
    rows.append(f"| scorecard episode | tvlqr swing-up, pendubot, noise {sigma} | {out[0]:.4f} | {out[1]:.4f} |")
    with tempfile.TemporaryDirectory() as tmp:
        model = pl.rigid()
        fmu = export(model, Path(tmp) / "rigid.fmu", 2)
        x0 = upright_state(model)
        x0[0] += 0.1
        out = []
        for est in (None, "ekf"):
            rec = Recorder(balance_controller(model, 0.01))
            traj = cosim(fmu, rec, 0.01, 5.0, x0=x0, measurement=MeasurementModel(sigma, seed=1), estimator=est)
            out.append(_rms(rec.seen, traj.x, 2))
        rows.append(f"| cosim (FMU) | lqr balance, rigid, noise {sigma} | {out[0]:.4f} | {out[1]:.4f} |")
    out = []
    for est in (None, "ekf"):
        env = gym.make("pendulab/DoublePendulum-v0", actuation="pendubot", measurement=MeasurementModel(sigma), estimator=est)
        env.reset(seed=4)
        errs = []
        for k in range(300):
            env.step(np.array([0.8 * np.sin(0.06 * k)], dtype=np.float32))
            errs.append(env.unwrapped.estimate[2:4] - env.unwrapped.state[2:4])
        out.append(float(np.sqrt(np.mean(np.square(errs)))))
    rows.append(f"| gym env | pendubot, pumping torque, 300 steps, noise {sigma} | {out[0]:.4f} | {out[1]:.4f} |")
    for r in rows[2:]:
        print(r, flush=True)
    return rows


def cosim_task(seeds: int, sigma: float = 0.3) -> list[str]:
    from pendulab.control.controllers import controller_for_task
    from pendulab.control.swingup.check import height_success
    from pendulab.control.swingup.tasks import load_task
    from pendulab.cosim import cosim
    from pendulab.evaluate.measurement import MeasurementModel
    from pendulab.fmu import export

    task = load_task("acrobot")
    ok = {None: 0, "ekf": 0}
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export(task.model, Path(tmp) / "acrobot.fmu", 2)
        params = {n: float(getattr(task.model.params, n)) for n in task.model.param_names}
        for seed in range(seeds):
            for est in ok:
                ctrl, x0 = controller_for_task("tvlqr", task)
                traj = cosim(fmu, ctrl, task.dt, task.t_final, x0=x0, params=params,
                             measurement=MeasurementModel(sigma, seed=seed), estimator=est)  # fmt: skip
                check = height_success(traj, task.rest_lengths, task.success_fraction)
                ok[est] += bool(check.success and check.t_up <= traj.t[-1] - 1.0 + 1e-9)
    line = (
        f"acrobot tvlqr co-simulated, velocity noise {sigma} rad/s, seeds 0-{seeds - 1}: success {ok[None]}/{seeds} "
        f"on the measurement, {ok['ekf']}/{seeds} on the EKF"
    )
    print(line, flush=True)
    return [line]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=5, help="scorecard runs per level of the stochastic categories")
    ap.add_argument("--seeds", type=int, default=5, help="co-simulated acrobot runs per estimator")
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args()
    t0 = time.perf_counter()
    md = ["# State estimation in the pipelines (benchmarks/bench_estimation_pipelines.py)", ""]
    md += ["## Rate error of what the controller is given", "", *rms_rows(), ""]
    md += ["## Co-simulated swing-up under velocity noise", "", *cosim_task(args.seeds), ""]
    md += [f"## Scorecard: tvlqr, {args.runs} runs per stochastic level, seed 0, one worker", "", *scorecards(args.runs), ""]
    md += [f"Total wall time {time.perf_counter() - t0:.0f} s (shared machine)."]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(md) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

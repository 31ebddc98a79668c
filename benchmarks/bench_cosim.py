"""Co-simulation master overhead per communication step vs time inside doStep.

For 1 ms and 10 ms communication steps (1000 steps each), rigid and elastic FMUs
(FMI 2 and FMI 3, embedded dopri5, tolerance 1e-8), LQR balance from 0.1 rad:

* doStep: time inside fmpy's ``doStep`` (the FMU's embedded solver + ctypes call);
* controller: time inside the controller's ``__call__`` (NumPy LQR law);
* master: the rest of the loop (getReal/getFloat64 of states and outputs,
  setReal of inputs, bookkeeping), per step;
* peer: the native sampled loop ``pendulab.simulate(..., u=controller)`` with
  CVODES, same controller and step, per step.

Medians over ``--repeats`` runs. Usage::

    PYTHONPATH=. python benchmarks/bench_cosim.py [--repeats 5] [--out benchmarks/results/cosim.md]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import pendulab as pl
from pendulab.control.feedback import LinearStateFeedback, as_feedback, balance_controller, upright_state
from pendulab.cosim import cosim
from pendulab.fmu.export import export


class TimedController(LinearStateFeedback):
    """LQR law that accumulates the time spent in its own calls."""

    spent: float = 0.0

    def __call__(self, t, x):
        start = time.perf_counter()
        try:
            return super().__call__(t, x)
        finally:
            self.spent += time.perf_counter() - start


def measure(fmu: Path, model: pl.Model, h: float, n_steps: int) -> dict[str, float]:
    base = balance_controller(model, h)
    ctrl = TimedController(model, base.K, base.x_eq, base.u_eq, h, base.input_names)
    x0 = upright_state(model)
    x0[0] += 0.1
    traj = cosim(fmu, ctrl, h, n_steps * h, x0=x0, solver="dopri5", tolerance=1e-8)
    wall, inside = traj.stats["wall_time"], traj.stats["time_in_do_step"]
    start = time.perf_counter()
    pl.simulate(model, x0, n_steps * h, dt=h, u=as_feedback(ctrl, model), rtol=1e-8, atol=1e-8)
    native = time.perf_counter() - start
    return {
        "do_step": inside / n_steps * 1e6,
        "controller": ctrl.spent / n_steps * 1e6,
        "master": (wall - inside - ctrl.spent) / n_steps * 1e6,
        "total": wall / n_steps * 1e6,
        "native": native / n_steps * 1e6,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--steps", type=int, default=1000, help="communication steps per run")
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "cosim.md")
    args = parser.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for version in (2, 3):
            for kind in ("rigid", "elastic"):
                model = pl.make_model(kind)
                print(f"exporting {kind} FMI {version}", file=sys.stderr, flush=True)
                fmu = export(model, Path(tmp) / f"{kind}{version}.fmu", version)
                for h in (1e-3, 1e-2):
                    runs = []
                    for r in range(args.repeats):
                        print(
                            f"  FMI {version} {kind} h = {h * 1e3:g} ms run {r + 1}/{args.repeats}", file=sys.stderr, flush=True
                        )
                        runs.append(measure(fmu, model, h, args.steps))
                    med = {k: statistics.median(run[k] for run in runs) for k in runs[0]}
                    rows.append((version, kind, h, med))
    lines = [
        "# Co-simulation master: overhead per communication step",
        "",
        f"`PYTHONPATH=. python benchmarks/bench_cosim.py --repeats {args.repeats} --steps {args.steps}` on "
        f"{platform.machine()} / Python {platform.python_version()} (shared 2-core machine: absolute numbers are noisy, "
        "ratios are measured in the same run).",
        "",
        f"Medians of {args.repeats} runs of {args.steps} communication steps; LQR balance from 0.1 rad; embedded dopri5, "
        "tolerance 1e-8. Times in microseconds per communication step. *master* = loop time outside doStep and the "
        "controller (reading states/outputs, setting inputs, bookkeeping through fmpy/ctypes). *native* = the same "
        "sampled loop through `pendulab.simulate` (CVODES, one integrator call per step). Each column is its own median, "
        "so the columns do not add up exactly to *total*.",
        "",
        "| FMI | plant | comm step | doStep [µs] | controller [µs] | master [µs] | master / doStep | total [µs] "
        "| native loop [µs] | native / total |",
        "|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for version, kind, h, m in rows:
        lines.append(
            f"| {version} | {kind} | {h * 1e3:g} ms | {m['do_step']:.1f} | {m['controller']:.1f} | {m['master']:.1f} | "
            f"{m['master'] / m['do_step']:.2f} | {m['total']:.1f} | {m['native']:.1f} | {m['native'] / m['total']:.1f} |"
        )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

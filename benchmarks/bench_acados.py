"""pendulab's RTI against acados' SQP-RTI: the same OCP, the same states, per-call time, first torques, swing-ups.

The OCP is the ICRA 2025 winner's acados MPC (``experiments/icra_2025/con_acados_mpc_*.py`` of the
double_pendulum repository) built twice, in pendulab (:func:`pendulab.control.nmpc.rti.rti_for_task`) and
in acados (``benchmarks/acados_worker.py``, in its own venv), for the same model, weights and constraints:

* N = 20 intervals over 0.5 s on the winner's non-uniform grid, 13 of 4 ms then 7 of 64 ms (upstream
  computes this grid under ``nonuniform_grid=True`` but leaves the line that passes it to acados
  commented out, so its runs used 20 x 25 ms; here the grid is passed to both);
* the nominal leaderboard plant (pendulab's rigid model with its parameters folded in, the same
  CasADi expression in both), RK4 with one step per started 10 ms (1 per 4 ms interval, 7 per 64 ms);
* the winner's weights: stage ``dt_k (|x - xr|_Q^2 + |u - ur|_R^2)`` (acados scales stage costs by the
  interval), Q = diag(1000, 1000, 100, 100), R = 250 (pendubot) / 200 (acrobot) on the driven torque,
  terminal ``|x_N - xr_N|_Qf^2``, Qf = diag(1e5, 1e5, 1e4, 1e4); |u| <= 6 N.m on the driven joint, the
  passive one unactuated (the winner's pendubot run allowed it 0.5 N.m, "bend the rules"; not here);
* one Gauss-Newton SQP iteration per call (SQP-RTI); acados: PARTIAL_CONDENSING_HPIPM (cond N = 10),
  ROBUST mode, QP tolerance 0.01, QP warm start, as the winner; pendulab: its condensed box QP.

Two things of the winner's OCP are not in it: the hard velocity bound |omega| <= 16 rad/s (pendulab's
RTI QP has torque bounds only; the benchmark reports the largest |omega| each run reached) and the
sin/cos (angle-wrapping) cost; instead both wrap the measured angles about the reference and track
pendulab's offline swing-up plan (the reference) before holding upright: the same reference window in both.

Per (task, rate) and per round (``--repeats``, the two implementations' order alternating):

1. **closed loop**: each controller swings up and balances its own RK4 plant at the control rate
   (500 Hz: the leaderboard v2 simulation, 2 ms; 1 kHz: the same plant at 1 ms), 10 s;
2. **replay**: the states of the first pendulab closed loop, in order, fed to each controller (reset
   first, each with its own warm start): the same inputs, so the torques compare call by call.

Per call = the whole controller call (pendulab: ``RTIController.__call__``; acados: the worker's call,
measured in the worker: reference window, wrap, ``set`` of yref and x0, ``solve()``, ``get``), wall and thread
CPU; "solver" = pendulab's compiled step (``_eval``) or acados' ``solve()`` alone, and acados' ``time_tot``.

Usage::

    bash benchmarks/setup_acados_env.sh            # once: /work/venvs/acados (Python 3.12, comma-deps-acados)
    PYTHONPATH=. python benchmarks/bench_acados.py [--repeats 3] [--tasks pendubot,acrobot] [--rates 500,1000]
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
from tqdm import tqdm

from pendulab.control.feedback import full_input
from pendulab.control.nmpc.rti import RTIController, joint_wrapped_error, rti_for_task
from pendulab.control.realai.spec import TASKS, TORQUE_LIMIT, leaderboard_task
from pendulab.evaluate.realai.criteria import criteria, score_v2, to_relative
from pendulab.evaluate.realai.plant import protocol_model
from pendulab.evaluate.realai.simulate import rk4_rollout
from pendulab.model.functions import model_functions
from pendulab.model.model import INPUT_NAMES, Model

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "acados.md"
FIGURE = ROOT / "docs" / "figures" / "acados_rti.png"
WORKER = ROOT / "benchmarks" / "acados_worker.py"
VENV = Path(os.environ.get("ACADOS_VENV", "/work/venvs/acados"))
T_FINAL = 10.0

#: The winner's grid (13 x 4 ms, then the rest of 0.5 s in 7 equal intervals), weights and QP settings.
GRID = (0.004,) * 13 + ((0.5 - 13 * 0.004) / 7,) * 7
Q_DIAG = (1000.0, 1000.0, 100.0, 100.0)
QF_DIAG = (1e5, 1e5, 1e4, 1e4)
R_TASK = {"pendubot": 250.0, "acrobot": 200.0}
QP = {"qp_solver": "PARTIAL_CONDENSING_HPIPM", "qp_solver_cond_N": 10, "hpipm_mode": "ROBUST", "qp_tol": 0.01}

_OPS = {
    ca.OP_ADD: "{0} + {1}", ca.OP_SUB: "{0} - {1}", ca.OP_MUL: "{0} * {1}", ca.OP_DIV: "{0} / {1}",
    ca.OP_POW: "{0} ** {1}", ca.OP_CONSTPOW: "{0} ** {1}", ca.OP_ATAN2: "ca.atan2({0}, {1})",
    ca.OP_NEG: "-{0}", ca.OP_SQ: "{0} * {0}", ca.OP_TWICE: "2.0 * {0}", ca.OP_INV: "1.0 / {0}",
    ca.OP_SQRT: "ca.sqrt({0})", ca.OP_SIN: "ca.sin({0})", ca.OP_COS: "ca.cos({0})", ca.OP_TAN: "ca.tan({0})",
    ca.OP_EXP: "ca.exp({0})", ca.OP_LOG: "ca.log({0})", ca.OP_FABS: "ca.fabs({0})", ca.OP_ATAN: "ca.atan({0})",
    ca.OP_TANH: "ca.tanh({0})", ca.OP_SIGN: "ca.sign({0})", ca.OP_ASSIGN: "{0}",
}  # fmt: skip


def rhs_code(model: Model, input_names: tuple[str, ...]) -> str:
    """pendulab's rhs with the model's parameters folded in as straight-line CasADi code (``x``, ``u`` -> ``xdot``).

    The CasADi versions differ (pendulab's, the acados wheel's) and serialized Functions do not cross
    them, so the SX graph is written out as source, operation by operation: the same expression in both.
    """
    f = model_functions(model.kind)["rhs"]
    x, u = ca.SX.sym("x", model.nx), ca.SX.sym("u", len(input_names))
    ufull = ca.SX.zeros(len(INPUT_NAMES))
    for i, n in enumerate(input_names):
        ufull[INPUT_NAMES.index(n)] = u[i]
    g = ca.Function("rhs", [x, u], [f(x, ufull, ca.DM(model.p))])
    lines, outs = [], {}
    for k in range(g.n_instructions()):
        op, ins, o = g.instruction_id(k), g.instruction_input(k), g.instruction_output(k)
        if op == ca.OP_INPUT:
            lines.append(f"w{o[0]} = {'xu'[ins[0]]}[{ins[1]}]")
        elif op == ca.OP_OUTPUT:
            lines.append(f"o{o[1]} = w{ins[0]}")
            outs[o[1]] = f"o{o[1]}"
        elif op == ca.OP_CONST:
            lines.append(f"w{o[0]} = {float(g.instruction_constant(k))!r}")
        elif op in _OPS:
            lines.append(f"w{o[0]} = " + _OPS[op].format(*(f"w{i}" for i in ins)))
        else:
            raise TypeError(f"rhs_code: CasADi operation {op} not supported")
    rows, _ = g.sparsity_out(0).get_triplet()
    dense = ["0.0"] * model.nx
    for nz, r in enumerate(rows):
        dense[r] = outs.get(nz, "0.0")
    lines.append(f"xdot = ca.vertcat({', '.join(dense)})")
    return "\n".join(lines)


def check_rhs_code(model: Model, input_names: tuple[str, ...], code: str) -> float:
    """Largest difference of the generated code against pendulab's rhs at random points (a self-check)."""
    x, u = ca.SX.sym("x", model.nx), ca.SX.sym("u", len(input_names))
    ns: dict[str, Any] = {"ca": ca, "x": x, "u": u}
    exec(compile(code, "<rhs>", "exec"), ns)  # noqa: S102
    g = ca.Function("g", [x, u], [ns["xdot"]])
    f = model_functions(model.kind)["rhs"]
    rng = np.random.default_rng(0)
    err = 0.0
    for _ in range(20):
        xv, uv = rng.normal(size=model.nx) * 3, rng.normal(size=len(input_names)) * 3
        uf = np.zeros(len(INPUT_NAMES))
        uf[[INPUT_NAMES.index(n) for n in input_names]] = uv
        err = max(err, float(np.max(np.abs(np.asarray(g(xv, uv)) - np.asarray(f(xv, uf, model.p))))))
    return err


def pendulab_rti(task: str, rate: int, qp_iterations: int) -> RTIController:
    """pendulab's RTI with the winner's OCP at ``rate`` Hz (compiled step, cached)."""
    ctrl, _ = rti_for_task(
        leaderboard_task(task), intervals=GRID, sample_time=1.0 / rate, q_angle=Q_DIAG[0], q_rate=Q_DIAG[2],
        r=R_TASK[task], terminal_weights=QF_DIAG, cost_per_second=True, qp_iterations=qp_iterations,
    )  # fmt: skip
    return ctrl


class AcadosProxy:
    """A pendulab SampledController that forwards each call to the acados worker (times measured there)."""

    def __init__(self, ctrl: RTIController, task: str, rate: int, code_dir: Path) -> None:
        o = ctrl.options
        cfg = {
            "nx": ctrl.model.nx, "m": len(ctrl.input_names), "intervals": list(o.grid), "steps": list(o.grid_steps),
            "Q": list(Q_DIAG), "R": [R_TASK[task]], "Qf": list(QF_DIAG), "u_max": ctrl.u_max,
            "goal": ctrl.goal.tolist(), "x_ref": ctrl.x_ref.tolist(), "u_ref": ctrl.u_ref.tolist(),
            "offsets": ctrl._offsets.tolist(), "sample_time": o.sample_time, "angles": [0, 1],
            "rhs_code": rhs_code(ctrl.model, ctrl.input_names), **QP,
        }  # fmt: skip
        self.sample_time, self.input_names = o.sample_time, ctrl.input_names
        fd, self._cfg = tempfile.mkstemp(suffix=".json", prefix=f"acados-{task}-{rate}-")
        os.close(fd)
        Path(self._cfg).write_text(json.dumps(cfg), encoding="utf-8")
        site = next((VENV / "lib").glob("python3*/site-packages"))
        env = {**os.environ, "ACADOS_SOURCE_DIR": str(site / "acados" / "install")}
        env["LD_LIBRARY_PATH"] = str(site / "acados" / "install" / "lib") + ":" + env.get("LD_LIBRARY_PATH", "")
        env.pop("PYTHONPATH", None)
        self.proc = subprocess.Popen(
            [str(VENV / "bin" / "python"), str(WORKER), self._cfg, str(code_dir)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env,
        )  # fmt: skip
        line = self.proc.stdout.readline()
        if line.strip() != b"READY":
            raise RuntimeError(f"acados worker failed to start (got {line!r}); see its stderr above")
        self.reset()

    def _ask(self, cmd: float, t: float = 0.0, x: np.ndarray | None = None) -> np.ndarray:
        req = np.zeros(6)
        req[0], req[1] = cmd, t
        if x is not None:
            req[2:6] = x
        self.proc.stdin.write(req.tobytes())
        self.proc.stdin.flush()
        return np.frombuffer(self.proc.stdout.read(64), dtype=np.float64)

    def reset(self) -> None:
        self._ask(1.0)
        self.rows: list[np.ndarray] = []

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        a = self._ask(0.0, t, np.asarray(x, dtype=float))
        self.rows.append(a.copy())
        return np.array([a[0]])

    def times(self) -> dict[str, np.ndarray]:
        r = np.array(self.rows)
        status = r[:, 5]
        return {"wall": r[:, 1], "cpu": r[:, 2], "solver": r[:, 3], "time_tot": r[:, 4], "unsolved": int(np.sum(status != 0))}

    def close(self) -> None:
        req = np.zeros(6)
        req[0] = 2.0  # quit (no answer)
        self.proc.stdin.write(req.tobytes())
        self.proc.stdin.close()
        self.proc.wait(timeout=30)
        os.unlink(self._cfg)


class PendulabTimed:
    """pendulab's RTI with the thread CPU time of each call and the wall time of its compiled step."""

    def __init__(self, ctrl: RTIController) -> None:
        self.ctrl, self.sample_time, self.input_names = ctrl, ctrl.sample_time, ctrl.input_names
        self._ev = ctrl._eval
        ctrl._eval = self._timed_eval
        self.reset()

    def _timed_eval(self) -> None:
        t0 = time.perf_counter()
        self._ev()
        self._solver.append(time.perf_counter() - t0)

    def reset(self) -> None:
        self.ctrl.reset()
        self._cpu: list[float] = []
        self._solver: list[float] = []
        self.rows: list[tuple[float, np.ndarray]] = []

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        c0 = time.thread_time()
        u = self.ctrl(t, x)
        self._cpu.append(time.thread_time() - c0)
        self.rows.append((t, np.array(x, dtype=float)))
        return u

    def times(self) -> dict[str, Any]:
        return {
            "wall": np.array(self.ctrl.solve_times), "cpu": np.array(self._cpu), "solver": np.array(self._solver),
            "unsolved": self.ctrl.qp_unsolved + self.ctrl.failures,
        }  # fmt: skip


def closed_loop(task: str, ctrl: Any, rate: int) -> dict[str, Any]:
    """Swing-up and balance of the nominal leaderboard plant, RK4 at the control period, controller every step."""
    model = protocol_model(task, None)
    dt = 1.0 / rate
    n = round(T_FINAL / dt)
    limit = np.zeros(len(INPUT_NAMES))
    limit[TASKS[task]] = TORQUE_LIMIT
    ctrl.reset()
    us: list[float] = []

    def policy(k: int, t: float, x: np.ndarray) -> np.ndarray:
        u = np.clip(full_input(ctrl, ctrl(t, x), t), -limit, limit)
        us.append(float(u[TASKS[task]]))
        return u

    gc.collect()
    gc.freeze()
    try:
        t, x, u = rk4_rollout(model, model.state(), policy, n, dt)
    finally:
        gc.unfreeze()
    t, x = t[:n], x[:n]
    values = criteria(t, to_relative(x), u, model.params.L1, model.params.L2)
    success = bool(values["swingup_time"] < t[-1])
    return {
        "success": success, "t_up": float(values["swingup_time"]), "score": float(score_v2(values, success)),
        "omega_max": float(np.max(np.abs(x[:, 2:4]))), "t": t, "x": x, "u": np.array(us), **ctrl.times(),
    }  # fmt: skip


def replay(ctrl: Any, states: list[tuple[float, np.ndarray]]) -> dict[str, Any]:
    """Feed the recorded (t, x) sequence to ``ctrl`` (reset first): torques and times per call."""
    ctrl.reset()
    gc.collect()
    gc.freeze()
    try:
        u = np.array([float(np.ravel(ctrl(t, x))[0]) for t, x in states])
    finally:
        gc.unfreeze()
    return {"u": u, **ctrl.times()}


def stats(a: np.ndarray) -> tuple[float, float, float]:
    """(median, 99th percentile, max) in ms."""
    a = np.asarray(a) * 1e3
    return float(np.median(a)), float(np.percentile(a, 99)), float(a.max())


def run_case(task: str, rate: int, repeats: int, code_dir: Path, qp_iterations: int) -> dict[str, Any]:
    ctrl = pendulab_rti(task, rate, qp_iterations)
    pl, ac = PendulabTimed(ctrl), AcadosProxy(ctrl, task, rate, code_dir / task)
    res: dict[str, Any] = {"pendulab": {"loop": [], "replay": []}, "acados": {"loop": [], "replay": []}, "load": []}
    impls = {"pendulab": pl, "acados": ac}
    states = None
    try:
        for rnd in tqdm(range(repeats), desc=f"{task} {rate} Hz", leave=False):
            order = ["pendulab", "acados"] if rnd % 2 == 0 else ["acados", "pendulab"]
            res["load"].append(os.getloadavg()[0])
            for name in order:
                r = closed_loop(task, impls[name], rate)
                res[name]["loop"].append(r)
                if name == "pendulab" and states is None:
                    states = list(pl.rows)
            for name in order:
                res[name]["replay"].append(replay(impls[name], states))
    finally:
        ac.close()
    res["rhs_err"] = check_rhs_code(ctrl.model, ctrl.input_names, rhs_code(ctrl.model, ctrl.input_names))
    res["options"] = ctrl.options
    res["same_qp_du"] = abs(reference_guess_torque(ctrl, states[0]) - float(res["acados"]["replay"][0]["u"][0]))
    return res


def reference_guess_torque(ctrl: RTIController, row: tuple[float, np.ndarray]) -> float:
    """pendulab's compiled step at ``row`` started, as acados' first call is, from the reference (not from a rollout)."""
    t, x = row
    k = int(np.floor(t / ctrl.options.sample_time + 1e-6))
    XR, UR = ctrl.window(k)
    x0 = XR[0] + joint_wrapped_error(np.asarray(x, dtype=float) - XR[0], XR[0], ctrl.options.angle_limit)
    X = XR.copy()
    X[0] = x0
    return float(ctrl.step(x0, X.T, UR.T, XR.T, UR.T)[0])


def summarize(res: dict[str, Any], name: str, mode: str) -> dict[str, Any]:
    runs = res[name][mode]
    cat = {k: np.concatenate([r[k] for r in runs]) for k in ("wall", "cpu", "solver")}
    out = {k: stats(v) for k, v in cat.items()}
    out["calls"] = len(cat["wall"])
    if name == "acados":
        out["time_tot"] = stats(np.concatenate([r["time_tot"] for r in runs]))
    out["unsolved"] = int(sum(r["unsolved"] for r in runs))
    if mode == "loop":
        out["success"] = f"{sum(r['success'] for r in runs)}/{len(runs)}"
        out["t_up"] = float(np.median([r["t_up"] for r in runs]))
        out["score"] = float(np.median([r["score"] for r in runs]))
        out["omega_max"] = float(max(r["omega_max"] for r in runs))
    return out


def plot(results: dict[tuple[str, int], dict[str, Any]], path: Path) -> None:
    """Per task: closed-loop angles of both at 500 Hz; per-call wall time distribution (replay) at each rate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tasks = sorted({k[0] for k in results}, key=["pendubot", "acrobot"].index)
    rates = sorted({k[1] for k in results})
    fig, axes = plt.subplots(len(tasks), 1 + len(rates), figsize=(5.0 * (1 + len(rates)), 3.8 * len(tasks)),
                             squeeze=False, constrained_layout=True)  # fmt: skip
    colors = {"pendulab": "C0", "acados": "C3"}
    for i, task in enumerate(tasks):
        ax = axes[i, 0]
        res = results[(task, rates[0])]
        for name in ("pendulab", "acados"):
            r = res[name]["loop"][0]
            for j, ls in ((0, "-"), (1, "--")):
                ax.plot(r["t"], r["x"][:, j], ls, color=colors[name], lw=1, label=f"{name} theta{j + 1}")
        ax.axhline(np.pi, color="k", lw=0.5, ls=":")
        ax.set(title=f"{task}: closed loop at {rates[0]} Hz", xlabel="time [s]", ylabel="angle [rad]")
        ax.legend(fontsize=7, loc="lower right")
        for j, rate in enumerate(rates):
            ax = axes[i, 1 + j]
            res = results[(task, rate)]
            for name in ("pendulab", "acados"):
                runs = res[name]["replay"]
                for key, ls in (("wall", "-"), ("solver", ":")):
                    v = np.sort(np.concatenate([r[key] for r in runs])) * 1e3
                    ax.plot(v, np.linspace(0, 1, len(v)), ls, color=colors[name],
                            label=f"{name} {'whole call' if key == 'wall' else 'solver only'}")  # fmt: skip
            ax.set_xscale("log")
            ax.set(title=f"{task}, {rate} Hz: per-call wall time (replay)", xlabel="time per call [ms]",
                   ylabel="fraction of calls")  # fmt: skip
            ax.grid(True, which="both", lw=0.3)
            ax.legend(fontsize=7, loc="lower right")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--tasks", default="pendubot,acrobot")
    ap.add_argument("--rates", default="500,1000")
    ap.add_argument("--qp-iterations", type=int, default=20, help="pendulab's active-set solves per call")
    ap.add_argument("--code-dir", type=Path, default=Path(tempfile.gettempdir()) / "pendulab-acados-code")
    args = ap.parse_args()
    if not (VENV / "bin" / "python").exists():
        sys.exit(f"no acados venv at {VENV}: run `bash benchmarks/setup_acados_env.sh` first (or set ACADOS_VENV)")
    load0 = os.getloadavg()
    results = {}
    for task in args.tasks.split(","):
        for rate in (int(r) for r in args.rates.split(",")):
            results[(task, rate)] = run_case(task, rate, args.repeats, args.code_dir, args.qp_iterations)
    load1 = os.getloadavg()
    plot(results, FIGURE)
    write(results, args, load0, load1)


def write(results: dict, args: argparse.Namespace, load0: tuple, load1: tuple) -> None:
    o = next(iter(results.values()))["options"]
    cmd = (
        f"PYTHONPATH=. nice -n 5 python benchmarks/bench_acados.py --repeats {args.repeats} --tasks {args.tasks} "
        f"--rates {args.rates} --qp-iterations {args.qp_iterations}"
    )
    lines = [
        "# pendulab RTI against acados SQP-RTI: same OCP, same states",
        "",
        f"`bash benchmarks/setup_acados_env.sh` then `{cmd}` on {platform.machine()} / Python {platform.python_version()} "
        f"({os.cpu_count()} cores, shared with other work; 1/5/15-min load average {load0[0]:.1f}/{load0[1]:.1f}/{load0[2]:.1f} "
        f"before, {load1[0]:.1f}/{load1[1]:.1f}/{load1[2]:.1f} after). acados: PyPI `comma-deps-acados` "
        "(acados_template, libacados, HPIPM, BLASFEO; its own Python 3.12 venv), driven by `benchmarks/acados_worker.py`.",
        "",
        f"OCP (both): {o.horizon} intervals, {o.prediction:g} s, non-uniform grid 13 x 4 ms + 7 x 64 ms; RK4 steps per "
        f"interval {sorted(set(o.grid_steps))}; stage cost dt_k (|x - xr|_Q^2 + |u - ur|_R^2), Q = diag{Q_DIAG}, "
        f"R = 250 (pendubot) / 200 (acrobot), terminal Qf = diag{QF_DIAG}; |u| <= 6 N.m on the driven joint; the "
        "reference: pendulab's swing-up plan, then upright. One Gauss-Newton SQP step per call. acados: SQP_RTI, "
        "PARTIAL_CONDENSING_HPIPM (cond N 10), ROBUST, QP tol 0.01, warm start = last iterate (no shift). pendulab: "
        f"`rti` (condensed box QP, {o.qp_iterations} primal-dual active-set solves, compiled C), warm start shifted by one "
        "sample. 'unsolved' = calls whose QP was not solved (pendulab: last iterate not a KKT point, or a failed step; "
        "acados: status != 0).",
        "",
        f"Medians over {args.repeats} interleaved rounds per case (order of the two alternating); per-call numbers pool "
        "all calls of all rounds. Times in ms. 'call' = the whole controller call from Python; 'solver' = pendulab's "
        "compiled step / acados' `solve()` alone; `time_tot` = acados' own timer.",
        "",
        "## Closed loop: each controller's own swing-up and balance (10 s, RK4 plant at the control period)",
        "",
        "| task | rate | impl | success | t_up [s] | max abs omega [rad/s] | calls | unsolved | call wall median / p99 / max "
        "| call CPU median / p99 / max | solver wall median / p99 / max | acados time_tot median / p99 |",
        "|---|---|---|---|---:|---:|---:|---:|---|---|---|---|",
    ]
    fmt = "{0:.3f} / {1:.3f} / {2:.2f}".format
    for (task, rate), res in results.items():
        for name in ("pendulab", "acados"):
            s = summarize(res, name, "loop")
            tt = f"{s['time_tot'][0]:.3f} / {s['time_tot'][1]:.3f}" if name == "acados" else "-"
            lines.append(
                f"| {task} | {rate} Hz | {name} | {s['success']} | {s['t_up']:.2f} | {s['omega_max']:.1f} | {s['calls']} | "
                f"{s['unsolved']} | "
                f"{fmt(*s['wall'])} | {fmt(*s['cpu'])} | {fmt(*s['solver'])} | {tt} |"
            )
    lines += [
        "",
        "## Replay: the same measured states (the first pendulab closed loop), each controller with its own warm start",
        "",
        "Ratio = pendulab / acados (target <= 1.0). |du| = |u_pendulab - u_acados| per call [N.m]: 'same QP' = "
        "pendulab's step started from the reference, as acados' first call is (the same QP up to HPIPM's tolerance); "
        "'first' = the controllers' first calls (pendulab's cold start is a rollout of the measured state, acados' "
        "the reference: different linearization points); median and max over the run (the warm starts differ: "
        "pendulab's is shifted, acados' is not).",
        "",
        "| task | rate | impl | calls | call wall median / p99 / max | call CPU median / p99 / max "
        "| solver wall median / p99 / max | ratio call wall median / p99 | ratio call CPU median / p99 "
        "| ratio solver median / p99 | abs du same QP / first / median / max |",
        "|---|---|---|---:|---|---|---|---|---|---|---|",
    ]
    summary = []
    for (task, rate), res in results.items():
        sp, sa = summarize(res, "pendulab", "replay"), summarize(res, "acados", "replay")
        du = np.abs(res["pendulab"]["replay"][0]["u"] - res["acados"]["replay"][0]["u"])
        for name, s in (("pendulab", sp), ("acados", sa)):
            if name == "pendulab":
                rw = f"{sp['wall'][0] / sa['wall'][0]:.2f} / {sp['wall'][1] / sa['wall'][1]:.2f}"
                rc = f"{sp['cpu'][0] / sa['cpu'][0]:.2f} / {sp['cpu'][1] / sa['cpu'][1]:.2f}"
                rs = f"{sp['solver'][0] / sa['solver'][0]:.2f} / {sp['solver'][1] / sa['solver'][1]:.2f}"
                dus = f"{res['same_qp_du']:.1e} / {du[0]:.1e} / {np.median(du):.1e} / {du.max():.2f}"
                summary.append((task, rate, sp, sa))
            else:
                rw = rc = rs = dus = "-"
            lines.append(
                f"| {task} | {rate} Hz | {name} | {s['calls']} | {fmt(*s['wall'])} | {fmt(*s['cpu'])} | "
                f"{fmt(*s['solver'])} | {rw} | {rc} | {rs} | {dus} |"
            )
    lines += [
        "",
        "Self-check: the model code handed to acados matches pendulab's rhs to "
        f"{max(r['rhs_err'] for r in results.values()):.1e} (20 random points).",
        "",
        f"Figure: `docs/figures/{FIGURE.name}` (closed-loop angles at the first rate; per-call wall time distributions "
        "of the replay, whole call and solver only, log scale).",
    ]
    OUT.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines), file=sys.stderr)


if __name__ == "__main__":
    main()

"""acados side of ``benchmarks/bench_acados.py``: one SQP-RTI controller, driven over stdin/stdout.

Runs in the acados venv made by ``benchmarks/setup_acados_env.sh`` (Python 3.12, ``comma-deps-acados``),
never in pendulab's environment, and imports nothing of pendulab. ``bench_acados.py`` starts it as::

    /work/venvs/acados/bin/python benchmarks/acados_worker.py CONFIG.json CODE_DIR

``CONFIG.json`` holds the OCP (written by ``bench_acados.py`` from the pendulab controller it is compared
with): the model's right-hand side as straight-line CasADi code (parameters folded in), the interval
grid, RK4 steps per interval, weights, torque bound, HPIPM settings, and the reference on the sample
grid with the node offsets. The worker builds the acados solver (code generated into ``CODE_DIR``; the
compiled library is reused when the OCP is unchanged), prints ``READY``, then answers binary requests:

* request: 6 float64 ``[command, t, x1, x2, x3, x4]``, command 0 = one controller call at time ``t``
  [s] from the measured state ``x``, 1 = reset (the next call starts cold from the reference), 2 = quit;
* answer: 8 float64 ``[u, wall, cpu, solve_wall, time_tot, status, 0, 0]``: the torque [N.m], the wall and
  thread CPU time of the whole call [s] (reference window, state wrap, writing the solver's inputs,
  solve, reading the torque), the wall time of ``solve()`` alone and acados' own ``time_tot`` [s], and
  the solver status.

A call is what pendulab's ``RTIController.__call__`` does, the acados way: the reference window at the
nodes, the measured state's angles wrapped about the reference, one SQP-RTI iteration (preparation and
feedback in one ``solve()``, ``rti_phase`` 0) warm-started from the previous iterate as acados keeps it
(no shift, as the ICRA 2025 controller), the first torque clipped to the bound.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import sys
import time
from pathlib import Path

from acados_env import acados_env

REQUEST, ANSWER = 6, 8


acados_env()  # before the wheel's CasADi and acados_template are imported

import casadi as ca  # noqa: E402  (the wheel's CasADi)
import numpy as np  # noqa: E402
from acados_template import AcadosModel, AcadosOcp, AcadosOcpSolver  # noqa: E402


def build_solver(cfg: dict, code_dir: Path) -> AcadosOcpSolver:
    """The acados SQP-RTI solver of the OCP in ``cfg`` (code generated and compiled in ``code_dir``)."""
    nx, m, N = cfg["nx"], cfg["m"], len(cfg["intervals"])
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", m)
    namespace = {"ca": ca, "x": x, "u": u}
    exec(compile(cfg["rhs_code"], "<pendulab rhs>", "exec"), namespace)  # noqa: S102 (our own generated code)
    f_expl = namespace["xdot"]
    key = hashlib.sha256(json.dumps({k: cfg[k] for k in sorted(cfg) if k not in ("x_ref", "u_ref")}).encode()).hexdigest()
    name = f"pdl_{key[:12]}"
    model = AcadosModel()
    model.name = name
    model.x, model.u = x, u
    model.xdot = ca.SX.sym("xdot", nx)
    model.f_expl_expr = f_expl
    model.f_impl_expr = model.xdot - f_expl

    ocp = AcadosOcp()
    ocp.model = model
    ocp.dims.N = N
    # acados' least squares is 0.5 |y - yref|_W^2, each stage scaled by its interval: W = 2 diag(Q, R) gives
    # dt_k (|x - xr|_Q^2 + |u - ur|_R^2), pendulab's cost_per_second stage cost; the terminal cost is unscaled.
    ocp.cost.cost_type = "LINEAR_LS"
    ocp.cost.cost_type_e = "LINEAR_LS"
    ocp.cost.W = 2.0 * np.diag(cfg["Q"] + cfg["R"])
    ocp.cost.W_e = 2.0 * np.diag(cfg["Qf"])
    ocp.cost.Vx = np.vstack([np.eye(nx), np.zeros((m, nx))])
    ocp.cost.Vu = np.vstack([np.zeros((nx, m)), np.eye(m)])
    ocp.cost.Vx_e = np.eye(nx)
    ocp.cost.yref = np.zeros(nx + m)
    ocp.cost.yref_e = np.zeros(nx)
    ocp.constraints.lbu = -cfg["u_max"] * np.ones(m)
    ocp.constraints.ubu = cfg["u_max"] * np.ones(m)
    ocp.constraints.idxbu = np.arange(m)
    ocp.constraints.x0 = np.array(cfg["goal"])

    so = ocp.solver_options
    so.tf = float(sum(cfg["intervals"]))
    so.time_steps = np.array(cfg["intervals"])
    so.integrator_type = "ERK"
    so.sim_method_num_stages = 4  # classic RK4, as pendulab
    so.sim_method_num_steps = np.array(cfg["steps"], dtype=int)
    so.nlp_solver_type = "SQP_RTI"
    so.hessian_approx = "GAUSS_NEWTON"
    so.qp_solver = cfg["qp_solver"]
    so.qp_solver_cond_N = cfg["qp_solver_cond_N"]
    so.hpipm_mode = cfg["hpipm_mode"]
    tol = cfg["qp_tol"]
    so.qp_solver_tol_stat = so.qp_solver_tol_eq = so.qp_solver_tol_ineq = so.qp_solver_tol_comp = tol
    so.qp_solver_warm_start = 1
    so.print_level = 0

    code_dir.mkdir(parents=True, exist_ok=True)
    json_file = str(code_dir / f"{name}.json")
    lib = code_dir / "c_generated_code" / f"libacados_ocp_solver_{name}.so"
    ocp.code_export_directory = str(code_dir / "c_generated_code")
    cwd = os.getcwd()
    os.chdir(code_dir)  # acados_template writes some files relative to the working directory
    try:
        fresh = not lib.exists()
        stdout = sys.stdout
        sys.stdout = sys.stderr  # keep stdout for the binary answers
        try:
            solver = AcadosOcpSolver(ocp, json_file=json_file, build=fresh, generate=fresh, verbose=False)
        finally:
            sys.stdout = stdout
    finally:
        os.chdir(cwd)
    return solver


class Controller:
    """One SQP-RTI call per sample, on pendulab's reference window (see the module docstring)."""

    def __init__(self, cfg: dict, solver: AcadosOcpSolver) -> None:
        self.solver = solver
        self.N, self.nx, self.m = len(cfg["intervals"]), cfg["nx"], cfg["m"]
        self.x_ref, self.u_ref = np.array(cfg["x_ref"]), np.array(cfg["u_ref"]).reshape(-1, self.m)
        self.goal = np.array(cfg["goal"])
        self.offsets = np.array(cfg["offsets"], dtype=int)
        self.h = float(cfg["sample_time"])
        self.u_max = float(cfg["u_max"])
        self.angles = list(cfg["angles"])
        self.cold = True

    def window(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        idx = k + self.offsets
        K = len(self.x_ref)
        xr = np.where((idx < K)[:, None], self.x_ref[np.minimum(idx, K - 1)], self.goal)
        ur = np.where((idx[:-1] < K)[:, None], self.u_ref[np.minimum(idx[:-1], K - 1)], 0.0)
        return xr, ur

    def __call__(self, t: float, x: np.ndarray) -> tuple[float, float, float, int]:
        s = self.solver
        k = int(math.floor(t / self.h + 1e-6))
        xr, ur = self.window(k)
        e = x - xr[0]
        e[self.angles] = (e[self.angles] + math.pi) % (2 * math.pi) - math.pi
        x0 = xr[0] + e
        for j in range(self.N):
            s.set(j, "yref", np.concatenate([xr[j], ur[j]]))
        s.set(self.N, "yref", xr[self.N])
        if self.cold:  # start from the reference, as pendulab's cold start
            for j in range(self.N):
                s.set(j, "x", xr[j])
                s.set(j, "u", ur[j])
            s.set(self.N, "x", xr[self.N])
            self.cold = False
        s.set(0, "lbx", x0)
        s.set(0, "ubx", x0)
        t0 = time.perf_counter()
        status = s.solve()
        solve_wall = time.perf_counter() - t0
        u = s.get(0, "u")
        if not np.all(np.isfinite(u)):
            u = np.zeros(self.m)
            self.cold = True
        return float(np.clip(u[0], -self.u_max, self.u_max)), solve_wall, float(np.ravel(s.get_stats("time_tot"))[0]), int(status)

    def reset(self) -> None:
        self.solver.reset()
        self.cold = True


def main() -> None:
    cfg = json.loads(Path(sys.argv[1]).read_text(encoding="utf-8"))
    solver = build_solver(cfg, Path(sys.argv[2]).resolve())
    ctrl = Controller(cfg, solver)
    out = sys.stdout.buffer
    inp = sys.stdin.buffer
    out.write(b"READY\n")
    out.flush()
    size = 8 * REQUEST
    while True:
        buf = inp.read(size)
        if len(buf) < size:
            break
        req = np.frombuffer(buf, dtype=np.float64)
        cmd = int(req[0])
        if cmd == 2:
            break
        if cmd == 1:
            ctrl.reset()
            ans = np.zeros(ANSWER)
        else:
            w0, c0 = time.perf_counter(), time.thread_time()
            u, solve_wall, time_tot, status = ctrl(float(req[1]), req[2:6].copy())
            c1, w1 = time.thread_time(), time.perf_counter()
            ans = np.array([u, w1 - w0, c1 - c0, solve_wall, time_tot, status, 0.0, 0.0])
        out.write(ans.tobytes())
        out.flush()


if __name__ == "__main__":
    main()

"""The ICRA 2025 entries that ship in RealAIGym's repository, run through pendulab's v3 and v3-hardware protocols.

Not part of CI: it needs the upstream package (``dfki-ric-underactuated-lab/double_pendulum``) and the entries'
weights, from a fetched snapshot, in a venv of their own (``bash benchmarks/setup_realai_env.sh``). Run it with that
venv's python (pendulab is installed editable there too)::

    /work/venvs/realai/bin/python benchmarks/bench_upstream_entries.py                    # every case, resumed
    /work/venvs/realai/bin/python benchmarks/bench_upstream_entries.py --report           # tables of what is recorded

Entries (``--entries``): ``ar_eapo`` and ``mcpilco`` run in this process, ``acados_mpc`` in a worker process of the
Python 3.12 acados venv (``--acados-worker``, over a pipe); ``vimppi`` (written for a GPU) runs in this process on JAX's
CPU backend, one XLA thread, ~45 ms a call: its hardware-final entry is held at its declared 5 ms as the robot's loop
ran it (:class:`HeldEntry`), a 60 s episode ~10 min, not real time (the protocols do not charge compute time to the
plant). What cannot run is in :data:`CANNOT_RUN`, recorded as such. Each entry comes in up to three **variants** (``--variants``):

* ``hw``: the hardware-final submission, ``experiments/icra_2025/con_<entry>_<task>.py`` (model 1.0 weights, the
  0.5 N.m passive allowance used for friction compensation). These are the entries whose published hardware scores
  the ranking question is about; they run on every protocol.
* ``sim``: the simulation-stage submission, ``leaderboard/<task>/simulation_v3/con_<entry>.py`` (model 1.1 weights for
  AR-EAPO, MC-PILCO's simulation policy), the code behind the published *simulation* scores, on the simulation
  protocols only: the reproduction check.
* ``hw-adapter``: the hardware-final object handed to pendulab's runners as it is (what a user would do), to show
  how ``run_v3``/``run_v3_hardware`` treat an upstream object themselves.

Protocols (``--protocols``): ``v3`` (:func:`pendulab.evaluate.realai.v3.run_v3` as it is), ``v3-legacy`` (the same loop
with the reset schedule the published simulation runs drew, ``schedule="published"``, and the entry clipped only by
the plant's 6 N.m as upstream's simulator did, ``passive_limit=6``), ``v3-hardware``
(:func:`~pendulab.evaluate.realai.v3_hardware.run_v3_hardware`, ``--allowance`` 0.5 N.m by default; ``--plant FILE``
a what-if robot), and ``upstream-sim``, a check rather than a pendulab protocol: the hardware-final acados entries
through upstream's own wrapper and simulator only (:func:`upstream_simulation`, in the acados worker).

How an entry is driven: upstream's protocols (simulation and hardware alike) wrap the entry in
``GlobalPolicyTestingControllerV2``, which calls the entry's **raw** ``get_control_output_(x, t)`` (no filter, no
friction or gravity compensation of the entry), and neither the simulator nor the hardware loop calls the entry's
``init``/``reset`` (its ``con_`` file initialises it once). :class:`RawEntry` gives the entry that shape and
:func:`pendulab.control.realai.adapter.from_realai` runs it with ``task="full"``, so the protocol's own clip decides
what reaches the passive joint (0 N.m in simulation, the ``--allowance`` on v3-hardware). Every case loads its
entry afresh (the entries keep counters). MC-PILCO's hardware submission runs its loop at 1/330 s and its policy
every 10 calls (33 Hz); pendulab's loop runs at 2 ms, so its ``ctrl_rate`` is set to 15 (policy every 30 ms).

Each finished (variant, entry, task, protocol, seed) case is written to ``--out``
(``pendulab-out/upstream_entries/<case>.json``) as it finishes; a re-run skips recorded cases (``--force`` reruns).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import importlib.util
import json
import os
import sys
import time
import traceback
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from pendulab.model.plant_file import IdentifiedPlant

REPO = Path(__file__).resolve().parents[1]
UPSTREAM_DEFAULT = Path(os.environ.get("REALAI_UPSTREAM", "/work/upstream_realai"))

#: Published ICRA 2025 hardware scores, average of the runs (dfki-ric-underactuated-lab/real_ai_gym_leaderboard,
#: leaderboards/icra2025/ICRA_2025_<task>_real_system_results.csv). The simulation scores, the hardware best runs and
#: the entries' names are pendulab's own (PUBLISHED_V3, PUBLISHED_HARDWARE, ENTRY_LABELS), imported where used: the
#: acados worker runs this file in a venv of its own and needs none of them.
PUBLISHED_HW_MEAN = {
    "pendubot": {"acados_mpc": 0.716, "ar_eapo": 0.696, "mcpilco": 0.542, "vimppi": 0.363},
    "acrobot": {"acados_mpc": 0.755, "ar_eapo": 0.616, "mcpilco": 0.566, "vimppi": 0.364},
}
ENTRIES = ("acados_mpc", "ar_eapo", "mcpilco", "vimppi")
#: Why an entry does not run in this benchmark (written into its case records and the report).
CANNOT_RUN = {
    ("acados_mpc", "sim"): (
        "only the hardware-final acados submission (experiments/icra_2025/con_acados_mpc_<task>.py) is wired to the "
        "acados worker; the simulation-stage one (leaderboard/<task>/simulation_v3/con_acados_mpc.py) is not run."
    ),
    ("vimppi", "sim"): (
        "not run: the simulation-stage VIMPPI is called every 2 ms (upstream's simulator dt), ~45 ms a call on this "
        "CPU (JAX CPU, 4096 rollouts of 20 steps): ~25 min a 60 s episode, and its published runs' reset schedule is "
        "not recoverable (see the reproduction check), so no exact check would come of it; the hardware-final VIMPPI "
        "(hw) is run."
    ),
    ("acados_mpc", "hw-adapter"): (
        "the acados entry runs in a worker process; pendulab's own from_realai path needs the object in-process."
    ),
    ("vimppi", "hw-adapter"): "not run: the hw variant is the same object behind the same adapter (~45 ms a call).",
}
SEEDS_V3 = {"pendubot": [333], "acrobot": [777]}
#: Seeds whose published-draw schedule (``reset_schedule(seed, schedule="published")``) matches the published
#: simulation runs' reset times.
LEGACY_SEEDS = {"pendubot": [777], "acrobot": [333]}


def entry_file(upstream: Path, variant: str, entry: str, task: str) -> Path:
    """The upstream ``con_`` file of an entry."""
    if variant in ("hw", "hw-adapter"):
        return upstream / "experiments" / "icra_2025" / f"con_{entry}_{task}.py"
    return upstream / "leaderboard" / task / "simulation_v3" / f"con_{entry}.py"


@contextlib.contextmanager
def _in_dir(path: Path):
    old_cwd, old_path = os.getcwd(), list(sys.path)
    os.chdir(path)
    sys.path.insert(0, str(path))
    for mod in ("parameters", "sim_parameters"):  # the con_ files import these by plain name
        sys.modules.pop(mod, None)
    try:
        yield
    finally:
        os.chdir(old_cwd)
        sys.path[:] = old_path
        for mod in ("parameters", "sim_parameters"):
            sys.modules.pop(mod, None)


def load_entry(
    upstream: Path, variant: str, entry: str, task: str, latency: float = 0.0, period: float | None = None
) -> tuple[Any, dict[str, Any]]:
    """Import an entry's ``con_`` file afresh (its relative paths resolve in its folder) and return its controller.

    Returns
    -------
    controller : object
        The upstream ``AbstractController`` the ``con_`` file builds.
    meta : dict
        ``file``, the entry's ``dt`` if it declares one, and notes on what was changed.
    """
    path = entry_file(upstream, variant, entry, task)
    if not path.exists():
        raise FileNotFoundError(f"no {path}")
    if entry != "vimppi" and (latency or period is not None):
        raise ValueError("a latency or period applies to the held entries only (vimppi)")
    if entry == "vimppi":
        _jax_on_one_cpu_thread()
    name = f"_upstream_{variant}_{entry}_{task}_{time.monotonic_ns()}"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    with _in_dir(path.parent), contextlib.redirect_stdout(sys.stderr):
        spec.loader.exec_module(mod)
    ctrl = mod.controller
    meta: dict[str, Any] = {"file": str(path.relative_to(upstream)), "entry_dt": getattr(mod, "dt", None), "notes": []}
    if entry == "mcpilco" and variant in ("hw", "hw-adapter"):
        # upstream: loop at 1/330 s, policy every 10 calls (30.3 ms); pendulab's loop: 2 ms -> every 15 calls (30 ms)
        meta["notes"].append(f"ctrl_rate {ctrl.ctrl_rate} -> 15 (policy every 30 ms at 2 ms calls, as 10 x 1/330 s)")
        ctrl.ctrl_rate = 15
    if entry == "vimppi":
        # the robot's loop ran each entry at its con file's dt (leaderboard_score_run.py: run_experiment(dt=imp.dt))
        held = float(mod.dt) if period is None else float(period)
        meta["notes"].append(
            f"held at its dt = {held * 1e3:g} ms (the hardware loop's rate; pendulab's loop steps 2 ms): called at the "
            "first step at or after each multiple of dt, the torque held in between; JAX CPU backend, one XLA thread"
        )
        if period is not None:
            meta["notes"].append(f"what-if: called every {held * 1e3:g} ms instead of its dt = {mod.dt * 1e3:g} ms")
        ctrl = HeldEntry(ctrl, held, latency)
        if latency:
            meta["notes"].append(f"what-if: each output takes effect {latency * 1e3:g} ms after its state")
    if entry == "mcpilco" and variant in ("hw", "hw-adapter"):
        meta["policy_file"] = Path(getattr(mod, "policy_par_path", "")).name
    return ctrl, meta


ACADOS_VENV = Path(os.environ.get("REALAI_ACADOS_VENV", "/work/venvs/realai-acados"))
#: The checks in upstream's own code (see :func:`upstream_simulation`): on the model-1.0 plant, on the entry's own model.
UPSTREAM_SIM = ("upstream-sim", "upstream-sim-own")
ACADOS_SQP_CAP = 3  # SQP iterations per call of the acrobot acados entry (stands in for its 3 ms timeout)
_REQ, _ANS = 6, 3  # float64 words: request [cmd, t, x1..x4] (cmd 0 call, 2 quit); answer [u1, u2, wall]


class _Timed:
    """An upstream controller whose ``get_control_output_`` calls are timed (wall [s])."""

    def __init__(self, controller: Any) -> None:
        self.controller = controller
        self.times: list[float] = []

    def get_control_output_(self, x: Any, t: float | None = None) -> Any:
        t0 = time.perf_counter()
        u = self.controller.get_control_output_(x, t)
        self.times.append(time.perf_counter() - t0)
        return u

    def __getattr__(self, name: str) -> Any:
        return getattr(self.controller, name)


def upstream_simulation(
    controller: Any, icra_dir: Path, dt: float, seed: int, t_final: float = 60.0, plant_pars: Any = None
) -> dict[str, Any]:
    """An entry through upstream's own code only: the hardware final's wrapper in upstream's simulator.

    ``GlobalPolicyTestingControllerV2`` with the hardware final's parameters (``experiments/icra_2025/parameters.py``:
    10 PID resets of 1 s, limits 3.5 pi / 20 rad/s) around the entry, ``np.random.seed(seed)`` before it draws its
    schedule, upstream's ``Simulator`` on the model-1.0 plant of that file (RK4 at the entry's ``dt``, torques clipped
    to its [6, 6]), scored by upstream's ``get_uptime`` (height 0.9). Imports upstream and NumPy only (runs in either
    venv); a check of pendulab's protocols against upstream's code, not a pendulab protocol. ``plant_pars`` (upstream
    ``model_parameters``) replaces the model-1.0 plant, e.g. by the entry's own model.
    """
    with _in_dir(icra_dir):
        from double_pendulum.analysis.leaderboard import get_number_of_swingups, get_uptime
        from double_pendulum.controller.global_policy_testing_controller import GlobalPolicyTestingControllerV2
        from double_pendulum.model.symbolic_plant import SymbolicDoublePendulum
        from double_pendulum.simulation.simulation import Simulator
        from parameters import goal, height, kd, ki, kp, method, mpar_nolim, n_disturbances, reset_length

        timed = _Timed(controller)
        np.random.seed(seed)
        wrapper = GlobalPolicyTestingControllerV2(
            timed, goal=goal, n_disturbances=n_disturbances, t_max=t_final, reset_length=reset_length, method=method,
            height=height, mpar=mpar_nolim, kp=kp, ki=ki, kd=kd, pos_limit=3.5 * np.pi, vel_limit=20.0,
            pid_pos_contribution_limit=[3.0, 3.0],
        )  # fmt: skip
        t0 = time.perf_counter()
        plant = SymbolicDoublePendulum(model_pars=mpar_nolim if plant_pars is None else plant_pars)
        T, X, U = Simulator(plant=plant).simulate(
            t0=0.0, x0=[0.0] * 4, tf=t_final, dt=dt, controller=wrapper, integrator="runge_kutta"
        )
        T, X = np.asarray(T), np.asarray(X)
        uptime = float(get_uptime(T, X, mpar=mpar_nolim, method="height", height=height))
        times = np.asarray(timed.times)
        return {
            "score": uptime / t_final,
            "uptime": uptime,
            "n_swingups": int(get_number_of_swingups(T, X, mpar=mpar_nolim, method="height", height=height)),
            "dt": dt,
            "controller_time": {"median_s": float(np.median(times)), "max_s": float(times.max()), "calls": int(times.size)},
            "wall_time_s": time.perf_counter() - t0,
        }


def acados_worker(con_file: str, simulate_seed: int | None = None, own_plant: bool = False) -> None:
    """``--acados-worker CON_FILE``: build upstream's AcadosMpc entry from its ``con_`` file (in the acados venv) and
    answer ``get_control_output_`` requests on stdin/stdout (binary float64). Imports nothing of pendulab.

    With ``simulate_seed`` (``--upstream-sim-seed``) it instead runs :func:`upstream_simulation` at the entry's own
    ``dt`` and writes its record as one JSON line; with ``own_plant`` (``--upstream-sim-own``) on the entry's own model
    (its ``con_`` file's ``mpar``: the links, friction and rotor inertia its MPC predicts with) instead of model 1.0."""
    from acados_env import acados_env  # benchmarks/acados_env.py (this script's folder is on the path)

    acados_env()
    proto_out = os.fdopen(os.dup(1), "wb", buffering=0)
    os.dup2(2, 1)  # everything the entry (Python or C) prints goes to stderr; the protocol keeps the real stdout
    sys.stdout = sys.stderr
    path = Path(con_file).resolve()
    # the con_ file imports hardware_control_loop_tmotors (motor drivers) only to name run_experiment: stub it
    import types

    stub = types.ModuleType("double_pendulum.experiments.hardware_control_loop_tmotors")
    stub.run_experiment = None
    sys.modules[stub.__name__] = stub
    # the wheel's acados_template (0.2.x) takes the horizon as dims.N; upstream (acados >= 0.4) sets
    # solver_options.N_horizon: carry it over where the solver is made
    import acados_template.acados_ocp_solver as aos

    make = aos.make_ocp_dims_consistent

    def _dims_consistent(ocp, *a, **k):
        n = getattr(ocp.solver_options, "N_horizon", None)
        if getattr(ocp.dims, "N", None) is None and n is not None:
            ocp.dims.N = int(n)
        cap = os.environ.get("REALAI_ACADOS_MAX_ITER")
        if cap and ocp.solver_options.nlp_solver_type == "SQP":
            # the 0.2.x solver has no timeout_max_time (upstream's acrobot entry: full SQP, 40 iterations, 3 ms
            # timeout): cap the iterations instead, so a call costs about what the timeout allowed
            ocp.solver_options.nlp_solver_max_iter = min(int(cap), int(ocp.solver_options.nlp_solver_max_iter))
        return make(ocp, *a, **k)

    aos.make_ocp_dims_consistent = _dims_consistent
    # ... and has no split RTI timings (upstream only logs them): report NaN for those
    get_stats = aos.AcadosOcpSolver.get_stats

    def _get_stats(self, field):
        if field in ("time_feedback", "time_preparation"):
            return float("nan")
        return get_stats(self, field)

    aos.AcadosOcpSolver.get_stats = _get_stats
    if not hasattr(aos.AcadosOcpSolver, "get_status"):  # newer API: the status of the last solve()
        aos.AcadosOcpSolver.get_status = lambda self: self.status
    spec = importlib.util.spec_from_file_location("_acados_entry", path)
    mod = importlib.util.module_from_spec(spec)
    with _in_dir(path.parent):
        spec.loader.exec_module(mod)
    ctrl = mod.controller
    if simulate_seed is not None:
        own = None
        if own_plant:
            own = copy.deepcopy(mod.mpar)
            own.Ir = float(np.ravel(own.Ir)[0])  # the con files set it as a list, which upstream's sympy plant refuses
        rec = upstream_simulation(ctrl, path.parent, float(mod.dt), simulate_seed, plant_pars=own)
        proto_out.write((json.dumps(rec) + "\n").encode())
        return
    proto_out.write(b"READY\n")
    stdin = sys.stdin.buffer
    while True:
        buf = stdin.read(8 * _REQ)
        if len(buf) < 8 * _REQ:
            break
        req = np.frombuffer(buf, dtype=np.float64)
        if req[0] == 2:
            break
        t0 = time.perf_counter()
        u = np.asarray(ctrl.get_control_output_(np.array(req[2:6]), float(req[1])), dtype=float).reshape(-1)
        wall = time.perf_counter() - t0
        proto_out.write(np.array([u[0], u[1], wall], dtype=np.float64).tobytes())


def _acados_process(con_file: Path, log: Any, *extra: str) -> Any:
    """The acados worker (``--acados-worker CON_FILE [extra]``) started in the acados venv, stderr to ``log``."""
    import subprocess

    py = ACADOS_VENV / "bin" / "python"
    if not py.exists():
        raise FileNotFoundError(f"no acados venv at {ACADOS_VENV} (bash benchmarks/setup_realai_env.sh)")
    env = dict(os.environ)
    libs = sorted(ACADOS_VENV.glob("lib/python3*/site-packages/acados/install/lib"))
    if libs:  # the generated solver's library loads qpOASES/HPIPM/BLASFEO from here (dlopen: set before start)
        env["LD_LIBRARY_PATH"] = os.pathsep.join([str(libs[0]), *filter(None, [env.get("LD_LIBRARY_PATH")])])
    return subprocess.Popen(
        [str(py), str(Path(__file__).resolve()), "--acados-worker", str(con_file), *extra],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=log,
        env=env,
    )


def acados_upstream_simulation(con_file: Path, seed: int, log: Path, own_plant: bool = False) -> dict[str, Any]:
    """:func:`upstream_simulation` of the acados entry ``con_file``, run by a worker in the acados venv."""
    with open(log, "w") as fh:
        proc = _acados_process(con_file, fh, "--upstream-sim-seed", str(seed), *(["--upstream-sim-own"] if own_plant else []))
        out, _ = proc.communicate()
    if proc.returncode != 0 or not out.strip():
        raise RuntimeError(f"acados worker failed (exit {proc.returncode}; see {log})")
    return json.loads(out.decode().strip().splitlines()[-1])


class AcadosProxy:
    """Upstream's AcadosMpc entry in a worker process of the acados venv, with the entry's ``get_control_output_``."""

    def __init__(self, con_file: Path, log: Path) -> None:
        self._log = open(log, "w")
        self.proc = _acados_process(con_file, self._log)
        line = self.proc.stdout.readline()
        if line.strip() != b"READY":
            self.close()
            raise RuntimeError(f"acados worker did not start (see {log}): {line!r}")
        self.worker_times: list[float] = []

    def get_control_output_(self, x: np.ndarray, t: float | None = None) -> np.ndarray:
        self.proc.stdin.write(np.array([0.0, t or 0.0, *np.asarray(x, dtype=float)[:4]], dtype=np.float64).tobytes())
        self.proc.stdin.flush()
        ans = np.frombuffer(self.proc.stdout.read(8 * _ANS), dtype=np.float64)
        self.worker_times.append(float(ans[2]))
        return ans[:2].copy()

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                self.proc.stdin.write(np.array([2.0, 0, 0, 0, 0, 0], dtype=np.float64).tobytes())
                self.proc.stdin.flush()
                self.proc.wait(timeout=10)
            except Exception:
                self.proc.kill()
        self._log.close()


def _jax_on_one_cpu_thread() -> None:
    """Start JAX's CPU backend with one XLA thread before a VIMPPI ``con_`` file runs.

    The ``con_`` files set GPU-only ``XLA_FLAGS`` after importing jax; the backend reads the flags when it starts,
    so starting it here keeps these (one thread: two benchmark processes share the 2 cores without contention;
    measured: the same ~45 ms a call as XLA's default threading on this machine).
    """
    os.environ["XLA_FLAGS"] = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
    os.environ["JAX_PLATFORMS"] = "cpu"
    import jax

    jax.devices()


class HeldEntry:
    """An upstream entry called at its own period: at the first call at or after each multiple of ``period``.

    Between those calls the last torque is returned. Upstream's hardware loop ran each entry at its ``con_`` file's
    ``dt``; pendulab's loops step 2 ms (v3) or 2.0-3.7 ms (v3-hardware), so an entry declared at 5 ms is held.
    With ``latency`` > 0 (a what-if: the entry's compute time on the robot's computer) a new output takes effect
    ``latency`` seconds after the state it was computed from; until the first one does, the output is zero.
    """

    def __init__(self, controller: Any, period: float, latency: float = 0.0) -> None:
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"period must be a positive number of seconds, got {period!r}")
        if not (np.isfinite(latency) and 0.0 <= latency <= period):
            raise ValueError(f"latency must be in [0, period = {period!r}] s, got {latency!r}")
        self.controller, self.period, self.latency = controller, period, latency
        self.call_times: list[float] = []  # wall [s] of each call of the entry itself (holds excluded)
        self._next: float | None = None
        self._u = np.zeros(2)  # upstream's (u1, u2); what the robot's motors get before the first output
        self._pending: tuple[float, np.ndarray] | None = None

    def get_control_output_(self, x: Any, t: float | None = None) -> np.ndarray:
        """The entry's output at its own period (``t`` [s] required), held between its calls."""
        if t is None:
            raise ValueError("HeldEntry needs the time t [s]")
        if self._pending is not None and t >= self._pending[0] - 1e-9:
            self._u, self._pending = self._pending[1], None
        if self._next is None or t >= self._next - 1e-9 or t < self._next - 2 * self.period:
            t0 = time.perf_counter()
            u = np.asarray(self.controller.get_control_output_(x, t), dtype=float).reshape(-1)
            self.call_times.append(time.perf_counter() - t0)
            self._next = (np.floor(t / self.period + 1e-9) + 1.0) * self.period
            if self.latency > 0.0:
                self._pending = (t + self.latency, u)
            else:
                self._u = u
        return self._u

    def __getattr__(self, name: str) -> Any:
        return getattr(self.controller, name)


class RawEntry:
    """An upstream entry as ``GlobalPolicyTestingControllerV2`` drives it: raw ``get_control_output_``, no init/reset."""

    def __init__(self, controller: Any) -> None:
        self.controller = controller

    def init(self) -> None:
        """Nothing: upstream's simulator and hardware loop never call it (the ``con_`` file did)."""

    def reset(self) -> None:
        """Nothing: as above."""

    def get_control_output(self, x: np.ndarray, t: float | None = None) -> np.ndarray:
        """``(u1, u2)`` [N.m] of the entry's raw output at joint-coordinate state ``x``."""
        return np.asarray(self.controller.get_control_output_(np.asarray(x, dtype=float), t), dtype=float).reshape(-1)


def case_id(variant: str, entry: str, task: str, protocol: str, seed: int, allowance: float) -> str:
    tail = f"_a{allowance:g}" if protocol == "v3-hardware" else ""
    return f"{variant}_{entry}_{task}_{protocol}_s{seed}{tail}"


def run_case(
    upstream: Path,
    variant: str,
    entry: str,
    task: str,
    protocol: str,
    seed: int,
    allowance: float,
    progress: Any = None,
    plant: IdentifiedPlant | None = None,
    entry_latency: float = 0.0,
    entry_period: float | None = None,
) -> dict[str, Any]:
    """Run one case and return its record (score, published scores, controller time, protocol details).

    ``plant`` (an ``IdentifiedPlant``, v3-hardware only) replaces the identified C.1 as the simulated robot;
    ``entry_latency`` [s] delays a held entry's outputs and ``entry_period`` [s] replaces its period
    (:class:`HeldEntry`, VIMPPI; what-ifs).
    """
    from pendulab.control.realai.adapter import from_realai
    from pendulab.evaluate.realai.leaderboard_published import PUBLISHED_HARDWARE as PUBLISHED_HW_BEST
    from pendulab.evaluate.realai.upstream_records import ENTRY_LABELS as LABELS
    from pendulab.evaluate.realai.v3 import run_v3
    from pendulab.evaluate.realai.v3_definition import PLANT_LIMIT
    from pendulab.evaluate.realai.v3_definition import PUBLISHED_V3 as PUBLISHED_SIM
    from pendulab.evaluate.realai.v3_hardware import run_v3_hardware

    t0 = time.perf_counter()
    if protocol in UPSTREAM_SIM:
        if entry != "acados_mpc" or variant != "hw":
            raise RuntimeError(
                "upstream-sim runs the hardware-final acados entries (AR-EAPO and MC-PILCO are checked against their "
                "published runs instead: v3-legacy)"
            )
        con = entry_file(upstream, variant, entry, task)
        if task == "acrobot":
            os.environ.setdefault("REALAI_ACADOS_MAX_ITER", str(ACADOS_SQP_CAP))
        cap = os.environ.get("REALAI_ACADOS_MAX_ITER") if task == "acrobot" else None
        log = Path(os.environ.get("REALAI_ACADOS_LOG", "/tmp")) / f"acados_sim_{task}.log"
        own = protocol == "upstream-sim-own"
        rec = acados_upstream_simulation(con, seed, log, own_plant=own)
        plant_note = "the entry's own model (its mpar)" if own else "the model-1.0 plant"
        rec.update(
            case=case_id(variant, entry, task, protocol, seed, 0.0),
            variant=variant,
            entry=entry,
            label=LABELS[entry],
            task=task,
            protocol=protocol,
            seed=seed,
            allowance=0.0,
            upstream_file=str(con.relative_to(upstream)),
            notes=[
                "upstream's own code: GlobalPolicyTestingControllerV2 (hardware final's parameters) in upstream's Simulator "
                f"on {plant_note}, "
                "RK4 at the entry's dt, np.random.seed(seed) before the wrapper, get_uptime",
                *([f"full SQP capped at {cap} iterations per call (no timeout_max_time in acados 0.2.x)"] if cap else []),
            ],
            published_sim=PUBLISHED_SIM[task].get(entry),
            published_hw_best=PUBLISHED_HW_BEST[task].get(entry),
            published_hw_mean=PUBLISHED_HW_MEAN[task].get(entry),
            status="ok",
            recorded=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        )
        return rec
    if entry == "acados_mpc":
        if variant != "hw":
            raise RuntimeError("only the hardware-final acados entry (experiments/icra_2025) is wired to the worker")
        con = entry_file(upstream, variant, entry, task)
        if task == "acrobot":
            os.environ.setdefault("REALAI_ACADOS_MAX_ITER", str(ACADOS_SQP_CAP))
        ctrl = AcadosProxy(con, Path(os.environ.get("REALAI_ACADOS_LOG", "/tmp")) / f"acados_worker_{task}.log")
        meta = {
            "file": str(con.relative_to(upstream)),
            "entry_dt": 0.001 if task == "pendubot" else 0.003,
            "notes": [
                *(
                    [
                        f"full SQP capped at {os.environ['REALAI_ACADOS_MAX_ITER']} iterations per call: the available acados "
                        "0.2.x has no timeout_max_time, upstream's 3 ms SQP timeout (Nlp_max_iter 40 would take ~50 ms a call "
                        "here, ~30 min a run); an approximation of the submitted controller"
                    ]
                    if task == "acrobot"
                    else []
                ),
                "runs in a worker process (acados venv, Python 3.12); controller time below includes the pipe round trip, "
                "worker_time the entry's own get_control_output_",
                "upstream ran it at dt = 1 ms (pendubot) / 3 ms (acrobot), solving every mpc_cycle_dt of the same length; "
                "pendulab's loop calls it every 2 ms",
            ],
        }
    else:
        ctrl, meta = load_entry(upstream, variant, entry, task, entry_latency, entry_period)
    load_s = time.perf_counter() - t0
    # hw-adapter: the upstream object handed to pendulab as is, so run_v3/run_v3_hardware wrap it themselves
    # (pendulab.evaluate.realai.v3.protocol_entry: RawEntry, get_control_output_ raw, clipped to the rules, timed)
    wrapped = ctrl if variant == "hw-adapter" else from_realai(RawEntry(ctrl), task="full", sample_time=0.002)
    label = f"{LABELS[entry]} ({variant})"
    if protocol == "v3":
        res = run_v3(task, wrapped, label, seed=seed, progress=progress)
    elif protocol == "v3-legacy" and variant == "hw-adapter":
        raise RuntimeError("hw-adapter runs pendulab's own protocol paths only (v3, v3-hardware)")
    elif protocol == "v3-legacy":
        # the published simulation runs exactly: their schedule draw, and the entry's torque clipped only by the
        # simulated plant's [6, 6] (upstream's Simulator clips everything to mpar_nolim; the [6, 0] rule is not enforced)
        res = run_v3(task, wrapped, label, seed=seed, progress=progress, passive_limit=PLANT_LIMIT, schedule="published")
    else:
        res = run_v3_hardware(task, wrapped, label, seed=seed, passive_allowance=allowance, progress=progress, plant=plant)
    if isinstance(ctrl, AcadosProxy):
        wt = np.asarray(ctrl.worker_times)
        ctrl.close()
        meta["worker_time"] = {"median_s": float(np.median(wt)), "max_s": float(wt.max()), "calls": int(wt.size)}
    if isinstance(ctrl, HeldEntry) and ctrl.call_times:
        ct = np.asarray(ctrl.call_times)
        meta["worker_time"] = {"median_s": float(np.median(ct)), "max_s": float(ct.max()), "calls": int(ct.size)}
    d = res.to_dict()
    for k in ("reset_states_relative", "intervals"):
        d.pop(k, None)
    u = np.asarray(res.u, dtype=float)
    passive = 1 if task == "pendubot" else 0
    if protocol == "v3-legacy":
        d["protocol"] = "v3-legacy"
        d["schedule"] = "legacy: states (15, 4) drawn first, as the published ICRA 2025 simulation runs"
        d["entry_torque_limit"] = [PLANT_LIMIT, PLANT_LIMIT]
    d.update(
        case=case_id(variant, entry, task, protocol, seed, allowance),
        variant=variant,
        entry=entry,
        label=LABELS[entry],
        allowance=allowance if protocol == "v3-hardware" else 0.0,
        upstream_file=meta["file"],
        entry_dt=meta["entry_dt"],
        notes=meta["notes"],
        worker_time=meta.get("worker_time"),
        load_s=load_s,
        passive_torque_max=float(np.abs(u[:, passive]).max()) if u.size else None,
        published_sim=PUBLISHED_SIM[task].get(entry),
        published_hw_best=PUBLISHED_HW_BEST[task].get(entry),
        published_hw_mean=PUBLISHED_HW_MEAN[task].get(entry),
        plant=None if plant is None else {"params": plant.params, "what_if": plant.meta.get("what_if")},
        entry_latency=entry_latency,
        entry_period=entry_period,
        status="ok",
        recorded=time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    )
    return d


def planned_cases(args: argparse.Namespace) -> list[tuple[str, str, str, str, int, float]]:
    cases = []
    for task in args.tasks:
        for variant in args.variants:
            for entry in args.entries:
                protocols = [p for p in args.protocols if p != "v3-hardware"] if variant == "sim" else args.protocols
                for protocol in protocols:
                    if protocol in UPSTREAM_SIM:  # upstream's own simulator: wired for the acados entries only
                        if (variant, entry) == ("hw", "acados_mpc"):
                            cases += [(variant, entry, task, protocol, s, 0.0) for s in args.hw_seeds]
                    elif protocol == "v3-legacy":
                        cases += [(variant, entry, task, protocol, s, 0.0) for s in LEGACY_SEEDS[task]]
                    elif protocol == "v3":
                        seeds = list(dict.fromkeys(SEEDS_V3[task] + (args.extra_v3_seeds if variant == "hw" else [])))
                        cases += [(variant, entry, task, protocol, s, 0.0) for s in seeds]
                    else:
                        cases += [(variant, entry, task, protocol, s, a) for s in args.hw_seeds for a in args.allowance]
    return cases


def _write(path: Path, record: dict[str, Any]) -> None:
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(record, indent=2) + "\n")
    tmp.replace(path)


def load_records(out: Path) -> list[dict[str, Any]]:
    return [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]


def _fmt(v: Any, nd: int = 3) -> str:
    return "–" if v is None else f"{v:.{nd}f}"


def report(out: Path) -> str:
    """Markdown tables of the recorded cases: scores beside the published ones, Spearman rho, controller time."""
    from pendulab.evaluate.realai.leaderboard_published import PUBLISHED_HARDWARE as PUBLISHED_HW_BEST
    from pendulab.evaluate.realai.upstream_records import ENTRY_LABELS as LABELS
    from pendulab.evaluate.realai.upstream_records import spearman_rho
    from pendulab.evaluate.realai.v3_definition import PUBLISHED_V3 as PUBLISHED_SIM

    recs = [r for r in load_records(out) if r.get("status") == "ok"]
    lines: list[str] = []
    groups: dict[tuple[str, str, str, float], list[dict[str, Any]]] = {}
    for r in recs:
        groups.setdefault((r["task"], r["protocol"], r["variant"], r.get("allowance", 0.0)), []).append(r)
    lines += [
        "| task | protocol | variant | entry | seeds | score per seed | mean | published sim | published hw best (mean) | "
        "swing-ups | limit resets / stops | ctrl time median / max [ms] |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    means: dict[tuple[str, str, str, float], dict[str, float]] = {}
    for key in sorted(groups):
        task, protocol, variant, allowance = key
        by_entry: dict[str, list[dict[str, Any]]] = {}
        for r in groups[key]:
            by_entry.setdefault(r["entry"], []).append(r)
        for entry, rs in sorted(by_entry.items()):
            rs.sort(key=lambda r: r["seed"])
            scores = [r["score"] for r in rs]
            ct = [r["controller_time"] for r in rs]
            meds = [c["median_s"] for c in ct if c["median_s"] is not None]
            med = float(np.median(meds)) * 1e3 if meds else float("nan")
            mx = max([c["max_s"] for c in ct if c["max_s"] is not None], default=float("nan")) * 1e3
            proto = protocol if protocol != "v3-hardware" else f"v3-hardware (allowance {allowance:g})"
            lr = (
                " / ".join([str(sum(r.get("limit_resets", 0) for r in rs)), str(sum(1 for r in rs if r.get("stopped_at")))])
                if protocol == "v3-hardware"
                else "–"
            )
            lines.append(
                f"| {task} | {proto} | {variant} | {LABELS[entry]} | {', '.join(str(r['seed']) for r in rs)} | "
                f"{', '.join(f'{s:.3f}' for s in scores)} | {np.mean(scores):.3f} | {_fmt(PUBLISHED_SIM[task].get(entry))} | "
                f"{_fmt(PUBLISHED_HW_BEST[task].get(entry))} ({_fmt(PUBLISHED_HW_MEAN[task].get(entry))}) | "
                f"{', '.join(str(r['n_swingups']) for r in rs)} | {lr} | {med:.3f} / {mx:.2f} |"
            )
            means.setdefault(key, {})[entry] = float(np.mean(scores))
    lines += [
        "",
        "| task | protocol | variant | entries (ran) | rho vs published sim | rho vs published hw (best) | "
        "rho vs published hw (mean) |",
        "|---|---|---|---|---|---|---|",
    ]
    for key, m in sorted(means.items()):
        task, protocol, variant, allowance = key
        names = sorted(m)
        proto = protocol if protocol != "v3-hardware" else f"v3-hardware (allowance {allowance:g})"
        cells = []
        for pub in (PUBLISHED_SIM, PUBLISHED_HW_BEST, PUBLISHED_HW_MEAN):
            if len(names) < 2:
                cells.append("– (one entry)")
                continue
            rho = spearman_rho([m[n] for n in names], [pub[task][n] for n in names])
            # with n entries rho takes few values (n = 3: ±1, ±0.5); asymptotic p-values mean nothing here
            cells.append(f"{rho:+.2f} (n = {len(names)})")
        lines.append(f"| {task} | {proto} | {variant} | {', '.join(LABELS[n] for n in names)} | " + " | ".join(cells) + " |")
    fails: dict[tuple[str, str, str, str], list[str]] = {}
    for r in load_records(out):
        if r.get("status") != "ok":
            fails.setdefault((r["entry"], r["variant"], r["status"], r.get("error", "")), []).append(
                f"{r['task']} {r['protocol']} s{r['seed']}"
            )
    if fails:
        lines += ["", "| entry | variant | status | cases | why |", "|---|---|---|---|---|"]
        lines += [f"| {LABELS[e]} | {v} | {st} | {len(cs)} | {why} |" for (e, v, st, why), cs in sorted(fails.items())]
    return "\n".join(lines) + "\n"


def figure(out: Path, path: Path) -> Path:
    """Each hardware-final entry's mean score on pendulab's v3 and v3-hardware against its published hardware score."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scores: dict[tuple[str, str, str], list[float]] = {}
    published: dict[tuple[str, str], float] = {}
    for f in sorted(out.glob("hw_*.json")):
        d = json.loads(f.read_text())
        if d.get("status") != "ok" or d["protocol"] not in ("v3", "v3-hardware") or d.get("published_hw_best") is None:
            continue
        scores.setdefault((d["label"], d["task"], d["protocol"]), []).append(float(d["score"]))
        published[d["label"], d["task"]] = float(d["published_hw_best"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 5), layout="constrained")
    for ax, task in zip(axes, ("pendubot", "acrobot"), strict=True):
        for protocol, marker, color in (("v3", "o", "tab:gray"), ("v3-hardware", "s", "tab:blue")):
            for (label, t, p), vals in scores.items():
                if t != task or p != protocol:
                    continue
                x, y = published[label, task], float(np.mean(vals))
                ax.errorbar(x, y, yerr=np.std(vals) if len(vals) > 1 else None, fmt=marker, color=color, capsize=3)
                ax.annotate(f"{label} ({len(vals)})", (x, y), textcoords="offset points", xytext=(5, 4), fontsize=8)
        ax.plot([0, 1], [0, 1], "k:", lw=0.8, label="simulated = published")
        ax.plot([], [], "o", color="tab:gray", label="pendulab v3 (simulation protocol)")
        ax.plot([], [], "s", color="tab:blue", label="pendulab v3-hardware (identified C.1, 0.5 N.m allowance)")
        ax.set(xlim=(0, 1), ylim=(0, 1), title=task, xlabel="published hardware score (ICRA 2025 final, best run) [-]")
        ax.set_ylabel("pendulab score, mean over seeds (± std) [-]")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--upstream", type=Path, default=UPSTREAM_DEFAULT, help="upstream work tree (setup_realai_env.sh)")
    ap.add_argument("--out", type=Path, default=REPO / "pendulab-out" / "upstream_entries")
    ap.add_argument("--tasks", nargs="+", default=["pendubot", "acrobot"])
    ap.add_argument("--entries", nargs="+", default=list(ENTRIES), choices=ENTRIES)
    ap.add_argument("--variants", nargs="+", default=["sim", "hw"], choices=["sim", "hw", "hw-adapter"])
    ap.add_argument(
        "--protocols",
        nargs="+",
        default=["v3", "v3-legacy", "v3-hardware"],
        choices=["v3", "v3-legacy", "v3-hardware", *UPSTREAM_SIM],
        help="upstream-sim: the acados entries in upstream's own simulator and wrapper (a check of pendulab's protocols); "
        "upstream-sim-own: the same on the entry's own model as the plant",
    )
    ap.add_argument("--hw-seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--extra-v3-seeds", nargs="*", type=int, default=[], help="v3 seeds besides 333/777 (hw variant)")
    ap.add_argument("--allowance", nargs="+", type=float, default=[0.5], help="v3-hardware passive allowance [N.m]")
    ap.add_argument("--force", action="store_true", help="rerun recorded cases")
    ap.add_argument("--report", action="store_true", help="only print the tables of the recorded cases")
    ap.add_argument("--figure", type=Path, help="only draw simulated against published hardware score (PNG)")
    ap.add_argument(
        "--plant",
        help="plant file of the simulated robot in v3-hardware (a what-if robot, IdentifiedPlant.with_params); "
        "needs --protocols v3-hardware and an --out of its own, so its cases never mix with the identified robot's",
    )
    ap.add_argument(
        "--entry-latency",
        type=float,
        default=0.0,
        metavar="S",
        help="what-if: VIMPPI's outputs take effect S seconds after their state (in [0, its period]; its compute time "
        "on the robot's computer); needs --entries vimppi and an --out of its own",
    )
    ap.add_argument(
        "--entry-period",
        type=float,
        default=None,
        metavar="S",
        help="what-if: VIMPPI called every S seconds instead of its con file's dt (a loop slowed by its compute "
        "time); needs --entries vimppi and an --out of its own",
    )
    ap.add_argument("--acados-worker", metavar="CON_FILE", help=argparse.SUPPRESS)
    ap.add_argument("--upstream-sim-seed", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--upstream-sim-own", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.acados_worker:
        acados_worker(args.acados_worker, args.upstream_sim_seed, args.upstream_sim_own)
        return
    plant = None
    if args.plant is not None:
        from pendulab.model.plant_file import load_plant

        if args.protocols != ["v3-hardware"] or args.out == ap.get_default("out"):
            ap.error("--plant needs --protocols v3-hardware and an --out directory of its own")
        plant = load_plant(args.plant)
    if (args.entry_latency or args.entry_period) and (args.entries != ["vimppi"] or args.out == ap.get_default("out")):
        ap.error("--entry-latency and --entry-period need --entries vimppi and an --out directory of its own")
    args.out.mkdir(parents=True, exist_ok=True)
    if args.report:
        print(report(args.out))
        return
    if args.figure:
        print(figure(args.out, args.figure))
        return
    from tqdm import tqdm

    cases = planned_cases(args)
    for variant, entry, task, protocol, seed, allowance in cases:  # the entries that cannot run: recorded once
        if (entry, variant) in CANNOT_RUN:
            path = args.out / f"{case_id(variant, entry, task, protocol, seed, allowance)}.json"
            _write(
                path,
                {
                    "case": path.stem,
                    "variant": variant,
                    "entry": entry,
                    "task": task,
                    "protocol": protocol,
                    "seed": seed,
                    "status": "not run",
                    "error": CANNOT_RUN[entry, variant],
                },
            )
    todo = [
        c for c in cases if (c[1], c[0]) not in CANNOT_RUN and (args.force or not (args.out / f"{case_id(*c)}.json").exists())
    ]
    print(f"{len(cases)} cases planned, {len(todo)} to run -> {args.out}", file=sys.stderr)
    outer = tqdm(todo, desc="cases", unit="case", position=0)
    for variant, entry, task, protocol, seed, allowance in outer:
        cid = case_id(variant, entry, task, protocol, seed, allowance)
        outer.set_postfix_str(cid)
        inner = tqdm(total=30000, desc=cid, unit="step", position=1, leave=False, mininterval=2.0)

        def progress(done: int, total: int, bar: Any = inner) -> None:
            bar.total = total
            bar.n = done
            bar.refresh()

        try:
            rec = run_case(
                args.upstream, variant, entry, task, protocol, seed, allowance, progress, plant, args.entry_latency,
                args.entry_period,
            )  # fmt: skip
        except Exception as exc:  # recorded, not fatal: the report says which entry failed and why
            rec = {
                "case": cid,
                "variant": variant,
                "entry": entry,
                "task": task,
                "protocol": protocol,
                "seed": seed,
                "status": "failed",
                "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc(),
            }
        inner.close()
        _write(args.out / f"{cid}.json", rec)
        if rec["status"] == "ok":
            ct = rec["controller_time"]
            timing = (
                f"ctrl median {1e3 * ct['median_s']:.3f} ms, max {1e3 * ct['max_s']:.2f} ms"
                if ct["median_s"] is not None
                else "ctrl time not recorded (entry called raw by the protocol)"
            )
            tqdm.write(
                f"{cid}: score {rec['score']:.3f} (published sim {_fmt(rec['published_sim'])}, hw "
                f"{_fmt(rec['published_hw_best'])}); {timing}; wall {rec['wall_time_s']:.0f} s"
            )
        else:
            tqdm.write(f"{cid}: {rec['status']}: {rec['error']}")
    print(report(args.out))


if __name__ == "__main__":
    main()

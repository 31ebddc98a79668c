"""Ctrl-C stops long ensembles: the flip-map command, pl.ensemble on every executor, and map_runs.

Each test starts a real process, waits until it is computing, sends SIGINT to its whole process
group (what a terminal's Ctrl-C does) and checks that it ends as interrupted (exit 130 or a
KeyboardInterrupt caught by the script), with no traceback from the process or its workers.

The time limits are hang guards, not speed tests: before the fix these commands ran for minutes
(1e12 s horizons) or 26-37 s (queued chunks); measured here they stop in 0.1-0.6 s. The 20 s
ceiling leaves a wide margin for a loaded machine.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytest.importorskip("heyoka")

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="process-group SIGINT is POSIX")

#: Hang guard [s] between SIGINT and the end of the process (measured 0.1-0.6 s; see the module docstring).
CEILING = 20.0
#: Upper bound [s] on start-up (imports, JIT compilation) before the process signals it is computing.
START_LIMIT = 120.0


def _interrupt(cmd: list[str], ready, cwd: Path, settle: float = 1.0) -> tuple[int, str, str, float]:
    """Run ``cmd``, wait for ``ready(proc)``, let it compute ``settle`` s, SIGINT its group; (rc, out, err, latency)."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        cmd,
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env=env,
        # A shell starts background jobs with SIGINT ignored and children inherit that: give the child
        # the default disposition, as a terminal's foreground command has.
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        deadline = time.monotonic() + START_LIMIT
        while not ready(proc):
            assert proc.poll() is None, f"ended before it was interrupted: {proc.communicate()}"
            assert time.monotonic() < deadline, "did not start computing"
            time.sleep(0.05)
        time.sleep(settle)
        assert proc.poll() is None, "finished before the interrupt: the workload is too short for this test"
        t0 = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=CEILING)
        latency = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    return proc.returncode, out, err, latency


def test_flipmap_command_stops_on_ctrl_c(tmp_path: Path) -> None:
    out = tmp_path / "o"
    # Elastic runs to t = 1e12 s: each lane would take its whole step budget (seconds) without the interrupt.
    cmd = [sys.executable, "-m", "pendulab", "ensemble", "flipmap", "--model", "elastic", "--no-compare"]
    cmd += ["--grid", "5", "--t-max", "1e12", "--out", str(out), "--no-progress"]
    rc, stdout, err, latency = _interrupt(cmd, lambda p: out.exists(), tmp_path)
    print(f"flipmap: SIGINT -> exit in {latency:.3f} s")
    assert rc == 130, (rc, err)
    assert "Traceback" not in err and "interrupted" in err, err
    assert latency < CEILING


_SCRIPT = textwrap.dedent(
    """
    import multiprocessing, sys
    import numpy as np
    import pendulab as pl
    from pendulab.ensemble import map_runs

    mode = sys.argv[1]
    rng = np.random.default_rng(0)
    pl.ensemble(pl.rigid(), [[1.0, 0.5, 0.0, 0.0]], 0.5, threads=1)  # compile before "ready"
    def slow(x):
        import time
        time.sleep(30.0)
        return x
    print("ready", flush=True)
    try:
        if mode == "map_runs":
            map_runs(slow, range(40), workers=2)
        else:
            n = {"main": 2, "threads": 40, "processes": 6000}[mode]
            x0 = np.zeros((n, 4))
            x0[:, :2] = rng.uniform(-3.0, 3.0, (n, 2))
            pl.ensemble(pl.rigid(), x0, 1e12, threads=1 if mode == "main" else 2, max_steps=2**31 - 1)
    except KeyboardInterrupt:
        import time
        # A worker that is exiting (terminated, not yet reaped) is not left behind: one that still runs 2 s later is.
        deadline = time.monotonic() + 2.0
        while multiprocessing.active_children() and time.monotonic() < deadline:
            time.sleep(0.05)
        print("KeyboardInterrupt; workers left:", len(multiprocessing.active_children()), flush=True)
        sys.exit(130)
    print("finished without interrupt", flush=True)
    """
)


@pytest.mark.parametrize("mode", ["main", "threads", "processes", "map_runs"])
def test_long_python_ensemble_stops_on_ctrl_c(tmp_path: Path, mode: str) -> None:
    script = tmp_path / "long_ensemble.py"
    script.write_text(_SCRIPT)
    lines: list[str] = []

    def ready(proc: subprocess.Popen) -> bool:
        lines.append(proc.stdout.readline())
        return lines[-1].strip() == "ready"

    rc, out, err, latency = _interrupt([sys.executable, str(script), mode], ready, tmp_path)
    print(f"pl.ensemble ({mode}): SIGINT -> exit in {latency:.3f} s")
    assert rc == 130, (rc, out, err)
    assert "KeyboardInterrupt; workers left: 0" in out, (out, err)
    # No traceback from the process or its workers (EOFError, KeyboardInterrupt, BrokenPipe...).
    assert "Traceback" not in err and "Error" not in err, err
    assert latency < CEILING


def test_long_lyapunov_estimate_stops_on_ctrl_c() -> None:
    # A SIGINT 0.5 s into a 1e9 s estimate of a regular (small) oscillation, renormalised every 1e5 s
    # (about 2e6 Taylor steps, seconds in C++): handled between two propagation slices instead.
    import threading

    import pendulab as pl
    from pendulab.ensemble.lyapunov import largest_lyapunov

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals are delivered to the main thread")
    largest_lyapunov(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 1.0)  # compile outside the timed part

    def ctrl_c(signum, frame):  # what Python's SIGINT handler does (SIGINT may be ignored in a background job)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGALRM, ctrl_c)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        t0 = time.monotonic()
        with pytest.raises(KeyboardInterrupt):
            largest_lyapunov(pl.rigid(), [0.1, 0.1, 0.0, 0.0], 1e9, renorm_interval=1e5, max_steps=2**62)
        latency = time.monotonic() - t0 - 0.5
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
    print(f"largest_lyapunov: SIGINT -> KeyboardInterrupt in {latency:.3f} s")
    assert latency < CEILING


def test_shutdown_now_leaves_no_pool_thread_to_race_the_exit_hook() -> None:
    # Found in CI: after a Ctrl-C, Python's exit hook wrote to the wake-up pipe of a pool whose manager thread was
    # closing it (CPython 3.11 takes no lock there): "OSError: [Errno 9] Bad file descriptor" on stderr. shutdown_now
    # ends the manager thread before it returns, so nothing is left to race.
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from pendulab.ensemble.pool import ignore_sigint, shutdown_now

    pool = ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("fork"), initializer=ignore_sigint)
    futures = [pool.submit(time.sleep, 60.0) for _ in range(4)]  # two running, two queued
    deadline = time.monotonic() + 60.0
    while not any(f.running() for f in futures) and time.monotonic() < deadline:
        time.sleep(0.01)
    manager, workers = pool._executor_manager_thread, list(pool._processes.values())
    shutdown_now(pool)
    assert not manager.is_alive() and not any(w.is_alive() for w in workers)
    assert all(f.cancelled() or f.done() for f in futures)

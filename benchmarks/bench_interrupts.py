"""Ctrl-C latency per command: SIGINT at a moment inside each phase, time until the process has exited.

    python benchmarks/bench_interrupts.py [--repeats 3] [--out benchmarks/results/interrupts.md]

Target (issue 31): every command ends with ``pendulab: interrupted``, exit 130, no traceback, within 1 s on
an idle machine, finished work kept. Each case starts the command in a fresh process (SIGINT at its default:
a shell's background job would ignore it), waits the stated time so the signal lands in the named phase,
sends SIGINT and measures until the process is gone (a signal that lands after the command has finished,
in the interpreter's teardown, is ignored: the run's own status stands). Every case runs idle and loaded (two busy-looping
processes on the 2 cores, started before the case), interleaved; medians and maxima of ``--repeats``.
"""

from __future__ import annotations

import argparse
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

from tqdm import tqdm

OUT = Path(__file__).resolve().parent / "results" / "interrupts.md"
PL = [sys.executable, "-m", "pendulab"]
#: (phase, delay before SIGINT [s], command after ``pendulab``; ``{out}`` is a fresh folder).
CASES: list[tuple[str, float, list[str]]] = [
    ("start-up imports (swingup)", 0.08, ["swingup", "--task", "pendubot", "--no-gif", "--out", "{out}"]),
    ("swing-up: elastic NLP solve (IPOPT)", 6.0, ["swingup", "--task", "pendubot_elastic", "--out", "{out}"]),
    ("score: scorecard runs", 3.0, ["score", "--task", "pendubot", "--controller", "lqr", "--runs", "3", "--out", "{out}"]),
    ("simulate: a long RK45 run", 3.0, ["simulate", "--model", "elastic", "--t-final", "500", "--method", "RK45",
                                        "--out", "{out}/x.csv"]),
    ("ensemble flipmap (workers)", 4.0, ["ensemble", "flipmap", "--grid", "300", "--out", "{out}"]),
    ("fmu export (C compile)", 0.6, ["fmu", "export", "--model", "elastic", "--out", "{out}/p.fmu"]),
    ("scene check --verify (chaotic)", 0.7, ["scene", "check", "rigid_chaotic", "--verify"]),
]  # fmt: skip


def _once(delay: float, argv: list[str]) -> tuple[float, int, bool, bool]:
    with tempfile.TemporaryDirectory(prefix="pendulab-intr-") as tmp:
        cmd = PL + [a.replace("{out}", tmp) for a in argv]
        proc = subprocess.Popen(
            cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )  # fmt: skip
        time.sleep(delay)
        finished_first = proc.poll() is not None
        t0 = time.perf_counter()
        if not finished_first:
            proc.send_signal(signal.SIGINT)
        err = proc.communicate(timeout=600)[1]
        return time.perf_counter() - t0, proc.returncode, "Traceback" in err, finished_first


def _burners(n: int) -> list[subprocess.Popen]:
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    rows = [
        "| phase | load | median [s] | max [s] | exit codes | traceback | finished before the signal |",
        "|---|---|---|---|---|---|---|",
    ]
    within = True
    jobs = [(case, load) for case in CASES for load in ("idle", "loaded")]
    for (phase, delay, argv), load in tqdm(jobs, desc="interrupt cases", unit="case"):
        burners = _burners(2) if load == "loaded" else []
        try:
            results = [_once(delay, argv) for _ in range(args.repeats)]
        finally:
            for b in burners:
                b.kill()
        lat = [r[0] for r in results if not r[3]]
        codes = sorted({r[1] for r in results})
        tb = any(r[2] for r in results)
        early = sum(r[3] for r in results)
        med = statistics.median(lat) if lat else float("nan")
        if load == "idle" and (not lat or max(lat) > 1.0 or codes != [130] or tb):
            within = False
        worst = max(lat, default=float("nan"))
        rows.append(f"| {phase} | {load} | {med:.2f} | {worst:.2f} | {codes} | {'yes' if tb else 'no'} | {early} |")
    load_avg = os.getloadavg()[0]
    text = "\n".join(
        [
            "# Ctrl-C latency per command",
            "",
            f"`python benchmarks/bench_interrupts.py --repeats {args.repeats}` — {datetime.now(timezone.utc):%Y-%m-%d %H:%M} "
            f"UTC, {platform.machine()}, {os.cpu_count()} cores, load average {load_avg:.2f} at the end; 'loaded' = two "
            "busy-looping processes on the 2 cores during the case.",
            "",
            *rows,
            "",
            f"Target (idle: exit 130, no traceback, <= 1 s): {'met' if within else 'NOT met'} in this run.",
            "",
        ]
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()

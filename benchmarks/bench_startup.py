"""Start-up cost: ``import pendulab``, ``pendulab --help`` and a CLI error on a bad option, against peers in the same run.

    python benchmarks/bench_startup.py [--repeats 15] [--out benchmarks/results/startup.md]

Target (issue 32): each <= 0.3 s on an idle machine. Every case is a fresh interpreter (wall time of the
whole process, ``subprocess``), the cases interleaved round by round so load drifts hit all alike;
medians of ``--repeats`` rounds. Peers measured in the same run: a bare interpreter, ``import numpy``
(pendulab's floor: every command needs it) and the eager import pendulab had before (its public names
forced: SciPy's integrate, CasADi, the ensemble engine), so the gain is a ratio, not a clock.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from tqdm import tqdm

OUT = Path(__file__).resolve().parent / "results" / "startup.md"
PY = sys.executable
CASES: dict[str, list[str]] = {
    "python -c pass (peer)": [PY, "-c", "pass"],
    "import numpy (peer: the floor)": [PY, "-c", "import numpy"],
    "import pendulab": [PY, "-c", "import pendulab"],
    "pendulab --help": [PY, "-m", "pendulab", "--help"],
    "pendulab simulate --bogus (error, exit 2)": [PY, "-m", "pendulab", "simulate", "--bogus"],
    "eager import (peer: before, names forced)": [PY, "-c", "import pendulab as p; p.simulate; p.ensemble; p.modes"],
}
TARGET_S = 0.3
MEASURED = ("import pendulab", "pendulab --help", "pendulab simulate --bogus (error, exit 2)")


def _once(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    times: dict[str, list[float]] = {k: [] for k in CASES}
    for cmd in CASES.values():  # warm the OS file cache and the byte-code caches once
        _once(cmd)
    for _ in tqdm(range(args.repeats), desc="start-up rounds", unit="round"):
        for label, cmd in CASES.items():
            times[label].append(_once(cmd))
    med = {k: statistics.median(v) for k, v in times.items()}
    floor = med["import numpy (peer: the floor)"]
    eager = med["eager import (peer: before, names forced)"]
    rows = ["| case | median [s] | min [s] | max [s] | / import numpy | / eager import |", "|---|---|---|---|---|---|"]
    for k, v in times.items():
        rows.append(f"| {k} | {med[k]:.3f} | {min(v):.3f} | {max(v):.3f} | {med[k] / floor:.2f} | {med[k] / eager:.2f} |")
    met = [k for k in MEASURED if med[k] <= TARGET_S]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    text = "\n".join(
        [
            "# Start-up cost",
            "",
            f"`python benchmarks/bench_startup.py --repeats {args.repeats}` — {datetime.now(timezone.utc):%Y-%m-%d %H:%M} "
            f"UTC, {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, load average "
            f"{load:.2f} at the end.",
            "",
            "Wall time of a fresh interpreter per case (medians of interleaved rounds).",
            "",
            *rows,
            "",
            f"Target <= {TARGET_S} s (idle machine): met by {len(met)} of {len(MEASURED)} ({', '.join(met) or 'none'}) "
            "in this run. "
            f"`pendulab --help` costs {med['pendulab --help'] / floor:.2f}x `import numpy` and "
            f"{med['pendulab --help'] / eager:.2f}x the former eager import.",
            "",
        ]
    )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()

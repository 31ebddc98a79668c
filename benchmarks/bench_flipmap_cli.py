"""The whole flip-map command against an earlier version of pendulab, in the same run.

    git worktree add /tmp/before <commit>
    python benchmarks/bench_flipmap_cli.py --before /tmp/before [--rounds 5] [--grid 400]

Each round runs ``python -m pendulab ensemble flipmap --model rigid --grid N --t-max 10`` in a fresh process for
three cases, interleaved so that all see the same machine load: the checkout given by ``--before`` (first on
``PYTHONPATH``), this checkout, and this checkout with SymPy hidden (a ``sitecustomize`` that sets
``sys.modules["sympy"] = None``, as in an environment where it is not installed: pendulab does not require it,
heyoka imports it when present). Prints every wall time and the medians.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from tqdm import tqdm

HERE = Path(__file__).resolve().parent.parent


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", type=Path, required=True, help="checkout of the earlier version (its repository root)")
    ap.add_argument("--rounds", type=int, default=5, help="interleaved rounds (medians), default 5")
    ap.add_argument("--grid", type=int, default=400, help="grid points per angle, default 400")
    args = ap.parse_args(argv)
    if args.rounds < 1 or args.grid < 2:
        ap.error("--rounds must be >= 1 and --grid >= 2")
    if not (args.before / "pendulab" / "__init__.py").is_file():
        ap.error(f"--before {args.before}: no pendulab package there")
    with tempfile.TemporaryDirectory() as tmp:
        hide = Path(tmp) / "hide_sympy"
        hide.mkdir()
        (hide / "sitecustomize.py").write_text('import sys\nsys.modules["sympy"] = None\n')
        cases = {
            f"before ({args.before})": str(args.before),
            "after": str(HERE),
            "after, SymPy hidden": f"{HERE}{os.pathsep}{hide}",
        }
        walls: dict[str, list[float]] = {name: [] for name in cases}
        with tqdm(total=args.rounds * len(cases), desc="flipmap CLI", unit="run", file=sys.stderr) as bar:
            for _ in range(args.rounds):
                for name, path in cases.items():
                    out = tempfile.mkdtemp(dir=tmp)
                    cmd = [sys.executable, "-m", "pendulab", "ensemble", "flipmap", "--model", "rigid"]
                    cmd += ["--grid", str(args.grid), "--t-max", "10", "--no-progress", "--out", out]
                    env = {**os.environ, "PYTHONPATH": path, "MPLBACKEND": "Agg"}
                    t0 = time.perf_counter()
                    # cwd outside both checkouts: `python -m` puts the working directory first on sys.path.
                    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tmp)
                    walls[name].append(time.perf_counter() - t0)
                    if proc.returncode:
                        raise SystemExit(f"{name}: the command failed ({proc.returncode}): {proc.stderr[-500:]}")
                    bar.update()
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    print(f"{args.grid} x {args.grid}, {args.rounds} interleaved rounds, load average at the end {load}")
    for name, values in walls.items():
        print(f"{name}: median {statistics.median(values):.2f} s ({', '.join(f'{v:.2f}' for v in values)})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Rebuild ``pendulab/identify/data/realaigym_a0.npz`` from DFKI's design A.0 records.

Reads RealAIGym's repository (github.com/dfki-ric-underactuated-lab/double_pendulum, BSD-3-Clause) at
commit 1e8544e from a local git clone or mirror (no work tree needed) and keeps, as float32, the nine
readable 2022-08-15 sys-id records whole (``trajectory_06`` ... ``_10`` are absent upstream) and the
first ``SECONDS`` of the three 2022-08-19 pendubot swing-up experiments.

Usage::

    python benchmarks/make_a0_archive.py REPO [SECONDS] [OUT]
"""

from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np

BASE = "data/experiment_records/design_A.0"
COMMIT = "1e8544e"
COLUMNS = ["time", "pos_meas1", "pos_meas2", "vel_meas1", "vel_meas2", "tau_meas1", "tau_meas2", "tau_con1", "tau_con2"]
FIT = {f"20220815-trajectory_{k:02d}": f"20220815/sys_id/trajectory_{k:02d}.csv" for k in (0, 1, 2, 3, 4, 5, 11, 12, 13)}
SWING = {
    "20220819-174435": "20220819/174435-pendubot_tvlqr_lqr/trajectory.csv",
    "20220819-174932": "20220819/174932-pendubot_tvlqr_lqr/trajectory.csv",
    "20220819-175617": "20220819/175617-pendubot_tvlqr_lqr_VIDEO/trajectory.csv",
}


def main() -> None:
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    repo = sys.argv[1]
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 20.0
    out = sys.argv[3] if len(sys.argv) > 3 else "pendulab/identify/data/realaigym_a0.npz"
    arrays = {"columns": np.array(COLUMNS)}
    for stamp, path in {**FIT, **SWING}.items():
        show = ["git", "-C", repo, "show", f"{COMMIT}:{BASE}/{path}"]
        text = subprocess.run(show, check=True, capture_output=True, text=True).stdout
        header = [h.strip() for h in text.splitlines()[0].split(",")]
        data = np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1)[:, [header.index(c) for c in COLUMNS]]
        if stamp in SWING:
            data = data[data[:, 0] <= seconds]
        arrays["r" + stamp.replace("-", "_")] = data.astype(np.float32)
        print(stamp, data.shape)
    np.savez_compressed(out, **arrays)
    print(out, os.path.getsize(out), "bytes")


if __name__ == "__main__":
    main()

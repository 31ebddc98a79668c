#!/usr/bin/env bash
# Set up RealAIGym's upstream package (dfki-ric-underactuated-lab/double_pendulum) in its own virtual environment
# for benchmarks/bench_upstream_entries.py. Never installs into pendulab's own (system) environment.
#
# The upstream repository is not on PyPI: it comes from a fetched snapshot (a git directory; the search tool's
# `fetch github:dfki-ric-underactuated-lab/double_pendulum` leaves one at
# /work/.mirror/dfki-ric-underactuated-lab+double_pendulum/repo). This script
#
#   1. clones it to a work tree (default /work/upstream_realai), checking out every blob the snapshot holds
#      (a snapshot may lack a few large files: system-identification records and old SAC histories, none
#      of which the ICRA 2025 entries load);
#   2. makes a Python 3.11 venv (default /work/venvs/realai) with only what the ICRA 2025 entries whose
#      weights ship upstream need: AR-EAPO (torch CPU, stable-baselines3 2.3.2, gymnasium, numba),
#      MC-PILCO (numpy, dill) and VIMPPI (jax[cpu]), plus upstream's model/filter modules (scipy, sympy, pyyaml, pandas,
#      matplotlib); upstream's setup.py pulls much more (drake, opencv, motor drivers, jax[cuda12]), so it
#      is installed with --no-deps;
#   3. installs pendulab itself editable into the same venv (so one process runs both);
#   4. makes a second venv (default /work/venvs/realai-acados, Python 3.12: acados' wheel is built for it) with
#      acados (benchmarks/setup_acados_env.sh's recipe), upstream's package (--no-deps) and the modules its
#      import chain needs, for the acados MPC entry's worker process (SKIP_ACADOS=1 skips it). The wheel's
#      acados_template is 0.2.x; bench_upstream_entries.py bridges the three API differences upstream's
#      AcadosMpc hits (solver_options.N_horizon -> dims.N, get_status, the split RTI timings).
#
# Usage:
#     bash benchmarks/setup_realai_env.sh [VENV_DIR] [UPSTREAM_WORKTREE]
#     SNAPSHOT=/path/to/repo.git PYTHON=python3.11 ACADOS_VENV=/work/venvs/realai-acados bash benchmarks/setup_realai_env.sh
#
# VIMPPI (written for JAX on a GPU) runs on JAX's CPU build, ~45 ms a call: not real time, ~10 min a 60 s episode.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
REPO_ROOT="$(cd "$HERE/.." && pwd)"
VENV="${1:-/work/venvs/realai}"
UPSTREAM="${2:-/work/upstream_realai}"
SNAPSHOT="${SNAPSHOT:-/work/.mirror/dfki-ric-underactuated-lab+double_pendulum/repo}"
PYTHON="${PYTHON:-python3.11}"

# 1. the upstream work tree
if [ ! -f "$UPSTREAM/src/python/setup.py" ]; then
    if [ ! -d "$SNAPSHOT" ]; then
        echo "setup_realai_env: no upstream snapshot at $SNAPSHOT (set SNAPSHOT=...)" >&2
        exit 1
    fi
    git clone -q --no-checkout "$SNAPSHOT" "$UPSTREAM"
    # check out only the blobs the snapshot holds (a plain checkout stops at the first missing one)
    git -C "$UPSTREAM" ls-tree -r HEAD | awk '{print $3" "$4}' > "$UPSTREAM/.blobs"
    cut -d' ' -f1 "$UPSTREAM/.blobs" | git -C "$UPSTREAM" cat-file --batch-check | awk '$2 == "missing" {print $1}' > "$UPSTREAM/.missing" || true
    grep -vF -f "$UPSTREAM/.missing" "$UPSTREAM/.blobs" | cut -d' ' -f2- > "$UPSTREAM/.present" || true
    git -C "$UPSTREAM" checkout HEAD --pathspec-from-file="$UPSTREAM/.present"
    echo "setup_realai_env: checked out $(wc -l < "$UPSTREAM/.present") files, $(wc -l < "$UPSTREAM/.missing") absent from the snapshot"
fi
git -C "$UPSTREAM" log --oneline -1

# 2. the venv
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
PIP=("$VENV/bin/python" -m pip install --quiet)
"${PIP[@]}" --upgrade pip setuptools wheel
# torch: the CPU build where a local CPU wheel exists (this machine's /opt/wheels); else PyPI's default build,
# which drags in ~5 GB of CUDA libraries (unused: everything runs on the CPU).
CPU_TORCH="$(ls /opt/wheels/torch-*+cpu-cp311-*.whl 2>/dev/null | sort -V | tail -1 || true)"
if [ -n "$CPU_TORCH" ] && ! "$VENV/bin/python" -c "import torch" >/dev/null 2>&1; then
    "${PIP[@]}" "$CPU_TORCH"
fi
"${PIP[@]}" "torch" "stable-baselines3==2.3.2" "gymnasium" "numba" "dill" "pyyaml" "pandas" "scipy" "sympy" \
    "matplotlib" "tqdm" "cloudpickle"
# VIMPPI: JAX's CPU build (upstream lists jax[cuda12]; no GPU here). 0.10.2 is what the recorded runs used.
"${PIP[@]}" "jax[cpu]==0.10.2"
"${PIP[@]}" --no-deps -e "$UPSTREAM/src/python"

# 3. pendulab (editable, with its own dependencies)
"${PIP[@]}" -e "$REPO_ROOT"

# 4. the acados MPC entry: acados' wheel is built for CPython 3.12 only, so upstream's AcadosMpc runs in a worker
#    process of a venv of its own (benchmarks/setup_acados_env.sh's recipe in ACADOS_VENV, plus upstream's package
#    and the few modules its import chain needs); bench_upstream_entries.py --acados-worker is that worker.
ACADOS_VENV="${ACADOS_VENV:-/work/venvs/realai-acados}"
if [ "${SKIP_ACADOS:-0}" != "1" ]; then
    bash "$HERE/setup_acados_env.sh" "$ACADOS_VENV"
    "$ACADOS_VENV/bin/python" -m pip install --quiet pyyaml pandas scipy sympy matplotlib
    "$ACADOS_VENV/bin/python" -m pip install --quiet --no-deps -e "$UPSTREAM/src/python"
fi

"$VENV/bin/python" - <<'EOF'
import torch, stable_baselines3, numba, jax, double_pendulum, pendulab
from double_pendulum.controller.AR_EAPO import NumbaJITController, AR_EAPOController  # noqa: F401
from double_pendulum.controller.mcpilco import mcpilco_controller  # noqa: F401
from double_pendulum.controller.vimppi.controller import MPPIController  # noqa: F401
print("setup_realai_env: torch", torch.__version__, "| sb3", stable_baselines3.__version__, "| numba", numba.__version__,
      "| jax", jax.__version__, "| double_pendulum", double_pendulum.__file__, "| pendulab", pendulab.__file__)
EOF

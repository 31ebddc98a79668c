#!/usr/bin/env bash
# Set up acados in its own virtual environment for benchmarks/bench_acados.py (not a pendulab dependency).
#
# acados comes from PyPI as `comma-deps-acados`: the wheel ships acados_template, the t_renderer
# binary, libacados, HPIPM, BLASFEO, qpOASES and a slim CasADi 3.7 built for CPython 3.12, so the venv
# must be a Python 3.12 one. It never goes into pendulab's environment (its CasADi would shadow
# pendulab's). The wheel lays acados out as
#
#   site-packages/acados/install/{bin/t_renderer, lib/libacados.so ..., include/...}
#   site-packages/acados/acados_template/
#
# so this script adds a .pth file that puts site-packages/acados on sys.path (acados_template imports as
# a top-level package) and writes `activate-acados.sh` with ACADOS_SOURCE_DIR (= .../acados/install:
# acados_template finds lib/, include/ and bin/t_renderer there), TERA_PATH, ACADOS_PYTHON_INTERFACE_PATH
# (the templates and acados_layout.json, which the wheel keeps beside install/) and LD_LIBRARY_PATH.
# benchmarks/acados_worker.py sets the same variables itself, so sourcing the file is only for use by hand.
#
# Usage:
#     bash benchmarks/setup_acados_env.sh [VENV_DIR]     # default /work/venvs/acados
#     PYTHON=python3.12 bash benchmarks/setup_acados_env.sh
set -euo pipefail

VENV="${1:-/work/venvs/acados}"
PYTHON="${PYTHON:-}"
VERSION="${ACADOS_WHEEL_VERSION:-0.2.2.post92}"

if [ -z "$PYTHON" ]; then
    # python3.12 on PATH, else a pyenv-installed 3.12 (a pyenv shim fails when 3.12 is not the selected version).
    for cand in python3.12 "$(pyenv root 2>/dev/null)"/versions/3.12*/bin/python3.12; do
        if "$cand" -c 'import sys; assert sys.version_info[:2] == (3, 12)' >/dev/null 2>&1; then
            PYTHON="$cand"
            break
        fi
    done
fi
if [ -z "$PYTHON" ]; then
    echo "setup_acados_env: no CPython 3.12 found (the wheel's CasADi is built for it); set PYTHON=..." >&2
    exit 1
fi
if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet "comma-deps-acados==$VERSION" numpy

SITE="$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
INSTALL="$SITE/acados/install"
echo "$SITE/acados" > "$SITE/acados_template_path.pth"
cat > "$VENV/activate-acados.sh" <<EOF
# source after $VENV/bin/activate
export ACADOS_SOURCE_DIR="$INSTALL"
export TERA_PATH="$INSTALL/bin/t_renderer"
export ACADOS_PYTHON_INTERFACE_PATH="$SITE/acados/acados_template"
export LD_LIBRARY_PATH="$INSTALL/lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
EOF

# Smoke test: the wheel's own check, then the imports the worker needs.
ACADOS_SOURCE_DIR="$INSTALL" TERA_PATH="$INSTALL/bin/t_renderer" LD_LIBRARY_PATH="$INSTALL/lib" "$VENV/bin/python" - <<'EOF'
import acados
acados.smoketest()
import casadi
import acados_template
print(f"acados venv ok: casadi {casadi.__version__}, acados_template at {acados_template.__file__}")
EOF
echo "ACADOS_SOURCE_DIR=$INSTALL"

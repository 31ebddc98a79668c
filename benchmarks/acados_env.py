"""Point ``acados_template`` at the ``comma-deps-acados`` wheel's install tree: shared by the acados workers.

Imported only inside the acados venv (``benchmarks/setup_acados_env.sh``, ``benchmarks/setup_realai_env.sh``), by
``acados_worker.py`` (``bench_acados.py``) and by ``bench_upstream_entries.py --acados-worker``; imports nothing of
pendulab.
"""

from __future__ import annotations

import os
import sys
import sysconfig
from pathlib import Path


def acados_env() -> None:
    """Set acados' environment (lib/, include/, bin/t_renderer, templates) and put the wheel's package on the path."""
    site = Path(sysconfig.get_paths()["purelib"]) / "acados"
    install = site / "install"
    os.environ.setdefault("ACADOS_SOURCE_DIR", str(install))
    os.environ.setdefault("TERA_PATH", str(install / "bin" / "t_renderer"))
    os.environ.setdefault("ACADOS_PYTHON_INTERFACE_PATH", str(site / "acados_template"))
    if str(site) not in sys.path:
        sys.path.insert(0, str(site))

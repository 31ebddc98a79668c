"""Ctrl-C at start-up lands in an import (5-25 s on a loaded machine): the CLI still ends with one line, exit 130.

Found (issue 31): Ctrl-C during the start-up imports of ``swingup``, ``score`` and ``scene check`` printed a
Python traceback and exited -2. A real SIGINT lands wherever the process is; here the interrupt is raised
deterministically *by* an import (a meta-path finder that raises ``KeyboardInterrupt`` when the named
module is imported), through the real console entry point in a fresh interpreter, at each stage: the
entry's own import of the CLI, the parser's command modules (CasADi), and the lazy imports inside a
running command (SciPy's integrators, the swing-up solver, heyoka).
"""

from __future__ import annotations

import subprocess
import sys

import pytest

DRIVER = """
import importlib.abc, sys
target = sys.argv[1]

class Interrupt(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target_module=None):
        if name == target:
            raise KeyboardInterrupt
        return None

sys.meta_path.insert(0, Interrupt())
sys.argv = ["pendulab", *sys.argv[2:]]
from pendulab._entry import run
run()
"""


@pytest.mark.parametrize(
    ("module", "argv"),
    [
        ("pendulab.cli", ["--help"]),
        ("casadi", ["modes", "--model", "rigid"]),
        (
            "pendulab.integrate.scipy_methods",
            ["simulate", "--model", "rigid", "--t-final", "1", "--method", "RK45", "--out", "x.csv"],
        ),
        ("pendulab.control.swingup.episode", ["swingup", "--task", "pendubot", "--no-gif", "--out", "run"]),
        ("heyoka", ["simulate", "--model", "rigid", "--t-final", "1", "--method", "taylor", "--out", "x.csv"]),
    ],
)
def test_an_interrupt_in_any_start_up_import_ends_cleanly(module, argv, tmp_path):
    if module == "heyoka":
        pytest.importorskip("heyoka", reason="the [taylor] extra")
    proc = subprocess.run(
        [sys.executable, "-c", DRIVER, module, *argv], capture_output=True, text=True, timeout=300, cwd=tmp_path
    )
    assert proc.returncode == 130, (proc.returncode, proc.stderr[-2000:])
    assert "pendulab: interrupted" in proc.stderr
    assert "Traceback" not in proc.stderr, proc.stderr[-2000:]

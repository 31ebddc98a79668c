"""Without an optional extra, the CLI says which extra to install in one line (exit 2), and what needs no extra runs.

Each case runs ``python -m pendulab`` in a subprocess in which the extra's modules cannot be imported
(``sys.modules[name] = None``, which is what a venv without the extra gives ``import`` and
``importlib.util.find_spec``). A real venv without extras was checked by hand (closing note of issue 20);
this test keeps the behaviour from regressing without a network install in the suite.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: The extras' top-level modules.
EXTRAS = {"taylor": ["heyoka"], "dask": ["dask", "distributed"], "gym": ["gymnasium"]}

RUN = """
import sys
for name in {blocked!r}:
    sys.modules[name] = None
from pendulab.cli import main
sys.exit(main({argv!r}))
"""

#: (id, blocked extra, CLI arguments with {out}, extra named in the message)
CASES = [
    ("simulate-taylor", "taylor", ["simulate", "--model", "rigid", "--t-final", "0.1", "--method", "taylor"], "taylor"),
    ("flipmap", "taylor", ["ensemble", "flipmap", "--grid", "3", "--t-max", "0.1", "--out", "{out}"], "taylor"),
    (
        "flipmap-scheduler",
        "dask",
        ["ensemble", "flipmap", "--grid", "3", "--t-max", "0.1", "--scheduler", "tcp://127.0.0.1:1", "--out", "{out}"],
        "dask",
    ),
    ("bench-ensemble-heyoka", "taylor", ["bench", "ensemble", "--grid", "3", "--t-max", "0.1", "--out", "{out}"], "taylor"),
    ("bench-ensemble-dask", "dask", ["bench", "ensemble", "--grid", "3", "--t-max", "0.1", "--out", "{out}"], "dask"),
]


def _run(blocked: list[str], argv: list[str]) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "MPLBACKEND": "Agg"}
    code = RUN.format(blocked=blocked, argv=argv)
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize(("blocked_extra", "args", "named"), [pytest.param(*c[1:], id=c[0]) for c in CASES])
def test_missing_extra_is_one_line_naming_it(blocked_extra, args, named, tmp_path):
    argv = [a.replace("{out}", str(tmp_path / "out")) for a in args]
    proc = _run(EXTRAS[blocked_extra], argv)
    assert proc.returncode == 2, f"exit {proc.returncode}\n{proc.stderr[-3000:]}"
    # Progress lines may come first; the error is one line, the last, and there is no traceback.
    errors = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert len(errors) == 1 and proc.stderr.strip().splitlines()[-1] == errors[0], proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr
    assert f"pendulab[{named}]" in errors[0], errors[0]
    assert proc.stdout == ""


def test_auto_method_runs_without_any_extra(tmp_path):
    """method='auto' never needs an extra: without heyoka it picks a compiled or CasADi method."""
    out = tmp_path / "run.csv"
    blocked = [m for mods in EXTRAS.values() for m in mods]
    proc = _run(blocked, ["simulate", "--model", "rigid", "--set", "theta1=1", "--t-final", "1", "--out", str(out), "--json"])
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "taylor" not in proc.stdout.split('"method"')[1].split(",")[0]
    # The run is real: a pendulum released at 1 rad stays on its energy level (rtol 1e-8 default: drift << 1e-4 J).
    rows = out.read_text().splitlines()
    assert len(rows) > 50


def test_gym_without_gymnasium_names_the_extra():
    code = (
        "import sys\nsys.modules['gymnasium'] = None\n"
        "try:\n    import pendulab.gym\nexcept ImportError as exc:\n    print(type(exc).__name__, exc)\n    sys.exit(3)\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 3, proc.stderr[-3000:]  # an ImportError (subclass), caught as such
    assert proc.stdout.startswith("MissingExtraError") and "pendulab[gym]" in proc.stdout, proc.stdout

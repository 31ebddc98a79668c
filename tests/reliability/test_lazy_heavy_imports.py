"""A command or lookup that does not use SciPy's integrators or optimisers (or SymPy) never imports them.

Found (issue 32): the flip-map command imported ``scipy.integrate`` (the method registry imported every
family's module to validate a method name) and ``scipy.optimize`` (the energy threshold), 0.8 s and 0.5 s
of a command measured against 2 s. The class: looking a method up, building an ensemble, and the
flip-map command, each in a fresh interpreter; the SciPy methods themselves still work afterwards. The
console entry also marks SymPy absent (heyoka imports it when installed: 0.33-0.5 s, for nothing a command uses);
where SymPy is not installed that check holds trivially.
"""

from __future__ import annotations

import subprocess
import sys

import pytest

HEAVY = ("scipy.integrate", "scipy.optimize")

LOOKUP = """
import sys
import pendulab as pl
spec = pl.METHODS["RK45"]
from pendulab.ensemble import engine  # noqa: F401
print(sorted(m for m in {heavy!r} if m in sys.modules))
x0 = [0.5, 0.0, 0.0, 0.0]
a = pl.simulate(pl.rigid(), x0, 0.5, dt=0.1, method=spec.name, rtol=1e-10, atol=1e-10)
b = pl.simulate(pl.rigid(), x0, 0.5, dt=0.1, method="cvodes", rtol=1e-10, atol=1e-10)
print(float(abs(a.x - b.x).max()))
"""

FLIPMAP = """
import sys
sys.argv = ["pendulab", "ensemble", "flipmap", "--grid", "8", "--t-max", "1", "--no-progress", "--out", "out"]
from pendulab._entry import run
try:
    run()
except SystemExit as exc:
    assert exc.code in (0, None), exc.code
print(sorted(m for m in {heavy!r} if sys.modules.get(m) is not None))
"""


def _last_lines(code: str, cwd) -> list[str]:
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=cwd)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout.strip().splitlines()


def test_looking_a_method_up_imports_no_scipy_integrator_and_the_method_still_runs(tmp_path):
    imported, gap = _last_lines(LOOKUP.format(heavy=HEAVY), tmp_path)[-2:]
    assert imported == "[]"
    assert float(gap) < 1e-7  # SciPy's RK45 against CVODES, both at 1e-10: the SciPy path is intact


def test_the_flip_map_command_imports_no_scipy_integrator_or_optimiser(tmp_path):
    pytest.importorskip("heyoka", reason="the [taylor] extra")
    assert _last_lines(FLIPMAP.format(heavy=(*HEAVY, "sympy")), tmp_path)[-1] == "[]"
    assert (tmp_path / "out" / "flipmap.npz").is_file() and (tmp_path / "out" / "flipmap.png").is_file()


EVERY_MODULE = """
import pkgutil, types
import pendulab
for info in pkgutil.walk_packages(pendulab.__path__, "pendulab."):
    name = info.name
    if name.endswith("__main__"):
        continue
    scope = {}
    try:
        exec(f"import {name} as _m", scope)
    except Exception as exc:
        print("FAIL", name, type(exc).__name__, exc)
        continue
    parent, _, last = name.rpartition(".")
    if not isinstance(scope["_m"], types.ModuleType) or scope["_m"].__name__ != name:
        print("PUBLIC", name, scope["_m"] is getattr(__import__(parent, fromlist=["_"]), last))
print("DONE")
"""


def test_every_module_imports_with_the_import_as_statement():
    """``import pendulab.X.Y as m`` works for every module, in a fresh interpreter where nothing is loaded yet.

    Found: ``import pendulab.ensemble.flipmap as fm`` raised ``ImportError: cannot import name 'flipmap' from
    'ensemble'`` -- the statement fetches ``pendulab.ensemble``, which is the public function of that name, and the
    import system's fallback looked for the submodule under the function's ``__name__``. Where a public name
    shadows its own module (``pendulab.integrate.simulate``), the statement yields that public object, as documented
    in :mod:`pendulab._lazy`: never an error, never another object.
    """
    lines = _last_lines(EVERY_MODULE, None)
    assert lines[-1] == "DONE"
    assert [line for line in lines if line.startswith("FAIL")] == []
    public = [line.split() for line in lines if line.startswith("PUBLIC")]
    assert all(same == "True" for _, _, same in public), public
    # The public names that shadow their own module (a new one is a decision, reviewed here).
    assert {name for _, name, _ in public} == {
        "pendulab.ensemble", "pendulab.fmu.export", "pendulab.fmu.validate", "pendulab.integrate.simulate",
        "pendulab.integrate.taylor.translate",
    }  # fmt: skip

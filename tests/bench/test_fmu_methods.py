"""The FMU's embedded solvers (through fmpy) run in the work-precision benchmark and reach sensible errors."""

import math

import numpy as np
import pytest

from pendulab.bench.cases import CASES
from pendulab.bench.fmu_methods import fmu_bench_runner
from pendulab.bench.reference import load_reference
from pendulab.bench.workprecision import BENCH_METHODS, run_work_precision
from pendulab.integrate import SimulationError

pytestmark = pytest.mark.needs_cc  # the FMU is exported (compiled) on first use


def test_fmu_methods_are_registered_tolerance_sweeps():
    for name in ("fmu-dopri5", "fmu-rodas4"):
        assert BENCH_METHODS[name].sweep == "tol" and BENCH_METHODS[name].family == "fmu"


def test_fmu_solvers_quick_rigid_chaotic_2s():
    rows = run_work_precision(["rigid_chaotic_2s"], ["fmu-dopri5", "fmu-rodas4"], quick=True, repeats=1)
    by = {(r.method, r.setting): r for r in rows}
    assert set(by) == {(m, t) for m in ("fmu-dopri5", "fmu-rodas4") for t in (1e-4, 1e-7)}
    assert all(r.status == "ok" and r.wall_median > 0 for r in rows)
    for m in ("fmu-dopri5", "fmu-rodas4"):
        # 2 s of chaos amplifies local errors ~1e2-1e3: tolerance 1e-7 must still land below 1e-4 (measured ~1e-5).
        assert by[(m, 1e-7)].grid_error < 1e-4
        # Tightening the tolerance 1000x must pay off by at least 10x (4th/5th order methods).
        assert by[(m, 1e-7)].grid_error < 0.1 * by[(m, 1e-4)].grid_error
        # Undamped: the energy drift is the solver's, well below the 1e-4 grid error bound.
        assert by[(m, 1e-7)].energy_drift < 1e-4


def test_fmu_rodas4_steps_over_stiff_springs_after_quasi_static_start():
    case = CASES["elastic_stiff_1e6_qs"]
    ref = load_reference(case)
    traj = fmu_bench_runner(1)(case.model, case.x0, case.t_final, case.dt, 1e-7)
    assert traj.method == "fmu:rodas4" and traj.x.shape == ref.x.shape
    # L-stable rodas4 at 1e-7 on k = 1e6 N/m: measured 3.6e-7 over the grid; 1e-5 leaves room for platform noise.
    assert np.max(np.abs(traj.x - ref.x)) < 1e-5
    np.testing.assert_allclose(traj.t, ref.t, rtol=0, atol=1e-12)  # one doStep per output point of the case grid


def test_fmu_bench_runner_rejects_unknown_solver_and_reports_failures():
    with pytest.raises(ValueError, match="solver must be one of"):
        fmu_bench_runner(2)
    case = CASES["rigid_chaotic_2s"]
    # A NaN start value is refused by the FMU (Error status): reported as a SimulationError naming the method.
    x0 = case.x0.copy()
    x0[0] = math.nan
    with pytest.raises(SimulationError, match="fmu:dopri5"):
        fmu_bench_runner(0)(case.model, x0, case.t_final, case.dt, 1e-6)

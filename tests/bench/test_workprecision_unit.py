"""Work-precision bookkeeping: fastest-method table, method registry, CSV round trip."""

import math

import pytest

from pendulab.bench.workprecision import (
    BENCH_METHODS,
    BenchMethod,
    Row,
    fastest_table,
    merge_rows,
    read_csv,
    write_csv,
)


def _row(method, err, wall, setting=1e-6):
    return Row("c", method, "tol", setting, "ok", grid_error=err, wall_median=wall)


def test_fastest_table_picks_cheapest_run_reaching_each_level():
    rows = [_row("A", 1e-3, 0.01), _row("A", 1e-7, 1.0), _row("B", 1e-5, 0.1), _row("B", 1e-9, 0.5)]
    rows.append(Row("c", "C", "tol", 1e-3, "failed"))
    t = {e["level"]: e for e in fastest_table(rows, "c", levels=(1e-2, 1e-4, 1e-6, 1e-8, 1e-10))}
    assert t[1e-2]["method"] == "A" and t[1e-2]["runner_up"] == "B" and t[1e-2]["ratio"] == pytest.approx(10.0)
    assert t[1e-4]["method"] == "B" and t[1e-4]["runner_up"] == "A"
    assert t[1e-6]["method"] == "B" and t[1e-6]["wall_median"] == 0.5  # B's 0.5 s beats A's 1 s
    assert t[1e-10]["method"] is None


def test_bench_methods_come_from_the_integrate_registry_and_reject_bad_sweeps():
    def run(*_args):
        raise NotImplementedError

    from pendulab.integrate import METHODS

    native = [m for m in BENCH_METHODS.values() if m.family != "fmu"]
    assert native and all(m.name in METHODS for m in native)
    # The sweep kind follows the registry: fixed-step methods sweep the step, the others the tolerance.
    assert all((m.sweep == "step") == METHODS[m.name].fixed_step for m in native)
    with pytest.raises(ValueError, match="sweep must be"):
        BenchMethod("fmu-x", "order", (1.0,), (1.0,), run)
    with pytest.raises(ValueError, match="non-empty"):
        BenchMethod("fmu-x", "tol", (), (1.0,), run)


def test_csv_round_trip(tmp_path):
    rows = [_row("A", 1.5e-7, 0.25), Row("c", "B", "step", 0.01, "unstable", message="state blew up")]
    back = read_csv(write_csv(rows, tmp_path / "r.csv"))
    assert back[0].grid_error == pytest.approx(1.5e-7) and back[0].wall_median == pytest.approx(0.25)
    assert back[1].status == "unstable" and math.isnan(back[1].grid_error)


def test_merge_rows_replaces_only_remeasured_case_method_pairs():
    old = [
        Row("elastic_soft", "DOP853", "tol", 1e-3, "ok", grid_error=1.0),
        Row("rigid_regular", "DOP853", "tol", 1e-3, "ok", grid_error=2.0),
        Row("rigid_regular", "rk4", "step", 1e-2, "ok", grid_error=3.0),
    ]
    new = [Row("rigid_regular", "DOP853", "tol", 1e-5, "ok", grid_error=4.0)]
    merged = merge_rows(old, new)
    # The old DOP853 sweep of rigid_regular is replaced as a whole; other pairs stay; CASES / BENCH_METHODS order.
    assert [(r.case, r.method, r.grid_error) for r in merged] == [
        ("rigid_regular", "DOP853", 4.0),
        ("rigid_regular", "rk4", 3.0),
        ("elastic_soft", "DOP853", 1.0),
    ]

"""The bench commands run end to end in quick mode and write consistent results."""

import csv

import numpy as np
import pytest

from pendulab.bench.cases import CASES
from pendulab.bench.reference import load_reference
from pendulab.bench.workprecision import read_csv
from pendulab.cli import main


def test_work_precision_quick(tmp_path, capsys):
    rc = main(
        [
            "bench",
            "work-precision",
            "--quick",
            "--cases",
            "rigid_chaotic_2s",
            "--methods",
            "DOP853",
            "rk4",
            "--repeats",
            "1",
            "--out",
            str(tmp_path),
        ]
    )
    assert rc == 0
    rows = {(r.method, r.setting): r for r in read_csv(tmp_path / "work_precision.csv")}
    assert all(r.status == "ok" for r in rows.values())
    # Tighter tolerance / smaller step must reach a smaller achieved error (chaos amplifies but 2 s is short).
    assert rows[("DOP853", 1e-7)].grid_error < rows[("DOP853", 1e-4)].grid_error
    assert rows[("rk4", 2e-3)].grid_error < 1e-2 * rows[("rk4", 1e-2)].grid_error  # order 4: (5x)^4 = 625x
    for metric in ("grid_error", "final_error", "energy_drift"):
        assert (tmp_path / f"work_precision_{metric}.png").stat().st_size > 10_000
    assert "wrote" in capsys.readouterr().out


def test_work_precision_rejects_unknown_case(capsys):
    assert main(["bench", "work-precision", "--cases", "nope", "--quick"]) == 2
    assert "unknown case" in capsys.readouterr().err


def test_stability_quick(tmp_path):
    assert main(["bench", "stability", "--quick", "--out", str(tmp_path)]) == 0
    with (tmp_path / "rk4_limit.csv").open() as fh:
        limits = list(csv.DictReader(fh))
    # The 5 % criterion, as recorded by the command.
    assert limits and all(abs(float(r["relative_difference"])) < 0.05 for r in limits)
    with (tmp_path / "stability_map.csv").open() as fh:
        cells = list(csv.DictReader(fh))
    # Forward Euler never reaches "stable and accurate" at k = 1e6; RK4 beyond h w = 2.83 is unstable.
    assert not any(c["method"] == "forward-euler" and float(c["k"]) == 1e6 and c["class"] == "stable-accurate" for c in cells)
    assert all(c["class"] == "unstable" for c in cells if c["method"] == "rk4" and float(c["h_omega_max"]) > 2.9)
    with (tmp_path / "step_counts.csv").open() as fh:
        steps = {(r["method"], r["start"], float(r["k"])): int(r["steps"]) for r in csv.DictReader(fh)}
    # Explicit RK45 pays for stiffness, L-stable Radau after a quasi-static start much less.
    rk_growth = steps[("RK45", "quasi-static", 1e4)] / steps[("RK45", "quasi-static", 1e2)]
    radau_growth = steps[("Radau", "quasi-static", 1e4)] / steps[("Radau", "quasi-static", 1e2)]
    assert rk_growth > 2 * radau_growth


@pytest.mark.parametrize("name", ["rigid_chaotic_2s", "elastic_stiff_1e4_qs"])
def test_stored_reference_agrees_with_independent_method(name):
    from pendulab import simulate

    case = CASES[name]
    ref = load_reference(case)
    x = simulate(case.model, case.x0, case.t_final, case.dt, "cvodes-adams", 1e-12, 1e-12).x
    diff = np.max(np.abs(x - ref.x))
    # CVODES Adams at 1e-12 (local) with <= 1e3 error growth over the horizon: within 1e-8;
    # a stale or wrong reference would be off by orders of magnitude more.
    assert diff < 1e-8, diff
    assert ref.accuracy < 1e-8


def test_rigid_reference_self_consistent_to_stated_accuracy():
    from pendulab.bench.reference import gbs_mp

    case = CASES["rigid_chaotic_2s"]
    ref = load_reference(case)
    X, _ = gbs_mp(case.model, case.x0, 0.2, case.dt, substeps=2)
    # Recomputing the 32-digit GBS over the first 0.2 s reproduces the stored solution to its stated accuracy.
    assert np.max(np.abs(X - ref.x[: X.shape[0]])) <= ref.accuracy


def test_references_json_is_one_object_on_stdout(tmp_path, monkeypatch, capsys):
    import json

    from pendulab.bench import reference

    stored = load_reference(CASES["rigid_chaotic_2s"])
    # The 32-digit recomputation takes minutes: reuse the stored reference, the command's output is under test.
    monkeypatch.setattr(reference, "compute_reference", lambda case, progress=None: stored)
    args = ["bench", "references", "--cases", "rigid_chaotic_2s", "--out", str(tmp_path), "--json"]
    assert main(args) == 0
    summary = json.loads(capsys.readouterr().out)
    [entry] = summary["references"]
    assert entry["case"] == "rigid_chaotic_2s" and entry["accuracy"] == stored.accuracy
    assert (tmp_path / entry["file"].split("/")[-1]).exists()

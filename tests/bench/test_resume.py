"""Long studies keep finished work: a journal per point, --resume, failures recorded, outputs where a user expects."""

import json
from dataclasses import asdict

import numpy as np
import pytest

from pendulab.bench import stability as st
from pendulab.bench import workprecision as wp
from pendulab.bench.journal import Journal
from pendulab.cli import main

CASE, METHODS = "rigid_chaotic_2s", ["DOP853", "rk4"]
# Deterministic columns of a row (timings differ between runs by nature).
_STABLE = ("case", "method", "sweep", "setting", "status", "final_error", "grid_error", "energy_drift", "n_steps", "message")


def _table(rows):
    return [tuple(asdict(r)[k] for k in _STABLE) for r in rows]


def _run(**kw):
    return wp.run_work_precision([CASE], METHODS, quick=True, repeats=1, **kw)


def _counting_measure(monkeypatch, fail_on=None, exc=KeyboardInterrupt):
    """Wrap _measure: record each measured (method, setting); raise ``exc`` on call number ``fail_on`` (an interrupt once)."""
    calls = []
    real = wp._measure
    armed = [fail_on is not None]

    def measure(method, case, model, x0, ref, setting, repeats):
        calls.append((method.name, setting))
        if armed[0] and len(calls) == fail_on:
            armed[0] = exc is not KeyboardInterrupt  # an interrupt happens once; an error on every run
            raise exc
        return real(method, case, model, x0, ref, setting, repeats)

    monkeypatch.setattr(wp, "_measure", measure)
    return calls


def test_work_precision_interrupted_then_resumed_equals_uninterrupted(tmp_path, monkeypatch):
    journal = tmp_path / "journal.json"
    calls = _counting_measure(monkeypatch, fail_on=2)
    with pytest.raises(KeyboardInterrupt):
        _run(journal=journal)
    first = calls[0]
    # The first point was recorded before the interrupt, the interrupted one was not.
    assert len(Journal(journal, "work-precision", {"quick": True, "repeats": 1, "slow_run_s": 5.0}, resume=True)) == 1

    calls.clear()
    resumed = _run(journal=journal, resume=True)
    assert first not in calls  # the finished point is not recomputed
    assert len(calls) == len(resumed) - 1

    monkeypatch.undo()
    fresh = _run(journal=tmp_path / "fresh.json")
    assert _table(resumed) == _table(fresh)


def test_work_precision_failing_point_is_recorded_and_study_goes_on(tmp_path, monkeypatch):
    _counting_measure(monkeypatch, fail_on=1, exc=RuntimeError("Unknown option: boom"))
    rows = _run(journal=tmp_path / "j.json")
    assert rows[0].status == "failed" and rows[0].message == "RuntimeError: Unknown option: boom"
    assert all(r.status == "ok" for r in rows[1:])  # the others still ran
    # A resumed run keeps the recorded failure instead of retrying it.
    calls = _counting_measure(monkeypatch)
    again = _run(journal=tmp_path / "j.json", resume=True)
    assert calls == [] and again[0].status == "failed"


def test_resume_with_other_settings_is_an_error(tmp_path):
    journal = tmp_path / "j.json"
    wp.run_work_precision([CASE], ["rk4"], quick=True, repeats=1, journal=journal)
    with pytest.raises(ValueError, match="repeats"):
        wp.run_work_precision([CASE], ["rk4"], quick=True, repeats=2, journal=journal, resume=True)


def test_cli_interrupt_then_resume_json(tmp_path, monkeypatch, capsys):
    args = [
        "bench",
        "work-precision",
        "--quick",
        "--cases",
        CASE,
        "--methods",
        *METHODS,
        "--repeats",
        "1",
        "--out",
        str(tmp_path),
    ]
    _counting_measure(monkeypatch, fail_on=3)
    assert main(args) == 130
    assert (tmp_path / "work_precision_journal.json").exists()
    assert not (tmp_path / "work_precision.csv").exists()
    assert "--resume" in capsys.readouterr().err  # the interrupted command says how to continue
    monkeypatch.undo()
    assert main([*args, "--resume", "--json", "--no-progress"]) == 0
    out = capsys.readouterr().out
    summary = json.loads(out)  # nothing but one JSON object on stdout
    assert summary["resumed_points"] == 2
    assert summary["points"] == 4 and summary["status"] == {"ok": 4}
    assert len(wp.read_csv(tmp_path / "work_precision.csv")) == 4


def test_cli_default_outputs_go_to_pendulab_out(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert (
        main(["bench", "work-precision", "--quick", "--cases", CASE, "--methods", "rk4", "--repeats", "1", "--no-progress"]) == 0
    )
    assert (tmp_path / "pendulab-out" / "bench-work-precision" / "work_precision.csv").exists()
    assert not (tmp_path / "docs").exists()
    assert "wrote pendulab-out/bench-work-precision/work_precision.csv" in capsys.readouterr().out


def _stable_result(res):
    return (
        {m: v.tolist() for m, v in res.maps.items()},
        {m: v.tolist() for m, v in res.errors.items()},
        res.blowup,
        res.step_counts,
        {k: (t.tolist(), dE.tolist()) for k, (t, dE) in res.energy.items()},
    )


def test_stability_interrupted_then_resumed_equals_uninterrupted(tmp_path, monkeypatch):
    journal = tmp_path / "stability.json"
    calls = []
    real = st.classify

    def classify(model, method, n_steps, ref_positions):
        calls.append((model.params.k1, method, n_steps))
        if len(calls) == 2 and not monkeypatch_state["resumed"]:
            raise KeyboardInterrupt
        return real(model, method, n_steps, ref_positions)

    monkeypatch_state = {"resumed": False}
    monkeypatch.setattr(st, "classify", classify)
    with pytest.raises(KeyboardInterrupt):
        st.run_stability(quick=True, journal=journal)
    first = calls[0]
    calls.clear()
    monkeypatch_state["resumed"] = True
    resumed = st.run_stability(quick=True, journal=journal, resume=True)
    assert first not in calls  # the finished map cell is not recomputed
    monkeypatch.undo()
    fresh = st.run_stability(quick=True)
    assert _stable_result(resumed) == _stable_result(fresh)
    assert resumed.failures == []


def test_stability_failing_unit_is_recorded_and_study_goes_on(tmp_path, monkeypatch, capsys):
    real = st._step_count

    def step_count(model, method, x0, tol):
        if method == "Radau":
            raise RuntimeError("Radau failed for this test")
        return real(model, method, x0, tol)

    monkeypatch.setattr(st, "_step_count", step_count)
    assert main(["bench", "stability", "--quick", "--out", str(tmp_path), "--json", "--no-progress"]) == 0
    summary = json.loads(capsys.readouterr().out)
    failed = {f["unit"] for f in summary["failures"]}
    assert failed == {f"steps|Radau|k={k!r}|{s}" for k in (1e2, 1e4) for s in ("quasi-static", "rest-length")}
    assert all("RuntimeError: Radau failed" in f["reason"] for f in summary["failures"])
    # The other step counts and studies completed.
    assert {r["method"] for r in summary["step_counts"]} == {"RK45"}
    assert len(summary["rk4_blowup"]) == 1 and len(summary["energy_change_J"]) == 4


def test_stability_prints_no_json_unasked(tmp_path, capsys):
    assert main(["bench", "stability", "--quick", "--out", str(tmp_path), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "{" not in out and "RK4 blow-up step" in out
    # A failed map cell (class FAILED) would be drawn blank; here every cell has a class.
    cells = np.loadtxt(tmp_path / "stability_map.csv", delimiter=",", skiprows=1, usecols=1)
    assert cells.size == 3 * 2 * 3  # 3 methods x 2 stiffnesses x 3 steps in the quick map


def test_merge_and_resume_together_is_an_error(tmp_path, capsys):
    assert main(["bench", "work-precision", "--quick", "--merge", "--resume", "--out", str(tmp_path)]) == 2
    assert "--merge and --resume" in capsys.readouterr().err

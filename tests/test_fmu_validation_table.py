"""`fmu validate`'s table says what each row ran: the FMU's parameters and start, or each scene as written."""

from __future__ import annotations

from pathlib import Path

from pendulab.fmu.validation_report import ValidationReport, ValidationRow


def _report(settings: str) -> ValidationReport:
    rows = [ValidationRow("rigid_chaotic_forced", "CS-dopri5", s, 1e-9, 1e-6) for s in ("theta1", "theta2")]
    params, start = ({"m2": 2.5}, {"theta1": 0.0, "theta2": 0.0, "omega1": 0.0, "omega2": 0.0}) if settings == "fmu" else ({}, {})
    return ValidationReport(Path("p.fmu"), "rigid", [], rows, settings=settings, params=params, start=start)


def test_rows_at_the_fmu_start_are_named_by_the_input_they_borrow():
    table = _report("fmu").table()
    assert "m2=2.5" in table and "theta1=0" in table  # the values that ran, not the scene's
    assert "NOT its parameters or initial state" in table
    head = next(line for line in table.splitlines() if line.endswith("result"))
    assert head.startswith("input of scene")  # the row is the scene's forcing, not the scene
    assert table.rstrip().endswith("overall: PASS")


def test_rows_of_named_scenes_say_they_ran_as_written():
    table = _report("scenes").table()
    assert "each scene as written" in table and "NOT" not in table
    assert next(line for line in table.splitlines() if line.endswith("result")).startswith("scene ")

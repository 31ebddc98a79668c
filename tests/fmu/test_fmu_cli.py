"""`pendulab fmu export|validate` from the command line."""

from __future__ import annotations

import zipfile

from pendulab.cli import main


def test_cli_export_sets_parameters_and_initial_state(tmp_path, capsys):
    out = tmp_path / "e.fmu"
    rc = main(
        [
            "fmu",
            "export",
            "--model",
            "rigid",
            "--set",
            "m2=2.5",
            "--initial",
            "theta1=0.3",
            "--fmi-version",
            "3",
            "--out",
            str(out),
            "--no-timestamp",
        ]
    )
    assert rc == 0 and "wrote" in capsys.readouterr().out
    md = zipfile.ZipFile(out).read("modelDescription.xml").decode()
    assert 'name="m2"' in md and 'start="2.5"' in md and 'start="0.3"' in md


def test_cli_validate_passes_and_writes_plot(fmu_builds, tmp_path, capsys):
    rc = main(["fmu", "validate", str(fmu_builds[("rigid", 2)].path), "--scene", "rigid_chaotic_forced", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0, out
    assert "overall: PASS" in out and "no problem" in out
    assert (tmp_path / "rigid2_validation.png").stat().st_size > 10_000


def test_cli_bad_input_exits_2_with_one_line(fmu_builds, tmp_path, capsys):
    assert main(["fmu", "export", "--model", "rigid", "--set", "m1", "--out", str(tmp_path / "x.fmu")]) == 2
    assert "--set = 'm1': not NAME=VALUE" in capsys.readouterr().err  # one parser of NAME=VALUE for every command
    assert main(["fmu", "export", "--model", "rigid", "--init", "theta1=nan", "--out", str(tmp_path / "x.fmu")]) == 2
    assert "--init = 'theta1=nan': theta1: 'nan' is not a finite number" in capsys.readouterr().err
    assert main(["fmu", "validate", str(fmu_builds[("rigid", 2)].path), "--scene", "elastic_soft_forced"]) == 2
    assert "not for the rigid model" in capsys.readouterr().err
    assert main(["fmu", "validate", str(tmp_path / "missing.fmu")]) == 2


def test_cli_validate_exits_1_on_fail(fmu_builds, monkeypatch, capsys):
    import dataclasses
    import importlib

    v = importlib.import_module("pendulab.fmu.validate")  # the module (the package exports the function)

    # an impossible bound (1e-15, below the solvers' 1e-10 tolerance) must turn into FAIL and exit status 1
    strict = tuple(dataclasses.replace(s, bound=1e-15) for s in v.SCENES)
    monkeypatch.setattr(v, "SCENES", strict)
    assert main(["fmu", "validate", str(fmu_builds[("rigid", 3)].path), "--scene", "rigid_chaotic_forced"]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "overall: FAIL" in out


def test_validate_checks_the_fmu_at_its_own_parameters_and_start(tmp_path, capsys, monkeypatch):
    """Issue 20: an FMU exported with --set/--initial was validated at the scene's parameters and start."""
    import importlib
    import json

    out = tmp_path / "own.fmu"
    args = ["fmu", "export", "--model", "rigid", "--set", "m2=2.5", "--set", "b1=0.1", "--initial", "theta1=1.0"]
    assert main([*args, "--out", str(out), "--no-timestamp", "--json"]) == 0
    exported = json.loads(capsys.readouterr().out)
    assert exported["params"]["m2"] == 2.5 and exported["start"]["theta1"] == 1.0 and exported["fmu"] == str(out)

    v = importlib.import_module("pendulab.fmu.validate")
    seen = []
    run_fmu = v._run_fmu

    def spy(unzipdir, md, scene, *rest):
        seen.append((scene.scene.model.params.m2, scene.scene.model.params.b1, float(scene.scene.x0[0])))
        return run_fmu(unzipdir, md, scene, *rest)

    monkeypatch.setattr(v, "_run_fmu", spy)
    assert main(["fmu", "validate", str(out), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["passed"] and report["settings"] == "fmu"
    assert report["params"]["m2"] == 2.5 and report["params"]["b1"] == 0.1 and report["start"]["theta1"] == 1.0
    # Every FMU run (and so its reference, from the same scene object) used the FMU's own values, not the scenes' 1 kg / 0.8 rad.
    assert seen and set(seen) == {(2.5, 0.1, 1.0)}

    seen.clear()
    assert main(["fmu", "validate", str(out), "--scene", "rigid_forced", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["settings"] == "scenes" and report["params"] == {}
    assert set(seen) == {(1.0, 0.0, 0.8)}  # on request: the scene's own parameters and start

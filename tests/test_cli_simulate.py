"""``pendulab simulate``: files, --set, summaries, and one-line errors on bad input."""

import csv
import json

import numpy as np
import pytest

import pendulab as pl
from pendulab.cli import main
from pendulab.scene import load_scene


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def test_rigid_csv_columns_set_and_energy(tmp_path, capsys):
    out = tmp_path / "traj.csv"
    args = ["simulate", "--model", "rigid", "--set", "theta1=2", "--set", "theta2=2", "--set", "m2=0.5"]
    args += ["--t-final", "2", "--dt", "0.02", "--method", "cvodes-adams", "--rtol", "1e-11", "--atol", "1e-11"]
    assert main([*args, "--out", str(out)]) == 0
    header, data = read_csv(out)
    model = pl.rigid(m2=0.5)
    assert header == ["t", *model.state_names, *model.input_names, *model.output_names]
    assert data.shape == (101, len(header)) and data[-1, 0] == 2.0
    x = data[:, 1 : 1 + model.nx]
    # --set reached the initial state, and the parameter: the energy column is that of m2 = 0.5 kg.
    np.testing.assert_array_equal(x[0], [2.0, 2.0, 0.0, 0.0])
    energy = data[:, header.index("energy")]
    # Same CasADi function on the values printed with repr(): equal to round-off.
    np.testing.assert_allclose(energy, model.energy(x), rtol=0, atol=1e-12)
    assert abs(energy[0] - pl.rigid().energy(x[0])) > 1.0  # m2 = 1 kg would give a different energy
    # Chaotic start, undamped: energy conserved; CVODES Adams at 1e-11 keeps it to ~1e-9 relative over 2 s.
    assert np.max(np.abs(energy - energy[0])) < 1e-8 * abs(energy[0])
    table = capsys.readouterr().out
    assert "energy drift [J]" in table and "cvodes-adams" in table


def test_scene_set_npz_json(tmp_path, capsys):
    out = tmp_path / "traj.npz"
    args = ["simulate", "--scene", "elastic_soft", "--set", "k1=800", "--t-final", "0.5", "--json", "--out", str(out)]
    assert main(args) == 0
    summary = json.loads(capsys.readouterr().out)
    data = np.load(out)
    x = data["x"]
    model = pl.elastic(k1=800.0, k2=100.0)
    # r1 is not stated in the scene: it starts at the static hanging length of the NEW stiffness.
    assert x[0, 2] == pytest.approx(1.0 + 2 * 9.81 / 800.0, abs=1e-15)
    assert summary["params"]["k1"] == 800.0 and summary["model"] == "elastic"
    e = model.energy(x)
    assert summary["energy_initial_J"] == pytest.approx(e[0], abs=1e-12)
    # The summary's drift is the CSV's: same samples, same definition.
    assert summary["energy_drift_J"] == pytest.approx(np.max(np.abs(e - e[0])), rel=1e-9, abs=1e-15)
    assert summary["energy_drift_J"] < 1e-6  # rtol = atol = 1e-10 in the scene, 0.5 s
    stretch = model.stretch(x)
    assert summary["max_stretch_m"] == pytest.approx(np.max(np.abs(stretch)), rel=1e-12)
    assert summary["n_rhs"] > 0 and summary["final_state"]["theta1"] == pytest.approx(x[-1, 0], abs=1e-15)


def test_plot_writes_figures(tmp_path, capsys):
    assert main(["simulate", "--scene", "rigid_regular", "--t-final", "1", "--plot", str(tmp_path / "figs")]) == 0
    pngs = sorted(p.name for p in (tmp_path / "figs").glob("*.png"))
    # A rigid run has no spring-stretch figure; the six others are written and non-trivial.
    assert pngs == sorted(
        ["fig2_snapshots.png", "fig3_angles.png", "fig4_angles_compare.png", "fig5_positions.png", "fig6_phase.png", "energy.png"]
    )
    assert all((tmp_path / "figs" / p).stat().st_size > 10_000 for p in pngs)


BAD = [
    (["--model", "rigid", "--set", "k1=5"], "'k1'"),
    (["--model", "rigid", "--set", "theta1=abc"], "'abc'"),
    (["--model", "rigid", "--set", "theta1"], "not NAME=VALUE"),
    (["--model", "rigid", "--set", "theta1=nan"], "finite"),
    (["--model", "rigid", "--set", "m1=-1"], "'m1'"),
    (["--model", "elastic", "--set", "k2=0"], "'k2'"),
    (["--model", "flexible"], "'flexible'"),
    (["--scene", "no_such_scene"], "'no_such_scene'"),
    (["--model", "rigid", "--t-final", "-1"], "--t-final = '-1'"),
    (["--model", "rigid", "--dt", "zero"], "--dt = 'zero'"),
    (["--model", "rigid", "--rtol", "0"], "--rtol = '0'"),
    (["--model", "rigid", "--method", "euler"], "'euler'"),
    (["--model", "rigid", "--out", "traj.txt"], "'traj.txt'"),
    ([], "exactly one of"),
    (["--scene", "rigid_regular", "--model", "rigid"], "exactly one of"),
]


@pytest.mark.parametrize(("args", "fragment"), BAD, ids=[" ".join(a) or "none" for a, _ in BAD])
def test_bad_input_one_line_exit_2(args, fragment, capsys, tmp_path):
    assert main(["simulate", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("pendulab simulate: error:") and fragment in err[-1]
    # At most a progress line precedes the error; the error itself is one line.
    assert len(err) <= 2


def test_bad_scene_file_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[model]\nkind = 'rigid'\n[simulation]\ntfinal = 3.0\n")
    assert main(["simulate", "--scene", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.toml" in err[0] and "[simulation] tfinal = 3.0" in err[0]


def _auto(tmp_path, capsys, scene, *extra):
    out = tmp_path / f"{scene}.csv"
    args = ["simulate", "--scene", scene, "--model", "auto", "--json", "--out", str(out), *extra]
    assert main(args) == 0
    captured = capsys.readouterr()
    header, data = read_csv(out)
    return json.loads(captured.out), captured.err, dict(zip(header, data.T, strict=True))


def test_model_auto_stiff_scene_runs_the_rigid_model(tmp_path, capsys):
    summary, err, cols = _auto(tmp_path, capsys, "elastic_stiff", "--t-final", "1")
    assert summary["model_level"] == "rigid"
    assert "chosen: rigid" in err and "linearized" in err  # the hierarchy report went to stderr
    assert cols["t"][-1] == 1.0  # --t-final reached the scene before the choice
    # The chosen model is reported truthfully: the rigid model with its own states, no spring rows or columns.
    assert summary["model"] == "rigid" and summary["scene_model"] == "elastic"
    assert "r1" not in cols and "v2" not in cols and "r1" not in summary["final_state"]
    assert summary["max_stretch_m"] is None and summary["method"] != "rigid"
    assert summary["n_steps"] is not None or summary["method"] == "taylor"  # the rigid run's own solver statistics
    scene = load_scene("elastic_stiff")
    rigid = pl.simulate(pl.rigid(), [0.3, 0.3, 0.0, 0.0], 1.0, scene.dt, scene.method, scene.rtol, scene.atol)
    # Same rigid model, method and tolerances as the hierarchy's rigid level: equal to round-off.
    np.testing.assert_allclose(cols["theta1"], rigid["theta1"], rtol=0, atol=1e-12)
    full = scene.simulate(t_final=1.0)
    dev = np.max(np.abs(cols["x2"] - full["x2"]))
    # Within the scene's 1e-3 m tolerance of the elastic model, yet not the elastic run itself (~1e-5 m static stretch).
    assert 1e-7 < dev < scene.tolerance


def test_model_auto_soft_scene_runs_the_elastic_model(tmp_path, capsys):
    summary, err, cols = _auto(tmp_path, capsys, "elastic_soft", "--t-final", "0.5")
    assert summary["model_level"] == "elastic" and "chosen: elastic" in err
    # The scene's own run: its method (not the level's name) and that solver's statistics.
    assert summary["model"] == "elastic" and not summary["method"].startswith("elastic") and summary["n_rhs"]
    full = load_scene("elastic_soft").simulate(t_final=0.5)
    # The chosen level is the scene's own native run: identical samples.
    np.testing.assert_allclose(cols["theta2"], full["theta2"], rtol=0, atol=1e-12)
    assert np.ptp(cols["r1"]) > 1e-3  # the springs really move (soft: static stretch 0.2 m)


def test_model_auto_applies_set_before_choosing(tmp_path, capsys):
    # The soft scene made stiff with --set: the hierarchy sees k = 1e6 N/m and the rigid model suffices.
    summary, _, cols = _auto(tmp_path, capsys, "elastic_soft", "--t-final", "1", "--set", "k1=1e6", "--set", "k2=1e6")
    assert summary["model_level"] == "rigid" and summary["scene_params"]["k1"] == 1e6
    assert summary["model"] == "rigid" and "r2" not in cols


def test_model_auto_without_scene_is_a_one_line_error(capsys):
    assert main(["simulate", "--model", "auto", "--t-final", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--model auto needs --scene" in err and "\n" not in err


def test_model_auto_table_names_the_chosen_model_and_its_states(tmp_path, capsys):
    # Issue 20: the table said "model elastic", "method rigid (auto)", "final r1 1.000000" for a rigid run.
    assert main(["simulate", "--scene", "elastic_stiff", "--model", "auto", "--t-final", "0.5"]) == 0
    table = capsys.readouterr().out
    rows = {line.split("  ")[0].strip(): line.split()[-1] for line in table.splitlines()[2:]}
    # The level is chosen on measured cost (ties within 1.5x go to the simpler model): a rigid level either way.
    assert rows["model"] == "rigid" and rows["model level"] in ("rigid", "rigid+quasi-static"), table
    assert "final r1" not in rows and "final v1" not in rows
    method_line = next(line for line in table.splitlines() if line.startswith("method"))
    assert "rigid" not in method_line  # the rigid model's own method, not the level's name

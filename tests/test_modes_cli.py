"""``pendulab modes``: JSON content, figures written, one-line errors with exit status 2."""

import json
import math

import pytest

from pendulab.cli import main


def test_modes_json_rigid_analytic(capsys):
    assert main(["modes", "--model", "rigid", "--set", "L1=0.5", "--set", "L2=0.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [e["name"] for e in out["equilibria"]] == ["down-down", "down-up", "up-down", "up-up"]
    dd = out["equilibria"][0]
    w = sorted(m["omega_n_rad_s"] for m in dd["modes"])
    # Equal masses and lengths: omega^2 = (2 -+ sqrt 2) g / L; printed JSON keeps full precision.
    assert w[0] ** 2 == pytest.approx((2 - math.sqrt(2)) * 9.81 / 0.5, rel=1e-12)
    assert w[1] ** 2 == pytest.approx((2 + math.sqrt(2)) * 9.81 / 0.5, rel=1e-12)
    assert [e["n_unstable"] for e in out["equilibria"]] == [0, 1, 1, 2]


def test_modes_table_controllability_and_plot(tmp_path, capsys):
    args = ["modes", "--model", "elastic", "--equilibrium", "up-up", "--controllability", "--plot", str(tmp_path)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "spring stretch in-phase" in text and "unstable (2 modes)" in text
    assert "up-up       pendubot   4/8" in text  # springs unreachable by the torques at a vertical equilibrium
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written == ["modes_elastic_up-up.png", "modes_frequency_vs_stiffness.png"]
    assert all((tmp_path / n).stat().st_size > 10_000 for n in written)  # real figures, not empty files


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["--model", "stiff"], "--model 'stiff'"),
        (["--model", "rigid", "--equilibrium", "sideways"], "--equilibrium 'sideways'"),
        (["--model", "rigid", "--torque", "1"], "--torque '1'"),
        (["--model", "rigid", "--torque", "0,90"], "exceeds the largest gravity torque"),
        (["--model", "rigid", "--set", "k1=3"], "unknown parameter name(s) ['k1']"),
        (["--model", "rigid", "--set", "m1"], "not NAME=VALUE"),
    ],
)
def test_modes_bad_input_exits_2(argv, fragment, capsys):
    assert main(["modes", *argv]) == 2
    err = capsys.readouterr().err
    assert fragment in err and len(err.strip().splitlines()) == 1


def test_modes_out_writes_the_json_and_the_figures(tmp_path, capsys):
    out = tmp_path / "modes"
    assert main(["modes", "--model", "rigid", "--equilibrium", "down-down", "--out", str(out), "--json"]) == 0
    printed = json.loads(capsys.readouterr().out)
    written = json.loads((out / "modes.json").read_text())
    assert written["equilibria"] == printed["equilibria"]  # the file is what --json prints
    assert (out / "modes_rigid_down-down.png").stat().st_size > 10_000
    assert main(["modes", "--model", "rigid", "--out", str(out), "--plot", str(tmp_path / "other")]) == 2
    assert "--plot only without --out" in capsys.readouterr().err

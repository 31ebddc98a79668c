"""g = 0 is an admissible parameter (>= 0): every path either handles it or refuses it by name (issue 31).

Found: ``scene check`` of a scene with ``g = 0`` ended in a ZeroDivisionError traceback (the a priori
rule's energy scale, then the automatic method choice's pendular time scale); springs of 1e300 N/m
in an obscure index error.
"""

from __future__ import annotations

import numpy as np
import pytest

import pendulab as pl
from pendulab.cli import main

SCENE = """[model]
kind = "{kind}"
[model.params]
{params}
[initial]
theta1 = 0.5
[simulation]
t_final = 1.0
[outputs]
names = ["theta1"]
tolerance = 0.01
"""


def test_auto_method_without_gravity_integrates_a_rigid_rotation_exactly():
    # No gravity, both links spinning at 1 rad/s: the arm turns as one rigid body, theta_i(t) = t exactly.
    model = pl.rigid(g=0.0)
    tr = pl.simulate(model, model.state(omega1=1.0, omega2=1.0), 1.0, 0.1, "auto", 1e-10, 1e-10)
    assert np.allclose(tr.x[:, 0], tr.t, atol=1e-9) and np.allclose(tr.x[:, 1], tr.t, atol=1e-9)  # tol 1e-10 over 1 s
    at_rest = pl.simulate(model, model.state(), 1.0, 0.1, "auto")
    assert np.all(at_rest.x == 0.0)  # nothing moves without gravity and motion


@pytest.mark.parametrize(
    ("kind", "params", "message"),
    [
        ("rigid", "g = 0", "needs g > 0"),
        ("elastic", "g = 0", "needs g > 0"),
        ("elastic", "k1 = 1e50\nk2 = 1e50", "beyond the 1e+06 rad/s the rule resolves"),
    ],
)
def test_scene_check_refuses_scenes_outside_the_rules_domain(kind, params, message, tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(kind=kind, params=params))
    assert main(["scene", "check", str(scene)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_scene_check_measure_runs_without_gravity(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(SCENE.format(kind="rigid", params="g = 0"))
    assert main(["scene", "check", str(scene), "--measure", "--repeats", "1", "--json"]) == 0
    assert "chosen" in capsys.readouterr().out

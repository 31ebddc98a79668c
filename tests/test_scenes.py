"""Scene files: loading, validation messages, shipped scenes."""

import numpy as np
import pytest

import pendulab as pl
from pendulab.model.counterpart import rigid_counterpart, rigid_state
from pendulab.scene import list_scenes, load_scene

GOOD = """
[scene]
name = "round_trip"
description = "a test scene"
[model]
kind = "elastic"
[model.params]
m1 = 2.0
k1 = 300.0
c2 = 0.5
[initial]
theta1 = 0.4
r2 = 1.1
[simulation]
t_final = 2.5
dt = 0.05
method = "RK45"
rtol = 1e-7
atol = 1e-9
[outputs]
names = ["theta1", "x2", "stretch1"]
tolerance = 0.02
[input]
tau1 = 0.25
[task]
target = "up-up"
horizon = 3.0
"""


def trapezoid(f, t):
    return float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(t)))


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_round_trip_every_field(tmp_path):
    scene = load_scene(write(tmp_path, GOOD))
    assert scene.name == "round_trip" and scene.description == "a test scene"
    assert scene.model.kind == "elastic"
    assert scene.model.params == pl.ElasticParams(m1=2.0, k1=300.0, c2=0.5)
    # Unstated r1 takes the static hanging length (m1 + m2) g / k1 beyond L1; stated values are kept.
    expected_r1 = 1.0 + (2.0 + 1.0) * 9.81 / 300.0
    np.testing.assert_allclose(scene.x0, [0.4, 0.0, expected_r1, 1.1, 0, 0, 0, 0], rtol=0, atol=1e-15)
    assert (scene.t_final, scene.dt, scene.method, scene.rtol, scene.atol) == (2.5, 0.05, "RK45", 1e-7, 1e-9)
    assert scene.outputs == ("theta1", "x2", "stretch1") and scene.tolerance == 0.02
    np.testing.assert_array_equal(scene.u, [0.25, 0.0])
    assert scene.extra == {"task": {"target": "up-up", "horizon": 3.0}}
    with pytest.raises(ValueError):
        scene.x0[0] = 1.0  # the frozen scene's arrays are read-only


def test_defaults_when_sections_are_omitted(tmp_path):
    scene = load_scene(write(tmp_path, '[model]\nkind = "rigid"\n', name="bare.toml"))
    assert scene.name == "bare" and scene.u is None and scene.tolerance is None
    assert (scene.t_final, scene.dt, scene.method) == (10.0, 0.01, "auto")
    np.testing.assert_array_equal(scene.x0, [0, 0, 0, 0])


def test_with_settings_recomputes_unstated_spring_length(tmp_path):
    scene = load_scene(write(tmp_path, GOOD)).with_settings(k1=600.0, theta2=0.1, m2=1.5)
    assert scene.model.params.k1 == 600.0 and scene.model.params.m2 == 1.5
    # r1 was not stated in the file: it follows the new stiffness and masses; r2 was stated: it stays.
    np.testing.assert_allclose(scene.x0[:4], [0.4, 0.1, 1.0 + 3.5 * 9.81 / 600.0, 1.1], rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match=r"unknown name\(s\) \['lc1'\].*parameter.*state"):
        scene.with_settings(lc1=0.5)


def test_simulate_uses_scene_settings_and_overrides(tmp_path):
    scene = load_scene(write(tmp_path, GOOD))
    traj = scene.simulate(t_final=0.5, method="cvodes", rtol=1e-10, atol=1e-10)
    assert traj.method == "cvodes" and traj.t[-1] == 0.5 and traj.t[1] == 0.05
    # The scene's constant torque is applied: it is what reaches the trajectory's input columns.
    np.testing.assert_array_equal(traj["tau1"], 0.25)
    # Energy balance with torque and damper: E(T) - E(0) = integral of (power in - dissipation).
    # Trapezoid on a 0.05 s grid is the limiting error here; 2 % of the exchanged energy is ample.
    model = scene.model
    p_net = model.power_in(traj.x, traj.u) - model.dissipation(traj.x)
    delta = traj["energy"][-1] - traj["energy"][0]
    assert abs(delta - trapezoid(p_net, traj.t)) < 0.02 * trapezoid(np.abs(p_net), traj.t)
    with pytest.raises(ValueError, match="unknown simulate override"):
        scene.simulate(horizon=1.0)


def test_simulate_matches_direct_call():
    scene = load_scene("rigid_regular")
    a = scene.simulate(t_final=1.0)
    b = pl.simulate(pl.rigid(), [0.3, 0.3, 0, 0], 1.0, dt=0.01, method="cvodes", rtol=1e-10, atol=1e-10)
    # Same model, same call: identical up to round-off.
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-14)


BAD = [
    # (file text, fragments the message must contain)
    ("[model\nkind = 'rigid'", ["malformed TOML"]),
    ("[scene]\nname = 'x'\n", ["[model]", "missing", "table"]),
    ("[model]\nkind = 'flexible'\n", ["[model] kind", "'flexible'", "'rigid'", "'elastic'"]),
    ("[model]\nkind = 'rigid'\nmodel = 3\n", ["[model] model = 3", "one of the keys"]),
    ("[model]\nkind = 'rigid'\n[model.params]\nk1 = 500.0\n", ["[model.params] k1 = 500.0", "rigid parameters", "'m1'"]),
    ("[model]\nkind = 'rigid'\n[model.params]\nm1 = -1.0\n", ["[model.params]", "'m1'", "-1.0", "> 0"]),
    ("[model]\nkind = 'rigid'\n[model.params]\nm1 = '1'\n", ["[model.params] m1 = '1'", "a finite number"]),
    ("[model]\nkind = 'rigid'\n[model.params]\nL1 = nan\n", ["[model.params] L1 = nan", "finite"]),
    ("[model]\nkind = 'elastic'\n[model.params]\nk2 = 0.0\n", ["'k2'", "0.0", "> 0"]),
    ("[model]\nkind = 'rigid'\n[initial]\nr1 = 1.0\n", ["[initial] r1 = 1.0", "rigid state names", "'theta1'"]),
    ("[model]\nkind = 'rigid'\n[initial]\ntheta1 = true\n", ["[initial] theta1 = True", "a finite number"]),
    ("[model]\nkind = 'elastic'\n[initial]\nr1 = -0.5\n", ["[initial]", "spring lengths > 0"]),
    ("[model]\nkind = 'rigid'\n[simulation]\ntfinal = 5.0\n", ["[simulation] tfinal = 5.0", "'t_final'"]),
    ("[model]\nkind = 'rigid'\n[simulation]\nt_final = 0.0\n", ["[simulation] t_final = 0.0", "out of range"]),
    ("[model]\nkind = 'rigid'\n[simulation]\ndt = -0.01\n", ["[simulation] dt = -0.01", "out of range"]),
    ("[model]\nkind = 'rigid'\n[simulation]\nt_final = '10'\n", ["[simulation] t_final = '10'", "a finite number"]),
    ("[model]\nkind = 'rigid'\n[simulation]\nt_final = 1.0\ndt = 2.0\n", ["[simulation] dt = 2.0", "t_final"]),
    ("[model]\nkind = 'rigid'\n[simulation]\nmethod = 'euler'\n", ["[simulation] method = 'euler'", "'cvodes'"]),
    ("[model]\nkind = 'rigid'\n[simulation]\nrtol = 0\n", ["[simulation] rtol = 0", "out of range"]),
    ("[model]\nkind = 'rigid'\n[outputs]\nnames = ['stretch1']\n", ["[outputs] names = ['stretch1']", "'theta1'"]),
    ("[model]\nkind = 'rigid'\n[outputs]\nnames = 'theta1'\n", ["[outputs] names = 'theta1'", "list"]),
    ("[model]\nkind = 'rigid'\n[outputs]\ntolerance = -1.0\n", ["[outputs] tolerance = -1.0", "out of range"]),
    ("[model]\nkind = 'rigid'\n[input]\ntau3 = 1.0\n", ["[input] tau3 = 1.0", "'tau1'"]),
    ("[scene]\nauthor = 'me'\n[model]\nkind = 'rigid'\n", ["[scene] author = 'me'", "'name'"]),
    ("scene = 3\n[model]\nkind = 'rigid'\n", ["[scene] = 3", "table"]),
    ("[model]\nkind = 'rigid'\n[initial]\nstart = 'quasi-static'\n", ["[initial] start = 'quasi-static'", "'static'"]),
    ("[model]\nkind = 'elastic'\n[initial]\nstart = 'relaxed'\n", ["[initial] start = 'relaxed'", "'rest-length'"]),
    ("[model]\nkind = 'elastic'\n[initial]\nstart = 'quasi-static'\nr1 = 1.0\n", ["[initial] start", "no stated r1, r2"]),
    ("[model]\nkind = 'rigid'\n[input.sine]\namplitude = [1.0]\nfrequency = 1.0\n", ["[input.sine] amplitude = [1.0]", "2"]),
    ("[model]\nkind = 'rigid'\n[input.sine]\namplitude = [1.0, 0.0]\n", ["[input.sine] frequency", "missing"]),
    ("[model]\nkind = 'rigid'\n[input.sine]\namplitude = [1.0, 0.0]\nfrequency = 1\nphase = 0\n", ["phase"]),
]


@pytest.mark.parametrize(("text", "fragments"), BAD, ids=[f"bad{i}" for i in range(len(BAD))])
def test_bad_scene_files_name_file_section_key_value(tmp_path, text, fragments):
    path = write(tmp_path, text, name="bad_scene.toml")
    with pytest.raises(ValueError) as info:
        load_scene(path)
    message = str(info.value)
    assert "bad_scene.toml" in message and "\n" not in message.strip()
    for fragment in fragments:
        assert fragment in message, f"{fragment!r} not in {message!r}"


def test_missing_scene_lists_shipped_names():
    with pytest.raises(FileNotFoundError, match=r"no_such_scene.*seed_paper"):
        load_scene("no_such_scene")


def test_shipped_scenes_load_and_run_briefly():
    names = list_scenes()
    assert {"seed_paper", "rigid_regular", "rigid_chaotic", "elastic_soft", "elastic_stiff"} <= set(names)
    for name in names:
        scene = load_scene(name)
        assert scene.name == name and scene.description
        traj = scene.simulate(t_final=min(scene.t_final, 0.2))
        e = traj["energy"]
        # Shipped scenes are undamped and unforced: energy is conserved to integrator accuracy (tolerances <= 1e-8).
        assert np.max(np.abs(e - e[0])) <= 1e-6 * max(1.0, abs(e[0])), name


def test_seed_paper_starts_rigid_and_elastic_identically():
    scene = load_scene("seed_paper")
    rigid = rigid_counterpart(scene.model)
    assert rigid.kind == "rigid" and scene.model.kind == "elastic"
    for name in ("m1", "m2", "L1", "L2", "g", "b1", "b2"):
        assert getattr(rigid.params, name) == getattr(scene.model.params, name)
    x0r = rigid_state(scene.model, scene.x0)
    # Springs start at rest length: both bobs at the same place, same (zero) velocities.
    np.testing.assert_allclose(rigid.positions(x0r), scene.model.positions(scene.x0), rtol=0, atol=1e-15)
    assert rigid.energy(x0r) == pytest.approx(scene.model.energy(scene.x0), abs=1e-12)
    assert rigid_counterpart(rigid) is rigid


def test_start_rules_set_unstated_spring_lengths(tmp_path):
    """static: hanging stretch; rest-length: r = L; quasi-static: zero radial acceleration at the start."""
    base = "[model]\nkind = 'elastic'\n[model.params]\nk1 = 1e4\nk2 = 1e4\n[initial]\ntheta1 = 0.3\ntheta2 = 0.5\n"
    static = load_scene(write(tmp_path, base, name="a.toml"))
    rest = load_scene(write(tmp_path, base + "start = 'rest-length'\n", name="b.toml"))
    qs = load_scene(write(tmp_path, base + "start = 'quasi-static'\n", name="c.toml"))
    m = static.model
    p = m.params
    np.testing.assert_allclose(static.x0[2:4], [p.L1 + (p.m1 + p.m2) * p.g / p.k1, p.L2 + p.m2 * p.g / p.k2], rtol=1e-15)
    np.testing.assert_allclose(rest.x0[2:4], [p.L1, p.L2], rtol=0, atol=0)
    # Quasi-static: the radial accelerations vanish (to the root finder's accuracy) and the angles are kept.
    assert np.max(np.abs(m.rhs(qs.x0)[6:8])) < 1e-9
    np.testing.assert_array_equal(qs.x0[[0, 1, 4, 5]], [0.3, 0.5, 0.0, 0.0])
    # A changed stiffness keeps the rule: the quasi-static lengths follow it.
    stiffer = qs.with_settings(k1=1e5, k2=1e5)
    assert stiffer.start == "quasi-static" and np.max(np.abs(stiffer.model.rhs(stiffer.x0)[6:8])) < 1e-9


def test_sine_input_is_held_on_the_output_grid(tmp_path):
    text = "[model]\nkind = 'rigid'\n[simulation]\nt_final = 1.0\ndt = 0.1\n[input]\ntau2 = 0.2\n"
    text += "[input.sine]\namplitude = [0.5, 0.0]\nfrequency = 0.5\n"
    scene = load_scene(write(tmp_path, text))
    t = scene.grid()
    u = scene.inputs()
    np.testing.assert_allclose(u[:, 0], 0.5 * np.sin(np.pi * t), rtol=0, atol=1e-15)
    np.testing.assert_allclose(u[:, 1], 0.2, rtol=0, atol=0)
    traj = scene.simulate(rtol=1e-10, atol=1e-10)
    # simulate holds row k over [t_k, t_k+1): the applied torques are the scene's samples.
    np.testing.assert_allclose(traj.u[:-1], u[:-1], rtol=0, atol=0)


def test_bench_and_validation_groups_are_scenes():
    bench, validation = list_scenes("bench"), list_scenes("validation")
    assert "bench/rigid_chaotic_10s" in bench and "validation/elastic_stiff_forced" in validation
    assert not set(list_scenes()) & {n.split("/")[1] for n in validation}  # validation names are their own
    case = load_scene("bench/elastic_stiff_1e6_qs")
    assert case.start == "quasi-static" and case.model.params.k1 == 1e6
    with pytest.raises(ValueError, match="unknown scene group 'tasks'"):
        list_scenes("tasks")
    with pytest.raises(FileNotFoundError):
        load_scene("nogroup/rigid_chaotic_10s")

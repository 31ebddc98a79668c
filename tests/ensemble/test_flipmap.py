"""The flip map: npz layout and indexing, flip times against a direct simulation, the exact energy skip, the CLI."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pendulab as pl
from pendulab.cli import main

pytest.importorskip("heyoka", reason="the flip map integrates with method='taylor' (heyoka)")

from pendulab.bench.ensemble import hand_loop  # noqa: E402  (needs heyoka)
from pendulab.ensemble.flipmap import (  # noqa: E402
    FlipMap,
    flip_energy_threshold,
    flip_map,
    flip_map_grid,
)

G = 9.81


@pytest.fixture(scope="module")
def small_map() -> FlipMap:
    # 9 x 7 (odd, so theta = 0 is a grid point; unequal, so swapped indices would show), 3 s.
    return flip_map(pl.rigid(), (9, 7), 3.0, threads=1)


def test_threshold_rigid_is_the_analytic_value() -> None:
    # V = -a cos(theta1) - b cos(theta2): V_flip = -|a - b|; unit parameters: a = 2g, b = g.
    assert flip_energy_threshold(pl.rigid()) == pytest.approx(-G, abs=1e-9)  # IPOPT to 1e-14: exact to rounding
    m = pl.rigid(m2=2.0, lc1=0.5)
    a, b = (1.0 * 0.5 + 2.0 * 1.0) * G, 2.0 * 1.0 * G
    assert flip_energy_threshold(m) == pytest.approx(-abs(a - b), abs=1e-9)


def test_threshold_elastic_is_the_closed_form() -> None:
    # Link 2 up (theta2 = pi, theta1 = 0): r1 = L + 2g/k, r2 = L - g/k -> V = -g - 2.5 g^2/k (m = L = 1);
    # link 1 up gives g - 2.5 g^2/k, larger.
    k = 1e3
    assert flip_energy_threshold(pl.elastic(k1=k, k2=k)) == pytest.approx(-G - 2.5 * G**2 / k, abs=1e-8)


def test_npz_keys_shapes_and_indexing(small_map: FlipMap, tmp_path) -> None:
    path = small_map.save_npz(tmp_path / "fm.npz")
    with np.load(path) as z:
        assert {"theta1", "theta2", "t_flip"} <= set(z.files)
        th1, th2, tf = z["theta1"], z["theta2"], z["t_flip"]
    assert th1.shape == (9,) and th2.shape == (7,) and tf.shape == (9, 7)
    np.testing.assert_array_equal(th1, flip_map_grid(9))
    np.testing.assert_array_equal(th2, flip_map_grid(7))
    # theta1 = theta2 = 0 (hanging at rest) never flips.
    i0, j0 = int(np.flatnonzero(th1 == 0.0)[0]), int(np.flatnonzero(th2 == 0.0)[0])
    assert np.isnan(tf[i0, j0])
    # A high-energy point with theta1 != theta2, so t_flip[j, i] would be another point: the direct
    # simulation (the hand-written heyoka loop, independent of the engine) finds the same flip time.
    i, j = 8, 5
    x0 = np.array([[th1[i], th2[j], 0.0, 0.0]])
    direct, _ = hand_loop(pl.rigid(), x0, 3.0)
    assert np.isfinite(direct[0]) and np.isfinite(tf[i, j])
    assert tf[i, j] == pytest.approx(direct[0], abs=1e-8)  # both tol 1e-12; 3 s of a fast flip: ~1e-10
    # The mirror point flips at the same time (point symmetry of the equations).
    assert tf[8 - i, 6 - j] == tf[i, j]
    assert FlipMap.load_npz(path).t_flip.shape == (9, 7)


def test_symmetry_shortcut_matches_full_integration(small_map: FlipMap) -> None:
    full = flip_map(pl.rigid(), (9, 7), 3.0, symmetry=False, threads=1)
    assert full.n_simulated > small_map.n_simulated
    np.testing.assert_array_equal(np.isnan(full.t_flip), np.isnan(small_map.t_flip))
    # Mirror runs are separate integrations: equal to the tolerance, amplified over <= 3 s.
    np.testing.assert_allclose(full.t_flip, small_map.t_flip, atol=1e-7, equal_nan=True)


def test_energy_skip_is_exact(small_map: FlipMap) -> None:
    th1, th2 = np.meshgrid(small_map.theta1, small_map.theta2, indexing="ij")
    # Rigid, unit parameters: a point can flip only if 2 cos(theta1) + cos(theta2) <= 1.
    np.testing.assert_array_equal(small_map.skipped, 2 * np.cos(th1) + np.cos(th2) > 1 + 1e-9)
    assert np.all(np.isnan(small_map.t_flip[small_map.skipped]))
    # Points just inside the forbidden region, along the boundary, integrated directly for 20 s: none flips.
    delta = 1e-3
    t2 = np.array([0.0, 1.0, 2.0, 2.8, -1.5])
    t1 = np.arccos((1 + delta - np.cos(t2)) / 2)
    x0 = np.column_stack([t1, t2, np.zeros(5), np.zeros(5)])
    assert np.all(pl.rigid().potential_energy(x0) < flip_energy_threshold(pl.rigid()))
    tf, _ = hand_loop(pl.rigid(), x0, 20.0)
    assert np.all(np.isnan(tf))
    # ... and just outside, where the skip keeps the points, some flip (the bound is not loose).
    t1_out = np.arccos((1 - 0.2 - np.cos(t2)) / 2)
    tf_out, _ = hand_loop(pl.rigid(), np.column_stack([t1_out, t2, np.zeros(5), np.zeros(5)]), 20.0)
    assert np.any(np.isfinite(tf_out))


def test_cli_writes_npz_and_pngs(tmp_path, capsys) -> None:
    out = tmp_path / "fm"
    status = main(["ensemble", "flipmap", "--model", "rigid", "--grid", "8", "--t-max", "1", "--out", str(out), "--no-progress"])
    assert status == 0
    assert (out / "flipmap.npz").exists() and (out / "flipmap.png").exists()
    with np.load(out / "flipmap.npz") as z:
        assert z["t_flip"].shape == (8, 8)
    out2 = tmp_path / "cmp"
    status = main(
        [
            "ensemble",
            "flipmap",
            "--model",
            "elastic",
            "--k",
            "1000",
            "--grid",
            "4",
            "--t-max",
            "0.3",
            "--out",
            str(out2),
            "--no-progress",
        ]
    )
    assert status == 0
    for name in ("flipmap.npz", "flipmap.png", "flipmap_compare.png", "flipmap_rigid.npz"):
        assert (out2 / name).exists(), name
    with np.load(out2 / "flipmap.npz") as z:
        assert str(z["kind"]) == "elastic"


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--model", "floppy"], "--model"),
        (["--grid", "0"], "--grid"),
        (["--grid", "ten"], "--grid"),
        (["--t-max", "-1"], "--t-max"),
        (["--t-max", "nan"], "--t-max"),
        (["--model", "elastic", "--k", "-5"], "--k"),
        (["--scheduler", "localhost:8786"], "--scheduler"),
    ],
)
def test_cli_rejects_bad_input(argv, needle, tmp_path, capsys) -> None:
    status = main(["ensemble", "flipmap", "--out", str(tmp_path / "x"), "--no-progress", *argv])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert len(err.splitlines()) == 1 and needle in err


def test_cli_json_is_one_object_on_stdout(tmp_path, capsys) -> None:
    import json

    argv = ["ensemble", "flipmap", "--grid", "6", "--t-max", "1", "--out", str(tmp_path / "j"), "--no-progress", "--json"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    summary = json.loads(out)  # the whole of stdout is one JSON object
    rigid = summary["maps"]["rigid"]
    assert rigid["n_points"] == 36 and rigid["n_flipped"] <= 36 - rigid["n_skipped"]
    assert rigid["settings"]["rtol"] == 1e-12 and summary["files"][0].endswith("flipmap.npz")


def test_cli_help_and_default_out(capsys, tmp_path, monkeypatch) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["ensemble", "flipmap", "--help"])
    assert exc.value.code == 0 and "--t-max" in capsys.readouterr().out
    # Without --out the map goes to ./pendulab-out/ensemble-flipmap/, like every command's outputs.
    monkeypatch.chdir(tmp_path)
    assert main(["ensemble", "flipmap", "--grid", "4", "--t-max", "0.5", "--no-progress"]) == 0
    assert (tmp_path / "pendulab-out" / "ensemble-flipmap" / "flipmap.npz").exists()


def test_bad_arguments_raise_value_error() -> None:
    with pytest.raises(ValueError, match="t_max"):
        flip_map(pl.rigid(), 4, -1.0)
    with pytest.raises(ValueError, match="n_grid"):
        flip_map(pl.rigid(), 0, 1.0)
    with pytest.raises(ValueError, match="theta_range"):
        flip_map(pl.rigid(), 4, 1.0, theta_range=(1.0, -1.0))
    with pytest.raises(ValueError, match="symmetry"):
        flip_map(pl.rigid(), 4, 1.0, theta_range=(0.0, math.pi), symmetry=True)

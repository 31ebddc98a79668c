"""``pendulab demo`` on a shortened horizon: every promised file, with meaningful content."""

import csv
import json

import numpy as np
import pytest
from PIL import Image

from pendulab.cli import main
from pendulab.viz.figures import FIGURES


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo") / "pendulab-out"
    assert main(["demo", "--out", str(out), "--t-final", "1.0", "--json"]) == 0
    return out


def read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array(rows[1:], dtype=float)


def test_every_promised_file(demo_dir):
    expected = {f"{name}.png" for name in FIGURES} | {"pendulums.gif", "rigid.csv", "elastic.csv", "summary.json"}
    assert expected <= {p.name for p in demo_dir.iterdir()}


def test_figures_are_not_blank(demo_dir):
    for name in FIGURES:
        img = np.asarray(Image.open(demo_dir / f"{name}.png").convert("L"), dtype=float)
        assert img.shape[0] > 200 and img.shape[1] > 400, name
        # Drawn content: a blank (single-colour) figure has zero spread; axes, text and lines give plenty.
        assert img.std() > 10.0 and (img < 128).mean() > 0.005, name


def test_gif_plays_the_horizon(demo_dir):
    gif = Image.open(demo_dir / "pendulums.gif")
    # 1 s at 20 frames per second, both ends included.
    assert gif.n_frames == 21 and gif.info["duration"] == 50
    first = np.asarray(gif.convert("L"), dtype=float)
    gif.seek(gif.n_frames - 1)
    last = np.asarray(gif.convert("L"), dtype=float)
    assert np.abs(first - last).mean() > 0.5  # the pendulums moved between the first and last frame


def test_csv_identical_start_and_energy(demo_dir):
    hr, rigid = read_csv(demo_dir / "rigid.csv")
    he, elastic = read_csv(demo_dir / "elastic.csv")
    pos = ["x1", "y1", "x2", "y2"]
    r0 = rigid[0, [hr.index(n) for n in pos]]
    e0 = elastic[0, [he.index(n) for n in pos]]
    # Identical initial conditions: springs at rest length, so both bobs start at the same place.
    np.testing.assert_allclose(r0, e0, rtol=0, atol=1e-14)
    # ... and the elastic pendulum departs from the rigid one within the first second (springs matter).
    gap = np.abs(rigid[:, hr.index("x2")] - elastic[:, he.index("x2")])
    assert gap[-1] > 1e-3
    for h, data in ((hr, rigid), (he, elastic)):
        e = data[:, h.index("energy")]
        # Undamped, unforced, rtol = atol = 1e-10: energy conserved to ~1e-8 relative.
        assert np.max(np.abs(e - e[0])) < 1e-6 * abs(e[0])


def test_summary_matches_data(demo_dir, capsys):
    summary = json.loads((demo_dir / "summary.json").read_text())
    assert summary["scene"] == "seed_paper"
    runs = {r["label"]: r for r in summary["runs"]}
    assert set(runs) == {"rigid", "elastic"}
    he, elastic = read_csv(demo_dir / "elastic.csv")
    stretch = elastic[:, [he.index("stretch1"), he.index("stretch2")]]
    assert runs["elastic"]["max_stretch_m"] == pytest.approx(np.max(np.abs(stretch)), rel=1e-12)
    assert runs["rigid"]["max_stretch_m"] is None
    for r in runs.values():
        assert r["n_rhs"] > 0 and r["wall_time_s"] > 0 and r["t_final_s"] == 1.0
        # The demo runs CVODES at 1e-10 over 1 s: relative drift ~1e-8, so 1e-6 leaves 100x margin.
        assert r["energy_drift_rel"] < 1e-6


@pytest.mark.parametrize(
    ("args", "fragment"),
    [(["--t-final", "-2"], "--t-final = '-2'"), (["--scene", "no_such_scene"], "'no_such_scene'")],
)
def test_demo_bad_input_one_line_exit_2(tmp_path, capsys, args, fragment):
    assert main(["demo", "--out", str(tmp_path / "out"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("pendulab demo: error:") and fragment in err[0]

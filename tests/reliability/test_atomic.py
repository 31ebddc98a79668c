"""Outputs are written atomically: a failing write leaves the old file (or none), never a truncated one."""

import csv
import json
import zipfile

import numpy as np
import pytest
from PIL import Image

import pendulab
from pendulab.cli import main
from pendulab.integrate.trajectory import Trajectory


def _traj(n: int = 50) -> Trajectory:
    t = np.linspace(0.0, 1.0, n)
    x = np.column_stack([np.sin(t), np.cos(t), t, -t])
    return Trajectory(
        t=t,
        x=x,
        u=np.zeros((n, 2)),
        y=np.column_stack([t**2]),
        state_names=("theta1", "theta2", "omega1", "omega2"),
        input_names=("tau1", "tau2"),
        output_names=("energy",),
        method="test",
    )


def _leftovers(directory):
    """Temporary files of pendulab._io (hidden, with ``.tmp`` in the name)."""
    return sorted(p.name for p in directory.iterdir() if p.name.startswith(".") and ".tmp" in p.name)


class _DiskFullError(Exception):
    pass


def test_csv_and_npz_roundtrip(tmp_path):
    traj = _traj()
    path = traj.to_csv(tmp_path / "sub" / "a.csv")
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["t", *traj.names] and len(rows) == 51
    npz = traj.to_npz(tmp_path / "a.npz")
    with np.load(npz) as data:
        np.testing.assert_array_equal(data["x"], traj.x)
    # NumPy's rule kept: a name without .npz gets the suffix, the returned path is as given.
    bare = traj.to_npz(tmp_path / "b")
    assert bare == tmp_path / "b" and (tmp_path / "b.npz").is_file()
    assert _leftovers(tmp_path) == [] and _leftovers(tmp_path / "sub") == []


def test_failing_csv_write_keeps_the_old_file(tmp_path, monkeypatch):
    good = _traj(10).to_csv(tmp_path / "out.csv")
    before = good.read_bytes()
    big = _traj(1000)
    calls = {"n": 0}
    real_table = Trajectory.table

    def table_then_fail(self):
        # Rows are written one by one: fail after part of them is on disk.
        for k, row in enumerate(real_table(self)):
            calls["n"] += 1
            if k == 500:
                raise _DiskFullError("disk full")
            yield row

    monkeypatch.setattr(Trajectory, "table", table_then_fail)
    with pytest.raises(_DiskFullError):
        big.to_csv(good)
    assert calls["n"] > 100
    assert good.read_bytes() == before
    assert _leftovers(tmp_path) == []


def test_interrupted_npz_write_leaves_nothing(tmp_path, monkeypatch):
    def interrupted(*args, **kwargs):
        fh = args[0]
        fh.write(b"PK\x03\x04 partial")
        raise KeyboardInterrupt

    monkeypatch.setattr(np, "savez", interrupted)
    with pytest.raises(KeyboardInterrupt):
        _traj().to_npz(tmp_path / "t.npz")
    assert list(tmp_path.iterdir()) == []


def test_figure_save_is_atomic(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    from pendulab.viz.save import save_figure

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    path = save_figure(fig, tmp_path / "f.png")
    Image.open(path).load()
    before = path.read_bytes()
    assert not plt.fignum_exists(fig.number)

    real = Figure.savefig

    def half_then_fail(self, fname, **kwargs):
        real(self, fname, **kwargs)
        with open(fname, "r+b") as fh:
            fh.truncate(100)
        raise KeyboardInterrupt

    monkeypatch.setattr(Figure, "savefig", half_then_fail)
    fig2, ax2 = plt.subplots()
    ax2.plot([1, 0], [0, 1])
    with pytest.raises(KeyboardInterrupt):
        save_figure(fig2, path)
    assert path.read_bytes() == before
    assert not plt.fignum_exists(fig2.number)  # closed even on failure
    assert _leftovers(tmp_path) == []


def test_gif_and_figures_of_a_run(tmp_path):
    from pendulab.viz.animate import animate
    from pendulab.viz.figures import save_figures

    model = pendulab.rigid()
    traj = pendulab.simulate(model, model.state(theta1=1.0), 0.3, dt=0.05)
    written = save_figures({"rigid": (model, traj)}, tmp_path)
    gif = animate({"rigid": (model, traj)}, tmp_path / "a.gif", duration=0.3)
    for p in [*written.values(), gif]:
        with Image.open(p) as im:
            im.load()
    assert Image.open(gif).n_frames > 1
    assert _leftovers(tmp_path) == []


@pytest.mark.needs_cc
def test_failing_fmu_export_keeps_the_old_fmu(tmp_path, monkeypatch):
    import importlib

    export = importlib.import_module("pendulab.fmu.export").export  # the package re-exports the function

    model = pendulab.rigid()
    fmu = export(model, tmp_path / "r.fmu", 2)
    before = fmu.read_bytes()
    assert zipfile.ZipFile(fmu).testzip() is None

    real_writestr = zipfile.ZipFile.writestr
    count = {"n": 0}

    def fail_midway(self, info, data, *a, **k):
        count["n"] += 1
        if count["n"] == 3:
            raise KeyboardInterrupt
        return real_writestr(self, info, data, *a, **k)

    monkeypatch.setattr(zipfile.ZipFile, "writestr", fail_midway)
    with pytest.raises(KeyboardInterrupt):
        export(model, fmu, 2)
    assert fmu.read_bytes() == before
    assert _leftovers(tmp_path) == []


def test_demo_summary_is_written_last(tmp_path, monkeypatch):
    """A summary.json in a demo directory means every other file is complete."""
    import pendulab.commands.demo as demo

    order = []
    real = demo.atomic_write_text

    def record(path, text, *a, **k):
        order.append(sorted(p.name for p in path.parent.iterdir() if not p.name.startswith(".")))
        return real(path, text, *a, **k)

    monkeypatch.setattr(demo, "atomic_write_text", record)
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--t-final", "0.3", "--no-gif", "--json"]) == 0
    assert len(order) == 1 and "summary.json" not in order[0]
    summary = json.loads((out / "summary.json").read_text())
    assert {p.rsplit("/", 1)[-1] for p in summary["files"].values()} <= set(order[0])

"""``pendulab identify`` end to end on synthetic CSV records, and its one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulab.cli import main
from pendulab.model.plant_file import load_plant


def _csv(tmp_path, rec, name):
    path = tmp_path / f"{name}.csv"
    data = np.column_stack([rec.t, rec.q, rec.tau])
    np.savetxt(path, data, delimiter=",", header="t,a1,a2,u1,u2", comments="")
    return path


def test_identify_writes_a_plant_file_that_loads(tmp_path, synthetic_records, capsys):
    files = [str(_csv(tmp_path, r, r.name)) for r in synthetic_records[:3]]
    out = tmp_path / "out"
    code = main(["identify", *files, "--columns", "time=t,q1=a1,q2=a2,tau1=u1,tau2=u2", "--structure", "+coulomb",
                 "--out", str(out), "--json", "--no-progress"])  # fmt: skip
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    plant = load_plant(out / "plant.json")
    assert report["chosen_structure"] == "+coulomb"
    # DFKI 1.0 generated the data: its Coulomb friction comes back to within 0.03 N.m (3 records of 6 s, noise 0.01 N.m)
    assert plant.params["cf1"] == pytest.approx(0.16, abs=0.03)
    assert plant.params["cf2"] == pytest.approx(0.12, abs=0.03)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["identify"], "at least two RECORD files"),
        (["identify", "--dataset", "c9"], "--dataset 'c9'"),
        (["identify", "a.csv", "b.csv", "--columns", "time=t,q1=a"], "missing roles"),
        (["identify", "--dataset", "c1", "--geometry", "l3=1"], "unknown names \\['l3'\\]"),
        (["identify", "--dataset", "c1", "--cutoff", "-1"], "--cutoff = '-1'"),
        (["identify", "--dataset", "c1", "--input", "volts"], "--input 'volts'"),
        (["identify", "nope1.csv", "nope2.csv"], "record file not found"),
    ],
)
def test_bad_command_lines_give_one_line(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    import re

    assert re.search(message, err), err

"""The closed loop as an SSP 1.0 archive: schema-valid, consistent with its FMUs, and it runs.

OMSimulator cannot be installed from PyPI here, so the second importer is tests/fmu/ssp_runner.py (fmpy
under the SSD's connections and parameter sets, nothing of pendulab). Its result must equal
``pendulab cosim`` (the plant FMU under the Python controller) at the same sample-and-hold instants.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from pendulab.cli import main
from pendulab.cosim import cosim
from pendulab.cosim.ssp import SSD_NS, export_ssp
from pendulab.fmu.controller_export import design_controller
from tests.fmu.ssp_runner import run_ssp

SCHEMAS = Path(__file__).parent / "data" / "ssp1"  # SSP 1.0 XSDs (modelica/ssp-standard v1.0.1, BSD-2, notice kept)
SSD = f"{{{SSD_NS}}}"


@pytest.fixture(scope="module")
def loops(tmp_path_factory):
    root = tmp_path_factory.mktemp("ssp")
    return {
        ("tvlqr", "pendubot", 2): export_ssp(root / "pendubot_tvlqr.ssp", controller="tvlqr", task="pendubot", fmi_version=2),
        ("swingup", None, 3): export_ssp(root / "rigid_swingup.ssp", controller="swingup", fmi_version=3, stop_time=8.0),
        ("lqr", None, 2): export_ssp(root / "elastic_lqr.ssp", controller="lqr", kind="elastic", stop_time=2.0),
    }


def test_ssd_and_parameter_sets_are_schema_valid(loops):
    etree = pytest.importorskip("lxml.etree")
    ssd = etree.XMLSchema(etree.parse(str(SCHEMAS / "SystemStructureDescription.xsd")))
    ssv = etree.XMLSchema(etree.parse(str(SCHEMAS / "SystemStructureParameterValues.xsd")))
    for res in loops.values():
        with zipfile.ZipFile(res.path) as z:
            assert z.namelist()[0] == "SystemStructure.ssd"
            assert ssd.validate(etree.fromstring(z.read("SystemStructure.ssd"))), ssd.error_log
            for name in ("resources/plant.ssv", "resources/controller.ssv"):
                assert ssv.validate(etree.fromstring(z.read(name))), ssv.error_log


def test_connectors_match_the_fmus(loops, tmp_path):
    """SSP 1.0: a connector's kind matches its FMU variable's causality; connections run output -> input."""
    import xml.etree.ElementTree as ET

    for res in loops.values():
        with zipfile.ZipFile(res.path) as z:
            z.extractall(tmp_path / res.path.stem)
        base = tmp_path / res.path.stem
        system = ET.parse(base / "SystemStructure.ssd").getroot().find(f"{SSD}System")
        kinds = {}
        for comp in system.find(f"{SSD}Elements"):
            fmu = base / comp.get("source")
            assert validate_fmu(str(fmu)) == []
            md = read_model_description(str(fmu))
            assert md.fmiVersion.startswith(str(res.fmi_version))
            causality = {v.name: v.causality for v in md.modelVariables}
            for c in comp.find(f"{SSD}Connectors"):
                assert causality[c.get("name")] == c.get("kind"), (comp.get("name"), c.get("name"))
                kinds[(comp.get("name"), c.get("name"))] = c.get("kind")
        conns = system.find(f"{SSD}Connections")
        assert len(conns) == len(res.state_names) + len(res.torque_names)
        for c in conns:
            assert kinds[(c.get("startElement"), c.get("startConnector"))] == "output"
            assert kinds[(c.get("endElement"), c.get("endConnector"))] == "input"


@pytest.mark.parametrize("case", [("tvlqr", "pendubot", 2), ("swingup", None, 3), ("lqr", None, 2)])
def test_ssp_run_equals_cosim(loops, tmp_path, case):
    """The SSP under the second importer vs pendulab.cosim of the same plant FMU and the Python controller."""
    res = loops[case]
    ran = run_ssp(res.path, tmp_path / "run", res.sample_time, res.stop_time, ("plant", list(res.state_names)))
    name, task, _ = case
    ctrl, x0, model = design_controller(name, task, kind="elastic" if name == "lqr" else "rigid")
    with zipfile.ZipFile(res.path) as z:
        (tmp_path / "plant.fmu").write_bytes(z.read("resources/plant.fmu"))
    traj = cosim(tmp_path / "plant.fmu", ctrl, res.sample_time, res.stop_time, x0=x0)
    np.testing.assert_allclose(ran["t"], traj.t, rtol=0, atol=1e-12)
    # same plant binary, same sample instants, torques equal to rounding (test_controller_fmu): the two loops agree
    # to rounding amplified over the run (measured <= 3e-15 rad; the pumping swing-up is sensitive, so 1e-9)
    assert np.max(np.abs(ran["x"] - traj.x)) <= 1e-9
    if name != "lqr":  # swung up and balanced (angles upright modulo 2 pi)
        np.testing.assert_allclose(np.cos(ran["x"][-1][:2]), [-1.0, -1.0], atol=1e-6)


def test_ssp_run_equals_the_cosim_command(loops, tmp_path):
    """`pendulab cosim --task pendubot --controller tvlqr` (its own plant FMU and controller) vs the SSP run."""
    res = loops[("tvlqr", "pendubot", 2)]
    out = tmp_path / "cosim"
    assert main(["cosim", "--task", "pendubot", "--controller", "tvlqr", "--no-gif", "--no-progress", "--out", str(out)]) == 0
    data = np.genfromtxt(out / "cosim.csv", delimiter=",", names=True)
    ran = run_ssp(res.path, tmp_path / "run", res.sample_time, res.stop_time, ("plant", list(res.state_names)))
    x_cli = np.column_stack([data[n] for n in res.state_names])
    assert x_cli.shape == ran["x"].shape
    # the CLI writes the CSV with 17 significant digits or fewer: agreement to the printed precision and rounding
    assert np.max(np.abs(x_cli - ran["x"])) <= 1e-9
    summary = json.loads((out / "summary.json").read_text())
    assert summary["sample_time"] == res.sample_time


def test_cli_ssp_export(tmp_path, capsys):
    out = tmp_path / "loop.ssp"
    assert main(["ssp", "export", "--controller", "lqr", "--t-final", "1", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["connections"][0] == "plant.theta1 -> controller.theta1" and out.exists()
    assert main(["ssp", "export", "--controller", "nmpc", "--out", str(out)]) == 2
    assert "NMPC is not exported" in capsys.readouterr().err
    assert main(["ssp", "export", "--task", "pendubot", "--kind", "rigid", "--out", str(out)]) == 2
    assert main(["ssp", "export", "--t-final", "-1", "--out", str(out)]) == 2


class _JacobiDelayed:
    """The loop of fmpy's SSP master (Jacobi: every FMU steps, then outputs are read at the new time and passed on).

    The controller FMU's torques read at t_k are the law at t_k with the inputs of the previous step, x(t_{k-1}):
    so the plant gets nothing over [t_0, t_1), the law with the connectors' initial zeros over [t_1, t_2), then
    law(t_k, x_{k-1}).
    """

    def __init__(self, inner) -> None:
        self.inner, self.sample_time, self.input_names = inner, inner.sample_time, inner.input_names
        self.prev = None

    def reset(self) -> None:
        self.inner.reset()
        self.prev = None

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        if self.prev is None:
            self.prev = np.zeros_like(x)
            return np.zeros(len(self.input_names))
        out = np.asarray(self.inner(t, self.prev))
        self.prev = x.copy()
        return out


@pytest.mark.parametrize("case", [("tvlqr", "pendubot", 2), ("lqr", None, 2)])
def test_fmpy_ssp_importer_runs_it(loops, tmp_path, case):
    """A third-party SSP importer: fmpy.ssp (FMI 1/2 only) validates the SSD against its own copy of the schema,
    loads both FMUs and runs the loop with its Jacobi master; equal to pendulab.cosim of that master's loop."""
    from fmpy.ssp.simulation import simulate_ssp

    res = loops[case]
    out = simulate_ssp(str(res.path), stop_time=res.stop_time, step_size=res.sample_time)
    name, task, _ = case
    ctrl, x0, _model = design_controller(name, task, kind="elastic" if name == "lqr" else "rigid")
    with zipfile.ZipFile(res.path) as z:
        (tmp_path / "plant.fmu").write_bytes(z.read("resources/plant.fmu"))
    traj = cosim(tmp_path / "plant.fmu", _JacobiDelayed(ctrl), res.sample_time, res.stop_time, x0=x0)
    x = np.column_stack([out[f"plant.{n}"] for n in res.state_names])  # row k: after the step to t_{k+1}
    n = min(len(x), len(traj.x) - 1)
    assert n >= round(res.stop_time / res.sample_time) - 1
    # same plant binary, same torques (to rounding): rounding amplified over the run (measured <= 8e-14)
    assert np.max(np.abs(x[:n] - traj.x[1 : n + 1])) <= 1e-9
    if task:  # with fmpy's one-sample delay the pendubot still swings up and balances
        np.testing.assert_allclose(np.cos(x[n - 1][:2]), [-1.0, -1.0], atol=1e-6)

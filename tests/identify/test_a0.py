"""The second robot, RealAIGym's design A.0: its shipped records, DFKI's sets, and an identification on it."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.identify.datasets import A0_SWINGUP, A0_SYSID, SHIPPED_COLUMNS, a0_record
from pendulab.identify.fit import fit_regression, normals, realize
from pendulab.identify.pipeline import STRUCTURES, choose_structure, compare_structures, structure_base
from pendulab.identify.preprocess import DEFAULT_CUTOFF_HZ, common_interval, prepare, quantum
from pendulab.identify.published import A0_GEOMETRY, DFKI_A0
from pendulab.identify.records import REALAIGYM_COLUMNS, REALAIGYM_COMMAND_COLUMNS
from pendulab.identify.regressor import STANDARD_NAMES, robot_to_standard, standard_to_robot
from pendulab.identify.validation import standard_vector
from pendulab.model.plant_file import IdentifiedPlant
from pendulab.model.robot import check_robot_params

#: (count, duration [s], median interval [s]) of each kind of shipped A.0 record, read off the upstream files.
KINDS = {"sysid": (8, 10.0, 0.002), "sysid_11": (1, 6.0, 0.0015), "swingup": (3, 20.0, 0.0025)}


def _kind(stamp: str) -> str:
    return "swingup" if stamp in A0_SWINGUP else ("sysid_11" if stamp.endswith("_11") else "sysid")


@pytest.mark.parametrize("stamp", A0_SYSID + A0_SWINGUP)
def test_shipped_a0_records_load_with_the_robots_columns_and_sampling(stamp):
    rec = a0_record(stamp)
    n = rec.t.size
    assert rec.q.shape == rec.tau.shape == rec.qd.shape == (n, 2)
    assert all(np.isfinite(a).all() for a in (rec.t, rec.q, rec.tau, rec.qd))
    _, duration, interval = KINDS[_kind(stamp)]
    assert rec.duration == pytest.approx(duration, abs=0.01)  # the last sample lands within a few ms of the nominal end
    assert np.median(np.diff(rec.t)) == pytest.approx(interval, rel=0.01)  # float32 stamps and loop jitter: well under 1 %
    # Same sensors as C.1: encoder step 12.5 rad / 2^15, torque-reading step 5.86e-3 N.m.
    assert quantum(rec.q[:, 0]) == pytest.approx(12.5 / 2**15, rel=1e-4)  # float32 storage: 1e-7 relative
    reading = a0_record(stamp, REALAIGYM_COLUMNS).tau
    assert quantum(reading[:, 0]) == pytest.approx(5.86081e-3, rel=1e-4)  # float32 storage: 1e-7 relative
    # The default input is the command, which is not a reading: no step (its values are continuous).
    assert quantum(rec.tau[:, 1]) < 1e-4  # a reading would step by 5.9e-3; the command's gaps are float32 noise-sized


def test_the_archive_holds_realaigyms_columns_and_the_kinds_add_up():
    assert (len(A0_SYSID), len(A0_SWINGUP)) == (9, 3)
    assert sum(k[0] for k in KINDS.values()) == 12
    rec = a0_record(A0_SYSID[0], REALAIGYM_COMMAND_COLUMNS)
    assert rec.tau.shape[1] == 2 and len(SHIPPED_COLUMNS) == 9
    with pytest.raises(KeyError, match="unknown A.0 record"):
        a0_record("20220815-trajectory_06")  # not in the upstream repository (absent blob)


def test_the_swingups_drive_the_shoulder_and_only_compensate_the_elbows_friction():
    for stamp in A0_SWINGUP:
        con = a0_record(stamp, REALAIGYM_COMMAND_COLUMNS).tau
        # Pendubot: the shoulder command saturates at the controller's 5 N.m limit ...
        assert np.abs(con[:, 0]).max() == pytest.approx(5.0, abs=1e-6)  # float32 of exactly 5.0
        # ... the elbow gets only friction compensation: at most 0.1719 N.m in the three records.
        assert np.abs(con[:, 1]).max() < 0.175  # margin over the largest, 0.1719 N.m, for float32 storage and no more


@pytest.mark.parametrize(
    ("name", "margin1", "margin2"),
    [("1.0", 0.00874, 0.0078597), ("2.0", 0.0031266, 0.0035126), ("2.1", 0.0031266, 0.0035126)],
)
def test_dfki_a0_sets_are_physically_consistent(name, margin1, margin2):
    # Unlike C.1's 2.0 and 3.0, every A.0 set has each link's inertia about its joint above m r^2:
    # the inertia about the centre of mass, I - m r^2, is positive (values from the published yml files).
    p = check_robot_params(DFKI_A0[name])
    assert p["I1"] - p["m1"] * p["r1"] ** 2 == pytest.approx(margin1, rel=1e-4)  # the published digits, rounded to 5
    assert p["I2"] - p["m2"] * p["r2"] ** 2 == pytest.approx(margin2, rel=1e-4)  # the published digits, rounded to 5
    assert (p["l1"], p["l2"]) == (A0_GEOMETRY["l1"], A0_GEOMETRY["l2"])


# --- An identification on A.0: the pipeline up to its consistent regression (structure choice, fit, physical
# realization). The output-error refinement takes most of a minute, too slow here; benchmarks/bench_identify_a0.py
# judges the whole pipeline. Its refined model fits angles, not torques: measured there, its held-out torque
# residual is below every DFKI set's on the elbow for 8 of 9 records but on the shoulder only for 1 (DFKI 2.0 is
# within 0.02 N.m), and on the swing-ups on neither joint (0.623 / 0.220 against DFKI 2.0's 0.601 / 0.173 N.m).

PRIOR = robot_to_standard(DFKI_A0["1.0"])


def _dfki_rms(nrm) -> np.ndarray:
    """Torque residual RMS of each DFKI A.0 set, shape (3, 2) [N.m]."""
    return np.array([nrm.rms(standard_vector(p)) for p in DFKI_A0.values()])


def test_the_consistent_regression_on_eight_sysid_records_beats_every_dfki_set_on_the_ninth():
    held, rest = a0_record(A0_SYSID[0]), [a0_record(s) for s in A0_SYSID[1:]]
    grid = common_interval(rest)  # trajectory_11 (1.5 ms) goes onto the others' 2 ms grid
    assert grid == pytest.approx(0.002, rel=1e-3)  # float32 stamps: 2.0001 ms
    preps = [prepare(r, dt=grid) for r in rest]
    data = [normals(p, A0_GEOMETRY) for p in preps]
    chosen = choose_structure(compare_structures(data, preps, A0_GEOMETRY, PRIOR, DEFAULT_CUTOFF_HZ))
    assert chosen.name == "+rotor"  # as on all nine (benchmarks/results/identify_a0.md)
    free = dict(STRUCTURES)[chosen.name]
    fit = fit_regression(data, free, PRIOR)
    base = structure_base(preps, free, A0_GEOMETRY)
    pi = realize(base, base.beta(fit.pi), PRIOR, free)
    plant = IdentifiedPlant(params=standard_to_robot(pi, A0_GEOMETRY), structure=free)  # validates: raises if unphysical
    p = plant.params
    assert p["I1"] > p["m1"] * p["r1"] ** 2 and p["I2"] > p["m2"] * p["r2"] ** 2  # strictly: 0.0093 and 0.0019 kg.m2 above
    held_out = normals(prepare(held), A0_GEOMETRY)
    ours = held_out.rms(np.array([pi[n] for n in STANDARD_NAMES]))
    dfki = _dfki_rms(held_out)
    # Measured: 0.146 / 0.060 N.m against the best DFKI set per joint, 0.164 (2.0) / 0.207 (1.0) N.m.
    assert (ours < dfki.min(axis=0)).all(), (ours, dfki)


def test_leave_one_out_regression_beats_dfkis_best_set_pooled_and_on_eight_of_nine_records():
    records = [a0_record(s) for s in A0_SYSID]
    grid = common_interval(records)
    fitted = [normals(prepare(r, dt=grid), A0_GEOMETRY) for r in records]  # every fold's eight share this grid
    judged = [normals(prepare(r), A0_GEOMETRY) for r in records]  # a held-out record on its own grid
    free = dict(STRUCTURES)["+rotor"]
    sq, sq_dfki, n, below = np.zeros(2), np.zeros((3, 2)), 0, []
    for k, nrm in enumerate(judged):
        fit = fit_regression([d for i, d in enumerate(fitted) if i != k], free, PRIOR)
        ours, dfki = nrm.rms(fit.vector()), _dfki_rms(nrm)
        sq += nrm.n * ours**2
        sq_dfki += nrm.n * dfki**2
        n += nrm.n
        below.append(bool((ours < dfki.min(axis=0)).all()))
    pooled, pooled_dfki = np.sqrt(sq / n), np.sqrt(sq_dfki / n)
    # Measured: 0.168 / 0.090 N.m against DFKI 2.0's 0.177 / 0.153 (the best set on both joints).
    assert (pooled < pooled_dfki.min(axis=0)).all(), (pooled, pooled_dfki)
    # The one exception: trajectory_11's shoulder (0.156 against DFKI 2.0's 0.142 N.m).
    assert sum(below) >= 8, dict(zip(A0_SYSID, below, strict=True))


class _CapturedError(Exception):
    """Raised by the stand-in identification to end the command once its arguments are seen."""


def test_the_cli_dataset_a0_takes_a0s_records_geometry_prior_and_input(monkeypatch):
    import pendulab.identify.pipeline as pipeline
    from pendulab.cli import main

    seen = {}

    def fake_identify(records, fixed, prior, **kwargs):
        seen.update(records=records, fixed=fixed, prior=prior, meta=kwargs["meta"])
        raise _CapturedError

    monkeypatch.setattr(pipeline, "identify", fake_identify)
    with pytest.raises(_CapturedError):
        main(["identify", "--dataset", "a0", "--no-progress"])
    assert [r.name for r in seen["records"]] == list(A0_SYSID)
    assert seen["fixed"] == dict(A0_GEOMETRY)
    assert seen["prior"]["m1"] == DFKI_A0["1.0"]["m1"]
    assert seen["meta"]["prior"].startswith("DFKI A.0")
    # The default input of A.0 is the command: the shoulder of the elbow-only runs reads exactly zero.
    assert np.abs(seen["records"][-1].tau[:, 0]).max() == 0.0
    with pytest.raises(_CapturedError):
        main(["identify", "--dataset", "a0", "--input", "meas", "--no-progress"])
    assert np.abs(seen["records"][-1].tau[:, 0]).max() > 0.4  # the reading: up to 0.53 N.m where the command is zero

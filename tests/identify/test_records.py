"""Bad records get a clear error naming the record and what is wrong; good ones read exactly."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.identify.datasets import C1_BLIND, C1_EXCITATION, c1_record
from pendulab.identify.preprocess import prepare, quantum
from pendulab.identify.records import ColumnMap, RecordError, make_record, read_record

HEADER = "time,pos_meas1,pos_meas2,vel_meas1,vel_meas2,tau_meas1,tau_meas2"


def _write(tmp_path, rows, header=HEADER, name="rec.csv"):
    path = tmp_path / name
    path.write_text(header + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return path


def _rows(n=200, dt=0.002):
    t = np.arange(n) * dt
    return [[ti, 0.1 * np.sin(ti), 0.2 * np.cos(ti), 0.0, 0.0, 0.05, -0.05] for ti in t]


def test_a_good_file_reads_back_exactly(tmp_path):
    rows = _rows()
    rec = read_record(_write(tmp_path, rows))
    assert rec.q.shape == (200, 2)
    assert np.array_equal(rec.q[:, 0], np.array([r[1] for r in rows]))
    assert np.array_equal(rec.tau[:, 1], np.array([r[6] for r in rows]))


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda rows: rows[:1], "at least 50"),
        (
            lambda rows: [r if i != 7 else [r[0], float("nan"), *r[2:]] for i, r in enumerate(rows)],
            "'pos_meas1' is not finite at row 7",
        ),
        (lambda rows: [r if i != 9 else [rows[8][0], *r[1:]] for i, r in enumerate(rows)], "time repeats at row 9"),
        (lambda rows: [r if i != 9 else [rows[5][0], *r[1:]] for i, r in enumerate(rows)], "time goes backwards at row 9"),
        (lambda rows: [], "at least 50"),
    ],
    ids=["one-sample", "nan", "duplicate-time", "non-monotonic", "header-only"],
)
def test_bad_records_raise_a_clear_error(tmp_path, edit, message):
    with pytest.raises(RecordError, match=message):
        read_record(_write(tmp_path, edit(_rows())))


def test_missing_columns_are_all_named(tmp_path):
    path = _write(tmp_path, [r[:5] for r in _rows()], header="time,pos_meas1,pos_meas2,vel_meas1,vel_meas2")
    with pytest.raises(RecordError, match=r"missing columns \['tau_meas1', 'tau_meas2'\]"):
        read_record(path)


def test_empty_file_and_no_file(tmp_path):
    empty = tmp_path / "empty.csv"
    empty.write_text("")
    with pytest.raises(RecordError, match="empty"):
        read_record(empty)
    with pytest.raises(FileNotFoundError):
        read_record(tmp_path / "nope.csv")


def test_a_general_column_map_reads_anyones_names(tmp_path):
    header = "t,a,b,u,v"
    rows = [[r[0], r[1], r[2], r[5], r[6]] for r in _rows()]
    cols = ColumnMap(time="t", angles=("a", "b"), torques=("u", "v"))
    rec = read_record(_write(tmp_path, rows, header=header), cols)
    assert np.array_equal(rec.tau[:, 0], np.array([r[3] for r in rows]))


def test_saturated_records_are_refused_and_saturated_samples_dropped():
    t = np.arange(1000) * 0.002
    q = np.column_stack([np.sin(t), np.cos(t)])
    tau = np.column_stack([np.full(t.size, 1.0), np.zeros(t.size)])
    with pytest.raises(RecordError, match="reach the torque limit"):
        prepare(make_record("sat", t, q, tau), torque_limit=(1.0, 1.0))
    tau[:] = 0.2
    tau[500:520, 0] = 1.0  # a short saturated burst
    prep = prepare(make_record("burst", t, q, tau), torque_limit=(1.0, 1.0))
    edge = 125  # two periods of the 8 Hz cutoff at 2 ms: the filter's reach
    assert not prep.use[500 - edge : 520 + edge].any()  # the burst and a filter length around it are out
    assert prep.use[edge : 500 - edge - 1].all() and prep.use[520 + edge + 1 : 1000 - edge].all()


def test_bad_preprocessing_arguments():
    t = np.arange(1000) * 0.002
    rec = make_record("r", t, np.zeros((1000, 2)), np.zeros((1000, 2)))
    with pytest.raises(ValueError, match="cutoff_hz must be in"):
        prepare(rec, cutoff_hz=300.0)  # above Nyquist (250 Hz)
    with pytest.raises(ValueError, match="torque_limit"):
        prepare(rec, torque_limit=(1.0, -1.0))


def test_shipped_c1_records_carry_the_robots_quantization():
    assert len(C1_EXCITATION) == 8 and len(C1_BLIND) == 2
    rec = c1_record(C1_EXCITATION[0])
    # The encoder step of C.1's motors (CubeMars AK80-6, 12.5 rad over 2^15 counts): 3.815e-4 rad.
    assert quantum(rec.q[:, 0]) == pytest.approx(12.5 / 2**15, rel=1e-4)  # float32 storage: 1e-7 relative
    assert np.diff(rec.t).min() > 0.0019 and np.diff(rec.t).max() < 0.004
    with pytest.raises(KeyError, match="unknown C.1 record"):
        c1_record("20230629-000000")

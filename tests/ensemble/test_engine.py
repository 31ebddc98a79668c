"""pendulab.ensemble: batch runs against single runs, per-lane events, threads, results, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pendulab as pl
from pendulab.ensemble import EnsembleResult, Event
from pendulab.ensemble.engine import local_chunk_size

hy = pytest.importorskip("heyoka")

TOL = 1e-12


@pytest.fixture(scope="module")
def model():
    return pl.rigid()


def _single_flip_time(model, x0, t_final):
    """Independent reference: heyoka *scalar* mode, four separate events theta_i = +-pi."""
    from pendulab.integrate.taylor import compiled_integrator, structure_key

    system, _ = compiled_integrator(structure_key(model.kind, model.p, (0, 1), TOL))
    th1, th2 = (v for v, _ in system.sys[:2])
    evs = [hy.t_event(e) for e in (th1 - math.pi, th1 + math.pi, th2 - math.pi, th2 + math.pi)]
    ta = hy.taylor_adaptive(system.sys, list(x0), pars=system.pars([0.0, 0.0], model.p), tol=TOL, t_events=evs)
    out = ta.propagate_until(t_final)
    return np.nan if out[0] == hy.taylor_outcome.time_limit else ta.time


def test_ensemble_equals_single_simulate_runs(model):
    x0 = np.array([[1.0, 1.5, 0.0, 0.0], [2.0, 2.0, 0.0, 0.0], [0.5, -0.3, 1.0, -1.0], [1.0, 1.5, 0.0, 0.0]])
    m2 = np.array([1.0, 1.0, 0.7, 2.0])
    res = pl.ensemble(model, x0, 3.0, params={"m2": m2}, threads=2)
    assert isinstance(res, EnsembleResult) and list(res.status) == ["ok"] * 4
    for i in range(4):
        traj = pl.simulate(model.with_params(m2=m2[i]), x0[i], 3.0, method="taylor", rtol=TOL, atol=TOL)
        # Same translated ODE and step sequence; SIMD vs scalar libm differ at the rounding level.
        np.testing.assert_allclose(res.x_final[i], traj.x[-1], rtol=0, atol=1e-12)
    assert np.all(res.t_final == 3.0)


def test_params_array_in_param_names_order_equals_mapping(model):
    x0 = np.array([1.0, 1.2, 0.0, 0.0])
    P = np.tile(model.p, (3, 1))
    P[:, model.param_names.index("L2")] = [0.5, 1.0, 1.5]
    a = pl.ensemble(model, x0, 2.0, params=P, threads=1)
    b = pl.ensemble(model, x0, 2.0, params={"L2": [0.5, 1.0, 1.5]}, threads=1)
    np.testing.assert_array_equal(a.x_final, b.x_final)  # same runs, same lanes: bitwise


def test_flip_times_are_per_lane_and_equal_single_runs(model):
    # Lane 0 flips almost at once; the others later, at different times, or never.
    x0 = np.array(
        [
            [3.0, 0.0, 3.0, 0.0],
            [2.0, 2.0, 0.0, 0.0],
            [1.8, 2.2, 0.0, 0.0],
            [2.2, 1.6, 0.0, 0.0],
            [0.3, 0.2, 0.0, 0.0],
            [2.5, 2.5, 0.0, 0.0],
            [-2.0, 2.4, 0.0, 0.0],
            [2.9, -1.0, 0.0, 0.0],
            [1.0, 2.9, 0.0, 0.0],
            [2.6, 2.0, 0.0, 0.0],
        ]
    )
    t_final = 4.0
    res = pl.ensemble(model, x0, t_final, events=["flip"], threads=1)
    t_flip = res.event_times["flip"]
    ref = np.array([_single_flip_time(model, x, t_final) for x in x0])
    np.testing.assert_array_equal(np.isnan(t_flip), np.isnan(ref))
    assert t_flip[0] < 0.5 and np.nanmax(t_flip) > 1.0  # one early lane did not stop the others
    # Chaotic amplification of rounding differences over <= 4 s stays far below 1e-9.
    np.testing.assert_allclose(t_flip[~np.isnan(ref)], ref[~np.isnan(ref)], rtol=0, atol=1e-9)
    flipped = ~np.isnan(t_flip)
    assert np.all(res.status[flipped] == "event") and np.all(res.status[~flipped] == "ok")
    np.testing.assert_array_equal(res.t_final[flipped], t_flip[flipped])
    np.testing.assert_allclose(np.max(np.abs(res.x_final[flipped, :2]), axis=1), math.pi, rtol=0, atol=1e-12)
    assert np.all(res.terminal_event[flipped] == "flip")


def test_recorded_event_is_first_crossing_and_run_goes_on(model):
    x0 = np.array([[1.0, 1.0, 0.0, 0.0], [0.5, -0.5, 0.0, 0.0], [1.5, 0.0, 0.5, 0.0]])
    ev = [
        Event("theta1_zero", "theta1", value=0.0, terminal=False),
        Event("down", lambda x, p: x[2], terminal=False, direction=1),
    ]
    res = pl.ensemble(model, x0, 3.0, events=ev, threads=1)
    assert list(res.status) == ["ok"] * 3 and np.all(res.t_final == 3.0)
    t0 = res.event_times["theta1_zero"]
    assert np.all(np.isfinite(t0))
    for i in range(3):
        traj = pl.simulate(model, x0[i], t0[i], dt=t0[i], method="taylor", rtol=TOL, atol=TOL)
        assert abs(traj.x[-1, 0]) < 1e-10  # the event time is the zero of theta1 (root accuracy)
        # First crossing: no zero of theta1 earlier (dense check).
        dense = pl.simulate(model, x0[i], t0[i], dt=t0[i] / 400, method="taylor", rtol=TOL, atol=TOL)
        assert np.all(np.sign(dense.x[:-2, 0]) == np.sign(x0[i, 0]))
    # omega1 upward crossing of 0 after starting at rest with theta1 > 0 happens after the first swing.
    assert np.all(res.event_times["down"] > t0)


def test_t_eval_matches_simulate_grid_and_is_nan_after_stop(model):
    x0 = np.array([[1.0, 1.5, 0.0, 0.0], [3.0, 0.0, 3.0, 0.0]])
    te = np.linspace(0.0, 2.0, 21)
    res = pl.ensemble(model, x0, 2.0, t_eval=te, events=["flip"], threads=1)
    traj = pl.simulate(model, x0[0], 2.0, dt=0.1, method="taylor", rtol=TOL, atol=TOL)
    np.testing.assert_allclose(res.x[0], traj.x, rtol=0, atol=1e-12)  # dense output vs steps landing on grid
    after = te > res.t_final[1]
    assert np.all(np.isnan(res.x[1, after])) and np.all(np.isfinite(res.x[1, ~after]))


def test_threads_and_chunks_do_not_change_results(model):
    rng = np.random.default_rng(3)
    x0 = np.zeros((40, 4))
    x0[:, :2] = rng.uniform(-3, 3, (40, 2))
    a = pl.ensemble(model, x0, 2.0, events=["flip"], threads=1)
    seen = []
    b = pl.ensemble(model, x0, 2.0, events=["flip"], threads=2, chunk_size=8, progress=lambda d, t: seen.append((d, t)))
    # Another chunking puts runs in other SIMD lanes, next to other runs: each lane's arithmetic (and its
    # double-length time) is its own, so the results are the same to the last bit, at any batch width.
    c = pl.ensemble(model, x0, 2.0, events=["flip"], threads=1, chunk_size=5, batch_size=2)
    for other in (b, c):
        np.testing.assert_array_equal(a.x_final, other.x_final)
        np.testing.assert_array_equal(a.event_times["flip"], other.event_times["flip"])
    # The chunking is a pure function of (n, chunk_size, batch_size, threads), never of the host.
    assert b.stats["chunk_size"] == local_chunk_size(40, 8, b.stats["batch_size"], 2)
    assert seen[-1] == (40, 40) and b.stats["n_chunks"] == math.ceil(40 / b.stats["chunk_size"])


def test_table_and_npz(model, tmp_path):
    res = pl.ensemble(model, [[1.0, 1.0, 0.0, 0.0], [3.0, 0.0, 3.0, 0.0]], 1.0, events=["flip"], threads=1)
    tab = res.table()
    assert tab["status"].tolist() == ["ok", "event"] and "t_flip" in tab.dtype.names and "m2" in tab.dtype.names
    np.testing.assert_array_equal(tab["theta1"], res.x_final[:, 0])
    res.to_npz(tmp_path / "e.npz")
    with np.load(tmp_path / "e.npz") as z:
        np.testing.assert_array_equal(z["event_time_flip"], res.event_times["flip"])
        assert z["status"].tolist() == ["ok", "event"]


def test_elastic_output_event(model):
    el = pl.elastic(k1=200.0, k2=200.0)
    x0 = np.array([1.0, 1.0, 1.05, 1.05, 0.0, 0.0, 0.0, 0.0])
    res = pl.ensemble(el, x0, 1.0, params={"k1": [200.0, 300.0]}, events=[Event("low", "y2", value=-1.5, terminal=True)])
    for i, k1 in enumerate([200.0, 300.0]):
        t = res.event_times["low"][i]
        assert res.status[i] == "event"
        y2 = el.with_params(k1=k1).outputs(res.x_final[i])[el.output_names.index("y2")]
        assert abs(y2 + 1.5) < 1e-10 and 0 < t < 1.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"x0": np.zeros((0, 4))}, "empty"),
        ({"x0": np.zeros((3, 3))}, "x0 must have shape"),
        ({"x0": np.zeros((3, 4)), "params": {"m2": [1.0, 2.0]}}, "x0 has 3 runs but params has 2"),
        ({"x0": [[np.nan, 0, 0, 0]]}, "x0 must be finite"),
        ({"x0": np.zeros(4)}, "needs params"),
        ({"params": {"mass": [1.0]}}, "unknown parameter names \\['mass'\\]"),
        ({"params": {"m2": [1.0, -1.0]}, "x0": np.zeros(4)}, "inadmissible"),
        ({"params": np.ones((1, 3))}, "params must have shape"),
        ({"events": ["flop"]}, "unknown event 'flop'"),
        ({"events": [Event("e", "theta9")]}, "unknown signal 'theta9'"),
        ({"events": ["flip", "flip"]}, "duplicate event name"),
        ({"events": [Event("e", "theta1", direction=2)]}, "direction"),
        ({"t_eval": [0.0, 5.0]}, "t_eval"),
        ({"chunk_size": 0}, "chunk_size"),
        ({"threads": 0}, "threads"),
        ({"method": "nope"}, "method"),
        ({"t_final": -1.0}, "t_final"),
    ],
)
def test_bad_input_names_argument_and_value(model, kwargs, match):
    args = {"x0": np.zeros((1, 4)), "t_final": 1.0, **kwargs}
    with pytest.raises(ValueError, match=match):
        pl.ensemble(model, args.pop("x0"), args.pop("t_final"), **args)


def test_fallback_method_without_events(model):
    x0 = np.array([[1.0, 1.5, 0.0, 0.0], [0.2, 0.1, 0.0, 0.0]])
    a = pl.ensemble(model, x0, 1.0, method="cvodes", rtol=1e-10, atol=1e-10)
    b = pl.ensemble(model, x0, 1.0, threads=1)
    np.testing.assert_allclose(a.x_final, b.x_final, atol=1e-7)  # CVODES at 1e-10 over 1 s
    with pytest.raises(ValueError, match="events need method='taylor'"):
        pl.ensemble(model, x0, 1.0, method="cvodes", events=["flip"])


def test_shared_workers_run_ensembles_in_one_set_of_processes(model, monkeypatch):
    from pendulab.ensemble import chunks

    monkeypatch.setattr(chunks, "_PROCESS_MIN_RUNS", 8)  # worker processes for a test-sized ensemble
    rng = np.random.default_rng(5)
    x0 = np.zeros((40, 4))
    x0[:, :2] = rng.uniform(-3, 3, (40, 2))
    alone = pl.ensemble(model, x0, 2.0, events=["flip"], threads=2, chunk_size=8)
    workers = []
    with chunks.shared_workers():
        first = pl.ensemble(model, x0, 2.0, events=["flip"], threads=2, chunk_size=8)
        pool = chunks._SHARED.get().pool
        workers.append(dict(pool._processes))
        second = pl.ensemble(model, x0[::-1], 2.0, events=["flip"], threads=2, chunk_size=8)
        workers.append(dict(chunks._SHARED.get().pool._processes))
    assert len(workers[0]) == 2 and workers[0].keys() == workers[1].keys()  # the same two processes ran both
    assert not any(p.is_alive() for p in workers[0].values())  # and ended with the block
    assert chunks._SHARED.get() is None
    # Same chunks in the same lanes: bitwise the results of an ensemble with its own pool.
    np.testing.assert_array_equal(first.event_times["flip"], alone.event_times["flip"])
    np.testing.assert_array_equal(second.event_times["flip"], alone.event_times["flip"][::-1])  # other lanes, same bits
    assert np.isfinite(alone.event_times["flip"]).sum() >= 10  # the runs flip: the comparison has content

"""Ensembles and flip maps under bad input, budgets, missing extras and interrupted studies.

Every check goes through the shared layer (``pendulab._checks``): a wrong model type is a
TypeError, tolerances live in (0, 1), elastic springs have positive length, sizes are bounded
with a reason, and a run that ends badly says why in its status and message.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

import pendulab as pl
from pendulab._checks import MissingExtraError
from pendulab.cli import main
from pendulab.ensemble import EnsembleResult
from pendulab.ensemble.flipmap import FlipMap, flip_map
from pendulab.ensemble.lyapunov import largest_lyapunov

hy = pytest.importorskip("heyoka")


@pytest.fixture(scope="module")
def rigid() -> pl.Model:
    return pl.rigid()


# -- checks through the shared layer ------------------------------------------------------
def test_model_must_be_a_model(rigid: pl.Model) -> None:
    with pytest.raises(TypeError, match="model must be a pendulab Model, got str"):
        pl.ensemble("rigid", [[1.0, 1.0, 0.0, 0.0]], 1.0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="model must be a pendulab Model, got str"):
        flip_map("rigid", 5, 1.0)


def test_elastic_start_with_nonpositive_spring_is_refused() -> None:
    el = pl.elastic()
    x0 = np.tile(el.rest_state(), (3, 1))
    x0[1, 2] = -1.0
    with pytest.raises(ValueError, match=r"x0\[1\]: spring lengths r1, r2 must be > 0 m, got \[-1.0"):
        pl.ensemble(el, x0, 1.0)


def test_spring_through_zero_length_fails_its_lane_only() -> None:
    el = pl.elastic(k1=200.0, k2=200.0)
    crash = el.rest_state()
    crash[6] = -30.0  # v1: link 1's bob thrown at its pivot
    x0 = np.array([crash, el.rest_state(), el.rest_state()])
    with pytest.raises(pl.SimulationError, match="spring length r1"):
        pl.simulate(el, crash, 1.0, method="taylor")  # the rule the ensemble follows
    res = pl.ensemble(el, x0, 1.0, threads=1)
    assert res.status.tolist() == ["failed", "ok", "ok"]
    assert "spring length r1 reached 0 m" in res.message[0]
    assert 0.0 < res.t_final[0] < 0.1 and abs(res.x_final[0, 2]) < 1e-9  # stopped at the crossing (event root)
    # The hanging runs were not disturbed by the lane that stopped: still at rest after 1 s.
    np.testing.assert_allclose(res.x_final[1:], x0[1:], rtol=0, atol=1e-9)  # rest state to the solver tolerance


@pytest.mark.parametrize("rtol", [1.0, 10.0, 0.0, -1e-3])
def test_rtol_outside_unit_interval_is_refused_everywhere(rigid: pl.Model, rtol: float) -> None:
    with pytest.raises(ValueError, match="rtol"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]], 1.0, rtol=rtol)
    with pytest.raises(ValueError, match="rtol"):
        flip_map(rigid, 5, 1.0, rtol=rtol)
    with pytest.raises(ValueError, match="rtol"):
        largest_lyapunov(rigid, [2.0, 2.0, 0.0, 0.0], 1.0, rtol=rtol)


def test_tolerance_below_double_epsilon_is_refused_before_compiling(rigid: pl.Model) -> None:
    # rtol = 1e-100 used to compile a Taylor order of ~117 for 86 s (uninterruptible) for no extra digit.
    with pytest.raises(ValueError, match=r"rtol = 1e-100: out of range; expected a finite number in \[2.22e-16, 1\)"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]], 1.0, rtol=1e-100)
    with pytest.raises(ValueError, match=r"atol must be at least 2.22e-16"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]], 1.0, atol=1e-20)
    with pytest.raises(ValueError, match=r"rtol = 1e-300: out of range; expected a finite number in \[2.22e-16, 1\)"):
        largest_lyapunov(rigid, [2.0, 2.0, 0.0, 0.0], 1.0, rtol=1e-300)


def test_cli_rtol_one_or_more_is_a_one_line_error(tmp_path, capsys) -> None:
    status = main(["ensemble", "flipmap", "--grid", "4", "--rtol", "100", "--out", str(tmp_path / "o"), "--no-progress"])
    err = capsys.readouterr().err.strip()
    assert status == 2 and len(err.splitlines()) == 1 and "--rtol = '100'" in err and "[2.22e-16, 1)" in err


def test_inertia_rule_is_checked_per_run(rigid: pl.Model) -> None:
    # Run 0: lc2 = 0 with I2 = 0.1; run 1: lc2 = 0.5 with I2 = 0. Each has link-2 inertia; the column
    # extremes (lc2 = 0, I2 = 0) would not, so a column-wise check refused two valid runs.
    res = pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]] * 2, 1.0, params={"lc2": [0.0, 0.5], "I2": [0.1, 0.0]}, threads=1)
    assert res.status.tolist() == ["ok", "ok"]
    for i, (lc2, i2) in enumerate([(0.0, 0.1), (0.5, 0.0)]):
        traj = pl.simulate(rigid.with_params(lc2=lc2, I2=i2), [1.0, 1.0, 0.0, 0.0], 1.0, method="taylor", rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(res.x_final[i], traj.x[-1], rtol=0, atol=1e-10)  # same ODE, SIMD vs scalar, 1 s
    with pytest.raises(ValueError, match=r"params: run 1 is inadmissible .*inertia"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]] * 2, 1.0, params={"lc2": [0.5, 0.0], "I2": [0.0, 0.0]})


def test_sizes_are_bounded_with_the_limit_named(rigid: pl.Model) -> None:
    with pytest.raises(ValueError, match=r"n_grid must be at most 20000 \(grid points per angle\)"):
        flip_map(rigid, 10**6, 1.0)
    with pytest.raises(ValueError, match=r"n1 \* n2 must be at most 16000000"):
        flip_map(rigid, (10000, 10000), 1.0)
    with pytest.raises(ValueError, match=r"max_steps = 1099511627776: out of range; expected an integer in \[1, 2147483647\]"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]], 1.0, max_steps=2**40)
    with pytest.raises(ValueError, match=r"len\(x0\) \* len\(t_eval\) must be at most"):
        pl.ensemble(rigid, np.zeros((2000, 4)), 1.0, t_eval=np.linspace(0, 1, 10**6))


def test_worker_and_event_counts_are_bounded(rigid: pl.Model) -> None:
    from pendulab.ensemble import Event, map_runs

    # threads=10**6 on a big ensemble used to mean one forked process per chunk: hundreds of thousands.
    with pytest.raises(ValueError, match=r"threads = 1000000: out of range; expected an integer in \[1, 256\]"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]], 1.0, threads=10**6)
    with pytest.raises(ValueError, match=r"workers = 1000000: out of range; expected an integer in \[1, 256\]"):
        map_runs(abs, range(4), workers=10**6)
    with pytest.raises(ValueError, match=r"number of events must be at most 64"):
        pl.ensemble(rigid, [[1.0, 1.0, 0.0, 0.0]], 1.0, events=[Event(f"e{i}", "theta1", value=0.01 * i) for i in range(65)])


# -- budgets ------------------------------------------------------------------------------
def test_step_budget_fails_runs_with_a_message(rigid: pl.Model) -> None:
    # The reproducer that used to run for minutes: horizon 1e12 s.
    res = pl.ensemble(rigid, [[1.0, 0.5, 0.0, 0.0], [2.0, 2.0, 0.0, 0.0]], 1e12, max_steps=5000, threads=1)
    assert res.status.tolist() == ["failed", "failed"]
    assert all("step budget exhausted (max_steps = 5000 steps)" in m for m in res.message)
    assert res.stats["n_steps"] == 2 * 5000  # the budget is exact: slices end at the first lane's budget
    assert np.all(np.isfinite(res.x_final)) and np.all(res.t_final > 0)


def test_wall_time_budget_fails_the_rest(rigid: pl.Model) -> None:
    res = pl.ensemble(rigid, [[1.0, 0.5, 0.0, 0.0]] * 3, 1e12, max_steps=2**31 - 1, max_wall_time=0.2, threads=1)
    assert res.status.tolist() == ["failed"] * 3
    assert all("wall-time budget exhausted" in m for m in res.message)


@pytest.mark.parametrize("t_eval", [None, [0.0, 5.0]])
def test_wall_time_budget_names_every_run_of_a_chunk(rigid: pl.Model, t_eval) -> None:
    # More runs per chunk than lanes (40 runs, 2 lanes, chunks of 10), in the streaming loop (no grid) and the stepped
    # one: the runs in the lanes fail on the budget, the queued ones fail before they start; none is left without an
    # outcome or reported as something else (a lane refilled after the budget ran out once read "non-finite state").
    x0 = np.tile([1.0, 0.5, 0.0, 0.0], (40, 1))
    res = pl.ensemble(rigid, x0, 1e12, max_steps=2**31 - 1, max_wall_time=0.2, threads=1, batch_size=2, t_eval=t_eval)
    assert res.stats["chunk_size"] == 10 and res.status.tolist() == ["failed"] * 40
    ends = ("wall-time budget exhausted (max_wall_time)", "before the run started")
    assert all(m.endswith(ends) for m in res.message)
    unstarted = np.array([m.endswith("before the run started") for m in res.message])
    assert unstarted.sum() == 40 - 4 * 2  # each of the 4 chunks had its 2 lanes running when the budget ran out
    assert np.all(res.t_final[unstarted] == 0.0) and np.array_equal(res.x_final[unstarted], x0[unstarted])
    assert np.all(res.t_final[~unstarted] > 0.0)


def test_default_step_budget_bounds_the_huge_horizon(rigid: pl.Model) -> None:
    res = pl.ensemble(rigid, [[1.0, 0.5, 0.0, 0.0]], 1e12, threads=1)
    assert res.status.tolist() == ["failed"] and "max_steps = 1000000" in res.message[0]


def test_flip_map_budget_is_a_runtime_error(rigid: pl.Model) -> None:
    with pytest.raises(RuntimeError, match="step budget exhausted"):
        flip_map(rigid, 5, 1e12, max_steps=3000)


# -- outputs ------------------------------------------------------------------------------
def test_npz_round_trip_keeps_arrays_and_settings(rigid: pl.Model, tmp_path) -> None:
    te = np.linspace(0.0, 1.0, 5)
    res = pl.ensemble(
        rigid, [[1.0, 1.0, 0.0, 0.0], [3.0, 0.0, 3.0, 0.0]], 1.0, events=["flip"], t_eval=te, threads=1, rtol=1e-10, batch_size=2
    )
    path = res.to_npz(tmp_path / "e")
    assert path.name == "e.npz"
    back = EnsembleResult.from_npz(path)
    for name in ("x_final", "t_final", "status", "message", "terminal_event", "x", "t_eval", "x0", "params"):
        np.testing.assert_array_equal(getattr(back, name), getattr(res, name))
    np.testing.assert_array_equal(back.event_times["flip"], res.event_times["flip"])
    assert back.state_names == res.state_names and back.param_names == res.param_names
    assert back.stats["rtol"] == 1e-10 and back.stats["batch_size"] == 2 and back.stats["pendulab_version"] == pl.__version__
    with pytest.raises(ValueError, match="not an ensemble result"):
        np.savez(tmp_path / "other.npz", a=np.zeros(2))
        EnsembleResult.from_npz(tmp_path / "other.npz")


def test_flip_map_npz_carries_its_settings(rigid: pl.Model, tmp_path) -> None:
    el = pl.elastic(k1=1000.0, k2=1000.0)
    fmap = flip_map(el, 5, 0.5, start="static", rtol=1e-10, threads=1, batch_size=2)
    back = FlipMap.load_npz(fmap.save_npz(tmp_path / "fm.npz"))
    assert back.settings["start"] == "static" and back.settings["rtol"] == 1e-10
    assert back.settings["batch_size"] == 2 and back.settings["pendulab_version"] == pl.__version__
    np.testing.assert_array_equal(back.t_flip, fmap.t_flip)


# -- long studies keep finished work --------------------------------------------------------
def test_interrupted_flip_map_resumes_to_the_same_map(rigid: pl.Model, tmp_path) -> None:
    ck = tmp_path / "fm.partial.npz"
    kw = {"threads": 1, "batch_size": 4, "block_size": 6}
    full = flip_map(rigid, (9, 7), 3.0, **kw)

    def stop_in_second_block(done: int, total: int) -> None:
        if done > 6:  # the first block (6 runs) is finished and recorded
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        flip_map(rigid, (9, 7), 3.0, checkpoint=ck, progress=stop_in_second_block, **kw)
    assert ck.exists()
    with np.load(ck) as z:
        assert int(z["done"].sum()) >= 6 and not z["done"].all()
    resumed = flip_map(rigid, (9, 7), 3.0, checkpoint=ck, resume=True, **kw)
    assert resumed.n_resumed >= 6 and resumed.n_simulated + resumed.n_resumed == full.n_simulated
    # Blocks and chunking are the same with or without the interruption: the same map, bit for bit.
    np.testing.assert_array_equal(resumed.t_flip, full.t_flip)
    with pytest.raises(ValueError, match="fm.partial.npz was written with other settings .*t_max"):
        flip_map(rigid, (9, 7), 2.0, checkpoint=ck, resume=True, **kw)


def test_cli_resume_continues_from_the_partial_file(tmp_path, capsys, monkeypatch) -> None:
    import pendulab.commands.ensemble as cmd

    fm_module = sys.modules["pendulab.ensemble.flipmap"]  # pendulab.ensemble.ensemble (the function) hides the path

    monkeypatch.setattr(cmd, "_BLOCK", 10)  # blocks of 10 runs, so this small map has several
    out = tmp_path / "o"
    argv = ["ensemble", "flipmap", "--grid", "9", "--t-max", "2", "--out", str(out), "--no-progress", "--threads", "1"]
    assert main(argv) == 0
    ref = FlipMap.load_npz(out / "flipmap.npz")
    assert not (out / "flipmap_rigid.partial.npz").exists()  # removed once the map is written
    real = flip_map

    def interrupted(*args, **kwargs):
        def stop(done, total):
            if done > 10:  # inside the second block: the first is recorded
                raise KeyboardInterrupt

        return real(*args, **{**kwargs, "progress": stop})

    monkeypatch.setattr(fm_module, "flip_map", interrupted)
    assert main(argv) == 130
    assert (out / "flipmap_rigid.partial.npz").exists()
    monkeypatch.setattr(fm_module, "flip_map", real)
    capsys.readouterr()
    assert main([*argv, "--resume"]) == 0
    assert "taken from the partial file" in capsys.readouterr().out
    np.testing.assert_array_equal(FlipMap.load_npz(out / "flipmap.npz").t_flip, ref.t_flip)


# -- missing extras -----------------------------------------------------------------------
def test_missing_heyoka_is_named(monkeypatch, tmp_path, capsys) -> None:
    monkeypatch.setitem(sys.modules, "heyoka", None)
    with pytest.raises(MissingExtraError, match=r"pendulab\[taylor\]"):
        pl.ensemble(pl.rigid(), [[1.0, 1.0, 0.0, 0.0]], 1.0)
    for argv in (
        ["ensemble", "flipmap", "--grid", "4", "--out", str(tmp_path / "o"), "--no-progress"],
        ["bench", "ensemble", "--grid", "4", "--out", str(tmp_path / "b.md")],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "pendulab[taylor]" in err, err


def test_missing_dask_is_named(monkeypatch, tmp_path, capsys) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)
    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    for argv in (
        ["ensemble", "flipmap", "--grid", "4", "--out", str(tmp_path / "o"), "--no-progress", "--scheduler", "tcp://127.0.0.1:1"],
        ["bench", "ensemble", "--grid", "4", "--out", str(tmp_path / "b.md"), "--workers", "1"],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "pendulab[dask]" in err, err

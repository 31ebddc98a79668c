"""The double-pendulum flip map: time to the first flip over a grid of release angles.

Every grid point (theta1, theta2) is released **at rest** and integrated until
either link flips over (``|theta1|`` or ``|theta2|`` reaches pi, the built-in
terminal ``"flip"`` event of :func:`pendulab.ensemble`) or ``t_max`` passes.
The result, :class:`FlipMap`, holds the 1-D grids and ``t_flip[i_theta1,
i_theta2]`` [s] (NaN where no flip happened before ``t_max``).

Two exact savings make the map cheap:

* **Energy threshold.** Without torques the mechanical energy E never grows
  (it is conserved, or dissipated by the dampers), and E >= V (kinetic energy
  is non-negative). A flip needs a configuration with ``|theta_i| = pi``, so a
  point released at rest with potential energy ``V0`` below

      V_flip = min { V(q) : |theta1| = pi  or  |theta2| = pi }

  can never flip (:func:`flip_energy_threshold` computes V_flip from the
  model's own potential-energy function). Rigid model, with
  ``a = (m1 lc1 + m2 L1) g`` and ``b = m2 lc2 g`` so that
  ``V = -a cos(theta1) - b cos(theta2)``: ``V_flip = min(a - b, b - a) = -|a - b|``;
  for unit masses and lengths ``V_flip = -g``, i.e. a point can flip only if
  ``2 cos(theta1) + cos(theta2) <= 1`` (69 % of the square; the rest is skipped).
* **Point symmetry.** The equations are odd in the angles (gravity potential
  even, no torques), so the point released at (-theta1, -theta2) moves as the
  mirror image of the one at (theta1, theta2) and flips at the same time. When
  the grid is antisymmetric (the default range), only one of each mirror pair
  is integrated.

The elastic model is released at rest with **quasi-static** spring lengths
(:func:`pendulab.model.quasistatic.quasi_static_state` at omega = 0: each
spring carries the gravity load along its link in that pose), so the flip map
compares link compliance and not an artificial spring oscillation started by
releasing the springs at their hanging lengths (``start="static"`` does that).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import bounded_int, check_model
from .._inputs import checked
from .._io import check_writable
from .flipmap_plot import plot_flip_map, plot_flip_map_compare
from .flipmap_release import MAX_GRID, flip_energy_threshold, flip_initial_states, flip_map_grid
from .flipmap_result import FlipMap, _block_digest, _load_checkpoint, _save_checkpoint

__all__ = [
    "FlipMap",
    "flip_map",
    "flip_map_grid",
    "flip_energy_threshold",
    "flip_initial_states",
    "plot_flip_map",
    "plot_flip_map_compare",
]

#: Largest number of grid points of the whole grid (each point holds a state and a time).
MAX_GRID_POINTS = 16_000_000
#: Runs per recorded block of :func:`flip_map` with a ``checkpoint`` (each block is saved when done).
DEFAULT_BLOCK = 10000


# -- the map --------------------------------------------------------------------
@checked()
def flip_map(
    model: Any,
    n_grid: int | tuple[int, int],
    t_max: float,
    *,
    theta_range: Sequence[float] = (-math.pi, math.pi),
    theta2_range: Sequence[float] | None = None,
    start: str = "quasi-static",
    skip_low_energy: bool = True,
    symmetry: bool | None = None,
    client: Any = None,
    threads: int | None = None,
    chunk_size: int = 2000,
    progress: Callable[[int, int], Any] | bool | None = None,
    rtol: float = 1e-12,
    batch_size: int | None = None,
    max_steps: int = 1_000_000,
    max_wall_time: float | None = None,
    checkpoint: str | Path | None = None,
    resume: bool = False,
    block_size: int = DEFAULT_BLOCK,
) -> FlipMap:
    """Time to the first flip for every release angle of a grid.

    Parameters
    ----------
    model : Model
        Rigid or elastic model (no torques are applied).
    n_grid : int or (int, int)
        Grid points per angle (n1 = n2), or ``(n1, n2)``; at most :data:`MAX_GRID` per angle and
        :data:`MAX_GRID_POINTS` in all.
    t_max : float
        Horizon [s] (> 0).
    theta_range : (float, float)
        Range of theta1 [rad] (and of theta2 unless ``theta2_range`` is given);
        the grid is cell-centred (:func:`flip_map_grid`).
    theta2_range : (float, float), optional
        Range of theta2 [rad].
    start : {"quasi-static", "static"}
        Elastic spring lengths at release (:func:`flip_initial_states`).
    skip_low_energy : bool
        Skip points whose release energy is below :func:`flip_energy_threshold`
        (exact: they cannot flip). Default True.
    symmetry : bool, optional
        Integrate one point of each mirror pair (theta1, theta2), (-theta1,
        -theta2). Default: when the grids are antisymmetric.
    client : dask.distributed.Client or str, optional
        Run on a Dask cluster (a client or a scheduler address "tcp://...").
    threads : int, optional
        Local threads (default: the engine's choice).
    chunk_size : int
        Runs per task.
    progress : callable(done, total) or bool, optional
        Progress reporting over all runs, as in :func:`pendulab.ensemble`.
    rtol : float
        Integration tolerance in (0, 1) (also the absolute tolerance).
    batch_size : int, optional
        SIMD lanes (see :func:`pendulab.ensemble`); default the host's, or ``PENDULAB_SIMD_SIZE``.
    max_steps : int
        Step budget of each run.
    max_wall_time : float, optional
        Wall-time budget of the whole map [s].
    checkpoint : str or Path, optional
        Partial-results file (``.npz``): the runs go in blocks of ``block_size``, and after each
        block the finished flip times are written there atomically. Removed when the map is done.
    resume : bool
        Continue from ``checkpoint``: blocks already recorded are not run again if they validate (a
        :mod:`pendulab._journal` header: pendulab version, model, grid and settings, and each block's
        SHA-256); a block that was edited or damaged, or a checkpoint of another pendulab version, is
        run again with a :class:`~pendulab._journal.JournalWarning`. A checkpoint of this version with
        other settings is an error. Without ``resume`` an existing checkpoint is overwritten.
    block_size : int
        Runs per recorded block (with ``checkpoint``). The blocks are the same with or without a
        resume, so a resumed map equals an uninterrupted one bit for bit.

    Returns
    -------
    FlipMap
        The map; ``t_flip[i, j]`` is NaN where no flip happened before ``t_max``.

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Bad grid, horizon, range, ``start``, ``rtol`` or budget; a checkpoint of other settings
        (:class:`~pendulab._journal.JournalError`).
    PermissionError
        Nothing can be written where ``checkpoint`` goes (checked before any run).
    RuntimeError
        An integration failed or a budget was spent (the engine's message says which).
    KeyboardInterrupt
        Ctrl-C; with ``checkpoint`` the finished blocks are kept.
    """
    from .batch import default_batch_size
    from .chunks import shared_workers
    from .engine import ensemble

    t0 = time.perf_counter()
    check_model(model)
    n1, n2 = (n_grid, n_grid) if not isinstance(n_grid, (tuple, list)) else tuple(n_grid)
    n1 = bounded_int("n_grid", n1, high=MAX_GRID, why="grid points per angle")
    n2 = bounded_int("n_grid", n2, high=MAX_GRID, why="grid points per angle")
    bounded_int("n_grid total points n1 * n2", n1 * n2, high=MAX_GRID_POINTS, why="memory of the states and flip times")
    if not (isinstance(t_max, (int, float, np.floating, np.integer)) and math.isfinite(t_max) and t_max > 0):
        raise ValueError(f"t_max must be a finite number > 0 [s], got {t_max!r}")
    tol = float(rtol)
    block = int(block_size)
    S = default_batch_size() if batch_size is None else batch_size
    th1 = flip_map_grid(n1, theta_range)
    th2 = flip_map_grid(n2, theta_range if theta2_range is None else theta2_range)
    T1, T2 = np.meshgrid(th1, th2, indexing="ij")
    x_all = flip_initial_states(model, T1.ravel(), T2.ravel(), start=start)
    threshold = flip_energy_threshold(model)
    V0 = np.asarray(model.potential_energy(x_all), dtype=float).reshape(n1, n2)
    # A margin at the rounding level of V, so a point exactly at the threshold is kept.
    margin = 1e-9 * (abs(threshold) + float(np.max(np.abs(V0))))
    skipped = V0 < threshold - margin if skip_low_energy else np.zeros((n1, n2), bool)
    antisym = np.array_equal(th1[::-1], -th1) and np.array_equal(th2[::-1], -th2)
    if symmetry is None:
        symmetry = antisym
    elif symmetry and not antisym:
        raise ValueError("symmetry=True needs grids symmetric about 0 (theta ranges (-a, a))")
    todo = ~skipped
    if symmetry:
        flat = np.arange(n1 * n2).reshape(n1, n2)
        todo &= flat <= flat[::-1, ::-1]  # the mirror of [i, j] is [n1-1-i, n2-1-j]
    idx = np.flatnonzero(todo.ravel())
    params = {k: float(v) for k, v in model.params.resolved().items()}
    settings = {
        "start": start,
        "rtol": tol,
        "atol": tol,
        "batch_size": int(S),
        "chunk_size": int(chunk_size),
        "threads": threads,
        "skip_low_energy": bool(skip_low_energy),
        "symmetry": bool(symmetry),
        "max_steps": int(max_steps),
        "theta1_range": [float(th1[0]), float(th1[-1])],
        "theta2_range": [float(th2[0]), float(th2[-1])],
        "block_size": block if checkpoint is not None else None,
    }
    # What a checkpoint must match to be resumed (the results depend on all of it, chunking included).
    identity = {"kind": model.kind, "params": params, "n1": n1, "n2": n2, "t_max": float(t_max), **settings}
    values = np.full(idx.size, np.nan)
    done = np.zeros(idx.size, bool)
    blocks = [(a, min(a + block, idx.size)) for a in range(0, idx.size, block)] if checkpoint is not None else [(0, idx.size)]
    n_resumed = 0
    digests: dict[str, str] = {}
    if checkpoint is not None:
        if Path(checkpoint).exists() and not Path(checkpoint).is_file():
            raise IsADirectoryError(f"checkpoint {checkpoint} exists and is not a file; remove it or choose another")
        check_writable(Path(checkpoint).parent)  # before the first block, not at its first save
    if checkpoint is not None and resume and Path(checkpoint).exists():
        # Only blocks that validate (pendulab version, settings, each block's SHA-256) are taken; the rest are run.
        values, done, digests = _load_checkpoint(Path(checkpoint), identity, idx.size, blocks)
        n_resumed = int(done.sum())
    report = _overall_progress(progress, idx.size, n_resumed)
    deadline = None if max_wall_time is None else time.perf_counter() + float(max_wall_time)
    try:
        with shared_workers():  # one set of worker processes for every block
            for a, b in blocks:
                if b <= a or done[a:b].all():
                    continue
                left = None if deadline is None else max(deadline - time.perf_counter(), 1e-9)
                base = int(done.sum())
                res = ensemble(
                    model,
                    x_all[idx[a:b]],
                    float(t_max),
                    events=["flip"],
                    method="taylor",
                    client=client,
                    threads=threads,
                    chunk_size=chunk_size,
                    rtol=tol,
                    atol=tol,
                    progress=lambda d, _n, base=base: report(base + d),
                    batch_size=S,
                    max_steps=max_steps,
                    max_wall_time=left,
                )
                _check_status(res, x_all[idx[a:b]])
                values[a:b] = np.asarray(res.event_times["flip"], dtype=float)
                done[a:b] = True
                if checkpoint is not None:
                    digests[f"{a}-{b}"] = _block_digest(identity, a, b, values)
                    _save_checkpoint(Path(checkpoint), identity, values, done, digests)
    finally:
        report(None)
    t_flip = np.full((n1, n2), np.nan)
    if idx.size:
        tf = t_flip.ravel()
        tf[idx] = values
        t_flip = tf.reshape(n1, n2)
        if symmetry:
            mirror = t_flip[::-1, ::-1]
            t_flip = np.where(todo, t_flip, mirror)
            t_flip[skipped] = np.nan
    return FlipMap(
        theta1=th1,
        theta2=th2,
        t_flip=t_flip,
        t_max=float(t_max),
        kind=model.kind,
        params=params,
        energy_threshold=threshold,
        skipped=skipped,
        n_simulated=int(idx.size) - n_resumed,
        wall_time=time.perf_counter() - t0,
        settings=settings,
        n_resumed=n_resumed,
    )


def _overall_progress(progress: Any, total: int, start: int) -> Callable[[int | None], None]:
    """One progress report over all blocks: ``report(done)`` with the absolute count, ``report(None)`` to close."""
    if progress is None or progress is False:
        return lambda done: None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, initial=start, unit="run", desc="flip map")

        def tq(done: int | None) -> None:
            if done is None:
                bar.close()
            else:
                bar.update(done - bar.n)

        return tq
    if not callable(progress):
        raise ValueError(f"progress must be a callable progress(done, total), True or None, got {progress!r}")

    def cb(done: int | None) -> None:
        if done is not None:
            progress(done, total)

    return cb


def _check_status(res: Any, x0: np.ndarray) -> None:
    """Raise when any run of the ensemble failed (a flip or reaching t_max is success)."""
    failed = getattr(res, "failed", None)
    if failed is None:
        success = getattr(res, "success", None)
        if success is None or np.ndim(success) == 0:
            return
        failed = ~np.asarray(success, dtype=bool)
    failed = np.asarray(failed, dtype=bool)
    if np.any(failed):
        i = int(np.argmax(failed))
        message = np.asarray(getattr(res, "message", [""] * len(failed)))[i]
        raise RuntimeError(
            f"flip map: {int(failed.sum())} integration(s) failed, first at theta = {x0[i, :2].tolist()} rad: {message}"
        )

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

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import bounded_int, check_model, relative_tolerance
from .._io import atomic_path
from .._version import __version__

__all__ = [
    "FlipMap",
    "flip_map",
    "flip_map_grid",
    "flip_energy_threshold",
    "flip_initial_states",
    "plot_flip_map",
    "plot_flip_map_compare",
]

_STARTS = ("quasi-static", "static")
#: Largest number of grid points per angle, and of the whole grid (each point holds a state and a time).
MAX_GRID = 20000
MAX_GRID_POINTS = 16_000_000
#: Runs per recorded block of :func:`flip_map` with a ``checkpoint`` (each block is saved when done).
DEFAULT_BLOCK = 10000


@dataclass(frozen=True)
class FlipMap:
    """Time to the first flip over a grid of release angles.

    Attributes
    ----------
    theta1 : ndarray, shape (n1,)
        Release angles of link 1 [rad] (absolute, from the downward vertical).
    theta2 : ndarray, shape (n2,)
        Release angles of link 2 [rad].
    t_flip : ndarray, shape (n1, n2)
        Time to the first flip [s], indexed ``[i_theta1, i_theta2]``; NaN
        where neither link flipped before ``t_max`` (or could not, see ``skipped``).
    t_max : float
        Horizon [s].
    kind : str
        Model kind, ``"rigid"`` or ``"elastic"``.
    params : dict of str to float
        The model's parameters (SI units).
    energy_threshold : float
        ``V_flip`` [J], the least potential energy of a flipped configuration.
    skipped : ndarray of bool, shape (n1, n2)
        Points not integrated because their release energy is below ``energy_threshold``.
    n_simulated : int
        Number of integrations actually run (after the energy skip and symmetry).
    wall_time : float
        Wall-clock time of :func:`flip_map` [s].
    settings : dict
        How the map was computed: ``start``, ``rtol``, ``batch_size``, ``skip_low_energy``,
        ``symmetry``, ``max_steps``, ``pendulab_version`` (stored in the NPZ file).
    n_resumed : int
        Integrations taken from a checkpoint instead of being run again.
    """

    theta1: np.ndarray
    theta2: np.ndarray
    t_flip: np.ndarray
    t_max: float
    kind: str
    params: dict[str, float] = field(default_factory=dict)
    energy_threshold: float = float("nan")
    skipped: np.ndarray | None = None
    n_simulated: int = 0
    wall_time: float = float("nan")
    settings: dict[str, Any] = field(default_factory=dict)
    n_resumed: int = 0

    @property
    def flipped(self) -> np.ndarray:
        """Boolean mask, shape (n1, n2): the points that flipped before ``t_max``."""
        return np.isfinite(self.t_flip)

    def save_npz(self, path: str | Path) -> Path:
        """Write the map as NPZ.

        Keys: ``theta1`` (n1,), ``theta2`` (n2,) [rad], ``t_flip`` (n1, n2) [s]
        indexed ``[i_theta1, i_theta2]`` with NaN for no flip; also ``t_max``,
        ``kind``, ``energy_threshold``, ``skipped``, ``params`` (JSON) and ``settings``
        (JSON: start mode, tolerance, batch width, pendulab version, ...).

        Parameters
        ----------
        path : str or Path
            File name (``.npz`` is appended by NumPy when missing).

        Returns
        -------
        Path
            The file written.
        """
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        skipped = self.skipped if self.skipped is not None else np.zeros(self.t_flip.shape, bool)
        with atomic_path(path if path.suffix == ".npz" else Path(f"{path}.npz")) as tmp:
            np.savez(
                tmp,
                theta1=self.theta1,
                theta2=self.theta2,
                t_flip=self.t_flip,
                t_max=np.float64(self.t_max),
                kind=np.str_(self.kind),
                energy_threshold=np.float64(self.energy_threshold),
                skipped=skipped,
                params=np.str_(json.dumps(self.params)),
                settings=np.str_(json.dumps({**self.settings, "pendulab_version": __version__})),
            )
        return path if path.suffix == ".npz" else path.with_name(path.name + ".npz")

    @classmethod
    def load_npz(cls, path: str | Path) -> FlipMap:
        """Read a map written by :meth:`save_npz`.

        Parameters
        ----------
        path : str or Path
            NPZ file.

        Returns
        -------
        FlipMap
            The map (``n_simulated`` and ``wall_time`` are not stored).
        """
        with np.load(path) as z:
            return cls(
                theta1=z["theta1"],
                theta2=z["theta2"],
                t_flip=z["t_flip"],
                t_max=float(z["t_max"]),
                kind=str(z["kind"]),
                params=json.loads(str(z["params"])),
                energy_threshold=float(z["energy_threshold"]),
                skipped=z["skipped"],
                settings=json.loads(str(z["settings"])) if "settings" in z.files else {},
            )


# -- grid and initial states ----------------------------------------------------
def _check_range(name: str, rng: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in rng)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (low, high) in rad, got {rng!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} must be finite with low < high [rad], got {rng!r}")
    return lo, hi


def flip_map_grid(n: int, theta_range: Sequence[float] = (-math.pi, math.pi)) -> np.ndarray:
    """Cell-centred grid of ``n`` release angles over ``theta_range``.

    The points are the centres of ``n`` equal cells, so no point lies on the
    flipped boundary ``|theta| = pi``; for a range symmetric about 0 the grid
    is exactly antisymmetric (``grid[::-1] == -grid`` bit for bit) and an odd
    ``n`` contains 0.

    Parameters
    ----------
    n : int
        Number of points (>= 1).
    theta_range : (float, float)
        Interval [rad].

    Returns
    -------
    ndarray, shape (n,)
        Angles [rad], increasing.

    Raises
    ------
    ValueError
        ``n`` is not a positive integer, or a bad range.
    """
    n = bounded_int("n_grid", n, high=MAX_GRID, why="grid points per angle")
    lo, hi = _check_range("theta_range", theta_range)
    h = (hi - lo) / n
    centre = 0.5 * (lo + hi)
    return centre + (np.arange(n) - (n - 1) / 2.0) * h


def flip_energy_threshold(model: Any) -> float:
    """Least potential energy of a configuration in which a link has flipped.

    ``V_flip = min { V(q) : |theta1| = pi or |theta2| = pi }``, minimised
    numerically over the free coordinates (the other angle, and the spring
    lengths of the elastic model) with the model's own potential-energy
    function and its exact CasADi gradient, from several starts. A point
    released at rest with ``V0 < V_flip`` can never flip (energy never grows
    without torques). Rigid model: ``V_flip = -|a - b|`` with
    ``a = (m1 lc1 + m2 L1) g``, ``b = m2 lc2 g`` (``-g`` for unit parameters).

    Parameters
    ----------
    model : Model
        Rigid or elastic model.

    Returns
    -------
    float
        ``V_flip`` [J] (gravity potential zero at the pivot height).

    Raises
    ------
    RuntimeError
        The minimisation did not converge.
    """
    import casadi as ca
    from scipy.optimize import minimize

    check_model(model)
    nq, nx = model.nq, model.nx
    pot = model.functions["potential"]
    best = math.inf
    for flipped in (0, 1):
        free = [i for i in range(nq) if i != flipped]
        z = ca.SX.sym("z", len(free))
        q = [ca.SX(0)] * nq
        q[flipped] = ca.SX(math.pi)
        for k, i in enumerate(free):
            q[i] = z[k]
        x = ca.vertcat(*q, ca.SX.zeros(nx - nq))
        v = pot(x, model.p)
        f = ca.Function("v_flip", [z], [v, ca.gradient(v, z)])
        bounds = [(None, None) if i < 2 else (1e-6 * model.rest_state()[i], None) for i in free]
        rest = model.rest_state()
        for other in (0.0, 0.5 * math.pi, math.pi, -0.5 * math.pi):
            z0 = np.array([other if i < 2 else rest[i] for i in free])
            res = minimize(
                lambda zz, f=f: tuple(np.asarray(a, float).ravel() for a in f(zz)),
                z0,
                jac=True,
                method="L-BFGS-B",
                bounds=bounds,
                options={"ftol": 1e-15, "gtol": 1e-12, "maxiter": 1000},
            )
            if not np.isfinite(res.fun):
                raise RuntimeError(f"flip energy threshold: minimisation failed for link {flipped + 1}: {res.message}")
            best = min(best, float(res.fun))
    return best


def flip_initial_states(model: Any, theta1: Any, theta2: Any, *, start: str = "quasi-static") -> np.ndarray:
    """States released at rest at the angles (theta1[k], theta2[k]).

    Parameters
    ----------
    model : Model
        Rigid or elastic model.
    theta1, theta2 : array_like, shape (N,)
        Release angles [rad].
    start : {"quasi-static", "static"}
        Elastic model only: spring lengths with zero radial acceleration in the
        release pose (default), or the static hanging lengths of
        :meth:`Model.rest_state` (excites the spring modes).

    Returns
    -------
    ndarray, shape (N, nx)
        Initial states, rates zero.

    Raises
    ------
    ValueError
        Unknown ``start`` or mismatched shapes.
    """
    check_model(model)
    if start not in _STARTS:
        raise ValueError(f"start must be one of {list(_STARTS)}, got {start!r}")
    t1 = np.asarray(theta1, dtype=float).ravel()
    t2 = np.asarray(theta2, dtype=float).ravel()
    if t1.shape != t2.shape:
        raise ValueError(f"theta1 and theta2 must have the same length, got {t1.shape} and {t2.shape}")
    x0 = np.tile(model.rest_state(), (t1.size, 1))
    x0[:, 0], x0[:, 1] = t1, t2
    if model.kind == "elastic" and start == "quasi-static" and t1.size:
        from ..model.quasistatic import quasi_static_lengths

        x0[:, 2:4] = quasi_static_lengths(model, np.column_stack([t1, t2]), np.zeros((t1.size, 2)))
    return x0


# -- the map --------------------------------------------------------------------
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
        Continue from ``checkpoint`` (blocks already recorded are not run again; the file must
        have been written with the same model, grid and settings). Without it an existing
        checkpoint is overwritten.
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
        Bad grid, horizon, range, ``start``, ``rtol`` or budget; a checkpoint of other settings.
    RuntimeError
        An integration failed or a budget was spent (the engine's message says which).
    KeyboardInterrupt
        Ctrl-C; with ``checkpoint`` the finished blocks are kept.
    """
    from .batch import default_batch_size
    from .engine import ensemble

    t0 = time.perf_counter()
    check_model(model)
    n1, n2 = (n_grid, n_grid) if not isinstance(n_grid, (tuple, list)) else tuple(n_grid)
    n1 = bounded_int("n_grid", n1, high=MAX_GRID, why="grid points per angle")
    n2 = bounded_int("n_grid", n2, high=MAX_GRID, why="grid points per angle")
    bounded_int("n_grid total points n1 * n2", n1 * n2, high=MAX_GRID_POINTS, why="memory of the states and flip times")
    if not (isinstance(t_max, (int, float, np.floating, np.integer)) and math.isfinite(t_max) and t_max > 0):
        raise ValueError(f"t_max must be a finite number > 0 [s], got {t_max!r}")
    tol = relative_tolerance("rtol", rtol)
    block = bounded_int("block_size", block_size, high=10**8, why="runs per recorded block")
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
    if checkpoint is not None and resume and Path(checkpoint).exists():
        values, done = _load_checkpoint(Path(checkpoint), identity, idx.size)
        n_resumed = int(done.sum())
    report = _overall_progress(progress, idx.size, n_resumed)
    deadline = None if max_wall_time is None else time.perf_counter() + float(max_wall_time)
    try:
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
                _save_checkpoint(Path(checkpoint), identity, values, done)
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


def _save_checkpoint(path: Path, identity: dict[str, Any], values: np.ndarray, done: np.ndarray) -> None:
    """Write the finished flip times atomically (an interrupted write keeps the previous checkpoint)."""
    with atomic_path(path) as tmp:
        np.savez(tmp, identity=np.str_(json.dumps(identity, sort_keys=True)), values=values, done=done)


def _load_checkpoint(path: Path, identity: dict[str, Any], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Flip times and done mask of a checkpoint written with the same ``identity``; ValueError otherwise."""
    try:
        with np.load(path, allow_pickle=False) as z:
            stored = json.loads(str(z["identity"]))
            values, done = np.array(z["values"], dtype=float), np.array(z["done"], dtype=bool)
    except (OSError, KeyError, ValueError) as exc:
        raise ValueError(f"checkpoint {str(path)!r} cannot be read as a flip-map checkpoint ({exc}); delete it") from exc
    expected = json.loads(json.dumps(identity, sort_keys=True))
    if stored != expected or values.shape != (n,) or done.shape != (n,):
        diff = sorted(k for k in set(stored) | set(expected) if stored.get(k) != expected.get(k))
        raise ValueError(
            f"checkpoint {str(path)!r} was written with other settings ({', '.join(diff) or 'sizes'} differ); "
            "run without resume to start over"
        )
    return values, done


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


# -- figures --------------------------------------------------------------------
def _save(fig: Any, path: str | Path) -> None:
    """Save a PNG atomically: an interrupted run never leaves a truncated image."""
    # Constrained layout sizes the panels; with equal-aspect images it can still leave the x-labels
    # outside the canvas (seen with --k 3000), so the saved area is the tight box of every artist.
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=150, bbox_inches="tight", pad_inches=0.08)


def _draw(fmap: FlipMap, ax: Any, *, cmap: str, vmin: float, vmax: float, show_threshold: bool) -> Any:
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    colours = plt.get_cmap(cmap).with_extremes(bad="white")
    data = np.ma.masked_invalid(fmap.t_flip.T)  # rows = theta2 (vertical axis)
    h1 = fmap.theta1[1] - fmap.theta1[0] if fmap.theta1.size > 1 else 1.0
    h2 = fmap.theta2[1] - fmap.theta2[0] if fmap.theta2.size > 1 else 1.0
    extent = (fmap.theta1[0] - h1 / 2, fmap.theta1[-1] + h1 / 2, fmap.theta2[0] - h2 / 2, fmap.theta2[-1] + h2 / 2)
    im = ax.imshow(
        data,
        origin="lower",
        extent=extent,
        cmap=colours,
        norm=LogNorm(vmin=vmin, vmax=vmax),
        interpolation="nearest",
        aspect="equal",
    )
    if show_threshold and fmap.skipped is not None and fmap.skipped.any() and fmap.theta1.size > 2:
        ax.contour(fmap.theta1, fmap.theta2, fmap.skipped.T.astype(float), levels=[0.5], colors="0.55", linewidths=0.6)
    ticks = [-math.pi, -math.pi / 2, 0.0, math.pi / 2, math.pi]
    labels = ["$-\\pi$", "$-\\pi/2$", "0", "$\\pi/2$", "$\\pi$"]
    for setter, lim in ((ax.set_xticks, extent[:2]), (ax.set_yticks, extent[2:])):
        keep = [(t, s) for t, s in zip(ticks, labels, strict=True) if lim[0] - 1e-9 <= t <= lim[1] + 1e-9]
        if keep:
            setter([t for t, _ in keep], [s for _, s in keep])
    ax.set_xlabel(r"$\theta_1$ at release [rad]")
    ax.set_ylabel(r"$\theta_2$ at release [rad]")
    return im


def _plain_ticks(cbar: Any) -> None:
    """Colour-bar ticks as plain numbers (0.3, 1, 4), not 3 x 10^-1."""
    from matplotlib.ticker import FuncFormatter

    def minor(v: float, _pos: int) -> str:  # label 2, 3, 5 per decade only: no overlapping labels
        lead = f"{v:.0e}"[0]
        return f"{v:g}" if lead in "235" else ""

    cbar.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    cbar.ax.yaxis.set_minor_formatter(FuncFormatter(minor))


def _limits(maps: Sequence[FlipMap]) -> tuple[float, float]:
    finite = [m.t_flip[np.isfinite(m.t_flip)] for m in maps]
    finite = [f for f in finite if f.size]
    vmax = max(m.t_max for m in maps)
    vmin = min(float(f.min()) for f in finite) if finite else vmax / 100
    return max(vmin, vmax * 1e-4), vmax


def _title(fmap: FlipMap) -> str:
    if fmap.kind == "elastic":
        k1, k2 = fmap.params.get("k1", float("nan")), fmap.params.get("k2", float("nan"))
        stiff = f"k = {k1:g} N/m" if k1 == k2 else f"k1 = {k1:g}, k2 = {k2:g} N/m"
        return f"elastic double pendulum ({stiff})"
    return "rigid double pendulum"


def plot_flip_map(
    fmap: FlipMap,
    path: str | Path | None = None,
    *,
    ax: Any = None,
    cmap: str = "viridis",
    title: str | None = None,
    show_threshold: bool = True,
) -> Any:
    """The classic flip-map picture: time to the first flip, log colour scale, no flip in white.

    Parameters
    ----------
    fmap : FlipMap
        The map.
    path : str or Path, optional
        Save the figure there (PNG, 150 dpi).
    ax : matplotlib Axes, optional
        Draw into these axes instead of a new figure.
    cmap : str
        Matplotlib colour map of the flip time (log scale, ``vmin`` the fastest
        flip, ``vmax = t_max``).
    title : str, optional
        Axes title (default: model, grid, horizon).
    show_threshold : bool
        Draw the energy boundary ``V0 = V_flip`` as a thin grey line (the points
        outside cannot flip).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    import matplotlib.pyplot as plt

    fig = ax.figure if ax is not None else plt.figure(figsize=(6.6, 5.4), layout="constrained")
    ax = ax if ax is not None else fig.add_subplot()
    vmin, vmax = _limits([fmap])
    im = _draw(fmap, ax, cmap=cmap, vmin=vmin, vmax=vmax, show_threshold=show_threshold)
    _plain_ticks(fig.colorbar(im, ax=ax, label="time to first flip [s]"))
    n1, n2 = fmap.t_flip.shape
    ax.set_title(title or f"{_title(fmap)}: {n1} x {n2} released at rest, white = no flip in {fmap.t_max:g} s", fontsize=9)
    if path is not None:
        _save(fig, path)
    return fig


def plot_flip_map_compare(
    maps: Sequence[FlipMap],
    path: str | Path | None = None,
    *,
    cmap: str = "viridis",
    show_threshold: bool = True,
) -> Any:
    """Flip maps side by side (e.g. rigid and elastic) on one shared colour scale.

    Parameters
    ----------
    maps : sequence of FlipMap
        Maps to show, left to right.
    path : str or Path, optional
        Save the figure there (PNG, 150 dpi).
    cmap : str
        Matplotlib colour map.
    show_threshold : bool
        Draw each map's energy boundary.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    ValueError
        ``maps`` is empty.
    """
    import matplotlib.pyplot as plt

    if not maps:
        raise ValueError("maps must hold at least one FlipMap, got none")
    fig, axes = plt.subplots(1, len(maps), figsize=(5.0 * len(maps) + 1.2, 5.0), layout="constrained", squeeze=False)
    vmin, vmax = _limits(maps)
    im = None
    for fmap, ax in zip(maps, axes[0], strict=True):
        im = _draw(fmap, ax, cmap=cmap, vmin=vmin, vmax=vmax, show_threshold=show_threshold)
        frac = float(np.mean(fmap.flipped))
        ax.set_title(f"{_title(fmap)}\n{frac:.1%} flip within {fmap.t_max:g} s", fontsize=9)
    for ax in axes[0][1:]:
        ax.set_ylabel("")
    _plain_ticks(fig.colorbar(im, ax=list(axes[0]), label="time to first flip [s]", shrink=0.9))
    fig.suptitle("Double pendulum released at rest: white = no flip", fontsize=10)
    if path is not None:
        _save(fig, path)
    return fig

"""A library of precomputed swing-up plans for the RealAIGym v3 protocol: re-planner plans built offline, played in real time.

v3 throws the pendulum 15 times into a random configuration: a reset PID (kp 10, saturated at 6 N.m, plus
gravity compensation) drives for 0.2 s from wherever the pendulum is toward a configuration drawn uniformly,
and hands over with the velocities it has built up (typically 5-10 rad/s, not at rest). When the controller
balances upright at the reset (what it does between resets), the hand-over state is a function of the drawn
configuration (2-D) and the upright branch it left from. The library therefore solves, offline, the
re-planner's time-optimal swing-up (:func:`~pendulab.control.replanning.plan_swingup`, the same planner and
options as ``replan``) from the *simulated* hand-over states of a grid of drawn configurations and upright
branches (plus hanging at rest, the protocol's start), and stores each plan's reference and TVLQR gains.

Online (:class:`LibrarySwingUp`), the controller looks up the *nearest knot of any plan* (a KD-tree over
``(cos th1, sin th1, cos th2, sin th2, c w1, c w2)`` of every 2 ms sample of every plan; angles wrap, so a plan
serves every branch) and tracks that plan from that knot with its TVLQR gains; it looks up again after a gap
in its calls (a reset), when the tracking error leaves the tube, or when a plan ends outside the catch. A state
farther than ``accept`` from every knot is pumped by the state-based fallback
(:class:`~pendulab.control.global_swingup.GlobalSwingUp`) until it enters the library's reach; near upright the
fallback's verified LQR catch takes over. A call is a tree query and a 1x4 gain product: tens of microseconds.

Each plan is then re-planned to *enter the scored band* as early as possible
(:func:`~pendulab.control.band_plan.band_entry_refine`: the v3 score counts time above 0.9 (l1 + l2), not
time at rest upright), kept only where its TVLQR closed loop on the design model enters the band sooner
and stays there. A hand-over moves at 5-30 rad/s, and reversing that motion toward the nearest upright branch costs
time: the v3 simulation library also plans toward the branches ahead of the motion
(:func:`~pendulab.control.replanning.upright_goals`) and keeps, per start, the plan whose closed loop enters the band
first (``goals_ahead``).

The library is cached on disk (:class:`PlanCache`): one ``.npz`` per plan, named by a hash of the task, the
design model's parameters, the planner options and the start state, published atomically as each plan finishes
with a seal beside it (its SHA-256 and that key; the one cache mechanism of :mod:`pendulab.native.cache`), so a
build resumes where it stopped (Ctrl-C keeps finished plans), concurrent builds solve each plan once, and an
entry that is damaged, edited or swapped for another's is never used: it is solved again, with a warning.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import zipfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._checks import bounded_int, positive_float
from .._inputs import checked
from ..model.model import INPUT_NAMES
from ..native.cache import cache_lock, cached_artifact, digest_path, publish, read_sealed, warn_rebuild
from .global_swingup import GlobalSwingUp, global_controller
from .lqr import wrap_state_error
from .plan_starts import DEFAULT_BRANCHES, library_starts, reset_handover, rest_starts

__all__ = [
    "LIBRARY_VERSION",
    "LIBRARY_GOALS_AHEAD",
    "DEFAULT_BRANCHES",
    "PlanCache",
    "shipped_grown_path",
    "read_shipped_grown",
    "PlanLibrary",
    "LibrarySwingUp",
    "reset_handover",
    "library_starts",
    "rest_starts",
    "build_library",
    "library_controller",
]

#: Bumped when the stored format or the planner changes (part of every entry's key).
#: 2: every entry sealed (SHA-256 and key beside it); the unsealed entries of 1 are never read.
LIBRARY_VERSION: int = 2


def _read_entry(data: bytes) -> tuple[dict[str, np.ndarray] | None, str | None]:
    """A plan entry from the bytes of its ``.npz``, or why they are not one (fields, shapes, non-finite values)."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            entry = {k: np.array(z[k]) for k in z.files}
        if entry["ok"].shape != ():
            return None, "holds no plan (field ok is not a scalar)"
        if bool(entry["ok"]):
            n = len(entry["x_ref"])
            if entry["x_ref"].shape != (n, 4) or entry["K"].shape != (n - 1, 4) or entry["u_ref"].shape != (n - 1,):
                return None, "holds a plan of inconsistent shapes"
            if n < 2 or not all(np.all(np.isfinite(entry[k])) for k in ("x_ref", "u_ref", "K")):
                return None, "holds a plan with fewer than 2 knots or non-finite values"
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        return None, f"is not a plan entry ({type(exc).__name__}: {exc})"
    return entry, None


def _entry_check(tmp: Path) -> str | None:
    """Why a freshly written entry file is not a plan entry (verified before it is published), or None."""
    return _read_entry(tmp.read_bytes())[1]


class PlanCache:
    """One ``.npz`` file per plan under ``directory``, keyed by the design and the start; sealed, atomic, self-healing.

    Each entry goes through the one cache mechanism (:mod:`pendulab.native.cache`): published
    atomically with its seal beside it (``<entry>.sha256``: the SHA-256 of the file and the entry's
    key, the design and the start it was solved for), and checked against the seal, on the very
    bytes read, before it is used. A damaged or edited entry (digest mismatch) or one swapped for
    another's (sealed for another key) is never used: it is solved again with a
    :class:`~pendulab.native.cache.CacheRebuildWarning` (:meth:`get`), or discarded with one (:meth:`load`).

    Parameters
    ----------
    directory : str or Path
        Cache directory (created on the first write).
    design : dict
        Everything a plan depends on besides its start (task, model parameters, planner options); JSON-serialisable.

    Attributes
    ----------
    rebuilt : int
        Entries found damaged, edited or swapped (discarded or solved again) by this object.
    """

    def __init__(self, directory: str | Path, design: dict) -> None:
        self.directory = Path(directory)
        self.design = dict(design, version=LIBRARY_VERSION)
        self.rebuilt = 0

    def key(self, start: np.ndarray) -> str:
        """What the entry of ``start`` is solved for (sealed with it): the design and the start, as JSON.

        Parameters
        ----------
        start : ndarray, shape (4,)
            Start state (theta1, theta2 [rad], omega1, omega2 [rad/s]).

        Returns
        -------
        str
        """
        return json.dumps({"design": self.design, "start": [round(float(v), 12) for v in start]}, sort_keys=True)

    def path(self, start: np.ndarray) -> Path:
        """The entry of the plan from ``start``.

        Parameters
        ----------
        start : ndarray, shape (4,)
            Start state (theta1, theta2 [rad], omega1, omega2 [rad/s]).

        Returns
        -------
        Path
            ``plan-<hash>.npz`` in the cache directory (the hash covers the design and the start).
        """
        return self.directory / f"plan-{hashlib.sha256(self.key(start).encode()).hexdigest()[:20]}.npz"

    def grown_starts_path(self) -> Path:
        """Where this library's grown starts are listed: ``extra_starts-<hash>.npy``, the hash of the design alone.

        Grown starts are the hand-overs one protocol's closed loop met that the grid did not cover
        (``benchmarks/bench_v3.py --grow-seeds``). They belong to the library they were grown for: a file per
        task shared by every design let starts grown on the simulation protocol's library enter the rate-bounded
        hardware library too (~160 plans solved anew and a lower score, 2026-11-28). Each design now reads
        only its own list.

        Returns
        -------
        Path
            An ``(S, 4)`` array of start states (theta1, theta2 [rad], omega1, omega2 [rad/s]) when present.
        """
        return self.directory / f"extra_starts-{self.design_digest}.npy"

    @property
    def design_digest(self) -> str:
        """SHA-256 (first 20 hex digits) of the design alone: names the starts grown for this design."""
        return hashlib.sha256(json.dumps(self.design, sort_keys=True).encode()).hexdigest()[:20]

    def _what(self, start: np.ndarray) -> str:
        return f"the plan library in {self.directory} needs the plan from start {np.round(start, 6).tolist()}; it"

    def _read(self, start: np.ndarray) -> tuple[dict[str, np.ndarray] | None, str | None]:
        """The entry of ``start`` checked against its seal (on the bytes parsed), or why it cannot be used."""
        data, reason = read_sealed(self.path(start), self.key(start))
        return _read_entry(data) if reason is None else (None, reason)

    def load(self, start: np.ndarray) -> dict[str, np.ndarray] | None:
        """The stored entry, or None if missing or unusable (never an entry that fails its seal).

        An entry that fails its seal (damaged, edited, swapped for another's) or holds no valid plan
        (wrong fields, shapes or non-finite values) is deleted with a
        :class:`~pendulab.native.cache.CacheRebuildWarning`, so it is solved again.

        Parameters
        ----------
        start : ndarray, shape (4,)
            Start state (theta1, theta2 [rad], omega1, omega2 [rad/s]).

        Returns
        -------
        dict or None
            ``ok``, and for a solved plan ``x_ref`` (n, 4), ``u_ref`` (n - 1,) [N.m] and ``K`` (n - 1, 4).
        """
        entry, reason = self._read(start)
        if reason is None or reason == "is missing":
            return entry
        path = self.path(start)
        try:
            with cache_lock(path):
                # Again under the lock: a writer between its two renames shows a mismatch that is not damage.
                entry, reason = self._read(start)
                if reason is None or reason == "is missing":
                    return entry
                self._discard(path, reason, removed=True)
        except OSError:  # a read-only folder: the entry is still never used
            self._discard(path, reason, removed=False)
        return None

    def _discard(self, path: Path, reason: str, *, removed: bool) -> None:
        self.rebuilt += 1
        if removed:
            path.unlink(missing_ok=True)
            digest_path(path).unlink(missing_ok=True)
        action = "deleted it; it is solved again when the library is built" if removed else "not using it"
        warn_rebuild(f"pendulab: the plan-library entry {path} {reason}; {action}")

    def get(self, start: np.ndarray, solve: Callable[[], dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
        """The stored entry of ``start``, solved by ``solve()`` and published when missing or unusable.

        Concurrent processes solve an entry once (the others wait on its lock and read it); an entry that
        fails its seal or holds no valid plan is solved again with a
        :class:`~pendulab.native.cache.CacheRebuildWarning`.

        Parameters
        ----------
        start : ndarray, shape (4,)
            Start state (theta1, theta2 [rad], omega1, omega2 [rad/s]).
        solve : callable
            ``solve()`` returns the entry: ``ok``, and for a solved plan ``x_ref``, ``u_ref``, ``K``.

        Returns
        -------
        dict
            The entry (see :meth:`load`).

        Raises
        ------
        RuntimeError
            The folder cannot be written, ``solve`` failed, or its entry is not a valid plan.
        """
        path, key, what = self.path(start), self.key(start), self._what(start)
        hint = f"choose a writable directory for the plan library (now {self.directory})"
        entry, reason = self._read(start)
        if reason is None:
            return entry
        rebuild = None
        if reason != "is missing":
            self.rebuilt += 1
            _, seal_reason = read_sealed(path, key)
            # Intact by its seal but not a valid plan (e.g. written by a faulty build): rebuild it anyway.
            rebuild = reason if seal_reason is None else None

        def make(tmp: Path) -> None:
            np.savez(tmp, **solve())

        opts = {"what": what, "key": key, "check": _entry_check, "hint": hint}
        cached_artifact(path, make, rebuild=rebuild, **opts)
        entry, reason = self._read(start)
        if reason is not None:  # another process's entry in between, or damage after the rename: solve once more
            cached_artifact(path, make, rebuild=reason, **opts)
            entry, reason = self._read(start)
            if reason is not None:
                raise RuntimeError(f"{what}: the cache file {path} {reason} right after it was built; delete it and retry")
        return entry

    def save(self, start: np.ndarray, entry: dict[str, np.ndarray]) -> None:
        """Publish an entry atomically with its seal (a crash leaves the old file or none, never a truncated one).

        Parameters
        ----------
        start : ndarray, shape (4,)
            Start state (theta1, theta2 [rad], omega1, omega2 [rad/s]).
        entry : dict of str to ndarray
            ``ok`` and, for a solved plan, ``x_ref``, ``u_ref``, ``K``.

        Raises
        ------
        RuntimeError
            The folder cannot be written.
        """
        hint = f"choose a writable directory for the plan library (now {self.directory})"
        publish(self.path(start), lambda tmp: np.savez(tmp, **entry), what=self._what(start), key=self.key(start), hint=hint)


@dataclass
class PlanLibrary:
    """Solved plans (references and TVLQR gains at the sample time) and the KD-tree over all their knots.

    Attributes
    ----------
    starts : ndarray, shape (S, 4)
        Start of each plan.
    x_ref : list of ndarray, shape (N_i, 4)
        References (absolute angles) [rad, rad/s].
    u_ref : list of ndarray, shape (N_i - 1,)
        Driven torque [N.m].
    K : list of ndarray, shape (N_i - 1, 4)
        TVLQR gains of the driven torque.
    velocity_scale : float
        Weight ``c`` of the rates in the lookup metric [s].
    n_failed : int
        Starts whose plan could not be solved (not in the library).
    n_refined : int
        Plans re-planned for band entry.
    """

    starts: np.ndarray
    x_ref: list[np.ndarray]
    u_ref: list[np.ndarray]
    K: list[np.ndarray]
    velocity_scale: float = 0.3
    n_failed: int = 0
    n_refined: int = 0
    _tree: object = field(default=None, init=False, repr=False)
    _index: np.ndarray = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        from scipy.spatial import cKDTree

        if len(self.x_ref) == 0:
            raise ValueError("a plan library needs at least one solved plan, got none")
        feats, index = [], []
        for i, xr in enumerate(self.x_ref):
            m = len(xr) - 1  # knots with a gain
            feats.append(self.features(xr[:m]))
            index.append(np.column_stack([np.full(m, i), np.arange(m)]))
        self._tree = cKDTree(np.concatenate(feats))
        self._index = np.concatenate(index)

    def digest(self) -> str:
        """SHA-256 of everything the library plays (starts, references, torques, gains, lookup weight), hex.

        A result computed with this library (a journaled leaderboard case) names it: another library (grown,
        re-planned, of another design) is another experiment, never read back as this one's.

        Returns
        -------
        str
            64 hex digits.
        """
        h = hashlib.sha256()
        for a in (self.starts, *self.x_ref, *self.u_ref, *self.K, np.array([self.velocity_scale])):
            arr = np.ascontiguousarray(a, dtype=float)
            h.update(repr(arr.shape).encode())
            h.update(arr.tobytes())
        return h.hexdigest()

    def features(self, x: np.ndarray) -> np.ndarray:
        """Lookup coordinates of states: angles on the circle, rates scaled by ``velocity_scale``.

        Parameters
        ----------
        x : ndarray, shape (..., 4)
            States (theta1, theta2 [rad], omega1, omega2 [rad/s]).

        Returns
        -------
        ndarray, shape (..., 6)
            ``(cos th1, sin th1, cos th2, sin th2, c w1, c w2)``.
        """
        x = np.asarray(x, dtype=float)
        c = self.velocity_scale
        return np.stack(
            [np.cos(x[..., 0]), np.sin(x[..., 0]), np.cos(x[..., 1]), np.sin(x[..., 1]), c * x[..., 2], c * x[..., 3]], axis=-1
        )

    def tube_error(self, e: np.ndarray, scaled: bool = True) -> float:
        """Squared size of a tracking error as the plans' tubes measure it: angles plus the rates weighted by
        :attr:`velocity_scale` as in the lookup metric (``scaled``), or unweighted.

        Parameters
        ----------
        e : ndarray, shape (4,)
            State error with its angles wrapped (:func:`~pendulab.control.lqr.wrap_state_error`) [rad, rad/s].
        scaled : bool
            Weight the rates by :attr:`velocity_scale`.

        Returns
        -------
        float
            ``e1^2 + e2^2 + c^2 (e3^2 + e4^2)`` [rad^2], ``c`` the scale or 1 [s].
        """
        c = self.velocity_scale if scaled else 1.0
        return float(e[0] ** 2 + e[1] ** 2 + c * c * (e[2] ** 2 + e[3] ** 2))

    def nearest(self, x: np.ndarray, within: float | None = None) -> tuple[int, int, float]:
        """The knot nearest to a state, over every plan.

        Parameters
        ----------
        x : ndarray, shape (4,)
            State (theta1, theta2 [rad], omega1, omega2 [rad/s]).
        within : float, optional
            Only a knot at most this far counts (lookup coordinates). The search then prunes every branch beyond
            it: a state far from every plan costs microseconds instead of visiting much of the tree (up to 1.4 ms,
            most of a 2 ms control period, on the acrobot's library of 82,000 knots, measured in v3 episodes).

        Returns
        -------
        tuple of (int, int, float)
            Plan index, knot index, distance in lookup coordinates; ``(-1, -1, inf)`` when no knot is ``within``.
        """
        if within is None:
            d, j = self._tree.query(self.features(x))
        else:  # nextafter: a knot exactly at the bound still counts (the tree keeps only closer ones)
            d, j = self._tree.query(self.features(x), distance_upper_bound=float(np.nextafter(within, np.inf)))
            if not math.isfinite(d):
                return -1, -1, math.inf
        i, k = self._index[int(j)]
        return int(i), int(k), float(d)

    def __len__(self) -> int:
        return len(self.x_ref)


def build_library(
    fallback: GlobalSwingUp,
    actuation: str,
    starts: np.ndarray,
    cache: PlanCache,
    *,
    horizon: float,
    n_intervals: int,
    min_time: bool = True,
    max_iter: int = 150,
    solve: bool = True,
    band: float | None = None,
    band_cache: PlanCache | None = None,
    velocity_limit: float | None = None,
    goals_ahead: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> PlanLibrary:
    """Solve (or load) the plan from each start and assemble the library; each solved plan is cached as it finishes.

    Parameters
    ----------
    fallback : GlobalSwingUp
        Design model, sample time and torque limit.
    actuation : {"pendubot", "acrobot"}
        Driven joint.
    starts : ndarray, shape (S, 4)
        Start states.
    cache : PlanCache
        Where plans are stored.
    horizon, n_intervals, min_time, max_iter
        Planner options (:func:`~pendulab.control.replanning.plan_swingup`).
    solve : bool
        Solve the missing plans (False: assemble the cached ones only, e.g. while another process builds).
    band : float, optional
        Scored height [m]: re-plan each plan for band entry (:func:`~pendulab.control.band_plan.band_entry_refine`),
        kept where its closed loop enters the band sooner; needs ``band_cache``.
    band_cache : PlanCache, optional
        Where the band-entry entries are stored (the time-optimal plans they start from stay in ``cache``).
    velocity_limit : float, optional
        Bound on both joint rates of every plan and band-entry re-plan [rad/s]; the library admits only plans that
        keep it (:func:`~pendulab.control.band_plan.within_joint_limit`); None: unbounded. It must be part of the
        caches' designs (:func:`library_controller` puts it there), so bounded and unbounded plans never mix.
    goals_ahead : bool
        Also plan toward the upright branches ahead of the start's motion
        (:func:`~pendulab.control.replanning.upright_goals`; each cached beside ``cache`` under the design plus its
        ``goal_offset``) and keep, per start, the band-entry entry whose closed loop enters the band first. Needs
        ``band``, and must be part of ``band_cache``'s design (:func:`library_controller` puts it there).
    progress : callable, optional
        ``progress(done, total)`` after each start.

    Returns
    -------
    PlanLibrary

    Raises
    ------
    ValueError
        ``starts`` not of shape (S, 4) with finite values, ``goals_ahead`` without ``band``, or no plan solved.
    RuntimeError
        The cache folder cannot be written, or a solve failed (the message names the entry's file).
    KeyboardInterrupt
        Propagated; plans finished before it stay cached.

    Warns
    -----
    CacheRebuildWarning
        A cached entry was damaged, edited or swapped for another's: solved again (or, with ``solve=False``, discarded).
    """
    from .band_plan import band_entry_refine, within_joint_limit
    from .replanning import plan_swingup, upright_goals

    if (band is None) != (band_cache is None):
        raise ValueError(f"band and band_cache go together, got band={band!r} and band_cache={band_cache!r}")
    if goals_ahead and band is None:
        raise ValueError("goals_ahead ranks the goals by the closed loop's band entry: it needs band (and band_cache)")
    starts = np.asarray(starts, dtype=float)
    if starts.ndim != 2 or starts.shape[1] != 4 or len(starts) == 0 or not np.all(np.isfinite(starts)):
        raise ValueError(f"starts must be a finite array of shape (S, 4) with S >= 1, got shape {starts.shape}")
    j = INPUT_NAMES.index(fallback.input_names[0])

    def solve_plan(s: np.ndarray, goal_offset: tuple[int, int] = (0, 0)) -> dict[str, np.ndarray]:
        tr = plan_swingup(
            fallback, actuation, s, horizon=horizon, n_intervals=n_intervals, min_time=min_time, max_iter=max_iter,
            velocity_limit=velocity_limit, goal_offset=goal_offset,
        )  # fmt: skip
        if tr is None:
            return {"ok": np.array(False)}
        m = min(len(tr.K), len(tr.u_ref), len(tr.x_ref) - 1)
        return {"ok": np.array(True), "x_ref": tr.x_ref[: m + 1], "u_ref": tr.u_ref[:m, j], "K": tr.K[:m, j, :]}

    def refine_plan(s: np.ndarray) -> dict[str, np.ndarray]:
        best: dict[str, np.ndarray] = {"ok": np.array(False), "refined": np.array(False)}
        for offset in upright_goals(s) if goals_ahead else [(0, 0)]:
            # The nearest branch's plan is the plain library's entry; the others are cached beside it.
            plans = cache if offset == (0, 0) else PlanCache(cache.directory, dict(cache.design, goal_offset=list(offset)))
            entry = plans.get(s, lambda o=offset: solve_plan(s, o))  # the band entry's lock is held: order band -> plan
            if not bool(entry["ok"]):
                continue
            found = band_entry_refine(
                fallback.model, actuation, entry, band=band, u_max=fallback.u_max, velocity_limit=velocity_limit
            )
            if not bool(best["ok"]) or float(found["t_enter"]) < float(best["t_enter"]):
                best = found
        return best

    kept, xs, us, ks, failed, n_refined = [], [], [], [], 0, 0
    for n, s in enumerate(starts):
        if band_cache is not None:
            entry = band_cache.get(s, lambda s=s: refine_plan(s)) if solve else band_cache.load(s)
            if entry is None:
                entry = cache.load(s)
        else:
            entry = cache.get(s, lambda s=s: solve_plan(s)) if solve else cache.load(s)
        if entry is not None and bool(entry["ok"]) and within_joint_limit(entry["x_ref"], velocity_limit):
            kept.append(s)
            xs.append(entry["x_ref"])
            us.append(entry["u_ref"])
            ks.append(entry["K"])
            n_refined += int(bool(entry.get("refined", False)))
        elif entry is not None:
            failed += 1
        if progress is not None:
            progress(n + 1, len(starts))
    return PlanLibrary(np.array(kept).reshape(-1, 4), xs, us, ks, n_failed=failed, n_refined=n_refined)


@dataclass
class LibrarySwingUp:
    """Real-time global swing-up: nearest-knot lookup in a :class:`PlanLibrary`, TVLQR tracking, fallback pumping and catch.

    Attributes
    ----------
    fallback : GlobalSwingUp
        Pumping outside the library's reach, and the catch LQR (with hysteresis) near upright.
    library : PlanLibrary
        The plans.
    accept : float
        Largest lookup distance at which a plan is taken (else the fallback pumps).
    replan_error : float
        Leave a plan when the wrapped tracking error ``|x - x_ref|^2`` exceeds this (rates weighted by the
        library's ``velocity_scale`` when ``scaled_tube``, as in the lookup metric).
    scaled_tube : bool
        Weight the rates' tracking error like the lookup does (False: unweighted, as the re-planner).
    n_lookups : int
        Plans taken (diagnostics).
    handovers : list of ndarray
        The state at each gap in the calls (the protocol's reset hand-overs; diagnostics and library growth).
    grown_starts : Path or None
        Where starts grown for this library's design are listed (:meth:`PlanCache.grown_starts_path`): growth
        appends there, and only a library of the same design reads them.
    design_digest : str
        :attr:`PlanCache.design_digest` of the library's design ("" when not built by :func:`library_controller`).
    """

    fallback: GlobalSwingUp
    library: PlanLibrary
    accept: float = 1.0
    replan_error: float = 1.0
    scaled_tube: bool = True
    n_lookups: int = 0
    handovers: list[np.ndarray] = field(default_factory=list)
    grown_starts: Path | None = None
    design_digest: str = ""
    _plan: tuple[int, int, float] | None = field(default=None, init=False, repr=False)
    _t_last: float | None = field(default=None, init=False, repr=False)

    @property
    def sample_time(self) -> float:
        """[s] (the fallback's)."""
        return self.fallback.sample_time

    @property
    def input_names(self) -> tuple[str, ...]:
        """The driven torque."""
        return self.fallback.input_names

    def reset(self) -> None:
        """Forget the plan and the catch."""
        self.fallback.reset()
        self._plan, self._t_last = None, None

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        fb, lib, h = self.fallback, self.library, self.fallback.sample_time
        if self._t_last is not None and t - self._t_last > 1.5 * h:
            self._plan, fb.caught = None, False  # a gap in the calls: the protocol reset the pendulum
            self.handovers.append(x.copy())
        self._t_last = t
        v = fb.cost(x)
        if fb.caught and v > fb.release_level:
            fb.caught = False
        elif not fb.caught and v < fb.catch_level:
            fb.caught = True
        if fb.caught:
            self._plan = None
            return np.clip(fb.balance(t, x), -fb.u_max, fb.u_max)
        e = None
        if self._plan is not None:
            i, k0, t0 = self._plan
            k = k0 + int((t - t0) / h + 1e-6)
            if k >= len(lib.K[i]):
                self._plan = None  # ended outside the catch
            else:
                e = wrap_state_error(x - lib.x_ref[i][k], fb.model.state_names)
                if lib.tube_error(e, self.scaled_tube) > self.replan_error:
                    self._plan = None
        if self._plan is None:
            i, k, d = lib.nearest(x, within=self.accept)
            if d > self.accept:
                return np.array([fb.pump(x)])
            self._plan = (i, k, t)
            self.n_lookups += 1
            e = wrap_state_error(x - lib.x_ref[i][k], fb.model.state_names)
        u = float(lib.u_ref[i][k] - lib.K[i][k] @ e)
        return np.array([min(max(u, -fb.u_max), fb.u_max)])


#: Library grid (drawn configurations per relative angle) per task, and the default cache directory.
LIBRARY_GRID: dict[str, int] = {"pendubot": 6, "acrobot": 6}
#: Upright branches per task (the acrobot's plans take ~3x longer to solve: its library has the two main ones).
LIBRARY_BRANCHES: dict[str, tuple[tuple[int, int], ...]] = {"pendubot": DEFAULT_BRANCHES, "acrobot": DEFAULT_BRANCHES[:2]}
#: Re-plan the library's plans for band entry, per task. The acrobot's was switched on 2026-11-28 after its band-entry
#: solves were first run (170 s; 70 of 92 plans improved): v3 on the training seeds 10-15, 0.449 -> 0.550, every seed
#: better (``benchmarks/results/v3.md`` has the scored seeds).
LIBRARY_BAND: dict[str, bool] = {"pendubot": True, "acrobot": True}
#: The same for a rate-bounded library (the hardware protocol's, ``velocity_limit`` given). Such a library admits only
#: plans whose *joint* rates keep the bound (:func:`~pendulab.control.band_plan.within_joint_limit`): the robot resets
#: above 20 rad/s of either joint. Until 2026-11-29 the plans bounded the *link* rates: of the acrobot's 67 plans
#: bounded to 16 rad/s that way, 65 turned the elbow joint faster than 20 rad/s (median peak 27), the pendubot's 49 of
#: 135. Now every planner bounds the joint rates. The acrobot's link-bounded re-plans had lost (0.109 against 0.202 on
#: its v3-hardware training seeds 10-13: they were the plans that ran fastest past the reset); re-planned with the
#: joints bounded, ``mpc_library`` scored 0.649 on its training seeds 30-45 against 0.639 with the plain plans, so both
#: tasks re-plan (``benchmarks/results/v3_hardware.md``, "The plans' rate bound is on the robot's joints").
LIBRARY_BAND_BOUNDED: dict[str, bool] = {"pendubot": True, "acrobot": True}
#: Tracking-error tube (``LibrarySwingUp.replan_error``) of the unbounded (v3 simulation) library, per task: leave a plan
#: and look up the nearest one again when the scaled squared error exceeds it. Decided on the v3 validation seeds
#: 70-99 (2026-11-29, shipped growth): acrobot 0.568 at 1.0, 0.587 at 0.5, 0.601-0.604 at 0.15-0.35, 0.592-0.595 at
#: 0.05-0.1; pendubot 0.746 / 0.750 / 0.749 at 1.0 / 0.5 / 0.25 (kept at 1.0). Re-checked with goals ahead (training
#: seeds 30-49, then validation 70-99, ``benchmarks/results/v3.md``): unchanged. The rate-bounded library keeps 1.0.
LIBRARY_REPLAN_ERROR: dict[str, float] = {"pendubot": 1.0, "acrobot": 0.25}
#: Plan each start of the unbounded (v3 simulation) library toward the upright branches ahead of its motion too, and
#: keep the one whose closed loop enters the band first (``build_library(goals_ahead=True)``), per task. Decided on the
#: v3 validation seeds 70-99 (2026-11-29, shipped growth, same starts): pendubot 0.746 -> 0.818 (28 of 30 seeds
#: better), acrobot 0.602 -> 0.710 (29 of 30). The rate-bounded library aims at the nearest branch only: the hardware
#: protocol's 1 s resets hand over near rest, where there is no motion to go ahead of (not measured there).
LIBRARY_GOALS_AHEAD: dict[str, bool] = {"pendubot": True, "acrobot": True}
#: Configurations at rest per angle that a rate-bounded library also plans from (:func:`rest_starts`: where the
#: hardware protocol's 1 s PID resets hand over; a bound is given for that protocol).
LIBRARY_REST_GRID: dict[str, int] = {"pendubot": 6, "acrobot": 6}
DEFAULT_LIBRARY_DIR: str = "pendulab-out/plan_library"
#: Grown starts shipped with pendulab, beside the shipped plans: ``grown_<task>.npz`` holds ``starts`` (S, 4), ``design``
#: (:attr:`PlanCache.design_digest` of the design they were grown for) and ``seeds`` (the v3 *training* seeds whose
#: hand-overs they are; ``benchmarks/bench_v3.py --grow-seeds ... --ship``). Shipped, every checkout builds the library
#: its recorded scores were measured with, instead of one grown in a local cache that a fresh clone does not have.
SHIPPED_GROWN_DIR: Path = Path(__file__).resolve().parent / "realai" / "plans"


def shipped_grown_path(task: str) -> Path:
    """The shipped grown starts of ``task``'s default library (:data:`SHIPPED_GROWN_DIR`).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}

    Returns
    -------
    Path
    """
    return SHIPPED_GROWN_DIR / f"grown_{task}.npz"


def read_shipped_grown(task: str, design_digest: str) -> tuple[np.ndarray, list[int]]:
    """Shipped grown starts of ``task`` when they were grown for the design ``design_digest``, else none.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
    design_digest : str
        :attr:`PlanCache.design_digest` of the library asking.

    Returns
    -------
    starts : ndarray, shape (S, 4)
        (theta1, theta2 [rad], omega1, omega2 [rad/s]); S = 0 for another design or no file.
    seeds : list of int
        The training seeds they were grown on.
    """
    path = shipped_grown_path(task)
    if not path.exists():
        return np.zeros((0, 4)), []
    with np.load(path, allow_pickle=False) as z:
        if str(z["design"]) != design_digest:
            return np.zeros((0, 4)), []
        return np.asarray(z["starts"], dtype=float).reshape(-1, 4), [int(v) for v in z["seeds"]]


def _valid_starts(a: np.ndarray) -> np.ndarray:
    return a if a.ndim == 2 and a.shape[1] == 4 and np.all(np.isfinite(a)) else np.zeros((0, 4))


@checked()
def library_controller(
    task: str,
    *,
    n_grid: int | None = None,
    branches: Sequence[tuple[int, int]] | None = None,
    directory: str | Path | None = None,
    accept: float = 1.0,
    band: bool | None = None,
    build: bool = True,
    velocity_limit: float | None = None,
    rest_grid: int | None = None,
    goals_ahead: bool | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> LibrarySwingUp:
    """The plan-library swing-up on a RealAIGym leaderboard task's plant; builds (or completes) the cached library first.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    n_grid : int, optional
        Drawn configurations per angle (:func:`library_starts`); default :data:`LIBRARY_GRID`.
    branches : sequence of (int, int), optional
        Upright branches the resets leave from; default :data:`LIBRARY_BRANCHES`.
    directory : str or Path, optional
        Cache root (a subdirectory per task); default ``./pendulab-out/plan_library``. Starts grown for this
        very design (:meth:`PlanCache.grown_starts_path`) are added to the grid's.
    accept : float
        Lookup distance within which a plan is taken.
    band : bool, optional
        Re-plan for band entry (faster into the scored band); default :data:`LIBRARY_BAND`, or
        :data:`LIBRARY_BAND_BOUNDED` with a ``velocity_limit``.
    build : bool
        Solve missing plans (False: use the cached ones only).
    velocity_limit : float, optional
        Bound on both joint rates of every plan [rad/s] (the hardware protocol resets the robot above 20 rad/s,
        :data:`~pendulab.control.realai.spec.PLAN_VELOCITY_LIMIT_HW`; :func:`build_library`); None: unbounded.
        Part of every entry's key: bounded plans are cached apart from unbounded ones and from those of another bound.
    rest_grid : int, optional
        Also plan from rest at ``rest_grid`` x ``rest_grid`` configurations (:func:`rest_starts`, the hardware
        protocol's hand-overs; 0: none); default :data:`LIBRARY_REST_GRID` with a ``velocity_limit``, else 0.
    goals_ahead : bool, optional
        Also plan toward the upright branches ahead of each start's motion and keep the fastest band entry
        (:func:`build_library`; only with band entry); default :data:`LIBRARY_GOALS_AHEAD` without a
        ``velocity_limit``, else False. Part of the band-entry entries' key.
    progress : callable, optional
        ``progress(done, total)`` over the starts while building.

    Returns
    -------
    LibrarySwingUp

    Raises
    ------
    ValueError
        Unknown task, bad ``n_grid`` or ``rest_grid``, non-positive ``accept``, ``goals_ahead`` without band entry,
        or no plan solved.
    InputError
        ``velocity_limit`` not a finite positive rate (its declaration in :data:`pendulab._inputs.INPUTS`).
    """
    from .realai.spec import HEIGHT_FRACTION, check_task
    from .replanning import REPLAN_DEFAULTS

    check_task(task)
    accept = positive_float("accept", accept)
    fb = global_controller(task)
    horizon, n_int, min_time = REPLAN_DEFAULTS[task]
    n = LIBRARY_GRID[task] if n_grid is None else n_grid
    design = {
        "task": task,
        "params": [float(v) for v in fb.model.p],
        "planner": {"horizon": horizon, "n_intervals": n_int, "min_time": min_time, "max_iter": 150},
        "sample_time": fb.sample_time,
        "u_max": fb.u_max,
    }
    if velocity_limit is not None:  # only then: the unbounded library's keys (and its cache) stay as they were
        # "joints": the bound is on the joint rates (plans bounded on the link rates were cached before 2026-11-29)
        design.update(velocity_limit=float(velocity_limit), rate_bound="joints")
    root = Path(DEFAULT_LIBRARY_DIR if directory is None else directory)
    cache = PlanCache(root / task, design)
    starts = library_starts(fb.model, n, LIBRARY_BRANCHES[task] if branches is None else branches)
    if n_grid is None and branches is None:  # the shipped growth completes the default grid it was grown on
        starts = np.vstack([starts, _valid_starts(read_shipped_grown(task, cache.design_digest)[0])])
    extra = cache.grown_starts_path()
    if extra.exists():
        try:
            more = np.load(extra, allow_pickle=False)
        except (OSError, ValueError, EOFError):
            more = np.zeros((0, 4))  # a damaged list only loses the grown starts; the grid stands
        starts = np.vstack([starts, _valid_starts(more)])
    if rest_grid is None:
        n_rest = LIBRARY_REST_GRID[task] if velocity_limit is not None else 0
    else:
        n_rest = bounded_int("rest_grid", rest_grid, low=0, high=64, why="plans per angle of the library's rest grid")
    if n_rest > 0:
        starts = np.vstack([starts, rest_starts(n_rest)])
    use_band = (LIBRARY_BAND if velocity_limit is None else LIBRARY_BAND_BOUNDED)[task] if band is None else bool(band)
    prm = fb.model.params
    height = HEIGHT_FRACTION * (prm.L1 + prm.L2) if use_band else None
    if goals_ahead is None:
        ahead = use_band and velocity_limit is None and LIBRARY_GOALS_AHEAD[task]
    else:
        ahead = bool(goals_ahead)
    band_design = dict(design, band=height, goals_ahead=True) if ahead else dict(design, band=height)
    band_cache = PlanCache(root / task, band_design) if use_band else None
    lib = build_library(
        fb,
        task,
        starts,
        cache,
        horizon=horizon,
        n_intervals=n_int,
        min_time=min_time,
        solve=build,
        band=height,
        band_cache=band_cache,
        velocity_limit=design.get("velocity_limit"),
        goals_ahead=ahead,
        progress=progress,
    )
    tube = LIBRARY_REPLAN_ERROR[task] if velocity_limit is None else 1.0
    return LibrarySwingUp(fb, lib, accept=accept, replan_error=tube, grown_starts=extra, design_digest=cache.design_digest)

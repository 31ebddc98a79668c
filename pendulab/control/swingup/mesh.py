"""h-refinement of a swing-up mesh and the transfer of a solution onto the refined mesh.

:func:`refine_mesh` splits the intervals whose relative defect exceeds the
tolerance. A method whose local error on an interval of length h behaves like
``C h^(q + 1)`` cuts an interval's defect ``e`` to about ``e / n^(q + 1)``
when split into ``n`` equal pieces; pieces are handed out greedily, one at a
time to the interval with the largest predicted defect, until every
prediction is below ``safety * tolerance``. The total is then rounded up to
the next size of a fixed ladder (:data:`MESH_SIZES`), the extra pieces again
going to the largest predictions: the compiled NLP depends on N only
(:mod:`.transcription`), so refinements of different starts and tasks land on
a few sizes and reuse a few cached NLPs instead of building one per refinement.

:func:`collocation_states` evaluates the collocation polynomials of a solution
anywhere in the horizon, so a re-solve on a refined mesh starts from the
previous solution exactly (every new interval lies inside an old one, whose
held torque it inherits).

:func:`radau_resolution` and :func:`oscillation_mesh` are the p-refinement
rule of stiff elastic tasks: Radau IIA collocation of degree ``d`` propagates
an undamped oscillation ``y' = i w y`` over one interval with the stability
function ``R`` = the (d - 1, d) Padé approximant of ``exp``, so the per-interval
error of a mode is ``|R(i h w) - exp(i h w)|`` times its amplitude. Degree 3
keeps that below 1e-3 only up to ``h w`` = 1.41, degree 7 up to 6.6: a spring
mode of 346 rad/s needs ~740 intervals over 3 s at degree 3 and ~160 at degree 7.
"""

from __future__ import annotations

import heapq
import math
from typing import Any

import casadi as ca
import numpy as np

__all__ = [
    "MESH_SIZES",
    "refine_mesh",
    "mesh_size",
    "collocation_states",
    "parent_intervals",
    "radau_resolution",
    "oscillation_mesh",
]

#: Interval counts a refinement rounds up to (beyond the last: multiples of 250).
MESH_SIZES: tuple[int, ...] = (20, 30, 40, 50, 60, 80, 100, 120, 150, 200, 250, 300, 400, 500, 600, 800, 1000)
#: Largest number of pieces one interval is split into per refinement: the error model
#: e ~ h^(q+1) is asymptotic, so large extrapolations are not trusted.
MAX_SPLIT = 8


def mesh_size(n: int) -> int:
    """Smallest ladder size >= ``n``.

    Parameters
    ----------
    n : int
        Number of intervals needed.

    Returns
    -------
    int
        The next entry of :data:`MESH_SIZES`, or ``n`` rounded up to a multiple
        of 250 beyond the ladder.
    """
    for size in MESH_SIZES:
        if size >= n:
            return size
    return int(250 * np.ceil(n / 250))


def refine_mesh(
    mesh: Any,
    interval_error: Any,
    tolerance: float,
    order: int,
    *,
    max_intervals: int = 1000,
    safety: float = 0.5,
) -> tuple[np.ndarray, np.ndarray]:
    """Split the intervals whose error exceeds the tolerance.

    Parameters
    ----------
    mesh : array_like, shape (N,)
        Interval fractions of the current mesh (positive, summing to 1).
    interval_error : array_like, shape (N,)
        Worst relative defect of each interval (dimensionless; inf allowed).
    tolerance : float
        Target relative defect (> 0).
    order : int
        q in the error model ``e ~ h^(q + 1)`` (>= 1), e.g. the collocation degree.
    max_intervals : int
        Cap on the refined mesh size.
    safety : float
        Aim at ``safety * tolerance`` (in (0, 1]) to absorb the model's error.

    Returns
    -------
    mesh : ndarray, shape (M,)
        Refined interval fractions (N < M <= max_intervals unless nothing
        needed splitting or N already is the cap; then M = N).
    pieces : ndarray of int, shape (N,)
        Into how many equal pieces each old interval was split.

    Raises
    ------
    ValueError
        Inconsistent shapes, a non-positive tolerance or order, or a safety outside (0, 1].
    """
    frac = np.asarray(mesh, dtype=float)
    err = np.asarray(interval_error, dtype=float)
    if frac.ndim != 1 or err.shape != frac.shape:
        raise ValueError(f"mesh and interval_error must be 1-D of equal length, got {frac.shape} and {err.shape}")
    if not tolerance > 0.0:
        raise ValueError(f"tolerance must be > 0, got {tolerance!r}")
    if not (isinstance(order, (int, np.integer)) and order >= 1):
        raise ValueError(f"order must be an integer >= 1, got {order!r}")
    if not 0.0 < safety <= 1.0:
        raise ValueError(f"safety must be in (0, 1], got {safety!r}")
    N = frac.size
    pieces = np.ones(N, dtype=int)
    err = np.where(np.isfinite(err), err, 1e300)  # a failed interval: split it as much as allowed
    target, power = safety * tolerance, order + 1.0
    # Max-heap of predicted errors e_k / n_k^(q+1).
    heap = [(-e, k) for k, e in enumerate(err) if e > target]
    heapq.heapify(heap)
    budget = max_intervals - N

    def split_worst() -> bool:
        nonlocal budget
        while heap and budget > 0:
            _, k = heapq.heappop(heap)
            if pieces[k] >= MAX_SPLIT:
                continue
            pieces[k] += 1
            budget -= 1
            pred = err[k] / pieces[k] ** power
            heapq.heappush(heap, (-pred, k))
            return True
        return False

    while heap and -heap[0][0] > target and split_worst():
        pass
    M = int(pieces.sum())
    if M > N:
        # Round up to the ladder (within the cap), extra pieces to the largest predictions.
        M_ladder = min(mesh_size(M), max_intervals)
        heap = [(-err[k] / pieces[k] ** power, k) for k in range(N)]
        heapq.heapify(heap)
        while int(pieces.sum()) < M_ladder and split_worst():
            pass
    new = np.repeat(frac / pieces, pieces)
    return new / new.sum(), pieces


def parent_intervals(pieces: Any) -> np.ndarray:
    """Old interval of each new interval.

    Parameters
    ----------
    pieces : array_like of int, shape (N,)
        Pieces per old interval (from :func:`refine_mesh`).

    Returns
    -------
    ndarray of int, shape (sum(pieces),)
        Index of the old interval containing each new one.
    """
    p = np.asarray(pieces, dtype=int)
    return np.repeat(np.arange(p.size), p)


def collocation_states(t: Any, x: Any, xc: Any, degree: int, scheme: str, tq: Any) -> np.ndarray:
    """States of a collocation solution at arbitrary times (its own polynomials).

    Parameters
    ----------
    t : array_like, shape (N + 1,)
        Grid times [s] of the solution.
    x : array_like, shape (N + 1, nx)
        Grid states.
    xc : array_like, shape (N * degree, nx)
        Collocation states, ``degree`` rows per interval.
    degree : int
        Collocation degree d.
    scheme : {"radau", "legendre"}
        Collocation points (CasADi's ``collocation_points``).
    tq : array_like, shape (K,)
        Query times [s], clipped to [t[0], t[-1]].

    Returns
    -------
    ndarray, shape (K, nx)
        The interval polynomial through (x_k, xc_k1..xc_kd) evaluated at each
        query time; the grid states exactly at grid times.

    Raises
    ------
    ValueError
        Inconsistent shapes.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    N = t.size - 1
    xc = np.asarray(xc, dtype=float)
    if x.shape[0] != N + 1 or xc.shape != (N * degree, x.shape[1]):
        raise ValueError(f"x must have {N + 1} rows and xc {N * degree} rows of {x.shape[1]} states, got {x.shape}, {xc.shape}")
    tq = np.clip(np.asarray(tq, dtype=float), t[0], t[-1])
    k = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, N - 1)
    tau = (tq - t[k]) / (t[k + 1] - t[k])
    nodes = np.append(0.0, ca.collocation_points(degree, scheme))
    # Lagrange basis values at tau, shape (K, d + 1).
    basis = np.ones((tq.size, degree + 1))
    for r in range(degree + 1):
        for s in range(degree + 1):
            if s != r:
                basis[:, r] *= (tau - nodes[s]) / (nodes[r] - nodes[s])
    pts = np.concatenate([x[:-1, None, :], xc.reshape(N, degree, -1)], axis=1)  # (N, d + 1, nx)
    out = np.einsum("kr,krn->kn", basis, pts[k])
    at_end = tq >= t[-1]
    out[at_end] = x[-1]
    return out


def _radau_oscillation_error(z: np.ndarray, degree: int) -> np.ndarray:
    """|R(iz) - exp(iz)| with R the (d - 1, d) Padé approximant of exp (Radau IIA's stability function)."""
    k, j = degree - 1, degree
    iz = 1j * np.asarray(z, dtype=float)
    num = sum(
        math.factorial(k + j - n)
        * math.factorial(k)
        / (math.factorial(k + j) * math.factorial(n) * math.factorial(k - n))
        * iz**n
        for n in range(k + 1)
    )
    den = sum(
        math.factorial(k + j - n)
        * math.factorial(j)
        / (math.factorial(k + j) * math.factorial(n) * math.factorial(j - n))
        * (-iz) ** n
        for n in range(j + 1)
    )
    return np.abs(num / den - np.exp(iz))


def radau_resolution(degree: int, tolerance: float) -> float:
    """Largest ``h w`` at which Radau collocation of ``degree`` follows an undamped oscillation within ``tolerance``.

    Parameters
    ----------
    degree : int
        Collocation degree d (>= 1).
    tolerance : float
        Per-interval error allowed, relative to the oscillation's amplitude (0 < tolerance < 1).

    Returns
    -------
    float
        ``h w`` [rad], interval length times angular frequency (e.g. 1.41 for d = 3
        and 6.6 for d = 7 at 1e-3).

    Raises
    ------
    ValueError
        ``degree`` < 1 or ``tolerance`` outside (0, 1).
    """
    if not (isinstance(degree, (int, np.integer)) and degree >= 1):
        raise ValueError(f"degree must be an integer >= 1, got {degree!r}")
    if not (0.0 < float(tolerance) < 1.0):
        raise ValueError(f"tolerance must be in (0, 1), got {tolerance!r}")
    # The error grows monotonically from 0 up to h w ~ 2 d; beyond, the Padé approximant has nothing left to resolve.
    z = np.linspace(0.0, 2.0 * degree, 20001)[1:]
    above = np.nonzero(_radau_oscillation_error(z, int(degree)) > tolerance)[0]
    if not above.size:
        return float(z[-1])
    return float(z[max(int(above[0]) - 1, 0)])


def oscillation_mesh(horizon: float, omega: float, degree: int, tolerance: float, N: int = 1) -> int:
    """Uniform intervals that resolve an oscillation of ``omega`` over ``horizon`` at ``degree`` (at least ``N``).

    Parameters
    ----------
    horizon : float
        Time span [s] (> 0).
    omega : float
        Angular frequency to resolve [rad/s] (>= 0; inf raises).
    degree : int
        Radau collocation degree.
    tolerance : float
        Per-interval error relative to the oscillation's amplitude (see :func:`radau_resolution`).
    N : int
        Lower bound on the result (e.g. what the slow motion needs).

    Returns
    -------
    int
        ``max(N, ceil(horizon * omega / radau_resolution(degree, tolerance)))``.

    Raises
    ------
    ValueError
        Non-positive or non-finite ``horizon``, negative or non-finite ``omega``, or bad ``degree`` / ``tolerance``.
    """
    if not (math.isfinite(horizon) and horizon > 0.0):
        raise ValueError(f"horizon must be a positive finite time [s], got {horizon!r}")
    if not (math.isfinite(omega) and omega >= 0.0):
        raise ValueError(f"omega must be a finite frequency >= 0 [rad/s], got {omega!r}")
    return max(int(N), math.ceil(horizon * omega / radau_resolution(degree, tolerance)))

"""Release states of the flip map: the angle grid, the energy threshold ``V_flip`` and the initial states.

See :mod:`pendulab.ensemble.flipmap` for the method (energy threshold, point symmetry, quasi-static start).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._checks import check_model
from .._inputs import checked

__all__ = ["flip_map_grid", "flip_energy_threshold", "flip_initial_states", "MAX_GRID"]

_STARTS = ("quasi-static", "static")
#: Largest number of grid points per angle (see also flipmap.MAX_GRID_POINTS for the whole grid).
MAX_GRID = 20000


# -- grid and initial states ----------------------------------------------------
def _check_range(name: str, rng: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in rng)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (low, high) in rad, got {rng!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} must be finite with low < high [rad], got {rng!r}")
    return lo, hi


@checked(n="grid")
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
    n = int(n)
    lo, hi = _check_range("theta_range", theta_range)
    h = (hi - lo) / n
    centre = 0.5 * (lo + hi)
    return centre + (np.arange(n) - (n - 1) / 2.0) * h


#: IPOPT outcomes of a converged minimisation ("search direction too small": no step left at rounding level).
_CONVERGED = ("Solve_Succeeded", "Solved_To_Acceptable_Level", "Search_Direction_Becomes_Too_Small")


@checked()
def flip_energy_threshold(model: Any) -> float:
    """Least potential energy of a configuration in which a link has flipped.

    ``V_flip = min { V(q) : |theta1| = pi or |theta2| = pi }``, minimised
    numerically over the free coordinates (the other angle, and the spring
    lengths of the elastic model) with the model's own potential-energy
    function and its exact CasADi derivatives (IPOPT), from several starts. A point
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

    check_model(model)
    nq, nx = model.nq, model.nx
    pot = model.functions["potential"]
    rest = model.rest_state()
    # IPOPT through CasADi (already loaded, exact Hessian), not SciPy's L-BFGS-B: importing scipy.optimize
    # alone was 0.5 s of the flip-map command, whose whole budget is 2 s. The threshold must not be
    # too high (points above the true one would be skipped), so the solve goes to 1e-14.
    options = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes", "tol": 1e-14, "max_iter": 1000}}
    best = math.inf
    for flipped in (0, 1):
        free = [i for i in range(nq) if i != flipped]
        z = ca.SX.sym("z", len(free))
        q = [ca.SX(0)] * nq
        q[flipped] = ca.SX(math.pi)
        for k, i in enumerate(free):
            q[i] = z[k]
        x = ca.vertcat(*q, ca.SX.zeros(nx - nq))
        solver = ca.nlpsol("v_flip", "ipopt", {"x": z, "f": pot(x, model.p)}, options)
        lower = [-math.inf if i < 2 else 1e-6 * rest[i] for i in free]
        converged, statuses = [], []
        for other in (0.0, 0.5 * math.pi, math.pi, -0.5 * math.pi):
            z0 = [other if i < 2 else rest[i] for i in free]
            value = float(solver(x0=z0, lbx=lower)["f"])
            statuses.append(solver.stats()["return_status"])
            if math.isfinite(value) and statuses[-1] in _CONVERGED:
                converged.append(value)
        if not converged:  # every start failed: no threshold to trust
            raise RuntimeError(f"flip energy threshold: minimisation failed for link {flipped + 1}: {sorted(set(statuses))}")
        best = min(best, *converged)
    return best


@checked()
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

"""The static spring stretch: spring lengths that carry the gravity load along each link (one place).

With the links at rest at absolute angles (theta1, theta2), spring 2 carries
the along-link weight component m2 g cos(theta2) and spring 1 carries
(m1 + m2) g cos(theta1). This is exact for aligned vertical configurations
(hanging: stretched; inverted: compressed) and a seed elsewhere; the exact
zero-radial-acceleration lengths at any state are
:func:`pendulab.model.quasistatic.quasi_static_lengths`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .params import ElasticParams

__all__ = ["static_spring_lengths", "static_spring_rates"]


def _loads(params: ElasticParams) -> tuple[float, float]:
    """Static stretch of each spring when hanging straight down [m]."""
    if not isinstance(params, ElasticParams):
        raise TypeError(f"params must be ElasticParams (springs), got {type(params).__name__}")
    return (params.m1 + params.m2) * params.g / params.k1, params.m2 * params.g / params.k2


def static_spring_lengths(params: ElasticParams, theta: Any = (0.0, 0.0)) -> np.ndarray:
    """Spring lengths r1, r2 [m] carrying the gravity load along each link.

    Parameters
    ----------
    params : ElasticParams
        Elastic parameters (masses, rest lengths, g, stiffnesses).
    theta : array_like, shape (2,) or (N, 2)
        Absolute link angles [rad] from the downward vertical (default hanging).

    Returns
    -------
    ndarray, shape (2,) or (N, 2)
        ``r1 = L1 + (m1 + m2) g cos(theta1) / k1``, ``r2 = L2 + m2 g cos(theta2) / k2``.

    Raises
    ------
    TypeError
        ``params`` are not elastic parameters.
    """
    a1, a2 = _loads(params)
    th = np.asarray(theta, dtype=float)
    return np.stack([params.L1 + a1 * np.cos(th[..., 0]), params.L2 + a2 * np.cos(th[..., 1])], axis=-1)


def static_spring_rates(params: ElasticParams, theta: Any, omega: Any) -> np.ndarray:
    """Time derivative of :func:`static_spring_lengths` along a motion (theta, omega).

    Parameters
    ----------
    params : ElasticParams
        Elastic parameters.
    theta, omega : array_like, shape (2,) or (N, 2)
        Link angles [rad] and rates [rad/s].

    Returns
    -------
    ndarray, shape (2,) or (N, 2)
        dr1/dt, dr2/dt [m/s].

    Raises
    ------
    TypeError
        ``params`` are not elastic parameters.
    """
    a1, a2 = _loads(params)
    th, om = np.asarray(theta, dtype=float), np.asarray(omega, dtype=float)
    return np.stack([-a1 * np.sin(th[..., 0]) * om[..., 0], -a2 * np.sin(th[..., 1]) * om[..., 1]], axis=-1)

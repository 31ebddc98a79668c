"""Controllability and observability: staircase subspaces, finite-horizon Gramians, a report.

The controllability *matrix* of the elastic pendulum spans many decades (spring
modes near 36 rad/s raise A^7 to ~1e11), so ranks come from an orthogonal
staircase (Krylov) iteration instead, and the strength of the weakest
direction from the finite-horizon Gramian
``W(T) = int_0^T exp(A t) B B^T exp(A^T t) dt`` (computed by Van Loan's
block exponential), which exists for unstable A as well.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import expm, null_space

from .._inputs import checked
from ..analysis.equilibria import Equilibrium, equilibria, equilibrium
from ..analysis.linearize import OutputSpec, linearize
from ..model.model import ACTUATIONS, Model

__all__ = [
    "controllable_subspace",
    "finite_gramian",
    "ReportRow",
    "controllability_report",
    "format_report",
]


@checked()
def controllable_subspace(A: np.ndarray, B: np.ndarray, rtol: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal bases of the controllable subspace of (A, B) and of its complement.

    Parameters
    ----------
    A : ndarray, shape (n, n)
    B : ndarray, shape (n, m)
    rtol : float
        New Krylov directions shorter than ``rtol * max(||A||, ||B||)`` count as
        dependent.

    Returns
    -------
    Qc : ndarray, shape (n, r)
        Orthonormal basis of span[B, AB, A^2 B, ...]; r is the controllability rank.
    Qu : ndarray, shape (n, n - r)
        Orthonormal basis of its orthogonal complement.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import controllable_subspace, upright_state
    >>> model = pl.elastic()
    >>> lin = pl.linearize(model, upright_state(model), inputs="pendubot")
    >>> Qc, Qu = controllable_subspace(lin.A, lin.B)
    >>> Qc.shape[1], Qu.shape[1]  # rank 4 of 8: the spring states are out of reach upright
    (4, 4)
    >>> bool(np.allclose(Qu.T @ lin.B, 0.0) and np.allclose(Qu.T @ lin.A @ Qc, 0.0))  # invariant complement
    True
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    n = A.shape[0]
    scale = max(np.linalg.norm(A, 2), np.linalg.norm(B, 2), 1e-300)
    basis = np.zeros((n, 0))
    block = B
    for _ in range(n):
        # Two Gram-Schmidt passes keep the basis orthogonal to machine precision.
        for _ in range(2):
            block = block - basis @ (basis.T @ block)
        U, s, _ = np.linalg.svd(block, full_matrices=False)
        keep = s > rtol * scale
        if not np.any(keep):
            break
        new = U[:, keep]
        basis = np.hstack([basis, new])
        if basis.shape[1] >= n:
            break
        block = A @ new
    Qu = null_space(basis.T) if basis.shape[1] < n else np.zeros((n, 0))
    return basis, Qu


@checked()
def finite_gramian(A: np.ndarray, B: np.ndarray, horizon: float) -> np.ndarray:
    """Finite-horizon controllability Gramian ``int_0^T e^(At) B B^T e^(A^T t) dt``.

    Computed with Van Loan's block exponential, so ``A`` may be unstable. For
    the observability Gramian pass ``A.T`` and ``C.T``.

    Parameters
    ----------
    A : ndarray, shape (n, n)
        State matrix [1/s].
    B : ndarray, shape (n, m)
        Input matrix.
    horizon : float
        Horizon T [s].

    Returns
    -------
    ndarray, shape (n, n)
        The symmetric Gramian W(T).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import finite_gramian, upright_state
    >>> W = finite_gramian(np.array([[-1.0]]), np.array([[1.0]]), 1.0)  # int_0^1 exp(-2 t) dt
    >>> round(float(W[0, 0]), 4), round(float((1 - np.exp(-2.0)) / 2), 4)
    (0.4323, 0.4323)
    >>> model = pl.rigid()
    >>> for act in ("pendubot", "acrobot"):  # weakest reachable direction upright in 1 s
    ...     lin = pl.linearize(model, upright_state(model), inputs=act)
    ...     print(act, f"{np.linalg.eigvalsh(finite_gramian(lin.A, lin.B, 1.0)).min():.2g}")
    pendubot 7.4e-05
    acrobot 1.1e-05
    """
    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float)
    n = A.shape[0]
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -A
    M[:n, n:] = B @ B.T
    M[n:, n:] = A.T
    E = expm(M * horizon)
    W = E[n:, n:].T @ E[:n, n:]
    return 0.5 * (W + W.T)


@dataclass(frozen=True)
class ReportRow:
    """Controllability and observability of one actuation at one equilibrium.

    Attributes
    ----------
    equilibrium : str
    actuation : str
    n : int
        Number of states.
    ctrb_rank, obsv_rank : int
        Staircase ranks (n means controllable / observable).
    ctrb_min_sv, obsv_min_sv : float
        Smallest eigenvalue of the finite-horizon controllability / observability
        Gramian; units are mixed (state units squared per N^2 m^2 s, per output
        unit squared) -- compare rows, not absolute values.
    ctrb_weakest, obsv_weakest : tuple of str
        States that dominate the weakest direction (components >= 30 % of the
        largest, by magnitude), or the uncontrollable / unobservable subspace
        when the rank is deficient.
    uncontrollable_eigenvalues : ndarray of complex
        Eigenvalues of A restricted to the uncontrollable subspace (empty when
        controllable).
    outputs : tuple of str
        Measured signals used for observability.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import controllability_report
    >>> row = controllability_report(pl.elastic(), at=["down-down"], actuations=["acrobot"])[0]  # a ReportRow
    >>> row.equilibrium, row.ctrb_rank, row.obsv_rank, row.outputs  # 4 of 8 states, from the two encoders
    ('down-down', 4, 4, ('theta1', 'theta2'))
    >>> np.round(np.abs(row.uncontrollable_eigenvalues), 2)  # spring modes the elbow torque cannot reach [rad/s]
    array([13.82, 13.82, 36.18, 36.18])
    >>> import json
    >>> json.loads(json.dumps(row.as_dict()))["ctrb_weakest"]  # as_dict() is JSON-friendly
    ['r1', 'r2', 'v1', 'v2']
    """

    equilibrium: str
    actuation: str
    n: int
    ctrb_rank: int
    ctrb_min_sv: float
    ctrb_weakest: tuple[str, ...]
    obsv_rank: int
    obsv_min_sv: float
    obsv_weakest: tuple[str, ...]
    uncontrollable_eigenvalues: np.ndarray
    outputs: tuple[str, ...]

    def as_dict(self) -> dict[str, Any]:
        """JSON-friendly row.

        Returns
        -------
        dict
            One entry per field; tuples become lists and
            ``uncontrollable_eigenvalues`` a list of ``[real, imag]`` pairs [1/s].
        """
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d["uncontrollable_eigenvalues"] = [[float(e.real), float(e.imag)] for e in self.uncontrollable_eigenvalues]
        d["ctrb_weakest"] = list(self.ctrb_weakest)
        d["obsv_weakest"] = list(self.obsv_weakest)
        d["outputs"] = list(self.outputs)
        return d


def _dominant(vectors: np.ndarray, names: Sequence[str]) -> tuple[str, ...]:
    """States whose rows carry >= 30 % of the largest row norm of a basis (n, r)."""
    weight = np.linalg.norm(vectors.reshape(len(names), -1), axis=1)
    return tuple(n for n, w in zip(names, weight, strict=True) if w >= 0.3 * weight.max())


def _weakest(W: np.ndarray, missing: np.ndarray, names: Sequence[str]) -> tuple[float, tuple[str, ...]]:
    """Smallest Gramian eigenvalue and the states of the weakest direction.

    When the rank is deficient the weakest "direction" is the whole missing
    subspace (``missing``, n x (n - rank)); name its states rather than one
    arbitrary vector inside it.
    """
    w, V = np.linalg.eigh(W)
    direction = missing if missing.shape[1] else V[:, :1]
    return float(max(w[0], 0.0)), _dominant(direction, names)


@checked()
def controllability_report(
    model: Model,
    at: Sequence[str | Equilibrium] | None = None,
    actuations: Sequence[str] = tuple(ACTUATIONS),
    outputs: OutputSpec = ("theta1", "theta2"),
    horizon: float = 1.0,
) -> list[ReportRow]:
    """Controllability and observability per actuation at each equilibrium.

    Parameters
    ----------
    model : Model
    at : sequence of str or Equilibrium, optional
        Equilibria (names are solved at zero torque); default all four.
    actuations : sequence of {"full", "pendubot", "acrobot"}
    outputs : str or sequence of str
        Measured signals for observability (default the two joint encoders'
        absolute angles).
    horizon : float
        Gramian horizon T [s].

    Returns
    -------
    list of ReportRow
        One row per (equilibrium, actuation), equilibria in the outer loop.

    Raises
    ------
    ValueError
        ``horizon`` is not a finite positive number.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import controllability_report
    >>> for row in controllability_report(pl.rigid(), at=["up-up"]):
    ...     print(row.actuation, f"{row.ctrb_rank}/{row.n}")
    full 4/4
    pendubot 4/4
    acrobot 4/4
    >>> row = controllability_report(pl.elastic(), at=["up-up"], actuations=["pendubot"])[0]
    >>> row.ctrb_rank, row.ctrb_weakest  # the torques cannot reach the springs upright (to first order)
    (4, ('r1', 'r2', 'v1', 'v2'))
    """
    if not (isinstance(horizon, (int, float)) and np.isfinite(horizon) and horizon > 0):
        raise ValueError(f"horizon must be a positive number of seconds, got {horizon!r}")
    eqs = equilibria(model) if at is None else [equilibrium(model, e) if isinstance(e, str) else e for e in at]
    rows = []
    for eq in eqs:
        for act in actuations:
            lin = linearize(model, eq, inputs=act, outputs=outputs)
            Qc, Qu = controllable_subspace(lin.A, lin.B)
            Qo, Qno = controllable_subspace(lin.A.T, lin.C.T)
            c_sv, c_dir = _weakest(finite_gramian(lin.A, lin.B, horizon), Qu, lin.state_names)
            o_sv, o_dir = _weakest(finite_gramian(lin.A.T, lin.C.T, horizon), Qno, lin.state_names)
            unc = np.linalg.eigvals(Qu.T @ lin.A @ Qu) if Qu.shape[1] else np.zeros(0, dtype=complex)
            rows.append(
                ReportRow(
                    equilibrium=eq.name,
                    actuation=act,
                    n=model.nx,
                    ctrb_rank=Qc.shape[1],
                    ctrb_min_sv=c_sv,
                    ctrb_weakest=c_dir,
                    obsv_rank=Qo.shape[1],
                    obsv_min_sv=o_sv,
                    obsv_weakest=o_dir,
                    uncontrollable_eigenvalues=unc,
                    outputs=lin.output_names,
                )
            )
    return rows


def format_report(rows: Sequence[ReportRow]) -> str:
    """Plain-text table of a controllability report.

    Parameters
    ----------
    rows : sequence of ReportRow
        As returned by :func:`controllability_report`.

    Returns
    -------
    str
        A header, a rule and one line per row (ranks as ``rank/n``, smallest
        Gramian eigenvalues and the weakest states), newline-separated.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import controllability_report, format_report
    >>> print(format_report(controllability_report(pl.rigid(), at=["up-up", "down-down"], actuations=["pendubot"])))
    equilibrium actuation  ctrb min eig Wc  weakest (ctrb)          obsv min eig Wo  weakest (obsv)
    -----------------------------------------------------------------------------------------------
    up-up       pendubot   4/4    7.37e-05  theta1,theta2           4/4     0.00237  omega1,omega2
    down-down   pendubot   4/4     0.00152  theta1,omega1,omega2    4/4      0.0139  omega1,omega2
    """
    head = (
        f"{'equilibrium':<11} {'actuation':<9} {'ctrb':>5} {'min eig Wc':>10}  {'weakest (ctrb)':<22} "
        f"{'obsv':>5} {'min eig Wo':>10}  weakest (obsv)"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r.equilibrium:<11} {r.actuation:<9} {r.ctrb_rank:>2}/{r.n:<2} {r.ctrb_min_sv:>10.3g}  "
            f"{','.join(r.ctrb_weakest):<22} {r.obsv_rank:>2}/{r.n:<2} {r.obsv_min_sv:>10.3g}  {','.join(r.obsv_weakest)}"
        )
    return "\n".join(lines)

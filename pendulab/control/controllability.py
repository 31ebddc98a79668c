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

"""``Trajectory``: the result of a simulation (native or FMU), with named columns."""

from __future__ import annotations

import csv
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_open

__all__ = ["Trajectory"]


@dataclass(frozen=True)
class Trajectory:
    """Time series of states, inputs and outputs on an output grid.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Output times [s].
    x : ndarray, shape (N, nx)
        States in ``state_names`` order.
    u : ndarray, shape (N, nu)
        Inputs applied from ``t[k]`` to ``t[k+1]`` (last row repeats).
    y : ndarray, shape (N, ny)
        Outputs in ``output_names`` order.
    state_names, input_names, output_names : tuple of str
    method : str
        Integration method (or ``"fmu:..."``).
    success : bool
        True when the run reached ``t[-1]`` as requested.
    message : str
        Solver message.
    stats : dict
        Solver statistics: ``wall_time`` [s], ``n_rhs`` (right-hand-side
        evaluations, where the solver reports them), ``n_steps``, ...

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> traj = pl.simulate(pl.rigid(), [1.0, 0.0, 0.0, 0.0], 2.0, dt=0.01)
    >>> traj.t.shape, traj.x.shape, traj.u.shape, traj.y.shape  # 201 output times
    ((201,), (201, 4), (201, 2), (201, 5))
    >>> traj.output_names
    ('x1', 'y1', 'x2', 'y2', 'energy')
    >>> bool(np.ptp(traj["energy"]) < 1e-6)  # any state, input or output by name; energy conserved [J]
    True
    >>> traj.to_csv("swing.csv").name
    'swing.csv'
    """

    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    y: np.ndarray
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    method: str
    success: bool = True
    message: str = ""
    stats: Mapping[str, Any] = field(default_factory=dict)

    @property
    def names(self) -> tuple[str, ...]:
        """All column names: states, inputs, outputs."""
        return self.state_names + self.input_names + self.output_names

    def __getitem__(self, name: str) -> np.ndarray:
        """Column by name, e.g. ``traj["theta1"]``, shape (N,)."""
        for names, data in ((self.state_names, self.x), (self.input_names, self.u), (self.output_names, self.y)):
            if name in names:
                return data[:, names.index(name)]
        raise KeyError(f"unknown column {name!r}; available: {list(self.names)}")

    def table(self) -> np.ndarray:
        """All columns side by side.

        Returns
        -------
        ndarray, shape (N, 1 + nx + nu + ny)
            Columns t [s], states, inputs, outputs (SI units), in the order
            ``("t",) + names``.
        """
        return np.column_stack([self.t, self.x, self.u, self.y])

    def to_csv(self, path: str | Path) -> Path:
        """Write a CSV with header ``t, <states>, <inputs>, <outputs>`` (SI units).

        The file is written atomically (a temporary file renamed over ``path``):
        an interrupted run never leaves a truncated CSV.

        Parameters
        ----------
        path : str or Path
            Output file; missing parent directories are created.

        Returns
        -------
        Path
            The file written.
        """
        path = Path(path)
        with atomic_open(path, "w", newline="") as fh:
            writer = csv.writer(fh)
            writer.writerow(("t",) + self.names)
            for row in self.table():
                writer.writerow([repr(float(v)) for v in row])
        return path

    def to_npz(self, path: str | Path) -> Path:
        """Write the arrays, names, method, success flag and message to a NumPy ``.npz`` archive.

        ``stats`` is not written. The file is written atomically (a temporary
        file renamed over it): an interrupted run never leaves a truncated archive.

        Parameters
        ----------
        path : str or Path
            Output file; missing parent directories are created. NumPy appends
            ``.npz`` when the name lacks it.

        Returns
        -------
        Path
            ``path`` as given (without any suffix NumPy appended).
        """
        path = Path(path)
        target = path if path.name.endswith(".npz") else path.with_name(path.name + ".npz")
        with atomic_open(target, "wb") as fh:
            self._savez(fh)
        return path

    def _savez(self, fh: Any) -> None:
        np.savez(
            fh,
            t=self.t,
            x=self.x,
            u=self.u,
            y=self.y,
            state_names=np.array(self.state_names),
            input_names=np.array(self.input_names),
            output_names=np.array(self.output_names),
            method=np.array(self.method),
            success=np.array(self.success),
            message=np.array(self.message),
        )

"""High-accuracy reference solutions, computed once and stored as data.

Every case gets a primary reference, SciPy DOP853 at rtol = atol = 1e-13,
checked against an independent solution:

* rigid cases: a Gragg-Bulirsch-Stoer extrapolation integrator in 32-digit
  arithmetic (mpmath) on the same right-hand side (the CasADi graph translated
  to Python, evaluated with mpmath instead of ``math``); its own accuracy is
  checked by halving its step. It is the stored solution when present, and
  the DOP853 run is kept to state how far a double-precision 1e-13 solution is.
* elastic cases: CVODES Adams at rtol = atol = 1e-13 (different code,
  different method family).

The stored ``accuracy`` of a reference is the max-abs difference over the
output grid between the two independent solutions (an upper estimate of the
error of the less accurate one); errors below it are not resolved.
Files: ``references/<case>.npz`` with t, x (on the output grid), the
methods used and the agreement numbers.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from .._io import atomic_path
from ..integrate import simulate
from ..model.pycode import to_python
from ..scene import Scene

__all__ = ["Reference", "REFERENCE_DIR", "load_reference", "compute_reference", "gbs_mp", "ReferenceMissingError"]

REFERENCE_DIR = Path(__file__).resolve().parent / "references"


class ReferenceMissingError(FileNotFoundError):
    """No stored reference for a case (run ``pendulab bench references``)."""


@dataclass(frozen=True)
class Reference:
    """A stored reference solution on a case's output grid.

    Attributes
    ----------
    case : str
        Case (scene) name.
    t : ndarray, shape (N,)
        Output grid [s].
    x : ndarray, shape (N, nx)
        Reference states on the grid.
    method : str
        How the stored solution was computed.
    check_method : str
        The independent solution(s) it was checked against.
    accuracy : float
        Max-abs grid difference between the two independent solutions
        [state units]; errors below it are not resolved.
    notes : str
        Agreement figures in words.
    """

    case: str
    t: np.ndarray  # (N,) [s]
    x: np.ndarray  # (N, nx)
    method: str
    check_method: str
    accuracy: float  # max-abs grid difference between the two independent solutions
    notes: str

    def save(self, directory: Path = REFERENCE_DIR) -> Path:
        """Write ``<directory>/<case>.npz`` (compressed; the directory is created).

        Parameters
        ----------
        directory : Path
            Target directory; default the shipped ``references`` folder.

        Returns
        -------
        Path
            The written file.
        """
        directory.mkdir(parents=True, exist_ok=True)
        path = directory / f"{self.case}.npz"
        with atomic_path(path) as tmp:
            np.savez_compressed(
                tmp,
                t=self.t,
                x=self.x,
                method=self.method,
                check_method=self.check_method,
                accuracy=self.accuracy,
                notes=self.notes,
            )
        return path


def load_reference(case: Scene, directory: Path = REFERENCE_DIR) -> Reference:
    """Load the stored reference of ``case``.

    Parameters
    ----------
    case : Scene
        A benchmark case; its name selects the file, its ``t_final`` and
        ``x0`` must match the stored solution (``x0`` to 1e-12).
    directory : Path
        Where the ``<case>.npz`` files are.

    Returns
    -------
    Reference
        The stored solution.

    Raises
    ------
    ReferenceMissingError
        No file for the case, or the stored horizon or start state differs
        (stale); run ``pendulab bench references``.
    """
    path = Path(directory) / f"{case.name}.npz"
    if not path.is_file():
        raise ReferenceMissingError(f"no stored reference for case {case.name!r} at {path}; run 'pendulab bench references'")
    d = np.load(path)
    t = d["t"]
    # 1e-12: the quasi-static start comes from a Newton solve whose last bits may vary by platform.
    if not np.isclose(t[-1], case.t_final) or not np.allclose(d["x"][0], case.x0, rtol=0, atol=1e-12):
        raise ReferenceMissingError(f"stored reference {path} does not match case {case.name!r}; run 'pendulab bench references'")
    return Reference(case.name, t, d["x"], str(d["method"]), str(d["check_method"]), float(d["accuracy"]), str(d["notes"]))


# -- extended-precision Gragg-Bulirsch-Stoer -----------------------------------
def _mp_rhs(model: Any) -> Callable[[list], list]:
    import mpmath

    g = to_python(model.functions["rhs"])
    # The generated code calls _m.<fun> and _np.array: point them at mpmath / a list.
    g.__globals__["_m"] = mpmath
    g.__globals__["_np"] = SimpleNamespace(array=list)
    p = [mpmath.mpf(float(v)) for v in model.p]
    u = [mpmath.mpf(0)] * model.nu
    return lambda x: g(x, u, p)


def gbs_mp(
    model: Any,
    x0: np.ndarray,
    t_final: float,
    dt: float,
    *,
    substeps: int = 1,
    levels: int = 12,
    dps: int = 32,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[np.ndarray, float]:
    """Gragg-Bulirsch-Stoer extrapolation in ``dps``-digit arithmetic, fixed macro step.

    Parameters
    ----------
    model : Model
        Unforced model (torques zero).
    x0 : ndarray, shape (nx,)
    t_final, dt : float
        Horizon and output step [s]; the macro step is ``dt / substeps``.
    substeps : int
        Macro steps per output interval.
    levels : int
        Extrapolation levels, midpoint sequence 2, 4, ..., 2 levels (order 2 levels).
    dps : int
        Decimal digits of the mpmath arithmetic.
    progress : callable(int, int), optional
        Called as ``progress(k, n_out)`` after each output interval.

    Returns
    -------
    X : ndarray, shape (N, nx)
        States on the output grid (rounded to float64).
    est : float
        Largest difference between the last two extrapolation levels over all
        macro steps (local error estimate).
    """
    import mpmath

    n_out = int(round(t_final / dt))
    with mpmath.workdps(dps):
        f = _mp_rhs(model)
        H = mpmath.mpf(t_final) / (n_out * substeps)
        x = [mpmath.mpf(float(v)) for v in x0]
        nx = len(x)
        X = np.empty((n_out + 1, nx))
        X[0] = x0
        est = mpmath.mpf(0)
        seq = [2 * (j + 1) for j in range(levels)]
        for k in range(n_out):
            for _ in range(substeps):
                f0 = f(x)
                T: list[list] = []
                for j, n in enumerate(seq):
                    h = H / n
                    z0 = x
                    z1 = [a + h * b for a, b in zip(x, f0, strict=False)]
                    for _i in range(n - 1):
                        fz = f(z1)
                        z0, z1 = z1, [a + 2 * h * b for a, b in zip(z0, fz, strict=False)]
                    fz = f(z1)
                    row = [[(a + b + h * c) / 2 for a, b, c in zip(z0, z1, fz, strict=False)]]
                    for m in range(1, j + 1):
                        ratio = (mpmath.mpf(seq[j]) / seq[j - m]) ** 2 - 1
                        row.append([a + (a - b) / ratio for a, b in zip(row[m - 1], T[j - 1][m - 1], strict=False)])
                    T.append(row)
                x = T[-1][-1]
                est = max(est, max(abs(a - b) for a, b in zip(T[-1][-1], T[-1][-2], strict=False)))
            X[k + 1] = [float(v) for v in x]
            if progress is not None:
                progress(k + 1, n_out)
        return X, float(est)


def compute_reference(case: Scene, *, progress: Callable[[str], None] | None = None) -> Reference:
    """Compute the reference of one case (seconds for elastic cases, about a minute for rigid 10 s).

    Rigid cases: GBS in 32 digits at macro step dt/4, checked at dt/2 and
    against DOP853 (1e-13). Elastic cases: DOP853 checked against CVODES
    Adams (both at 1e-13).

    Parameters
    ----------
    case : Scene
        A benchmark case (unforced).
    progress : callable(str), optional
        Called with a one-line message before each solve.

    Returns
    -------
    Reference
        The solution on the case's output grid, not yet saved.
    """
    model = case.model
    x0 = case.x0
    say = progress or (lambda _msg: None)
    say(f"{case.name}: DOP853 rtol 1e-13")
    dop = simulate(model, x0, case.t_final, case.dt, "DOP853", 1e-13, 1e-13).x
    if case.kind == "rigid":
        # Macro step dt/2 = 25 ms (h w ~ 0.25 in the fast phases of the chaotic
        # swing), checked by halving it.
        say(f"{case.name}: Gragg-Bulirsch-Stoer, 32 digits")
        X, est = gbs_mp(model, x0, case.t_final, case.dt, substeps=2)
        say(f"{case.name}: Gragg-Bulirsch-Stoer, 32 digits, half step")
        X2, _ = gbs_mp(model, x0, case.t_final, case.dt, substeps=4)
        self_check = float(np.max(np.abs(X - X2)))
        dop_err = float(np.max(np.abs(dop - X2)))
        return Reference(
            case.name,
            np.linspace(0.0, case.t_final, X.shape[0]),
            X2,
            "Gragg-Bulirsch-Stoer extrapolation (order 24), mpmath 32 digits, macro step dt/4",
            "same at macro step dt/2; and SciPy DOP853 rtol=atol=1e-13",
            # Rounding the 32-digit solution to float64 leaves at least one ulp.
            max(self_check, float(np.finfo(float).eps * np.max(np.abs(X2)))),
            f"GBS step-halving difference {self_check:.3e}; DOP853(1e-13) vs GBS {dop_err:.3e}; "
            f"last-level local estimate {est:.3e}",
        )
    say(f"{case.name}: CVODES Adams rtol 1e-13")
    adams = simulate(model, x0, case.t_final, case.dt, "cvodes-adams", 1e-13, 1e-13).x
    diff = float(np.max(np.abs(dop - adams)))
    return Reference(
        case.name,
        np.linspace(0.0, case.t_final, dop.shape[0]),
        dop,
        "SciPy DOP853 rtol=atol=1e-13",
        "CVODES Adams rtol=atol=1e-13",
        diff,
        f"DOP853 vs CVODES Adams max grid difference {diff:.3e}",
    )

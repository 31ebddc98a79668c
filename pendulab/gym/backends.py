"""Plants behind the environment: one state advanced by one sample ``dt`` at a time under a held torque.

* :class:`NativePlant` keeps one integrator alive across steps, so a step costs one call
  into compiled code: heyoka's adaptive Taylor integrator (``integrator="taylor"``; the
  compiled system is shared through :mod:`pendulab.integrate.taylor`'s cache, torques are
  runtime parameters, unactuated torques are specialised to zero) or the C library's
  DOPRI5 / RODAS4 interval stepper (``"compiled-dopri5"`` / ``"compiled-rodas4"``, the
  FMU's solvers run natively). ``"auto"`` takes Taylor when heyoka is installed (fastest at
  every tolerance and stiffness measured, see ``docs/gym.md``), else compiled DOPRI5.
* :class:`FmuBackend` drives the exported co-simulation FMU through fmpy
  (:class:`pendulab.cosim.FmuPlant`); the FMU is exported once per model kind and source
  digest into the cache folder and reused (parameters are FMU parameters set at start).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ..integrate.taylor import compiled_integrator, structure_key
from ..integrate.taylor.availability import heyoka_module, unavailable_reason
from ..model.model import ACTUATIONS, Model, make_model
from ..native.build import cache_dir, compiler_unavailable_reason, source_digest
from ..native.library import native_library

__all__ = ["INTEGRATORS", "NativePlant", "FmuBackend", "resolve_integrator", "cached_fmu"]

#: Integrators of the native backend.
INTEGRATORS: tuple[str, ...] = ("auto", "taylor", "compiled-dopri5", "compiled-rodas4")
_MAX_STEPS = 1_000_000


def resolve_integrator(integrator: str) -> str:
    """The integrator ``"auto"`` stands for here, or ``integrator`` itself once checked.

    Parameters
    ----------
    integrator : {"auto", "taylor", "compiled-dopri5", "compiled-rodas4"}
        Requested integrator.

    Returns
    -------
    str
        ``"taylor"`` when heyoka is importable, else ``"compiled-dopri5"`` (for ``"auto"``).

    Raises
    ------
    ValueError
        Unknown name.
    RuntimeError
        ``"auto"`` with neither heyoka nor a C compiler available.
    """
    if integrator not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {list(INTEGRATORS)}, got {integrator!r}")
    if integrator != "auto":
        return integrator
    if unavailable_reason() is None:
        return "taylor"
    reason = compiler_unavailable_reason()
    if reason is None:
        return "compiled-dopri5"
    raise RuntimeError(
        f"the native backend needs heyoka ({unavailable_reason()}) or a C compiler ({reason}); install one of them"
    )


class NativePlant:
    """One model state advanced sample by sample by a persistent compiled integrator.

    Parameters
    ----------
    model : Model
        Rigid or elastic model (its parameters are fixed for the plant's life).
    actuation : {"full", "pendubot", "acrobot"}
        Which torques can be non-zero (the others are specialised away by the Taylor integrator).
    integrator : {"auto", "taylor", "compiled-dopri5", "compiled-rodas4"}
        See the module docstring.
    tol : float
        Tolerance: heyoka's ``tol``, or ``rtol = atol`` of the C solvers.

    Attributes
    ----------
    integrator : str
        The integrator in use (``"auto"`` resolved).
    t : float
        Time [s] since the last :meth:`reset`.

    Raises
    ------
    ValueError
        Unknown integrator or actuation.
    """

    def __init__(self, model: Model, actuation: str, *, integrator: str = "auto", tol: float = 1e-10) -> None:
        if actuation not in ACTUATIONS:
            raise ValueError(f"actuation must be one of {list(ACTUATIONS)}, got {actuation!r}")
        self.model = model
        self.integrator = resolve_integrator(integrator)
        self.t = 0.0
        self._actuated = ACTUATIONS[actuation]
        if self.integrator == "taylor":
            self._hy = heyoka_module()
            zero_u = tuple(i for i in range(model.nu) if i not in self._actuated)
            system, ta = compiled_integrator(structure_key(model.kind, model.p, zero_u, tol))
            ta.pars[:] = system.pars(np.zeros(model.nu), model.p)
            self._ta = ta
            # Views into heyoka's buffers, fetched once (each attribute access builds a new view).
            self._state = ta.state
            self._pars = ta.pars
            self._ok = self._hy.taylor_outcome.time_limit
            self._last = model.rest_state()
        else:
            lib = native_library(model.kind, purpose=f"the gym native backend ({self.integrator})")
            self._stepper = lib.stepper(self.integrator.removeprefix("compiled-"), model.p, rtol=tol, atol=tol)
            self._x = model.rest_state()

    def reset(self, x0: np.ndarray) -> None:
        """Set the state and restart the clock.

        Parameters
        ----------
        x0 : ndarray, shape (nx,)
            Initial state.
        """
        self.t = 0.0
        if self.integrator == "taylor":
            self._ta.time = 0.0
            self._state[:] = x0
            self._last = np.array(x0, dtype=float)
        else:
            self._x = np.array(x0, dtype=float)
            self._stepper.h = 0.0

    def step(self, tau: np.ndarray, dt: float) -> tuple[np.ndarray, str | None]:
        """Advance by ``dt`` holding ``tau``.

        Parameters
        ----------
        tau : ndarray, shape (2,)
            Torques (tau1, tau2) [N.m]; the unactuated ones must be 0.
        dt : float
            Sample time [s].

        Returns
        -------
        x : ndarray, shape (nx,)
            New state (a fresh array).
        failure : str or None
            None on success, else why the integrator stopped (the state is then unchanged).
        """
        if self.integrator == "taylor":
            pars = self._pars
            for i in self._actuated:
                pars[i] = tau[i]
            res = self._ta.propagate_for(dt, _MAX_STEPS)  # positional: keyword parsing costs ~1 us
            if res[0] != self._ok:
                self._state[:] = self._last
                return self._last.copy(), f"heyoka stopped with outcome {res[0]} at t = {self.t:.6g} s"
            self.t += dt
            self._last = self._state.copy()
            return self._last.copy(), None
        x1, failure = self._stepper.step(self.t, self.t + dt, self._x, tau, _MAX_STEPS)
        if failure is not None:
            return self._x.copy(), f"{self.integrator} failed at t = {self.t:.6g} s: {failure.message}"
        self.t += dt
        self._x = x1.copy()
        return self._x.copy(), None

    def close(self) -> None:
        """Nothing to free (the compiled integrator is shared through a cache)."""


def cached_fmu(kind: str) -> Path:
    """The co-simulation FMU (FMI 2) of a model kind, exported on first use into the cache folder.

    The file name carries a digest of the generated sources, so a changed pendulab exports again.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind (parameters are set per instance, not compiled in).

    Returns
    -------
    Path
        The FMU.

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        Not cached and no C compiler found.
    """
    # Imported here: the FMU packages (and python-control through pendulab.cosim) load only for the FMU backend.
    from ..fmu.codegen import compiled_sources, generate_sources
    from ..fmu.export import export

    model = make_model(kind)
    digest = source_digest(generate_sources(model, 2), compiled_sources(2))[:16]
    path = cache_dir().parent / "gym" / f"pendulab_{kind}_{digest}.fmu"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        export(model, path, 2, timestamp=False)
    return path


class FmuBackend:
    """The exported FMU as the plant, one ``doStep`` per sample, through fmpy.

    A reset instantiates the FMU afresh with the new start state (the FMU's states are not
    settable after initialization).

    Parameters
    ----------
    model : Model
        Its kind selects the FMU, its parameters are set as FMU parameters.
    solver : {"dopri5", "rodas4"}
        The FMU's embedded solver.
    tol : float
        The embedded solver's tolerance.
    fmu_path : path-like, optional
        An FMU of the same kind to use instead of the cached export.

    Attributes
    ----------
    integrator : str
        ``"fmu-<solver>"``.
    t : float
        Time [s] since the last :meth:`reset`.

    Raises
    ------
    ValueError
        ``fmu_path`` is an FMU of another model kind, or an unknown solver.
    """

    def __init__(self, model: Model, *, solver: str = "dopri5", tol: float = 1e-10, fmu_path: Any = None) -> None:
        from ..cosim.plant import StepRejectedError, inspect_fmu

        if solver not in ("dopri5", "rodas4"):
            raise ValueError(f"solver must be 'dopri5' or 'rodas4', got {solver!r}")
        self.model = model
        self.info = inspect_fmu(cached_fmu(model.kind) if fmu_path is None else fmu_path)
        if self.info.kind != model.kind:
            raise ValueError(f"fmu_path is a {self.info.kind} FMU, but the environment's model is {model.kind}")
        values = model.params.resolved()
        self._params = {n: float(values[n]) for n in self.info.parameter_names if n in values}
        self._solver = solver
        self._tol = tol
        self.integrator = f"fmu-{solver}"
        self.t = 0.0
        self._plant: Any = None
        self._rejected = StepRejectedError
        self._x = model.rest_state()

    def reset(self, x0: np.ndarray) -> None:
        """Instantiate the FMU afresh at state ``x0``.

        Parameters
        ----------
        x0 : ndarray, shape (nx,)
            Initial state.
        """
        from ..cosim.plant import FmuPlant

        self.close()
        self._plant = FmuPlant(self.info, params=self._params, x0=x0, solver=self._solver, tolerance=self._tol)
        self._x = np.array(x0, dtype=float)
        self.t = 0.0

    def step(self, tau: np.ndarray, dt: float) -> tuple[np.ndarray, str | None]:
        """Advance by ``dt`` holding ``tau`` (one ``doStep``).

        Parameters
        ----------
        tau : ndarray, shape (2,)
            Torques (tau1, tau2) [N.m].
        dt : float
            Sample time [s].

        Returns
        -------
        x : ndarray, shape (nx,)
            New state (a fresh array).
        failure : str or None
            None on success, else the FMU's reason (the state is then the last good one).

        Raises
        ------
        RuntimeError
            Stepping before :meth:`reset`, or the FMU returned Error.
        """
        plant = self._plant
        if plant is None:
            raise RuntimeError("FmuBackend.step called before reset")
        plant.set_inputs(tau)
        try:
            plant.do_step(dt)
        except self._rejected as exc:
            return self._x.copy(), str(exc)
        x, _ = plant.read()
        if not all(math.isfinite(v) for v in x):
            return self._x.copy(), f"the FMU's state became non-finite at t = {self.t:.6g} s"
        self._x = np.array(x, dtype=float)
        self.t += dt
        return self._x.copy(), None

    def close(self) -> None:
        """Free the FMU instance (idempotent)."""
        plant, self._plant = self._plant, None
        if plant is not None:
            plant.close()

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
import zipfile
from array import array
from pathlib import Path
from typing import Any

import numpy as np

from .._inputs import checked
from ..integrate.taylor import compiled_integrator, structure_key
from ..integrate.taylor.availability import heyoka_module, taylor_unavailable_reason
from ..model.model import ACTUATIONS, Model, make_model
from ..native.build import cache_dir, cached_artifact, compiler_unavailable_reason, source_digest
from ..native.loader import native_library

__all__ = ["INTEGRATORS", "NativePlant", "FmuBackend", "resolve_integrator", "cached_fmu", "MAX_REPLAY_STEPS"]

#: Integrators of the native backend.
INTEGRATORS: tuple[str, ...] = ("auto", "taylor", "compiled-dopri5", "compiled-rodas4")
_MAX_STEPS = 1_000_000
#: Steps since a reset up to which the FMU backend can be pickled (a copy replays them: ~30 us each).
MAX_REPLAY_STEPS = 100_000


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
    if taylor_unavailable_reason() is None:
        return "taylor"
    reason = compiler_unavailable_reason()
    if reason is None:
        return "compiled-dopri5"
    raise RuntimeError(
        f"the native backend needs heyoka ({taylor_unavailable_reason()}) or a C compiler ({reason}); install one of them"
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
        Unknown integrator or actuation, or ``tol`` not in (0, 1).

    Notes
    -----
    Pickling and ``copy.deepcopy`` save the settings and the integrator's full state (state,
    time, step-size guess) and rebuild the integrator from them, so a copy steps bit for bit
    like the original (the compiled code is never pickled: its buffers would no longer be the
    ones the plant writes).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.gym import NativePlant
    >>> model = pl.rigid()
    >>> plant = NativePlant(model, "pendubot")  # "auto": Taylor series (heyoka) when installed
    >>> x0 = model.state(theta1=2.0, theta2=2.0)
    >>> plant.reset(x0)
    >>> for _ in range(500):  # 5 s, unforced, in 10 ms samples
    ...     x, failure = plant.step(np.zeros(2), 0.01)
    >>> plant.integrator, failure, round(plant.t, 6)
    ('taylor', None, 5.0)
    >>> bool(abs(model.energy(x) - model.energy(x0)) < 1e-8)  # undamped: energy kept [J]
    True
    """

    @checked(tol="tolerance")
    def __init__(self, model: Model, actuation: str, *, integrator: str = "auto", tol: float = 1e-10) -> None:
        if actuation not in ACTUATIONS:
            raise ValueError(f"actuation must be one of {list(ACTUATIONS)}, got {actuation!r}")
        tol = float(tol)
        self.model = model
        self.actuation = actuation
        self.tol = tol
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

    def __getstate__(self) -> dict[str, Any]:
        """Settings and the integrator's state (the compiled integrator itself is rebuilt on unpickling)."""
        state: dict[str, Any] = {
            "model": self.model,
            "actuation": self.actuation,
            "integrator": self.integrator,
            "tol": self.tol,
            "t": self.t,
        }
        if self.integrator == "taylor":
            state.update(x=np.array(self._state), dtime=tuple(self._ta.dtime), last=self._last.copy())
        else:
            state.update(x=self._x.copy(), h=self._stepper.h, totals=dict(self._stepper.totals))
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Rebuild the integrator from the settings, then restore its state exactly."""
        self.__init__(state["model"], state["actuation"], integrator=state["integrator"], tol=state["tol"])
        self.t = state["t"]
        if self.integrator == "taylor":
            self._state[:] = state["x"]
            self._ta.dtime = state["dtime"]  # double-length time: the last step of propagate_for depends on it
            self._last = np.array(state["last"], dtype=float)
        else:
            self._x = np.array(state["x"], dtype=float)
            self._stepper.h = state["h"]
            self._stepper.totals.update(state["totals"])


def cached_fmu(kind: str, *, rebuild: str | None = None) -> Path:
    """The co-simulation FMU (FMI 2) of a model kind, exported on first use into the cache folder.

    The file name carries a digest of the generated sources, so a changed pendulab exports again.
    The FMU's SHA-256 is written beside it (``<fmu>.sha256``) and checked on every call, before
    fmpy reads the archive: a damaged file (truncated, flipped bytes, emptied, replaced) is
    exported again once, with a :class:`~pendulab.native.build.CacheRebuildWarning` naming it.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind (parameters are set per instance, not compiled in).
    rebuild : str, optional
        Export again even when the digest matches, for this reason (e.g. the FMU failed to load).

    Returns
    -------
    Path
        The FMU, intact.

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        Not cached and no C compiler found.
    RuntimeError
        The cache folder cannot be written or the export failed; the message names the cache path.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.cosim import inspect_fmu
    >>> from pendulab.gym import cached_fmu
    >>> path = cached_fmu("rigid")  # exported (C compiler) on the first call, then read from the cache
    >>> path.name.startswith("pendulab_rigid_"), path.suffix
    (True, '.fmu')
    >>> cached_fmu("rigid") == path  # the same file while pendulab's generated sources are unchanged
    True
    >>> inspect_fmu(path).fmi_version, inspect_fmu(path).kind
    ('2.0', 'rigid')
    """
    # Imported here: the FMU packages (and python-control through pendulab.cosim) load only for the FMU backend.
    from ..fmu.codegen import compiled_sources, generate_sources
    from ..fmu.export import export

    model = make_model(kind)
    digest = source_digest(generate_sources(model, 2), compiled_sources(2))
    path = cache_dir().parent / "gym" / f"pendulab_{kind}_{digest[:16]}.fmu"
    what = f"the gym FMU backend needs its {kind} FMU; it"
    key = f"gym-fmu-{kind}-{digest}"  # sealed with the file: the other kind's FMU moved here is refused
    return cached_artifact(path, lambda tmp: export(model, tmp, 2, timestamp=False), what=what, rebuild=rebuild, key=key)


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
        ``fmu_path`` is an FMU of another model kind, an unknown solver, or ``tol`` not in (0, 1)
        (checked before anything is exported or loaded).
    RuntimeError
        The cached FMU cannot be built, or fails to load after one rebuild (the message names its path).

    Notes
    -----
    Pickling and ``copy.deepcopy`` save the settings, the start state of the episode and the
    torques held since (at most :data:`MAX_REPLAY_STEPS` steps); unpickling instantiates the FMU
    afresh and replays them, so the copy is in the very state of the original (the FMU's solver
    keeps its step-size guess from one step to the next, which a copy of the state alone would lose).

    Examples
    --------
    The FMU and the native plant of an environment, stepped side by side, agree:

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.gym import FmuBackend, NativePlant
    >>> model = pl.rigid()
    >>> fmu, native = FmuBackend(model, solver="rodas4"), NativePlant(model, "full")
    >>> x0 = model.state(theta1=1.0)
    >>> fmu.reset(x0); native.reset(x0)
    >>> for _ in range(100):  # 1 s in 10 ms samples
    ...     x_fmu, failure = fmu.step(np.array([0.5, 0.0]), 0.01)
    ...     x_native, _ = native.step(np.array([0.5, 0.0]), 0.01)
    >>> fmu.integrator, failure, round(fmu.t, 6), bool(np.abs(x_fmu - x_native).max() < 1e-6)
    ('fmu-rodas4', None, 1.0, True)
    >>> fmu.close()
    """

    @checked(tol="tolerance")
    def __init__(self, model: Model, *, solver: str = "dopri5", tol: float = 1e-10, fmu_path: Any = None) -> None:
        from ..cosim.plant import StepRejectedError, inspect_fmu

        if solver not in ("dopri5", "rodas4"):
            raise ValueError(f"solver must be 'dopri5' or 'rodas4', got {solver!r}")
        tol = float(tol)
        self.model = model
        self._fmu_path = fmu_path
        self._cached = fmu_path is None
        if self._cached:
            path = cached_fmu(model.kind)  # verified by its digest before fmpy reads it
            try:
                self.info = inspect_fmu(path)
            except (OSError, ValueError) as exc:
                path = cached_fmu(model.kind, rebuild=f"cannot be read as an FMU ({exc})")
                try:
                    self.info = inspect_fmu(path)
                except (OSError, ValueError) as exc2:
                    raise RuntimeError(
                        f"the cached FMU {path} cannot be read even after a rebuild ({exc2}); delete {path.parent} and retry"
                    ) from exc2
        else:
            self.info = inspect_fmu(fmu_path)
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
        self._x0: np.ndarray | None = None
        self._history: array | None = array("d")  # tau1, tau2, dt of every step since the reset (None: too many)

    def reset(self, x0: np.ndarray) -> None:
        """Instantiate the FMU afresh at state ``x0``.

        Parameters
        ----------
        x0 : ndarray, shape (nx,)
            Initial state.

        Raises
        ------
        RuntimeError
            The FMU's binary fails to load even after the cached FMU was rebuilt once.
        """
        from ..cosim.plant import FmuPlant

        self.close()
        kwargs = {"params": self._params, "x0": x0, "solver": self._solver, "tolerance": self._tol}
        try:
            self._plant = FmuPlant(self.info, **kwargs)
        except (OSError, zipfile.BadZipFile) as exc:  # the archive or the binary inside cannot be loaded
            if not self._cached:
                raise
            from ..cosim.plant import inspect_fmu

            path = cached_fmu(self.model.kind, rebuild=f"has a binary that fails to load ({exc})")
            self.info = inspect_fmu(path)
            try:
                self._plant = FmuPlant(self.info, **kwargs)
            except (OSError, zipfile.BadZipFile) as exc2:
                raise RuntimeError(
                    f"the cached FMU {path} fails to load even after a rebuild ({exc2}); delete {path.parent} and retry"
                ) from exc2
        self._x = np.array(x0, dtype=float)
        self._x0 = self._x.copy()
        self._history = array("d")
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
        history = self._history
        if history is not None:
            if len(history) < 3 * MAX_REPLAY_STEPS:
                history.extend((float(tau[0]), float(tau[1]), float(dt)))
            else:
                self._history = None
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

    def __getstate__(self) -> dict[str, Any]:
        """Settings, the episode's start state and the torques held since (replayed on unpickling).

        Raises
        ------
        ValueError
            More than :data:`MAX_REPLAY_STEPS` steps since the last reset.
        """
        if self._history is None:
            raise ValueError(
                f"cannot pickle or copy the FMU backend after more than {MAX_REPLAY_STEPS} steps since the last reset "
                "(a copy replays the steps of the episode); call reset() first"
            )
        return {
            "model": self.model,
            "solver": self._solver,
            "tol": self._tol,
            "fmu_path": self._fmu_path,
            "x0": self._x0 if self._plant is not None else None,
            "history": array("d", self._history),
            "x": self._x.copy(),
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        """Instantiate the FMU afresh at the episode's start and replay the held torques."""
        self.__init__(state["model"], solver=state["solver"], tol=state["tol"], fmu_path=state["fmu_path"])
        if state["x0"] is None:
            return
        self.reset(state["x0"])
        h = state["history"]
        for k in range(0, len(h), 3):
            self.step(np.array(h[k : k + 2]), h[k + 2])
        if not np.array_equal(self._x, state["x"]):
            raise RuntimeError(
                f"replaying {len(h) // 3} steps of the FMU {self.info.path} did not reproduce the pickled state "
                f"({self._x.tolist()} != {np.asarray(state['x']).tolist()})"
            )

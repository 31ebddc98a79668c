"""One pendulab FMU as a co-simulation plant on fmpy's instance API.

:func:`inspect_fmu` reads what the master needs from the model description
(:class:`FmuInfo`); :class:`FmuPlant` instantiates the FMU once, sets
parameters and start values, initializes it, reads states and outputs, sets
inputs, steps, and saves/restores its state for step retries. The instance is
always freed (``terminate`` when legal, then ``freeInstance``), whatever goes wrong.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import positive_float
from ..model.builders import STATE_NAMES
from ..model.model import INPUT_NAMES, Model, make_model
from ..model.params import ElasticParams, RigidParams

__all__ = ["FmuInfo", "FmuPlant", "StepRejectedError", "inspect_fmu", "StepCheck"]

_STATES = STATE_NAMES
_PARAMS = {"rigid": RigidParams, "elastic": ElasticParams}
_FLOAT_TYPES = ("Real", "Float64")
_INT_TYPES = ("Integer", "Enumeration", "Int32", "Int64")

#: ``check(t, x_before, x_after) -> bool``: False rejects the step just taken.
StepCheck = Callable[[float, np.ndarray, np.ndarray], bool]


class StepRejectedError(RuntimeError):
    """A communication step was rejected and could not be completed by retrying with smaller steps.

    Examples
    --------
    A step check keeps link 1 within 0.5 rad of upright; a controller limited to 1 N.m cannot:

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control.feedback import balance_controller, upright_state
    >>> from pendulab.cosim import StepRejectedError, cosim
    >>> from pendulab.fmu import export
    >>> model = pl.rigid()
    >>> weak = balance_controller(model, sample_time=0.01, u_max=1.0)
    >>> near_upright = lambda t, x_before, x_after: abs(x_after[0] - np.pi) < 0.5
    >>> try:
    ...     cosim(export(model, "rigid.fmu"), weak, 0.01, 5.0, x0=upright_state(model) + [0.1, 0, 0, 0],
    ...           check=near_upright, max_halvings=3)
    ... except StepRejectedError as err:  # a RuntimeError
    ...     print(err)
    step at t = 0.90125 s rejected at the smallest step h = 0.00125 s: the step result was refused
    """


@dataclass(frozen=True)
class FmuInfo:
    """What the master knows about a pendulab FMU (from its model description).

    Attributes
    ----------
    path : Path
    fmi_version : str
        "2.0" or "3.0".
    kind : str
        "rigid" or "elastic" (from the state variables).
    state_names, input_names, output_names : tuple of str
    variables : dict
        Model variable by name.
    model_description : fmpy.model_description.ModelDescription

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.cosim import inspect_fmu
    >>> from pendulab.fmu import export
    >>> info = inspect_fmu(export(pl.elastic(), "elastic.fmu", fmi_version=3))
    >>> info.fmi_version, info.kind
    ('3.0', 'elastic')
    >>> info.state_names
    ('theta1', 'theta2', 'r1', 'r2', 'omega1', 'omega2', 'v1', 'v2')
    >>> info.input_names, info.output_names
    (('tau1', 'tau2'), ('x1', 'y1', 'x2', 'y2', 'energy', 'stretch1', 'stretch2'))
    """

    path: Path
    fmi_version: str
    kind: str
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    variables: Mapping[str, Any] = field(repr=False)
    model_description: Any = field(repr=False)

    @property
    def can_get_set_state(self) -> bool:
        return bool(self.model_description.coSimulation.canGetAndSetFMUstate)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.model_description.modelVariables if v.causality in ("parameter", "structuralParameter"))

    def model(self, params: Mapping[str, float] | None = None) -> Model:
        """The native pendulab ``Model`` with the FMU's parameter start values, overridden by ``params``.

        Parameters
        ----------
        params : mapping of str to float, optional
            Parameter values by name (e.g. ``{"m1": 1.2}``); names that are not
            model parameters of this kind are ignored.

        Returns
        -------
        Model
            A rigid or elastic model (``kind``); parameters without a start
            value in the FMU keep the model defaults.
        """
        names = _PARAMS[self.kind].names()
        values = {n: float(self.variables[n].start) for n in names if n in self.variables and self.variables[n].start is not None}
        values.update({k: float(v) for k, v in (params or {}).items() if k in names})
        return make_model(self.kind, **values)


def inspect_fmu(fmu_path: str | Path) -> FmuInfo:
    """Read and check an FMU's model description: a pendulab plant with Co-Simulation.

    Parameters
    ----------
    fmu_path : str or Path
        The ``.fmu`` file.

    Returns
    -------
    FmuInfo
        Version, kind, state/input names and the Real outputs, with the
        model description.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not an FMU, not a pendulab FMU (states tau1/tau2 missing) or no Co-Simulation interface.

    Examples
    --------
    >>> from pathlib import Path
    >>> import pendulab as pl
    >>> from pendulab.cosim import inspect_fmu
    >>> from pendulab.fmu import export
    >>> info = inspect_fmu(export(pl.rigid(), "rigid.fmu"))
    >>> info.fmi_version, info.kind, info.state_names, info.input_names
    ('2.0', 'rigid', ('theta1', 'theta2', 'omega1', 'omega2'), ('tau1', 'tau2'))
    >>> _ = Path("notes.fmu").write_text("not an archive")
    >>> inspect_fmu("notes.fmu")
    Traceback (most recent call last):
        ...
    ValueError: ...
    """
    from fmpy import read_model_description

    path = Path(fmu_path)
    if not path.exists():
        raise FileNotFoundError(f"fmu_path: no such file {str(path)!r}")
    try:
        md = read_model_description(str(path))
    except Exception as exc:  # fmpy raises bare Exceptions (besides BadZipFile, KeyError, XML errors)
        raise ValueError(f"fmu_path: {str(path)!r} is not a readable FMU ({_first_line(exc)})") from None
    variables = {v.name: v for v in md.modelVariables}
    kind = "elastic" if all(n in variables for n in _STATES["elastic"]) else "rigid"
    inputs = tuple(v.name for v in md.modelVariables if v.causality == "input")
    missing = [n for n in _STATES[kind] if n not in variables] + [n for n in INPUT_NAMES if n not in inputs]
    if not str(md.generationTool or "").startswith("pendulab"):
        raise ValueError(
            f"fmu_path: {str(path)!r} (model {md.modelName!r}, generated by {md.generationTool!r}) is not a pendulab FMU; "
            "export one with pendulab.fmu.export(model, path)"
        )
    if missing:
        raise ValueError(
            f"fmu_path: {str(path)!r} (model {md.modelName!r}) is not a pendulab FMU: it lacks the variables "
            f"{missing}; expected states {list(_STATES['rigid'])} or {list(_STATES['elastic'])} and inputs {list(INPUT_NAMES)}"
        )
    if md.coSimulation is None:
        raise ValueError(
            f"fmu_path: {str(path)!r} has no Co-Simulation interface (Model Exchange only); "
            "a co-simulation master needs an FMU exported with Co-Simulation"
        )
    outputs = tuple(v.name for v in md.modelVariables if v.causality == "output" and v.type in _FLOAT_TYPES)
    return FmuInfo(path, md.fmiVersion, kind, _STATES[kind], inputs, outputs, variables, md)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


class FmuPlant:
    """One Co-Simulation instance of a pendulab FMU (a context manager that always frees it).

    Parameters
    ----------
    fmu : str, Path or FmuInfo
    params : mapping, optional
        Parameter values by name (e.g. ``{"m1": 1.2}``), set before initialization.
    x0 : array_like, shape (nx,), optional
        Initial state in ``state_names`` order (start values); default: the FMU's.
    solver : str or int, optional
        Embedded solver (the FMU's structural parameter ``solver``).
    tolerance : float, optional
        Relative tolerance of the embedded solver (passed to the FMU at initialization).
    instance_name : str, optional
    start_time : float
        [s].

    Raises
    ------
    FMUBinaryError (ValueError)
        The FMU's binary is not the one pendulab exported, and it crashed (the signal is named), failed or
        hung in a probe process (:func:`pendulab.fmu.binaries.check_fmu_binary`); it is never loaded here.
    """

    def __init__(
        self,
        fmu: str | Path | FmuInfo,
        *,
        params: Mapping[str, float] | None = None,
        x0: Any = None,
        solver: str | int | None = None,
        tolerance: float | None = None,
        instance_name: str | None = None,
        start_time: float = 0.0,
    ) -> None:
        self.info = fmu if isinstance(fmu, FmuInfo) else inspect_fmu(fmu)
        info = self.info
        self._values = self._start_values(params, x0, solver)
        if tolerance is not None:
            tolerance = positive_float("tolerance", tolerance)
        self.tolerance = tolerance
        self.time = float(start_time)
        self.time_in_do_step = 0.0
        self.n_do_step = 0
        self._fmu: Any = None
        self._unzipdir: str | None = None
        self._instantiated = False
        self._errored = False
        self._fmi3 = info.fmi_version.startswith("3")
        self._vr = {n: info.variables[n].valueReference for n in info.variables}
        self._read_vrs = [self._vr[n] for n in info.state_names + info.output_names]
        self._input_vrs = [self._vr[n] for n in INPUT_NAMES]
        try:
            self._open(instance_name or info.model_description.coSimulation.modelIdentifier)
        except BaseException:
            self.close()
            raise

    # -- setup -------------------------------------------------------------------
    def _start_values(self, params, x0, solver) -> dict[str, float | int]:
        info = self.info
        values: dict[str, float | int] = {}
        for name, value in (params or {}).items():
            if name not in info.parameter_names:
                raise ValueError(
                    f"params: {name!r} is not a parameter of the FMU {info.path.name!r}; "
                    f"expected one of {list(info.parameter_names)}"
                )
            values[name] = float(value)
        if x0 is not None:
            x = np.asarray(x0, dtype=float)
            if x.shape != (len(info.state_names),) or not np.all(np.isfinite(x)):
                raise ValueError(
                    f"x0 must be finite with shape ({len(info.state_names)},) = {list(info.state_names)} for the "
                    f"{info.kind} FMU, got {np.asarray(x0).tolist()!r}"
                )
            values.update(zip(info.state_names, x.tolist(), strict=True))
        if solver is not None:
            values.update(_solver_value(solver))
        return values

    def _open(self, instance_name: str) -> None:
        import fmpy
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        from ..fmu.binaries import check_fmu_binary

        info = self.info
        md = info.model_description
        self._unzipdir = fmpy.extract(str(info.path))
        check_fmu_binary(self._unzipdir, md, fmu=info.path)  # a binary pendulab did not export runs in a child first
        cls = FMU3Slave if self._fmi3 else FMU2Slave
        token = md.instantiationToken if cls is FMU3Slave else md.guid
        self._fmu = cls(
            guid=token,
            unzipDirectory=self._unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self._fmu.instantiate()
        self._instantiated = True
        fmu = self._fmu  # the FMI 2 / FMI 3 names of the calls the loop needs
        self._get_real = fmu.getFloat64 if self._fmi3 else fmu.getReal
        self._set_real = fmu.setFloat64 if self._fmi3 else fmu.setReal
        self._set_by_name(self._values)
        if cls is FMU3Slave:
            self._fmu.enterInitializationMode(tolerance=self.tolerance, startTime=self.time)
        else:
            self._fmu.setupExperiment(tolerance=self.tolerance, startTime=self.time)
            self._fmu.enterInitializationMode()
        self._fmu.exitInitializationMode()

    def _set_by_name(self, values: Mapping[str, float | int]) -> None:
        floats = {n: float(v) for n, v in values.items() if self.info.variables[n].type in _FLOAT_TYPES}
        if floats:
            self._set_real([self._vr[n] for n in floats], list(floats.values()))
        for name, value in values.items():
            var_type = self.info.variables[name].type
            if var_type in _INT_TYPES:
                if not self._fmi3:
                    self._fmu.setInteger([self._vr[name]], [int(value)])
                else:
                    setter = self._fmu.setInt64 if var_type in ("Int64", "Enumeration") else self._fmu.setInt32
                    setter([self._vr[name]], [int(value)])

    # -- stepping ----------------------------------------------------------------
    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """States and outputs at the current communication point.

        Returns
        -------
        x : ndarray, shape (nx,)
            States in ``info.state_names`` order.
        y : ndarray, shape (ny,)
            Outputs in ``info.output_names`` order.
        """
        values = np.array(self._get_real(self._read_vrs))
        nx = len(self.info.state_names)
        return values[:nx], values[nx:]

    def set_inputs(self, u: np.ndarray) -> None:
        """Set the inputs, held constant over the next step(s).

        Parameters
        ----------
        u : array_like, shape (2,)
            Torques (tau1, tau2) [N.m].
        """
        self._set_real(self._input_vrs, [float(v) for v in u])

    def do_step(self, h: float, *, allow_restore: bool = False) -> None:
        """Advance by ``h`` from ``self.time``; on success ``self.time`` increases by ``h``.

        Parameters
        ----------
        h : float
            Communication step [s].
        allow_restore : bool
            Tell the FMU a state saved before the current point may be
            restored (``noSetFMUStatePriorToCurrentPoint`` false).

        Raises
        ------
        StepRejectedError
            The FMU discarded the step (FMI Discard, early return or termination request).
        RuntimeError
            The FMU returned Error/Fatal (the instance can then only be freed).
        """
        from fmpy.fmi1 import FMICallException

        start = time.perf_counter()
        try:
            result = self._fmu.doStep(self.time, h, noSetFMUStatePriorToCurrentPoint=not allow_restore)
        except FMICallException as exc:
            if exc.status == 2:  # fmi2Discard / fmi3Discard
                raise StepRejectedError(f"FMU discarded the step from t = {self.time:.6g} s, h = {h:.3g} s") from None
            self._errored = True
            raise RuntimeError(
                f"FMU {self.info.path.name!r} failed in doStep at t = {self.time:.6g} s, h = {h:.3g} s "
                f"(status {exc.status}); see the FMU log above"
            ) from None
        finally:
            self.time_in_do_step += time.perf_counter() - start
            self.n_do_step += 1
        if isinstance(result, tuple) and (result[1] or result[2]):  # FMI 3: terminateSimulation / earlyReturn
            raise StepRejectedError(f"FMU returned early from the step at t = {self.time:.6g} s, h = {h:.3g} s")
        self.time += h

    def get_state(self) -> Any:
        """Save the complete FMU state (needs canGetAndSetFMUstate).

        Returns
        -------
        object
            Opaque FMU state handle; release it with :meth:`free_state`.

        Raises
        ------
        ValueError
            The FMU cannot get and set its state.
        """
        self._require_state_access()
        return self._fmu.getFMUState() if self._fmi3 else self._fmu.getFMUstate()

    def set_state(self, state: Any, t: float) -> None:
        """Restore a state saved with :meth:`get_state`.

        Parameters
        ----------
        state : object
            The saved FMU state handle.
        t : float
            Time [s] at which it was saved; becomes ``self.time``.
        """
        (self._fmu.setFMUState if self._fmi3 else self._fmu.setFMUstate)(state)
        self.time = t

    def free_state(self, state: Any) -> None:
        """Release a state saved with :meth:`get_state`.

        Parameters
        ----------
        state : object
            The saved FMU state handle; not usable afterwards.
        """
        (self._fmu.freeFMUState if self._fmi3 else self._fmu.freeFMUstate)(state)

    def _require_state_access(self) -> None:
        if not self.info.can_get_set_state:
            raise ValueError(f"FMU {self.info.path.name!r} cannot get and set its state (canGetAndSetFMUstate is false)")

    def step_with_retry(self, h: float, check: StepCheck | None, max_halvings: int, stats: dict) -> None:
        """Advance by ``h``; on rejection restore the saved state and cover ``h`` in two halves, recursively.

        A step is rejected when the FMU discards it, a state is not finite, or
        ``check`` returns False.

        Parameters
        ----------
        h : float
            Communication step [s].
        check : callable or None
            ``check(t, x_before, x_after) -> bool``; False rejects the step.
        max_halvings : int
            How many more times a rejected step may be halved.
        stats : dict
            Updated in place: ``n_rejected`` counts rejected attempts.

        Raises
        ------
        StepRejectedError
            A step was rejected with no halvings left.
        ValueError
            The FMU cannot get and set its state.
        RuntimeError
            The FMU reported an error.
        """
        x_before, _ = self.read()
        t0 = self.time
        state = self.get_state()
        try:
            try:
                self.do_step(h, allow_restore=True)
                x_after, _ = self.read()
                ok = bool(np.all(np.isfinite(x_after))) and (check is None or bool(check(t0, x_before, x_after)))
                reason = "the step result was refused"
            except StepRejectedError as exc:
                ok, reason = False, str(exc)
            if ok:
                return
            stats["n_rejected"] = stats.get("n_rejected", 0) + 1
            if max_halvings <= 0:
                raise StepRejectedError(f"step at t = {t0:.6g} s rejected at the smallest step h = {h:.3g} s: {reason}")
            self.set_state(state, t0)
        finally:
            self.free_state(state)
        self.step_with_retry(h / 2, check, max_halvings - 1, stats)
        self.step_with_retry(h / 2, check, max_halvings - 1, stats)

    # -- teardown ----------------------------------------------------------------
    def close(self) -> None:
        """Terminate (when legal) and free the instance, unload the library and delete the extracted files."""
        fmu, self._fmu = self._fmu, None
        try:
            if fmu is not None:
                try:
                    if self._instantiated and not self._errored:
                        fmu.terminate()
                except Exception:  # noqa: S110 - freeing must still happen; the original error matters more
                    pass
                finally:
                    if self._instantiated:
                        fmu.freeInstance()
                    else:
                        fmu.freeLibrary()
        finally:
            if self._unzipdir is not None:
                shutil.rmtree(self._unzipdir, ignore_errors=True)
                self._unzipdir = None

    def __enter__(self) -> FmuPlant:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _solver_value(solver: str | int) -> dict[str, int]:
    from ..fmu.codegen import SOLVER_NAMES

    if isinstance(solver, str):
        if solver not in SOLVER_NAMES:
            raise ValueError(f"solver must be one of {list(SOLVER_NAMES)} (or its index), got {solver!r}")
        return {"solver": SOLVER_NAMES.index(solver)}
    if isinstance(solver, bool) or not isinstance(solver, int) or not 0 <= solver < len(SOLVER_NAMES):
        raise ValueError(f"solver must be one of {list(SOLVER_NAMES)} or an index 0..{len(SOLVER_NAMES) - 1}, got {solver!r}")
    return {"solver": solver}

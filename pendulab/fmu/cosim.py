"""A co-simulation master on fmpy's instance API: pendulab FMUs as plants under sampled controllers.

:func:`cosim` instantiates one FMU once, sets parameters and start values,
initializes it, then per communication step reads the states and outputs,
evaluates the controller (at its sample times), sets the inputs (held constant
over the step) and calls ``doStep``. :class:`FmuPlant` is the instance wrapper
it is built on; :func:`cosim_many` steps several FMUs side by side with the
same inputs. Both can save the FMU state before a step and, when a step is
rejected (``doStep`` returns Discard, the result is non-finite, or a
user check refuses it), restore the state and retry the step in halves.

The instance is always freed (``terminate`` when legal, then
``freeInstance``), whatever goes wrong.
"""

from __future__ import annotations

import math
import shutil
import time
import zipfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..control.sampled import SampledController
from ..model.model import INPUT_NAMES, Model, make_model
from ..model.params import ElasticParams, RigidParams
from ..model.trajectory import Trajectory

__all__ = ["cosim", "cosim_many", "FmuInfo", "FmuPlant", "StepRejectedError", "inspect_fmu", "StepCheck"]

_STATES = {
    "rigid": ("theta1", "theta2", "omega1", "omega2"),
    "elastic": ("theta1", "theta2", "r1", "r2", "omega1", "omega2", "v1", "v2"),
}
_PARAMS = {"rigid": RigidParams, "elastic": ElasticParams}
_FLOAT_TYPES = ("Real", "Float64")
_INT_TYPES = ("Integer", "Enumeration", "Int32", "Int64")

#: ``check(t, x_before, x_after) -> bool``: False rejects the step just taken.
StepCheck = Callable[[float, np.ndarray, np.ndarray], bool]


class StepRejectedError(RuntimeError):
    """A communication step was rejected and could not be completed by retrying with smaller steps."""


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
        """The native pendulab ``Model`` with the FMU's parameter start values, overridden by ``params``."""
        names = _PARAMS[self.kind].names()
        values = {n: float(self.variables[n].start) for n in names if n in self.variables and self.variables[n].start is not None}
        values.update({k: float(v) for k, v in (params or {}).items() if k in names})
        return make_model(self.kind, **values)


def inspect_fmu(fmu_path: str | Path) -> FmuInfo:
    """Read and check an FMU's model description: a pendulab plant with Co-Simulation.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        Not an FMU, not a pendulab FMU (states tau1/tau2 missing) or no Co-Simulation interface.
    """
    from fmpy import read_model_description

    path = Path(fmu_path)
    if not path.exists():
        raise FileNotFoundError(f"fmu_path: no such file {str(path)!r}")
    try:
        md = read_model_description(str(path))
    except (zipfile.BadZipFile, KeyError, OSError, ValueError, Exception) as exc:  # fmpy raises bare Exceptions
        raise ValueError(f"fmu_path: {str(path)!r} is not a readable FMU ({_first_line(exc)})") from None
    variables = {v.name: v for v in md.modelVariables}
    kind = "elastic" if all(n in variables for n in _STATES["elastic"]) else "rigid"
    inputs = tuple(v.name for v in md.modelVariables if v.causality == "input")
    missing = [n for n in _STATES[kind] if n not in variables] + [n for n in INPUT_NAMES if n not in inputs]
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


def _positive(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a positive number [s], got {value!r}") from exc
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a positive finite number [s], got {value!r}")
    return v


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
            tolerance = _positive("tolerance", tolerance)
        self.tolerance = tolerance
        self.time = float(start_time)
        self.time_in_do_step = 0.0
        self.n_do_step = 0
        self._fmu: Any = None
        self._unzipdir: str | None = None
        self._instantiated = False
        self._errored = False
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
            values.update(_solver_value(info, solver))
        return values

    def _open(self, instance_name: str) -> None:
        import fmpy
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        info = self.info
        md = info.model_description
        self._unzipdir = fmpy.extract(str(info.path))
        cls = FMU3Slave if info.fmi_version.startswith("3") else FMU2Slave
        token = md.instantiationToken if cls is FMU3Slave else md.guid
        self._fmu = cls(
            guid=token,
            unzipDirectory=self._unzipdir,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self._fmu.instantiate()
        self._instantiated = True
        self._set_by_name(self._values)
        if cls is FMU3Slave:
            self._fmu.enterInitializationMode(tolerance=self.tolerance, startTime=self.time)
        else:
            self._fmu.setupExperiment(tolerance=self.tolerance, startTime=self.time)
            self._fmu.enterInitializationMode()
        self._fmu.exitInitializationMode()

    def _set_by_name(self, values: Mapping[str, float | int]) -> None:
        fmi3 = self.info.fmi_version.startswith("3")
        floats = [(self._vr[n], float(v)) for n, v in values.items() if self.info.variables[n].type in _FLOAT_TYPES]
        ints = [(self._vr[n], int(v)) for n, v in values.items() if self.info.variables[n].type in _INT_TYPES]
        if floats:
            vrs, vals = zip(*floats, strict=True)
            (self._fmu.setFloat64 if fmi3 else self._fmu.setReal)(list(vrs), list(vals))
        for vr, v in ints:
            var_type = next(x.type for x in self.info.model_description.modelVariables if x.valueReference == vr)
            if fmi3:
                (self._fmu.setInt64 if var_type in ("Int64", "Enumeration") else self._fmu.setInt32)([vr], [v])
            else:
                self._fmu.setInteger([vr], [v])

    # -- stepping ----------------------------------------------------------------
    def read(self) -> tuple[np.ndarray, np.ndarray]:
        """States (nx,) and outputs (ny,) at the current communication point."""
        fmi3 = self.info.fmi_version.startswith("3")
        values = np.array((self._fmu.getFloat64 if fmi3 else self._fmu.getReal)(self._read_vrs))
        nx = len(self.info.state_names)
        return values[:nx], values[nx:]

    def set_inputs(self, u: np.ndarray) -> None:
        """Set (tau1, tau2) [N.m], held constant over the next step(s)."""
        fmi3 = self.info.fmi_version.startswith("3")
        (self._fmu.setFloat64 if fmi3 else self._fmu.setReal)(self._input_vrs, [float(v) for v in u])

    def do_step(self, h: float, *, allow_restore: bool = False) -> None:
        """Advance by ``h`` [s] from ``self.time``.

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
        """Save the complete FMU state (needs canGetAndSetFMUstate)."""
        self._require_state_access()
        return self._fmu.getFMUState() if self.info.fmi_version.startswith("3") else self._fmu.getFMUstate()

    def set_state(self, state: Any, t: float) -> None:
        """Restore a state saved at time ``t`` [s]."""
        (self._fmu.setFMUState if self.info.fmi_version.startswith("3") else self._fmu.setFMUstate)(state)
        self.time = t

    def free_state(self, state: Any) -> None:
        (self._fmu.freeFMUState if self.info.fmi_version.startswith("3") else self._fmu.freeFMUstate)(state)

    def _require_state_access(self) -> None:
        if not self.info.can_get_set_state:
            raise ValueError(f"FMU {self.info.path.name!r} cannot get and set its state (canGetAndSetFMUstate is false)")

    def step_with_retry(self, h: float, check: StepCheck | None, max_halvings: int, stats: dict) -> None:
        """Advance by ``h``; on rejection restore the saved state and cover ``h`` in two halves, recursively."""
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


def _solver_value(info: FmuInfo, solver: str | int) -> dict[str, int]:
    var = info.variables.get("solver")
    if var is None:
        raise ValueError(f"solver: the FMU {info.path.name!r} has no structural parameter 'solver'; got solver={solver!r}")
    if isinstance(solver, str):
        items = _enum_items(info, var)
        if solver not in items:
            raise ValueError(f"solver must be one of {list(items)} for the FMU {info.path.name!r}, got {solver!r}")
        return {"solver": items[solver]}
    return {"solver": int(solver)}


def _enum_items(info: FmuInfo, var: Any) -> dict[str, int]:
    decl = getattr(var, "declaredType", None)
    items = getattr(decl, "items", None) or []
    return {item.name: int(item.value) for item in items}


def _check_controller(controller: SampledController, info: FmuInfo, comm_step: float) -> int:
    """Validate the controller against the FMU; return samples-per-step ratio."""
    for attr in ("sample_time", "input_names", "reset"):
        if not hasattr(controller, attr):
            raise TypeError(f"controller must be a SampledController (sample_time, input_names, reset, __call__); lacks {attr!r}")
    names = tuple(controller.input_names)
    unknown = [n for n in names if n not in info.input_names]
    if not names or unknown or len(set(names)) != len(names):
        raise ValueError(
            f"controller input_names {list(names)} do not match the FMU {info.path.name!r}: expected distinct names "
            f"among its inputs {list(info.input_names)}"
        )
    ts = _positive("controller.sample_time", controller.sample_time)
    ratio = ts / comm_step
    m = round(ratio)
    if m < 1 or abs(ratio - m) > 1e-9 * ratio:
        raise ValueError(
            f"controller.sample_time ({ts:g} s) must be a whole multiple of comm_step ({comm_step:g} s): the master "
            "samples the controller only at communication points"
        )
    return m


def _n_steps(t_final: float, comm_step: float) -> int:
    ratio = t_final / comm_step
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-9 * ratio:
        raise ValueError(f"t_final ({t_final:g} s) must be a whole number of communication steps ({comm_step:g} s)")
    return n


def _controller_output(controller: SampledController, t: float, x: np.ndarray) -> np.ndarray:
    u = np.asarray(controller(t, x.copy()), dtype=float).reshape(-1)
    if u.shape != (len(controller.input_names),) or not np.all(np.isfinite(u)):
        raise ValueError(
            f"controller returned {u.tolist()!r} at t = {t:.6g} s; expected {len(controller.input_names)} finite torques "
            f"for {list(controller.input_names)}"
        )
    full = np.zeros(len(INPUT_NAMES))
    for name, value in zip(controller.input_names, u, strict=True):
        full[INPUT_NAMES.index(name)] = value
    return full


def cosim(
    fmu_path: str | Path,
    controller: SampledController,
    comm_step: float,
    t_final: float,
    *,
    params: Mapping[str, float] | None = None,
    x0: Any = None,
    solver: str | int | None = None,
    tolerance: float | None = None,
    check: StepCheck | None = None,
    max_halvings: int = 0,
) -> Trajectory:
    """Co-simulate a pendulab FMU (Co-Simulation, FMI 2 or 3) under a sampled-data controller.

    Per communication step ``[t_k, t_k + comm_step]`` with ``t_k = k comm_step``:
    read states and outputs, evaluate the controller when ``t_k`` is one of its
    sample times, set the torques (held constant) and ``doStep``.

    Parameters
    ----------
    fmu_path : str or Path
        A pendulab FMU with a Co-Simulation interface.
    controller : SampledController
        ``sample_time`` must be a whole multiple of ``comm_step``; ``input_names``
        a subset of the FMU's inputs (tau1, tau2; undriven inputs stay 0).
    comm_step : float
        Communication step [s], > 0.
    t_final : float
        Horizon [s], a whole number of communication steps.
    params : mapping, optional
        FMU parameters by name.
    x0 : array_like, shape (nx,), optional
        Initial state (FMU state variable start values); default the FMU's start values.
    solver : str or int, optional
        Embedded solver (structural parameter ``solver`` of the FMU).
    tolerance : float, optional
        Relative tolerance of the embedded solver.
    check : callable, optional
        ``check(t, x_before, x_after) -> bool``; False rejects a step (needs ``max_halvings`` > 0 to retry).
    max_halvings : int
        When > 0, the master saves the FMU state before each step and, on a
        rejected step (Discard, non-finite result or ``check`` False), restores
        it and covers the step in halves, at most this many times.

    Returns
    -------
    Trajectory
        ``t`` shape (N+1,), states ``x`` (N+1, nx) and outputs ``y`` read from the
        FMU, inputs ``u`` (N+1, 2) applied from ``t[k]`` (last row repeated);
        ``stats``: ``wall_time``, ``time_in_do_step`` [s], ``n_do_step``,
        ``n_rejected``, ``comm_step``.

    Raises
    ------
    ValueError
        Not a pendulab Co-Simulation FMU, mismatched controller, non-positive
        or inconsistent steps, bad parameters or start values.
    StepRejectedError
        A step could not be completed even at the smallest retry step.
    RuntimeError
        The FMU reported an error.
    """
    h = _positive("comm_step", comm_step)
    n = _n_steps(_positive("t_final", t_final), h)
    info = inspect_fmu(fmu_path)
    every = _check_controller(controller, info, h)
    if max_halvings and not info.can_get_set_state:
        raise ValueError(f"max_halvings={max_halvings} needs an FMU that can get and set its state; {info.path.name!r} cannot")
    nx, ny = len(info.state_names), len(info.output_names)
    X, Y, U = np.empty((n + 1, nx)), np.empty((n + 1, ny)), np.zeros((n + 1, len(INPUT_NAMES)))
    stats: dict[str, Any] = {"n_rejected": 0, "comm_step": h}
    controller.reset()
    wall = time.perf_counter()
    with FmuPlant(info, params=params, x0=x0, solver=solver, tolerance=tolerance) as plant:
        u = np.zeros(len(INPUT_NAMES))
        for k in range(n + 1):
            X[k], Y[k] = plant.read()
            if k == n:
                break
            t = k * h
            if k % every == 0:
                u = _controller_output(controller, t, X[k])
            U[k] = u
            plant.set_inputs(u)
            plant.time = t  # multiply, never accumulate: t_k = k h exactly as in the native grid
            if max_halvings:
                plant.step_with_retry(h, check, max_halvings, stats)
            else:
                plant.do_step(h)
        stats.update(time_in_do_step=plant.time_in_do_step, n_do_step=plant.n_do_step)
    U[-1] = U[-2] if n else U[-1]
    stats["wall_time"] = time.perf_counter() - wall
    return Trajectory(
        t=np.arange(n + 1) * h,
        x=X,
        u=U,
        y=Y,
        state_names=info.state_names,
        input_names=INPUT_NAMES,
        output_names=info.output_names,
        method=f"fmu:fmi{info.fmi_version[0]}:cs" + (f":{solver}" if solver is not None else ""),
        success=True,
        message=f"co-simulated {info.path.name} to t = {n * h:.6g} s in {n} communication steps of {h:g} s",
        stats=stats,
    )


def cosim_many(
    fmu_paths: Sequence[str | Path],
    controller: SampledController,
    comm_step: float,
    t_final: float,
    *,
    feedback_from: int = 0,
    x0: Sequence[Any] | None = None,
    params: Sequence[Mapping[str, float] | None] | None = None,
    solver: str | int | None = None,
    tolerance: float | None = None,
) -> list[Trajectory]:
    """Step several pendulab FMUs side by side in one master, all driven by the same inputs.

    The controller reads plant ``feedback_from``; every plant receives its
    torques, so the others show their open-loop response to the same input
    sequence (e.g. rigid vs elastic).

    Parameters
    ----------
    fmu_paths : sequence of str or Path
    controller : SampledController
    comm_step, t_final : float
        [s].
    feedback_from : int
        Index of the plant whose state the controller sees.
    x0 : sequence of array_like or None, optional
        Per-plant initial states.
    params : sequence of mapping or None, optional
        Per-plant parameters.
    solver, tolerance
        As in :func:`cosim`, for all plants.

    Returns
    -------
    list of Trajectory
        One per FMU, on the same time grid with identical ``u``.
    """
    h = _positive("comm_step", comm_step)
    n = _n_steps(_positive("t_final", t_final), h)
    infos = [inspect_fmu(p) for p in fmu_paths]
    if not infos:
        raise ValueError("fmu_paths must name at least one FMU, got an empty sequence")
    if not 0 <= feedback_from < len(infos):
        raise ValueError(f"feedback_from must index fmu_paths (0..{len(infos) - 1}), got {feedback_from!r}")
    x0s = list(x0) if x0 is not None else [None] * len(infos)
    ps = list(params) if params is not None else [None] * len(infos)
    if len(x0s) != len(infos) or len(ps) != len(infos):
        raise ValueError(f"x0 and params must have one entry per FMU ({len(infos)}), got {len(x0s)} and {len(ps)}")
    every = _check_controller(controller, infos[feedback_from], h)
    controller.reset()
    X = [np.empty((n + 1, len(i.state_names))) for i in infos]
    Y = [np.empty((n + 1, len(i.output_names))) for i in infos]
    U = np.zeros((n + 1, len(INPUT_NAMES)))
    plants: list[FmuPlant] = []
    wall = time.perf_counter()
    try:
        for j, info in enumerate(infos):
            plants.append(FmuPlant(info, params=ps[j], x0=x0s[j], solver=solver, tolerance=tolerance, instance_name=f"plant{j}"))
        u = np.zeros(len(INPUT_NAMES))
        for k in range(n + 1):
            for j, plant in enumerate(plants):
                X[j][k], Y[j][k] = plant.read()
            if k == n:
                break
            if k % every == 0:
                u = _controller_output(controller, k * h, X[feedback_from][k])
            U[k] = u
            for plant in plants:
                plant.set_inputs(u)
                plant.time = k * h
                plant.do_step(h)
    finally:
        for plant in plants:
            plant.close()
    U[-1] = U[-2] if n else U[-1]
    wall = time.perf_counter() - wall
    return [
        Trajectory(
            t=np.arange(n + 1) * h,
            x=X[j],
            u=U.copy(),
            y=Y[j],
            state_names=info.state_names,
            input_names=INPUT_NAMES,
            output_names=info.output_names,
            method=f"fmu:fmi{info.fmi_version[0]}:cs",
            message=f"plant {j} of {len(infos)} ({info.kind}) in one master",
            stats={"wall_time": wall, "comm_step": h, "time_in_do_step": plants[j].time_in_do_step},
        )
        for j, info in enumerate(infos)
    ]

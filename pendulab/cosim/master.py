"""A co-simulation master on fmpy's instance API: pendulab FMUs as plants under sampled controllers.

:func:`cosim` instantiates one FMU once, sets parameters and start values,
initializes it, then per communication step reads the states and outputs,
evaluates the controller (at its sample times), sets the inputs (held constant
over the step) and calls ``doStep``. :class:`~pendulab.cosim.plant.FmuPlant` is the
instance wrapper it is built on. :func:`cosim_many` steps several FMUs side
by side with the same inputs; :func:`cosim` is its one-plant case, so both
share one loop, and both can save the FMU state before a step and, when a step is
rejected (``doStep`` returns Discard, the result is non-finite, or a
user check refuses it), restore the state and retry the step in halves.

The instance is always freed (``terminate`` when legal, then
``freeInstance``), whatever goes wrong.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._checks import positive_float
from .._inputs import checked
from ..control.feedback import SampledController, full_input
from ..integrate.trajectory import Trajectory
from ..model.model import INPUT_NAMES
from .plant import FmuInfo, FmuPlant, StepCheck, inspect_fmu

if TYPE_CHECKING:
    from ..control.estimation import StateEstimator
    from ..evaluate.measurement import MeasurementModel

__all__ = ["cosim", "cosim_many"]


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
    ts = positive_float("controller.sample_time", controller.sample_time, "[s]")
    ratio = ts / comm_step
    m = round(ratio)
    if m < 1 or abs(ratio - m) > 1e-9 * ratio:
        raise ValueError(
            f"controller.sample_time ({ts:g} s) must be a whole multiple of comm_step ({comm_step:g} s): the master "
            "samples the controller only at communication points"
        )
    return m


#: Most communication steps of one run: each step is a row of the result and a controller call (an NMPC solve),
#: so a typo in t_final cannot allocate gigabytes or run for days.
MAX_COMM_STEPS = 1_000_000


def _n_steps(t_final: float, comm_step: float) -> int:
    ratio = t_final / comm_step
    if ratio > MAX_COMM_STEPS + 0.5:
        raise ValueError(
            f"t_final / comm_step = {t_final:g} s / {comm_step:g} s is {ratio:.3g} communication steps; at most {MAX_COMM_STEPS} "
            "(each step is a row of the result and a controller call)"
        )
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-9 * ratio:
        raise ValueError(f"t_final ({t_final:g} s) must be a whole number of communication steps ({comm_step:g} s)")
    return n


def _controller_output(controller: SampledController, t: float, x: np.ndarray) -> np.ndarray:
    """Controller torques scattered into (tau1, tau2); undriven inputs stay 0."""
    # A diverging estimator overflows on its way to a non-finite estimate: reported below, not as numpy warnings.
    with np.errstate(over="ignore", invalid="ignore"):
        u = np.asarray(controller(t, x.copy()), dtype=float).reshape(-1)
    x_hat = getattr(controller, "x_hat", None)
    if x_hat is not None and not np.isfinite(x_hat).all():
        raise ValueError(
            f"the state estimate is not finite at t = {t:.6g} s: the estimator diverged (e.g. a measurement delay "
            "it does not model: estimator='mmae' identifies one)"
        )
    return full_input(controller, u, t)


def _check_measurement(estimator: Any, measurement: Any) -> None:
    """Reject a bad estimator name or measurement model before any FMU is instantiated."""
    from ..evaluate.measurement import MeasurementModel

    if measurement is not None and not isinstance(measurement, MeasurementModel):
        raise TypeError(
            "measurement must be a pendulab.evaluate.measurement.MeasurementModel (velocity noise, delay) or None, "
            f"got {type(measurement).__name__}"
        )
    if estimator is None:
        return
    from ..control.estimation import StateEstimator
    from ..control.robust import ESTIMATORS

    if isinstance(estimator, str) and estimator not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {list(ESTIMATORS)} or an object with reset() and update(), got {estimator!r}")
    if not isinstance(estimator, str | StateEstimator):
        raise TypeError(
            f"estimator must be one of {list(ESTIMATORS)} or an object with reset() and update(), got {type(estimator).__name__}"
        )


def _estimated(controller: SampledController, estimator: Any, info: FmuInfo, params: Any, x0: np.ndarray) -> Any:
    """``controller`` fed by ``estimator`` (a name: built on the FMU's model at the controller's sample time from ``x0``)."""
    from ..control.robust import EstimatedController, build_estimator

    u_max = getattr(controller, "u_max", None)
    # Undriven inputs stay 0 whatever the limit (the wrapper scatters the command to the driven ones only).
    torque = None if u_max is None else np.array([float(u_max) if n in controller.input_names else 0.0 for n in INPUT_NAMES])
    est = build_estimator(estimator, info.model(params), float(controller.sample_time), x0=x0, torque_limit=torque)
    return EstimatedController(controller, est)


def _run(
    infos: Sequence[FmuInfo],
    controller: SampledController,
    h: float,
    n: int,
    *,
    feedback_from: int,
    x0s: Sequence[Any],
    params: Sequence[Mapping[str, float] | None],
    solver: str | int | None,
    tolerance: float | None,
    check: StepCheck | None,
    max_halvings: int,
    estimator: str | StateEstimator | None = None,
    measurement: MeasurementModel | None = None,
) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray, list[dict[str, Any]], float]:
    """The one master loop: states, outputs, shared inputs and per-plant stats of ``n`` steps of ``h``."""
    every = _check_controller(controller, infos[feedback_from], h)
    _check_measurement(estimator, measurement)
    if isinstance(max_halvings, bool) or not isinstance(max_halvings, int) or max_halvings < 0:
        raise ValueError(f"max_halvings must be a non-negative integer, got {max_halvings!r}")
    if max_halvings:
        cannot = [i.path.name for i in infos if not i.can_get_set_state]
        if cannot:
            raise ValueError(f"max_halvings={max_halvings} needs FMUs that can get and set their state; {cannot} cannot")
    X = [np.empty((n + 1, len(i.state_names))) for i in infos]
    Y = [np.empty((n + 1, len(i.output_names))) for i in infos]
    U = np.zeros((n + 1, len(INPUT_NAMES)))
    stats: list[dict[str, Any]] = [{"n_rejected": 0, "comm_step": h} for _ in infos]
    plants: list[FmuPlant] = []
    wall = time.perf_counter()
    try:
        for j, info in enumerate(infos):
            name = None if len(infos) == 1 else f"plant{j}"
            plants.append(FmuPlant(info, params=params[j], x0=x0s[j], solver=solver, tolerance=tolerance, instance_name=name))
        u = np.zeros(len(INPUT_NAMES))
        for k in range(n + 1):
            for j, plant in enumerate(plants):
                X[j][k], Y[j][k] = plant.read()
            if k == 0:  # the start state is known only now (the FMU's start values unless x0 is given)
                x_start = X[feedback_from][0]
                if estimator is not None:
                    controller = _estimated(controller, estimator, infos[feedback_from], params[feedback_from], x_start)
                controller.reset()
                if measurement is not None:
                    measurement.reset(x_start)
            if k == n:
                break
            t = k * h
            if k % every == 0:
                # The controller (or its estimator) sees the measurement: delayed by whole samples, noisy rates.
                x_meas = X[feedback_from][k] if measurement is None else measurement(X[feedback_from][k])
                u = _controller_output(controller, t, x_meas)
            U[k] = u
            for j, plant in enumerate(plants):
                plant.set_inputs(u)
                plant.time = t  # multiply, never accumulate: t_k = k h exactly as in the native grid
                if max_halvings:
                    plant.step_with_retry(h, check, max_halvings, stats[j])
                else:
                    plant.do_step(h)
        for j, plant in enumerate(plants):
            stats[j].update(time_in_do_step=plant.time_in_do_step, n_do_step=plant.n_do_step)
    finally:
        for plant in plants:
            plant.close()
    U[-1] = U[-2]  # last row repeats, as in native trajectories
    return X, Y, U, stats, time.perf_counter() - wall


@checked()
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
    estimator: str | StateEstimator | None = None,
    measurement: MeasurementModel | None = None,
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
    estimator : {"ekf", "mmae"} or StateEstimator, optional
        Feed the controller the estimator's state instead of the measurement
        (:class:`~pendulab.control.robust.EstimatedController`; a name is built by
        :func:`~pendulab.control.robust.build_estimator` on the FMU's model with ``params`` at the
        controller's sample time, from the start state read from the FMU).
    measurement : MeasurementModel, optional
        What the controller (or its estimator) sees at each of its samples:
        :class:`~pendulab.evaluate.measurement.MeasurementModel` (delay in controller samples, Gaussian
        noise on ``omega1, omega2``, seeded; reset at the start state). Default: the FMU's state as it is.

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
        or inconsistent steps, bad parameters or start values, an unknown estimator name.
    TypeError
        ``estimator`` neither a name nor an estimator, ``measurement`` not a MeasurementModel.
    StepRejectedError
        A step could not be completed even at the smallest retry step.
    RuntimeError
        The FMU reported an error.

    Examples
    --------
    LQR balancing of the upright rigid pendulum, the FMU as the plant, 10 ms communication steps:

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control.feedback import balance_controller, upright_state
    >>> from pendulab.cosim import cosim
    >>> from pendulab.fmu import export
    >>> model = pl.rigid()
    >>> fmu = export(model, "rigid.fmu", timestamp=False)
    >>> controller = balance_controller(model, sample_time=0.01)  # continuous LQR gain, zero-order hold
    >>> x0 = upright_state(model) + [0.1, 0.0, 0.0, 0.0]  # link 1 tilted by 0.1 rad
    >>> traj = cosim(fmu, controller, comm_step=0.01, t_final=5.0, x0=x0, solver="rodas4", tolerance=1e-10)
    >>> traj.x.shape, traj.stats["n_do_step"], bool(np.abs(traj.x[-1] - upright_state(model)).max() < 1e-3)
    ((501, 4), 500, True)

    The same sampled-data loop integrated natively agrees:

    >>> native = pl.simulate(model, x0, 5.0, dt=0.01, u=controller, method="cvodes", rtol=1e-10, atol=1e-10)
    >>> bool(np.abs(native.x - traj.x).max() < 1e-6)
    True
    """
    h = float(comm_step)
    n = _n_steps(float(t_final), h)
    info = inspect_fmu(fmu_path)
    X, Y, U, stats, wall = _run(
        [info],
        controller,
        h,
        n,
        feedback_from=0,
        x0s=[x0],
        params=[params],
        solver=solver,
        tolerance=tolerance,
        check=check,
        max_halvings=max_halvings,
        estimator=estimator,
        measurement=measurement,
    )
    return Trajectory(
        t=np.arange(n + 1) * h,
        x=X[0],
        u=U,
        y=Y[0],
        state_names=info.state_names,
        input_names=INPUT_NAMES,
        output_names=info.output_names,
        method=f"fmu:fmi{info.fmi_version[0]}:cs" + (f":{solver}" if solver is not None else ""),
        success=True,
        message=f"co-simulated {info.path.name} to t = {n * h:.6g} s in {n} communication steps of {h:g} s",
        stats={**stats[0], "wall_time": wall},
    )


@checked(feedback_from="fmu_index")
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
    check: StepCheck | None = None,
    max_halvings: int = 0,
    estimator: str | StateEstimator | None = None,
    measurement: MeasurementModel | None = None,
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
    solver, tolerance, check, max_halvings
        As in :func:`cosim`, for all plants (a rejected step is retried per plant).
    estimator, measurement
        As in :func:`cosim`, on the feedback plant.

    Returns
    -------
    list of Trajectory
        One per FMU, on the same time grid with identical ``u``.

    Raises
    ------
    ValueError
        No FMU, ``feedback_from`` out of range, ``x0`` or ``params`` not one
        entry per FMU, non-positive steps, or the errors of :func:`cosim`.
    StepRejectedError
        A step could not be completed even at the smallest retry step.
    RuntimeError
        An FMU reported an error.

    Examples
    --------
    One controller balances plant 0; plant 1, with a heavier link 2, gets the same torques open loop:

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control.feedback import balance_controller, upright_state
    >>> from pendulab.cosim import cosim_many
    >>> from pendulab.fmu import export
    >>> model = pl.rigid()
    >>> fmu = export(model, "rigid.fmu", timestamp=False)
    >>> x0 = upright_state(model) + [0.1, 0.0, 0.0, 0.0]
    >>> balanced, heavier = cosim_many(
    ...     [fmu, fmu], balance_controller(model, 0.01), 0.01, 3.0, x0=[x0, x0], params=[None, {"m2": 1.2}]
    ... )
    >>> bool(np.array_equal(balanced.u, heavier.u))  # identical inputs
    True
    >>> np.round(balanced.x[-1, :2], 3), bool(abs(heavier.x[-1, 0] - np.pi) > 1.0)  # upright; fallen
    (array([3.142, 3.142]), True)
    """
    h = float(comm_step)
    n = _n_steps(float(t_final), h)
    infos = [inspect_fmu(p) for p in fmu_paths]
    if not infos:
        raise ValueError("fmu_paths must name at least one FMU, got an empty sequence")
    if not 0 <= feedback_from < len(infos):
        raise ValueError(f"feedback_from must index fmu_paths (0..{len(infos) - 1}), got {feedback_from!r}")
    x0s = list(x0) if x0 is not None else [None] * len(infos)
    ps = list(params) if params is not None else [None] * len(infos)
    if len(x0s) != len(infos) or len(ps) != len(infos):
        raise ValueError(f"x0 and params must have one entry per FMU ({len(infos)}), got {len(x0s)} and {len(ps)}")
    X, Y, U, stats, wall = _run(
        infos,
        controller,
        h,
        n,
        feedback_from=feedback_from,
        x0s=x0s,
        params=ps,
        solver=solver,
        tolerance=tolerance,
        check=check,
        max_halvings=max_halvings,
        estimator=estimator,
        measurement=measurement,
    )
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
            stats={**stats[j], "wall_time": wall},
        )
        for j, info in enumerate(infos)
    ]

"""A thin adapter over fmpy's low-level FMI 2 / FMI 3 classes used by the runtime tests."""

from __future__ import annotations

import numpy as np


class Driver:
    """Uniform get/set/step/state calls for one instantiated FMU (CS or ME, FMI 2 or 3)."""

    def __init__(self, built, interface: str = "CS", name: str = "inst", logger=None) -> None:
        self.built = built
        self.v3 = built.version == 3
        self.vr = built.vr
        self.fmu = built.instance(interface, name, logger)
        self.t = 0.0

    # values by name
    def set(self, **values: float) -> None:
        vrs = [self.vr[n] for n in values]
        (self.fmu.setFloat64 if self.v3 else self.fmu.setReal)(vrs, [float(v) for v in values.values()])

    def get(self, *names: str) -> np.ndarray:
        vrs = [self.vr[n] for n in names]
        return np.array((self.fmu.getFloat64 if self.v3 else self.fmu.getReal)(vrs))

    def set_solver(self, solver: int) -> None:
        (self.fmu.setInt32 if self.v3 else self.fmu.setInteger)([self.vr["solver"]], [solver])

    def initialize(self, tolerance: float = 1e-10) -> None:
        if self.v3:
            self.fmu.enterInitializationMode(tolerance=tolerance, startTime=0.0)
        else:
            self.fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def step(self, h: float) -> None:
        self.fmu.doStep(self.t, h)
        self.t += h

    def get_state(self):
        return self.fmu.getFMUState() if self.v3 else self.fmu.getFMUstate()

    def set_state(self, state) -> None:
        (self.fmu.setFMUState if self.v3 else self.fmu.setFMUstate)(state)

    def serialize(self, state) -> bytes:
        return self.fmu.serializeFMUState(state) if self.v3 else self.fmu.serializeFMUstate(state)

    def deserialize(self, data: bytes):
        return self.fmu.deserializeFMUState(data) if self.v3 else self.fmu.deSerializeFMUstate(data)

    def free_state(self, state) -> None:
        (self.fmu.freeFMUState if self.v3 else self.fmu.freeFMUstate)(state)

    def close(self) -> None:
        try:
            self.fmu.terminate()
        except Exception:  # noqa: BLE001 - already terminated or in error state
            pass
        self.fmu.freeInstance()


def started(
    built,
    x0: dict[str, float],
    *,
    solver: int = 0,
    tolerance: float = 1e-10,
    interface: str = "CS",
    name: str = "inst",
    logger=None,
    **params: float,
) -> Driver:
    """An initialized instance with the given start states, parameters and solver."""
    d = Driver(built, interface, name, logger)
    d.set(**x0, **params)
    if interface == "CS":
        d.set_solver(solver)
    d.initialize(tolerance)
    return d

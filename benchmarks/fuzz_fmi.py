"""FMI call-sequence fuzzer for the pendulab FMUs (FMI 2 and 3, Co-Simulation and Model Exchange, rigid and elastic).

Random call sequences with edge-value arguments (NaN, +-inf, 0, negative, tiny and huge steps, invalid
value references, out-of-order calls, corrupted and garbage serialized states, NULL pointers) are driven
through fmpy's low-level classes (``FMU2Slave``/``FMU2Model``/``FMU3Slave``/``FMU3Model``; the raw
shared-library entry point for calls of the other interface). A sequence is a pure function of its seed and
configuration, so every finding is reproducible with ``--replay SEED``.

Each batch of sequences runs in its own subprocess: a crash (signal) or a hang (timeout) is reported with
the seed and the call sequence. Checked after every call:

* the status is a valid FMI status (0..4);
* a Discard/Error/Fatal status comes with a message through the logger callback;
* a call rejected with Error that leaves the instance usable changed nothing (the FMU state, serialized
  before and after, is bit-identical);
* once the instance is in the Error state (a solver failure), every call that would continue the simulation
  (DoStep, Set*, mode changes, GetFMUState, directional derivatives ...) returns Error, until FreeInstance,
  Reset or SetFMUState with a state stored before the error (the restart the FMI standard allows).

The life-cycle state is read from the FMU state itself (GetFMUState + Serialize: the ``machine`` field of
``CoreData`` in ``pendulab/fmu/c/fmu_core.h``; GetFMUState is refused only in the Error state).

Run: ``PYTHONPATH=. python benchmarks/fuzz_fmi.py --sequences 2000 [--length 60] [--seed 0] [--jobs 2]``
(builds the four FMUs in a temporary directory unless ``--fmu-dir`` holds ``{rigid,elastic}{2,3}.fmu``).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import os
import random
import struct
import subprocess
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from pendulab.model.builders import STATE_NAMES
from pendulab.model.params import ElasticParams, RigidParams

CONFIGS = [(kind, version, interface) for kind in ("rigid", "elastic") for version in (2, 3) for interface in ("CS", "ME")]
# from the model's own declarations: a parameter added to a model moves the FMU state's fields
NX = {kind: len(names) for kind, names in STATE_NAMES.items()}
NP = {"rigid": len(RigidParams.names()), "elastic": len(ElasticParams.names())}
NU, NY = 2, 6  # checked against the model description by the worker

NAN, INF = math.nan, math.inf
FLOATS = [
    NAN,
    INF,
    -INF,
    0.0,
    -0.0,
    -1.0,
    1e-300,
    -1e-300,
    5e-324,
    1e300,
    -1e300,
    1.7976931348623157e308,
    1e-15,
    1e-8,
    0.5,
    1.0,
    2.0,
    10.0,
    0.01,
    3.0,
]
STEPS = [0.01] * 8 + [0.001, 0.1, 1.0, 1e-300, 5e-324, 1e-15, 1e-12, 0.0, -0.0, -0.01, -1e-300, NAN, INF, -INF, 1e300, 1e6]
BAD_VRS = [1, 99, 150, 299, 350, 499, 899, 903, 9999, 2**32 - 1]
STATUS_NAMES = ["OK", "Warning", "Discard", "Error", "Fatal"]

# CoreData layout (fmu_core.h, LP64): magic u64, machine i32 (+4 pad), time, x[nx], u[nu], p[np],
# tolerance, max_step, solver i32, tolerance_from_master i32, OdeSolver {n, method i32; rtol, atol, h_max;
# max_steps i64; h; n_steps, n_rejected, n_rhs, n_jac i64}
MACHINE_OFFSET = 8
MACHINE_NAMES = {
    1: "Instantiated",
    2: "InitializationMode",
    4: "StepMode",
    8: "EventMode",
    16: "ContinuousTimeMode",
    32: "Terminated",
    64: "Error",
}
PAD = range(12, 16)


def field_offsets(nx: int, nu: int, np_: int) -> dict[str, tuple[int, str]]:
    """Byte offset and struct format of the fields of a serialized FMU state."""
    off = {"magic": (0, "<Q"), "machine": (8, "<i"), "time": (16, "<d")}
    o = 24
    for i in range(nx):
        off[f"x{i}"] = (o + 8 * i, "<d")
    o += 8 * nx
    for i in range(nu):
        off[f"u{i}"] = (o + 8 * i, "<d")
    o += 8 * nu
    for i in range(np_):
        off[f"p{i}"] = (o + 8 * i, "<d")
    o += 8 * np_
    off.update(tolerance=(o, "<d"), max_step=(o + 8, "<d"), solver=(o + 16, "<i"), tol_flag=(o + 20, "<i"))
    o += 24
    off.update(
        ode_n=(o, "<i"),
        ode_method=(o + 4, "<i"),
        ode_rtol=(o + 8, "<d"),
        ode_hmax=(o + 24, "<d"),
        ode_max_steps=(o + 32, "<q"),
        ode_h=(o + 40, "<d"),
        ode_n_steps=(o + 48, "<q"),
    )
    return off


# --------------------------------------------------------------------------------------- generation
def generate(seed: int, kind: str, version: int, interface: str, length: int) -> list[tuple]:
    """The call sequence of ``seed``: a list of ``(name, *args)`` tuples (plain Python values)."""
    rng = random.Random(f"{seed}|{kind}|{version}|{interface}")
    nx, cs = NX[kind], interface == "CS"
    state_vrs = list(range(100, 100 + nx))
    good_vrs = [0, *state_vrs, *range(200, 200 + nx), 300, 301, *range(400, 406), *range(500, 500 + NP[kind]), 900, 901]

    def f() -> float:
        return rng.choice(FLOATS) if rng.random() < 0.5 else rng.uniform(-3.0, 3.0)

    def vrs(n: int) -> list[int]:
        return [rng.choice(good_vrs) if rng.random() < 0.85 else rng.choice(BAD_VRS) for _ in range(n)]

    def tvalue() -> str | float:  # communication point / time: usually "the FMU's time"
        r = rng.random()
        return "now" if r < 0.8 else ("now+eps" if r < 0.88 else f())

    calls: list[tuple] = []
    phase = 0  # the generator's intention only; the FMU's real state may differ (out-of-order calls)
    for _ in range(length):
        r = rng.random()
        if phase == 0 and r < 0.3:
            calls.append(
                ("set_real", vrs(rng.randint(1, 3)), [f() if rng.random() < 0.4 else rng.uniform(0.1, 2.0) for _ in range(3)])
            )
        elif phase == 0 and r < 0.4:
            calls.append(("set_int", [rng.choice([902, 902, 902, 5])], [rng.choice([0, 1, 1, 2, -1, 2**31 - 1])]))
        elif phase == 0 and r < 0.7:
            calls.append(
                (
                    "enter_init",
                    rng.random() < 0.5,
                    rng.choice([1e-8, 1e-6, 1e-10, 0.0, -1.0, NAN, 2.0]),
                    rng.choice([0.0, 0.0, 1.0, -5.0, NAN, INF, 1e300]),
                )
            )
            phase = 1
        elif phase == 1 and r < 0.6:
            calls.append(("exit_init",))
            phase = 2
        else:
            calls.append(_any_call(rng, f, vrs, tvalue, nx, cs))
            if calls[-1][0] in ("reset",):
                phase = 0
    return calls


def _any_call(rng, f, vrs, tvalue, nx: int, cs: bool) -> tuple:
    weights = {
        "do_step": 30 if cs else 3,
        "get_real": 8,
        "set_real": 8,
        "get_int": 2,
        "set_int": 2,
        "get_state": 5,
        "set_state": 5,
        "free_state": 2,
        "serialize": 4,
        "deserialize": 6,
        "corrupt_blob": 6,
        "garbage_blob": 3,
        "enter_init": 2,
        "exit_init": 2,
        "terminate": 2,
        "reset": 2,
        "directional": 3,
        "debug_logging": 2,
        "null_call": 4,
        "me_event": 4 if not cs else 1,
        "me_cont": 4 if not cs else 1,
        "me_set_time": 6 if not cs else 1,
        "me_set_states": 6 if not cs else 1,
        "me_get_derivatives": 5 if not cs else 1,
        "me_completed": 4 if not cs else 1,
        "me_get_states": 2,
        "me_nominals": 1,
        "me_indicators": 1,
        "status": 1,
    }
    name = rng.choices(list(weights), list(weights.values()))[0]
    if name == "do_step":
        return ("do_step", tvalue(), rng.choice(STEPS) if rng.random() < 0.5 else rng.choice([0.01, 0.02, 0.005]))
    if name in ("get_real", "me_get_states"):
        return ("get_real", vrs(rng.randint(0, 4)))
    if name == "set_real":
        n = rng.randint(1, 3)
        return ("set_real", vrs(n), [f() for _ in range(n)])
    if name == "get_int":
        return ("get_int", [rng.choice([902, 902, 3])])
    if name == "set_int":
        return ("set_int", [rng.choice([902, 902, 3])], [rng.choice([0, 1, 7, -1])])
    if name in ("get_state", "free_state", "serialize"):
        return (name, rng.randint(0, 2))
    if name == "set_state":
        return ("set_state", rng.randint(0, 2))
    if name == "deserialize":
        return ("deserialize", rng.randint(0, 2))
    if name == "corrupt_blob":
        fieldname = rng.choice(
            [
                "magic",
                "machine",
                "time",
                "x0",
                f"x{nx - 1}",
                "x2",
                "u0",
                "p0",
                "p1",
                "p2",
                "p4",
                "p5",
                "tolerance",
                "max_step",
                "solver",
                "tol_flag",
                "ode_n",
                "ode_method",
                "ode_rtol",
                "ode_hmax",
                "ode_max_steps",
                "ode_h",
                "ode_n_steps",
                "byte",
            ]
        )
        value = rng.choice([NAN, INF, -1.0, 0.0, 1e300, 2.0, 7, -5, 2**40, 1e-300])
        return ("corrupt_blob", rng.randint(0, 2), fieldname, value, rng.randint(0, 10**6))
    if name == "garbage_blob":
        return (
            "garbage_blob",
            rng.choice(["empty", "short", "long", "zeros", "random", "truncated", "extended"]),
            rng.randint(0, 10**6),
        )
    if name == "enter_init":
        return ("enter_init", rng.random() < 0.5, rng.choice([1e-8, 0.0, NAN]), rng.choice([0.0, NAN, -1.0]))
    if name in ("exit_init", "terminate", "reset", "me_event", "me_cont", "me_completed", "me_nominals"):
        return (name,)
    if name == "directional":
        return ("directional", vrs(rng.randint(0, 3)), vrs(rng.randint(0, 3)), rng.choice([1.0, NAN, 0.0]))
    if name == "debug_logging":
        return (
            "debug_logging",
            rng.random() < 0.5,
            rng.choice([[], ["logCalls"], ["logStatusError", "logCalls"], ["nonsense"], [None]]),
        )
    if name == "me_set_time":
        return ("me_set_time", tvalue() if rng.random() < 0.5 else rng.choice([0.5, 1.0, NAN, INF, -1.0]))
    if name == "me_set_states":
        n = rng.choice([nx] * 6 + [0, nx - 1, nx + 1])
        return ("me_set_states", n, [f() if rng.random() < 0.15 else rng.uniform(0.5, 1.5) for _ in range(n)])
    if name == "me_get_derivatives":
        return ("me_get_derivatives", rng.choice([nx] * 5 + [0, 1]))
    if name == "me_indicators":
        return ("me_indicators", rng.choice([0, 0, 1]))
    if name == "status":
        return ("status", rng.randint(0, 4))
    return (
        "null_call",
        rng.choice(
            [
                "get_real",
                "set_real",
                "get_state",
                "set_state",
                "deserialize",
                "serialize",
                "size",
                "do_step_outputs",
                "set_states",
                "derivatives",
                "directional",
                "free_state",
                "event_info",
                "completed",
                "debug_logging",
                "status",
                "get_int",
            ]
        ),
    )


# --------------------------------------------------------------------------------------- execution
class PropertyViolationError(Exception):
    """A checked property does not hold."""


@dataclass
class Stats:
    sequences: int = 0
    calls: int = 0
    statuses: Counter = field(default_factory=Counter)
    error_state_entries: int = 0
    restarts_from_error: int = 0


MUST_FAIL_IN_ERROR = {
    "do_step",
    "set_real",
    "set_int",
    "enter_init",
    "exit_init",
    "terminate",
    "get_state",
    "directional",
    "me_event",
    "me_cont",
    "me_set_time",
    "me_set_states",
    "me_completed",
}


class Runner:
    """Executes call sequences on one FMU (one library load; a fresh instance per sequence)."""

    def __init__(self, unzipdir: str, kind: str, version: int, interface: str) -> None:
        from fmpy import read_model_description

        self.kind, self.version, self.interface = kind, version, interface
        self.v3, self.cs = version == 3, interface == "CS"
        md = read_model_description(unzipdir)
        self.guid = md.guid
        names = {v.name: v.valueReference for v in md.modelVariables}
        self.nx = sum(1 for v in md.modelVariables if 100 <= v.valueReference < 200)
        self.nu = sum(1 for v in md.modelVariables if 300 <= v.valueReference < 400)
        self.np = sum(1 for v in md.modelVariables if 500 <= v.valueReference < 900)
        assert self.nx == NX[kind] and "theta1" in names
        self.offsets = field_offsets(self.nx, self.nu, self.np)
        pnames = sorted((v.valueReference, v.name) for v in md.modelVariables if 500 <= v.valueReference < 900)
        self.positive = [n in ("m1", "m2", "L1", "L2", "k1", "k2") for _, n in pnames]
        ident = md.coSimulation.modelIdentifier if self.cs else md.modelExchange.modelIdentifier
        if self.v3:
            from fmpy import fmi3

            cls = fmi3.FMU3Slave if self.cs else fmi3.FMU3Model
        else:
            from fmpy import fmi2

            cls = fmi2.FMU2Slave if self.cs else fmi2.FMU2Model
        self.fmu = cls(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=ident, instanceName="fuzz")
        self.p = "fmi3" if self.v3 else "fmi2"
        if self.v3:
            from fmpy import fmi3 as types
        else:
            from fmpy import fmi2 as types
        self.byte = types.fmi3Byte if self.v3 else types.fmi2Byte
        self.log: list[tuple[int, str]] = []
        self._make_callbacks()

    # ---- logging
    def _make_callbacks(self) -> None:
        if self.v3:
            from fmpy.fmi3 import fmi3LogMessageCallback

            def log3(env, status, category, message):
                self.log.append((status, message.decode(errors="replace") if message else ""))

            self._log3 = fmi3LogMessageCallback(log3)
            from fmpy.fmi3 import fmi3IntermediateUpdateCallback

            self._no_update = fmi3IntermediateUpdateCallback()
        else:
            from fmpy.fmi2 import calloc as c_calloc
            from fmpy.fmi2 import (
                fmi2CallbackAllocateMemoryTYPE,
                fmi2CallbackFreeMemoryTYPE,
                fmi2CallbackFunctions,
                fmi2CallbackLoggerTYPE,
            )
            from fmpy.fmi2 import free as c_free
            from fmpy.logging import addLoggerProxy

            def log2(env, name, status, category, message):
                self.log.append((status, message.decode(errors="replace") if message else ""))

            cb = fmi2CallbackFunctions()
            cb.logger = fmi2CallbackLoggerTYPE(log2)
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(c_calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(c_free)
            addLoggerProxy(ctypes.byref(cb))
            self._cb = cb

    # ---- raw calls
    def raw(self, name: str, *args) -> int:
        """Status of ``fmi{2,3}<name>(instance, *args)`` through fmpy (or the library for the other interface)."""
        from fmpy.fmi1 import FMICallException

        full = self.p + name
        fn = getattr(self.fmu, full, None)
        try:
            if fn is not None:
                res = fn(self.fmu.component, *args)
            else:
                res = self._dll(full, args)(self.fmu.component, *args)
        except FMICallException as exc:
            return exc.status
        return int(res) if res is not None else 0

    def _dll(self, full: str, args) -> ctypes._CFuncPtr:
        f = getattr(self.fmu.dll, full)
        types = [ctypes.c_void_p]
        for a in args:
            types.append(ctypes.c_double if isinstance(a, float) else (ctypes.c_int if isinstance(a, int) else ctypes.c_void_p))
        f.argtypes, f.restype = types, ctypes.c_int
        return f

    def instantiate(self) -> None:
        if self.v3:
            if self.cs:
                c = self.fmu.fmi3InstantiateCoSimulation(
                    b"fuzz", self.guid.encode(), None, False, False, False, False, None, 0, None, self._log3, self._no_update
                )
            else:
                c = self.fmu.fmi3InstantiateModelExchange(b"fuzz", self.guid.encode(), None, False, False, None, self._log3)
        else:
            kind = 1 if self.cs else 0
            c = self.fmu.fmi2Instantiate(b"fuzz", kind, self.guid.encode(), b"", ctypes.byref(self._cb), False, False)
        if not c:
            raise PropertyViolationError("instantiation failed")
        self.fmu.component = c

    def free_instance(self) -> None:
        getattr(self.fmu, self.p + "FreeInstance")(self.fmu.component)
        self.fmu.component = None

    # ---- the oracle: life-cycle state and a bit-exact snapshot from the FMU state
    def snapshot(self) -> tuple[str, bytes | None]:
        state = ctypes.c_void_p()
        saved = list(self.log)
        name = "GetFMUState" if self.v3 else "GetFMUstate"
        st = self.raw(name, ctypes.byref(state))
        if st != 0:
            msgs = self.log[len(saved) :]
            self.log[:] = saved
            if any("not allowed in state Error" in m for _, m in msgs):
                return "Error", None
            raise PropertyViolationError(f"oracle {self.p}{name} failed with status {st}: {msgs}")
        size = ctypes.c_size_t()
        self.raw("SerializedFMUStateSize" if self.v3 else "SerializedFMUstateSize", state, ctypes.byref(size))
        buf = (self.byte * size.value)()
        st2 = self.raw("SerializeFMUState" if self.v3 else "SerializeFMUstate", state, buf, size.value)
        self.raw("FreeFMUState" if self.v3 else "FreeFMUstate", ctypes.byref(state))
        self.log[:] = saved
        if st2 != 0:
            raise PropertyViolationError(f"oracle serialize failed with status {st2}")
        blob = bytearray(ctypes.string_at(buf, size.value))
        machine = struct.unpack_from("<i", blob, MACHINE_OFFSET)[0]
        self.check_invariants(blob)
        for i in PAD:
            blob[i] = 0
        return MACHINE_NAMES.get(machine, f"?{machine}"), bytes(blob)

    # ---- one sequence
    def run(self, calls: list[tuple], stats: Stats, trace: list[str] | None = None) -> None:
        self.instantiate()
        self.states: list[ctypes.c_void_p] = [ctypes.c_void_p(), ctypes.c_void_p(), ctypes.c_void_p()]
        self.blobs: list[bytes | None] = [None, None, None]
        try:
            machine, snap = self.snapshot()
            for k, call in enumerate(calls):
                if trace is not None:
                    trace.append(f"{k}: {call!r}")
                self.log.clear()
                before_machine, before = machine, snap
                status = self.execute(call, machine)
                stats.calls += 1
                if status not in range(5):
                    raise PropertyViolationError(f"call {k} {call!r}: invalid status {status}")
                stats.statuses[STATUS_NAMES[status]] += 1
                if status >= 2 and not any(s >= 2 for s, _ in self.log):
                    raise PropertyViolationError(f"call {k} {call!r}: status {STATUS_NAMES[status]} without a logged message")
                machine, snap = self.snapshot()
                if before_machine == "Error" and machine == "Error" and call[0] in MUST_FAIL_IN_ERROR and status != 3:
                    raise PropertyViolationError(f"call {k} {call!r}: returned {STATUS_NAMES[status]} in the Error state")
                if before_machine == "Error" and machine != "Error":
                    if not (status == 0 and call[0] in ("reset", "set_state")):
                        raise PropertyViolationError(
                            f"call {k} {call!r}: left the Error state with status {STATUS_NAMES[status]}"
                        )
                    stats.restarts_from_error += 1
                if machine == "Error" and before_machine != "Error":
                    stats.error_state_entries += 1
                    if status != 3:
                        raise PropertyViolationError(
                            f"call {k} {call!r}: entered the Error state but returned {STATUS_NAMES[status]}"
                        )
                if status == 3 and machine != "Error" and before_machine != "Error" and snap != before:
                    raise PropertyViolationError(f"call {k} {call!r}: rejected with Error but changed the instance")
        finally:
            for s in self.states:
                if s.value:
                    self.raw("FreeFMUState" if self.v3 else "FreeFMUstate", ctypes.byref(s))
            self.free_instance()
        stats.sequences += 1

    def check_invariants(self, blob: bytes) -> None:
        """The instance data obeys the setters' rules, however it got there (set, restored, stepped)."""

        def get(name):
            off, fmt = self.offsets[name]
            return struct.unpack_from(fmt, blob, off)[0]

        bad = []
        if not math.isfinite(get("time")):
            bad.append("time")
        bad += [f"x{i}" for i in range(self.nx) if not math.isfinite(get(f"x{i}"))]
        bad += [f"u{i}" for i in range(self.nu) if not math.isfinite(get(f"u{i}"))]
        for i, pos in enumerate(self.positive):
            v = get(f"p{i}")
            if not math.isfinite(v) or (v <= 0.0 if pos else v < 0.0):
                bad.append(f"p{i}={v}")
        if not 0.0 < get("tolerance") < 1.0:
            bad.append("tolerance")
        if get("solver") not in (0, 1):
            bad.append("solver")
        if bad:
            raise PropertyViolationError(f"the instance holds invalid data: {', '.join(bad)}")

    def _time(self, value) -> float:
        if not isinstance(value, str):
            return value
        t = (ctypes.c_double * 1)()
        vr = (ctypes.c_uint * 1)(0)
        saved = list(self.log)
        st = self.raw("GetFloat64" if self.v3 else "GetReal", vr, 1, t, *((1,) if self.v3 else ()))
        self.log[:] = saved
        now = t[0] if st == 0 else 0.0
        return now if value == "now" else now * (1 + 1e-12) + 1e-13

    def execute(self, call: tuple, machine: str) -> int:
        name, args = call[0], call[1:]
        v3 = self.v3
        D = ctypes.c_double
        if name == "set_real":
            vrs, vals = args[0], args[1][: len(args[0])]
            a, b = (ctypes.c_uint * len(vrs))(*vrs), (D * len(vals))(*vals)
            return self.raw("SetFloat64", a, len(vrs), b, len(vals)) if v3 else self.raw("SetReal", a, len(vrs), b)
        if name == "get_real":
            vrs = args[0]
            a, b = (ctypes.c_uint * max(1, len(vrs)))(*vrs), (D * max(1, len(vrs)))()
            return self.raw("GetFloat64", a, len(vrs), b, len(vrs)) if v3 else self.raw("GetReal", a, len(vrs), b)
        if name in ("set_int", "get_int"):
            vrs = args[0]
            a = (ctypes.c_uint * len(vrs))(*vrs)
            b = (ctypes.c_int * len(vrs))(*(args[1] if name == "set_int" else [0] * len(vrs)))
            fn = ("SetInt32" if v3 else "SetInteger") if name == "set_int" else ("GetInt32" if v3 else "GetInteger")
            return self.raw(fn, a, len(vrs), b, len(vrs)) if v3 else self.raw(fn, a, len(vrs), b)
        if name == "enter_init":
            tol_defined, tol, start = args
            if v3:
                return self.raw("EnterInitializationMode", int(tol_defined), tol, start, 0, 0.0)
            st = self.raw("SetupExperiment", int(tol_defined), tol, start, 0, 0.0)
            return st if st != 0 else self.raw("EnterInitializationMode")
        if name == "exit_init":
            return self.raw("ExitInitializationMode")
        if name == "terminate":
            return self.raw("Terminate")
        if name == "reset":
            return self.raw("Reset")
        if name == "do_step":
            t, h = self._time(args[0]), args[1]
            if v3:
                b = [ctypes.c_bool() for _ in range(3)]
                last = D()
                return self.raw("DoStep", t, h, 1, *(ctypes.byref(x) for x in b), ctypes.byref(last))
            return self.raw("DoStep", t, h, 1)
        if name == "get_state":
            return self.raw("GetFMUState" if v3 else "GetFMUstate", ctypes.byref(self.states[args[0]]))
        if name == "set_state":
            return self.raw("SetFMUState" if v3 else "SetFMUstate", self.states[args[0]])
        if name == "free_state":
            return self.raw("FreeFMUState" if v3 else "FreeFMUstate", ctypes.byref(self.states[args[0]]))
        if name == "serialize":
            s = self.states[args[0]]
            size = ctypes.c_size_t()
            st = self.raw("SerializedFMUStateSize" if v3 else "SerializedFMUstateSize", s, ctypes.byref(size))
            if st != 0:
                return st
            buf = (self.byte * size.value)()
            st = self.raw("SerializeFMUState" if v3 else "SerializeFMUstate", s, buf, size.value)
            if st == 0:
                self.blobs[args[0]] = ctypes.string_at(buf, size.value)
            return st
        if name == "deserialize":
            blob = self.blobs[args[0]]
            return self._deserialize(blob if blob is not None else b"", args[0])
        if name == "corrupt_blob":
            slot, fieldname, value, salt = args
            blob = self.blobs[slot]
            if blob is None:
                return self._deserialize(b"\x01" * 8, slot)
            data = bytearray(blob)
            if fieldname == "byte":
                data[salt % len(data)] ^= 1 << (salt % 8)
            else:
                off, fmt = self.offsets[fieldname]
                if fmt == "<d":
                    struct.pack_into(fmt, data, off, float(value))
                else:
                    iv = int(value) if isinstance(value, int) or math.isfinite(value) else -1
                    lo, hi = (-(2**31), 2**31 - 1) if fmt == "<i" else ((0, 2**64 - 1) if fmt == "<Q" else (-(2**63), 2**63 - 1))
                    struct.pack_into(fmt, data, off, min(max(iv, lo), hi))
            return self._deserialize(bytes(data), slot)
        if name == "garbage_blob":
            form, salt = args
            rng = random.Random(salt)
            size = len(self.blobs[0]) if self.blobs[0] else 400
            data = {
                "empty": b"",
                "short": bytes(7),
                "long": bytes(size * 3),
                "zeros": bytes(size),
                "random": bytes(rng.getrandbits(8) for _ in range(size)),
                "truncated": (self.blobs[0] or bytes(size))[:-1],
                "extended": (self.blobs[0] or bytes(size)) + b"\x00",
            }[form]
            return self._deserialize(data, salt % 3)
        if name == "directional":
            unk, kn, seed = args
            a, b = (ctypes.c_uint * max(1, len(unk)))(*unk), (ctypes.c_uint * max(1, len(kn)))(*kn)
            s, out = (D * max(1, len(kn)))(*([seed] * len(kn))), (D * max(1, len(unk)))()
            if v3:
                return self.raw("GetDirectionalDerivative", a, len(unk), b, len(kn), s, len(kn), out, len(unk))
            return self.raw("GetDirectionalDerivative", a, len(unk), b, len(kn), s, out)
        if name == "debug_logging":
            on, cats = args
            arr = (ctypes.c_char_p * max(1, len(cats)))(*[c.encode() if c else None for c in cats])
            return self.raw("SetDebugLogging", int(on), len(cats), arr)
        if name == "me_event":
            return self.raw("EnterEventMode")
        if name == "me_cont":
            return self.raw("EnterContinuousTimeMode")
        if name == "me_set_time":
            return self.raw("SetTime", self._time(args[0]))
        if name == "me_set_states":
            n, vals = args
            return self.raw("SetContinuousStates", (D * max(1, n))(*vals), n)
        if name == "me_get_derivatives":
            n = args[0]
            return self.raw("GetContinuousStateDerivatives" if v3 else "GetDerivatives", (D * max(1, n))(), n)
        if name == "me_completed":
            a, b = (ctypes.c_bool(), ctypes.c_bool()) if v3 else (ctypes.c_int(), ctypes.c_int())
            return self.raw("CompletedIntegratorStep", 1, ctypes.byref(a), ctypes.byref(b))
        if name == "me_nominals":
            return self.raw("GetNominalsOfContinuousStates", (D * self.nx)(), self.nx)
        if name == "me_indicators":
            n = args[0]
            return self.raw("GetEventIndicators", (D * max(1, n))(), n)
        if name == "status":
            if v3:
                return self.raw("GetNumberOfContinuousStates", ctypes.byref(ctypes.c_size_t()))
            value = D()
            return self.raw("GetRealStatus", args[0], ctypes.byref(value))
        if name == "null_call":
            return self._null_call(args[0])
        raise ValueError(f"unknown call {name!r}")

    def _deserialize(self, data: bytes, slot: int) -> int:
        buf = (self.byte * max(1, len(data))).from_buffer_copy(data if data else b"\x00")
        name = "DeserializeFMUState" if self.v3 else "DeSerializeFMUstate"
        return self.raw(name, buf, len(data), ctypes.byref(self.states[slot]))

    def _new_discrete_states(self, ok: bool) -> int:
        if self.v3:
            b = [ctypes.c_bool() for _ in range(5)]
            return self.raw("UpdateDiscreteStates", *(ctypes.byref(x) for x in b), ctypes.byref(ctypes.c_double()))
        from fmpy.fmi2 import fmi2EventInfo

        info = fmi2EventInfo()
        return self.raw("NewDiscreteStates", ctypes.byref(info) if ok else None)

    def _null_call(self, which: str) -> int:
        v3, n = self.v3, self.nx
        if which == "get_real":
            return self.raw("GetFloat64", None, 1, None, 1) if v3 else self.raw("GetReal", None, 1, None)
        if which == "set_real":
            return self.raw("SetFloat64", None, 2, None, 2) if v3 else self.raw("SetReal", None, 2, None)
        if which == "get_int":
            return self.raw("GetInt32", None, 1, None, 1) if v3 else self.raw("GetInteger", None, 1, None)
        if which == "get_state":
            return self.raw("GetFMUState" if v3 else "GetFMUstate", None)
        if which == "set_state":
            return self.raw("SetFMUState" if v3 else "SetFMUstate", None)
        if which == "free_state":
            return self.raw("FreeFMUState" if v3 else "FreeFMUstate", None)
        if which == "deserialize":
            return self.raw("DeserializeFMUState" if v3 else "DeSerializeFMUstate", None, 100, None)
        if which == "serialize":
            return self.raw("SerializeFMUState" if v3 else "SerializeFMUstate", None, None, 0)
        if which == "size":
            return self.raw("SerializedFMUStateSize" if v3 else "SerializedFMUstateSize", None, None)
        if which == "do_step_outputs":
            if v3:
                return self.raw("DoStep", self._time("now"), 0.01, 1, None, None, None, None)
            return self.raw("DoStep", self._time("now"), 0.01, 1)
        if which == "set_states":
            return self.raw("SetContinuousStates", None, n)
        if which == "derivatives":
            return self.raw("GetContinuousStateDerivatives" if v3 else "GetDerivatives", None, n)
        if which == "directional":
            if v3:
                return self.raw("GetDirectionalDerivative", None, 1, None, 1, None, 1, None, 1)
            return self.raw("GetDirectionalDerivative", None, 1, None, 1, None, None)
        if which == "event_info":
            return (
                self._new_discrete_states(ok=False)
                if not v3
                else self.raw("UpdateDiscreteStates", None, None, None, None, None, None)
            )
        if which == "completed":
            return self.raw("CompletedIntegratorStep", 1, None, None)
        if which == "debug_logging":
            return self.raw("SetDebugLogging", 1, 2, None)
        if which == "status":
            if v3:
                return self.raw("GetNumberOfEventIndicators", None)
            return self.raw("GetRealStatus", 2, None)
        raise ValueError(which)


# --------------------------------------------------------------------------------------- worker / campaign
def worker(spec: dict) -> None:
    """Run the sequences of one batch; print ``SEQ seed`` before each and a JSON summary at the end."""
    runner = Runner(spec["unzipdir"], spec["kind"], spec["version"], spec["interface"])
    stats = Stats()
    violations = []
    for seed in spec["seeds"]:
        print(f"SEQ {seed}", flush=True)
        calls = generate(seed, spec["kind"], spec["version"], spec["interface"], spec["length"])
        try:
            runner.run(calls, stats)
        except PropertyViolationError as exc:
            violations.append({"seed": seed, "message": str(exc)})
            stats.sequences += 1
    out = {
        "sequences": stats.sequences,
        "calls": stats.calls,
        "statuses": dict(stats.statuses),
        "error_state_entries": stats.error_state_entries,
        "restarts_from_error": stats.restarts_from_error,
        "violations": violations,
    }
    print("RESULT " + json.dumps(out), flush=True)


@dataclass
class Finding:
    kind: str  # "crash", "hang", "violation", "worker"
    config: tuple
    seed: int | None
    message: str
    calls: list = field(default_factory=list)

    def report(self) -> str:
        kind, version, interface = self.config
        head = f"{self.kind.upper()} {kind} FMI {version} {interface} seed={self.seed}: {self.message}"
        repro = (
            f"  reproduce: PYTHONPATH=. python benchmarks/fuzz_fmi.py --replay {self.seed} --kind {kind} "
            f"--version {version} --interface {interface}"
        )
        seq = "\n".join(f"    {k}: {c!r}" for k, c in enumerate(self.calls))
        return f"{head}\n{repro}\n  call sequence:\n{seq}" if self.calls else f"{head}\n{repro}"


@dataclass
class Summary:
    sequences: int = 0
    calls: int = 0
    crashes: int = 0
    hangs: int = 0
    violations: int = 0
    statuses: Counter = field(default_factory=Counter)
    error_state_entries: int = 0
    restarts_from_error: int = 0
    findings: list = field(default_factory=list)
    wall_time: float = 0.0

    def table(self) -> str:
        lines = [
            f"sequences {self.sequences}, calls {self.calls}, crashes {self.crashes}, hangs {self.hangs}, "
            f"property violations {self.violations}, wall time {self.wall_time:.1f} s",
            "statuses seen: " + ", ".join(f"{k} {v}" for k, v in sorted(self.statuses.items())),
            f"entered the Error state {self.error_state_entries} times, restarted from a stored state / reset "
            f"{self.restarts_from_error} times",
        ]
        return "\n".join(lines)


def _run_batch(spec: dict, timeout: float) -> tuple[dict | None, Finding | None]:
    cmd = [sys.executable, __file__, "--worker", json.dumps(spec)]
    env = dict(os.environ, PYTHONFAULTHANDLER="1")
    config = (spec["kind"], spec["version"], spec["interface"])
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env, check=False)
        stdout, rc, stderr = proc.stdout, proc.returncode, proc.stderr
    except subprocess.TimeoutExpired as exc:
        out = exc.stdout.decode() if isinstance(exc.stdout, bytes) else (exc.stdout or "")
        seed = _last_seed(out)
        calls = generate(seed, *config, spec["length"]) if seed is not None else []
        return None, Finding("hang", config, seed, f"batch did not finish within {timeout:.0f} s", calls)
    result = next((line[7:] for line in stdout.splitlines() if line.startswith("RESULT ")), None)
    if rc != 0 or result is None:
        seed = _last_seed(stdout)
        calls = generate(seed, *config, spec["length"]) if seed is not None else []
        what = f"signal {-rc}" if rc < 0 else f"exit status {rc}"
        return None, Finding("crash" if rc < 0 else "worker", config, seed, f"{what}; stderr tail: {stderr[-800:]}", calls)
    return json.loads(result), None


def _last_seed(out: str) -> int | None:
    seeds = [int(line.split()[1]) for line in out.splitlines() if line.startswith("SEQ ")]
    return seeds[-1] if seeds else None


def run_campaign(
    unzipdirs: dict,
    sequences: int,
    *,
    length: int = 60,
    seed: int = 0,
    batch: int = 50,
    jobs: int = 2,
    timeout: float = 120.0,
    configs: list | None = None,
) -> Summary:
    """Fuzz ``sequences`` sequences spread over the configurations, ``batch`` per subprocess, ``jobs`` at a time.

    ``unzipdirs`` maps ``(kind, version)`` to an extracted FMU directory.
    """
    configs = configs or CONFIGS
    specs = []
    per = max(1, sequences // len(configs))
    for c, (kind, version, interface) in enumerate(configs):
        seeds = [seed + c * 1_000_000 + i for i in range(per)]
        for i in range(0, per, batch):
            specs.append(
                {
                    "unzipdir": str(unzipdirs[(kind, version)]),
                    "kind": kind,
                    "version": version,
                    "interface": interface,
                    "seeds": seeds[i : i + batch],
                    "length": length,
                }
            )
    summary = Summary()
    start = time.perf_counter()
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for result, finding in pool.map(lambda s: _run_batch(s, timeout), specs):
            if finding is not None:
                summary.findings.append(finding)
                summary.crashes += finding.kind in ("crash", "worker")
                summary.hangs += finding.kind == "hang"
                continue
            summary.sequences += result["sequences"]
            summary.calls += result["calls"]
            summary.statuses.update(result["statuses"])
            summary.error_state_entries += result["error_state_entries"]
            summary.restarts_from_error += result["restarts_from_error"]
            for v in result["violations"]:
                summary.violations += 1
                cfg = (s := next(x for x in specs if v["seed"] in x["seeds"]))["kind"], s["version"], s["interface"]
                summary.findings.append(Finding("violation", cfg, v["seed"], v["message"], generate(v["seed"], *cfg, length)))
    summary.wall_time = time.perf_counter() - start
    return summary


def build_fmus(directory: Path) -> dict:
    """Export (if missing) and extract the four FMUs; return ``{(kind, version): unzipdir}``."""
    from fmpy import extract

    import pendulab as pl
    from pendulab.fmu import export

    out = {}
    for kind in ("rigid", "elastic"):
        for version in (2, 3):
            path = directory / f"{kind}{version}.fmu"
            if not path.exists():
                export(pl.make_model(kind), path, version, timestamp=False)
            out[(kind, version)] = extract(str(path), str(directory / f"unzipped_{kind}{version}"))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sequences", type=int, default=400, help="number of call sequences (spread over 8 configurations)")
    ap.add_argument("--length", type=int, default=60, help="calls per sequence")
    ap.add_argument("--seed", type=int, default=0, help="first seed")
    ap.add_argument("--jobs", type=int, default=2, help="parallel subprocesses")
    ap.add_argument("--batch", type=int, default=50, help="sequences per subprocess")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per batch before it counts as a hang")
    ap.add_argument("--fmu-dir", type=Path, help="folder for the exported FMUs (default: a temporary folder)")
    ap.add_argument("--replay", type=int, help="run one sequence in this process and print every call")
    ap.add_argument("--kind", default="rigid")
    ap.add_argument("--version", type=int, default=2)
    ap.add_argument("--interface", default="CS")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        worker(json.loads(args.worker))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.fmu_dir or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        dirs = build_fmus(folder)
        if args.replay is not None:
            runner = Runner(dirs[(args.kind, args.version)], args.kind, args.version, args.interface)
            trace: list[str] = []
            calls = generate(args.replay, args.kind, args.version, args.interface, args.length)
            try:
                runner.run(calls, Stats(), trace)
                print("\n".join(trace) + "\nno violation")
                return 0
            except PropertyViolationError as exc:
                print("\n".join(trace) + f"\nVIOLATION: {exc}")
                return 1
        summary = run_campaign(
            dirs, args.sequences, length=args.length, seed=args.seed, batch=args.batch, jobs=args.jobs, timeout=args.timeout
        )
    print(summary.table())
    for f in summary.findings:
        print(f.report())
    return 1 if summary.findings else 0


if __name__ == "__main__":
    if str(Path(__file__).resolve().parents[1]) not in sys.path:
        sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    sys.exit(main())

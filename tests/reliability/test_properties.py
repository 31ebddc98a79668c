"""Property-based fuzzing (hypothesis) of the public API: constructors, simulate, analysis, scenes.

Every property has the same shape: a generated call either returns a result
that passes physical checks (finite states, documented shapes, energy
conserved to a tolerance-dependent bound when nothing drives or damps the
pendulum) or raises an exception of a documented type (``ValueError``,
``TypeError``, ``KeyError``, ``FileNotFoundError``, ``pendulab.SimulationError``,
``ImportError`` for a missing extra) with a non-empty one-line message. Any
other exception type, an accepted invalid input, a rejected valid input or a
run that exceeds its wall-clock limit fails the property.

Horizons are at most 1 s and output grids at most a few hundred points, so each
example runs in milliseconds; the whole file runs in well under 40 s with
``pytest -n 2``. Long mode multiplies the example counts by ``LONG_FACTOR``:
``pytest tests/reliability --fuzz-long`` (when the option exists) or
``PENDULAB_FUZZ_LONG=1 pytest tests/reliability``.
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import threading
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, note, settings
from hypothesis import strategies as st

import pendulab as pl
from pendulab._checks import BUDGETS
from pendulab._inputs import INPUTS, MAGNITUDE
from pendulab.scene import load_scene

# --------------------------------------------------------------------------- settings

#: Example-count multiplier of the long mode.
LONG_FACTOR = 25
#: No Hypothesis deadline: a per-example time limit is a timed assertion, and the suite must pass on a loaded
#: 2-core host. Speed lives in benchmarks/; here only a hang (HANG_LIMIT_S) fails an example.
DEADLINE_MS = None
#: Wall-clock limit of one example [s], a hang guard only: examples take ~0.01-0.5 s on an idle machine, and a
#: 60 s ceiling leaves a 100x margin for a loaded CI host while still catching a run that never ends.
HANG_LIMIT_S = 60.0

#: Exception types the public API documents.
DOCUMENTED = (ValueError, TypeError, KeyError, FileNotFoundError, pl.SimulationError, ImportError)

#: One representative method per family (the compiled one needs a C compiler).
METHOD_CASES = [
    pytest.param("cvodes", id="casadi-bdf"),
    pytest.param("cvodes-adams", id="casadi-adams"),
    pytest.param("RK45", id="scipy"),
    pytest.param("rk4", id="fixed"),
    pytest.param("taylor", id="taylor"),
    pytest.param("compiled-dopri5", id="compiled", marks=pytest.mark.needs_cc),
]
FAMILY = {
    "cvodes": "casadi",
    "cvodes-adams": "casadi",
    "RK45": "scipy",
    "rk4": "fixed",
    "taylor": "taylor",
    "compiled-dopri5": "compiled",
}


def _long_mode(request: pytest.FixtureRequest) -> bool:
    if os.environ.get("PENDULAB_FUZZ_LONG") == "1":
        return True
    try:
        return bool(request.config.getoption("--fuzz-long", default=False))
    except ValueError:  # option not registered
        return False


#: Wall-clock limit in force (raised for the Taylor method by run_property).
_LIMITS = {"hang": HANG_LIMIT_S}
#: The Taylor method compiles one integrator per tolerance and structural-zero pattern: ~0.1 s with a warm heyoka
#: JIT cache, several seconds (elastic) with a cold one (a fresh CI machine). Its examples get no deadline and this limit.
TAYLOR_HANG_LIMIT_S = 120.0


def run_property(request: pytest.FixtureRequest, test: Callable[[], None], examples: int, method: str | None = None) -> None:
    """Run a ``@given`` test with ``examples`` examples (times ``LONG_FACTOR`` in long mode)."""
    n = examples * LONG_FACTOR if _long_mode(request) else examples
    compiling = method is not None and FAMILY[method] == "taylor"
    _LIMITS["hang"] = TAYLOR_HANG_LIMIT_S if compiling else HANG_LIMIT_S
    try:
        settings(
            max_examples=n,
            deadline=DEADLINE_MS,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much, HealthCheck.data_too_large],
            print_blob=True,
            database=None,  # no .hypothesis example database written by this file
        )(test)()
    finally:
        _LIMITS["hang"] = HANG_LIMIT_S


class HangError(AssertionError):
    """An example exceeded its wall-clock limit."""


@contextlib.contextmanager
def time_limit(seconds: float | None = None) -> Iterator[None]:
    """Fail with HangError when the block runs longer than ``seconds`` (default: the limit in force; main thread, POSIX only)."""
    seconds = _LIMITS["hang"] if seconds is None else seconds
    if not hasattr(signal, "setitimer") or threading.current_thread() is not threading.main_thread():
        yield
        return

    def _alarm(signum: int, frame: Any) -> None:
        raise HangError(f"example exceeded the {seconds} s wall-clock limit (hang)")

    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


def outcome(call: Callable[[], Any]) -> tuple[Any, BaseException | None]:
    """Run ``call`` under the hang guard: ``(result, None)`` or ``(None, documented exception)``.

    An undocumented exception type, or a documented one with an empty or
    multi-line message, fails the property.
    """
    with time_limit():
        try:
            return call(), None
        except HangError:
            raise
        except DOCUMENTED as exc:
            check_message(exc)
            return None, exc
        except Exception as exc:
            raise AssertionError(f"undocumented exception type {type(exc).__module__}.{type(exc).__qualname__}: {exc}") from exc


def check_message(exc: BaseException) -> None:
    message = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
    message = str(message)
    assert message.strip(), f"{type(exc).__name__} with an empty message"
    assert "\n" not in message.strip(), f"{type(exc).__name__} message is not one line: {message!r}"


# --------------------------------------------------------------------------- strategies

NAN, INF = float("nan"), float("inf")
SPECIAL = [0.0, -0.0, 1.0, -1.0, NAN, INF, -INF, 5e-324, 1e-300, -1e-300, 1e-12, 1e300, 1.7976931348623157e308]
special_floats = st.sampled_from(SPECIAL)
any_float = st.one_of(special_floats, st.floats(allow_nan=True, allow_infinity=True))
#: Values of the wrong type for a number (a bool is not a number here).
wrong_type = st.one_of(
    st.text(max_size=4),
    st.none(),
    st.booleans(),
    st.lists(st.floats(-2, 2), min_size=0, max_size=3),
    st.complex_numbers(max_magnitude=10, allow_nan=False),
    st.just(np.array([1.0])),
    st.just(np.array(1.0)),
    st.builds(object),
    st.just({"value": 1.0}),
)
#: Numeric values that are real numbers of an accepted type.
numeric = st.one_of(
    any_float,
    st.integers(-(10**6), 10**6),
    st.floats(1e-3, 1e3).map(np.float64),
    st.floats(0.0625, 1024.0, width=32).map(np.float32),
    st.integers(1, 100).map(np.int64),
)
param_value = st.one_of(numeric, wrong_type)


def is_real(v: Any) -> bool:
    return not isinstance(v, bool) and isinstance(v, (int, float, np.floating, np.integer))


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


# --------------------------------------------------------------------------- models and parameters

PARAM_NAMES = {"rigid": pl.RigidParams.names(), "elastic": pl.ElasticParams.names()}
POSITIVE = {kind: {info.name: info.positive for info in pl.make_model(kind).param_info} for kind in ("rigid", "elastic")}
OPTIONAL = {kind: {info.name for info in pl.make_model(kind).param_info if info.optional} for kind in ("rigid", "elastic")}


def param_ok(kind: str, name: str, value: Any) -> bool:
    """Documented admissible value: a finite real number, > 0 or >= 0 by parameter (None where optional), and
    zero or of a magnitude within pendulab._inputs.MAGNITUDE (its square and inverse stay finite and non-zero)."""
    if value is None:
        return name in OPTIONAL[kind]
    if not is_real(value):
        return False
    v = float(value)
    in_magnitude = v == 0.0 or MAGNITUDE[0] <= abs(v) <= MAGNITUDE[1]
    return math.isfinite(v) and in_magnitude and (v > 0.0 if POSITIVE[kind][name] else v >= 0.0)


def nonneg(hi: float) -> st.SearchStrategy[float]:
    """Floats in [0, hi] that are zero or of an admissible magnitude (hypothesis also draws 1e-300)."""
    return st.floats(0.0, hi).filter(lambda v: v == 0.0 or v >= MAGNITUDE[0])


def cross_field_ok(kind: str, values: dict[str, Any]) -> bool:
    """Rules across fields, given admissible single values: rigid link 2 needs inertia about the elbow.

    ``m2 lc2^2 + I2 = 0`` makes the mass matrix singular (ValueError), evaluated in floating point as
    the package does (so ``lc2 = 1e-300`` underflows to a rejected zero).
    """
    if kind != "rigid":
        return True
    d = {**pl.RigidParams().resolved(), **{k: float(v) for k, v in values.items() if v is not None}}
    lc2 = d["L2"] if values.get("lc2") is None else d["lc2"]
    return d["m2"] * lc2 * lc2 + d["I2"] != 0.0  # as the package evaluates it (a huge lc2 gives inf, not OverflowError)


@st.composite
def param_sets(draw: st.DrawFn) -> tuple[str, dict[str, Any]]:
    kind = draw(st.sampled_from(["rigid", "elastic"]))
    names = list(PARAM_NAMES[kind]) + ["bogus", "k3", "M1", "l1"] + list(PARAM_NAMES["elastic" if kind == "rigid" else "rigid"])
    keys = draw(st.lists(st.sampled_from(names), max_size=4, unique=True))
    values = {}
    for k in keys:
        values[k] = draw(st.one_of(param_value, st.floats(1e-3, 1e3), st.none()))
    return kind, values


def test_constructors_accept_exactly_the_admissible_parameters(request):
    """rigid/elastic/make_model: accepted iff every value is admissible; accepted models are finite and at rest."""

    @given(param_sets())
    def prop(case):
        kind, values = case
        ctor = pl.rigid if kind == "rigid" else pl.elastic
        model, exc = outcome(lambda: ctor(**values))
        unknown = set(values) - set(PARAM_NAMES[kind])
        bad = {k for k, v in values.items() if k in PARAM_NAMES[kind] and not param_ok(kind, k, v)}
        note(f"unknown={unknown} bad={bad}")
        if unknown or bad:
            assert exc is not None, f"{kind}(**{values!r}) accepted invalid parameters {sorted(unknown | bad)}"
            assert isinstance(exc, (ValueError, TypeError)), exc
            named = unknown | bad
            assert any(repr(k) in str(exc) or k in str(exc) for k in named), f"message {exc} names none of {named}"
            return
        if not cross_field_ok(kind, values):
            assert isinstance(exc, ValueError), f"{kind}(**{values!r}) accepted a singular mass matrix"
            return
        assert exc is None, f"{kind}(**{values!r}) rejected admissible parameters: {exc!r}"
        assert isinstance(model, pl.Model) and model.kind == kind
        p = model.p
        assert p.shape == (len(PARAM_NAMES[kind]),) and np.all(np.isfinite(p))
        for k, v in values.items():
            if v is not None:
                assert model.params.resolved()[k] == float(v)
        # same model from make_model and from with_params
        assert np.array_equal(pl.make_model(kind, **values).p, p)
        # physically moderate parameters: the rest state is a finite equilibrium
        if all(v is None or 1e-3 <= abs(float(v)) <= 1e3 for v in values.values()):
            x = model.rest_state()
            assert x.shape == (model.nx,) and np.all(np.isfinite(x))
            f = model.rhs(x)
            assert np.all(np.isfinite(f))
            assert np.max(np.abs(f)) <= 1e-8 * (1.0 + model.params.g) * max(1.0, float(np.max(np.abs(p))))

    run_property(request, prop, 150)


def test_make_model_and_with_params_reject_bad_names_and_kinds(request):
    @given(
        kind=st.one_of(st.sampled_from(["rigid", "elastic"]), st.text(max_size=8), st.none(), st.integers()),
        change=st.dictionaries(st.sampled_from(["m1", "k1", "lc1", "g", "zz"]), param_value, max_size=2),
    )
    def prop(kind, change):
        model, exc = outcome(lambda: pl.make_model(kind))
        if kind not in ("rigid", "elastic"):
            assert isinstance(exc, (ValueError, TypeError)), f"make_model({kind!r}) gave {model!r}"
            return
        assert exc is None
        changed, exc = outcome(lambda: model.with_params(**change))
        ok = all(k in PARAM_NAMES[kind] and param_ok(kind, k, v) for k, v in change.items())
        if ok:
            assert exc is None, f"with_params(**{change!r}) rejected: {exc!r}"
            assert np.all(np.isfinite(changed.p))
        else:
            assert exc is not None, f"{kind}.with_params(**{change!r}) accepted invalid values"

    run_property(request, prop, 80)


def test_constructors_reject_positional_arguments():
    for ctor in (pl.rigid, pl.elastic):
        with pytest.raises(TypeError):
            ctor(1.0)


# --------------------------------------------------------------------------- simulate


@pytest.fixture(scope="module")
def warm() -> dict[str, bool]:
    """Run every family once per model kind outside the hypothesis deadline (JIT compile, C build)."""
    done: dict[str, bool] = {}
    return done


def _warm_up(done: dict[str, bool], method: str) -> None:
    if done.get(method):
        return
    for model in (pl.rigid(), pl.elastic()):
        x0 = model.rest_state().copy()
        x0[0] = 0.1
        pl.simulate(model, x0, 0.05, 0.01, method)
    done[method] = True


def energy_scale(model: pl.Model, x0: np.ndarray) -> float:
    """Size of the energies in play [J]: kinetic + largest gravity swing + spring energy at t = 0."""
    r = model.params.resolved()
    gravity = (r["m1"] + r["m2"]) * r["g"] * (r["L1"] + r["L2"]) * 2.0
    spring = float(model.spring_energy(x0)) if model.kind == "elastic" else 0.0
    return 1.0 + abs(float(model.kinetic_energy(x0))) + gravity + abs(spring)


#: Sampling step of the reference path whose rates size the energy bounds [s]: finer than any whip in the drawn models.
RATE_PATH_STEP = 1e-3


def fastest_rate(model: pl.Model, x0: np.ndarray, t_final: float) -> float:
    """Fastest rate in play [1/s]: largest eigenvalue modulus of the Jacobian at x0 plus the run's largest angular rate.

    The rates are read off a reference path sampled every :data:`RATE_PATH_STEP` (cvodes at 1e-10), never off the
    output grid the property drew: a pendulum gains speed during the run (link 1 massless at the pivot, released at
    rest: rate 0 at x0, ~3 rad/s later; CI's derandomized example drifted 2.2x beyond a bound taken at x0), and a
    whip peaks between coarse samples (long-mode fuzz: m2 = 3 kg on L1 = 3 m, no gravity, theta2 peaked at 33 rad/s
    at t = 0.67 s while the 0.125 s grid showed 7.4 rad/s; rk4 drifted 1.9e-3 J against a bound of 1.1e-3 J).
    """
    path = pl.simulate(model, x0, max(t_final, RATE_PATH_STEP), RATE_PATH_STEP, "cvodes", 1e-10, 1e-10).x
    rates = float(np.max(np.abs(path[:, model.nq : model.nq + 2])))
    return float(np.max(np.abs(np.linalg.eigvals(pl.linearize(model, x0).A)))) + rates


def energy_bound(method: str, rtol: float, atol: float, t_final: float, model: pl.Model, x0: np.ndarray) -> float:
    """Largest admissible energy drift [J] over the run.

    Both bounds grow with w t, w the fastest rate in play: a method's global
    error is its local error summed over the run, and the number of steps an
    adaptive method takes per unit time grows with w (a stiff spring of
    300 N/m, w ~ 25 1/s, drove cvodes to 3400 * tol over 1 s where a slow
    pendulum stays below 200 * tol; CI's derandomized examples found it).

    Adaptive methods: 1000 * max(rtol, atol) * scale * max(1, w t): the worst
    measured over 1,000 long-mode examples per method is 169 for cvodes, 30
    for cvodes-adams, 9 for RK45 and 2 for compiled-dopri5, so 1000 leaves a
    margin of 6 over cvodes. Fixed-step RK4 (default step h = 1e-3 s): its
    local energy error is O((w h)^5), so the bound is
    max(1e-8, 100 * t * w * (w h)^4) * scale.
    """
    scale = energy_scale(model, x0)
    t = max(t_final, 0.1)
    w = fastest_rate(model, x0, t_final)
    if FAMILY[method] == "fixed":
        h = 1e-3
        return max(1e-8, 100.0 * t * w * (w * h) ** 4) * scale
    return 1000.0 * max(rtol, atol) * scale * max(1.0, w * t)


@st.composite
def valid_states(draw: st.DrawFn, model: pl.Model, max_rate: float = 6.0, spread: float = 0.3) -> np.ndarray:
    """Admissible initial states: any angle (beyond 2 pi too), moderate rates, springs (1 +- spread) static length."""
    x0 = model.rest_state().copy()
    nq = model.nq
    x0[0:2] = draw(st.lists(st.floats(-50.0, 50.0), min_size=2, max_size=2))
    x0[nq : nq + 2] = draw(st.lists(st.floats(-max_rate, max_rate), min_size=2, max_size=2))
    if model.kind == "elastic":
        x0[2:4] *= np.array(draw(st.lists(st.floats(1.0 - spread, 1.0 + spread), min_size=2, max_size=2)))
        x0[6:8] = draw(st.lists(st.floats(-1.0, 1.0), min_size=2, max_size=2))
    return x0


@st.composite
def moderate_models(draw: st.DrawFn, damped: bool = False, k_min: float = 50.0) -> pl.Model:
    kind = draw(st.sampled_from(["rigid", "elastic"]))
    pos = st.floats(0.3, 3.0)
    params: dict[str, float] = {
        "m1": draw(pos),
        "m2": draw(pos),
        "L1": draw(pos),
        "L2": draw(pos),
        "g": draw(nonneg(20.0)),
    }
    if damped:
        params.update(b1=draw(nonneg(2.0)), b2=draw(nonneg(2.0)))
    if kind == "rigid":
        # lc beyond the link end and lc = 0 are admissible (see docs/reliability.md)
        params.update(
            lc1=draw(nonneg(4.0)),
            lc2=draw(nonneg(4.0)),
            I1=draw(nonneg(1.0)),
            I2=draw(nonneg(1.0)),
        )
        # lc1 = I1 = 0 (link 1's mass at the pivot) with a point-mass link 2 (I2 = 0), or lc2 = I2 = 0, gives a
        # mass matrix that is singular at some configurations (theta1 = theta2): admissible, but not a
        # model to integrate through the singularity; keep the generated models regular
        if params["lc1"] < 0.05 and params["I1"] < 0.05:
            params["I1"] = 0.1
        if params["lc2"] < 0.05 and params["I2"] < 0.05:
            params["I2"] = 0.1
        if params["I2"] < 0.05:
            params["I2"] = 0.05
    else:
        params.update(k1=draw(st.floats(k_min, 2000.0)), k2=draw(st.floats(k_min, 2000.0)))
        if damped:
            params.update(c1=draw(nonneg(5.0)), c2=draw(nonneg(5.0)))
    return pl.make_model(kind, **params)


def tolerance(method: str, lo: float, hi: float) -> st.SearchStrategy[float]:
    """Tolerances in [lo, hi]: log-uniform, or a few fixed values for the Taylor method.

    heyoka compiles one integrator per (model structure, tolerance) pair, about
    0.1 s each: random tolerances would make every Taylor example a compilation.
    """
    if FAMILY[method] == "taylor":
        return st.sampled_from([v for v in (1e-10, 1e-8, 1e-6, 1e-4, 1e-3) if lo <= v <= hi])
    return log_uniform(lo, hi)


def examples(method: str, n: int) -> int:
    """Fewer examples for the Taylor method (each new structural-zero pattern of the parameters compiles)."""
    return max(10, n // 3) if FAMILY[method] == "taylor" else n


def check_trajectory(tr: Any, model: pl.Model, x0: np.ndarray, t_final: float, dt: float) -> None:
    """Documented shapes, grid and finiteness of a successful run."""
    n = max(1, math.ceil(t_final / dt - 1e-9)) + 1
    assert isinstance(tr, pl.Trajectory)
    assert tr.t.shape == (n,), (tr.t.shape, n)
    assert tr.t[0] == 0.0 and math.isclose(tr.t[-1], t_final, rel_tol=1e-12)
    assert np.all(np.diff(tr.t) > 0)
    assert tr.x.shape == (n, model.nx)
    assert tr.u.shape == (n, model.nu)
    assert tr.y.shape == (n, model.ny)
    assert np.all(np.isfinite(tr.x)) and np.all(np.isfinite(tr.u)) and np.all(np.isfinite(tr.y))
    assert np.allclose(tr.x[0], x0, rtol=1e-12, atol=1e-12)
    assert tr.success is True
    assert tr.state_names == model.state_names
    if model.kind == "elastic":
        # the polar coordinates (theta, r) describe the spring only while r > 0; a run that crosses
        # r = 0 must end in SimulationError, not return spring lengths <= 0
        assert np.all(tr.x[:, 2:4] > 0.0), f"spring length reached {float(np.min(tr.x[:, 2:4])):.3g} m without an error"


@pytest.mark.parametrize("method", METHOD_CASES)
def test_simulate_undamped_unforced_conserves_energy(request, warm, method):
    """Valid runs with nothing driving or damping the pendulum succeed and conserve energy."""
    _warm_up(warm, method)
    min_tol = 1e-8 if FAMILY[method] == "scipy" else 1e-10  # RK45 in Python at 1e-10 takes seconds: skipped

    @given(data=st.data())
    def prop(data):
        # springs stiff enough, rates moderate: no spring is compressed through r = 0 (a singularity)
        model = data.draw(moderate_models(damped=False, k_min=300.0), label="model")
        assume(model.kind == "rigid" or min(model.params.L1, model.params.L2) >= 0.5 * max(model.params.L1, model.params.L2))
        # small spring perturbations: a compressed spring 1 swinging through more than L2 drives r2 through 0
        x0 = data.draw(valid_states(model, max_rate=3.0, spread=0.05), label="x0")
        t_final = data.draw(st.floats(0.01, 1.0), label="t_final")
        dt = data.draw(st.floats(t_final / 100, max(t_final / 100, 0.2)), label="dt")
        rtol = data.draw(tolerance(method, min_tol, 1e-4), label="rtol")
        atol = data.draw(tolerance(method, min_tol, 1e-4), label="atol")
        u = data.draw(st.sampled_from([None, np.zeros(2), "zeros-callable"]), label="u")
        if isinstance(u, str):
            u = lambda t, x: [0.0, 0.0]  # noqa: E731
        note(f"pl.make_model({model.kind!r}, **{model.params.resolved()!r}); x0={x0.tolist()!r}")
        tr, exc = outcome(lambda: pl.simulate(model, x0, t_final, dt, method, rtol, atol, u))
        assert exc is None, f"valid run failed: {exc!r}"
        check_trajectory(tr, model, x0, t_final, dt)
        E = model.energy(tr.x)
        drift = float(np.max(np.abs(E - E[0])))
        bound = energy_bound(method, rtol, atol, t_final, model, x0)
        assert drift <= bound, f"energy drift {drift:.3g} J > bound {bound:.3g} J"

    run_property(request, prop, examples(method, 40), method)


def test_energy_bound_holds_for_a_stiff_spring_under_cvodes():
    """CI's derandomized example: springs of 300 N/m, no gravity, tol 1e-10; cvodes drifted 3.4e-7 J in 1 s.

    The old bound (2000 * tol * scale, blind to the rate) was 3.2e-7 J; the rate-aware bound must hold.
    """
    model = pl.make_model("elastic", m1=1.0, m2=1.0, L1=1.0, L2=2.0, g=0.0, k1=300.0, k2=300.0)
    x0 = np.array([0.0, 1.0, 1.0, 1.9375, 0.0, 0.0, 0.0, 0.0])
    tr = pl.simulate(model, x0, 1.0, 0.125, "cvodes", 1e-10, 1e-10)
    E = model.energy(tr.x)
    drift = float(np.max(np.abs(E - E[0])))
    assert drift > 2000.0 * 1e-10 * energy_scale(model, x0)  # the case the old, rate-blind bound refused
    assert drift <= energy_bound("cvodes", 1e-10, 1e-10, 1.0, model, x0)


def test_energy_bound_sees_a_whip_between_output_samples():
    """The long-mode fuzz's example: rk4 drifted 1.9e-3 J where the bound, sized on the 0.125 s output grid, was 1.1e-3 J.

    Link 1 carries no mass (lc1 = 0) and gravity is off: link 2 whips to 33 rad/s between two output samples.
    """
    model = pl.make_model("rigid", m1=1.0, m2=3.0, L1=3.0, L2=1.0, g=0.0, lc1=0.0, lc2=1.0, I1=0.1, I2=0.05)
    x0 = np.array([2.0, 0.0, 2.0, 0.0])
    tr = pl.simulate(model, x0, 1.0, 0.125, "rk4", 1e-4, 1e-4)
    E = model.energy(tr.x)
    drift = float(np.max(np.abs(E - E[0])))
    assert np.max(np.abs(tr.x[:, 2:])) < 10.0 < 30.0 < fastest_rate(model, x0, 1.0)  # the grid misses the whip
    assert 1e-3 < drift <= energy_bound("rk4", 1e-4, 1e-4, 1.0, model, x0)


@pytest.mark.parametrize("method", METHOD_CASES)
def test_simulate_damped_unforced_never_gains_energy(request, warm, method):
    _warm_up(warm, method)

    @given(data=st.data())
    def prop(data):
        model = data.draw(moderate_models(damped=True, k_min=300.0), label="model")
        # small spring perturbations: a compressed spring 1 swinging through more than L2 drives r2 through 0
        x0 = data.draw(valid_states(model, max_rate=3.0, spread=0.05), label="x0")
        t_final = data.draw(st.floats(0.01, 1.0), label="t_final")
        rtol = data.draw(tolerance(method, 1e-8, 1e-5), label="rtol")
        note(f"pl.make_model({model.kind!r}, **{model.params.resolved()!r}); x0={x0.tolist()!r}")
        tr, exc = outcome(lambda: pl.simulate(model, x0, t_final, 0.05, method, rtol, rtol))
        assert exc is None, f"valid run failed: {exc!r}"
        check_trajectory(tr, model, x0, t_final, 0.05)
        E = model.energy(tr.x)
        bound = energy_bound(method, rtol, rtol, t_final, model, x0)
        assert float(np.max(E - E[0])) <= bound, "a damped, unforced pendulum gained energy"

    run_property(request, prop, examples(method, 25), method)


# ---- the mixed (valid and invalid) fuzz of every simulate argument

_AMBIGUOUS = object()  # inputs whose acceptance the docs leave open (e.g. t_final="0.5", True)


@st.composite
def scalar_arg(draw: st.DrawFn, valid: st.SearchStrategy[float]) -> tuple[Any, Any]:
    """(value, verdict) for a positive-number argument: verdict True (valid), False (invalid) or _AMBIGUOUS."""
    choice = draw(st.integers(0, 9))
    if choice < 6:
        return draw(valid), True
    if choice < 8:
        return draw(st.sampled_from([0.0, -0.0, -1.0, -1e-300, NAN, INF, -INF])), False
    v = draw(wrong_type)
    if (
        isinstance(v, bool)
        or (isinstance(v, str) and _float_or_none(v) is not None)
        or (isinstance(v, np.ndarray) and v.size == 1)
    ):
        return v, _AMBIGUOUS  # float() accepts these; the docs say "float"
    if isinstance(v, list) and len(v) == 0:
        return v, False
    return v, False


def _float_or_none(s: str) -> float | None:
    try:
        return float(s)
    except ValueError:
        return None


@st.composite
def x0_arg(draw: st.DrawFn, model: pl.Model) -> tuple[Any, bool]:
    choice = draw(st.integers(0, 9))
    if choice < 6:
        x0 = draw(valid_states(model))
        return (x0.tolist() if draw(st.booleans()) else x0), True
    nx = model.nx
    if choice == 6:
        n = draw(st.sampled_from([0, 1, nx - 1, nx + 1, 2 * nx, 4 if nx == 8 else 8]))
        return [0.1] * n, False
    if choice == 7:
        x0 = draw(valid_states(model))
        x0[draw(st.integers(0, nx - 1))] = draw(st.sampled_from([NAN, INF, -INF]))
        return x0, False
    if choice == 8 and model.kind == "elastic":
        x0 = draw(valid_states(model))
        x0[draw(st.sampled_from([2, 3]))] = draw(st.sampled_from([0.0, -0.0, -0.5, -1e300]))
        return x0, False
    return draw(
        st.one_of(st.none(), st.text(max_size=4), st.just(np.zeros((2, nx))), st.just({"theta1": 0.1}), st.builds(object))
    ), False


@st.composite
def u_arg(draw: st.DrawFn, n_points: int, t_last: float) -> tuple[Any, bool, str]:
    """(u, valid, description) for a run with ``n_points`` output times, the last feedback sample at ``t_last``."""
    choice = draw(st.integers(0, 11))
    finite = st.floats(-5.0, 5.0)
    if choice == 0:
        return None, True, "None"
    if choice == 1:
        return np.array(draw(st.lists(finite, min_size=2, max_size=2))), True, "constant"
    if choice == 2:
        rows = draw(st.sampled_from([n_points, n_points - 1]))
        return (
            draw(st.lists(st.lists(finite, min_size=2, max_size=2), min_size=rows, max_size=rows)),
            True,
            f"sampled {rows} rows",
        )
    if choice == 3:
        k = draw(st.floats(-3.0, 3.0))
        return (lambda t, x: [k * x[0], -k * x[1]]), True, "callable, linear feedback"
    if choice == 4:
        rows = draw(
            st.sampled_from([0, 1, n_points + 1, n_points + 7, max(n_points - 2, 0)]).filter(
                lambda r: r not in (n_points, n_points - 1, 1) or r == 0
            )
        )
        return np.zeros((rows, 2)), False, f"sampled {rows} rows (wrong)"
    if choice == 5:
        shape = draw(st.sampled_from([(1,), (3,), (n_points, 3), (n_points, 1), (n_points, 2, 1)]))
        return np.zeros(shape), False, f"shape {shape}"
    if choice == 6:
        v = np.zeros(2)
        v[draw(st.integers(0, 1))] = draw(st.sampled_from([NAN, INF, -INF]))
        return v, False, "constant non-finite"
    if choice == 7:
        return draw(st.one_of(st.floats(-1, 1), st.integers(-3, 3), st.text(max_size=3))), False, "scalar or string"
    if choice == 8:
        bad = draw(st.sampled_from([NAN, INF]))
        t_bad = draw(st.floats(0.0, 1.0)) * t_last  # the feedback is sampled at t = 0, dt, ..., t_last
        return (lambda t, x: [0.0, bad if t >= t_bad else 0.0]), False, f"callable non-finite from t={t_bad}"
    if choice == 9:
        ret = draw(st.sampled_from([[1.0], [1.0, 2.0, 3.0], None, "ab", [[1.0, 2.0]] * 2, {"a": 1.0}, float("nan")]))
        return (lambda t, x: ret), False, f"callable returning {ret!r}"
    if choice == 10:
        return [[1.0, 2.0], [3.0]], False, "ragged list"
    return (lambda t, x: np.array([1e300, -1e300])), _AMBIGUOUS, "callable returning huge finite torques"


@pytest.mark.parametrize("method", METHOD_CASES)
def test_simulate_fuzz(request, warm, method):
    """Every argument of simulate, valid or not: a checked trajectory or a documented one-line error."""
    _warm_up(warm, method)
    min_tol = 1e-8 if FAMILY[method] == "scipy" else 1e-10

    @given(data=st.data())
    def prop(data):
        kind = data.draw(st.sampled_from(["rigid", "elastic"]), label="kind")
        model = pl.rigid() if kind == "rigid" else pl.elastic()
        x0, x_ok = data.draw(x0_arg(model), label="x0")
        t_final, t_ok = data.draw(scalar_arg(st.floats(0.01, 1.0)), label="t_final")
        tf = float(t_final) if t_ok is True else 0.5
        dt, dt_ok = data.draw(scalar_arg(st.floats(tf / 100, 1.0)), label="dt")
        rtol, r_ok = data.draw(scalar_arg(tolerance(method, min_tol, 1e-3)), label="rtol")
        atol, a_ok = data.draw(scalar_arg(tolerance(method, min_tol, 1e-3)), label="atol")
        max_step, m_ok = data.draw(
            st.one_of(st.just((None, True)), scalar_arg(st.floats(2e-3 if FAMILY[method] == "fixed" else 1e-3, 0.2))),
            label="max_step",
        )
        if max_step is None:
            m_ok = True  # None is max_step's documented default (scalar_arg's wrong types include None)
        verdicts = [x_ok, t_ok, dt_ok, r_ok, a_ok, m_ok]
        # keep the output grid small even for ambiguous values such as dt=True
        grid_ok = t_ok is True and dt_ok is True
        n_points = max(1, math.ceil(float(t_final) / float(dt) - 1e-9)) + 1 if grid_ok else 10
        t_last = float(t_final) * (n_points - 2) / (n_points - 1) if grid_ok else 0.0
        u, u_ok, u_desc = data.draw(u_arg(n_points, t_last), label="u")
        verdicts.append(u_ok)
        options = data.draw(st.sampled_from([None, {}, {"bogus_option": 1}]), label="options")
        opt_ok = not options
        verdicts.append(opt_ok)
        note(f"u: {u_desc}")
        if (t_ok is _AMBIGUOUS or dt_ok is _AMBIGUOUS) and not grid_ok:
            # e.g. t_final=True, dt="1e-9": a legitimately huge grid; not what this property is about
            try:
                if float(t_final) / float(dt) > 1000:
                    return
            except (TypeError, ValueError, ZeroDivisionError, OverflowError):
                pass
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            tr, exc = outcome(
                lambda: pl.simulate(model, x0, t_final, dt, method, rtol, atol, u, max_step=max_step, options=options)
            )
        valid = all(v is True for v in verdicts)
        invalid = False in verdicts
        if invalid:
            if exc is None and not opt_ok and FAMILY[method] == "scipy" and all(v is not False for v in verdicts[:-1]):
                # solve_ivp warns about unknown options instead of failing; accepted with a warning
                assert any("bogus_option" in str(w.message) for w in caught), "unknown option accepted without a warning"
            else:
                assert exc is not None, f"invalid input accepted (verdicts {verdicts})"
                assert isinstance(exc, (ValueError, TypeError)), (
                    f"bad input gave {type(exc).__name__}, not ValueError/TypeError: {exc}"
                )
            return
        if exc is not None:
            assert not valid or isinstance(exc, pl.SimulationError), f"valid input rejected: {exc!r}"
            return
        check_trajectory(tr, model, np.asarray(x0, dtype=float), float(t_final), float(dt))

    run_property(request, prop, examples(method, 60), method)


def test_simulate_rejects_unknown_methods(request):
    @given(method=st.one_of(st.text(max_size=12), st.none(), st.integers(), st.just(["rk4"]), st.just(b"rk4")))
    def prop(method):
        # names are case-insensitive (documented in MethodRegistry.resolve); "rk" is a deprecated alias
        known = isinstance(method, str) and method.lower() in {"auto", "rk", *(m.lower() for m in pl.METHODS)}
        tr, exc = outcome(lambda: pl.simulate(pl.rigid(), [0.1, 0.0, 0.0, 0.0], 0.05, 0.01, method))
        if known:
            return
        assert exc is not None and isinstance(exc, (ValueError, TypeError, KeyError)), f"method {method!r}: {tr!r} {exc!r}"

    run_property(request, prop, 60)


def test_simulate_rejects_non_models(request):
    @given(model=st.one_of(st.text(max_size=6), st.none(), st.integers(), st.builds(object), st.just(pl.RigidParams())))
    def prop(model):
        _, exc = outcome(lambda: pl.simulate(model, [0.1, 0.0, 0.0, 0.0], 0.05))
        assert isinstance(exc, TypeError), exc

    run_property(request, prop, 20)


# --------------------------------------------------------------------------- analysis

EQ_NAMES = ("down-down", "down-up", "up-down", "up-up")


@st.composite
def vector_arg(draw: st.DrawFn, n: int, valid: st.SearchStrategy[list[float]]) -> tuple[Any, bool]:
    choice = draw(st.integers(0, 6))
    if choice < 4:
        return draw(valid), True
    if choice == 4:
        v = list(draw(valid))
        v[draw(st.integers(0, n - 1))] = draw(st.sampled_from([NAN, INF, -INF]))
        return v, False
    if choice == 5:
        return [0.0] * draw(st.sampled_from([0, 1, n - 1, n + 1, 2 * n])), False
    return draw(st.one_of(st.none(), st.text(max_size=3), st.just(np.zeros((2, n))), st.builds(object))), False


def test_linearize_fuzz(request):
    """linearize: A, B, C, D of the documented shapes, finite, with the kinematic block dq/dt = v exact."""

    @given(data=st.data())
    def prop(data):
        model = data.draw(moderate_models(damped=data.draw(st.booleans())), label="model")
        nx, nq = model.nx, model.nq
        x, x_ok = data.draw(vector_arg(nx, valid_states(model).map(list)), label="x")
        u, u_ok = data.draw(
            st.one_of(st.just((None, True)), vector_arg(2, st.lists(st.floats(-20, 20), min_size=2, max_size=2))), label="u"
        )
        inputs = data.draw(st.sampled_from(["full", "pendubot", "acrobot", "both", "", None, 3]), label="inputs")
        in_ok = inputs in ("full", "pendubot", "acrobot")
        signals = list(model.state_names + model.output_names)
        outputs = data.draw(
            st.one_of(
                st.sampled_from(["states", "positions", "energy", "stretch", "outputs", "everything", None]),
                st.lists(st.sampled_from([*signals, "nope"]), min_size=0, max_size=4),
            ),
            label="outputs",
        )
        if isinstance(outputs, list):
            out_ok = bool(outputs) and all(o in signals for o in outputs) and len(set(outputs)) == len(outputs)
        else:
            out_ok = outputs in ("states", "positions", "energy", "outputs") or (outputs == "stretch" and model.kind == "elastic")
        u_ok = u_ok or u is None
        lin, exc = outcome(lambda: pl.linearize(model, x, u, inputs, outputs))
        ok = x_ok and u_ok and in_ok
        if not (ok and out_ok) and not (ok and isinstance(outputs, list) and not outputs):
            assert exc is not None, (
                f"invalid linearize input accepted: x_ok={x_ok} u_ok={u_ok} inputs={inputs!r} outputs={outputs!r}"
            )
            assert isinstance(exc, (ValueError, TypeError, KeyError)), exc
            return
        if exc is not None:
            assert ok and isinstance(outputs, list) and not outputs, f"valid linearize input rejected: {exc!r}"
            return
        m = 2 if inputs == "full" else 1
        ny = len(lin.output_names)
        assert lin.A.shape == (nx, nx) and lin.B.shape == (nx, m) and lin.C.shape == (ny, nx) and lin.D.shape == (ny, m)
        for mat in (lin.A, lin.B, lin.C, lin.D):
            assert np.all(np.isfinite(mat))
        assert np.array_equal(lin.A[:nq, :nq], np.zeros((nq, nq))) and np.array_equal(lin.A[:nq, nq:], np.eye(nq))
        assert np.all(lin.B[:nq] == 0.0)

    run_property(request, prop, 80)


def test_equilibrium_fuzz(request):
    """equilibrium: a state at rest with zero acceleration, or a documented one-line error."""

    @given(data=st.data())
    def prop(data):
        model = data.draw(moderate_models(damped=data.draw(st.booleans())), label="model")
        name = data.draw(
            st.one_of(st.sampled_from(EQ_NAMES), st.sampled_from(["up", "Down-Down", "", None, 2, "up_up"])), label="name"
        )
        u, u_ok = data.draw(
            st.one_of(st.just((None, True)), vector_arg(2, st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=2))), label="u"
        )
        note(f"pl.make_model({model.kind!r}, **{model.params.resolved()!r})")
        u_ok = u_ok or u is None
        eq, exc = outcome(lambda: pl.equilibrium(model, name, u))
        if name not in EQ_NAMES or not u_ok:
            assert exc is not None and isinstance(exc, (ValueError, TypeError)), f"invalid input accepted: name={name!r} u={u!r}"
            return
        if exc is not None:
            # documented: g = 0, a torque larger than gravity can hold, springs too soft
            assert isinstance(exc, ValueError), exc
            return
        assert eq.x.shape == (model.nx,) and np.all(np.isfinite(eq.x))
        assert np.all(eq.x[model.nq :] == 0.0)
        acc = model.rhs(eq.x, eq.u)
        scale = 1.0 + model.params.g + float(np.max(np.abs(eq.u)))
        assert np.max(np.abs(acc)) <= 1e-6 * scale, f"not at rest: rhs = {acc.tolist()}"
        if model.kind == "elastic":
            assert np.all(eq.x[2:4] > 0.0)
        assert eq.eigenvalues.shape == (model.nx,) and np.all(np.isfinite(eq.eigenvalues))

    run_property(request, prop, 60)


def test_analysis_rejects_non_models(request):
    """equilibria, equilibrium, linearize, modes given something that is not a Model: TypeError (known gap: AttributeError)."""

    @given(
        bad=st.one_of(st.text(max_size=6), st.none(), st.integers(), st.builds(object), st.just(pl.RigidParams())),
        which=st.sampled_from(["equilibria", "equilibrium", "linearize", "modes"]),
    )
    def prop(bad, which):
        calls = {
            "equilibria": lambda: pl.equilibria(bad),
            "equilibrium": lambda: pl.equilibrium(bad, "down-down"),
            "linearize": lambda: pl.linearize(bad, [0.0, 0.0, 0.0, 0.0]),
            "modes": lambda: pl.modes(bad),
        }
        _, exc = outcome(calls[which])
        assert isinstance(exc, TypeError), f"pl.{which}({bad!r}): {exc!r}"

    run_property(request, prop, 30)


def test_modes_at_a_non_equilibrium_state_is_rejected(request):
    """modes(at=state) where the state is not an equilibrium: ValueError (known gap: accepted silently)."""

    @given(data=st.data())
    def prop(data):
        model = data.draw(st.sampled_from([pl.rigid(), pl.elastic()]), label="model")
        x = data.draw(valid_states(model), label="x")
        acc = model.rhs(x)
        if np.max(np.abs(acc)) < 1e-3:
            return  # (close to) an equilibrium: modes are meaningful
        res, exc = outcome(lambda: pl.modes(model, at=x))
        assert isinstance(exc, ValueError), f"pl.modes(model, at={x.tolist()!r}) with rhs = {acc.tolist()} returned {res!r}"

    run_property(request, prop, 20)


def test_modes_at_equilibria(request):
    @given(model=moderate_models(damped=False), name=st.sampled_from(EQ_NAMES))
    def prop(model, name):
        eq, exc = outcome(lambda: pl.equilibrium(model, name))
        if exc is not None:
            return
        ms, exc = outcome(lambda: pl.modes(model, at=eq))
        assert exc is None, exc
        assert 1 <= len(ms) <= model.nx
        for mode in ms:
            assert math.isfinite(mode.omega_n) and mode.omega_n >= 0.0
            assert mode.kind in ("oscillatory", "unstable", "decaying", "neutral")
            assert np.all(np.isfinite(mode.shape))

    run_property(request, prop, 20)


# --------------------------------------------------------------------------- scenes

KNOWN_SECTIONS = ("scene", "model", "initial", "simulation", "outputs", "input")
#: Extra sections with a meaning elsewhere (swing-up tasks, FMU validation).
EXTRA_SECTIONS = ("task", "validation")


def toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(v)


def toml_text(tables: dict[str, dict[str, Any]]) -> str:
    lines = []
    for section, table in tables.items():
        lines.append(f"[{section}]")
        lines.extend(f"{k} = {toml_value(v)}" for k, v in table.items())
        lines.append("")
    return "\n".join(lines)


toml_scalar = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -1.0, 1e-300, 1e300]),
    st.integers(-5, 5),
    st.booleans(),
    st.text(alphabet="abcdefxyz_-0123456789 ", max_size=6),
    st.lists(st.floats(-2, 2), max_size=3),
)


def declared_ok(name: str, value: Any) -> bool:
    """The documented rule of a real input of pendulab._inputs.INPUTS, from its fields: a real number, finite,
    zero or of a magnitude within MAGNITUDE, inside [low, high] (ends excluded where declared open)."""
    spec = INPUTS[name]
    if not is_real(value) or not math.isfinite(value):
        return False
    v = float(value)
    if v != 0.0 and not MAGNITUDE[0] <= abs(v) <= MAGNITUDE[1]:
        return False
    above_low = spec.low is None or (v > spec.low if spec.open_low else v >= spec.low)
    below_high = spec.high is None or (v < spec.high if spec.open_high else v <= spec.high)
    return above_low and below_high


@st.composite
def scene_tables(draw: st.DrawFn) -> tuple[dict[str, dict[str, Any]], bool]:
    """A scene as TOML tables and whether every value is admissible."""
    kind = draw(st.sampled_from(["rigid", "elastic"]))
    ok = True
    tables: dict[str, dict[str, Any]] = {
        "scene": {"name": draw(st.text(alphabet="abc_", min_size=1, max_size=6))},
        "model": {"kind": kind},
    }
    params: dict[str, Any] = {}
    for name in draw(st.lists(st.sampled_from(PARAM_NAMES[kind]), max_size=3, unique=True)):
        if draw(st.booleans()):
            params[name] = draw(st.floats(0.5, 2.0))
        else:
            params[name] = draw(toml_scalar)
            ok = ok and is_real(params[name]) and param_ok(kind, name, float(params[name]))
    if params:
        tables["model.params"] = params
        if ok:
            ok = cross_field_ok(kind, params)
    initial: dict[str, Any] = {}
    for name in draw(st.lists(st.sampled_from(("theta1", "theta2", "omega1", "omega2")), max_size=3, unique=True)):
        # Either draw can fall outside the declaration (a float in [-10, 10] may be 3e-146, below the magnitude bound).
        initial[name] = draw(st.floats(-10, 10)) if draw(st.booleans()) else draw(toml_scalar)
        ok = ok and declared_ok("state", initial[name])
    if initial:
        tables["initial"] = initial
    sim: dict[str, Any] = {}
    t_final = draw(st.floats(0.05, 1.0))
    sim["t_final"] = t_final
    sim["dt"] = draw(st.floats(0.005, t_final))
    sim["method"] = draw(st.sampled_from(["auto", "rk4", "cvodes", "RK45"]))
    if draw(st.booleans()):
        key = draw(st.sampled_from(["t_final", "dt", "rtol", "atol", "method"]))
        sim[key] = draw(toml_scalar)
        if key == "method":
            ok = ok and sim[key] in ("auto", *pl.METHODS)
        else:
            ok = ok and declared_ok(key, sim[key])
            if key in ("t_final", "dt") and ok:
                # A valid horizon and step whose output grid fits the points budget (a larger one is a BudgetError,
                # which is a ValueError naming the file: the clean refusal the oracle expects of an invalid scene).
                budget = BUDGETS["output_points"]
                limit = int(os.environ.get(budget.env, budget.default))
                ok = sim["dt"] <= sim["t_final"] and sim["t_final"] / sim["dt"] + 1.0 <= limit
    tables["simulation"] = sim
    return tables, ok


@pytest.fixture
def scene_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("scenes")


def test_scene_fuzz_structured(request, scene_dir):
    """Generated TOML scenes: a validated Scene (finite x0, positive horizon) or a one-line ValueError."""
    counter = iter(range(10**9))

    @given(case=scene_tables())
    def prop(case):
        tables, ok = case
        path = scene_dir / f"s{next(counter)}.toml"
        text = toml_text(tables)
        path.write_text(text, encoding="utf-8")
        note(text)
        scene, exc = outcome(lambda: load_scene(path))
        if not ok:
            assert isinstance(exc, ValueError), f"invalid scene accepted: {scene!r}"
            assert str(path) in str(exc), "the message does not name the file"
            return
        assert exc is None, f"valid scene rejected: {exc!r}"
        assert np.all(np.isfinite(scene.x0)) and scene.x0.shape == (scene.model.nx,)
        assert 0 < scene.dt <= scene.t_final and scene.method in ("auto", *pl.METHODS)

    run_property(request, prop, 80)


def test_scene_fuzz_text(request, scene_dir):
    """Arbitrary text and bytes as a scene file: a Scene or a one-line ValueError (never a TOML or Unicode error)."""
    counter = iter(range(10**9))

    @given(
        content=st.one_of(
            st.text(max_size=200),
            st.binary(max_size=64),
            st.sampled_from(
                ["[model]\nkind = 'rigid'\n", "[model\n", "[model]\nkind = 'rigid'\n[model]\n", "\ufeff[model]\nkind='rigid'"]
            ),
        )
    )
    def prop(content):
        path = scene_dir / f"t{next(counter)}.toml"
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
        scene, exc = outcome(lambda: load_scene(path))
        if exc is not None:
            assert isinstance(exc, ValueError), exc
        else:
            assert np.all(np.isfinite(scene.x0))

    run_property(request, prop, 80)


def test_scene_misspelled_sections_are_rejected(request, scene_dir):
    """A one-character typo of a known section name is an error (known gap: silently kept in Scene.extra)."""
    counter = iter(range(10**9))

    @st.composite
    def typos(draw: st.DrawFn) -> str:
        section = draw(st.sampled_from(KNOWN_SECTIONS))
        i = draw(st.integers(0, len(section) - 1))
        op = draw(st.sampled_from(["drop", "swap", "double", "upper"]))
        if op == "drop":
            out = section[:i] + section[i + 1 :]
        elif op == "swap" and i + 1 < len(section):
            out = section[:i] + section[i + 1] + section[i] + section[i + 2 :]
        elif op == "upper":
            out = section[:i] + section[i].upper() + section[i + 1 :]
        else:
            out = section[:i] + section[i] + section[i:]
        return out

    @given(typo=typos().filter(lambda s: s not in KNOWN_SECTIONS + EXTRA_SECTIONS and s))
    def prop(typo):
        path = scene_dir / f"m{next(counter)}.toml"
        path.write_text(f"[model]\nkind = 'rigid'\n\n[{typo}]\nt_final = 1.0\n", encoding="utf-8")
        scene, exc = outcome(lambda: load_scene(path))
        assert isinstance(exc, ValueError), f"section [{typo}] accepted silently (extra = {dict(scene.extra) if scene else None})"
        assert typo in str(exc)

    run_property(request, prop, 20)


def test_scene_missing_files_and_names(request, scene_dir):
    @given(name=st.text(alphabet="abcxyz_/.", min_size=1, max_size=12))
    def prop(name):
        target = scene_dir / "missing" / name
        _, exc = outcome(lambda: load_scene(target))
        assert isinstance(exc, (FileNotFoundError, ValueError)), exc

    run_property(request, prop, 20)


# --------------------------------------------------------------------------- minimal reproducers found by the properties


def test_taylor_runs_a_model_with_structural_zeros():
    """Found by the energy property: heyoka rejects the Taylor system of this valid model."""
    tr, exc = outcome(lambda: pl.simulate(pl.rigid(g=0.0, lc2=0.0, I2=0.1), [0.1, 0.0, 0.0, 0.0], 0.01, 0.005, "taylor"))
    assert exc is None, f"valid run failed: {exc!r}"


def test_equilibrium_newton_failure_is_a_documented_one_line_error():
    """Found by the equilibrium property: Newton's failure surfaces as a multi-line RuntimeError."""
    model = pl.elastic(L1=3.0, g=1.0, k1=542.0, k2=50.0)
    eq, exc = outcome(lambda: pl.equilibrium(model, "up-down", u=[0.75, 0.0]))
    if exc is None:
        assert np.max(np.abs(model.rhs(eq.x, eq.u))) < 1e-6


def test_spring_compressed_through_zero_is_an_error():
    """Found by the damped-energy property: a soft spring is driven through r = 0; cvodes returns r2 < 0 silently."""
    model = pl.elastic(L1=2.0, L2=0.5, g=0.0, b2=1.0, k1=50.0, k2=50.0)
    x0 = [0.0, 9.0, 1.5, 0.375, 0.0, 0.0, 1.0, 0.0]
    tr, exc = outcome(lambda: pl.simulate(model, x0, 1.0, 0.05, "cvodes", 1e-8, 1e-8))
    if exc is None:
        check_trajectory(tr, model, np.asarray(x0), 1.0, 0.05)
    else:
        assert isinstance(exc, pl.SimulationError), exc


@pytest.mark.parametrize("u", [[1e300, -1e300], "callable"], ids=["constant", "callable"])
def test_huge_finite_torques_fail_fast(u):
    """Found by the simulate fuzz: RK45 under huge finite torques runs ~1e6 steps (89 s) before failing."""
    if u == "callable":
        u = lambda t, x: np.array([1e300, -1e300])  # noqa: E731
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        tr, exc = outcome(lambda: pl.simulate(pl.rigid(), [0.0, 0.0, 0.0, 0.0], 1.0, 1.0, "RK45", u=u))
    assert exc is None or isinstance(exc, (pl.SimulationError, ValueError)), exc

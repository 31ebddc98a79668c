"""Property-based tests of the surface added after the first reliability round: Gymnasium env, ensembles, control factories.

Same rules as test_properties.py (whose helpers this file reuses): every call either returns a correct
result or raises a documented exception type with a one-line message; acceptance is exactly the
documented admissible set; accepted calls are checked against an independent path.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, note
from hypothesis import strategies as st
from test_properties import SPECIAL, outcome, run_property

import pendulab as pl
from pendulab.integrate.taylor.availability import MIN_TOL

gym = pytest.importorskip("gymnasium")
pytest.importorskip("heyoka")

from pendulab.gym import DoublePendulumEnv  # noqa: E402

#: Numbers and None (numeric strings are left out: the package converts them with float(), a documented leniency).
NUMBER = st.one_of(st.sampled_from(SPECIAL), st.floats(-1e3, 1e3), st.none())


def _positive_ok(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0


def test_gym_env_accepts_exactly_the_admissible_settings(request):
    """dt, torque_limit > 0 finite; tol in (0, 1); reset_noise >= 0 finite: accepted iff all hold; accepted envs step."""

    @given(
        dt=st.one_of(st.sampled_from([0.01, 0.02, 0.005]), NUMBER),
        torque=st.one_of(st.just(5.0), NUMBER),
        tol=st.one_of(st.sampled_from([1e-10, 1e-6]), NUMBER),
        noise=st.one_of(st.just(0.05), NUMBER),
    )
    def prop(dt, torque, tol, noise):
        env, exc = outcome(lambda: DoublePendulumEnv("rigid", "pendubot", dt=dt, torque_limit=torque, tol=tol, reset_noise=noise))
        ok = (
            _positive_ok(dt)
            and dt <= 10.0  # the default 10 s episode: at least one step ...
            and 10.0 / dt <= 1e9 + 0.5  # ... and at most MAX_EPISODE_STEPS = 1e9 steps
            and _positive_ok(torque)
            and torque <= 1e4  # the u_max declaration: beyond it the reward's squared torque nears overflow
            and _positive_ok(tol)
            and MIN_TOL <= tol < 1.0  # heyoka (the default integrator) refuses tolerances below double epsilon
            and isinstance(noise, (int, float))
            and not isinstance(noise, bool)
            and math.isfinite(noise)
            and 0 <= noise <= 10.0  # the reset_noise declaration
            and all(v == 0 or 1e-100 <= abs(v) <= 1e100 for v in (dt, torque, tol, noise))  # magnitude bounds
        )
        note(f"ok={ok} exc={exc!r}")
        if not ok:
            assert isinstance(exc, (ValueError, TypeError)), f"accepted dt={dt!r} torque={torque!r} tol={tol!r} noise={noise!r}"
            return
        assert exc is None, f"rejected admissible settings: {exc!r}"
        if dt > 0.05 or noise > 0.5:
            return  # the first-order torque effect below holds for short steps from near rest only
        if torque * dt < 1e-10:
            # The torque changes omega1 by ~torque * dt / I: below this it nears the rounding of omega1 (6e-80 N.m
            # left it bit-identical); above it the difference is 1e7 ulp or more.
            return
        omega1 = {}
        for action in (1.0, -1.0):
            env.reset(seed=0)  # same seed: same (noisy) start for both actions
            obs, reward, _, _, _ = env.step(np.array([action], dtype=np.float32))
            assert np.all(np.isfinite(obs)) and math.isfinite(reward)
            omega1[action] = env.unwrapped.state[2]
        # From the same start, a positive shoulder torque leaves link 1 spinning faster in + than a negative one.
        assert omega1[1.0] > omega1[-1.0]

    run_property(request, prop, 40)


@st.composite
def elastic_starts(draw: st.DrawFn) -> tuple[np.ndarray, bool]:
    model = pl.elastic()
    x = model.state(theta1=draw(st.floats(-3, 3)), theta2=draw(st.floats(-3, 3)))
    bad = draw(st.sampled_from(["none", "r1", "r2", "nan", "shape"]))
    if bad in ("r1", "r2"):
        x[2 if bad == "r1" else 3] = draw(st.sampled_from([0.0, -0.0, -1.0, -1e-300, -math.inf]))
    elif bad == "nan":
        x[draw(st.integers(0, 7))] = math.nan
    elif bad == "shape":
        x = x[:-1]
    return x, bad == "none"


def test_gym_reset_state_is_checked_as_simulate_checks_it(request):
    """options['state']: accepted iff simulate would accept it as x0; the env then starts exactly there."""
    env = DoublePendulumEnv("elastic", "pendubot")

    @given(start=elastic_starts())
    def prop(start):
        x0, valid = start
        sim_ok = outcome(lambda: pl.elastic().check_start(x0))[1] is None
        assert sim_ok == valid
        result, exc = outcome(lambda: env.reset(seed=1, options={"state": x0}))
        if not valid:
            assert isinstance(exc, ValueError) and "options['state']" in str(exc), exc
            return
        assert exc is None, exc
        np.testing.assert_array_equal(env.unwrapped.state, x0)

    run_property(request, prop, 60)


@pytest.mark.parametrize("tol", [5e-324, 1e-100, 1e-17])
def test_gym_env_refuses_a_tolerance_below_double_epsilon(tol):
    """Found by the property above under CI's derandomized examples: tol = 5e-324 compiled an unbounded Taylor order
    (7 GB and minutes, uninterruptible); every heyoka integrator is now built from a key that refuses it."""
    with pytest.raises(ValueError, match=r"tol = .*: out of range; expected a finite number in \[2.22e-16, 1\)"):
        DoublePendulumEnv("rigid", "pendubot", tol=tol)

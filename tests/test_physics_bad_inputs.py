"""Bad input raises a clear exception that names the argument, the value and what was expected."""

import math

import numpy as np
import pytest

import pendulab as pl

NAN = float("nan")
RIGID_X0 = [0.1, 0.2, 0.0, 0.0]


def _sim(model=None, **kw):
    args = dict(x0=RIGID_X0, t_final=1.0)
    args.update(kw)
    return pl.simulate(model or pl.rigid(), args.pop("x0"), args.pop("t_final"), **args)


# (id, callable, exception type, substrings the message must contain)
CASES = [
    ("zero mass", lambda: pl.rigid(m1=0.0), ValueError, ["'m1'", "> 0", "0.0"]),
    ("negative mass", lambda: pl.elastic(m2=-1.0), ValueError, ["'m2'", "> 0", "-1.0"]),
    ("zero length", lambda: pl.rigid(L2=0.0), ValueError, ["'L2'", "> 0", "0.0"]),
    ("negative rest length", lambda: pl.elastic(L1=-0.5), ValueError, ["'L1'", "> 0", "-0.5"]),
    ("zero stiffness", lambda: pl.elastic(k1=0.0), ValueError, ["'k1'", "> 0", "0.0"]),
    ("negative stiffness", lambda: pl.elastic(k2=-10.0), ValueError, ["'k2'", "> 0", "-10.0"]),
    ("negative damper", lambda: pl.rigid(b1=-0.1), ValueError, ["'b1'", ">= 0", "-0.1"]),
    ("link 2 without inertia", lambda: pl.rigid(lc2=0.0), ValueError, ["link 2", "singular", "lc2 > 0 or I2 > 0"]),
    ("NaN parameter", lambda: pl.rigid(g=NAN), ValueError, ["'g'", "finite", "nan"]),
    ("inf parameter", lambda: pl.elastic(c1=math.inf), ValueError, ["'c1'", "finite", "inf"]),
    ("NaN via with_params", lambda: pl.rigid().with_params(I1=NAN), ValueError, ["'I1'", "finite", "nan"]),
    ("string parameter", lambda: pl.rigid(m1="1"), TypeError, ["'m1'", "real number", "'1'"]),
    ("unknown parameter", lambda: pl.rigid(k1=100.0), ValueError, ["'k1'", "unknown parameter", "m1"]),
    ("unknown parameter (with_params)", lambda: pl.elastic().with_params(lc1=0.5), ValueError, ["'lc1'", "unknown", "k1"]),
    ("unknown model kind", lambda: pl.make_model("soft"), ValueError, ["'soft'", "rigid", "elastic"]),
    ("unknown state name", lambda: pl.rigid().state(r1=1.0), ValueError, ["'r1'", "theta1"]),
    ("NaN in x0", lambda: _sim(x0=[0.1, NAN, 0.0, 0.0]), ValueError, ["x0", "finite", "nan"]),
    ("inf in x0", lambda: _sim(x0=[0.1, 0.0, math.inf, 0.0]), ValueError, ["x0", "finite", "inf"]),
    ("x0 too short", lambda: _sim(x0=[0.1, 0.2, 0.0]), ValueError, ["x0", "(4,)", "(3,)"]),
    ("x0 too long", lambda: _sim(pl.elastic(), x0=np.zeros(9)), ValueError, ["x0", "(8,)", "(9,)"]),
    ("rigid x0 for elastic", lambda: _sim(pl.elastic()), ValueError, ["x0", "(8,)", "(4,)"]),
    ("x0 a batch", lambda: _sim(x0=np.zeros((2, 4))), ValueError, ["x0", "(4,)", "(2, 4)"]),
    ("non-positive spring length", lambda: _sim(pl.elastic(), x0=np.zeros(8)), ValueError, ["r1, r2", "> 0", "0.0"]),
    (
        "spring length near zero (dynamics overflow)",
        lambda: _sim(pl.elastic(), x0=pl.elastic().state(r1=1e-300)),
        ValueError,
        ["x0", "not finite at this state", "r1=1e-300"],
    ),
    (
        "stiffness near zero (dynamics overflow)",
        lambda: _sim(pl.elastic(k1=1e-300), x0=pl.elastic(k1=1e-300).state()),
        ValueError,
        ["k1", "1e-300", "overflow or underflow"],
    ),
    (
        "batch start, second row bad",
        lambda: pl.elastic().check_start(np.vstack([pl.elastic().state(), pl.elastic().state(r2=-1.0)])),
        ValueError,
        ["x0[1]", "r1, r2", "-1.0"],
    ),
    ("rtol of 1 (no correct digit)", lambda: _sim(rtol=1.0), ValueError, ["rtol", "out of range", "1.0", "[2.22e-16, 1)"]),
    (
        "taylor tolerance below double epsilon (uninterruptible compile)",
        lambda: _sim(method="taylor", rtol=1e-100),
        ValueError,
        ["rtol", "2.22e-16", "1e-100"],
    ),
    ("unknown method", lambda: _sim(method="euler"), ValueError, ["'euler'", "cvodes", "DOP853"]),
    ("inf t_final", lambda: _sim(t_final=math.inf), ValueError, ["t_final", "not finite", "inf", "(0, 1e+12]"]),
    ("NaN t_final", lambda: _sim(t_final=NAN), ValueError, ["t_final", "not finite", "nan"]),
    ("zero t_final", lambda: _sim(t_final=0.0), ValueError, ["t_final", "out of range", "0.0", "(0, 1e+12]"]),
    ("negative dt", lambda: _sim(dt=-0.01), ValueError, ["dt", "out of range", "-0.01"]),
    ("zero rtol", lambda: _sim(rtol=0.0), ValueError, ["rtol", "out of range", "0.0"]),
    ("NaN atol", lambda: _sim(atol=NAN), ValueError, ["atol", "not finite", "nan"]),
    ("negative max_step", lambda: _sim(method="rk4", max_step=-1e-3), ValueError, ["max_step", "out of range", "-0.001"]),
    ("NaN in constant u", lambda: _sim(u=[0.0, NAN]), ValueError, ["u", "finite", "nan"]),
    ("u of wrong length", lambda: _sim(u=[0.0, 1.0, 2.0]), ValueError, ["u", "(2,)", "(3,)"]),
    ("scalar u", lambda: _sim(u=1.0), ValueError, ["u", "(2,)", "1.0"]),
    ("sampled u, wrong rows", lambda: _sim(u=np.zeros((7, 2))), ValueError, ["sampled u", "101", "7"]),
    ("NaN in sampled u", lambda: _sim(u=np.full((101, 2), NAN)), ValueError, ["u", "finite", "nan"]),
    ("callable u, wrong shape", lambda: _sim(u=lambda t, x: [1.0, 2.0, 3.0]), ValueError, ["u(t, x)", "t = 0", "(2,)", "3"]),
    ("callable u, NaN", lambda: _sim(u=lambda t, x: [0.0, NAN]), ValueError, ["u(t, x)", "finite", "nan"]),
    ("callable u, NaN later", lambda: _sim(u=lambda t, x: [0.0, NAN if t > 0.5 else 0.0]), ValueError, ["u(t, x)", "t = 0.5"]),
    ("model not a Model", lambda: pl.simulate("rigid", RIGID_X0, 1.0), TypeError, ["model", "Model", "str"]),
]


@pytest.mark.parametrize(("call", "exc", "parts"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_raises_clear_error(call, exc, parts):
    with pytest.raises(exc) as info:
        call()
    message = str(info.value)
    missing = [p for p in parts if p not in message]
    assert not missing, f"message {message!r} lacks {missing}"
    assert "\n" not in message  # one line, fit for the CLI's one-line error

"""Property-based tests of pl.ensemble's acceptance rules: accepted exactly when admissible, and right when accepted.

Each property draws inputs around the boundaries (zero, negative, tiny, NaN), computes the
documented admissibility independently, and checks that the ensemble accepts exactly those inputs
(a rejection is a ValueError or TypeError with a one-line message) and that what it accepts is
physically right.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pendulab as pl

pytest.importorskip("heyoka")

EPS = float(np.finfo(float).eps)
FEW = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
TOLS = st.one_of(
    st.sampled_from([1e-12, 1e-8, 0.5, 1.0, 2.0, 0.0, -1e-9, EPS, EPS / 2, 1e-300, math.nan, math.inf]),
    st.floats(1e-20, 2.0),
)


def _outcome(fn):
    try:
        return fn(), None
    except (ValueError, TypeError) as exc:
        assert "\n" not in str(exc).strip(), f"multi-line message: {exc}"
        return None, exc


@FEW
@given(rtol=TOLS, atol=TOLS)
def test_tolerances_accepted_exactly_when_admissible(rtol: float, atol: float) -> None:
    res, exc = _outcome(lambda: pl.ensemble(pl.rigid(), [[1.0, 1.0, 0.0, 0.0]], 0.2, rtol=rtol, atol=atol, threads=1))
    ok = 0 < rtol < 1 and math.isfinite(atol) and atol > 0 and min(rtol, atol) >= EPS
    if not ok:
        assert exc is not None, f"accepted rtol={rtol!r} atol={atol!r}"
        return
    assert exc is None, f"rejected admissible rtol={rtol!r} atol={atol!r}: {exc}"
    ref = pl.simulate(pl.rigid(), [1.0, 1.0, 0.0, 0.0], 0.2, method="cvodes", rtol=1e-12, atol=1e-12)
    # Over 0.2 s of regular motion the error stays near the requested tolerance (x100 margin, floor 1e-9).
    np.testing.assert_allclose(res.x_final[0], ref.x[-1], rtol=0, atol=max(1e-9, 100 * min(rtol, atol)))


@FEW
@given(r=st.lists(st.sampled_from([1.0, 0.5, 1e-3, 0.0, -0.0, -1.0, math.nan, 2.0]), min_size=4, max_size=4))
def test_elastic_starts_accepted_exactly_when_springs_are_extended(r: list[float]) -> None:
    el = pl.elastic(k1=500.0, k2=500.0)
    x0 = np.tile(el.rest_state(), (2, 1))
    x0[:, 2:4] = np.reshape(r, (2, 2))
    res, exc = _outcome(lambda: pl.ensemble(el, x0, 0.2, threads=1))
    ok = all(math.isfinite(v) and v > 0 for v in r)
    if not ok:
        assert exc is not None, f"accepted spring lengths {r}"
        return
    assert exc is None, f"rejected spring lengths {r}: {exc}"
    for i in range(2):
        if res.status[i] == "ok":
            assert np.all(res.x_final[i, 2:4] > 0)  # an ok run never reports a collapsed spring
        else:
            assert res.status[i] == "failed" and "spring length" in res.message[i]


@FEW
@given(
    lc2=st.lists(st.sampled_from([0.0, 0.5, 1.0]), min_size=3, max_size=3),
    i2=st.lists(st.sampled_from([0.0, 0.1]), min_size=3, max_size=3),
)
def test_inertia_rule_applies_per_run(lc2: list[float], i2: list[float]) -> None:
    m = pl.rigid()
    res, exc = _outcome(lambda: pl.ensemble(m, [[0.5, 0.5, 0.0, 0.0]] * 3, 0.2, params={"lc2": lc2, "I2": i2}, threads=1))
    ok = all(1.0 * a * a + b > 0 for a, b in zip(lc2, i2, strict=True))  # m2 lc2^2 + I2 > 0 run by run
    if not ok:
        assert exc is not None and "inadmissible" in str(exc), f"accepted lc2={lc2} I2={i2}"
        return
    assert exc is None, f"rejected lc2={lc2} I2={i2}: {exc}"
    e0 = np.array([m.with_params(lc2=a, I2=b).energy(np.array([0.5, 0.5, 0.0, 0.0])) for a, b in zip(lc2, i2, strict=True)])
    e1 = np.array([m.with_params(lc2=a, I2=b).energy(x) for a, b, x in zip(lc2, i2, res.x_final, strict=True)])
    np.testing.assert_allclose(e1, e0, rtol=0, atol=1e-10)  # each run conserves its own energy (tol 1e-12)

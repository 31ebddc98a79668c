"""The Python translations of the CasADi graph agree with CasADi itself, point by point and vectorized."""

import numpy as np
import pytest

import pendulab as pl
from pendulab.model.pycode import to_python


@pytest.mark.parametrize(
    "model", [pl.rigid(b1=0.1, I2=0.01), pl.elastic(k1=300.0, k2=300.0, c1=0.1, b2=0.2)], ids=["rigid", "elastic"]
)
def test_vectorized_batch_equals_casadi(model):
    rng = np.random.default_rng(1)
    X = rng.normal(size=(257, model.nx))
    if model.kind == "elastic":
        X[:, 2:4] = 0.5 + np.abs(X[:, 2:4])
    U = rng.normal(size=(257, 2))
    for name in ("rhs", "outputs"):
        ref = np.asarray(model.functions[name].map(257)(X.T, U.T, model.p)).T
        # Same operations in the same order: identical to the last bit (float64 either way).
        np.testing.assert_array_equal(getattr(model, name)(X, U), ref)
    for name in ("energy", "positions", "stretch", "dissipation", "spring_energy"):
        batch = getattr(model, name)(X)
        single = np.array([getattr(model, name)(x) for x in X[:7]])
        np.testing.assert_array_equal(batch[:7], single.reshape(batch[:7].shape))
        assert batch.shape[0] == 257 and batch.flags.writeable


def test_scalar_translation_equals_casadi():
    model = pl.elastic(k1=800.0, k2=500.0)
    f = to_python(model.functions["rhs"])
    x = model.state(theta1=1.0, theta2=-0.5, omega1=0.3)
    u = [0.2, -0.1]
    np.testing.assert_array_equal(f(x, u, model.p), np.asarray(model.functions["rhs"](x, u, model.p)).ravel())

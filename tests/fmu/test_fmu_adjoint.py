"""fmi3GetAdjointDerivative: CasADi's reverse mode on the graph of the directional derivatives.

Checked against the directional derivatives (v' (J w) == (J' v)' w, and the whole matrix), against the
CasADi Jacobian and against central finite differences of the FMU's own derivatives and outputs.
"""

from __future__ import annotations

import ctypes

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

import pendulab as pl
from tests.fmu.fmu_driver import started


def adjoint(d, unknowns, knowns, seed) -> np.ndarray:
    """J' seed; fmpy 0.3.32 sizes the sensitivity by the unknowns unless told (the standard: one per known)."""
    return np.array(d.fmu.getAdjointDerivative(unknowns, knowns, list(seed), nSensitivity=len(knowns)))


def _point(kind: str):
    model = pl.make_model(kind)
    x = model.state(theta1=0.9, theta2=-0.4, omega1=0.3)
    if kind == "elastic":
        x = model.state(theta1=0.9, theta2=-0.4, omega1=0.3, v1=0.01, r1=model.params.L1 * 0.98, r2=model.params.L2 * 1.01)
    return model, x, np.array([0.2, -0.1])


def _started(built, model, x, u, interface):
    d = started(built, dict(zip(model.state_names, x, strict=True)), interface=interface)
    d.set(tau1=u[0], tau2=u[1])
    if interface == "ME":
        d.fmu.enterContinuousTimeMode()
    return d


def _vrs(built, model):
    vr = built.vr
    unknowns = [vr[f"der({n})"] for n in model.state_names] + [vr[n] for n in model.output_names]
    knowns = [vr[n] for n in (*model.state_names, *model.input_names)]
    return unknowns, knowns


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("interface", ["CS", "ME"])
def test_adjoint_is_the_transpose_of_the_directional_derivative(fmu_builds, kind, interface):
    built = fmu_builds[(kind, 3)]
    model, x, u = _point(kind)
    d = _started(built, model, x, u, interface)
    unknowns, knowns = _vrs(built, model)
    rng = np.random.default_rng(7)
    for _ in range(5):
        v, w = rng.normal(size=len(unknowns)), rng.normal(size=len(knowns))
        Jw = np.array(d.fmu.getDirectionalDerivative(unknowns, knowns, list(w)))
        JTv = np.array(adjoint(d, unknowns, knowns, v))
        # two evaluation orders of the same sums: rounding only
        assert abs(v @ Jw - JTv @ w) <= 1e-12 * (np.abs(v) @ np.abs(Jw) + 1.0)
    # the whole matrix, row by row (adjoint) and column by column (directional)
    J_dir = np.column_stack([d.fmu.getDirectionalDerivative(unknowns, [k], [1.0]) for k in knowns])
    J_adj = np.vstack([adjoint(d, [r], knowns, [1.0]) for r in unknowns])
    np.testing.assert_allclose(J_adj, J_dir, rtol=1e-12, atol=1e-12)  # same graph, forward vs reverse mode: rounding
    jac = model.functions["jac_rhs"](x, u, model.p)
    np.testing.assert_allclose(J_adj[: model.nx], np.hstack([np.array(m) for m in jac]), rtol=1e-12, atol=1e-10)
    # subsets and a repeated unknown (its seeds add up)
    sub = adjoint(d, [unknowns[2], unknowns[2]], [knowns[1], knowns[0]], [0.5, 0.25])
    np.testing.assert_allclose(sub, 0.75 * J_dir[2, [1, 0]], rtol=1e-12, atol=1e-14)  # rounding
    d.close()


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_adjoint_matches_finite_differences(fmu_builds, kind):
    built = fmu_builds[(kind, 3)]
    model, x, u = _point(kind)
    d = _started(built, model, x, u, "ME")
    unknowns, knowns = _vrs(built, model)
    v = np.random.default_rng(3).normal(size=len(unknowns))
    JTv = np.array(adjoint(d, unknowns, knowns, v))

    def g(z: np.ndarray) -> float:  # v' (xdot, y) at states and inputs z, through the FMU
        d.fmu.setContinuousStates((ctypes.c_double * model.nx)(*z[: model.nx]), model.nx)
        d.set(tau1=z[model.nx], tau2=z[model.nx + 1])
        return float(v @ np.array(d.fmu.getFloat64(unknowns)))

    z0, eps = np.concatenate([x, u]), 1e-6
    fd = np.array([(g(z0 + eps * e) - g(z0 - eps * e)) / (2 * eps) for e in np.eye(len(z0))])
    # central differences: truncation O(eps^2) ~ 1e-12, rounding ~ 1e-16 |g| / eps ~ 1e-9 relative
    np.testing.assert_allclose(JTv, fd, rtol=1e-6, atol=1e-6)
    d.close()


def test_adjoint_bad_calls_are_errors(fmu_builds):
    built = fmu_builds[("rigid", 3)]
    model, x, u = _point("rigid")
    d = _started(built, model, x, u, "CS")
    vr = built.vr
    f = d.fmu.fmi3GetAdjointDerivative

    def call(unknowns, knowns, seed, n_sens):
        U = (ctypes.c_uint32 * len(unknowns))(*unknowns)
        K = (ctypes.c_uint32 * len(knowns))(*knowns)
        S = (ctypes.c_double * len(seed))(*seed)
        out = (ctypes.c_double * max(n_sens, 1))()
        return f(d.fmu.component, U, len(unknowns), K, len(knowns), S, len(seed), out, n_sens)

    with pytest.raises(FMICallException):  # seed count differs from unknown count
        call([vr["der(omega1)"]], [vr["theta1"]], [1.0, 2.0], 1)
    with pytest.raises(FMICallException):  # a state is not an unknown
        call([vr["theta1"]], [vr["theta1"]], [1.0], 1)
    with pytest.raises(FMICallException):  # a parameter is not a known
        call([vr["der(omega1)"]], [vr["g"]], [1.0], 1)
    with pytest.raises(FMICallException):  # non-finite seed
        call([vr["der(omega1)"]], [vr["theta1"]], [float("nan")], 1)
    # the instance is still usable after refused calls
    assert np.isfinite(adjoint(d, [vr["der(omega1)"]], [vr["theta1"]], [1.0])).all()
    d.close()


def test_adjoint_flag_in_model_description(fmu_builds):
    for kind in ("rigid", "elastic"):
        md3, md2 = fmu_builds[(kind, 3)].md, fmu_builds[(kind, 2)].md
        assert md3.coSimulation.providesAdjointDerivatives and md3.modelExchange.providesAdjointDerivatives
        assert not getattr(md2.coSimulation, "providesAdjointDerivatives", False)  # FMI 2 has no adjoints

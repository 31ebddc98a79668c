"""method="taylor": heyoka's Taylor integrator on the ODE translated from the CasADi graph.

Compiled integrators are cached per structure (kind, zero parameters, zero inputs, tol):
the tests share a few structures so that JIT compilation stays a small part of the run.
"""

import sys

import casadi as ca
import numpy as np
import pytest

import pendulab as pl

hy = pytest.importorskip("heyoka")

from pendulab.bench.cases import CASES  # noqa: E402
from pendulab.bench.reference import load_reference  # noqa: E402
from pendulab.integrate import taylor  # noqa: E402
from pendulab.integrate.registry import SimulationError  # noqa: E402

TIGHT = 1e-15
INPUT_TOL = 1e-12
CVODES = {"method": "cvodes", "rtol": 1e-12, "atol": 1e-12}


def swing_energy_drift(model: pl.Model, x: np.ndarray) -> float:
    """max |E(t) - E(0)| relative to the swing energy E(0) - E(rest) (not to E's arbitrary offset)."""
    e = model.energy(x)
    return float(np.max(np.abs(e - e[0])) / abs(e[0] - model.energy(model.rest_state())))


def test_chaotic_case_matches_stored_reference():
    ref = load_reference(CASES["rigid_chaotic_10s"])
    tr = pl.simulate(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 10.0, method="taylor", rtol=TIGHT, atol=TIGHT)
    assert tr.method == "taylor" and tr.stats["taylor_order"] >= 19 and tr.stats["tol"] == TIGHT
    # The reference (32-digit GBS, accuracy ~3e-15) is exact at this level; a 1e-15 local
    # tolerance amplified by the chaotic growth (1e4-1e6 over 10 s) leaves ~1e-11.
    assert np.max(np.abs(tr.x[-1] - ref.x[-1])) < 1e-10


def test_energy_conserved_rigid_regular():
    m = pl.rigid()
    tr = pl.simulate(m, m.state(theta1=0.3, theta2=0.3), 10.0, method="taylor", rtol=TIGHT, atol=TIGHT)
    # Undamped and unforced: only rounding (~1e-16 per step, ~400 steps) changes the energy.
    assert swing_energy_drift(m, tr.x) < 1e-12


@pytest.fixture(scope="module")
def elastic_run():
    m = pl.elastic(k1=500.0, k2=500.0)
    x0 = m.state(theta1=0.3, theta2=0.3)
    return m, x0, pl.simulate(m, x0, 1.0, method="taylor", rtol=INPUT_TOL, atol=INPUT_TOL)


def test_energy_conserved_elastic(elastic_run):
    m, _, tr = elastic_run
    # Springs exchange energy with the swing at ~14 and ~36 rad/s; a 1e-12 Taylor step keeps the
    # total to rounding level (measured ~1e-15 of the swing energy).
    assert swing_energy_drift(m, tr.x) < 1e-12


def test_elastic_matches_cvodes(elastic_run):
    m, x0, tr = elastic_run
    ref = pl.simulate(m, x0, 1.0, **CVODES)
    # CVODES BDF at 1e-12 is good to ~1e-9 over 1 s of spring oscillation; Taylor is far tighter.
    np.testing.assert_allclose(tr.x, ref.x, rtol=0, atol=1e-8)


def test_parameter_change_reuses_compiled_integrator():
    m = pl.rigid()
    x0 = m.state(theta1=0.3, theta2=-0.2)
    pl.simulate(m, x0, 1.0, method="taylor", rtol=TIGHT, atol=TIGHT)
    before = taylor.compile_count()
    m2 = m.with_params(m1=1.7, m2=0.6, L1=0.8, L2=1.3, g=3.7)
    tr = pl.simulate(m2, x0, 3.0, method="taylor", rtol=TIGHT, atol=TIGHT)
    assert taylor.compile_count() == before and tr.stats["compiled"] is False
    ref = pl.simulate(m2, x0, 3.0, **CVODES)
    # Regular motion, 3 s: CVODES at 1e-12 is accurate to ~1e-10; a wrong parameter would be O(1).
    np.testing.assert_allclose(tr.x, ref.x, rtol=0, atol=1e-8)


def test_zero_to_nonzero_parameter_is_a_new_structure():
    m = pl.rigid(b1=0.3, I2=0.05, lc1=0.6)
    x0 = m.state(theta1=1.0, theta2=0.5)
    before = taylor.compile_count()
    tr = pl.simulate(m, x0, 2.0, method="taylor", rtol=TIGHT, atol=TIGHT)
    assert taylor.compile_count() == before + 1
    ref = pl.simulate(m, x0, 2.0, **CVODES)
    # Damped, regular, 2 s: CVODES at 1e-12 is accurate to ~1e-10.
    np.testing.assert_allclose(tr.x, ref.x, rtol=0, atol=1e-8)
    # Only the energy changes when the damping value changes: same structure, no compilation.
    pl.simulate(m.with_params(b1=0.9), x0, 0.5, method="taylor", rtol=TIGHT, atol=TIGHT)
    assert taylor.compile_count() == before + 1


@pytest.fixture(scope="module")
def rigid_inputs():
    m = pl.rigid(b2=0.1)
    return m, m.state(theta1=0.4, theta2=-0.3)


def _agree(model, x0, u, t_final=2.0):
    tr = pl.simulate(model, x0, t_final, method="taylor", rtol=INPUT_TOL, atol=INPUT_TOL, u=u)
    ref = pl.simulate(model, x0, t_final, u=u, **CVODES)
    # Regular forced motion over 2 s: CVODES at 1e-12 is accurate to ~1e-10; an input-handling
    # error (wrong interval, sign or index) would be O(1e-3) or more. A feedback's torques follow
    # the states, so they agree to the same level; a schedule's torques are the same numbers.
    np.testing.assert_allclose(tr.x, ref.x, rtol=0, atol=1e-8)
    np.testing.assert_allclose(tr.u, ref.u, rtol=0, atol=1e-8 if callable(u) else 0.0)
    return tr


def test_constant_input_matches_cvodes(rigid_inputs):
    m, x0 = rigid_inputs
    _agree(m, x0, np.array([0.8, -0.3]))


def test_sampled_input_matches_cvodes(rigid_inputs):
    m, x0 = rigid_inputs
    t = pl.integrate.time_grid(2.0, 0.01)
    u = np.column_stack([np.sin(3 * t), 0.5 * np.cos(2 * t)])
    _agree(m, x0, u)


def test_pendubot_input_specialises_tau2(rigid_inputs):
    m, x0 = rigid_inputs
    t = pl.integrate.time_grid(2.0, 0.01)
    u = np.column_stack([np.where(t < 1.0, 1.0, -0.5), np.zeros_like(t)])
    tr = _agree(m, x0, u)
    assert tr.stats["n_steps"] > 0


def test_feedback_matches_cvodes(rigid_inputs):
    m, x0 = rigid_inputs

    def pd(t, x):
        return np.array([-4.0 * x[0] - 1.0 * x[2], -2.0 * (x[1] - x[0]) - 0.5 * x[3]])

    _agree(m, x0, pd)


def test_translation_equals_casadi_rhs_with_every_term():
    """Damping, inertias, offset centres of mass and both torques: the translated ODE is the CasADi rhs."""
    m = pl.rigid(m1=1.3, m2=0.7, L1=0.9, L2=1.1, b1=0.2, b2=0.1, lc1=0.4, lc2=0.6, I1=0.03, I2=0.02)
    system = taylor.translate(m.functions["rhs"], state_names=m.state_names)
    f = hy.cfunc([e for _, e in system.sys], list(hy.make_vars(*m.state_names)))
    rng = np.random.default_rng(1)
    for _ in range(5):
        x, u = rng.normal(size=4) * 2, rng.normal(size=2)
        got = f(x, pars=system.pars(u, m.p))
        # Same expression graph, reassociated: agreement to a few ulps of the largest term.
        np.testing.assert_allclose(got, m.rhs(x, u), rtol=1e-12, atol=1e-12)


def test_unmapped_operation_is_named():
    x, u, p = ca.SX.sym("x", 2), ca.SX.sym("u", 1), ca.SX.sym("p", 1)
    f = ca.Function("f", [x, u, p], [ca.vertcat(x[1], ca.floor(x[0]))])
    with pytest.raises(NotImplementedError, match="floor"):
        taylor.translate(f)


def test_step_limit_is_a_simulation_error():
    with pytest.raises(SimulationError, match="'taylor' failed at t = .*step limit"):
        pl.simulate(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 10.0, method="taylor", rtol=TIGHT, atol=TIGHT, options={"max_steps": 3})


def test_unknown_option_is_rejected():
    with pytest.raises(ValueError, match="unknown option 'order'"):
        pl.simulate(pl.rigid(), [0.1, 0.0, 0.0, 0.0], 0.1, method="taylor", options={"order": 20})


def test_missing_heyoka_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "heyoka", None)  # makes `import heyoka` raise ImportError
    with pytest.raises(ImportError, match=r"'taylor'.*pip install \"pendulab\[taylor\]\""):
        pl.simulate(pl.rigid(), [0.1, 0.0, 0.0, 0.0], 0.1, method="taylor")

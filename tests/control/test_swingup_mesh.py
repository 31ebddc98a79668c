"""A posteriori error estimate, non-uniform meshes and h-refinement of swing-up plans."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from pendulab.control import swing_up
from pendulab.control.swingup.errors import SCALE_FLOOR, estimate_error, estimate_error_arrays
from pendulab.control.swingup.mesh import MESH_SIZES, collocation_states, refine_mesh
from pendulab.control.swingup.tasks import load_task


@pytest.fixture(scope="module")
def pendubot():
    return load_task("pendubot").problem


@pytest.fixture(scope="module")
def skewed():
    # A deliberately non-uniform mesh: interval lengths growing 4x over the horizon.
    return np.linspace(1.0, 4.0, 20)


@pytest.fixture(scope="module")
def plan_skewed(pendubot, skewed):
    return swing_up(pendubot, "radau", 20, mesh=skewed, tolerance=None)


@pytest.fixture(scope="module")
def refined(pendubot):
    return swing_up(pendubot, "radau", 20, tolerance=1e-3)


def test_estimate_equals_direct_reintegration(plan_skewed):
    r = plan_skewed
    assert r.success, r.message
    # t is the actual non-uniform grid: interval lengths follow the requested mesh.
    np.testing.assert_allclose(np.diff(r.t), r.horizon * np.linspace(1.0, 4.0, 20) / np.linspace(1.0, 4.0, 20).sum(), rtol=1e-12)
    est = estimate_error(r, tolerance=1e-3)
    model = r.problem.model
    scale = np.maximum(np.abs(r.x).max(axis=0), SCALE_FLOOR)
    np.testing.assert_array_equal(est.scale, scale)
    for k in (0, 7, 13, 19):
        # Independent path: SciPy's Radau on the model's NumPy RHS, torque held on the interval.
        sol = solve_ivp(lambda _t, x, uk=r.u[k]: model.rhs(x, uk), (r.t[k], r.t[k + 1]), r.x[k], "Radau", rtol=1e-11, atol=1e-11)
        direct = np.abs(sol.y[:, -1] - r.x[k + 1]) / scale
        # Both integrations are accurate to ~1e-10 in state units; defects are ~1e-4..1e-2 relative.
        np.testing.assert_allclose(est.defects[k], direct, rtol=1e-4, atol=1e-8)
    assert est.worst == pytest.approx(est.defects.max()) and est.interval_worst.shape == (20,)
    assert est.passed == (est.worst <= 1e-3)


def test_estimate_array_form_and_other_model(plan_skewed):
    r = plan_skewed
    a = estimate_error_arrays(r.problem.model, r.t, r.x, r.u, tolerance=1e-2, method="compiled-dopri5")
    b = estimate_error(r, tolerance=1e-2, method="compiled-dopri5")
    np.testing.assert_array_equal(a.defects, b.defects)
    # The plan checked against another model (second link twice as heavy) does not satisfy those
    # dynamics: measured 0.25 vs 0.05 for its own (coarse, N = 20) model; 3x leaves margin.
    heavy = r.problem.model.with_params(m2=2.0 * r.problem.model.params.m2)
    assert estimate_error(r, model=heavy, tolerance=1e-2).worst > 3 * b.worst


def test_estimate_rejects_bad_input(plan_skewed):
    r = plan_skewed
    model = r.problem.model
    with pytest.raises(ValueError, match="x must have shape"):
        estimate_error_arrays(model, r.t, r.x[:, :3], r.u)
    with pytest.raises(ValueError, match="u must have shape"):
        estimate_error_arrays(model, r.t, r.x, r.u[:-1])
    with pytest.raises(ValueError, match="strictly increasing"):
        estimate_error_arrays(model, r.t[::-1], r.x, r.u)
    bad = r.x.copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError, match="x must be finite"):
        estimate_error_arrays(model, r.t, bad, r.u)
    with pytest.raises(ValueError, match="tolerance"):
        estimate_error(r, tolerance=0.0)
    with pytest.raises(TypeError, match="model"):
        estimate_error_arrays("rigid", r.t, r.x, r.u)


def test_refinement_lowers_estimate_monotonically_until_it_passes(refined):
    worst = [h["worst"] for h in refined.mesh_history]
    assert refined.success, refined.message
    assert len(worst) >= 2  # N = 20 does not meet 1e-3 (measured 0.10), so it had to refine
    assert all(b < a for a, b in zip(worst, worst[1:], strict=False))
    assert worst[-1] <= 1e-3 and refined.error.passed and refined.error.worst == worst[-1]
    # Refined sizes come from the ladder (cache reuse) and the grid is the refined one.
    assert all(h["N"] in MESH_SIZES for h in refined.mesh_history[1:])
    assert refined.N == refined.mesh_history[-1]["N"] == refined.t.size - 1
    # The plan still starts and ends where asked, and x_at/u_at interpolate on the refined grid.
    np.testing.assert_array_equal(refined.x[[0, -1]], np.array([refined.problem.start, refined.problem.target]))
    np.testing.assert_allclose(refined.x_at(refined.t), refined.x, atol=1e-12)
    np.testing.assert_array_equal(refined.u_at(refined.t[:-1] + 1e-9), refined.u)
    # wall_time covers every mesh; solve_time is the last mesh's solve.
    assert refined.solve_time == refined.mesh_history[-1]["solve_time"] <= refined.wall_time


def test_unreachable_tolerance_fails_with_reason(pendubot):
    r = swing_up(pendubot, "radau", 20, tolerance=1e-9, max_intervals=20)
    assert not r.success and r.error is not None and not r.error.passed
    assert "max_intervals=20" in r.message and "tolerance 1.0e-09" in r.message
    r = swing_up(pendubot, "radau", 20, tolerance=1e-9, max_refinements=0)
    assert not r.success and "max_refinements=0" in r.message
    # The plan itself is IPOPT-optimal: only the estimate rejects it.
    assert r.status == "Solve_Succeeded" and r.max_violation < 1e-6


def test_same_structure_reuses_the_nlp(pendubot, skewed):
    swing_up(pendubot, "radau", 20, mesh=skewed, tolerance=None)
    again = swing_up(pendubot, "radau", 20, mesh=skewed[::-1], tolerance=None)
    assert again.build_time == 0.0  # another mesh with the same N: no new NLP
    assert again.success, again.message


def test_uniform_mesh_given_explicitly_matches_default(pendubot):
    a = swing_up(pendubot, "radau", 20, tolerance=None)
    b = swing_up(pendubot, "radau", 20, mesh=np.full(20, 2.5), tolerance=None)
    # Same NLP up to rounding of the fractions (1 ulp): same optimum to IPOPT's tolerance.
    np.testing.assert_allclose(b.t, a.t, rtol=1e-14)
    np.testing.assert_allclose(b.x, a.x, atol=1e-6)
    assert b.cost == pytest.approx(a.cost, rel=1e-8)
    with pytest.raises(ValueError, match="mesh"):
        swing_up(pendubot, "radau", 20, mesh=np.ones(19))
    with pytest.raises(ValueError, match="mesh"):
        swing_up(pendubot, "radau", 20, mesh=np.r_[np.ones(19), -1.0])


def test_refine_mesh_splits_where_needed():
    err = np.full(40, 1e-5)
    err[12], err[30] = 3.6e-2, 2e-3
    new, pieces = refine_mesh(np.full(40, 1 / 40), err, 1e-3, 3)
    assert new.size == pieces.sum() and new.size in MESH_SIZES
    assert new.sum() == pytest.approx(1.0, abs=1e-14)
    # Error model e ~ h^4: 3.6e-2 needs n^4 >= 72 -> n >= 3 pieces to reach half the tolerance; 2e-3 needs 2.
    assert pieces[12] >= 3 and pieces[30] >= 2
    # Each old interval is split into equal pieces: the refined mesh nests in the old one.
    np.testing.assert_allclose(np.add.reduceat(new, np.r_[0, np.cumsum(pieces)[:-1]]), np.full(40, 1 / 40), rtol=1e-12)
    same, p = refine_mesh(np.full(40, 1 / 40), err, 1e-3, 3, max_intervals=40)
    assert same.size == 40 and np.all(p == 1)  # at the cap nothing is split
    with pytest.raises(ValueError, match="order"):
        refine_mesh(np.full(4, 0.25), np.ones(4), 1e-3, 0)


def test_collocation_states_reproduce_the_solution(plan_skewed):
    r = plan_skewed
    np.testing.assert_allclose(collocation_states(r.t, r.x, r.xc, r.degree, r.method, r.t), r.x, atol=1e-12)
    tau = np.array([0.155051025721682, 0.644948974278318, 1.0])  # Radau IIA(3) nodes
    tc = (r.t[:-1, None] + np.diff(r.t)[:, None] * tau[None, :]).ravel()
    # At the collocation points the interval polynomial returns the collocation states (the end node = next state).
    np.testing.assert_allclose(collocation_states(r.t, r.x, r.xc, r.degree, r.method, tc), r.xc, atol=1e-9)

"""Stiff elastic swing-ups: p-refinement rule (degree and mesh from the spring modes) and the error-estimate scales."""

import math

import casadi as ca
import numpy as np
import pytest

import pendulab as pl
from pendulab.control.swingup.errors import SCALES, estimate_error_arrays, rescale
from pendulab.control.swingup.mesh import oscillation_mesh, radau_resolution
from pendulab.control.swingup.planning import ELASTIC_DEGREE, elastic_error
from pendulab.control.swingup.tasks import load_task


def _radau_oscillator_error(z: float, degree: int) -> float:
    """|y(h) - exp(i z)| of Radau collocation of y' = i w y, y(0) = 1, over one interval h = z / w (direct solve)."""
    tau = np.array([0.0, *ca.collocation_points(degree, "radau")])
    # Derivative of the Lagrange basis on tau at the collocation points (rows) -> D y = i z y at tau[1:].
    D = np.zeros((degree, degree + 1))
    for j in range(degree + 1):
        others = np.delete(tau, j)
        coeffs = np.poly(others) / np.prod(tau[j] - others)
        D[:, j] = np.polyval(np.polyder(coeffs), tau[1:])
    A = D[:, 1:] - 1j * z * np.eye(degree)
    y = np.linalg.solve(A, -D[:, 0])
    return abs(y[-1] - np.exp(1j * z))  # Radau: the last collocation point is the interval's end


@pytest.mark.parametrize("degree", [3, 5, 7])
def test_radau_resolution_agrees_with_collocating_an_oscillator(degree):
    z = radau_resolution(degree, 1e-3)
    # At the resolution limit the directly collocated oscillator errs by the tolerance (grid step of the
    # scan 6e-4 in z: 2 % in the error); beyond it by more.
    assert _radau_oscillator_error(z, degree) == pytest.approx(1e-3, rel=2e-2)
    assert _radau_oscillator_error(1.1 * z, degree) > 1e-3
    # A looser tolerance allows longer intervals.
    assert radau_resolution(degree, 1e-2) > z


def test_higher_degree_resolves_longer_intervals():
    zs = [radau_resolution(d, 1e-3) for d in (1, 3, 5, 7)]
    assert zs == sorted(zs)
    # Degree 7 follows a mode ~4.7x longer per interval than degree 3 (Padé (6, 7) against (2, 3)).
    assert zs[3] / zs[1] == pytest.approx(4.73, rel=1e-2)
    with pytest.raises(ValueError, match="degree"):
        radau_resolution(0, 1e-3)
    with pytest.raises(ValueError, match="tolerance"):
        radau_resolution(3, 0.0)


def test_oscillation_mesh_of_the_stiff_tasks():
    task = load_task("pendubot_elastic")
    fastest = max(md.omega_n for md in pl.modes(task.model, "down-down") if md.spring_share >= 0.5)
    # Springs 25000 N/m: modes 126 and 346 rad/s (docs/swingup.md); 1 rad/s for rounding.
    assert fastest == pytest.approx(345.7, abs=1.0)
    n7 = oscillation_mesh(task.problem.horizon, fastest, ELASTIC_DEGREE, 1e-3, task.N)
    n3 = oscillation_mesh(task.problem.horizon, fastest, 3, 1e-3, task.N)
    assert n7 == math.ceil(3.0 * fastest / radau_resolution(7, 1e-3)) and 150 <= n7 <= 160
    assert n3 > 4 * n7  # degree 3 would need ~740 intervals
    # The lower bound holds when the springs need fewer intervals (soft springs, 69 rad/s).
    assert oscillation_mesh(3.0, 69.1, 7, 1e-3, 100) == 100
    with pytest.raises(ValueError, match="omega"):
        oscillation_mesh(3.0, math.inf, 7, 1e-3)
    with pytest.raises(ValueError, match="horizon"):
        oscillation_mesh(0.0, 100.0, 7, 1e-3)


@pytest.fixture(scope="module")
def ringing_plan():
    """An elastic trajectory with a spring ringing, on a grid too coarse for it, with its torques."""
    m = pl.elastic(k1=1e4, k2=1e4)
    x0 = m.rest_state() + np.array([0.4, 0.1, 0.002, 0.0, 0.0, 0.0, 0.0, 0.0])
    traj = pl.simulate(m, x0, 0.2, dt=0.02, method="cvodes", rtol=1e-12, atol=1e-12)
    x = traj.x.copy()
    x[4] += 1e-4  # a small error on the grid (all states) so that every defect is non-trivial
    return m, traj.t, x, np.zeros((traj.t.size - 1, 2))


def test_error_scales_share_the_absolute_defects(ringing_plan):
    m, t, x, u = ringing_plan
    state = estimate_error_arrays(m, t, x, u)
    bob = estimate_error_arrays(m, t, x, u, scale="bob-speed")
    assert state.scale_kind == "state" and bob.scale_kind == "bob-speed" and SCALES == ("state", "bob-speed")
    # One re-integration, two normalisations: identical absolute defects (same integrator, same plan).
    assert np.array_equal(state.absolute, bob.absolute)
    # bob-speed only raises the spring-rate scales, to the largest tangential bob speed.
    speed = np.max(np.abs(x[:, 2:4] * x[:, 4:6]))
    assert np.array_equal(bob.scale[:6], state.scale[:6])
    assert bob.scale[6:] == pytest.approx(np.maximum(state.scale[6:], speed), rel=1e-15)
    assert bob.worst <= state.worst
    # rescale() converts without re-integrating and agrees exactly; elastic_error is the bob-speed estimate.
    again = rescale(state, m, x, "bob-speed")
    assert again.worst == bob.worst and np.array_equal(again.defects, bob.defects)
    assert rescale(bob, m, x, "state").worst == state.worst
    assert elastic_error(m, t, x, u).worst == bob.worst
    assert "bob speed" in bob.summary() and "bob speed" not in state.summary()


def test_error_scale_is_the_same_for_a_rigid_model():
    m = pl.rigid()
    traj = pl.simulate(m, [0.5, 0.2, 0.0, 0.0], 0.4, dt=0.05, method="cvodes", rtol=1e-12, atol=1e-12)
    x = traj.x.copy()
    x[3, 0] += 1e-5
    u = np.zeros((traj.t.size - 1, 2))
    a = estimate_error_arrays(m, traj.t, x, u)
    b = estimate_error_arrays(m, traj.t, x, u, scale="bob-speed")
    assert np.array_equal(a.defects, b.defects)


def test_unknown_error_scale_raises(ringing_plan):
    m, t, x, u = ringing_plan
    with pytest.raises(ValueError, match="scale"):
        estimate_error_arrays(m, t, x, u, scale="bob")
    est = estimate_error_arrays(m, t, x, u)
    with pytest.raises(ValueError, match="scale"):
        rescale(est, m, x, "speed")
    with pytest.raises(ValueError, match="x must have shape"):
        rescale(est, m, x[:-1], "bob-speed")


def test_elastic_level_degree_and_mesh_come_from_the_spring_modes():
    from pendulab.control.swingup.planning import _elastic_discretisation

    stiff = load_task("pendubot_elastic").problem
    soft = load_task("acrobot_elastic_soft").problem
    # Stiff (346 rad/s): no degree <= 7 resolves it on 100 intervals -> degree 7 on ceil(3 * 345.7 / 6.67).
    assert _elastic_discretisation(stiff, "radau", 100, 3, 1e-3, 300) == (7, 156)
    # Soft (69 rad/s): h w = 2.07 on 100 intervals, beyond degree 3 (1.41) and within degree 4 (2.54).
    assert _elastic_discretisation(soft, "radau", 100, 3, 1e-3, 300) == (4, 100)
    # The interval cap holds; shooting has no degree to raise.
    assert _elastic_discretisation(stiff, "radau", 100, 3, 1e-3, 120) == (7, 120)
    assert _elastic_discretisation(stiff, "shooting", 100, 3, 1e-3, 300) == (3, 100)


def test_soft_elastic_task_plan_meets_the_tolerance_on_the_elastic_dynamics():
    from pendulab.control.swingup.errors import estimate_error
    from pendulab.control.swingup.planning import plan

    task = load_task("pendubot_elastic_soft")
    p = plan(task.problem, tolerance=1e-3, N=task.N, degree=task.degree)
    assert p.level == "elastic" and p.success, p.attempts
    assert (p.result.degree, p.result.N) == (4, 100)  # p-refinement, no h-refinement needed
    # An independent re-integration with another integrator agrees with the solver's estimate: both
    # integrate to 1e-10, far below the 1e-4-level defects (5 % covers where the worst interval's
    # defect sits between the two integrators' own errors).
    again = estimate_error(p.result, method="cvodes")
    assert again.worst == pytest.approx(p.estimate.worst, rel=5e-2) and again.passed
    assert p.estimate.scale_kind == "state" and p.attempts[-1]["worst_bob_speed"] <= p.estimate.worst

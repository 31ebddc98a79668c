"""Modes against analytic values: rigid omega^2 = (2 +- sqrt 2) g/L, the radial spring problem, up-up divergence."""

import math

import control as ct
import numpy as np
import pytest

import pendulab as pl
from pendulab.control import to_statespace


def _oscillations(mode_list):
    return [m for m in mode_list if m.kind == "oscillatory"]


def test_rigid_equal_masses_down_down_analytic():
    g, L = 9.81, 0.7
    model = pl.rigid(m1=1.3, m2=1.3, L1=L, L2=L, g=g)
    slow, fast = _oscillations(pl.modes(model, "down-down"))
    # Textbook result for equal point masses and lengths: omega^2 = (2 -+ sqrt 2) g / L; rtol = round-off of eig.
    assert slow.omega_n**2 == pytest.approx((2 - math.sqrt(2)) * g / L, rel=1e-12)
    assert fast.omega_n**2 == pytest.approx((2 + math.sqrt(2)) * g / L, rel=1e-12)
    assert fast.freq_hz == pytest.approx(fast.omega_n / (2 * math.pi), rel=1e-15)
    # Shapes: theta2 / theta1 = +sqrt 2 (in phase) and -sqrt 2 (anti phase).
    np.testing.assert_allclose(slow.shape, [1 / math.sqrt(2), 1.0], atol=1e-12)
    np.testing.assert_allclose(fast.shape, [-1 / math.sqrt(2), 1.0], atol=1e-12)
    assert (slow.label, fast.label) == ("pendular in-phase", "pendular anti-phase")
    assert slow.damping_ratio == pytest.approx(0.0, abs=1e-12) and math.isinf(slow.time_constant)


def test_rigid_up_up_two_unstable_modes_with_analytic_rates():
    g, L = 9.81, 0.7
    model = pl.rigid(m1=1.3, m2=1.3, L1=L, L2=L, g=g)
    unstable = [m for m in pl.modes(model, "up-up") if m.kind == "unstable"]
    assert len(unstable) == 2 == pl.equilibrium(model, "up-up").n_unstable
    # Flipping gravity turns omega^2 into growth rates sigma^2 = (2 -+ sqrt 2) g / L; tau = 1 / sigma.
    rates = sorted(1 / m.time_constant for m in unstable)
    np.testing.assert_allclose(np.square(rates), [(2 - math.sqrt(2)) * g / L, (2 + math.sqrt(2)) * g / L], rtol=1e-12)


@pytest.mark.parametrize("name", ["down-down", "down-up", "up-up"])
def test_elastic_spring_modes_match_radial_problem(name):
    m1, m2, k1, k2 = 0.8, 1.5, 900.0, 400.0
    model = pl.elastic(m1=m1, m2=m2, k1=k1, k2=k2)
    # At a vertical equilibrium the radial motion decouples from the angles. With bob2 = r1 e1 + r2 e2 and
    # e1.e2 = c = +-1, T = 1/2 (m1 + m2) r1'^2 + m2 c r1' r2' + 1/2 m2 r2'^2, V = 1/2 k1 dr1^2 + 1/2 k2 dr2^2.
    c = 1.0 if name in ("down-down", "up-up") else -1.0
    M = np.array([[m1 + m2, c * m2], [c * m2, m2]])
    K = np.diag([k1, k2])
    expected = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    springs = [m for m in pl.modes(model, name) if m.spring_share > 0.5]
    # Both paths are exact; rtol covers eigenvalue round-off.
    np.testing.assert_allclose([m.omega_n for m in springs], expected, rtol=1e-10)
    assert all(m.kind == "oscillatory" and "stretch" in m.label for m in springs)


def test_elastic_pendular_modes_converge_to_rigid():
    rigid = [m.omega_n for m in _oscillations(pl.modes(pl.rigid(), "down-down"))]
    gaps = []
    for k in (1e3, 1e4, 1e5):
        el = [m.omega_n for m in pl.modes(pl.elastic(k1=k, k2=k), "down-down") if m.spring_share < 0.5]
        gaps.append(np.max(np.abs(np.array(el) / rigid - 1)))
    # The static stretch (m g / k) lengthens the pendulum by O(1/k): the gap shrinks ~10x per decade of k.
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[2] < 2e-4 and gaps[1] / gaps[2] == pytest.approx(10, rel=0.1)


def test_damping_matches_python_control_damp():
    model = pl.elastic(b1=0.4, b2=0.2, c1=2.0, c2=1.0)
    ours = sorted((m.omega_n, m.damping_ratio) for m in pl.modes(model, "down-down"))
    wn, zeta, _ = ct.damp(to_statespace(model, "down-down"), doprint=False)
    theirs = sorted(set(zip(np.round(wn, 9), np.round(zeta, 9), strict=True)))
    # Independent eigen-analysis of the same matrix; rtol covers round-off.
    np.testing.assert_allclose(np.array(ours), np.array(theirs), rtol=1e-8)
    assert all(m.damping_ratio > 0 and np.isfinite(m.time_constant) for m in pl.modes(model, "down-down"))


def test_modes_at_a_state_and_bad_input():
    model = pl.rigid()
    by_state = pl.modes(model, np.array([0.0, 0.0, 0.0, 0.0]))
    by_name = pl.modes(model, "down-down")
    np.testing.assert_allclose([m.omega_n for m in by_state], [m.omega_n for m in by_name], rtol=1e-15)
    with pytest.raises(ValueError, match="unknown equilibrium name 'upside'"):
        pl.modes(model, "upside")
    with pytest.raises(ValueError, match=r"x must have shape \(4,\)"):
        pl.modes(model, np.zeros(8))


def test_the_table_gives_a_frequency_only_to_modes_that_oscillate():
    from pendulab.analysis.modes import mode_table

    model = pl.rigid()
    down = pl.modes(model, "down-down")
    up = pl.modes(model, "up-up")
    rows_down = mode_table(down).splitlines()[2:]
    rows_up = mode_table(up).splitlines()[2:]
    for row, m in zip(rows_down, down, strict=True):
        assert m.kind == "oscillatory" and f"{m.freq_hz:.4g}" in row.split()
    for row, m in zip(rows_up, up, strict=True):
        # a real eigenvalue is a growth or decay rate, not a frequency: the f [Hz] column says "-"
        assert m.kind in ("unstable", "decaying") and row.split()[4] == "-"

"""Quasi-static spring lengths: zero radial acceleration, analytic static stretch."""

import numpy as np
import pytest

import pendulab as pl
from pendulab.model.quasistatic import quasi_static_lengths, quasi_static_state


def test_at_rest_equals_static_hanging_length():
    m = pl.elastic(k1=300.0, k2=700.0, m1=2.0, m2=0.5)
    # Analytic: spring 1 carries (m1 + m2) g, spring 2 carries m2 g.
    np.testing.assert_allclose(quasi_static_state(m, [0.0, 0.0]), m.rest_state(), rtol=0, atol=1e-12)


def test_radial_accelerations_vanish_while_swinging():
    m = pl.elastic(k1=1e3, k2=1e3)
    x = quasi_static_state(m, [2.0, -1.0], [1.5, -3.0])
    xdot = m.rhs(x)
    # Newton tolerance 1e-12 on the residual (accelerations in m/s2).
    assert np.max(np.abs(xdot[6:8])) < 1e-9
    assert x[6] == x[7] == 0.0


def test_centrifugal_stretch_of_single_spinning_link():
    # Bob 2 massless-limit check: a tiny m2 and spring 1 spinning at omega with the
    # chain straight: k1 (r1 - L1) = m1 r1 omega^2 + m1 g cos(theta) (radial balance).
    m = pl.elastic(m1=1.0, m2=1e-9, k1=200.0, k2=200.0)
    w, th = 4.0, 0.0
    r1 = quasi_static_lengths(m, [th, th], [w, w])[0]
    expected = (200.0 * 1.0 + 1.0 * 9.81 * np.cos(th)) / (200.0 - w**2)
    assert r1 == pytest.approx(expected, rel=1e-6)  # m2 = 1e-9 kg perturbs at the 1e-9 level


def test_rigid_model_rejected():
    with pytest.raises(ValueError, match="elastic"):
        quasi_static_state(pl.rigid(), [0.0, 0.0])


def test_no_solution_names_the_failing_point():
    m = pl.elastic(k1=10.0, k2=10.0)
    th = np.array([[0.1, 0.1], [0.2, 0.2]])
    om = np.array([[0.0, 0.0], [10.0, 10.0]])  # m w^2 = 100 N/m > k = 10 N/m: the spring cannot hold the bob
    with pytest.raises(RuntimeError, match=r"theta=\[0\.2, 0\.2\]"):
        quasi_static_lengths(m, th, om)

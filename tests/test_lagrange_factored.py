"""The elastic pendulum's accelerations by block substitution through the bobs' Jacobian (pendulab.model.lagrange).

``point_mass_accelerations`` must give Lagrange's generic ``M^-1 rhs`` (the same energies, the mass matrix
solved directly) at any state and parameters, with a third of the expression; and refuse bodies that are not
a chain.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from pendulab.model.builders import build_elastic
from pendulab.model.lagrange import point_mass_accelerations


def test_factored_accelerations_equal_the_generic_solve_of_lagranges_equations():
    sm = build_elastic()
    factored = ca.Function("factored", [sm.x, sm.u, sm.p], [sm.eom.qdd])
    generic = ca.Function("generic", [sm.x, sm.u, sm.p], [ca.solve(sm.eom.M, sm.eom.rhs)])
    rng = np.random.default_rng(3)
    worst = 0.0
    for _ in range(300):
        x = np.concatenate([rng.uniform(-np.pi, np.pi, 2), rng.uniform(0.3, 2.0, 2), rng.normal(0.0, 5.0, 4)])
        u = rng.normal(0.0, 3.0, 2)
        # m1, m2, L1, L2, g, b1, b2, k1, k2, c1, c2: masses and lengths away from zero, soft to stiff springs.
        p = np.concatenate(
            [rng.uniform(0.2, 3.0, 4), [9.81], rng.uniform(0, 1, 2), rng.uniform(10, 1e5, 2), rng.uniform(0, 1, 2)]
        )
        a, b = np.asarray(factored(x, u, p)).ravel(), np.asarray(generic(x, u, p)).ravel()
        worst = max(worst, float(np.max(np.abs(a - b)) / np.max(np.abs(b))))
    assert worst < 1e-11, worst  # the same equations: rounding only (two orders of summation, stiff springs)
    assert factored.n_instructions() < 0.5 * generic.n_instructions()  # the point of the factorisation


def test_bodies_that_are_not_a_chain_are_refused():
    q, qd = ca.SX.sym("q", 4), ca.SX.sym("qd", 4)
    m = ca.SX.sym("m")
    first = q[1] * ca.vertcat(ca.sin(q[0]), -ca.cos(q[0]))
    second = first + q[3] * ca.vertcat(ca.sin(q[2]), -ca.cos(q[2]))
    applied = ca.SX.zeros(4, 1)
    with pytest.raises(ValueError, match="not a chain"):
        point_mass_accelerations(q, qd, [(m, second, (2, 3)), (m, first, (0, 1))], applied)
    with pytest.raises(ValueError, match="cover q once"):
        point_mass_accelerations(q, qd, [(m, first, (0, 1)), (m, second, (1, 3))], applied)
    assert point_mass_accelerations(q, qd, [(m, first, (0, 1)), (m, second, (2, 3))], applied).shape == (4, 1)

"""The CasADi -> heyoka translation: its exact rewrites and the cost of the elastic model's Taylor step.

A Taylor step costs O(order^2) per product, quotient or sine/cosine pair of two series and O(order)
per sum or scaling by a parameter, so the counts below are by kind, against the hand-written elastic
equations of ``benchmarks/bench_fastpath.py`` (``hand_written_elastic``: 51 decomposition entries,
2 divisions, 2 sine/cosine pairs, 10 products of two series).
"""

from __future__ import annotations

import re
from collections import Counter

import casadi as ca
import numpy as np
import pytest

import pendulab as pl

hy = pytest.importorskip("heyoka")

from pendulab.integrate import taylor  # noqa: E402

_U = re.compile(r"u_(\d+)")


def decomposition_kinds(ta: object, n: int) -> Counter:
    """Entries of heyoka's Taylor decomposition between the ``n`` variables and the ``n`` outputs, by kind.

    Every ``u_i`` is a Taylor series to heyoka, also one that depends on parameters only (such as
    ``-par``): a product or quotient with it as an operand is a full series operation.

    Parameters
    ----------
    ta : heyoka.taylor_adaptive
        A compiled integrator.
    n : int
        Number of state variables.

    Returns
    -------
    collections.Counter
        ``"product"`` (of two series), ``"division"`` (by a series), ``"sincos"`` (one sine/cosine
        pair), ``"pow"``, ``"parameter-only"`` (a series of parameters and numbers only), ``"other"``
        (sums, scalings by a parameter or a number).
    """
    dec = ta.decomposition
    constant: set[int] = set()  # u indices that depend on parameters and numbers only
    kinds: Counter = Counter()
    for k, (expr, _) in enumerate(dec[n : len(dec) - n]):
        s = str(expr)
        us = [int(i) for i in _U.findall(s)]
        if all(i in constant for i in us):
            constant.add(n + k)
            kinds["parameter-only"] += 1
        elif s.startswith("combined_sin"):
            kinds["sincos"] += 1
        elif s.startswith("combined_cos"):
            pass  # counted with its sine
        elif s.startswith("div("):
            kinds["division" if s[4:-1].split(", ")[1].startswith("u_") else "other"] += 1
        elif "**" in s:
            kinds["pow"] += 1
        elif " * " in s and len(us) == 2:
            kinds["product"] += 1
        else:
            kinds["other"] += 1
    return kinds


def test_elastic_step_costs_as_much_as_the_hand_written_equations():
    model = pl.elastic()
    key = taylor.structure_key("elastic", model.p, (0, 1), 1e-12)  # the unforced run (the elastic tests' structure)
    system, ta = taylor.compiled_integrator(key)
    kinds = decomposition_kinds(ta, model.nx)
    # Before the reciprocal cancellation, the canonical angles, the offsets and the hoisted opposite
    # coefficients: 130 entries, 16 divisions, 5 sine/cosine pairs (theta1 - theta2 three times under
    # different expressions), 35 products (7 of them by a -par series), 5 parameter-only entries.
    assert kinds["division"] == 2, kinds  # omega1' and omega2' over r1 and r2, once each
    assert kinds["sincos"] == 2, kinds  # theta1 and theta1 - theta2; gravity on bob 2 cancels
    assert kinds["product"] <= 10, kinds
    assert kinds["pow"] == 0, kinds
    assert kinds["parameter-only"] == 0, kinds  # heyoka takes -par for a series: (-par) * x is a product
    assert len(ta.decomposition) <= 51
    # The spring forces k (r - L) keep the stretch: the offsets are -L1 and -L2 exactly, not (k L) / k.
    derived = system.derived(pl.elastic(L1=0.9, L2=1.1, k1=300.0, k2=700.0).p)  # same structure, other values
    assert -0.9 in derived and -1.1 in derived


@pytest.mark.parametrize(
    "params, zero_inputs",
    [
        ({}, (0, 1)),
        ({}, ()),
        ({"m1": 1.3, "m2": 0.7, "L1": 0.9, "L2": 1.1, "b1": 0.2, "b2": 0.1, "k1": 300.0, "k2": 800.0, "c1": 0.5, "c2": 0.3}, ()),
    ],
    ids=["unforced", "torques", "every-term"],
)
def test_translated_elastic_rhs_equals_casadi_rhs(params, zero_inputs):
    model = pl.elastic(**params)
    zero_p = tuple(int(i) for i in np.flatnonzero(model.p == 0.0))
    system = taylor.translate(model.functions["rhs"], zero_params=zero_p, zero_inputs=zero_inputs, state_names=model.state_names)
    f = hy.cfunc([e for _, e in system.sys], list(hy.make_vars(*model.state_names)))
    rng = np.random.default_rng(7)
    n = 200
    X = np.column_stack([rng.uniform(-np.pi, np.pi, (n, 2)), rng.uniform(0.8, 1.2, (n, 2)), rng.normal(0.0, 4.0, (n, 4))])
    U = rng.normal(0.0, 2.0, (n, 2))
    U[:, list(zero_inputs)] = 0.0
    got = np.array([f(x, pars=system.pars(u, model.p)) for x, u in zip(X, U, strict=True)])
    want = np.asarray(model.rhs(X, U))
    # Reassociated, same terms: a few ulps of the largest term. Measured 1.5e-14, 1.6e-14 and 5.6e-14 for
    # the three cases; CasADi's own double evaluation is 1.5e-14, 0.9e-14 and 5.6e-14 from a 40-digit
    # one (the every-term case cancels large spring and damper terms). A wrong rewrite is O(1).
    rel = np.abs(got - want) / np.maximum(np.abs(want), 1.0)
    assert rel.max() < 1e-13


def test_exact_rewrites_on_a_small_graph():
    x, u, p = ca.SX.sym("x", 4), ca.SX.sym("u", 1), ca.SX.sym("p", 2)
    a, b, r, w = ca.vertsplit(x)
    k, L = ca.vertsplit(p)
    xdot = ca.vertcat(
        r * ((w * r) / (r * r)),  # = w: reciprocals cancel against their factor
        ca.sin(a) * ca.cos(b) - ca.cos(a) * ca.sin(b) + ca.cos((a - b) - a + b),  # = sin(a - b) + 1
        ca.sin(b - a) + ca.sin(a - b) + k * r - k * L,  # = k (r - L)
        u * ca.cos(a - b) / r + w * w / r,  # one division by r
    )
    f = ca.Function("f", [x, u, p], [xdot])
    system = taylor.translate(f, state_names=["a", "b", "r", "w"])
    rhs = [str(e) for _, e in system.sys]
    assert rhs[0] == "w"
    assert rhs[1].count("sin(") == 1 and "cos(" not in rhs[1]  # cos(0) = 1; one angle a - b
    assert "sin(" not in rhs[2] and len(re.findall(r"\br\b", rhs[2])) == 1
    assert rhs[3].count("/") == 1
    pars = [3.7, 0.3]
    assert -0.3 in system.derived(pars)  # the offset is -L itself, not the rounded quotient (k L) / k
    fn = hy.cfunc([e for _, e in system.sys], list(hy.make_vars("a", "b", "r", "w")))
    rng = np.random.default_rng(2)
    for _ in range(20):
        xv, uv = rng.uniform(-3.0, 3.0, 4), rng.normal(size=1)
        xv[2] = rng.uniform(0.5, 2.0)
        want = np.asarray(f(xv, uv, pars)).ravel()
        np.testing.assert_allclose(fn(xv, pars=system.pars(uv, pars)), want, rtol=1e-14, atol=1e-14)

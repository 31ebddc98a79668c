"""The CasADi right-hand sides against an independent SymPy derivation.

The reference is built with ``sympy.physics.mechanics``: particles and rigid
bodies (links, and a robot's geared motor rotors) placed in an inertial frame, gravity, springs, dampers and the joint
torques applied as *forces and torques* (``LagrangesMethod`` with the kinetic
energy alone as Lagrangian). pendulab instead builds T, V and a Rayleigh
function and differentiates them in CasADi, so the two paths share only the
geometry conventions (absolute angles from the downward vertical, y up).
"""

from functools import cache

import numpy as np
import pytest
import sympy as sp
from sympy.physics import mechanics as me

import pendulab as pl

# Accelerations of order 1e2 are formed by a 2x2 / 4x4 solve in both paths:
# round-off is ~1e-14 relative, so 1e-10 relative (floor 1 m/s^2, rad/s^2) has margin.
RTOL = 1e-10
N_SAMPLES = 25


def _torque_loads(N, A, B, tau1, tau2, b1, b2, w1, w2, cf1=0, cf2=0):
    """Joint 1 (ground-link 1) and joint 2 (link 1-link 2): actuator, damper and Coulomb friction
    (RealAIGym's smoothed ``cf atan(100 q')``), action and reaction."""
    joint1 = tau1 - b1 * w1 - cf1 * sp.atan(100 * w1)
    joint2 = tau2 - b2 * (w2 - w1) - cf2 * sp.atan(100 * (w2 - w1))
    return [(A, (joint1 - joint2) * N.z), (B, joint2 * N.z)]


@cache
def _reference(kind):
    """Lambdified (M, forcing) of the SymPy model: M(q, p) qdd = F(q, qd, u, p)."""
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    th1, th2 = me.dynamicsymbols("th1 th2")
    w1, w2 = th1.diff(t), th2.diff(t)
    tau1, tau2 = sp.symbols("tau1 tau2")
    A = N.orientnew("A", "Axis", [th1, N.z])
    B = N.orientnew("B", "Axis", [th2, N.z])
    e1 = sp.sin(th1) * N.x - sp.cos(th1) * N.y
    e2 = sp.sin(th2) * N.x - sp.cos(th2) * N.y
    if kind == "rigid":
        m1, m2, L1, L2, g, b1, b2, lc1, lc2, I1, I2, Ir, gr, cf1, cf2 = p = sp.symbols(
            "m1 m2 L1 L2 g b1 b2 lc1 lc2 I1 I2 Ir gr cf1 cf2"
        )
        q = [th1, th2]
        G1 = O.locatenew("G1", lc1 * e1)
        J = O.locatenew("J", L1 * e1)
        G2 = J.locatenew("G2", lc2 * e2)
        for P in (G1, G2, J):
            P.set_vel(N, P.pos_from(O).dt(N))
        link1 = me.RigidBody("link1", G1, A, m1, (me.inertia(A, 0, 0, I1), G1))
        link2 = me.RigidBody("link2", G2, B, m2, (me.inertia(B, 0, 0, I2), G2))
        # Geared motor rotors (their mass is in the links'): rotor 1 on the ground turns at gr th1';
        # rotor 2 on link 1 turns through a reversing gear at th1' - gr (th2' - th1') (RealAIGym's M_r).
        R1 = N.orientnew("R1", "Axis", [gr * th1, N.z])
        R2 = N.orientnew("R2", "Axis", [th1 - gr * (th2 - th1), N.z])
        rotor1 = me.RigidBody("rotor1", O, R1, 0, (me.inertia(R1, 0, 0, Ir), O))
        rotor2 = me.RigidBody("rotor2", J, R2, 0, (me.inertia(R2, 0, 0, Ir), J))
        bodies = [link1, link2, rotor1, rotor2]
        loads = [(G1, -m1 * g * N.y), (G2, -m2 * g * N.y)]
        friction = (cf1, cf2)
    else:
        m1, m2, L1, L2, g, b1, b2, k1, k2, c1, c2 = p = sp.symbols("m1 m2 L1 L2 g b1 b2 k1 k2 c1 c2")
        r1, r2 = me.dynamicsymbols("r1 r2")
        q = [th1, th2, r1, r2]
        P1 = O.locatenew("P1", r1 * e1)
        P2 = P1.locatenew("P2", r2 * e2)
        for P in (P1, P2):
            P.set_vel(N, P.pos_from(O).dt(N))
        bodies = [me.Particle("bob1", P1, m1), me.Particle("bob2", P2, m2)]
        friction = (0, 0)
        # Spring + dashpot tension along each link (positive = pulling the bob back).
        s1 = k1 * (r1 - L1) + c1 * r1.diff(t)
        s2 = k2 * (r2 - L2) + c2 * r2.diff(t)
        loads = [
            (P1, -m1 * g * N.y - s1 * e1 + s2 * e2),
            (P2, -m2 * g * N.y - s2 * e2),
        ]
    loads += _torque_loads(N, A, B, tau1, tau2, b1, b2, w1, w2, *friction)
    T = sum(body.kinetic_energy(N) for body in bodies)
    lm = me.LagrangesMethod(T, q, forcelist=loads, frame=N)
    lm.form_lagranges_equations()
    qd = [qi.diff(t) for qi in q]
    # Plain symbols for lambdify (derivatives before their functions).
    xs = sp.symbols(f"x0:{2 * len(q)}")
    subs = dict(zip(qd, xs[len(q) :], strict=True)) | dict(zip(q, xs[: len(q)], strict=True))
    M = sp.Matrix(lm.mass_matrix).subs(subs)
    F = sp.Matrix(lm.forcing).subs(subs)
    args = (xs, (tau1, tau2), p)
    return sp.lambdify(args, M, "numpy"), sp.lambdify(args, F, "numpy")


def _random_case(rng, kind):
    """A random state, input and parameter set (all parameters active)."""
    if kind == "rigid":
        L1, L2 = rng.uniform(0.3, 2.0, 2)
        params = dict(
            m1=rng.uniform(0.2, 3.0), m2=rng.uniform(0.2, 3.0), L1=L1, L2=L2, g=rng.uniform(1.0, 12.0),
            b1=rng.uniform(0.0, 0.5), b2=rng.uniform(0.0, 0.5),
            lc1=rng.uniform(0.1, 1.0) * L1, lc2=rng.uniform(0.1, 1.0) * L2,
            I1=rng.uniform(0.0, 0.3), I2=rng.uniform(0.0, 0.3),
            Ir=rng.uniform(0.0, 0.01), gr=rng.uniform(1.0, 10.0), cf1=rng.uniform(0.0, 0.5), cf2=rng.uniform(0.0, 0.5),
        )  # fmt: skip
        x = np.concatenate([rng.uniform(-np.pi, np.pi, 2), rng.uniform(-5.0, 5.0, 2)])
    else:
        params = dict(
            m1=rng.uniform(0.2, 3.0), m2=rng.uniform(0.2, 3.0), L1=rng.uniform(0.3, 2.0), L2=rng.uniform(0.3, 2.0),
            g=rng.uniform(1.0, 12.0), b1=rng.uniform(0.0, 0.5), b2=rng.uniform(0.0, 0.5),
            k1=rng.uniform(10.0, 2000.0), k2=rng.uniform(10.0, 2000.0), c1=rng.uniform(0.0, 2.0), c2=rng.uniform(0.0, 2.0),
        )  # fmt: skip
        x = np.concatenate(
            [
                rng.uniform(-np.pi, np.pi, 2),
                [params["L1"], params["L2"]] * rng.uniform(0.7, 1.3, 2),
                rng.uniform(-5.0, 5.0, 2),
                rng.uniform(-2.0, 2.0, 2),
            ]
        )
    u = rng.uniform(-3.0, 3.0, 2)
    return pl.make_model(kind, **params), x, u


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_rhs_matches_sympy_mechanics(kind):
    M_fun, F_fun = _reference(kind)
    rng = np.random.default_rng(20260521 if kind == "rigid" else 7)
    worst = 0.0
    for _ in range(N_SAMPLES):
        model, x, u = _random_case(rng, kind)
        p = model.p
        qdd_ref = np.linalg.solve(np.asarray(M_fun(x, u, p), float), np.asarray(F_fun(x, u, p), float).ravel())
        xdot = model.rhs(x, u)
        nq = model.nq
        np.testing.assert_array_equal(xdot[:nq], x[nq:])  # qdot is the velocity part, exactly
        err = np.max(np.abs(xdot[nq:] - qdd_ref) / np.maximum(1.0, np.abs(qdd_ref)))
        worst = max(worst, err)
        # The mass matrix is an independent output of both paths (the Hessian of T in CasADi).
        M_ca = model.mass_matrix(x)
        np.testing.assert_allclose(M_ca, np.asarray(M_fun(x, u, p), float), rtol=1e-12, atol=1e-12)
    assert worst < RTOL, f"largest relative acceleration mismatch {worst:.3e}"


def test_reference_is_sensitive_to_the_physics():
    """The comparison can fail: a mis-signed joint damper in the model would be caught."""
    M_fun, F_fun = _reference("rigid")
    rng = np.random.default_rng(3)
    model, x, u = _random_case(rng, "rigid")
    model = model.with_params(b2=0.4)
    wrong = model.with_params(b2=0.0)  # the model without the joint-2 damper
    p = model.p
    qdd_ref = np.linalg.solve(np.asarray(M_fun(x, u, p), float), np.asarray(F_fun(x, u, p), float).ravel())
    assert np.max(np.abs(wrong.rhs(x, u)[2:] - qdd_ref)) > 1e-3  # a 0.4 N.m.s damper at |dw| ~ 1 rad/s


def test_reference_sees_the_rotors_and_the_friction():
    """A model that dropped the rotor inertia or the Coulomb friction would be caught too."""
    M_fun, F_fun = _reference("rigid")
    model, x, u = _random_case(np.random.default_rng(5), "rigid")
    model = model.with_params(Ir=0.005, gr=6.0, cf1=0.3, cf2=0.2)
    qdd_ref = np.linalg.solve(np.asarray(M_fun(x, u, model.p), float), np.asarray(F_fun(x, u, model.p), float).ravel())
    assert np.max(np.abs(model.rhs(x, u)[2:] - qdd_ref) / np.maximum(1.0, np.abs(qdd_ref))) < RTOL
    for dropped in ({"Ir": 0.0}, {"cf1": 0.0}, {"cf2": 0.0}):
        # gr^2 Ir = 0.18 kg m^2 against link inertias of ~0.1-1; 0.2-0.3 N m of friction at |w| ~ 1-5 rad/s
        assert np.max(np.abs(model.with_params(**dropped).rhs(x, u)[2:] - qdd_ref)) > 1e-3, dropped

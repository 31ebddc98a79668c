"""The regression is the robot's own Lagrangian: linear, equal to forward dynamics, base parameters as analysed by hand."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.identify.published import C1_GEOMETRY, DFKI_C1
from pendulab.identify.regressor import STANDARD_NAMES, base_parameters, regressor_function, robot_to_standard, standard_to_robot
from pendulab.model.robot import check_robot_params, robot_inverse_dynamics, robot_params_vector, robot_rhs

FIXED = [C1_GEOMETRY[k] for k in ("l1", "l2", "g", "gr")]


def _random_standard(rng):
    pi = robot_to_standard(
        {
            **DFKI_C1["1.0"],
            **{k: v * rng.uniform(0.5, 1.5) for k, v in DFKI_C1["1.0"].items() if k in ("b1", "b2", "cf1", "cf2", "Ir")},
            "m1": rng.uniform(0.3, 0.75),
        }
    )  # I1 >= m1 r1^2 needs m1 <= 0.797 kg
    pi["o1"], pi["o2"] = rng.normal(0, 0.05, 2)
    return pi


def test_regressor_times_parameters_is_the_inverse_dynamics():
    rng = np.random.default_rng(1)
    Y = regressor_function()
    ID = robot_inverse_dynamics()
    for _ in range(20):
        pi = _random_standard(rng)
        q, qd, qdd = rng.normal(0, 2, 2), rng.normal(0, 5, 2), rng.normal(0, 20, 2)
        vec = np.array([pi[n] for n in STANDARD_NAMES])
        direct = np.asarray(ID(q, qd, qdd, robot_params_vector(standard_to_robot(pi, C1_GEOMETRY)))).ravel() + vec[-2:]
        # 1e-12 relative: the two paths differ only by round-off of the same symbolic graph
        assert np.asarray(Y(q, qd, qdd, FIXED)) @ vec == pytest.approx(direct, rel=1e-10, abs=1e-12)


def test_inverse_dynamics_inverts_the_forward_dynamics():
    rng = np.random.default_rng(2)
    p = robot_params_vector(DFKI_C1["1.0"])
    for _ in range(20):
        th, om, tau = rng.normal(0, 2, 2), rng.normal(0, 5, 2), rng.normal(0, 3, 2)
        xd = np.asarray(robot_rhs()(np.r_[th, om], tau, p)).ravel()
        q = np.array([th[0], th[1] - th[0]])
        qd = np.array([om[0], om[1] - om[0]])
        qdd = np.array([xd[2], xd[3] - xd[2]])
        # round-off of a 2x2 solve and its inverse
        assert np.asarray(robot_inverse_dynamics()(q, qd, qdd, p)).ravel() == pytest.approx(tau, abs=1e-12)


def test_hanging_at_rest_needs_only_the_offsets_and_a_tilted_link_its_gravity_torque():
    Y = np.asarray(regressor_function()([0.0, 0.0], [0.0, 0.0], [0.0, 0.0], FIXED))
    pi = np.array([robot_to_standard(DFKI_C1["1.0"])[n] for n in STANDARD_NAMES])
    assert Y @ pi == pytest.approx([0.0, 0.0], abs=1e-15)
    # Link 1 horizontal, link 2 hanging straight down (q2 = -pi/2): the shoulder holds (m1 r1 + m2 l1) g.
    Y = np.asarray(regressor_function()([np.pi / 2, -np.pi / 2], [0.0, 0.0], [0.0, 0.0], FIXED))
    p = DFKI_C1["1.0"]
    assert (Y @ pi)[0] == pytest.approx((p["m1"] * p["r1"] + p["m2"] * p["l1"]) * p["g"], rel=1e-12)


def test_base_parameters_are_the_combinations_found_by_hand():
    rng = np.random.default_rng(3)
    rows = np.concatenate(
        [
            np.asarray(regressor_function()(rng.normal(0, 1, 2), rng.normal(0, 3, 2), rng.normal(0, 9, 2), FIXED))
            for _ in range(200)
        ]
    )
    order = ["h1", "I1", "h2", "I2", "Ir", "b1", "b2", "cf1", "cf2", "o1", "o2", "m2", "m1"]
    base = base_parameters(rows[:, [STANDARD_NAMES.index(n) for n in order]], order)
    # m2 enters only as h1 + l1 m2 and I1 + l1^2 m2; m1 not at all (h1 and I1 already carry link 1).
    assert base.independent == ("h1", "I1", "h2", "I2", "Ir", "b1", "b2", "cf1", "cf2", "o1", "o2")
    assert base.dependent == ("m2", "m1")
    assert base.K[0] == pytest.approx([0.2, 0.0], abs=1e-9)  # l1 = 0.2 m
    assert base.K[1] == pytest.approx([0.04, 0.0], abs=1e-9)  # l1^2
    assert base.names[:2] == ("h1 + 0.2 m2", "I1 + 0.04 m2")


def test_unphysical_robot_parameters_are_refused():
    good = dict(DFKI_C1["1.0"])
    with pytest.raises(ValueError, match="I1 .* below m1 r1\\^2"):
        check_robot_params({**good, "I1": 0.5 * good["m1"] * good["r1"] ** 2})
    with pytest.raises(ValueError, match=r"\['m2'\] must be > 0"):
        check_robot_params({**good, "m2": 0.0})
    with pytest.raises(ValueError, match=r"\['cf1'\] must be >= 0"):
        check_robot_params({**good, "cf1": -0.1})
    with pytest.raises(ValueError, match="must be finite"):
        check_robot_params({**good, "b1": float("nan")})
    with pytest.raises(KeyError, match="unknown names \\['k1'\\]"):
        check_robot_params({**good, "k1": 1.0})


@pytest.mark.parametrize("name", ["2.0", "3.0"])
def test_dfki_sets_2_and_3_are_physically_inconsistent(name):
    # Their link-2 inertia about the elbow is below m2 r2^2: a negative inertia about the centre of mass.
    # pendulab's fit constrains this away; the validation still judges these sets as published.
    with pytest.raises(ValueError, match="I2 .* below m2 r2\\^2"):
        check_robot_params(DFKI_C1[name])


def test_open_loop_segments_of_the_true_model_follow_a_synthetic_record():
    """The open-loop predictions the figures draw: the model that made the record predicts it, a wrong one does not."""
    from conftest import synthetic_record, true_vector

    from pendulab.identify.preprocess import prepare
    from pendulab.identify.simulate import open_loop_segments

    prep = prepare(synthetic_record(3, duration=4.0))

    def worst_error(pi):
        segments = open_loop_segments(prep, pi, C1_GEOMETRY, every=1.0, length=0.25)
        assert len(segments) >= 2 and all(q.shape == (2, t.size) for t, q in segments)
        measured = [np.column_stack([np.interp(t, prep.t, prep.q[:, j]) for j in (0, 1)]) for t, _ in segments]
        return max(float(np.max(np.abs(q.T - m))) for (_, q), m in zip(segments, measured, strict=True))

    wrong = true_vector().copy()
    wrong[STANDARD_NAMES.index("I1")] *= 1.3  # the shoulder link's inertia 30 % too large
    right, off = worst_error(true_vector()), worst_error(wrong)
    # From filtered start states under 0.01 N.m torque-reading noise, 0.25 s ahead: measured 1.9e-3 rad for the
    # truth against 4.6e-3 for the wrong inertia; 3e-3 lies between, with margin on both sides.
    assert right < 3e-3 < off, (right, off)

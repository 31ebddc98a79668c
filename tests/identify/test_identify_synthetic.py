"""Known parameters come back from data the model generated with C.1's quantization, timing and noise."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.identify.fit import normals
from pendulab.identify.pipeline import compare_structures, identify
from pendulab.identify.preprocess import prepare
from pendulab.identify.published import C1_GEOMETRY, DFKI_C1
from pendulab.identify.regressor import robot_to_standard

# A prior that is wrong by 20-40 % (as a CAD model would be): recovery must come from the data.
PRIOR = {**robot_to_standard({**DFKI_C1["1.0"], "m2": 0.45, "r2": 0.3, "I2": 0.06, "cf1": 0.1, "b1": 0.01}), "o1": 0.0, "o2": 0.0}


@pytest.fixture(scope="module")
def result(synthetic_records):
    return identify(synthetic_records, C1_GEOMETRY, PRIOR, structure="+offset")


def test_base_parameters_recovered_within_their_intervals(result, synthetic_truth):
    params, offset = synthetic_truth
    truth = {**robot_to_standard(params), "o1": offset[0], "o2": offset[1]}
    beta_true = result.base.beta(truth)
    se = result.output_error.stderr()
    z = np.abs(result.output_error.beta - beta_true) / se
    # 3 standard errors: a 99.7 % interval, so eleven parameters pass together by chance with 97 %
    assert (z < 3.0).all(), dict(zip(result.base.names, z.round(2).tolist(), strict=True))
    # and the intervals are informative, not huge: every inertial combination to better than 5 %
    for name, b, s in zip(result.base.names, beta_true, se, strict=True):
        if name.split()[0] in ("h1", "I1", "h2", "I2"):
            assert s < 0.05 * abs(b), name


def test_the_plant_file_parameters_are_physical_and_reproduce_the_motion(result, synthetic_records):
    plant = result.plant
    assert plant.params["I2"] >= plant.params["m2"] * plant.params["r2"] ** 2
    # The identified model predicts held-in motion to a few encoder steps after 0.25 s.
    from pendulab.identify.simulate import prediction_errors

    prep = prepare(synthetic_records[0])
    err = prediction_errors(prep, result.vector(), C1_GEOMETRY, (0.25,))
    assert np.sqrt((err**2).mean()) < 5e-3  # rad; quantization 3.8e-4 and torque noise 0.01 N.m drive a few mrad


def test_structure_comparison_needs_coulomb_when_the_truth_has_it(synthetic_records):
    preps = [prepare(r) for r in synthetic_records]
    scores = {s.name: s for s in compare_structures([normals(p, C1_GEOMETRY) for p in preps], preps, C1_GEOMETRY, PRIOR, 8.0)}
    # The truth has Coulomb friction of 0.12-0.16 N.m: leaving it out must cost held-out error.
    assert scores["+coulomb"].cv_score < 0.8 * scores["+viscous"].cv_score
    assert scores["+coulomb"].bic < scores["+viscous"].bic


def test_bad_arguments(synthetic_records):
    with pytest.raises(ValueError, match="structure must be 'auto' or one of"):
        identify(synthetic_records, C1_GEOMETRY, PRIOR, structure="+magic")
    with pytest.raises(ValueError, match="at least two records"):
        identify(synthetic_records[:1], C1_GEOMETRY, PRIOR)

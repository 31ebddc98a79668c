"""A run that diverges under feedback fails as a run (SimulationError), never as the caller's bad feedback.

Found by the property fuzz: the elastic model under rk4 with 0.125 s steps (too long for its springs) became non-finite,
the feedback turned that state into a NaN torque, and the run was reported as ``ValueError: feedback u(t, x) ...
returned an invalid torque`` -- the user's feedback blamed for the integration's failure. The class: every method,
with the state checked once where all of them sample the feedback (``RunSpec.feedback_input``).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pendulab as pl
from pendulab.integrate.registry import SimulationError

#: The fuzz's falsifying start: springs at their hanging lengths, link 2 moving at 1 rad/s.
X0 = np.array([0.0, 0.0, 1.03924, 1.01962, 0.0, 1.0, 0.0, 0.0])


@pytest.mark.parametrize("method", list(pl.METHODS))
def test_feedback_never_sees_a_diverged_state(method):
    seen: list[np.ndarray] = []

    def feedback(t: float, x: np.ndarray) -> list[float]:
        seen.append(np.array(x))
        return [x[0], -x[1]]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # step-size advice of the fixed-step families
        try:
            tr = pl.simulate(pl.elastic(), X0, 1.0, 0.25, method, 1e-3, 1e-3, feedback, max_step=0.125)
        except SimulationError as exc:
            assert "failed at t =" in str(exc)  # the run's own error: method, time reached, reason
        else:
            assert np.isfinite(tr.x).all()
    assert seen and all(np.isfinite(x).all() for x in seen)


def test_a_diverging_fixed_step_run_names_the_divergence():
    with pytest.raises(SimulationError, match=r"'rk4' failed at t = 0\.75 s of 1 s: the state became non-finite"):
        pl.simulate(pl.elastic(), X0, 1.0, 0.25, "rk4", u=lambda t, x: [x[0], -x[1]], max_step=0.125)

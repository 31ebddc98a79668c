"""Every CasADi family's failure path ends in a SimulationError naming the method and the time reached.

The work-precision study crashed with ``Unknown option: disable_internal_warnings``: the error path
re-ran a failed collocation interval with a SUNDIALS-only option. Each method of the registry that
uses the CasADi runner is forced to fail cheaply here (stiff springs, a tiny step or Newton budget).
"""

import pytest

import pendulab as pl
from pendulab.integrate import SimulationError
from pendulab.integrate.casadi_methods import run_casadi
from pendulab.integrate.methods import METHODS

CASADI_METHODS = [name for name, spec in METHODS.items() if spec.runner is run_casadi]


def _forcing_options(name: str) -> dict:
    """Options that make the method fail within its first output interval (no long run needed)."""
    if METHODS[name].fixed_step:
        return {"rootfinder_options": {"max_iter": 1}}  # one Newton iteration cannot solve a 1e6 N/m step
    return {"max_num_steps": 3}  # SUNDIALS' per-interval step limit: 3 steps cannot cover 10 ms at k = 1e6


def test_every_casadi_family_is_covered():
    plugins = {METHODS[n].settings["plugin"] for n in CASADI_METHODS}
    # The three CasADi plugins the runner knows; a new one must be added to _forcing_options.
    assert plugins == {"cvodes", "idas", "collocation"}


@pytest.mark.parametrize("name", CASADI_METHODS)
def test_failure_is_a_simulation_error_naming_method_and_time(name):
    m = pl.elastic(k1=1e6, k2=1e6)
    with pytest.raises(SimulationError) as info:
        pl.simulate(m, m.state(theta1=0.3, theta2=0.3), 0.1, dt=0.01, method=name, options=_forcing_options(name))
    msg = str(info.value)
    assert "Unknown option" not in msg
    assert f"method {name!r} failed at t = " in msg
    assert info.value.method == name
    # The failure happens within the first output interval (the forcing allows no more).
    assert 0.0 <= info.value.t_reached <= 0.01


def test_issue_reproducer_collocation_radau():
    m = pl.elastic(k1=1e6, k2=1e6)
    with pytest.raises(SimulationError, match=r"method 'collocation-radau' failed at t = .* of 2 s") as info:
        pl.simulate(
            m,
            m.state(theta1=0.3, theta2=0.3),
            2.0,
            dt=0.002,
            method="collocation-radau",
            options={"rootfinder_options": {"max_iter": 1}},
        )
    # Collocation's hint points at its own step, not at "use collocation".
    assert "smaller collocation step" in str(info.value)

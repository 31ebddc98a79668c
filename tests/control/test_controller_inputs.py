"""Controller inputs that would make a useless or harmful controller are refused where they enter (issue 31).

Found: ``fmu export-controller --controller lqr --u-max 0`` (or -5), ``--sample-time 1e9`` and ``1e-9`` wrote
FMUs without complaint. The class: a torque limit that drives nothing, a sample time the plant's unstable
mode outruns, and one that costs 1e7 calls per step. The one entry of named controllers checks them.
"""

from __future__ import annotations

import pytest

import pendulab as pl
from pendulab.cli import main
from pendulab.control.controllers import (
    MAX_UNSTABLE_GROWTH,
    MIN_SAMPLE_TIME,
    check_sample_time,
    controller_for_task,
    make_controller,
)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--controller", "lqr", "--u-max", "0"], "--u-max = '0': out of range; expected a finite number in (0, 10000] N.m"),
        (["--controller", "swingup", "--u-max", "-5"], "--u-max = '-5': out of range"),
        (
            ["--controller", "lqr", "--sample-time", "1e9"],
            "--sample-time = '1e9': out of range; expected a finite number in [1e-05, 10] s",
        ),
        (["--controller", "lqr", "--sample-time", "1e-9"], "--sample-time = '1e-9': out of range"),
        (["--controller", "lqr", "--sample-time", "1"], "sample_time must be in [1e-05, 0.346] s"),  # the model's own bound
        (["--controller", "lqr", "--task", "pendubot", "--sample-time", "1"], "sample_time must be in [1e-05, 0.215] s"),
    ],
)
def test_export_controller_refuses_useless_controllers(argv, message, tmp_path, capsys):
    out = tmp_path / "c.fmu"
    assert main(["fmu", "export-controller", *argv, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()  # nothing written


def test_the_longest_sample_time_follows_the_unstable_rate():
    model = pl.rigid()
    # upright rigid default: the unstable mode's rate is sqrt((2 + sqrt 2) g) = 5.787 1/s (equal masses, lengths 1 m)
    rate = ((2 + 2**0.5) * 9.81) ** 0.5
    longest = MAX_UNSTABLE_GROWTH / rate
    assert check_sample_time(model, longest * (1 - 1e-9)) == pytest.approx(longest)
    with pytest.raises(ValueError, match="fastest unstable rate"):
        check_sample_time(model, longest * (1 + 1e-6))
    assert check_sample_time(model, MIN_SAMPLE_TIME) == MIN_SAMPLE_TIME
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="sample_time"):
            make_controller("lqr", model, bad)
    with pytest.raises(ValueError, match="sample_time must be in"):
        controller_for_task("swingup", "acrobot", sample_time=1.0)

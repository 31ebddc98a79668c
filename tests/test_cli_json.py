"""``--json``: one summary object on stdout and nothing else (strict JSON: no NaN), for the commands of this area.

``fmu export`` / ``fmu validate`` are covered in tests/fmu/test_fmu_cli.py, ``demo`` in tests/test_scene_inputs.py.
"""

from __future__ import annotations

import json

import pytest

from pendulab.cli import main


def _strict(text: str) -> dict:
    def refuse(name: str) -> None:
        raise ValueError(f"non-standard JSON constant {name} on stdout")

    return json.loads(text, parse_constant=refuse)


@pytest.mark.parametrize(
    "args, key",
    [
        (["simulate", "--scene", "validation/rigid_forced", "--t-final", "0.5", "--json"], "energy_balance_error_J"),
        (["simulate", "--scene", "elastic_stiff", "--model", "auto", "--t-final", "0.3", "--json"], "model_level"),
        (["modes", "--model", "elastic", "--torque", "1,0", "--json"], "equilibria"),
        (["scene", "check", "stiff_small_amplitude", "--json"], "chosen"),
    ],
)
def test_json_is_one_object_on_stdout(args, key, capsys):
    assert main(args) == 0
    out = capsys.readouterr().out
    data = _strict(out)  # the whole of stdout parses: nothing printed besides the object
    assert isinstance(data, dict) and key in data

"""Issue 15 (reliability): bad inputs fail loudly, in one line, with the documented exception type.

Scene files with a misspelt section, unreadable FMUs on the CLI, a non-model where a
model is expected, options a method does not know, and a linearization point that
is not an equilibrium where one is needed.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest

import pendulab as pl
from pendulab.cli import main
from pendulab.control import lqr_balance, to_statespace
from pendulab.control.bridge import to_nlsys
from pendulab.control.lqr import discrete_tvlqr
from pendulab.scene import list_scenes, load_scene
from pendulab.scene.core import FEATURE_SECTIONS

SCENE = "[model]\nkind = 'rigid'\n\n"


# -- 1. scene files: unknown top-level sections ------------------------------------------
def test_misspelt_section_is_an_error_naming_file_section_and_known_sections(tmp_path):
    path = tmp_path / "typo.toml"
    path.write_text(SCENE + "[simulaton]\nt_final = 1\n", encoding="utf-8")
    with pytest.raises(ValueError) as exc:
        load_scene(path)
    msg = str(exc.value)
    assert str(path) in msg and "[simulaton]" in msg
    assert "'simulation'" in msg and "'task'" in msg and "'validation'" in msg  # the known sections
    assert "\n" not in msg


@pytest.mark.parametrize("section", FEATURE_SECTIONS)
def test_feature_sections_are_kept_for_their_feature(tmp_path, section):
    path = tmp_path / "feature.toml"
    path.write_text(SCENE + f"[{section}]\nanything = 1\n", encoding="utf-8")
    assert dict(load_scene(path).extra) == {section: {"anything": 1}}


def test_every_shipped_scene_still_loads():
    names = [*list_scenes(), *list_scenes("bench"), *list_scenes("validation")]
    assert len(names) >= 26
    for name in names:
        assert set(load_scene(name).extra) <= set(FEATURE_SECTIONS)


# -- 2. fmu validate on unreadable files ----------------------------------------------------
def _schema_invalid(path: Path) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr(
            "modelDescription.xml",
            '<fmiModelDescription fmiVersion="2.0" modelName="x" guid="1"><Bogus/></fmiModelDescription>',
        )
    return path


def _truncated(path: Path) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("modelDescription.xml", "<fmiModelDescription/>" + "x" * 5000)
        zf.writestr("binaries/linux64/a.so", bytes(range(256)) * 40)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    return path


def _text(path: Path) -> Path:
    path.write_text("this is not an FMU\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("make", [_text, _truncated, _schema_invalid], ids=["text", "truncated", "schema-invalid"])
def test_fmu_validate_unreadable_file_is_one_line_and_status_2(tmp_path, capsys, make):
    path = make(tmp_path / "bad.fmu")
    status = main(["fmu", "validate", str(path)])
    err = capsys.readouterr().err
    assert status == 2  # distinct from FAIL (1)
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "bad.fmu" in err


def test_fmu_validate_api_raises_a_value_error(tmp_path):
    from pendulab.fmu.validate import UnreadableFMUError, validate

    with pytest.raises(UnreadableFMUError, match="modelDescription.xml is invalid: ERROR"):
        validate(_schema_invalid(tmp_path / "s.fmu"))
    assert issubclass(UnreadableFMUError, ValueError)


# -- 3. a non-model where a model is expected --------------------------------------------
NOT_MODELS = [("rigid", "str"), (None, "NoneType"), (pl.RigidParams(), "RigidParams")]
CALLS = {
    "modes": lambda m: pl.modes(m),
    "equilibria": lambda m: pl.equilibria(m),
    "equilibrium": lambda m: pl.equilibrium(m, "up-up"),
    "linearize": lambda m: pl.linearize(m, np.zeros(4)),
    "to_statespace": lambda m: to_statespace(m),
    "to_nlsys": lambda m: to_nlsys(m),
    "lqr_balance": lambda m: lqr_balance(m),
    "discrete_tvlqr": lambda m: discrete_tvlqr(m, np.zeros((2, 4)), np.zeros((2, 2)), 0.1, np.eye(4), np.eye(2), np.eye(4)),
    "simulate": lambda m: pl.simulate(m, np.zeros(4), 1.0),
}


@pytest.mark.parametrize("call", CALLS.values(), ids=CALLS.keys())
@pytest.mark.parametrize(("bad", "type_name"), NOT_MODELS, ids=[t for _, t in NOT_MODELS])
def test_non_model_is_a_type_error(call, bad, type_name):
    with pytest.raises(TypeError, match=f"^model must be a pendulab Model, got {type_name}"):
        call(bad)


# -- 6. options a method does not know ------------------------------------------------------
@pytest.mark.parametrize(
    ("method", "accepted"),
    [("cvodes", "max_num_steps"), ("idas", "max_num_steps"), ("collocation", "collocation_scheme"), ("RK45", "first_step"),
     ("LSODA", "min_step")],
)  # fmt: skip
def test_unknown_option_is_a_value_error_listing_the_accepted_ones(method, accepted):
    with pytest.raises(ValueError) as exc:
        pl.simulate(pl.rigid(), [0.1, 0, 0, 0], 0.1, method=method, options={"bogus": 1})
    msg = str(exc.value)
    assert f"method {method!r}" in msg and "'bogus'" in msg and accepted in msg
    assert ".cpp" not in msg and "casadi/core" not in msg  # no CasADi source path


def test_casadi_option_typo_suggests_the_name_and_bad_value_names_the_method():
    with pytest.raises(ValueError, match=r"did you mean \['max_num_steps'"):
        pl.simulate(pl.rigid(), [0.1, 0, 0, 0], 0.1, method="cvodes", options={"max_num_step": 10})
    with pytest.raises(ValueError, match=r"method 'cvodes': CasADi rejected .*max_num_steps") as exc:
        pl.simulate(pl.rigid(), [0.1, 0, 0, 0], 0.1, method="cvodes", options={"max_num_steps": "many"})
    assert ".cpp" not in str(exc.value)


def test_known_options_still_work():
    x0 = [0.5, 0.0, 0.0, 0.0]
    a = pl.simulate(pl.rigid(), x0, 1.0, method="cvodes", options={"max_order": 3})
    b = pl.simulate(pl.rigid(), x0, 1.0, method="RK45", rtol=1e-10, atol=1e-10, options={"first_step": 1e-4})
    # CVODES' global error at rtol = atol = 1e-8 is ~1e2-1e3 x the tolerance on this regular 1 s run.
    np.testing.assert_allclose(a.x[-1], b.x[-1], atol=1e-5)


# -- 7. equilibrium-only analyses at a non-equilibrium -----------------------------------------
TILTED = np.array([1.0, 0.0, 0.0, 0.0])  # link 1 at 1 rad, at rest: gravity accelerates it


def test_modes_lqr_and_statespace_refuse_a_non_equilibrium():
    model = pl.rigid()
    for call in (
        lambda: pl.modes(model, TILTED),
        lambda: lqr_balance(model, at=TILTED),
        lambda: to_statespace(model, TILTED),
    ):
        with pytest.raises(ValueError, match=r"not an equilibrium: \|f\(x, u\)\| = .*pendulab.equilibrium"):
            call()


def test_non_equilibrium_opt_out_and_exact_equilibria_pass():
    model = pl.rigid()
    assert len(pl.modes(model, TILTED, allow_non_equilibrium=True)) > 0
    assert to_statespace(model, TILTED, allow_non_equilibrium=True).nstates == 4
    upright = np.array([np.pi, np.pi, 0.0, 0.0])  # sin(pi) = 1.2e-16: an equilibrium to round-off
    assert len(pl.modes(model, upright)) > 0 and lqr_balance(model, at=upright).K.shape == (2, 4)
    stiff = pl.elastic(k1=1e8, k2=1e8)  # round-off of the solved spring lengths x k must still pass
    for name in ("down-down", "up-up"):
        assert pl.linearize(stiff, pl.equilibrium(stiff, name)).is_equilibrium


def test_linearize_marks_a_non_equilibrium():
    lin = pl.linearize(pl.rigid(), TILTED)
    assert not lin.is_equilibrium
    # |f| is the angular acceleration of link 1 released at 1 rad: of the order g sin(1) / L.
    assert 1.0 < lin.residual < 20.0
    assert pl.linearize(pl.rigid(), pl.equilibrium(pl.rigid(), "down-down")).is_equilibrium


def test_nested_unknown_casadi_option_is_named():
    with pytest.raises(ValueError, match="no_such_option") as exc:
        pl.simulate(pl.rigid(), [0.1, 0, 0, 0], 0.1, method="cvodes", options={"linear_solver_options": {"no_such_option": 1}})
    assert ".cpp" not in str(exc.value)

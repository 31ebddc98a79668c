"""A battery generated from the surface (issue 31): every declared input fed a standard set of bad values.

The surface is enumerated, not listed: every value-taking option of every ``pendulab`` sub-command
(``pendulab.commands.options.declared_actions`` walks the parser; an undeclared option fails the walk),
every key of the scene schema the reader checks, and every keyword that a public entry point checks
through ``@checked`` (found by walking the package's ``__all__``). Each input gets the battery below;
each case must end in a clean error naming the input and the value (``InputError`` / ``BudgetError``,
exit status 2 with one line on the CLI) or, where the declaration admits the value, the value itself.
The oracle of admissibility is written here from each declaration's documented fields (kind, range,
open ends, magnitude bounds), independently of the checking code. A new option or entry point is
covered the day it is added. Every case is a check before any work: no case runs a simulation.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import math
import os
import re
import runpy
from pathlib import Path
from typing import Any

import pytest

from pendulab._checks import BudgetError
from pendulab._inputs import INPUTS, MAGNITUDE, Input, InputError, checked, markdown_table
from pendulab.cli import build_parser, main
from pendulab.commands.options import PLAN, UndeclaredOptionError, check_options, declared_actions

#: The standard battery for a value given as text (CLI, strings reaching the API).
TEXT_BATTERY = ("nan", "inf", "-inf", "0", "-1", "1e300", "1e-300", "1.5", "abc", "", " ", "x" * 5000, "a\x00b")
#: The standard battery for a value given as a Python object (API, scene files).
OBJECT_BATTERY: tuple[Any, ...] = (
    "2.5",
    math.nan,
    math.inf,
    -math.inf,
    0,
    0.0,
    -1.0,
    1e300,
    1e-300,
    -1e-300,
    1.5,
    True,
    None,
    "abc",
    "",
    [1.0],
    {"a": 1},
    object(),
)
#: Modules whose ``__all__`` is the public API: the documented packages (docs/conf.py API_PACKAGES) and the
#: modules of the entry points the CLI drives.
PUBLIC_PACKAGES = (
    *runpy.run_path(str(Path(__file__).parents[2] / "docs" / "conf.py"), run_name="pendulab_docs_conf")["API_PACKAGES"],
    "pendulab.control.estimation", "pendulab.control.swingup", "pendulab.control.nmpc", "pendulab.analysis",
    "pendulab.evaluate.realai", "pendulab.ensemble.flipmap", "pendulab.evaluate.realai.v3",
    "pendulab.fmu.controller_export", "pendulab.cosim.ssp",
)  # fmt: skip


def number_ok(spec: Input, value: Any) -> bool:
    """Admissible for a real or integer declaration, from its documented fields."""
    if isinstance(value, bool):
        return False
    if isinstance(value, str):
        try:
            v = float(value) if spec.kind == "real" else float(int(value.strip()))
        except ValueError:
            return False
    elif isinstance(value, (int, float)):
        v = float(value)
        if spec.kind == "integer" and math.isfinite(v) and v != int(v):
            return False
    else:
        return False
    if not math.isfinite(v):
        return False
    if spec.kind == "real" and v != 0.0 and not MAGNITUDE[0] <= abs(v) <= MAGNITUDE[1]:
        return False
    above = spec.low is None or (v > spec.low if spec.open_low else v >= spec.low)
    below = spec.high is None or (v < spec.high if spec.open_high else v <= spec.high)
    return above and below


def text_ok(spec: Input, value: str) -> bool:
    """Admissible for a non-numeric declaration given as text (paths: the battery has none that exist)."""
    if not isinstance(value, str) or not value.strip() or "\x00" in value or len(value) > 4096:
        return False
    if spec.kind == "choice":
        return value in spec.choices
    if spec.kind == "items":
        name, sep, number = value.partition("=")
        return bool(sep and name.strip()) and number_ok(Input("item", "real", ""), number)
    if spec.kind == "reals":
        return all(number_ok(Input("item", "real", "", spec.low, spec.high), p) for p in value.split(","))
    if spec.kind == "file_in":
        return Path(value).is_file()
    return True  # text, names; file_out / dir_out in a writable working folder


def admissible(spec: Input, value: Any) -> bool:
    if spec.kind in ("real", "integer"):
        return number_ok(spec, value)
    return text_ok(spec, value)


def budget_exceeded(spec: Input, value: Any) -> bool:
    from pendulab._checks import BUDGETS

    if spec.budget is None:
        return False
    return float(value) > int(os.environ.get(BUDGETS[spec.budget].env, BUDGETS[spec.budget].default))


# --------------------------------------------------------------------------- the CLI


def cli_surface() -> list[tuple[str, Any, Input]]:
    return list(declared_actions(build_parser()))


def test_every_value_taking_option_is_declared_and_an_undeclared_one_fails_the_build():
    surface = cli_surface()
    commands = {command for command, _, _ in surface}
    assert len(surface) >= 140 and len(commands) >= 19, (len(surface), sorted(commands))
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    sub.choices["simulate"].add_argument("--new-knob", help="an option added without its declaration")
    with pytest.raises(UndeclaredOptionError, match="simulate --new-knob: no declaration"):
        list(declared_actions(parser))


def test_every_option_default_satisfies_its_declaration():
    for command, action, spec in cli_surface():
        defaults = action.default if isinstance(action.default, list) else [action.default]
        for value in defaults:
            if value is not None:
                spec.check(str(value) if spec.kind not in ("real", "integer") else value, action.dest), command


def test_every_special_value_a_help_text_promises_satisfies_its_declaration():
    # Found: `bench ensemble --elastic-grid` said "(0: skip; default 100)" while its declaration refused 0. A value
    # an option's help names with a meaning ("V: what it does") must pass the option's own check.
    promised = []
    for command, action, spec in cli_surface():
        for text in re.findall(r"(?:^|[(;,] ?)(-?\d[\d.e+-]*): ", action.help or ""):
            value = int(text) if spec.kind == "integer" else float(text) if spec.kind == "real" else text
            spec.check(value, f"{command} {action.option_strings[0]}")
            promised.append((command, action.dest, value))
    assert ("bench ensemble", "elastic_grid", 0) in promised  # the walk finds them


def test_cli_battery(tmp_path, monkeypatch, record_property):
    """Every option x every battery value, through the check the CLI runs right after parsing."""
    monkeypatch.chdir(tmp_path)  # relative output paths land here
    outcomes = {"clean error": 0, "accepted as declared": 0}
    for command, action, spec in cli_surface():
        plan = tuple(p for p in build_parser_plan(command) if p.dest == action.dest)
        label = plan[0].label  # options sharing a destination (--set, --init) are named by the first
        for value in TEXT_BATTERY:
            ns = argparse.Namespace(**{PLAN: plan, action.dest: value})
            ok = admissible(spec, value) and not budget_exceeded(spec, value if spec.kind != "integer" else 0)
            if ok:
                check_options(ns)
                got = getattr(ns, action.dest)
                if spec.kind in ("real", "integer"):
                    assert got == (float(value) if spec.kind == "real" else int(value)), (command, label, value)
                outcomes["accepted as declared"] += 1
            else:
                with pytest.raises((InputError, BudgetError)) as exc:
                    check_options(ns)
                message = str(exc.value)
                assert message.startswith(f"{label} = "), (command, label, value, message)
                assert "expected" in message or "budget" in message, message
                outcomes["clean error"] += 1
    record_property("cli_battery", outcomes)
    assert outcomes["clean error"] > 1000 and outcomes["accepted as declared"] > 100, outcomes


def build_parser_plan(command: str) -> tuple[Any, ...]:
    node = build_parser()
    for word in command.split():
        sub = next(a for a in node._actions if isinstance(a, argparse._SubParsersAction))
        node = sub.choices[word]
    return node.get_default(PLAN)


#: One bad value per sub-command through ``main``: exit 2, one line, the option and the value named.
END_TO_END = [
    (["simulate", "--model", "rigid", "--t-final", "nan"], "--t-final = 'nan'"),
    (["demo", "--t-final", "-1"], "--t-final = '-1'"),
    (["modes", "--model", "rigid", "--torque", "1,inf"], "--torque = '1,inf'"),
    (["fmu", "export", "--model", "rigid", "--out", "x.fmu", "--set", "m1=nan"], "--set = 'm1=nan'"),
    (["fmu", "export-controller", "--controller", "lqr", "--u-max", "0"], "--u-max = '0'"),
    (["fmu", "export-controller", "--controller", "lqr", "--sample-time", "1e-9"], "--sample-time = '1e-9'"),
    (["fmu", "validate", "missing.fmu"], "'missing.fmu': no such file"),
    (["cosim", "--comm-step", "1e300"], "--comm-step = '1e300'"),
    (["cosim", "sweep", "--tolerance", "0"], "--tolerance = '0'"),
    (["bench", "work-precision", "--repeats", "0"], "--repeats = '0'"),
    (["bench", "ensemble", "--t-max", "inf"], "--t-max = 'inf'"),
    (["scene", "check", "rigid_regular", "--tolerance", "-1"], "--tolerance = '-1'"),
    (["swingup", "--task", "pendubot", "--N", "1.5"], "--N = '1.5'"),
    (["ensemble", "flipmap", "--threads", "0"], "--threads = '0'"),
    (["score", "--workers", "-2"], "--workers = '-2'"),
    (["ssp", "export", "--t-final", "1e-300"], "--t-final = '1e-300'"),
    (["identify", "--dataset", "c1", "--cutoff", "nan"], "--cutoff = 'nan'"),
]


@pytest.mark.parametrize(("argv", "named"), END_TO_END, ids=[" ".join(a[:2]) for a, _ in END_TO_END])
def test_bad_values_end_every_command_in_one_line_before_any_work(argv, named, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and named in err and "expected" in err, err
    assert not any(tmp_path.iterdir()), "nothing may be written before the inputs are checked"


def test_paths_that_are_folders_files_or_not_writable_are_refused(tmp_path, monkeypatch):
    folder, file = tmp_path / "d", tmp_path / "f.csv"
    folder.mkdir()
    file.write_text("x")
    with pytest.raises(InputError, match="is a directory, not a file"):
        INPUTS["file_out"].check(str(folder), "--out")
    with pytest.raises(InputError, match="is a file, not a directory"):
        INPUTS["dir_out"].check(str(file), "--out")
    with pytest.raises(InputError, match="is a file, not a directory"):
        INPUTS["dir_out"].check(str(file / "run"), "--out")
    with pytest.raises(InputError, match="a folder"):
        INPUTS["file_in"].check(str(folder), "--fmu")
    assert INPUTS["dir_out"].check(str(tmp_path / "new" / "deeper"), "--out") == tmp_path / "new" / "deeper"
    # A read-only mount (root can write anywhere else): the nearest existing folder must be writable.
    real_access = os.access
    monkeypatch.setattr(os, "access", lambda p, mode: False if Path(p) == folder else real_access(p, mode))
    with pytest.raises(InputError, match="is not writable"):
        INPUTS["file_out"].check(str(folder / "sub" / "out.csv"), "--out")
    with pytest.raises(InputError, match="not writable"):
        INPUTS["dir_out"].check(str(folder), "--out")


# --------------------------------------------------------------------------- scene files

SCENE_KEYS = [
    ("simulation", "t_final", "t_final"),
    ("simulation", "dt", "dt"),
    ("simulation", "rtol", "rtol"),
    ("simulation", "atol", "atol"),
    ("outputs", "tolerance", "tolerance"),
    ("initial", "theta1", "state"),
    ("initial", "omega2", "state"),
    ("input", "tau1", "torque"),
]
TOML_BATTERY = ("nan", "inf", "-inf", "0", "-1.0", "1e300", "1e-300", "1.5", '"abc"', "true", "[1.0]")


@pytest.mark.parametrize(("section", "key", "name"), SCENE_KEYS, ids=[f"{s}.{k}" for s, k, _ in SCENE_KEYS])
def test_scene_battery(section, key, name, tmp_path):
    from pendulab.scene import load_scene

    spec = INPUTS[name]
    for i, text in enumerate(TOML_BATTERY):
        path = tmp_path / f"s{i}.toml"
        path.write_text(f'[model]\nkind = "rigid"\n[{section}]\n{key} = {text}\n')
        value: Any = {"true": True, '"abc"': "abc", "[1.0]": [1.0]}.get(text, None)
        value = float(text) if value is None else value
        ok = number_ok(spec, value) and not (section == "simulation" and key == "dt" and value > 10.0)  # dt <= t_final
        if ok:
            load_scene(path)
        else:
            with pytest.raises(ValueError) as exc:
                load_scene(path)
            assert str(path) in str(exc.value) and f"[{section}] {key}" in str(exc.value), str(exc.value)


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
def test_model_parameter_battery(kind, tmp_path):
    """Every parameter of the parameter table (the declaration of model inputs) in a scene file."""
    import pendulab as pl
    from pendulab.scene import load_scene

    for info in pl.make_model(kind).param_info:
        for i, text in enumerate(TOML_BATTERY):
            path = tmp_path / f"{info.name}{i}.toml"
            path.write_text(f'[model]\nkind = "{kind}"\n[model.params]\n{info.name} = {text}\n')
            try:
                value = float(text)
            except ValueError:
                value = math.nan
            ok = math.isfinite(value) and (value > 0 if info.positive else value >= 0)
            ok = ok and (value == 0 or MAGNITUDE[0] <= abs(value) <= MAGNITUDE[1])
            if ok and info.name in ("lc2",) and value == 0:
                ok = False  # m2 lc2^2 + I2 = 0: the singular mass matrix, refused by name
            if ok:
                load_scene(path)
            else:
                with pytest.raises(ValueError, match=info.name):
                    load_scene(path)


# --------------------------------------------------------------------------- the public API


def checked_entry_points() -> list[tuple[str, Any, dict[str, str]]]:
    """Every public callable (function or class) whose inputs ``@checked`` declares, found through ``__all__``."""
    pytest.importorskip("gymnasium")
    found: dict[int, tuple[str, Any, dict[str, str]]] = {}
    for package in PUBLIC_PACKAGES:
        module = importlib.import_module(package)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name, None)
            target = obj.__init__ if inspect.isclass(obj) else obj
            plan = getattr(target, "__pendulab_inputs__", None)
            if plan and id(target) not in found:
                found[id(target)] = (f"{package}.{name}", obj, plan)
    return list(found.values())


#: Entry points the issue names, which must check their inputs where they enter.
REQUIRED_ENTRY_POINTS = {
    "simulate", "ensemble", "flip_map", "swing_up", "score", "run_v3", "identify", "nmpc_controller",
    "ExtendedKalmanFilter", "export_controller", "export_ssp", "export", "DoublePendulumEnv",
}  # fmt: skip


def test_the_named_entry_points_check_every_declared_keyword():
    entries = checked_entry_points()
    names = {qual.rsplit(".", 1)[1] for qual, _, _ in entries}
    assert REQUIRED_ENTRY_POINTS <= names, sorted(REQUIRED_ENTRY_POINTS - names)
    for qual, obj, plan in entries:
        target = obj.__init__ if inspect.isclass(obj) else obj
        params = inspect.signature(target).parameters
        unchecked = [p for p in params if p in INPUTS and INPUTS[p].kind in ("real", "integer") and p not in plan]
        assert not unchecked, f"{qual}: declared inputs not checked: {unchecked}"


def scalar_number(annotation: Any) -> bool:
    """A parameter annotated as one number (``float``, ``int``, optionally ``| None``): what a declaration covers.

    Arrays, sequences and mappings of numbers (``x0``, ``levels``, ``R``) are checked by the function's shape and
    finiteness checks; a name or an index into them is not a number.
    """
    parts = {part.strip() for part in str(annotation).split("|")} - {"None"}
    return bool(parts) and parts <= {"float", "int"}


def public_numeric_parameters() -> list[tuple[str, str, dict[str, str]]]:
    """``(qualified name, parameter, plan)`` of every scalar numeric parameter of the public surface.

    Result types (frozen dataclasses a function returns) and the model parameter tables (``*Params``: checked
    by ``pendulab.model.params``, tested by ``test_model_parameter_battery``) are not inputs of this walk.
    """

    found, seen = [], set()
    for package in PUBLIC_PACKAGES:
        module = importlib.import_module(package)
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name, None)
            if obj is None or id(obj) in seen or (inspect.isclass(obj) and name.endswith("Params")):
                continue
            seen.add(id(obj))
            if inspect.isclass(obj):
                params = getattr(obj, "__dataclass_params__", None)
                if name.endswith("Result") or (params and params.frozen and not name.endswith(("Options", "Problem"))):
                    continue  # a result
                if issubclass(obj, BaseException) or getattr(obj, "_is_protocol", False):
                    continue  # an error, or a typing.Protocol (an interface, not a constructor)
                target = obj.__init__
            elif inspect.isfunction(obj):
                target = obj
            else:
                continue
            plan = getattr(target, "__pendulab_inputs__", {})
            for param in inspect.signature(target).parameters.values():
                if param.kind is param.VAR_KEYWORD:
                    if param.name != "params":  # ``**params`` are model parameters (the parameter table)
                        # Forwarded keywords are checked by name when the entry point is decorated.
                        forwarded = getattr(target, "__pendulab_forwards__", False)
                        found.append((f"{package}.{name}", param.name, {param.name: "*"} if forwarded else {}))
                elif param.name != "self" and scalar_number(param.annotation):
                    found.append((f"{package}.{name}", param.name, plan))
    return found


def test_every_numeric_keyword_of_the_public_api_is_declared():
    surface = public_numeric_parameters()
    undeclared = [f"{qual}({param})" for qual, param, plan in surface if param not in plan]
    assert not undeclared, f"declare these in pendulab._inputs and decorate with @checked: {undeclared}"
    assert len(surface) > 200, len(surface)  # the walk found the surface (304 parameters when written)


def test_an_undeclared_public_number_fails_the_walk(monkeypatch):
    def new_entry(model: Any, *, gain: float = 1.0) -> None:
        """A public function added without a declaration."""

    module = importlib.import_module("pendulab.control")
    monkeypatch.setattr(module, "new_entry", new_entry, raising=False)
    monkeypatch.setattr(module, "__all__", [*module.__all__, "new_entry"])
    assert ("pendulab.control.new_entry", "gain", {}) in public_numeric_parameters()


def test_values_are_checked_once_where_they_enter(monkeypatch):
    """One public call checks each input once: the layers it calls trust it (the model check included)."""
    import pendulab as pl
    import pendulab._checks as checks
    from pendulab.evaluate.scorecard import score

    model_checks = []
    real_is_model = checks._is_model
    monkeypatch.setattr(checks, "_is_model", lambda obj: model_checks.append(obj) or real_is_model(obj))
    score("lqr", "pendubot", runs=1, categories=["mass"], workers=1)
    assert model_checks == []  # score builds its models: nobody re-checks them on the way down (was 19 checks)
    model = pl.rigid()
    pl.simulate(model, [0.1, 0.0, 0.0, 0.0], 0.1, dt=0.05)
    assert model_checks == [model]  # checked where it entered, once
    with pytest.raises(TypeError, match="model must be a pendulab Model, got str"):
        pl.simulate("rigid", [0.1, 0.0, 0.0, 0.0], 0.1)

    calls = []

    @checked()
    def inner(t_final: float) -> float:
        return t_final

    @checked()
    def outer(t_final: float) -> float:
        calls.append(inner(t_final))
        return inner(-1.0)  # an inner layer trusts what the outer one passes

    assert outer(2) == -1.0 and calls == [2.0]
    with pytest.raises(InputError, match="t_final = -1"):
        inner(-1.0)  # called from outside, the same entry point checks


#: Body checks of a declared parameter that are narrower than its declaration, with the reason.
NARROWER_BODY_CHECKS = {
    ("pendulab/evaluate/realai/v3.py", "n_steps"): "a v3 run is at most the protocol's 30000 steps",
}


def test_no_entry_point_checks_a_declared_parameter_again():
    """An entry point's body does not re-check what ``@checked`` checked where it entered (checked once)."""
    import ast

    root = Path(__file__).parents[2]
    again = []
    for path in sorted((root / "pendulab").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if not isinstance(node, ast.FunctionDef):
                continue
            decorators = [d for d in node.decorator_list if isinstance(d, ast.Call) and getattr(d.func, "id", "") == "checked"]
            if not decorators:
                continue
            aliases = {k.arg for k in decorators[0].keywords}
            params = {a.arg for a in node.args.args + node.args.kwonlyargs}
            declared = {p for p in params if p in aliases or (p in INPUTS and INPUTS[p].kind in ("real", "integer"))}
            for call in ast.walk(node):
                if (
                    isinstance(call, ast.Call)
                    and getattr(call.func, "id", "") in ("positive_float", "bounded_int", "relative_tolerance")
                    and len(call.args) > 1
                    and isinstance(call.args[1], ast.Name)
                    and call.args[1].id in declared
                ):
                    where = (path.relative_to(root).as_posix(), call.args[1].id)
                    if where not in NARROWER_BODY_CHECKS:
                        again.append(f"{where[0]}:{call.lineno} {node.name}({where[1]})")
    assert not again, f"checked twice (the declaration already checks these): {again}"


def test_api_battery(record_property):
    """Every checked keyword of every entry point x the object battery: rejected values raise before the body runs."""
    refused = 0
    for qual, obj, plan in checked_entry_points():
        for param, name in plan.items():
            spec = INPUTS[name]
            for value in OBJECT_BATTERY:
                if value is None or (admissible(spec, value) and not isinstance(value, str)):
                    continue  # None means "the default"; admitted values would run the body without its other arguments
                with pytest.raises((InputError, BudgetError)) as exc:
                    obj(**{param: value})
                assert str(exc.value).startswith(f"{param}") and "expected" in str(exc.value), (qual, param, str(exc.value))
                refused += 1
    record_property("api_battery_refused", refused)
    assert refused > 500, refused


def test_checked_converts_and_names_its_inputs():
    @checked(horizon_s="horizon")
    def entry(t_final: float, *, horizon_s: float = 1.0, other: Any = 0.1) -> tuple[Any, Any, Any]:
        return t_final, horizon_s, other

    assert entry(2.5, horizon_s=3) == (2.5, 3.0, 0.1)
    assert entry(2.5, other=1e300)[2] == 1e300  # undeclared parameters are the function's own business
    with pytest.raises(InputError, match=r"t_final = '2.5': a str, not a number"):
        entry("2.5")
    with pytest.raises(InputError, match=r"horizon_s = 1000.0: out of range; expected a finite number in \(0, 30\] s"):
        entry(1.0, horizon_s=1000.0)
    with pytest.raises(TypeError, match="unknown inputs"):
        checked(x="no_such_input")(lambda x: x)


def test_forwarded_keywords_are_checked_as_their_target_declares_them():
    @checked(horizon="horizon_intervals")
    def target(*, horizon: int = 20, t_final: float = 1.0) -> tuple[Any, Any]:
        return horizon, t_final

    @checked(target)
    def forwarder(**options: Any) -> tuple[Any, Any]:
        return target(**options)

    @checked()
    def by_name(**options: Any) -> Any:
        return options

    assert forwarder(horizon=100) == (100, 1.0)  # 100 intervals: the target's meaning, not 100 s
    with pytest.raises(InputError, match=r"horizon = 501: out of range; expected an integer in \[1, 500\]"):
        forwarder(horizon=501)
    with pytest.raises(InputError, match=r"t_final = -1.0: out of range"):
        forwarder(t_final=-1.0)  # checked by the forwarder: the target, called from inside, trusts it
    with pytest.raises(InputError, match=r"t_final = nan: not finite"):
        by_name(t_final=math.nan)  # no target: a forwarded keyword is checked by its name
    assert by_name(t_final=2, other="x") == {"t_final": 2.0, "other": "x"}
    with pytest.raises(TypeError, match="forward needs"):
        checked(target)(lambda x: x)


def test_the_vector_env_checks_what_it_forwards_to_each_env():
    pytest.importorskip("gymnasium")
    from pendulab.gym import DoublePendulumVectorEnv

    with pytest.raises(InputError, match=r"torque_limit = 1e\+300: out of range; expected a finite number in \(0, 10000\] N.m"):
        DoublePendulumVectorEnv(2, torque_limit=1e300)


def test_declared_limits_equal_the_constants_of_the_layers_above():
    from pendulab.control.swingup.problem import MAX_INTERVALS
    from pendulab.evaluate.scorecard import MAX_RUNS

    assert INPUTS["N"].high == INPUTS["intervals"].high == MAX_INTERVALS
    assert INPUTS["runs_per_level"].high == MAX_RUNS
    from pendulab.control.nmpc.controller import MAX_HORIZON
    from pendulab.ensemble.batch import MAX_BATCH_SIZE
    from pendulab.ensemble.engine_checks import MAX_RUNS as MAX_ENSEMBLE_RUNS
    from pendulab.evaluate.realai.v3_hardware import PASSIVE_ALLOWANCE

    assert INPUTS["horizon_intervals"].high == MAX_HORIZON
    assert INPUTS["batch_size"].high == MAX_BATCH_SIZE
    assert INPUTS["chunk_size"].high == MAX_ENSEMBLE_RUNS
    assert INPUTS["passive_allowance"].high == PASSIVE_ALLOWANCE


def test_the_inputs_page_is_generated_from_the_declarations():
    page = (Path(__file__).parents[2] / "docs" / "inputs.md").read_text()
    assert markdown_table() in page, "regenerate docs/inputs.md: python -m pendulab._inputs > table"

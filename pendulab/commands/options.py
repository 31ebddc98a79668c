"""Every CLI option's declaration: which input of :data:`pendulab._inputs.INPUTS` it is.

:func:`declare_options` runs once on the whole parser (``pendulab.cli.build_parser``) and attaches each
option's declaration to its sub-command; :func:`check_options` (``pendulab.cli.main``, right after
parsing) converts and checks every value given: a value out of range, non-finite, of the wrong type or a
path that cannot be written is refused before any work, in one line naming the option, the value and
the range (exit status 2). An option that takes a value and has no declaration here is a programming error, refused when
the parser is built (and by ``tests/reliability/test_input_battery.py``): a new option is declared the
day it is added.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any, NamedTuple

from .._inputs import INPUTS, Input

__all__ = [
    "OPTION_INPUTS",
    "COMMAND_INPUTS",
    "MODE_INPUTS",
    "declare_options",
    "check_options",
    "declared_actions",
    "UndeclaredOptionError",
]

#: Option ``dest`` to declared input, for the options that mean the same in every command.
OPTION_INPUTS: Mapping[str, str] = {
    **{
        dest: dest
        for dest in (
            "t_final",
            "dt",
            "rtol",
            "atol",
            "tolerance",
            "max_wall_time",
            "sample_time",
            "comm_step",
            "u_max",
            "measurement_noise",
            "measurement_delay",
            "measurement_seed",
            "N",
            "starts",
            "gif_fps",
            "k",
            "cutoff",
            "repeats",
            "runs",
            "hand_runs",
            "grid",
            "elastic_grid",
            "t_max",
            "threads",
            "workers",
            "seed",
            "fmi_version",
            "passive_allowance",
        )
    },
    **{
        dest: "name"
        for dest in (
            "scene",
            "model",
            "method",
            "plant",
            "equilibrium",
            "controller",
            "task",
            "kind",
            "nmpc_solver",
            "actuation",
            "estimator",
            "solver",
            "cases",
            "methods",
            "guess",
            "planning",
            "protocol",
            "dataset",
            "input",
            "structure",
            "columns",
            "file",
            "records",
        )
    },
    **{dest: "set_item" for dest in ("set", "initial", "init", "param", "geometry")},
    **{dest: "names" for dest in ("platforms", "kinds", "categories", "controllers")},
    "torque": "reals",
    "steps": "steps",
    "torque_limit": "reals",
    "fmu": "file_in",
    "fmu_rigid": "file_in",
    "fmu_elastic": "file_in",
    "reference": "file_in",
    "plot": "dir_out",
    "out": "dir_out",
    "scheduler": "address",
}

#: ``"<command> <dest>"`` to declared input, where one command's option differs from the common meaning.
COMMAND_INPUTS: Mapping[str, str] = {
    "simulate out": "file_out",
    "swingup starts": "tracking_starts",
    "score runs": "runs_per_level",
    "fmu export out": "file_out",
    "fmu export-controller out": "file_out",
    "ssp export out": "file_out",
    "bench ensemble out": "file_out",
}


#: ``"<command> <dest>"`` to ``(mode, declared input)``: an option that means something else when the boolean option
#: ``mode`` of the same command is given. ``pendulab score --out`` is a folder, but with ``--leaderboard`` it is the
#: page (a Markdown file), which regenerating overwrites.
MODE_INPUTS: Mapping[str, tuple[str, str]] = {
    "score out": ("leaderboard", "file_out"),
}


class UndeclaredOptionError(RuntimeError):
    """A CLI option that takes a value and has no declaration (a programming error of pendulab)."""


def declared_actions(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()) -> Iterator[tuple[str, Any, Input]]:
    """Every value-taking option of ``parser`` and its sub-commands, with its declaration.

    Yields
    ------
    command : str
        The sub-command path (``"fmu export"``).
    action : argparse.Action
        The option.
    input : Input
        Its declaration.

    Raises
    ------
    UndeclaredOptionError
        An option takes a value but has no declaration.
    """
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            seen: set[int] = set()
            for name, sub in action.choices.items():
                if id(sub) not in seen:  # aliases map to the same parser
                    seen.add(id(sub))
                    yield from declared_actions(sub, (*path, name))
        elif action.nargs != 0 and action.dest not in ("help", "version"):
            command = " ".join(path)
            key = COMMAND_INPUTS.get(f"{command} {action.dest}", OPTION_INPUTS.get(action.dest))
            if key is None:
                flag = "/".join(action.option_strings) or action.dest
                raise UndeclaredOptionError(
                    f"pendulab {command} {flag}: no declaration; add it to pendulab.commands.options.OPTION_INPUTS"
                )
            yield command, action, INPUTS[key]


def declare_options(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """Attach every option's declaration to the sub-command that owns it (see :func:`check_options`).

    The options keep argparse's raw string (an option with ``choices`` keeps its own ``type``, which
    the choices are written in); :func:`check_options` converts and checks them right after parsing.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The whole ``pendulab`` parser.

    Returns
    -------
    argparse.ArgumentParser
        The same parser.
    """
    plans: dict[int, tuple[argparse.ArgumentParser, list[_Declared]]] = {}
    for command, action, spec in declared_actions(parser):
        owner = _owner(parser, command)
        label = action.option_strings[0] if action.option_strings else action.metavar or action.dest
        # Commands written for a string path keep getting one (checked); typed ones get a Path.
        as_path = action.type is not None and spec.kind in _PATH_KINDS
        if not action.choices:
            action.type = None
        if spec.kind in ("real", "integer") and action.help not in (None, argparse.SUPPRESS):
            action.help = f"{action.help} [admits {spec.interval()}]"
        mode = MODE_INPUTS.get(f"{command} {action.dest}")
        alternative = None if mode is None else (mode[0], INPUTS[mode[1]])
        plans.setdefault(id(owner), (owner, []))[1].append(_Declared(action.dest, spec, str(label), as_path, alternative))
    for owner, plan in plans.values():
        owner.set_defaults(**{PLAN: tuple(plan)})
    return parser


#: Namespace attribute holding the parsed sub-command's declarations.
PLAN = "_declared_inputs"

_PATH_KINDS = ("file_in", "file_out", "dir_out")


class _Declared(NamedTuple):
    dest: str
    spec: Input
    label: str
    as_path: bool
    mode: tuple[str, Input] | None = None  # (boolean option, declaration in force when it is given)


def _owner(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    """The sub-parser of ``command`` (``"fmu export"``) in ``parser``."""
    node = parser
    for word in command.split():
        sub = next(a for a in node._actions if isinstance(a, argparse._SubParsersAction))
        node = sub.choices[word]
    return node


def check_options(args: argparse.Namespace) -> argparse.Namespace:
    """Check and convert every declared option of the parsed sub-command in place, before any work.

    An option of :data:`MODE_INPUTS` is checked with its mode's declaration when that mode's flag is given.

    Parameters
    ----------
    args : argparse.Namespace
        What ``build_parser().parse_args`` returned.

    Returns
    -------
    argparse.Namespace
        The same namespace: numbers are ``float`` / ``int``, paths ``str`` (or ``Path`` where the
        option was declared with ``type=Path``), lists of values checked element by element.

    Raises
    ------
    InputError
        A value out of its declaration; the message names the option, the value and the range.
    BudgetError
        A value beyond its resource budget.
    """
    seen: set[str] = set()
    for item in getattr(args, PLAN, ()):
        if item.dest in seen:  # two spellings of one destination (--set and --init): checked once
            continue
        seen.add(item.dest)
        value = getattr(args, item.dest, None)
        if value is None:
            continue
        if item.mode is not None and getattr(args, item.mode[0], False):
            item = item._replace(spec=item.mode[1])
        if isinstance(value, list):
            setattr(args, item.dest, [_one(item, v) for v in value])
        else:
            setattr(args, item.dest, _one(item, value))
    return args


def _one(item: _Declared, value: Any) -> Any:
    checked = item.spec.check(value, item.label)
    if item.spec.kind in _PATH_KINDS:
        return Path(checked) if item.as_path else str(checked)
    return checked

"""``pendulab ssp export``: the closed loop (plant FMU + controller FMU + connections + parameter sets) as an SSP 1.0 file."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from . import CLIError
from ._common import add_vocabulary_option, typed_flag


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "ssp",
        help="write the closed loop (plant + controller FMUs) as an SSP 1.0 archive",
        description="System Structure and Parameterization (SSP 1.0) of a pendulab control loop: `pendulab ssp export`.",
    )
    sub = p.add_subparsers(dest="ssp_command", metavar="ACTION")
    sub.required = True
    e = sub.add_parser(
        "export",
        help="write plant.fmu + controller.fmu + SystemStructure.ssd + parameter sets into one .ssp",
        description="Design the controller, export the plant FMU (its states also declared outputs) and the controller "
        "FMU, connect plant states -> controller inputs and controller torques -> plant inputs, bind the parameter sets "
        "(plant parameters, controller sample_time) and write the .ssp (SSP 1.0; schema-valid). Any SSP importer runs it; "
        "stepped at the controller's sample time it is the loop of `pendulab cosim` with the same plant and controller.",
    )
    e.add_argument("--controller", choices=("lqr", "tvlqr", "swingup", "nmpc"), default="lqr", help="nmpc: explains why not")
    e.add_argument("--task", help="swing-up task: model, actuation, torque limit, start state, horizon and sample time")
    add_vocabulary_option(e, "model kind", "kind", "plant model without --task (default rigid)", default=None)
    e.add_argument("--fmi-version", type=int, choices=(2, 3), default=2, help="FMI version of both FMUs")
    e.add_argument("--sample-time", type=float, help="controller sample time [s] (default: the task's dt, else 0.01)")
    e.add_argument("--t-final", type=float, help="default experiment stop time [s] (default: the task's horizon, else 10)")
    e.add_argument("--out", type=Path, default=None, help="output .ssp (default ./pendulab-out/ssp/<task|kind>_<controller>.ssp)")
    e.add_argument("--no-timestamp", action="store_true", help="omit the FMUs' generationDateAndTime")
    e.add_argument("--json", action="store_true", help="print a JSON summary instead")
    e.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``pendulab ssp export``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments.

    Returns
    -------
    int
        0 on success.

    Raises
    ------
    CLIError
        Bad or inapplicable options, a controller that cannot be designed or exported.
    """
    from ..cosim.ssp import export_ssp

    if args.task is not None and args.kind is not None:
        raise CLIError(f"--task sets the model; {typed_flag(args, 'model kind')} does not apply with it")
    for flag, value in (("--sample-time", args.sample_time), ("--t-final", args.t_final)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise CLIError(f"{flag} must be a positive time [s], got {value!r}")
    label = args.task if args.task is not None else (args.kind or "rigid")
    out = args.out or Path("pendulab-out") / "ssp" / f"{label}_{args.controller}.ssp"
    out.parent.mkdir(parents=True, exist_ok=True)
    try:
        res = export_ssp(
            out,
            controller=args.controller,
            task=args.task,
            kind=args.kind or "rigid",
            fmi_version=args.fmi_version,
            sample_time=args.sample_time,
            stop_time=args.t_final,
            timestamp=not args.no_timestamp,
        )
    except (ValueError, FileNotFoundError) as exc:
        raise CLIError(f"ssp export: {exc}") from None
    summary = {
        "ssp": str(res.path),
        "controller": res.controller,
        "task": res.task,
        "fmi_version": res.fmi_version,
        "sample_time": res.sample_time,
        "stop_time": res.stop_time,
        "components": {"plant": "resources/plant.fmu", "controller": "resources/controller.fmu"},
        "connections": [f"plant.{n} -> controller.{n}" for n in res.state_names]
        + [f"controller.{n} -> plant.{n}" for n in res.torque_names],
        "x0": dict(zip(res.state_names, res.x0.tolist(), strict=True)),
        "bytes": res.path.stat().st_size,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(
            f"wrote {res.path} (SSP 1.0: plant + {res.controller} controller, FMI {res.fmi_version}, sample time "
            f"{res.sample_time:g} s, {len(summary['connections'])} connections)"
        )
    return 0

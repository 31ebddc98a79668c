"""``pendulab fmu export|validate|export-controller``: write an FMU of the pendulum or of a controller; check one with fmpy."""

from __future__ import annotations

import argparse
import json
import sys
import zipfile
from pathlib import Path

from . import CLIError
from ._common import add_plant_option, add_vocabulary_option, docs_page, parse_settings, plant_settings, typed_flag


def _binary_folders(path: Path) -> list[str]:
    with zipfile.ZipFile(path) as zf:
        return sorted({n.split("/")[1] for n in zf.namelist() if n.startswith("binaries/")})


def _export(args: argparse.Namespace) -> int:
    from ..fmu import export
    from ..model.model import make_model

    model = make_model(
        args.model, **{**plant_settings(args, args.model), **parse_settings(args.set, typed_flag(args, "parameters"))}
    )
    x0 = model.state(**parse_settings(args.initial, typed_flag(args, "initial state"))) if args.initial else None
    # code generation and the C compiler take seconds (a minute on a loaded machine): say so first
    platforms = f" for {args.platforms}" if args.platforms else ""
    print(f"pendulab fmu export: generating C code and compiling the {args.model} FMU{platforms} ...", file=sys.stderr)
    path = export(
        model, args.out, args.fmi_version, timestamp=not args.no_timestamp, x0=x0, platforms=args.platforms,
        flip_events=args.flip_events,
    )  # fmt: skip
    if args.json:
        start = model.state() if x0 is None else x0
        summary = {
            "fmu": str(path),
            "fmi_version": args.fmi_version,
            "model": args.model,
            "interfaces": ["CoSimulation", "ModelExchange"],
            "platforms": _binary_folders(path),
            "params": {k: float(v) for k, v in zip(model.param_names, model.p, strict=True)},
            "start": {k: float(v) for k, v in zip(model.state_names, start, strict=True)},
            "bytes": path.stat().st_size,
        }
        print(json.dumps(summary, indent=2))
    else:
        print(f"wrote {path} (FMI {args.fmi_version}.0, {args.model}, Co-Simulation + Model Exchange)")
    return 0


def _validate(args: argparse.Namespace) -> int:
    """Exit status 0 PASS, 1 FAIL; bad input (an unreadable file: ``UnreadableFMUError``, a ValueError)
    propagates to the dispatcher, which prints one line and returns 2."""
    from ..fmu import validate

    report = validate(
        args.fmu,
        scenes=args.scene or None,
        out_dir=args.out,
        progress=lambda msg: print(f"[fmu validate] {msg}", file=sys.stderr, flush=True),
    )
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        print(report.table())
        if report.plot is not None:
            print(f"overlay plot: {report.plot}")
    return 0 if report.passed else 1


def _export_controller(args: argparse.Namespace) -> int:
    from ..fmu.controller_export import design_controller, export_controller

    if args.task is not None and (args.kind is not None or args.u_max is not None):
        raise CLIError(
            f"--task sets the model and the torque limit; {typed_flag(args, 'model kind')} and --u-max do not apply with it"
        )
    if args.sample_time is not None and not (args.sample_time > 0 and args.sample_time < float("inf")):
        raise CLIError(f"--sample-time must be a positive period [s], got {args.sample_time!r}")
    try:
        ctrl, x0, model = design_controller(
            args.controller, args.task, kind=args.kind or "rigid", sample_time=args.sample_time,
            u_max=20.0 if args.u_max is None else args.u_max,
        )  # fmt: skip
    except (ValueError, FileNotFoundError) as exc:
        raise CLIError(f"--controller {args.controller}: {exc}") from None
    out = args.out or Path("pendulab-out") / "fmu" / f"{args.controller}_controller_fmi{args.fmi_version}.fmu"
    out.parent.mkdir(parents=True, exist_ok=True)
    path = export_controller(ctrl, out, args.fmi_version, timestamp=not args.no_timestamp)
    summary = {
        "fmu": str(path),
        "fmi_version": args.fmi_version,
        "controller": args.controller,
        "task": getattr(args, "task", None),
        "model": model.kind,
        "interfaces": ["CoSimulation"],
        "inputs": list(model.state_names),
        "outputs": list(ctrl.input_names),
        "sample_time": float(ctrl.sample_time),
        "start": {k: float(v) for k, v in zip(model.state_names, x0, strict=True)},
        "bytes": path.stat().st_size,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(
            f"wrote {path} (FMI {args.fmi_version}.0 Co-Simulation, {args.controller} controller for the {model.kind} "
            f"pendulum: inputs {', '.join(model.state_names)}; outputs {', '.join(ctrl.input_names)}; "
            f"sample_time {ctrl.sample_time:g} s)"
        )
    return 0


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("fmu", help="export an FMU (FMI 2/3, CS + ME) or a controller FMU, or validate one with fmpy")
    sub = p.add_subparsers(dest="fmu_command", metavar="ACTION")
    sub.required = True

    e = sub.add_parser("export", help="compile and write an FMU")
    add_vocabulary_option(e, "model kind", "model", "rigid | elastic", required=True)
    add_vocabulary_option(e, "parameters", "set", "parameter start values")
    add_vocabulary_option(e, "initial state", "initial", "state start values, e.g. theta1=1.0")
    add_plant_option(e, "--model rigid; --set overrides its values")
    e.add_argument("--fmi-version", type=int, choices=(2, 3), default=2)
    e.add_argument("--out", type=Path, required=True, help="output .fmu file")
    e.add_argument("--no-timestamp", action="store_true", help="omit generationDateAndTime (reproducible bytes)")
    e.add_argument(
        "--flip-events",
        action="store_true",
        help="add event indicators pi - |theta_i| (Model Exchange importers stop at every flip of a link)",
    )
    e.add_argument(
        "--platforms",
        default=None,
        metavar="LIST",
        help="binaries to build, comma-separated, e.g. x86_64-linux,x86_64-windows,aarch64-linux (linux64, win64 "
        'accepted); default: this machine; others are cross-compiled (pip install "pendulab[cross]")',
    )
    e.add_argument("--json", action="store_true", help="print a JSON summary (path, parameters, start values) instead")
    e.set_defaults(func=_export)

    c = sub.add_parser(
        "export-controller",
        help="write a controller (lqr, tvlqr, swingup) as a Co-Simulation FMU (generated C, no Python inside)",
        description="Design a pendulab controller and write it as an FMI 2/3 Co-Simulation FMU: the measured state as "
        "inputs, the torques as outputs, the sample time as a parameter (sample-and-hold as pendulab's sampled "
        f"controllers). The NMPC is not exportable (its solver is not generated as self-contained C; {docs_page('fmu')}).",
    )
    c.add_argument("--controller", choices=("lqr", "tvlqr", "swingup", "nmpc"), required=True, help="nmpc: explains why not")
    c.add_argument("--task", help="swing-up task (model, actuation, torque limit, sample time; tvlqr tracks its optimized plan)")
    add_vocabulary_option(c, "model kind", "kind", "model without --task (default rigid)", default=None)
    c.add_argument("--sample-time", type=float, help="controller sample time [s] (default: the task's dt, else 0.01)")
    c.add_argument("--u-max", type=float, default=None, help="torque limit [N.m] without --task (default 20)")
    c.add_argument("--fmi-version", type=int, choices=(2, 3), default=2)
    c.add_argument(
        "--out", type=Path, default=None, help="output .fmu (default ./pendulab-out/fmu/<controller>_controller_fmi<V>.fmu)"
    )
    c.add_argument("--no-timestamp", action="store_true", help="omit generationDateAndTime (reproducible bytes)")
    c.add_argument("--json", action="store_true", help="print a JSON summary instead")
    c.set_defaults(func=_export_controller)

    v = sub.add_parser(
        "validate",
        help="fmpy validate_fmu + agreement with the native integrator; exit 1 on FAIL, 2 on an unreadable file",
        description="Validate a pendulab FMU: fmpy's validate_fmu plus agreement with the native integrator on the "
        "validation scenes, by default at the FMU's own parameters and start values (its modelDescription start values; "
        "the scenes lend horizon, step, input, tolerance and bound); --scene runs named scenes as they are. "
        "Exit status: 0 PASS, 1 FAIL, 2 bad input (not a readable FMU - not a zip, a truncated "
        "archive, a schema-invalid modelDescription.xml -, not a pendulab FMU, unknown scene, a binary pendulab did not "
        "export that crashes or fails in a probe process), one line on stderr.",
    )
    v.add_argument("fmu", type=Path)
    v.add_argument(
        "--scene",
        action="append",
        metavar="NAME",
        help="validation scene run with ITS parameters and initial state (repeatable; default: every scene of the kind "
        "at the FMU's own parameters and start values)",
    )
    v.add_argument("--out", type=Path, default=None, help="directory for the overlay plot")
    v.add_argument("--json", action="store_true", help="print the report as JSON instead of the table")
    v.set_defaults(func=_validate)

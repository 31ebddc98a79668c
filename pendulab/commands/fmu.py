"""``pendulab fmu export|validate``: write an FMU of the rigid or elastic pendulum; check it with fmpy."""

from __future__ import annotations

import argparse
import json
import sys
import zipfile
from pathlib import Path

from . import CLIError


def _parse_sets(items: list[str]) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise CLIError(f"--set expects name=value, got {item!r}")
        try:
            out[name.strip()] = float(value)
        except ValueError as exc:
            raise CLIError(f"--set {name}: value must be a number, got {value!r}") from exc
    return out


def _binary_folders(path: Path) -> list[str]:
    with zipfile.ZipFile(path) as zf:
        return sorted({n.split("/")[1] for n in zf.namelist() if n.startswith("binaries/")})


def _export(args: argparse.Namespace) -> int:
    from ..fmu import export
    from ..model.model import make_model

    model = make_model(args.model, **_parse_sets(args.set or []))
    x0 = model.state(**_parse_sets(args.initial or [])) if args.initial else None
    path = export(model, args.out, args.fmi_version, timestamp=not args.no_timestamp, x0=x0, platforms=args.platforms)
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


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("fmu", help="export an FMU (FMI 2/3, CS + ME) or validate one with fmpy")
    sub = p.add_subparsers(dest="fmu_command", metavar="ACTION")
    sub.required = True

    e = sub.add_parser("export", help="compile and write an FMU")
    e.add_argument("--model", choices=("rigid", "elastic"), required=True)
    e.add_argument("--set", action="append", metavar="NAME=VALUE", help="parameter start value (repeatable)")
    e.add_argument("--initial", action="append", metavar="STATE=VALUE", help="state start value (repeatable)")
    e.add_argument("--fmi-version", type=int, choices=(2, 3), default=2)
    e.add_argument("--out", type=Path, required=True, help="output .fmu file")
    e.add_argument("--no-timestamp", action="store_true", help="omit generationDateAndTime (reproducible bytes)")
    e.add_argument(
        "--platforms",
        default=None,
        metavar="LIST",
        help="binaries to build, comma-separated, e.g. x86_64-linux,x86_64-windows,aarch64-linux (linux64, win64 "
        'accepted); default: this machine; others are cross-compiled (pip install "pendulab[cross]")',
    )
    e.add_argument("--json", action="store_true", help="print a JSON summary (path, parameters, start values) instead")
    e.set_defaults(func=_export)

    v = sub.add_parser(
        "validate",
        help="fmpy validate_fmu + agreement with the native integrator; exit 1 on FAIL, 2 on an unreadable file",
        description="Validate a pendulab FMU: fmpy's validate_fmu plus agreement with the native integrator on the "
        "validation scenes, by default at the FMU's own parameters and start values (its modelDescription start values; "
        "the scenes lend horizon, step, input, tolerance and bound); --scene runs named scenes as they are. "
        "Exit status: 0 PASS, 1 FAIL, 2 bad input (not a readable FMU - not a zip, a truncated "
        "archive, a schema-invalid modelDescription.xml -, not a pendulab FMU, unknown scene), one line on stderr.",
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

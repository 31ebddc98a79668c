"""``pendulab identify``: fit the robot model to measured records and write the plant file every study reads."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from ._common import CLIError, ProgressBar, parse_number, parse_settings

__all__ = ["register", "run"]

#: Shipped data sets: their records, known geometry and prior (DFKI's model 1.0 of the robot; only its masses matter).
_DATASETS = ("c1", "a0")


def register(subparsers: Any) -> None:
    """Add the ``identify`` sub-command."""
    p = subparsers.add_parser(
        "identify",
        help="identify the robot's parameters from measured records (writes a plant file for --plant)",
        description=(
            "Read measured records (RealAIGym's CSV columns or a --columns mapping), prepare them (uniform grid, "
            "zero-phase derivatives, saturation), choose the model structure by leave-one-record-out error, fit "
            "the base parameters (consistent regression, then output error by multiple shooting) with standard "
            "errors, and write OUT/plant.json and OUT/identification.json."
        ),
    )
    p.add_argument("records", nargs="*", metavar="RECORD", help="CSV files (at least two)")
    p.add_argument(
        "--dataset",
        metavar="NAME",
        help="use a shipped data set instead: c1 (RealAIGym design C.1, its eight excitation records) or a0 "
        "(design A.0, its nine sys-id records); sets the geometry and the prior to that robot's",
    )
    p.add_argument(
        "--columns",
        metavar="ROLE=NAME,...",
        help="column names for time, q1, q2 (q2 relative to link 1), tau1, tau2 (the input), e.g. "
        "time=t,q1=a1,q2=a2,tau1=u1,tau2=u2; default RealAIGym's (tau_meas1/2 the input)",
    )
    p.add_argument(
        "--input",
        metavar="KIND",
        help="RealAIGym columns: meas (tau_meas*) or con (tau_con*); default meas, con for --dataset a0 "
        "(A.0's choice: the command predicted its held-out sys-id records better)",
    )
    p.add_argument("--cutoff", metavar="HZ", help="zero-phase low-pass cutoff [Hz] (default 8)")
    p.add_argument("--torque-limit", metavar="T1,T2", help="input torque saturation per joint [N.m] (samples at it are dropped)")
    p.add_argument(
        "--structure", default="auto", metavar="NAME", help="auto (default) | rigid | +viscous | +coulomb | +rotor | +offset"
    )
    p.add_argument(
        "--geometry",
        metavar="NAME=VALUE",
        action="append",
        help="known l1, l2 [m], g [m/s2], gr [-]; default the --dataset's robot's, C.1's for RECORD files",
    )
    p.add_argument("--out", default="pendulab-out/identify", metavar="DIR", help="output folder (default pendulab-out/identify)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _column_map(args: argparse.Namespace) -> Any:
    from ..identify.records import REALAIGYM_COLUMNS, REALAIGYM_COMMAND_COLUMNS, ColumnMap

    kind = args.input if args.input is not None else ("con" if args.dataset == "a0" else "meas")
    if kind not in ("meas", "con"):
        raise CLIError(f"--input {args.input!r}: expected meas or con")
    if args.columns is None:
        return REALAIGYM_COLUMNS if kind == "meas" else REALAIGYM_COMMAND_COLUMNS
    roles = {}
    for item in args.columns.split(","):
        role, sep, name = item.partition("=")
        if not sep or not name.strip():
            raise CLIError(f"--columns {args.columns!r}: expected ROLE=NAME pairs, e.g. time=t,q1=a1,q2=a2,tau1=u1,tau2=u2")
        roles[role.strip()] = name.strip()
    need = ["time", "q1", "q2", "tau1", "tau2"]
    unknown = sorted(set(roles) - set(need))
    missing = [r for r in need if r not in roles]
    if unknown or missing:
        raise CLIError(f"--columns: unknown roles {unknown}, missing roles {missing}; expected {need}")
    return ColumnMap(time=roles["time"], angles=(roles["q1"], roles["q2"]), torques=(roles["tau1"], roles["tau2"]))


def run(args: argparse.Namespace) -> int:
    """Execute ``pendulab identify``; return the exit status."""
    from ..identify.datasets import A0_SYSID, C1_EXCITATION, a0_record, c1_record
    from ..identify.pipeline import identify
    from ..identify.published import A0_GEOMETRY, C1_GEOMETRY, DFKI_A0, DFKI_C1
    from ..identify.records import read_record
    from ..identify.regressor import FIXED_NAMES, robot_to_standard
    from ..model.plant_file import save_plant

    columns = _column_map(args)
    if args.dataset is not None and args.records:
        raise CLIError("give RECORD files or --dataset, not both")
    if args.dataset is not None:
        if args.dataset not in _DATASETS:
            raise CLIError(f"--dataset {args.dataset!r}: expected one of {list(_DATASETS)}")
        if args.dataset == "a0":
            records = [a0_record(s, columns) for s in A0_SYSID]
            geometry, published, robot = A0_GEOMETRY, DFKI_A0, "A.0"
        else:
            records = [c1_record(s, columns) for s in C1_EXCITATION]
            geometry, published, robot = C1_GEOMETRY, DFKI_C1, "C.1"
    else:
        if len(args.records) < 2:
            raise CLIError(f"need at least two RECORD files (or --dataset c1 / a0), got {len(args.records)}")
        records = [read_record(path, columns) for path in args.records]
        geometry, published, robot = C1_GEOMETRY, DFKI_C1, "C.1"
    fixed = dict(geometry)
    given = parse_settings(args.geometry)
    unknown = sorted(set(given) - set(FIXED_NAMES))
    if unknown:
        raise CLIError(f"--geometry: unknown names {unknown}; expected {list(FIXED_NAMES)}")
    fixed.update(given)
    for name, value in fixed.items():
        if value <= 0:
            raise CLIError(f"--geometry {name}={value}: must be > 0")
    cutoff = parse_number("--cutoff", args.cutoff, positive=True) or 8.0
    limit = (float("inf"), float("inf"))
    if args.torque_limit is not None:
        parts = args.torque_limit.split(",")
        if len(parts) != 2:
            raise CLIError(f"--torque-limit {args.torque_limit!r}: expected two numbers T1,T2 in N.m")
        limit = tuple(parse_number("--torque-limit", v, positive=True) for v in parts)  # type: ignore[assignment]
    prior = robot_to_standard(published["1.0"])
    bar = ProgressBar("output-error fit", enabled=not args.no_progress and sys.stderr.isatty())
    # the robot's name labels every study run on this plant (pendulab.evaluate.realai.plant.plant_label)
    meta = {
        "robot": robot if args.dataset else "records", "prior": f"DFKI {robot} model 1.0 (masses only)",
        **({"dataset": args.dataset} if args.dataset else {}),
    }  # fmt: skip
    result = identify(
        records, fixed, prior, cutoff_hz=cutoff, torque_limit=limit, structure=args.structure,
        progress=lambda it, rms: bar.iterate(1, unit="iteration"), meta=meta,
    )  # fmt: skip
    bar.close()
    out = Path(args.out)
    plant_path = save_plant(result.plant, out / "plant.json")
    report: dict[str, Any] = {
        "plant": str(plant_path),
        "chosen_structure": result.chosen,
        "structures": result.plant.meta["structures"],
        "base_parameters": result.plant.meta["base_parameters"],
        "params": result.plant.params,
        "stderr": {k: (None if v != v else v) for k, v in result.plant.stderr.items()},
        "torque_offset": list(result.plant.torque_offset),
        "fit_angle_rms": result.plant.meta["fit_angle_rms"],
        "records": [r.name for r in records],
    }
    (out / "identification.json").write_text(json.dumps(report, indent=2) + "\n")
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    print(f"structure: {result.chosen} (leave-one-record-out torque RMS, BIC):")
    for s in result.structures:
        print(f"  {s.name:10s} {s.n_base:2d} base params  LOO RMS {s.cv_rms[0]:.4f} / {s.cv_rms[1]:.4f} N.m  BIC {s.bic:9.1f}")
    print("base parameters (value ± standard error):")
    for name, (value, se) in result.plant.meta["base_parameters"].items():
        print(f"  {name:16s} {value: .6g} ± {se:.2g}")
    print(f"wrote {plant_path} and {out / 'identification.json'}")
    return 0

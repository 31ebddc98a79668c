"""Export and validate an FMU
==========================

Export the elastic double pendulum as an FMI 3.0 FMU and check it against the native integrator.

Writes ``elastic.fmu`` and the overlay plot ``elastic_validation.png`` to ``out_dir``.

Run: ``python examples/export_fmu.py [OUT_DIR]`` (default ``fmu_example``; needs a C compiler, a few seconds;
progress on stderr)
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import pendulab as pl
from pendulab.fmu import export, validate


def run(
    *,
    kind: str = "elastic",
    fmi_version: int = 3,
    scenes: tuple[str, ...] = ("elastic_stiff_forced",),
    out_dir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Export, validate on ``scenes``; return the FMU path, PASS flag, max error and plot path.

    ``progress(message)``, if given, is called before the export (C compilation) and the validation.
    """
    say = progress or (lambda message: None)
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="pendulab_fmu_"))
    say(f"exporting the {kind} model as an FMI {fmi_version}.0 FMU (generated C, compiled) ...")
    fmu = export(pl.make_model(kind), out / f"{kind}.fmu", fmi_version, timestamp=False)
    say(f"validating {fmu.name} against the native integrator on {', '.join(scenes)} (CS and ME) ...")
    report = validate(fmu, scenes=list(scenes), out_dir=out)
    return {
        "fmu": fmu,
        "passed": report.passed,
        "max_error": max(r.max_error for r in report.rows),
        "plot": report.plot,
        "table": report.table(),
    }


def main() -> None:
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("fmu_example")
    result = run(out_dir=out_dir, progress=lambda message: print(message, file=sys.stderr))
    print(result["table"])
    print(f"FMU: {result['fmu']}  plot: {result['plot']}")


if __name__ == "__main__":
    main()

"""Export and validate an FMU
==========================

Export the elastic double pendulum as an FMI 3.0 FMU and check it against the native integrator.

Writes ``elastic.fmu`` and the overlay plot ``elastic_validation.png`` to ``out_dir``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import pendulab as pl
from pendulab.fmu import export, validate


def run(
    *,
    kind: str = "elastic",
    fmi_version: int = 3,
    scenes: tuple[str, ...] = ("elastic_stiff_forced",),
    out_dir: str | Path | None = None,
) -> dict:
    """Export, validate on ``scenes``; return the FMU path, PASS flag, max error and plot path."""
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="pendulab_fmu_"))
    fmu = export(pl.make_model(kind), out / f"{kind}.fmu", fmi_version, timestamp=False)
    report = validate(fmu, scenes=list(scenes), out_dir=out)
    return {
        "fmu": fmu,
        "passed": report.passed,
        "max_error": max(r.max_error for r in report.rows),
        "plot": report.plot,
        "table": report.table(),
    }


def main() -> None:
    result = run(out_dir=Path("fmu_example"))
    print(result["table"])
    print(f"FMU: {result['fmu']}  plot: {result['plot']}")


if __name__ == "__main__":
    main()

"""Reading a pendulab FMU for validation: is the archive readable, which model kind, its start values."""

from __future__ import annotations

import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..model.model import make_model

__all__ = ["UnreadableFMUError", "fmu_kind", "fmu_start_values"]


class UnreadableFMUError(ValueError):
    """The file is not a readable FMU: not a zip archive, a truncated archive, no or a schema-invalid
    ``modelDescription.xml``. (The CLI reports it in one line with exit status 2, FAIL is status 1.)"""


def fmu_kind(model_description) -> str:
    """Model kind of a pendulab FMU from its model identifier.

    Parameters
    ----------
    model_description : fmpy.model_description.ModelDescription
        As read by ``fmpy.read_model_description``; the Co-Simulation (else
        Model Exchange) identifier is used.

    Returns
    -------
    str
        ``"rigid"`` or ``"elastic"``.

    Raises
    ------
    ValueError
        The identifier is neither ``pendulab_rigid`` nor ``pendulab_elastic``,
        or the FMU has neither interface.
    """
    interface = model_description.coSimulation or model_description.modelExchange
    if interface is None:
        raise ValueError("not a pendulab FMU: it has neither a Co-Simulation nor a Model Exchange interface")
    ident = interface.modelIdentifier
    for kind in ("rigid", "elastic"):
        if ident == f"pendulab_{kind}":
            return kind
    raise ValueError(f"not a pendulab FMU: model identifier {ident!r}, expected 'pendulab_rigid' or 'pendulab_elastic'")


def fmu_start_values(model_description, kind: str) -> tuple[dict[str, float], dict[str, float]]:
    """Parameter and state start values of a pendulab FMU, from its model description.

    Parameters
    ----------
    model_description : fmpy.model_description.ModelDescription
        As read by ``fmpy.read_model_description``.
    kind : {"rigid", "elastic"}
        The FMU's model kind (:func:`fmu_kind`).

    Returns
    -------
    params : dict of str to float
        Start values of the model parameters (SI units), by name.
    start : dict of str to float
        Start values of the states, by name (``model.state_names`` order).

    Raises
    ------
    ValueError
        A parameter or state of the model has no numeric start value in the FMU.
    """
    model = make_model(kind)
    starts = {v.name: v.start for v in model_description.modelVariables}
    out: list[dict[str, float]] = []
    for names, what in ((model.param_names, "parameter"), (model.state_names, "state")):
        values = {}
        for name in names:
            try:
                values[name] = float(starts[name])
            except (KeyError, TypeError, ValueError):
                raise ValueError(
                    f"not a pendulab FMU: {what} {name!r} has no numeric start value (got {starts.get(name)!r})"
                ) from None
        out.append(values)
    return out[0], out[1]


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _read(fmu: Path, validate_fmu: Callable, read_model_description: Callable) -> tuple[list[str], Any]:
    """fmpy's findings and the model description, or UnreadableFMUError in one line (fmpy raises bare
    ``Exception``, ``BadZipFile``, ``KeyError`` and ``ValidationError`` for unreadable files)."""
    try:
        with zipfile.ZipFile(fmu) as zf:
            bad = zf.testzip()
            names = set(zf.namelist())
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise UnreadableFMUError(f"FMU {str(fmu)!r} is not a readable FMU (zip archive): {_first_line(exc)}") from None
    if bad is not None:
        raise UnreadableFMUError(f"FMU {str(fmu)!r} is a corrupt archive: member {bad!r} fails its CRC check")
    if "modelDescription.xml" not in names:
        raise UnreadableFMUError(f"FMU {str(fmu)!r} is not an FMU: the archive has no modelDescription.xml")
    try:
        problems = list(validate_fmu(str(fmu)))
        md = read_model_description(str(fmu))
    except Exception as exc:  # noqa: BLE001 - fmpy's errors of an unreadable file, reported in one line
        detail = getattr(exc, "problems", None)
        reason = f"{detail[0]}" + (f" (and {len(detail) - 1} more)" if len(detail) > 1 else "") if detail else _first_line(exc)
        raise UnreadableFMUError(f"FMU {str(fmu)!r}: modelDescription.xml is invalid: {reason}") from None
    return problems, md

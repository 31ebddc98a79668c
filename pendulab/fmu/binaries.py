"""The FMU binaries pendulab loads in its own process: those it exported, and any other only after a probe.

A shared library loaded with ``dlopen`` runs in the caller's process: a damaged one (a truncated
``.so`` maps past its end) kills it with SIGBUS or SIGSEGV, which no ``try`` catches. So before
fmpy loads an FMU's binary here (:func:`pendulab.fmu.validate`, :class:`pendulab.cosim.FmuPlant`,
hence ``pendulab fmu validate`` and ``pendulab cosim --fmu``), :func:`check_fmu_binary` decides:

* **exported by pendulab**: :func:`pendulab.fmu.export` writes a manifest into the archive
  (:data:`MANIFEST_PATH`, the SHA-256 of every binary it packed). A binary that matches it is
  byte for byte what the export built and tested, and is loaded directly;
* **anything else** (no manifest, a binary that does not match it, an FMU re-packed by another
  tool): a child process loads the binary and runs it once (instantiate, initialize at the start
  values, one step, terminate, free). Only when the child finishes cleanly is the binary loaded
  here (once per distinct binary and process); a child killed by a signal, failing or hanging
  becomes a :class:`FMUBinaryError` naming the FMU, the binary, the signal and the stage reached.

The check runs on the extracted files the caller is about to load, so the bytes checked are the
bytes loaded.
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .._version import __version__
from .fmu_file import UnreadableFMUError

__all__ = ["MANIFEST_PATH", "FMUBinaryError", "binary_manifest", "check_fmu_binary", "PROBE_TIMEOUT"]

#: Where an exported FMU lists the SHA-256 of its binaries (FMI's folder for extra files, a reverse-domain name).
MANIFEST_PATH: str = "extra/org.pendulab/binaries.json"
#: Seconds a probe may take (interpreter start and fmpy import included) before it counts as hung.
PROBE_TIMEOUT: float = 120.0

#: Binaries (tuples of SHA-256) whose probe passed in this process: probed once, however many instances follow.
_PROBED: set[tuple[str, ...]] = set()
_LOCK = threading.Lock()


class FMUBinaryError(UnreadableFMUError):
    """An FMU's binary crashed, failed or hung in a probe process; it was not loaded in this one.

    A :class:`~pendulab.fmu.fmu_file.UnreadableFMUError` (a ``ValueError``): the CLI reports it in
    one line with exit status 2.
    """


def binary_manifest(files: Mapping[str, bytes]) -> bytes:
    """The manifest an export packs at :data:`MANIFEST_PATH`: the SHA-256 of every ``binaries/`` member.

    Parameters
    ----------
    files : mapping of str to bytes
        The archive's members by name.

    Returns
    -------
    bytes
        JSON (sorted keys: the archive stays byte-reproducible).
    """
    digests = {name: hashlib.sha256(data).hexdigest() for name, data in files.items() if name.startswith("binaries/")}
    text = json.dumps({"generator": f"pendulab {__version__}", "binaries": digests}, indent=1, sort_keys=True)
    return (text + "\n").encode()


def _digest(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _binaries(unzipdir: Path, md: Any) -> list[tuple[str, str]]:
    """``(archive name, interface)`` of the host binary of each interface the FMU declares."""
    import fmpy

    folder = fmpy.platform if str(md.fmiVersion).startswith("2") else fmpy.platform_tuple
    out = []
    for interface, desc in (("CoSimulation", md.coSimulation), ("ModelExchange", md.modelExchange)):
        if desc is not None:
            out.append((f"binaries/{folder}/{desc.modelIdentifier}{fmpy.sharedLibraryExtension}", interface))
    return out


def _manifest(unzipdir: Path) -> dict[str, str] | None:
    """The binary digests of the extracted FMU's manifest, or None without a readable one."""
    try:
        data = json.loads((unzipdir / MANIFEST_PATH).read_text(encoding="utf-8"))
        digests = data["binaries"]
    except (OSError, ValueError, TypeError, KeyError):
        return None
    return digests if isinstance(digests, dict) else None


def check_fmu_binary(unzipdir: str | os.PathLike, model_description: Any, *, fmu: str | os.PathLike) -> str:
    """Make sure loading the extracted FMU's binary cannot crash this process: trust it by its manifest, or probe it.

    Parameters
    ----------
    unzipdir : path-like
        The extracted FMU, about to be loaded by fmpy from there.
    model_description : fmpy.model_description.ModelDescription
        Its model description (the interfaces and their model identifiers).
    fmu : path-like
        The ``.fmu`` file, for messages.

    Returns
    -------
    str
        ``"exported by pendulab"`` (the binaries match the export's manifest), ``"probed"`` (a child
        process ran them cleanly) or ``"probed before"`` (the same binaries, in this process).

    Raises
    ------
    FMUBinaryError (UnreadableFMUError, ValueError)
        No binary for this platform, or the probe process was killed by a signal (the message names
        it, e.g. SIGBUS), failed or hung; the binary was not loaded in this process.
    """
    root = Path(unzipdir)
    binaries = _binaries(root, model_description)
    if not binaries:
        raise FMUBinaryError(f"FMU {str(fmu)!r} has neither a Co-Simulation nor a Model Exchange interface to load")
    names = sorted({name for name, _ in binaries})
    missing = [n for n in names if not (root / n).is_file()]
    if missing:
        raise FMUBinaryError(f"FMU {str(fmu)!r} has no binary for this platform: {missing[0]} is not in the archive")
    digests = {n: _digest(root / n) for n in names}
    manifest = _manifest(root)
    if manifest is not None and all(manifest.get(n) == d for n, d in digests.items()):
        return "exported by pendulab"
    key = tuple(digests[n] for n in names)
    with _LOCK:
        if key in _PROBED:
            return "probed before"
    note = ""
    if manifest is not None:
        note = "; it does not match the SHA-256 that pendulab recorded when it exported this FMU (damaged or replaced since)"
    _probe(root, model_description, fmu, names, note)
    with _LOCK:
        _PROBED.add(key)
    return "probed"


def _probe(root: Path, md: Any, fmu: Any, names: list[str], note: str) -> None:
    """Run the FMU once in a child process; FMUBinaryError unless it finishes cleanly."""
    args = {
        "unzipdir": str(root),
        "fmi3": str(md.fmiVersion).startswith("3"),
        "token": md.guid,
        "cs": md.coSimulation.modelIdentifier if md.coSimulation is not None else None,
        "me": md.modelExchange.modelIdentifier if md.modelExchange is not None else None,
        "step": float(getattr(md.defaultExperiment, "stepSize", None) or 1e-3),
    }
    what = f"FMU {str(fmu)!r}: its binary {', '.join(names)}"
    try:
        proc = subprocess.run(
            [sys.executable, "-c", _PROBE_SOURCE, json.dumps(args)],
            capture_output=True,
            text=True,
            timeout=PROBE_TIMEOUT,
            stdin=subprocess.DEVNULL,
        )
    except subprocess.TimeoutExpired:
        raise FMUBinaryError(
            f"{what} did not finish a probe run (load, instantiate, initialize, one step) in {PROBE_TIMEOUT:g} s; "
            f"it was not loaded in this process{note}"
        ) from None
    except OSError as exc:
        raise FMUBinaryError(f"{what} could not be probed in a child process ({exc}); it was not loaded") from None
    stages = [line[6:] for line in proc.stdout.splitlines() if line.startswith("stage ")]
    stage = f" while it {stages[-1]}" if stages else " while it was loaded"
    if proc.returncode == 0 and stages and stages[-1] == "finished":
        return
    if proc.returncode < 0:
        try:
            name = signal.Signals(-proc.returncode).name
        except ValueError:
            name = f"signal {-proc.returncode}"
        raise FMUBinaryError(
            f"{what} crashed a probe process with {name}{stage}: the binary is damaged or incompatible with this "
            f"machine; it was not loaded in this process{note}"
        )
    detail = [line for line in proc.stderr.splitlines() if line.startswith("probe-error: ")]
    reason = detail[-1][len("probe-error: ") :] if detail else f"exit status {proc.returncode}"
    raise FMUBinaryError(f"{what} failed a probe run{stage} ({reason}); it was not loaded in this process{note}")


# The child: fmpy only (no pendulab import: quick to start, and nothing of this process's state).
# It prints each stage before entering it, so the parent can say where a crash happened.
_PROBE_SOURCE = r"""
import json, sys
args = json.loads(sys.argv[1])
def stage(text):
    print("stage " + text, flush=True)
try:
    from fmpy import fmi2, fmi3
    for interface in ("cs", "me"):
        ident = args[interface]
        if ident is None:
            continue
        label = "Co-Simulation" if interface == "cs" else "Model Exchange"
        if args["fmi3"]:
            cls = fmi3.FMU3Slave if interface == "cs" else fmi3.FMU3Model
        else:
            cls = fmi2.FMU2Slave if interface == "cs" else fmi2.FMU2Model
        stage(f"was loaded ({label})")
        fmu = cls(guid=args["token"], unzipDirectory=args["unzipdir"], modelIdentifier=ident, instanceName="probe")
        stage(f"was instantiated ({label})")
        fmu.instantiate()
        stage(f"was initialized ({label})")
        if args["fmi3"]:
            fmu.enterInitializationMode(startTime=0.0)
        else:
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        if interface == "cs":
            stage(f"took one step ({label})")
            fmu.doStep(0.0, args["step"])
        stage(f"was terminated ({label})")
        fmu.terminate()
        fmu.freeInstance()
    stage("finished")
except Exception as exc:
    text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    print(f"probe-error: {type(exc).__name__}: {text}", file=sys.stderr, flush=True)
    sys.exit(3)
"""

"""The C layer under AddressSanitizer + UndefinedBehaviorSanitizer: the C importers and a C fuzz driver.

One build per session in a separate folder (never the cached FMUs): the FMU sources with
``-fsanitize=address,undefined -fno-omit-frame-pointer -g``, as a shared library for the dlopen harnesses
(tests/fmu/c/fmi{2,3}_harness.c, built with the sanitizers too, so the runtime comes from the executable)
and linked statically into tests/fmu/c/fuzz_driver.c (random call sequences with edge values, NULLs and
garbage FMU states). Skipped, with the reason, where the compiler cannot build sanitized programs.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

import pendulab as pl
from pendulab.fmu.codegen import compiled_sources, generate_sources, layout, token
from pendulab.fmu.export import find_compiler

HARNESS = Path(__file__).parent / "c"
SAN = ["-fsanitize=address,undefined", "-fno-omit-frame-pointer", "-g", "-O1"]
WARN = ["-std=c99", "-Wall", "-Wextra", "-Werror"]
ENV = dict(
    os.environ,
    ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:exitcode=86",
    UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:exitcode=87",
)


def _sanitizers_missing(cc: str, tmp: Path) -> str | None:
    src = tmp / "probe.c"
    src.write_text("#include <stdlib.h>\nint main(void) { char *p = malloc(4); p[0] = 0; free(p); return 0; }\n")
    proc = subprocess.run([cc, *SAN, str(src), "-o", str(tmp / "probe")], capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        return f"{cc} cannot build with {' '.join(SAN[:1])}: {proc.stderr.strip()[:200]}"
    run = subprocess.run([str(tmp / "probe")], capture_output=True, text=True, env=ENV, check=False)
    if run.returncode != 0:
        return f"sanitized programs do not run here: {run.stderr.strip()[:200]}"
    return None


def _shared_dir(tmp_path_factory) -> Path:
    base = tmp_path_factory.getbasetemp()
    return base.parent if base.name.startswith("popen-gw") else base


def _run(cmd: list[str]) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}\n{proc.stderr}")


def _build_one(cc: str, root: Path, kind: str, version: int) -> None:
    """Sanitized FMI layer, core and solver; the generated model functions (not hand-written) unsanitized."""
    model = pl.make_model(kind)
    src = root / f"{kind}{version}"
    src.mkdir(exist_ok=True)
    for name, data in generate_sources(model, version).items():
        (src / name).write_bytes(data)
    objs = []
    for unit in compiled_sources(version):
        obj = src / (unit + ".o")
        flags = ["-O1", "-g"] if unit == "model_functions.c" else [*WARN, *SAN]
        _run([cc, "-std=c99", *flags, "-fPIC", "-fvisibility=hidden", "-c", str(src / unit), "-o", str(obj)])
        objs.append(str(obj))
    _run([cc, *SAN, "-shared", *objs, "-o", str(src / f"pendulab_{kind}.so"), "-lm"])
    _run(
        [
            cc,
            *WARN,
            *SAN,
            f"-DFUZZ_FMI={version}",
            "-I",
            str(src),
            str(HARNESS / "fuzz_driver.c"),
            *[o for o in objs],
            "-o",
            str(src / "fuzz_driver"),
            "-lm",
        ]
    )
    _run([cc, *WARN, *SAN, "-I", str(src), str(HARNESS / f"fmi{version}_harness.c"), "-o", str(src / "harness"), "-ldl", "-lm"])
    (src / "token").write_text(token(layout(model), version))


@pytest.fixture(scope="session")
def san_build(tmp_path_factory):
    """{(kind, version): (folder, sanitized .so, fuzz driver, token)}, built once per session; skips without sanitizers."""
    import fcntl
    from concurrent.futures import ThreadPoolExecutor

    cc = find_compiler()
    root = _shared_dir(tmp_path_factory) / "pendulab_sanitized"
    root.mkdir(exist_ok=True)
    reason = _sanitizers_missing(cc, root)
    if reason:
        pytest.skip(reason)
    combos = [(kind, version) for kind in ("rigid", "elastic") for version in (2, 3)]
    with open(root / "build.lock", "w") as lock:  # one xdist worker builds, the others wait and reuse
        fcntl.flock(lock, fcntl.LOCK_EX)
        missing = [c for c in combos if not (root / f"{c[0]}{c[1]}" / "token").exists()]
        with ThreadPoolExecutor(max_workers=4) as pool:
            list(pool.map(lambda c: _build_one(cc, root, *c), missing))
        fcntl.flock(lock, fcntl.LOCK_UN)
    out = {}
    for kind, version in combos:
        src = root / f"{kind}{version}"
        out[(kind, version)] = (src, src / f"pendulab_{kind}.so", src / "fuzz_driver", (src / "token").read_text())
    return out


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("version", [2, 3])
def test_c_importer_is_clean_under_asan_ubsan(san_build, kind, version):
    src, lib, _, tok = san_build[(kind, version)]
    exe = src / "harness"
    proc = subprocess.run([str(exe), str(lib), tok, "50"], capture_output=True, text=True, timeout=120, env=ENV, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr, proc.stderr[-3000:]


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("version", [2, 3])
def test_c_fuzz_driver_is_clean_under_asan_ubsan(san_build, kind, version, request):
    _, _, fuzz, tok = san_build[(kind, version)]
    long = request.config.getoption("--fuzz-long", default=False)
    # elastic sequences are slower (huge steps run up to the internal-step limit): fewer in the short run
    n = (3000 if long else 300) if kind == "rigid" else (3000 if long else 40)
    proc = subprocess.run(
        [str(fuzz), tok, str(n), "60", str(version)], capture_output=True, text=True, timeout=600, env=ENV, check=False
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "runtime error" not in proc.stderr and "AddressSanitizer" not in proc.stderr, proc.stderr[-3000:]
    assert f"sequences={n} " in proc.stdout, proc.stdout

"""The native library's disk cache cannot poison later runs: damage matrix, load failure, interrupted and concurrent builds.

Every run that loads a (possibly damaged) cached library happens in a subprocess, so a crash
(SIGBUS, SIGSEGV, SIGILL when a damaged shared library is mapped) shows as a failing exit code
instead of killing the test session.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import pendulab as pl
from pendulab.native.build import digest_path, seal, sealed_key, shared_library_suffix, verify_cached

pytestmark = pytest.mark.needs_cc

ROOT = Path(__file__).resolve().parents[2]
X0 = [2.0, 0.0, 0.0, 0.0]  # the reproducer: --set theta1=2 (short horizon: the answer is checked below)
T_FINAL = 1.0
RUN = (
    "import json, warnings, pendulab as pl\n"
    "with warnings.catch_warnings(record=True) as w:\n"
    "    warnings.simplefilter('always')\n"
    f"    tr = pl.simulate(pl.rigid(), {X0}, {T_FINAL}, method='compiled-dopri5', rtol=1e-10, atol=1e-10)\n"
    "print(json.dumps({'x': tr.x[-1].tolist(), 'warnings': [f'{x.category.__name__}: {x.message}' for x in w]}))\n"
)
DAMAGES = ("truncate", "flip_bytes", "empty", "garbage")


def damage(path: Path, how: str) -> None:
    """Damage a cached file in place, the four ways of the issue's matrix."""
    data = bytearray(path.read_bytes())
    if how == "truncate":
        data = data[: len(data) // 3]
    elif how == "flip_bytes":
        for i in range(len(data) // 4, len(data), 997):  # past the ELF header: the file still maps, code is wrong
            data[i] ^= 0xFF
    elif how == "empty":
        data = bytearray()
    elif how == "garbage":
        data = bytearray(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    else:  # pragma: no cover
        raise ValueError(how)
    path.write_bytes(bytes(data))


def run(cache: Path, code: str = RUN, **env_extra: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PENDULAB_CACHE_DIR": str(cache), **env_extra}
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)


def library(cache: Path) -> Path:
    (lib,) = (cache / "native").glob(f"pendulab_native_rigid-*{shared_library_suffix()}")
    return lib


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> tuple[Path, list[float]]:
    """A cache folder holding an intact rigid library, and the answer it gives."""
    cache = tmp_path_factory.mktemp("native-cache")
    proc = run(cache)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["warnings"] == []  # a first build is not a rebuild: nothing to warn about
    assert verify_cached(library(cache)) is None
    return cache, out["x"]


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    # An independent integrator (heyoka Taylor at 1e-15) for "the right answer".
    return pl.simulate(pl.rigid(), X0, T_FINAL, method="taylor", rtol=1e-15, atol=1e-15).x[-1]


@pytest.mark.parametrize("how", DAMAGES)
def test_damaged_library_is_rebuilt_once_with_a_warning_and_the_right_answer(built, reference, tmp_path, how):
    good, x_good = built
    cache = tmp_path / "cache"
    shutil.copytree(good, cache)
    lib = library(cache)
    damage(lib, how)
    proc = run(cache)
    # A crash would be a negative exit code (signal) here, not a pytest crash.
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    out = json.loads(proc.stdout)
    rebuilt = [w for w in out["warnings"] if w.startswith("CacheRebuildWarning")]
    assert len(rebuilt) == 1 and str(lib) in rebuilt[0] and "rebuilding" in rebuilt[0], out["warnings"]
    # Same sources, compiler and flags as the first build: the same arithmetic, bit for bit.
    np.testing.assert_array_equal(out["x"], x_good)
    # DOPRI5 at 1e-10 vs Taylor at 1e-15 over 1 s from theta1 = 2 rad (before the chaos amplifies errors).
    np.testing.assert_allclose(out["x"], reference, rtol=0, atol=1e-7)
    assert verify_cached(lib) is None  # the cache is healed: the next run loads it silently
    again = json.loads(run(cache).stdout)
    assert again["warnings"] == [] and again["x"] == x_good


@pytest.mark.parametrize("how", ["missing", "wrong"])
def test_damaged_digest_file_is_a_rebuild_too(built, tmp_path, how):
    good, x_good = built
    cache = tmp_path / "cache"
    shutil.copytree(good, cache)
    lib = library(cache)
    if how == "missing":
        digest_path(lib).unlink()
    else:
        digest_path(lib).write_text("0" * 64 + "\n")
    out = json.loads(run(cache).stdout)
    assert any("CacheRebuildWarning" in w and str(lib) in w for w in out["warnings"])
    assert out["x"] == x_good and verify_cached(lib) is None


def test_a_library_that_fails_to_load_despite_its_digest_is_rebuilt(built, tmp_path):
    # A file whose digest matches but which dlopen refuses (as if a build had gone wrong): load failure -> rebuild.
    good, x_good = built
    cache = tmp_path / "cache"
    shutil.copytree(good, cache)
    lib = library(cache)
    key = sealed_key(lib)
    lib.write_bytes(b"not a shared library\n")
    seal(lib, key)
    proc = run(cache)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert any("failed to load" in w and str(lib) in w for w in out["warnings"]), out["warnings"]
    assert out["x"] == x_good and verify_cached(lib) is None


def test_cache_errors_name_the_cache_path(tmp_path):
    # A compiler that fails: the error names the cache file it was building.
    fail_cc = tmp_path / "failcc"
    fail_cc.write_text("#!/bin/sh\necho 'simulated compiler failure' >&2\nexit 1\n")
    fail_cc.chmod(0o755)
    cache = tmp_path / "cache"
    proc = run(cache, CC=str(fail_cc))
    assert proc.returncode != 0
    assert str(cache / "native") in proc.stderr and "simulated compiler failure" in proc.stderr
    assert "RuntimeError" in proc.stderr and not list((cache / "native").glob(f"*{shared_library_suffix()}"))
    # A cache "folder" that is a file: the error names it and the variable to set.
    blocker = tmp_path / "blocker"
    blocker.write_text("a file, not a folder")
    proc = run(blocker)
    assert proc.returncode != 0 and str(blocker / "native") in proc.stderr and "PENDULAB_CACHE_DIR" in proc.stderr


def test_two_processes_building_the_same_library_do_not_corrupt_each_other(built, tmp_path):
    _, x_good = built
    cache = tmp_path / "cache"
    env = {**os.environ, "PENDULAB_CACHE_DIR": str(cache)}
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", RUN], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    outs = [p.communicate(timeout=300) for p in procs]
    for p, (stdout, stderr) in zip(procs, outs, strict=True):
        assert p.returncode == 0, stderr
        out = json.loads(stdout)
        assert out["x"] == x_good and out["warnings"] == []  # the second waited for the first: no rebuild, no warning
    lib = library(cache)
    assert verify_cached(lib) is None
    assert not list((cache / "native").glob(".*"))  # no temporary left behind


def _stat(pid: int) -> tuple[str, str] | None:
    """(state, start time) of ``pid`` from /proc, or None when there is no such process."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (FileNotFoundError, ProcessLookupError, IndexError):
        return None
    return fields[0], fields[19]  # fields 3 and 22 of proc(5), counted after the command name


def _alive(pid: int, start: str | None = None) -> bool:
    """True while ``pid`` runs: a zombie (killed but not reaped by a container's init) counts as gone, and so does
    another process that reused the number (pid_max is 32768 here; a loaded host recycles pids within seconds)."""
    stat = _stat(pid)
    if stat is None or stat[0] in ("Z", "X"):
        return False
    return start is None or stat[1] == start


@pytest.mark.skipif(not Path("/proc").is_dir() or os.name != "posix", reason="reads /proc; POSIX signals")
def test_ctrl_c_during_a_build_kills_the_compiler_and_its_children(tmp_path):
    # A "compiler" that starts a child and waits, as gcc starts cc1/as/ld: both must die with the interrupt.
    pids = tmp_path / "pids"
    pids.mkdir()
    slow_cc = tmp_path / "slowcc"
    slow_cc.write_text(f'#!/bin/sh\nsleep 600 &\necho $! > "{pids}/child"\necho $$ > "{pids}/driver"\nwait\n')
    slow_cc.chmod(0o755)
    cache = tmp_path / "cache"
    env = {**os.environ, "PENDULAB_CACHE_DIR": str(cache), "CC": str(slow_cc)}
    code = (
        "import pendulab.native as n\ntry:\n    n.native_library('rigid')\nexcept KeyboardInterrupt:\n    print('interrupted')\n"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", code], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        for _ in range(1200):  # until the fake compiler runs (not a timing assertion: a bound on waiting)
            if (pids / "driver").exists() and (pids / "child").exists() and (pids / "driver").read_text().strip():
                break
            time.sleep(0.05)
        else:
            pytest.fail("the fake compiler never started")
        driver, child = (int((pids / n).read_text()) for n in ("driver", "child"))
        assert _alive(driver) and _alive(child)
        started = {pid: _stat(pid)[1] for pid in (driver, child)}
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert "interrupted" in stdout, stderr
    for _ in range(200):  # SIGKILL is asynchronous: give the kernel a moment to tear the group down
        if not (_alive(driver, started[driver]) or _alive(child, started[child])):
            break
        time.sleep(0.05)
    assert not _alive(driver, started[driver]) and not _alive(child, started[child])  # no orphaned compiler
    native = cache / "native"
    assert not list(native.glob(f"*{shared_library_suffix()}")) and not list(native.glob(".*"))  # nothing half-built left


def test_rtol_of_one_or_more_is_refused_before_anything_is_built(tmp_path, monkeypatch):
    monkeypatch.setenv("PENDULAB_CACHE_DIR", str(tmp_path / "cache"))
    for method in ("compiled-dopri5", "compiled-rodas4"):
        for rtol in (1.0, 10.0):
            with pytest.raises(ValueError, match=r"rtol = .*: out of range; expected a finite number in \[2.22e-16, 1\)"):
                pl.simulate(pl.rigid(), X0, 1.0, method=method, rtol=rtol)
    assert not (tmp_path / "cache").exists()  # refused before the library was looked up or built


def test_damaged_library_without_a_compiler_says_it_is_damaged_and_where(built, tmp_path):
    good, _ = built
    cache = tmp_path / "cache"
    shutil.copytree(good, cache)
    lib = library(cache)
    damage(lib, "truncate")
    proc = run(cache, PATH=str(tmp_path / "no-bin"), CC="no-such-compiler")
    assert proc.returncode != 0  # a clean error (the damaged file is never loaded), not a crash
    assert proc.returncode > 0 and "CompilerNotFoundError" in proc.stderr
    assert f"the cached file {lib} does not match its SHA-256 digest" in proc.stderr and "no C compiler" in proc.stderr


@pytest.mark.skipif(not Path("/proc").is_dir() or os.name != "posix", reason="reads /proc; POSIX signals")
def test_ctrl_c_while_the_compiler_starts_still_kills_it(tmp_path, monkeypatch):
    # Under load the Ctrl-C can land after the fork, inside Popen: the compiler runs but no process object exists yet.
    from pendulab.native import compiler

    real_popen = subprocess.Popen
    started: list[subprocess.Popen] = []

    def popen_hit_by_ctrl_c(*args, **kwargs):
        proc = real_popen(*args, **kwargs)
        started.append(proc)
        os.kill(os.getpid(), signal.SIGINT)  # delivered before Popen returns
        return proc

    monkeypatch.setattr(compiler.subprocess, "Popen", popen_hit_by_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        compiler._run_compiler(["sleep", "600"])
    (proc,) = started
    assert proc.returncode is not None and not _alive(proc.pid)  # killed and reaped, not orphaned

"""The gym FMU backend's cached FMU cannot poison later runs: damage matrix, damaged digest, load failure, concurrency.

Each run happens in a subprocess with its own cache folder, so a crash while loading a damaged
FMU's binary would show as a failing exit code.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pendulab.native.build import digest_path, seal, sealed_key, verify_cached

pytestmark = pytest.mark.needs_cc

ROOT = Path(__file__).resolve().parents[2]
RUN = (
    "import json, warnings\n"
    "import numpy as np, gymnasium as gym, pendulab.gym\n"
    "with warnings.catch_warnings(record=True) as w:\n"
    "    warnings.simplefilter('always')\n"
    "    env = gym.make(pendulab.gym.ENV_ID, model='rigid', actuation='full', backend='fmu')\n"
    "    env.reset(options={'state': [2.0, 0.0, 0.0, 0.0]})\n"
    "    for k in range(50):\n"
    "        env.step(np.array([np.sin(0.1 * k), 0.5], dtype=np.float32))\n"
    "    env.close()\n"
    "print(json.dumps({'x': env.unwrapped.state.tolist(),\n"
    "                  'warnings': [f'{x.category.__name__}: {x.message}' for x in w if 'pendulab' in str(x.message)]}))\n"
)


def damage(path: Path, how: str) -> None:
    """Damage a cached file in place, the four ways of the issue's matrix."""
    data = bytearray(path.read_bytes())
    if how == "truncate":
        data = data[: len(data) // 2]
    elif how == "flip_bytes":
        for i in range(len(data) // 4, len(data), 997):
            data[i] ^= 0xFF
    elif how == "empty":
        data = bytearray()
    elif how == "garbage":
        data = bytearray(np.random.default_rng(1).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    else:  # pragma: no cover
        raise ValueError(how)
    path.write_bytes(bytes(data))


def run(cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PENDULAB_CACHE_DIR": str(cache)}
    return subprocess.run([sys.executable, "-c", RUN], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)


def cached_fmu_file(cache: Path) -> Path:
    (fmu,) = (cache / "gym").glob("pendulab_rigid_*.fmu")
    return fmu


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> tuple[Path, list[float]]:
    """A cache folder holding an intact rigid FMU, and the state it ends in."""
    cache = tmp_path_factory.mktemp("fmu-cache")
    proc = run(cache)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["warnings"] == []
    assert verify_cached(cached_fmu_file(cache)) is None
    return cache, out["x"]


@pytest.mark.parametrize("how", ["truncate", "flip_bytes", "empty", "garbage"])
def test_damaged_fmu_is_exported_again_once_with_a_warning(built, tmp_path, how):
    good, x_good = built
    cache = tmp_path / "cache"
    shutil.copytree(good, cache)
    fmu = cached_fmu_file(cache)
    damage(fmu, how)
    proc = run(cache)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"  # a crash is a negative exit code
    out = json.loads(proc.stdout)
    assert len(out["warnings"]) == 1, out["warnings"]
    assert out["warnings"][0].startswith("CacheRebuildWarning") and str(fmu) in out["warnings"][0]
    # The same export (byte-reproducible archive, same solver, same torques): the same episode, bit for bit.
    assert out["x"] == x_good
    assert verify_cached(fmu) is None
    assert json.loads(run(cache).stdout)["warnings"] == []  # healed: the next run is silent


def test_missing_digest_and_unreadable_fmu_with_a_matching_digest_are_rebuilt(built, tmp_path):
    good, x_good = built
    cache = tmp_path / "cache"
    shutil.copytree(good, cache)
    fmu = cached_fmu_file(cache)
    digest_path(fmu).unlink()
    out = json.loads(run(cache).stdout)
    assert any("no digest file" in w and str(fmu) in w for w in out["warnings"]) and out["x"] == x_good
    # A file whose digest matches but that is no FMU (as if an export had gone wrong): read failure -> rebuild.
    key = sealed_key(fmu)
    fmu.write_bytes(b"PK\x03\x04 not really a zip")
    seal(fmu, key)
    proc = run(cache)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert any("cannot be read as an FMU" in w and str(fmu) in w for w in out["warnings"]), out["warnings"]
    assert out["x"] == x_good and verify_cached(fmu) is None


def test_two_processes_exporting_the_same_fmu_do_not_corrupt_each_other(built, tmp_path):
    _, x_good = built
    cache = tmp_path / "cache"
    env = {**os.environ, "PENDULAB_CACHE_DIR": str(cache)}
    pipes = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True}
    procs = [subprocess.Popen([sys.executable, "-c", RUN], cwd=ROOT, env=env, **pipes) for _ in range(2)]
    for p in procs:
        stdout, stderr = p.communicate(timeout=600)
        assert p.returncode == 0, stderr
        out = json.loads(stdout)
        assert out["x"] == x_good and out["warnings"] == []
    assert verify_cached(cached_fmu_file(cache)) is None
    assert not list((cache / "gym").glob(".*"))  # no temporary left behind

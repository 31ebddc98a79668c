"""Every cache kind refuses an entry that is damaged, edited or swapped for another's: rebuilt with a warning, never used.

One mechanism (``pendulab.native.cache``) serves the native libraries and RTI steps (``build_cached``), the gym
FMU (``cached_fmu``) and the plan library (``PlanCache``): each entry is sealed with its SHA-256 and its key.
Damages, per kind: truncate, edit (change bytes; for a plan, shift its reference by 0.5 rad or flip its TVLQR
gains and re-save it as a valid ``.npz``), swap two entries (file and seal moved together: intact but another
entry's), swap the files only. Nothing here loads a damaged binary: the checks happen before any load, and a
library is loaded only after it was rebuilt (intact).
"""

from __future__ import annotations

import ctypes
import os
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from pendulab.control.plan_library import PlanCache
from pendulab.native.cache import (
    CacheRebuildWarning,
    cached_artifact,
    digest_path,
    publish,
    read_sealed,
    seal,
    sealed_key,
    verify_cached,
)

DAMAGES = ("truncate", "edit", "swap", "swap_file_only")


def _swap(a: Path, b: Path, *, with_seals: bool) -> None:
    """Exchange two cache entries by renames (and their seals with them)."""
    pairs = [(a, b)] + ([(digest_path(a), digest_path(b))] if with_seals else [])
    for x, y in pairs:
        tmp = x.with_name(x.name + ".swap")
        os.replace(x, tmp)
        os.replace(y, x)
        os.replace(tmp, y)


def _damage(path: Path, other: Path, how: str, edit=None) -> None:
    if how == "truncate":
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    elif how == "edit":
        if edit is None:
            data = bytearray(path.read_bytes())
            data[len(data) // 2] ^= 0x01
            path.write_bytes(bytes(data))
        else:
            edit(path)
    elif how == "swap":
        _swap(path, other, with_seals=True)
    elif how == "swap_file_only":
        _swap(path, other, with_seals=False)
    else:  # pragma: no cover
        raise ValueError(how)


# -- the mechanism itself ------------------------------------------------------------------------------------


def test_a_published_entry_is_sealed_with_its_key_and_checked_on_the_bytes_read(tmp_path):
    path = tmp_path / "entry.bin"
    publish(path, lambda tmp: tmp.write_bytes(b"payload"), what="a test needs its entry; it", key="key-a")
    assert sealed_key(path) == "key-a" and verify_cached(path, "key-a") is None
    assert read_sealed(path, "key-a") == (b"payload", None)
    assert "built for another entry" in verify_cached(path, "key-b")
    assert read_sealed(path, "key-b")[0] is None
    path.write_bytes(b"payloaD")
    assert "does not match its SHA-256" in verify_cached(path, "key-a")
    assert read_sealed(path)[0] is None  # no bytes of a file that fails its seal are ever handed out
    digest_path(path).write_text("0" * 64 + "\n")  # an older pendulab's bare digest: no key, not trusted
    assert "unknown format" in verify_cached(path)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary left behind


def test_a_built_file_that_fails_its_check_is_never_published(tmp_path):
    path = tmp_path / "entry.bin"
    with pytest.raises(RuntimeError, match="could not be built into the cache file .*entry.bin: the built file is empty"):
        cached_artifact(path, lambda tmp: None, what="a test", key="k", check=lambda tmp: "is empty")
    assert not path.exists() and not digest_path(path).exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


# -- native libraries (and RTI steps: the same build_cached) -------------------------------------------------------

SOURCE = '__attribute__((visibility("default"))) int value(void) {{ return {}; }}\n'


def _tiny(directory: Path, n: int) -> Path:
    from pendulab.native.build import build_cached

    unit = "value.c"
    return build_cached("tiny", {unit: SOURCE.format(n).encode()}, [unit], purpose="a test", directory=directory)


@pytest.mark.needs_cc
@pytest.mark.parametrize("how", DAMAGES)
def test_native_library_damaged_edited_or_swapped_is_rebuilt_never_loaded(tmp_path, how):
    lib1, lib2 = _tiny(tmp_path, 1), _tiny(tmp_path, 2)
    assert lib1 != lib2 and sealed_key(lib1).startswith("tiny-") and sealed_key(lib1) != sealed_key(lib2)
    _damage(lib1, lib2, how)
    with pytest.warns(CacheRebuildWarning) as record:
        again = _tiny(tmp_path, 1)
    (message,) = [str(w.message) for w in record if issubclass(w.category, CacheRebuildWarning)]
    expected = "built for another entry" if how == "swap" else "does not match its SHA-256"
    assert str(lib1) in message and expected in message and "rebuilding" in message
    assert again == lib1 and verify_cached(lib1, sealed_key(lib1)) is None
    assert ctypes.CDLL(str(lib1)).value() == 1  # loaded only now, rebuilt: the right library
    if how in ("swap", "swap_file_only"):  # the other slot holds entry 1's library: refused and rebuilt too
        with pytest.warns(CacheRebuildWarning, match=str(lib2)):
            _tiny(tmp_path, 2)
        assert ctypes.CDLL(str(lib2)).value() == 2


@pytest.mark.needs_cc
def test_native_library_without_a_compiler_refuses_a_swapped_entry(tmp_path, monkeypatch):
    from pendulab.native.build import CompilerNotFoundError

    lib1, lib2 = _tiny(tmp_path, 1), _tiny(tmp_path, 2)
    _swap(lib1, lib2, with_seals=True)
    monkeypatch.setenv("PATH", str(tmp_path / "no-bin"))
    monkeypatch.setenv("CC", "no-such-compiler")
    with pytest.raises(CompilerNotFoundError, match="built for another entry"):
        _tiny(tmp_path, 1)


# -- the gym FMU ---------------------------------------------------------------------------------------------------


@pytest.mark.needs_cc
def test_gym_fmu_swapped_for_the_other_kind_is_exported_again(tmp_path, monkeypatch):
    from pendulab.gym.backends import cached_fmu

    monkeypatch.setenv("PENDULAB_CACHE_DIR", str(tmp_path / "cache"))
    rigid, elastic = cached_fmu("rigid"), cached_fmu("elastic")
    rigid_bytes = rigid.read_bytes()
    _swap(rigid, elastic, with_seals=True)  # both intact FMUs with valid seals, each in the other's place
    with pytest.warns(CacheRebuildWarning, match="built for another entry"):
        assert cached_fmu("rigid") == rigid
    assert rigid.read_bytes() == rigid_bytes  # the rigid FMU again (exports are byte-reproducible)
    rigid.write_bytes(rigid_bytes[:1000])
    with pytest.warns(CacheRebuildWarning, match="does not match its SHA-256"):
        cached_fmu("rigid")
    assert rigid.read_bytes() == rigid_bytes


# -- plan-library entries -------------------------------------------------------------------------------------------


def _plan(start: np.ndarray, n: int = 30) -> dict[str, np.ndarray]:
    """A deterministic stand-in for a solved plan from ``start`` (the cache does not care how it was solved)."""
    s = np.linspace(0.0, 1.0, n)[:, None]
    return {
        "ok": np.array(True),
        "x_ref": np.asarray(start, dtype=float) + s * np.array([1.0, -0.5, 2.0, 0.3]),
        "u_ref": np.linspace(-1.0, 1.0, n - 1),
        "K": np.tile([1.0, 2.0, 0.3, 0.4], (n - 1, 1)),
    }


def _resave(change):
    """An edit that leaves a valid ``.npz``: load, change one array, save over the entry."""

    def edit(path: Path) -> None:
        with np.load(path) as z:
            entry = {k: np.array(z[k]) for k in z.files}
        change(entry)
        np.savez(path, **entry)

    return edit


PLAN_EDITS = {
    "shift_reference": _resave(lambda e: e["x_ref"].__setitem__((slice(None), 0), e["x_ref"][:, 0] + 0.5)),
    "flip_gains": _resave(lambda e: e.__setitem__("K", -e["K"])),
}
PLAN_DAMAGES = [("truncate", None), ("swap", None), ("swap_file_only", None)] + [("edit", e) for e in PLAN_EDITS]


def _assert_same(entry, expected) -> None:
    assert entry is not None and entry.keys() == expected.keys()
    for k in expected:
        np.testing.assert_array_equal(entry[k], expected[k])


@pytest.mark.parametrize(("how", "edit"), PLAN_DAMAGES, ids=[e or h for h, e in PLAN_DAMAGES])
def test_plan_entry_damaged_edited_or_swapped_is_solved_again_never_used(tmp_path, how, edit):
    cache = PlanCache(tmp_path, {"task": "pendubot", "params": [1.0, 2.0]})
    a, b = np.array([0.1, 0.2, 0.0, 0.0]), np.array([-2.0, 1.0, 3.0, -4.0])
    solved: list[int] = []

    def solver(start, tag):
        return lambda: solved.append(tag) or _plan(start)

    for start, tag in ((a, 0), (b, 1)):
        _assert_same(cache.get(start, solver(start, tag)), _plan(start))
    assert solved == [0, 1]
    _assert_same(cache.get(a, solver(a, 9)), _plan(a))  # cached: not solved again
    assert solved == [0, 1]
    path = cache.path(a)
    _damage(path, cache.path(b), how, edit=PLAN_EDITS.get(edit))
    with pytest.warns(CacheRebuildWarning) as record:
        entry = cache.get(a, solver(a, 2))
    messages = [str(w.message) for w in record if issubclass(w.category, CacheRebuildWarning)]
    expected = "built for another entry" if how == "swap" else "does not match its SHA-256"
    assert len(messages) == 1 and str(path) in messages[0] and expected in messages[0], messages
    assert solved == [0, 1, 2]  # solved again, and what is returned is the plan from a, as solved
    _assert_same(entry, _plan(a))
    assert verify_cached(path, cache.key(a)) is None and cache.rebuilt == 1


@pytest.mark.parametrize(("how", "edit"), PLAN_DAMAGES, ids=[e or h for h, e in PLAN_DAMAGES])
def test_plan_entry_damaged_edited_or_swapped_is_discarded_by_a_cached_only_load(tmp_path, how, edit):
    cache = PlanCache(tmp_path, {"task": "acrobot"})
    a, b = np.array([3.0, 0.0, 0.0, 0.0]), np.array([0.0, 3.0, 1.0, 1.0])
    cache.save(a, _plan(a))
    cache.save(b, _plan(b))
    _assert_same(cache.load(a), _plan(a))
    _damage(cache.path(a), cache.path(b), how, edit=PLAN_EDITS.get(edit))
    with pytest.warns(CacheRebuildWarning, match="plan-library entry"):
        assert cache.load(a) is None  # never the damaged, edited or other entry
    assert not cache.path(a).exists() and not digest_path(cache.path(a)).exists()
    if how.startswith("swap"):
        with pytest.warns(CacheRebuildWarning):
            assert cache.load(b) is None  # b's slot holds a's entry
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("error", CacheRebuildWarning)
            _assert_same(cache.load(b), _plan(b))


def test_plan_entry_sealed_for_another_design_is_refused(tmp_path):
    # Entries copied from a library of another design (other parameters), seals and all, under this one's names.
    start = np.zeros(4)
    mine, theirs = PlanCache(tmp_path / "mine", {"params": [1.0]}), PlanCache(tmp_path / "theirs", {"params": [1.5]})
    theirs.save(start, _plan(start + 0.5))
    mine.path(start).parent.mkdir(parents=True)
    for src, dst in ((theirs.path(start), mine.path(start)),):
        shutil.copyfile(src, dst)
        shutil.copyfile(digest_path(src), digest_path(dst))
    with pytest.warns(CacheRebuildWarning, match="built for another entry"):
        assert mine.load(start) is None


def test_plan_entry_resealed_by_hand_is_used_only_under_its_own_key(tmp_path):
    # A seal is not a signature: who re-seals an edited entry under its key makes it used (documented limit).
    cache = PlanCache(tmp_path, {"task": "pendubot"})
    start = np.zeros(4)
    cache.save(start, _plan(start))
    PLAN_EDITS["flip_gains"](cache.path(start))
    seal(cache.path(start), cache.key(start))
    np.testing.assert_array_equal(cache.load(start)["K"], -_plan(start)["K"])

"""Suite-wide settings: tests that build C code skip, with the reason, where no C compiler is found.

Marker ``needs_cc``: the test exports an FMU or builds the native library. Every
test under ``tests/fmu/`` needs one (the FMUs are built per session), so that
directory is marked as a whole; elsewhere tests carry the marker themselves.
Everything else runs without a compiler. ``PENDULAB_TEST_NO_CC=1`` pretends
no compiler exists (used by a test of this rule).
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import numpy as np
import pytest

FMU_TESTS = Path(__file__).resolve().parent / "fmu"


class Recorder:
    """A controller that keeps every state it is given (what the inner controller of a pipeline sees)."""

    def __init__(self, ctrl):
        self.ctrl, self.sample_time, self.input_names = ctrl, ctrl.sample_time, ctrl.input_names
        self.seen: list = []

    def reset(self):
        self.ctrl.reset()
        self.seen = []

    def __call__(self, t, x):
        self.seen.append(np.array(x, dtype=float))
        return self.ctrl(t, x)


@pytest.fixture
def recorder() -> type[Recorder]:
    """The :class:`Recorder` class, for the estimator pipeline tests."""
    return Recorder


def compiler_missing() -> str | None:
    """Why C code cannot be built here (None when a compiler is found)."""
    if os.environ.get("PENDULAB_TEST_NO_CC") == "1":
        return "PENDULAB_TEST_NO_CC=1 is set"
    from pendulab.fmu.export import CompilerNotFoundError, find_compiler

    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        return str(exc)
    return None


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--fuzz-long", action="store_true", default=False, help="run the long FMI fuzz campaigns (tests/fmu/test_fmi_fuzz.py)"
    )


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "needs_cc: builds C code (an FMU or the native library); skipped without a C compiler")
    # A shell starts a background job with SIGINT ignored and every child inherits that, so the Ctrl-C tests
    # would test nothing (and fail). Give this process (each xdist worker runs this hook) Python's own handler;
    # exec resets a handled signal to the default, so the commands the tests start get a normal Ctrl-C too.
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    reason = compiler_missing()
    if reason is None:
        return
    skip = pytest.mark.skip(reason=f"needs a C compiler to build the FMU / native code: {reason}")
    for item in items:
        if item.get_closest_marker("needs_cc") or FMU_TESTS in Path(str(item.path)).resolve().parents:
            item.add_marker(skip)

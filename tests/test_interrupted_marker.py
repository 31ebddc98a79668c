"""An interrupted command leaves ``summary.json`` saying so in its output directory (never partial files alone)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pendulab.cli import main


def _interrupt(*args, **kwargs):
    raise KeyboardInterrupt


@pytest.mark.parametrize(
    ("argv", "target"),
    [
        (["swingup", "--task", "pendubot", "--no-progress"], "pendulab.control.swingup.episode.run_episode"),
        (["score", "--realai", "--task", "pendubot", "--controller", "best", "--no-progress"],
         "pendulab.evaluate.realai.realai_score"),
    ],
)  # fmt: skip
def test_an_interrupted_run_marks_its_output_directory(argv, target, tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "summary.json").write_text(json.dumps({"status": "complete", "from": "an earlier run"}))
    (out / "partial.csv").write_text("t\n0\n")  # what an interrupted run may leave
    monkeypatch.setattr(target, _interrupt)
    assert main([*argv, "--out", str(out)]) == 130
    err = capsys.readouterr().err
    assert "pendulab: interrupted" in err and str(out / "summary.json") in err
    marker = json.loads((out / "summary.json").read_text())
    assert marker["status"] == "interrupted" and marker["finished_files"] == ["partial.csv"]
    assert marker["command"].startswith("pendulab " + argv[0])


def test_a_run_that_fails_on_bad_input_marks_nothing(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["swingup", "--task", "no-such-task", "--out", str(out)]) == 2
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "make", "message"),
    [
        (["score", "--controller", "lqr", "--task", "pendubot"], "file", "is a file, not a directory"),
        (["swingup", "--task", "pendubot", "--no-progress"], "file", "is a file, not a directory"),
        (["score", "--controller", "lqr", "--task", "pendubot", "--resume"], "journal-dir", "is not a file"),
        (["score", "--protocol", "robustness-v2", "--controller", "lqr", "--task", "pendubot", "--quick"], "runs-dir",
         "is not a file"),
    ],
)  # fmt: skip
def test_unwritable_outputs_are_refused_before_any_work(argv, make, message, tmp_path, capsys, monkeypatch):
    """Found: robustness-v2 --out on a read-only mount ran its first batch (288 s), then failed; a records.json that
    was a directory read as "no records"."""
    import pendulab.control.swingup.episode as episode

    monkeypatch.setattr(episode, "run_episode", _interrupt)  # would mark work as started: must not be reached
    if make == "file":
        (tmp_path / "f").write_text("")
        out = tmp_path / "f" / "run"
    else:
        out = tmp_path / "run"
        (out / ("records.json" if make == "journal-dir" else "runs.json")).mkdir(parents=True)
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "interrupted" not in err and "Traceback" not in err


@pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs Linux /proc, where nothing can be created")
def test_a_folder_that_takes_no_entries_is_refused(capsys):
    assert main(["swingup", "--task", "pendubot", "--out", "/proc/pendulab-out"]) == 2
    assert "cannot write under /proc" in capsys.readouterr().err

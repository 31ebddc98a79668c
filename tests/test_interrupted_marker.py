"""An interrupted command leaves ``summary.json`` saying so in its output directory (never partial files alone)."""

from __future__ import annotations

import json

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

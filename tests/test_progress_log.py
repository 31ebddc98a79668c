"""Progress in a log: where stderr is not a terminal, the bars write whole lines, never carriage returns."""

from pendulab.commands._common import ProgressBar


def test_a_bar_in_a_log_writes_lines_and_its_total(capsys):
    bar = ProgressBar("runs of a study", True, "step")
    for done in range(0, 5001, 100):
        bar(done, 5000)
    bar.close()
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = err.splitlines()
    # a first line, then one per LOG_INTERVAL_S (30 s; this loop takes milliseconds), and the final state
    assert 2 <= len(lines) <= 3
    assert "5000/5000" in lines[-1] and "step" in lines[-1] and lines[-1].startswith("runs of a study")


def test_an_open_ended_bar_and_notes_in_a_log(capsys):
    bar = ProgressBar("planning (IPOPT)", True)
    bar.note("building the NLP ...")
    for _ in range(50):
        bar.iterate(1, "iter")
    bar.close()
    err = capsys.readouterr().err
    assert "\r" not in err and err.splitlines()[0] == "planning (IPOPT): building the NLP ..."
    assert "50iter" in err.splitlines()[-1]


def test_a_disabled_bar_is_silent(capsys):
    bar = ProgressBar("quiet", False)
    bar(1, 2)
    bar.iterate()
    bar.note("x")
    bar.close()
    assert capsys.readouterr().err == ""

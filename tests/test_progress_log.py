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


def test_the_swingup_animation_reports_every_frame(tmp_path):
    from types import SimpleNamespace

    from PIL import Image

    import pendulab as pl
    from pendulab.viz.swingup import animate_episode

    model = pl.rigid()
    closed = pl.simulate(model, model.state(theta1=1.0), 1.0, 0.02)
    ep = SimpleNamespace(
        closed_loop=closed, height=None, result=SimpleNamespace(horizon=0.5),
        task=SimpleNamespace(name="test", rest_lengths=(1.0, 1.0), model=model),
    )  # fmt: skip
    calls = []
    path = animate_episode(ep, tmp_path / "a.gif", fps=10, progress=lambda done, total: calls.append((done, total)))
    assert calls == [(k, 11) for k in range(1, 12)]  # 0 ... 1 s at 10 frames per second
    assert Image.open(path).n_frames == 11

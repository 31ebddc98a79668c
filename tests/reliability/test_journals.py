"""Journals that cannot lie: a resume re-runs what is edited, incomplete, stale or damaged, and publishes the truth.

Found: a leaderboard journal edited by hand (score 0.999), or written by an older pendulab, was published as is by
``score --leaderboard --resume``; a robustness journal with successes flipped gave 0.917 instead of 0.806; a journal
whose records lacked a field failed with ``error: 'category'`` after a 39 s controller build. The class: every
journal kind (the scorecard, the leaderboard's own scorecards, robustness v2, the leaderboard's v2 and v3 cases, the
flip-map checkpoint, the benchmark studies) under every tamper (one record edited, one record missing a field, another
pendulab version, the layout of older pendulabs, a truncated file). Each test resumes a pristine real run's journal
after one tamper and checks: exactly the affected runs are run again, the notice names the file and the problem, and
what is published equals the untampered run's. Cheapest real runs: LQR from hanging (every run fails fast), one run
per level, reduced grids, a 9 x 7 flip map.
"""

from __future__ import annotations

import json
import math
import shutil
import warnings
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import pendulab
from pendulab._journal import JournalError, JournalWarning, header
from pendulab._version import source_version
from pendulab.cli import main

#: One record edited / missing a field (that record re-runs); another version / the same release with other code /
#: old layout / truncated (all re-run).
TAMPERS = ("edit", "drop_field", "version", "code", "legacy", "truncate")
ONE_RECORD = ("edit", "drop_field")


#: The version a tampered journal claims: an older release; this release run by other code (an edited checkout), the
#: case a static release number used to hide (a changed controller constant read back as this code's scores).
_OTHER = {"version": "0.0.1", "code": f"{pendulab.__version__}+src.{'0' * 16}"}


def _tamper(path: Path, how: str, edit: Any, field: str) -> str:
    """Tamper with the JSON journal ``path``; return its first record's key (the one edited or stripped)."""
    doc = json.loads(path.read_text())
    key = next(iter(doc["records"]))
    if how == "edit":
        edit(doc["records"][key]["data"])
    elif how == "drop_field":
        del doc["records"][key]["data"][field]
    elif how in ("version", "code"):  # a consistent journal of another pendulab: only the version differs
        doc.update(header(doc["kind"], doc["settings"], version=_OTHER[how]))
    elif how == "legacy":  # what pendulab wrote before journals carried a version and hashes
        doc = {**doc["settings"], "records": [e["data"] for e in doc["records"].values()]}
    elif how == "truncate":
        text = path.read_text()
        path.write_text(text[: len(text) // 2])
        return key
    path.write_text(json.dumps(doc))
    return key


def _expected_notice(how: str, key: str, field: str) -> str:
    return {
        "edit": f"record {key} edited by hand or damaged",
        "drop_field": f"record {key} incomplete (lacks field {field!r})",
        "version": "was written by pendulab 0.0.1, this is pendulab",
        "code": f"was written by pendulab {_OTHER['code']}, this is pendulab {source_version()} (same release, other code",
        "legacy": "carries no pendulab version or integrity hash",
        "truncate": "is not valid JSON (truncated or damaged",
    }[how]


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


def _notices(record: list[warnings.WarningMessage]) -> list[str]:
    return [str(w.message) for w in record if issubclass(w.category, JournalWarning)]


# -- pendulab score: DIR/records.json --------------------------------------------------------------------------------
SCORE = ["score", "--controller", "lqr", "--task", "pendubot", "--runs", "1", "--categories", "delay,torque_noise",
         "--workers", "1", "--no-progress"]  # fmt: skip


def _card(out: Path) -> dict:
    card = json.loads((out / "scorecard.json").read_text())
    card.pop("wall_time_s")
    return card


def _count_episodes(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    import pendulab.evaluate.scorecard as sc

    calls: list[int] = []
    real = sc.run_perturbed_episode

    def counted(*args: Any, **kwargs: Any) -> Any:
        if "t_final" not in kwargs:  # not the warm-up call that compiles the sample map
            calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(sc, "run_perturbed_episode", counted)
    return calls


@pytest.fixture(scope="module")
def scorecard_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("card") / "out"
    assert main([*SCORE, "--out", str(out)]) == 0
    return out


def _flip_success(rec: dict) -> None:
    rec["success"], rec["reason"] = True, ""


@pytest.mark.parametrize("how", TAMPERS)
def test_scorecard_resume_reruns_exactly_what_does_not_validate(how, scorecard_run, tmp_path, monkeypatch, capsys):
    out = _copy(scorecard_run, tmp_path / "out")
    journal = out / "records.json"
    n = len(json.loads(journal.read_text())["records"])
    key = _tamper(journal, how, _flip_success, "category")
    calls = _count_episodes(monkeypatch)
    capsys.readouterr()
    assert main([*SCORE, "--out", str(out), "--resume"]) == 0
    err = capsys.readouterr().err
    assert len(calls) == (1 if how in ONE_RECORD else n)
    notices = [line for line in err.splitlines() if line.startswith(f"pendulab score: journal {journal}")]
    assert len(notices) == 1 and _expected_notice(how, key, "category") in notices[0], err
    assert _card(out) == _card(scorecard_run)  # the published card is the untampered run's
    # The rewritten journal validates again: a second resume runs nothing.
    calls.clear()
    assert main([*SCORE, "--out", str(out), "--resume"]) == 0
    assert calls == [] and "run again" not in capsys.readouterr().err


# -- the leaderboard's own scorecards: scorecard/TASK-CONTROLLER/records.json ------------------------------------------
@pytest.fixture
def one_card(monkeypatch: pytest.MonkeyPatch) -> Any:
    import pendulab.commands.leaderboard as lb

    monkeypatch.setattr(lb, "LEADERBOARD_TASKS", ("pendubot",))
    monkeypatch.setattr(lb, "LEADERBOARD_CONTROLLERS", ("lqr",))
    return lb


@pytest.fixture(scope="module")
def leaderboard_cards(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    import pendulab.commands.leaderboard as lb

    root = tmp_path_factory.mktemp("lb") / "scorecard"
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(lb, "LEADERBOARD_TASKS", ("pendubot",))
        mp.setattr(lb, "LEADERBOARD_CONTROLLERS", ("lqr",))
        result = lb._scorecards(1, 1, False, False, root, None)
    return root, result


@pytest.mark.parametrize("how", TAMPERS)
def test_leaderboard_scorecard_resume_reruns_exactly_what_does_not_validate(
    how, leaderboard_cards, one_card, tmp_path, monkeypatch
):
    pristine, before = leaderboard_cards
    root = _copy(pristine, tmp_path / "scorecard")
    journal = root / "pendubot-lqr" / "records.json"
    n = len(json.loads(journal.read_text())["records"])
    key = _tamper(journal, how, _flip_success, "success")
    calls = _count_episodes(monkeypatch)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        result = one_card._scorecards(1, 1, False, True, root, None)
    assert len(calls) == (1 if how in ONE_RECORD else n)
    notices = _notices(seen)
    assert len(notices) == 1 and str(journal) in notices[0] and _expected_notice(how, key, "success") in notices[0]
    card, ref = result["cards"][("lqr", "pendubot")], before["cards"][("lqr", "pendubot")]
    assert card.overall == ref.overall and card.categories == ref.categories and card.records == ref.records


def test_leaderboard_scorecard_wall_time_edited_is_not_published(leaderboard_cards, one_card, tmp_path):
    pristine, before = leaderboard_cards
    root = _copy(pristine, tmp_path / "scorecard")
    journal = root / "pendubot-lqr" / "records.json"
    doc = json.loads(journal.read_text())
    doc["meta"]["wall_time"] = 0.001
    journal.write_text(json.dumps(doc))
    with pytest.warns(JournalWarning, match="meta data .* do not match their SHA-256"):
        result = one_card._scorecards(1, 1, False, True, root, None)
    assert result["walls"][("lqr", "pendubot")] != 0.001  # measured again, not the edited value


# -- robustness v2: runs.json (pendulab score --protocol robustness-v2, the leaderboard, benchmarks) -------------------
ROBUST = {"levels": [0, 20], "categories": ["u_responsiveness", "delay", "perturbation"], "perturbation_repetitions": 2,
          "workers": 1}  # fmt: skip
#: Fields of a run that differ between two runs of the same run (timing).
TIMING = ("wall", "ctrl_median", "ctrl_max")


def _published(res: Any) -> dict:
    d = res.to_dict()
    for k in ("wall_time", "controller_time"):
        d.pop(k)
    d["records"] = [{k: v for k, v in r.items() if k not in TIMING} for r in res.records]
    return d


def _count_protocol_runs(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    import pendulab.evaluate.realai.robustness as rob

    calls: list[int] = []
    real = rob.run_protocol_episode

    def counted(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(rob, "run_protocol_episode", counted)  # workers=1: the runs are in this process
    return calls


@pytest.fixture(scope="module")
def robustness_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    from pendulab.evaluate.realai.robustness import robustness_v2

    journal = tmp_path_factory.mktemp("rob") / "runs.json"
    return journal, robustness_v2("acrobot", "lqr", journal=journal, **ROBUST)


@pytest.mark.parametrize("how", TAMPERS)
def test_robustness_resume_reruns_exactly_what_does_not_validate(how, robustness_run, tmp_path, monkeypatch):
    from pendulab.evaluate.realai.robustness import robustness_v2

    pristine, ref = robustness_run
    journal = tmp_path / "runs.json"
    shutil.copy(pristine, journal)
    key = _tamper(journal, how, lambda rec: rec.update(success=True), "category")
    calls = _count_protocol_runs(monkeypatch)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        res = robustness_v2("acrobot", "lqr", journal=journal, resume=True, **ROBUST)
    assert len(calls) == (1 if how in ONE_RECORD else len(ref.records))
    notices = _notices(seen)
    assert len(notices) == 1 and str(journal) in notices[0] and _expected_notice(how, key, "category") in notices[0]
    assert _published(res) == _published(ref)


def test_robustness_journal_is_validated_before_the_controller_is_built(robustness_run, tmp_path):
    """Found: records without "category" failed with ``error: 'category'`` after a 39 s controller build."""
    from pendulab.evaluate.realai.controllers import CONTROLLERS
    from pendulab.evaluate.realai.robustness import robustness_v2

    pristine, ref = robustness_run
    journal = tmp_path / "runs.json"
    shutil.copy(pristine, journal)
    _tamper(journal, "drop_field", None, "category")
    events: list[str] = []

    def lqr(task: str) -> Any:
        events.append("build")
        return CONTROLLERS["lqr"](task)

    def note(message: Any, *args: Any, **kwargs: Any) -> None:
        events.append("notice")

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = note
        res = robustness_v2("acrobot", lqr, journal=journal, resume=True, **ROBUST)
    assert events == ["notice", "build"] and res.rates == ref.rates
    # Other settings: refused before the build, naming the file and the difference.
    with pytest.raises(JournalError, match=rf"{journal}.*other settings \(seed 0 there, 1 now\)"):
        robustness_v2("acrobot", lqr, journal=journal, resume=True, seed=1, **ROBUST)
    assert events == ["notice", "build"]


def test_unwritable_journal_location_is_refused_before_any_work(tmp_path):
    from pendulab.evaluate.realai.leaderboard import run_protocols
    from pendulab.evaluate.realai.robustness import robustness_v2

    (tmp_path / "file").write_text("")
    built: list[str] = []
    with pytest.raises(NotADirectoryError, match="is a file"):
        robustness_v2("acrobot", lambda task: built.append(task), journal=tmp_path / "file" / "runs.json", **ROBUST)
    with pytest.raises(NotADirectoryError, match="is a file"):
        run_protocols(["lqr"], tasks=["pendubot"], protocols=["v2"], quick=True, root=tmp_path / "file" / "lb")
    assert built == []


# -- the leaderboard's v2 and v3 cases: v2/TASK-CONTROLLER.json, v3/TASK-CONTROLLER-seedS.json -----------------------
def _count_cases(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    import pendulab.evaluate.realai.simulate as sim
    import pendulab.evaluate.realai.v3 as v3

    calls = {"v2": 0, "v3": 0}

    def counting(module: Any, attr: str, key: str) -> None:
        inner = getattr(module, attr)

        def wrapped(*a: Any, **k: Any) -> Any:
            calls[key] += 1
            return inner(*a, **k)

        monkeypatch.setattr(module, attr, wrapped)

    counting(sim, "run_leaderboard", "v2")
    counting(v3, "run_v3", "v3")
    return calls


def _case_summary(run: Any, protocol: str) -> dict:
    summary = run.case(protocol, "pendubot", "lqr").summary
    if protocol == "v3":
        return {"mean": summary["mean"], "seeds": [{k: s[k] for k in ("uptime_fraction", "score", "n_swingups")}
                                                  for s in summary["seeds"]]}  # fmt: skip
    return {k: summary[k] for k in ("success", "score", "criteria")}


@pytest.fixture(scope="module")
def leaderboard_cases(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    from pendulab.evaluate.realai.leaderboard import run_protocols

    root = tmp_path_factory.mktemp("cases") / "root"
    return root, run_protocols(["lqr"], tasks=["pendubot"], protocols=["v2", "v3"], quick=True, root=root, workers=1)


@pytest.mark.parametrize("protocol", ["v2", "v3"])
@pytest.mark.parametrize("how", TAMPERS)
def test_leaderboard_case_resume_reruns_what_does_not_validate(how, protocol, leaderboard_cases, tmp_path, monkeypatch):
    """Found: ``score --leaderboard --resume`` published a case journal edited by hand (score 0.999) as is."""
    from pendulab.evaluate.realai.leaderboard import run_protocols

    pristine, ref = leaderboard_cases
    root = _copy(pristine, tmp_path / "root")
    journal = root / "quick" / protocol / ("pendubot-lqr.json" if protocol == "v2" else "pendubot-lqr-seed0.json")
    field = "score" if protocol == "v2" else "uptime_fraction"
    key = _tamper(journal, how, lambda s: s.update({field: 0.999}), field)
    calls = _count_cases(monkeypatch)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        run = run_protocols(["lqr"], tasks=["pendubot"], protocols=["v2", "v3"], quick=True, resume=True, root=root)
    assert calls == {"v2": 0, "v3": 0, protocol: 1}  # the other protocol's journal is reused
    notices = _notices(seen)
    assert len(notices) == 1 and str(journal) in notices[0] and _expected_notice(how, key, field) in notices[0]
    assert _case_summary(run, protocol) == _case_summary(ref, protocol)


def test_leaderboard_case_journal_past_the_budget_is_not_read_back_unless_it_validates(leaderboard_cases, tmp_path, monkeypatch):
    from pendulab.evaluate.realai.leaderboard import run_protocols

    pristine, _ = leaderboard_cases
    root = _copy(pristine, tmp_path / "root")
    _tamper(root / "quick" / "v2" / "pendubot-lqr.json", "edit", lambda s: s.update(score=0.999), "score")
    calls = _count_cases(monkeypatch)
    late = run_protocols(["lqr"], tasks=["pendubot"], protocols=["v2", "v3"], quick=True, resume=True, root=root,
                         max_wall_time=1e-9)  # fmt: skip
    assert calls == {"v2": 0, "v3": 0}
    assert [c.status for c in late.cases] == ["not run", "done"]  # the edited v2 case is neither run nor published


# -- the flip-map checkpoint: DIR/flipmap_<kind>.partial.npz ---------------------------------------------------------
FLIP = {"threads": 1, "batch_size": 4, "block_size": 6}


@pytest.fixture(scope="module")
def flip_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    from pendulab.ensemble.flipmap import flip_map

    pytest.importorskip("heyoka")
    ck = tmp_path_factory.mktemp("flip") / "fm.partial.npz"
    return ck, flip_map(pendulab.rigid(), (9, 7), 3.0, checkpoint=ck, **FLIP)


def _tamper_npz(path: Path, how: str) -> None:
    with np.load(path) as z:
        arrays = {k: np.array(z[k]) for k in z.files}
    doc = json.loads(str(arrays["journal"]))
    if how == "edit":  # one flip time of the first block
        arrays["values"][1] = 0.5 if math.isnan(arrays["values"][1]) else arrays["values"][1] + 0.5
    elif how == "drop_field":  # the first block's hash is gone: that block cannot be trusted
        del doc["records"]["0-6"]
    elif how in ("version", "code"):
        doc.update(header(doc["kind"], doc["settings"], version=_OTHER[how]))
    elif how == "legacy":
        arrays["identity"] = np.str_(json.dumps(doc["settings"]))
        del arrays["journal"]
    elif how == "truncate":
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])
        return
    if "journal" in arrays:
        arrays["journal"] = np.str_(json.dumps(doc))
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


@pytest.mark.parametrize("how", TAMPERS)
def test_flip_map_checkpoint_resume_reruns_exactly_what_does_not_validate(how, flip_run, tmp_path):
    from pendulab.ensemble.flipmap import flip_map

    pristine, ref = flip_run
    ck = tmp_path / "fm.partial.npz"
    shutil.copy(pristine, ck)
    _tamper_npz(ck, how)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        fmap = flip_map(pendulab.rigid(), (9, 7), 3.0, checkpoint=ck, resume=True, **FLIP)
    assert fmap.n_simulated == (6 if how in ONE_RECORD else ref.n_simulated)  # one block of 6 runs, or all
    notices = _notices(seen)
    want = {
        "edit": "block 0-6 edited by hand or damaged",
        "drop_field": "block 0-6 edited by hand or damaged",
        "truncate": "cannot be read as a flip-map checkpoint (truncated or damaged",
    }.get(how, _expected_notice(how, "", ""))
    assert len(notices) == 1 and str(ck) in notices[0] and want in notices[0]
    np.testing.assert_array_equal(fmap.t_flip, ref.t_flip)


# -- benchmark studies: OUT/work_precision_journal.json (stability, model choice: the same Journal) --------------------
BENCH_STABLE = ("case", "method", "sweep", "setting", "status", "final_error", "grid_error", "energy_drift", "n_steps")


def _rows(rows: list) -> list[tuple]:
    return [tuple(asdict(r)[k] for k in BENCH_STABLE) for r in rows]


@pytest.fixture(scope="module")
def bench_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list]:
    from pendulab.bench import workprecision as wp

    journal = tmp_path_factory.mktemp("wp") / "journal.json"
    return journal, wp.run_work_precision(["rigid_chaotic_2s"], ["rk4"], quick=True, repeats=1, journal=journal)


@pytest.mark.parametrize("how", TAMPERS)
def test_bench_study_resume_remeasures_exactly_what_does_not_validate(how, bench_run, tmp_path, monkeypatch):
    from pendulab.bench import workprecision as wp

    pristine, ref = bench_run
    journal = tmp_path / "journal.json"
    shutil.copy(pristine, journal)
    key = _tamper(journal, how, lambda row: row.update(grid_error=1e-99), "status")
    calls: list[int] = []
    real = wp._measure

    def measure(*args: Any) -> Any:
        calls.append(1)
        return real(*args)

    monkeypatch.setattr(wp, "_measure", measure)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        rows = wp.run_work_precision(["rigid_chaotic_2s"], ["rk4"], quick=True, repeats=1, journal=journal, resume=True)
    assert len(calls) == (1 if how in ONE_RECORD else len(ref))
    notices = _notices(seen)
    assert len(notices) == 1 and str(journal) in notices[0] and _expected_notice(how, key, "status") in notices[0]
    assert _rows(rows) == _rows(ref)


def test_a_journal_of_another_kind_is_refused_not_overwritten(robustness_run, tmp_path):
    from pendulab.bench import workprecision as wp

    pristine, _ = robustness_run
    journal = tmp_path / "journal.json"
    shutil.copy(pristine, journal)
    with pytest.raises(JournalError, match=rf"{journal} is a 'robustness-v2' journal, not a 'work-precision' one"):
        wp.run_work_precision(["rigid_chaotic_2s"], ["rk4"], quick=True, repeats=1, journal=journal, resume=True)
    assert journal.read_bytes() == pristine.read_bytes()

"""The leaderboard of the three RealAIGym protocols: published rows as upstream prints them, a quick run, resume, errors."""

from __future__ import annotations

import math

import pytest

from pendulab.cli import main
from pendulab.evaluate.realai import PUBLISHED
from pendulab.evaluate.realai.criteria import CRITERIA, score_v2
from pendulab.evaluate.realai.leaderboard import FULL, PROTOCOLS, Case, LeaderboardRun, check_controllers, run_protocols
from pendulab.evaluate.realai.leaderboard_published import (
    PUBLISHED_ROBUSTNESS_ROWS,
    PUBLISHED_V2_ROWS,
    PUBLISHED_V3_ROWS,
)
from pendulab.evaluate.realai.leaderboard_tables import protocol_tables
from pendulab.evaluate.realai.robustness import CATEGORIES, PUBLISHED_ROBUSTNESS, robustness_score
from pendulab.evaluate.realai.v3_definition import PUBLISHED_V3
from pendulab.model.plant_file import load_plant


def _half_unit(x: float) -> float:
    """Half a unit of the last printed digit of a published number (the page's rounding)."""
    text = repr(x)
    return 0.5 * 10.0 ** -(len(text.split(".")[1]) if "." in text else 0)


@pytest.mark.parametrize("task", ["pendubot", "acrobot"])
def test_published_v2_scores_follow_from_their_published_criteria(task):
    # Every published v2 score is the score formula on its own published criteria: the score of the criteria's
    # rounding interval (each criterion +- half a printed unit; the score falls with every criterion) contains it.
    assert len(PUBLISHED_V2_ROWS[task]) == 7  # every entry of the page
    for row in PUBLISHED_V2_ROWS[task]:
        lo = score_v2({k: row.values[k] + _half_unit(row.values[k]) for k in CRITERIA}, True)
        hi = score_v2({k: row.values[k] - _half_unit(row.values[k]) for k in CRITERIA}, True)
        # 0.0005: the published score is itself rounded to 3 digits.
        assert lo - 5e-4 <= row.score <= hi + 5e-4, (row.name, lo, row.score, hi)
    # A known one, tighter: History SAC on the acrobot, 1.0 s, 8.08 J, 1.8, 0.01 N m, 88.5 -> 0.653 (page: 0.655,
    # its smoothness printed with one significant digit).
    sac = next(r for r in PUBLISHED_V2_ROWS["acrobot"] if r.name == "history_sac")
    assert score_v2(dict(sac.values), True) == pytest.approx(0.6528, abs=1e-4)  # hand computation, 4 digits


def test_published_rows_are_the_protocol_tables_numbers():
    # Same numbers as the protocol modules' published tables, where both list an entry.
    for task in ("pendubot", "acrobot"):
        v2 = {r.name: r.score for r in PUBLISHED_V2_ROWS[task]}
        for name, score in PUBLISHED[task].items():
            assert v2[name] == score
        rv2 = {r.name: r for r in PUBLISHED_ROBUSTNESS_ROWS[task]}
        assert set(rv2) == set(PUBLISHED_ROBUSTNESS[task])
        for name, (rates, score) in PUBLISHED_ROBUSTNESS[task].items():
            assert rv2[name].score == score
            assert [100 * rv2[name].values[c] for c in CATEGORIES] == pytest.approx(rates, abs=1e-12)
            # The score formula on the published rates gives the published score (rates rounded to 0.1 %, score to
            # 3 digits: 0.0005 + 0.0005).
            assert robustness_score(rv2[name].values) == pytest.approx(score, abs=1e-3)
        v3 = {r.name: r.score for r in PUBLISHED_V3_ROWS[task] if r.score is not None}
        assert v3 == PUBLISHED_V3[task]


def test_tables_list_every_published_row_exactly_even_with_nothing_run():
    cases = [Case(p, t, "best", reason="test") for p in PROTOCOLS for t in ("pendubot", "acrobot")]
    text = "\n".join(protocol_tables(LeaderboardRun(FULL, cases, root=None)))  # type: ignore[arg-type]
    ar_eapo = "| published AR-EAPO (`ar_eapo`) | 87.6 | 81.0 | 100.0 | 100.0 | 81.0 | 98.0 | 0.913 |"
    assert ar_eapo in text
    assert "| published History SAC (`history_sac`) | 58.1 | 23.8 | 100.0 | 100.0 | 90.5 | 78.0 | 0.751 |" in text
    assert "| published History SAC (`history_sac`) | 1 | 1.15 | 7.67 | 2.36 | 0.007 | 62.07 | 0.682 |" in text
    assert "| published mcpilco (`mcpilco`) | 1 | 1.45 | 19.43 | 3.22 | 0.097 | 253.59 | 0.316 |" in text
    assert "0.799 (one unseeded run)" in text and "0.658 (one unseeded run)" in text
    # every ICRA 2025 simulation entry with its published score and swing-ups (no row left without its number)
    assert "| published AcadosMpc (`acados_mpc`) |  |  |  | 0.726 (one unseeded run) | 16 | | |" in text
    assert "| published mcpilco (`mcpilco`) |  |  |  | 0.307 (one unseeded run) | 34 | | |" in text
    assert "score not in the stored sources" not in text
    # 6 rows in the three protocol tables, one per task in the identified-robot table (its four cells), 2 in v3-hardware
    assert text.count("| pendulab `best` | not run (test) |") == 10
    # the ICRA 2025 hardware final's rows beside the v3-hardware ones
    assert "| published AcadosMPC (`acados_mpc`, real robot) |  |  |  | 0.721 | | | |" in text
    assert "| published AcadosMPC (`acados_mpc`, real robot) |  |  |  | 0.775 | | | |" in text
    assert text.count("| pendulab `best` | not run (test) | not run (test) | not run (test) | not run (test) |") == 2
    assert "1e8544e" in text  # upstream's commit is cited


def test_quick_leaderboard_runs_each_case_once_and_resumes_without_rerunning(tmp_path, monkeypatch):
    import pendulab.evaluate.realai.robustness as rob
    import pendulab.evaluate.realai.simulate as sim
    import pendulab.evaluate.realai.v3 as v3
    from pendulab.commands.leaderboard import write_leaderboard

    calls = {"v2": 0, "robustness-v2": 0, "v3": 0}
    plants = []

    def counting(module, attr, key):
        inner = getattr(module, attr)

        def wrapped(*a, **k):
            calls[key] += 1
            if key != "robustness-v2":
                plants.append(k.get("plant"))
            return inner(*a, **k)

        monkeypatch.setattr(module, attr, wrapped)

    counting(sim, "run_leaderboard", "v2")
    counting(rob, "run_protocol_episode", "robustness-v2")  # workers=1: episodes run in this process
    counting(v3, "run_v3", "v3")
    root = tmp_path / "journals"
    run = run_protocols(["lqr"], tasks=["pendubot"], quick=True, root=root, workers=1)
    # v2 and v3 twice: on the nominal plant and on the shipped identified C.1 robot
    assert calls == {"v2": 2, "robustness-v2": 13, "v3": 2}
    assert run.counts() == {
        "v2": (1, 0),
        "robustness-v2": (13, 0),
        "v3": (1, 0),
        "v2-identified": (1, 0),
        "v3-identified": (1, 0),
        "v3-hardware": (1, 0),
    }
    hw = run.case("v3-hardware", "pendubot", "lqr").summary["seeds"][0]
    assert hw["protocol"] == "v3-hardware" and hw["simulation"]["plant"].startswith("identified")
    assert 0.0 <= hw["uptime_fraction"] <= 1.0 and hw["duration"] == pytest.approx(10.0)
    assert sum(p is None for p in plants) == 2 and {p.params["cf1"] for p in plants if p is not None} == {
        load_plant("c1").params["cf1"]
    }
    assert run.case("v2-identified", "pendubot", "lqr").summary["simulation"]["plant"].startswith("identified")
    rv2 = run.case("robustness-v2", "pendubot", "lqr").summary
    assert set(rv2["rates"]) == set(CATEGORIES)
    assert all(0.0 <= r <= 1.0 and math.isfinite(r) for r in rv2["rates"].values())
    assert rv2["score"] == pytest.approx(sum(rv2["rates"].values()) / 6, abs=1e-12)  # the formula on the rates
    v3s = run.case("v3", "pendubot", "lqr").summary["seeds"]
    assert len(v3s) == 1 and 0.0 <= v3s[0]["uptime_fraction"] <= 1.0
    assert (root / "quick" / "robustness-v2" / "pendubot-lqr" / "runs.json").is_file()  # quick apart from full

    out = tmp_path / "page" / "leaderboard.md"
    write_leaderboard(out, controllers=["lqr"], quick=True, resume=True, root=root, tasks=["pendubot"], progress=False)
    assert calls == {"v2": 2, "robustness-v2": 13, "v3": 2}  # nothing ran again
    text = out.read_text()
    for heading in ("## RealAIGym simulation leaderboard v2", "## RealAIGym robustness leaderboard v2", "## RealAIGym v3",
                    "## On the identified robot"):  # fmt: skip
        assert heading in text
    assert (
        "NOT comparable" in text
        and "reused: v2 1, robustness-v2 13, v3 1, v2-identified 1, v3-identified 1, v3-hardware 1" in text
    )
    assert (out.parent / "figures" / "leaderboard_robustness_pendubot.png").stat().st_size > 10_000
    assert (out.parent / "figures" / "leaderboard_v3.png").is_file()
    # Each figure sits in its own protocol's section, so one section can be regenerated with its figure.
    v3_section = text.split("## RealAIGym v3 (")[1].split("\n## ")[0]
    assert "figures/leaderboard_v3.png" in v3_section and "leaderboard_robustness" not in v3_section

    # One protocol over the whole page: its section is regenerated, every other section stays to the byte.
    write_leaderboard(out, controllers=["lqr"], quick=True, resume=True, root=root, tasks=["pendubot"],
                      progress=False, protocols=["v3"])  # fmt: skip
    spliced = out.read_text()
    assert calls == {"v2": 2, "robustness-v2": 13, "v3": 2}  # journals reused

    def others(page: str) -> list[str]:
        return [s for s in page.split("\n## ") if not s.startswith("RealAIGym v3 (")]

    assert others(spliced) == others(text) and spliced.count("\n## ") == text.count("\n## ")
    provenance = "*This section: regenerated by `pendulab score --leaderboard --quick --resume --controllers lqr --protocol v3"
    assert f"{provenance} --out " in spliced

    # Past a wall-time budget complete journals are still read back and nothing runs; without resume nothing runs.
    late = run_protocols(["lqr"], tasks=["pendubot"], quick=True, resume=True, root=root, max_wall_time=1e-9)
    assert [c.status for c in late.cases] == ["done"] * 6 and calls == {"v2": 2, "robustness-v2": 13, "v3": 2}
    fresh = run_protocols(["lqr"], tasks=["pendubot"], quick=True, root=root, max_wall_time=1e-9)
    assert all(c.status == "not run" and "budget" in c.reason for c in fresh.cases)

    # A journal of other settings is refused on resume, not silently reused (one edited by hand is stale instead:
    # tests/reliability/test_journals.py).
    from pendulab._journal import Journal

    rec = root / "quick" / "v2" / "pendubot-lqr.json"
    Journal(rec, "leaderboard-case", {"protocol": "v2", "task": "pendubot", "controller": "best"}).record("summary", {})
    with pytest.raises(ValueError, match="other settings"):
        run_protocols(["lqr"], tasks=["pendubot"], protocols=["v2"], quick=True, resume=True, root=root)


def test_bad_controller_names_are_refused_with_the_table():
    with pytest.raises(ValueError, match=r"unknown \['nope'\]") as exc:
        check_controllers(["best", "nope"])
    assert "'replan'" in str(exc.value)  # names the table of valid names
    with pytest.raises(ValueError, match="unknown protocols"):
        check_controllers({"v4": ["best"]})
    with pytest.raises(TypeError, match="sequence of names"):
        check_controllers("best")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["score", "--leaderboard", "--controllers", "best,nope"], "--controllers 'best,nope'"),
        (
            ["score", "--controllers", "best", "--controller", "lqr", "--task", "pendubot"],
            "--controllers applies to --leaderboard",
        ),
        (["score", "--realai", "--quick", "--controller", "lqr", "--task", "pendubot"], "--quick applies to"),
        (["score", "--leaderboard", "--json"], "--json does not apply to --leaderboard"),
        (["score", "--leaderboard", "--controller", "lqr"], "do not apply to --leaderboard"),
    ],
)
def test_cli_leaderboard_options_refused_before_anything_runs(argv, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main([*argv, "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1, err
    assert not (tmp_path / "pendulab-out").exists()


@pytest.mark.parametrize("name", ["library", "mpc_library"])
def test_plan_library_is_built_with_its_own_progress_before_the_first_episode(tmp_path, monkeypatch, name):
    # The library's first use solves hundreds of plans (minutes): the leaderboard reports them as they finish,
    # bounded at the hardware protocol's rate on v3-hardware (unbounded on v3 for ``library``; ``mpc_library``
    # always plays the bounded one), and builds once per case, for every controller that plays it.
    from types import SimpleNamespace

    import pendulab.control.plan_library as pl_lib
    import pendulab.evaluate.realai.leaderboard as lb
    from pendulab.evaluate.realai.v3_hardware import PLAN_VELOCITY_LIMIT_HW

    v3_bound = None if name == "library" else PLAN_VELOCITY_LIMIT_HW

    builds = []

    def fake_library(task, *, progress=None, velocity_limit=None, **_):
        builds.append((task, velocity_limit))
        for k in range(3):
            progress(k + 1, 3)
        return SimpleNamespace(library=SimpleNamespace(digest=lambda: f"plans-{velocity_limit}"))

    def no_episode(*a, **k):
        raise RuntimeError("episode not run in this test")

    read_keys = []

    def journal_keys(path, keys):
        read_keys.append(dict(keys))

    monkeypatch.setattr(pl_lib, "library_controller", fake_library)
    monkeypatch.setattr(lb, "_run_v3", no_episode)
    monkeypatch.setattr(lb, "_read", journal_keys)
    seen = []
    run = run_protocols(
        [name], tasks=["pendubot"], protocols=("v3", "v3-hardware"), quick=True, root=tmp_path, resume=True,
        progress=lambda label, done, total: seen.append((label, done, total)),
    )  # fmt: skip
    assert builds == [("pendubot", v3_bound), ("pendubot", PLAN_VELOCITY_LIMIT_HW)]
    # Each case's journal names the library it plays: another library is never read back as this one's.
    assert [k["library_sha256"] for k in read_keys] == [f"plans-{v3_bound}", f"plans-{PLAN_VELOCITY_LIMIT_HW}"]
    label = "plan library for pendubot"
    assert [s for s in seen if s[0] == label] == [(label, k, 3) for k in (1, 2, 3)] * 2
    assert all(c.status == "failed" and "episode not run" in c.reason for c in run.cases)

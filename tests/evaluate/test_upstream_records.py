"""The ICRA 2025 entries' recorded v3-hardware episodes beside their real-robot scores: reading, ranking, the page."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulab.cli import main
from pendulab.evaluate.realai.leaderboard_published import PUBLISHED_HARDWARE
from pendulab.evaluate.realai.upstream_records import read_hardware_entries, spearman_rho


def _record(folder, entry, task, seed, score, allowance=0.5, **changes):
    """A case record as benchmarks/bench_upstream_entries.py writes it (the fields the reader uses)."""
    rec = {"variant": "hw", "entry": entry, "task": task, "protocol": "v3-hardware", "seed": seed, "score": score,
           "allowance": allowance, "status": "ok", "notes": []}  # fmt: skip
    rec.update(changes)
    path = folder / f"hw_{entry}_{task}_v3-hardware_s{seed}_a{allowance:g}.json"
    path.write_text(json.dumps(rec))
    return path


def test_entries_are_read_per_task_and_allowance_with_bad_records_named(tmp_path):
    for seed, score in enumerate((0.70, 0.74, 0.72)):
        _record(tmp_path, "acados_mpc", "pendubot", seed, score)
    _record(tmp_path, "ar_eapo", "pendubot", 0, 0.71)
    _record(tmp_path, "ar_eapo", "pendubot", 1, 0.10, allowance=0.0)  # another allowance: not this table's
    _record(tmp_path, "mcpilco", "pendubot", 0, 0.9, status="error")  # a failed case: not a score
    _record(tmp_path, "mcpilco", "acrobot", 0, 0.5)  # another task
    _record(tmp_path, "acados_mpc", "pendubot", 7, 1.7)  # a score no episode can have
    (tmp_path / "hw_ar_eapo_pendubot_v3-hardware_s9_a0.5.json").write_text("{not json")
    _record(tmp_path, "mcpilco", "pendubot", 3, 0.4, notes=["SQP capped: an approximation of the submitted controller"])
    entries, skipped = read_hardware_entries(tmp_path, "pendubot", 0.5)
    by = {e.entry: e for e in entries}
    assert list(by) == ["acados_mpc", "ar_eapo", "mcpilco"]  # best real-robot score first
    # 1e-15: the decimal scores are not exact in binary; mean and std are a few roundings of them
    assert by["acados_mpc"].seeds == (0, 1, 2) and by["acados_mpc"].mean == pytest.approx(0.72, abs=1e-15)
    assert by["acados_mpc"].std == pytest.approx(0.02, abs=1e-15)  # sample std of 0.70, 0.74, 0.72
    assert by["ar_eapo"].scores == (0.71,) and by["ar_eapo"].std == 0.0
    assert by["mcpilco"].approximation.startswith("SQP capped") and not by["acados_mpc"].approximation
    assert by["acados_mpc"].published_hardware == PUBLISHED_HARDWARE["pendubot"]["acados_mpc"]
    assert sorted(s.split(":")[0] for s in skipped) == [
        "hw_acados_mpc_pendubot_v3-hardware_s7_a0.5.json", "hw_ar_eapo_pendubot_v3-hardware_s9_a0.5.json",
    ]  # fmt: skip
    # No folder (CI, or the benchmark never ran): no entries, nothing skipped.
    assert read_hardware_entries(tmp_path / "absent", "acrobot", 0.5) == ([], [])
    with pytest.raises(ValueError, match="task must be one of"):
        read_hardware_entries(tmp_path, "cartpole", 0.5)


def test_spearman_rho_agrees_with_scipy_including_ties():
    from scipy.stats import spearmanr

    rng = np.random.default_rng(3)
    for n in (2, 3, 4, 7):
        for _ in range(20):
            a, b = rng.integers(0, 4, n).astype(float), rng.normal(size=n)  # integer draws: ties are common
            if np.ptp(a) == 0:
                assert np.isnan(spearman_rho(a, b))
                continue
            assert spearman_rho(a, b) == pytest.approx(spearmanr(a, b).statistic, abs=1e-12)  # rounding only
    assert spearman_rho([0.72, 0.71, 0.47], [0.721, 0.714, 0.559]) == 1.0  # the pendubot entries' order
    with pytest.raises(ValueError, match="same length >= 2"):
        spearman_rho([1.0], [2.0])
    with pytest.raises(ValueError, match="same length >= 2"):
        spearman_rho([1.0, 2.0], [2.0, 3.0, 4.0])


def test_hardware_leaderboard_page_shows_entries_beside_the_robot(tmp_path, monkeypatch):
    from pendulab.commands.leaderboard import write_leaderboard

    records = tmp_path / "records"
    records.mkdir()
    for entry, score in (("acados_mpc", 0.30), ("ar_eapo", 0.50), ("mcpilco", 0.40)):
        _record(records, entry, "pendubot", 0, score)
    page = write_leaderboard(
        tmp_path / "page" / "hw.md", progress=False, controllers=["global"], quick=True, root=tmp_path / "journals",
        tasks=["pendubot"], protocols=("v3-hardware",), passive_allowance=0.5, upstream_records=records,
    )  # fmt: skip
    text = page.read_text()
    assert "## RealAIGym v3 hardware protocol" in text and "passive joint allowance 0.5 N m" in text
    # Only the protocol asked for: no v2, robustness or v3 sections, no own scorecards.
    for other in ("## RealAIGym simulation leaderboard v2", "## RealAIGym robustness", "## RealAIGym v3 (ICRA", "scorecard"):
        assert other not in text, other
    assert "| published AcadosMPC (`acados_mpc`, real robot) |  | 0.721 | | | |" in text
    assert "| AR-EAPO (`ar_eapo`) | **0.500** | 0.000 | 1 | 0.714 | submitted |" in text
    # Protocol order AR-EAPO > MC-PILCO > AcadosMPC, robot AcadosMPC > AR-EAPO > MC-PILCO: rank differences 2, 1, 1,
    # rho = 1 - 6 * 6 / (3 * 8) = -0.5; VIMPPI named as not run.
    assert "(AcadosMPC, AR-EAPO, MC-PILCO): **-0.50**; not run: VIMPPI." in text
    assert "--protocol v3-hardware --passive-allowance 0.5" in text  # the page says how to make it again
    assert (page.parent / "figures" / "leaderboard_v3_hardware.png").stat().st_size > 10_000
    # The CLI takes the same restriction; an allowance for a protocol that has none is refused.
    monkeypatch.chdir(tmp_path)
    assert main(["score", "--leaderboard", "--protocol", "v3", "--passive-allowance", "0.5", "--no-progress"]) == 2
    assert not (tmp_path / "pendulab-out").exists()

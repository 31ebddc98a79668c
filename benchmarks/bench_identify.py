"""Identification of RealAIGym's design C.1 robot against DFKI's four published parameter sets, on real records.

1. **Leave-one-record-out** over the eight excitation records (:data:`pendulab.identify.datasets.C1_EXCITATION`):
   pendulab's whole pipeline (structure choice, regression, output error) runs on seven records and is
   judged on the eighth; DFKI's sets 1.0, 1.1, 2.0 and 3.0 are judged on the same records. Measures: torque
   residual RMS per joint, open-loop angle error at 0.1, 0.25, 0.5, 1 s from measured states every 0.1 s.
   Each finished fold is journaled (``--journal``) and skipped on ``--resume``.
2. **Reproducibility**: fits on two disjoint halves (records 1,3,5,7 and 2,4,6,8) and their base
   parameters compared with their 95 % intervals.
3. **Speed**: the whole identification on the eight records, wall time, median of ``--repeats`` runs.
4. **Blind test**: the model fitted on all eight records, and DFKI's sets, judged once on the two
   swing-up records 154220 and 154548 (never used to fit, tune or choose).

Writes ``benchmarks/results/identify.md``, ``identify.json`` and the figure ``identify_c1.png``.

Usage::

    python benchmarks/bench_identify.py [--repeats 3] [--resume]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pendulab._journal import Journal
from pendulab.identify.datasets import C1_BLIND, C1_EXCITATION, c1_record
from pendulab.identify.pipeline import identify
from pendulab.identify.preprocess import prepare
from pendulab.identify.published import C1_GEOMETRY, DFKI_C1
from pendulab.identify.regressor import robot_to_standard
from pendulab.identify.simulate import HORIZONS
from pendulab.identify.validation import RecordScore, leave_one_out, score_record, standard_vector
from pendulab.viz.identify import identification_figure

RESULTS = Path(__file__).resolve().parent / "results"
PRIOR = robot_to_standard(DFKI_C1["1.0"])
OTHERS = {f"DFKI {k}": v for k, v in DFKI_C1.items()}


def pooled(scores: list[RecordScore]) -> tuple[np.ndarray, np.ndarray]:
    """Torque RMS per joint (sample-weighted) and prediction RMS per horizon and joint, pooled over records."""
    n = np.array([s.torque_n for s in scores])
    torque = np.sqrt(sum(s.torque_n * s.torque_rms**2 for s in scores) / n.sum())
    errs = np.concatenate([s.prediction for s in scores], axis=1)
    return torque, np.sqrt((errs**2).mean(axis=1))


def summary(scores: dict[str, list[RecordScore]]) -> dict[str, dict[str, list]]:
    """Pooled torque RMS per joint and prediction RMS per horizon and joint, by model (for the JSON)."""
    return {m: {"torque_rms": pooled(v)[0].tolist(), "prediction_rms": pooled(v)[1].tolist()} for m, v in scores.items()}


def to_json(s: RecordScore) -> dict:
    return {"record": s.record, "model": s.model, "torque_rms": s.torque_rms.tolist(), "torque_n": s.torque_n,
            "prediction": s.prediction.tolist()}  # fmt: skip


def from_json(d: dict) -> RecordScore:
    return RecordScore(d["record"], d["model"], np.array(d["torque_rms"]), d["torque_n"], np.array(d["prediction"]))


def fold_journal(path: Path, kind: str, settings: dict, resume: bool) -> tuple[Journal, dict[str, list[RecordScore]]]:
    """The journal of the leave-one-record-out folds and, with ``resume``, the folds in it that validate.

    A :mod:`pendulab._journal` journal: pendulab version, ``settings``, each fold with its SHA-256; an edited or
    incomplete fold (or a journal of another pendulab version) is run again with a notice.
    """

    def check(record: str, scores: list) -> None:
        for s in scores:
            if from_json(s).record != record:
                raise ValueError(f"a score of record {s['record']!r} filed under {record!r}")

    journal = Journal(path, kind, settings, resume=resume, check=check)
    return journal, {k: [from_json(s) for s in v] for k, v in journal.records.items()}


def table(by_model: dict[str, list[RecordScore]]) -> list[str]:
    head = "| model | torque RMS q1 / q2 [N.m] | " + " | ".join(f"angle RMS at {h} s, q1 / q2 [rad]" for h in HORIZONS) + " |"
    lines = [head, "|" + "---|" * (2 + len(HORIZONS))]
    for name, scores in by_model.items():
        tq, pr = pooled(scores)
        cells = " | ".join(f"{pr[k, 0]:.4f} / {pr[k, 1]:.4f}" for k in range(len(HORIZONS)))
        lines.append(f"| {name} | {tq[0]:.3f} / {tq[1]:.3f} | {cells} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="timed identifications (median)")
    ap.add_argument("--journal", default="pendulab-out/bench_identify/folds.json")
    ap.add_argument("--resume", action="store_true", help="skip folds already in the journal")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args()
    out = Path(args.out)
    journal, done = fold_journal(Path(args.journal), "identify-c1-folds", {"records": list(C1_EXCITATION)}, args.resume)
    records = [c1_record(s) for s in C1_EXCITATION]
    bar = tqdm(total=len(records), initial=len(done), desc="leave-one-record-out folds", unit="fold")

    def on_fold(record: str, scores: list[RecordScore]) -> None:
        journal.record(record, [to_json(s) for s in scores])
        bar.update(1)

    folds = leave_one_out(records, C1_GEOMETRY, PRIOR, OTHERS, done=done, on_fold=on_fold)
    bar.close()
    by_model: dict[str, list[RecordScore]] = {}
    for scores in folds.values():
        for s in scores:
            by_model.setdefault(s.model, []).append(s)
    k025 = HORIZONS.index(0.25)
    ours_t, ours_p = pooled(by_model["pendulab"])
    best_other = {j: min(pooled(v)[1][k025, j] for m, v in by_model.items() if m != "pendulab") for j in range(2)}
    gain = {j: 1.0 - ours_p[k025, j] / best_other[j] for j in range(2)}
    beats_all = all(
        (ours_t < pooled(v)[0]).all() and (ours_p < pooled(v)[1]).all() for m, v in by_model.items() if m != "pendulab"
    )

    # Speed: the whole identification on the eight records.
    times = []
    final = None
    for _ in tqdm(range(args.repeats), desc="timed identifications", unit="run"):
        t0 = time.perf_counter()
        final = identify(records, C1_GEOMETRY, PRIOR)
        times.append(time.perf_counter() - t0)
    assert final is not None

    # Reproducibility: two disjoint halves, each with its own structure choice, then both at the structure the
    # eight records chose (the base parameters of one structure are what can be compared).
    halves, chosen_by_half = [], []
    for half in tqdm((records[0::2], records[1::2]), desc="halves", unit="half"):
        chosen_by_half.append(identify(half, C1_GEOMETRY, PRIOR).chosen)
        halves.append(identify(half, C1_GEOMETRY, PRIOR, structure=final.chosen))
    repro = []
    for name, a, sa, b, sb in zip(halves[0].base.names, halves[0].output_error.beta, halves[0].output_error.stderr(),
                                  halves[1].output_error.beta, halves[1].output_error.stderr(), strict=True):  # fmt: skip
        z = abs(a - b) / max(np.hypot(sa, sb), 1e-300)
        repro.append({"base": name, "half_a": [a, sa], "half_b": [b, sb], "z": z, "agree_95": bool(z <= 1.96)})

    # Blind test: judged once, nothing chosen on it.
    blind: dict[str, list[RecordScore]] = {}
    blind_preps = []
    for stamp in C1_BLIND:
        prep = prepare(c1_record(stamp))
        blind_preps.append(prep)
        blind.setdefault("pendulab", []).append(score_record(prep, "pendulab", final.vector(), C1_GEOMETRY))
        for name, p in OTHERS.items():
            blind.setdefault(name, []).append(score_record(prep, name, standard_vector(p), C1_GEOMETRY))

    # Figure: the blind records under the final model and DFKI 1.0 / 2.0; the error panels are the held-out folds'.
    models = {name: [vec] * len(blind_preps) for name, vec in (("pendulab (fit on the eight)", final.vector()),
              ("DFKI 1.0", standard_vector(DFKI_C1["1.0"])), ("DFKI 2.0", standard_vector(DFKI_C1["2.0"])))}  # fmt: skip
    fig = identification_figure(blind_preps, models, folds, C1_GEOMETRY, out / "identify_c1.png",
                                title="RealAIGym C.1: leave-one-record-out errors; blind records, 1 s open loop")  # fmt: skip

    plant = final.plant
    lines = [
        "# Identification of RealAIGym's design C.1 robot (real records)",
        "",
        f"Command: `python benchmarks/bench_identify.py --repeats {args.repeats}`; "
        f"machine: {platform.processor() or platform.machine()}, "
        f"{time.strftime('%Y-%m-%d')}. Figure: [identify_c1.png](identify_c1.png).",
        "",
        "## Leave-one-record-out on the eight excitation records (pooled over the held-out records)",
        "",
        *table(by_model),
        "",
        f"At 0.25 s pendulab's error is {100 * gain[0]:.0f} % (q1) and {100 * gain[1]:.0f} % (q2) below the best DFKI set "
        f"(target >= 30 %); lower than every DFKI set in torque residual per joint and at every horizon: {beats_all}.",
        "",
        "## Structure chosen (all eight records)",
        "",
        "| structure | base parameters | LOO torque RMS q1 / q2 [N.m] | LOO weighted score | BIC |",
        "|---|---|---|---|---|",
        *[
            f"| {s.name} | {s.n_base} | {s.cv_rms[0]:.4f} / {s.cv_rms[1]:.4f} | {s.cv_score:.4f} | {s.bic:.1f} |"
            for s in final.structures
        ],
        "",
        f"Chosen: **{final.chosen}** (smallest structure within 1 % of the best cross-validated score).",
        "",
        "## Parameters (all eight records; standard errors from the output-error fit)",
        "",
        "| base parameter | value | standard error |",
        "|---|---|---|",
        *[
            f"| {n} | {b:.6g} | {s:.2g} |"
            for n, b, s in zip(final.base.names, final.output_error.beta, final.output_error.stderr(), strict=True)
        ],
        "",
        "Physical realization (masses from the prior, DFKI 1.0; the motion cannot see them): "
        + ", ".join(f"{k} = {v:.5g}" for k, v in plant.params.items())
        + f"; torque offsets {plant.torque_offset[0]:.4g}, {plant.torque_offset[1]:.4g} N.m.",
        "",
        "## Reproducibility: records 1,3,5,7 against 2,4,6,8",
        "",
        f"Structures each half chooses on its own: {chosen_by_half[0]} / {chosen_by_half[1]} (the eight records: "
        f"{final.chosen}); the table fits both halves at {final.chosen}.",
        "",
        "| base parameter | half A (value, s.e.) | half B (value, s.e.) | z | within 95 % |",
        "|---|---|---|---|---|",
        *[
            f"| {r['base']} | {r['half_a'][0]:.5g} ± {r['half_a'][1]:.2g} | {r['half_b'][0]:.5g} ± {r['half_b'][1]:.2g} "
            f"| {r['z']:.2f} | {r['agree_95']} |"
            for r in repro
        ],
        "",
        "## Speed",
        "",
        f"Whole identification on the eight records (prepare, five structures x eight folds, regression, output error): "
        f"median {np.median(times):.1f} s of {len(times)} runs ({', '.join(f'{t:.1f}' for t in times)} s); target <= 60 s.",
        "",
        "## Blind test: the two swing-up records (never fitted, tuned or chosen on)",
        "",
        *table(blind),
        "",
    ]
    out.mkdir(parents=True, exist_ok=True)
    (out / "identify.md").write_text("\n".join(lines))
    doc = {
        "loo": summary(by_model),
        "gain_at_0.25s": [gain[0], gain[1]], "beats_every_dfki_set": beats_all, "chosen": final.chosen,
        "reproducibility": repro, "identify_seconds": times,
        "blind": {m: {"torque_rms": pooled(v)[0].tolist(), "prediction_rms": pooled(v)[1].tolist()} for m, v in blind.items()},
        "horizons": list(HORIZONS), "figure": str(fig.name),
    }  # fmt: skip
    (out / "identify.json").write_text(json.dumps(doc, indent=2) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

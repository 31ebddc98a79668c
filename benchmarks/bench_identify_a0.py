"""Identification of RealAIGym's design A.0 robot (the second robot) against DFKI's three A.0 sets, on real records.

The same pipeline as for C.1 (``bench_identify.py``), every setting at its default (8 Hz cutoff, the
same structures, 1 % rule, output error), on another robot: A.0's link lengths are C.1's swapped
(0.3 / 0.2 m), its records another lab day and another kind of motion.

1. **Leave-one-record-out** over A.0's nine sys-id records (:data:`pendulab.identify.datasets.A0_SYSID`):
   pendulab's whole pipeline runs on eight records and is judged on the ninth; DFKI's sets 1.0, 2.0
   and 2.1 are judged on the same records. Measures: torque residual RMS per joint, open-loop angle
   error at 0.1, 0.25, 0.5, 1 s from measured states every 0.1 s. Done twice: with the measured torque
   as the input (as for C.1) and with the commanded one. **The input is chosen here**: the one whose
   held-out angle RMS is lower at more of the (horizon, joint) pairs (the angles are the same
   measurement either way; the torque residuals are against different signals and do not compare).
   Each finished fold is journaled and skipped on ``--resume``.
2. **The model**: the pipeline on all nine sys-id records with the chosen input (structure
   comparison, parameters with standard errors, wall time); also with the other input, for reference.
3. **Validation**: the models and DFKI's sets judged once on the three pendubot swing-ups of
   2022-08-19 (:data:`~pendulab.identify.datasets.A0_SWINGUP`), which nothing was fitted, tuned or
   chosen on; the chosen input's table is the result, the other input's is shown for reference.

Writes ``benchmarks/results/identify_a0.md``, ``identify_a0.json`` and the figure ``identify_a0.png``;
journals and the fitted plant go under ``pendulab-out/bench_identify_a0/``.

Usage::

    python benchmarks/bench_identify_a0.py [--resume]
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
from bench_identify import fold_journal, pooled, summary, table, to_json
from tqdm import tqdm

from pendulab._journal import Journal
from pendulab.identify.datasets import A0_SWINGUP, A0_SYSID, a0_record
from pendulab.identify.pipeline import identify
from pendulab.identify.preprocess import Prepared, prepare
from pendulab.identify.published import A0_GEOMETRY, DFKI_A0
from pendulab.identify.records import REALAIGYM_COLUMNS, REALAIGYM_COMMAND_COLUMNS
from pendulab.identify.regressor import robot_to_standard
from pendulab.identify.simulate import HORIZONS, open_loop_segments
from pendulab.identify.validation import RecordScore, leave_one_out, score_record, standard_vector
from pendulab.model.plant_file import save_plant
from pendulab.viz.save import save_figure

RESULTS = Path(__file__).resolve().parent / "results"
PRIOR = robot_to_standard(DFKI_A0["1.0"])
OTHERS = {f"DFKI {k}": v for k, v in DFKI_A0.items()}
INPUTS = {"measured": REALAIGYM_COLUMNS, "commanded": REALAIGYM_COMMAND_COLUMNS}
#: One colour per model in every panel of the figure.
COLORS = {"pendulab": "tab:blue", "DFKI 1.0": "tab:orange", "DFKI 2.0": "tab:green", "DFKI 2.1": "tab:red"}


def run_folds(kind: str, journal: Path, resume: bool) -> dict[str, list[RecordScore]]:
    """Leave-one-record-out over the sys-id records with one torque column as the input, journaled per fold."""
    log, done = fold_journal(journal, "identify-a0-folds", {"records": list(A0_SYSID), "input": kind}, resume)
    records = [a0_record(s, INPUTS[kind]) for s in A0_SYSID]
    bar = tqdm(total=len(records), initial=len(done), desc=f"leave-one-record-out, {kind} torque", unit="fold")

    def on_fold(record: str, scores: list[RecordScore]) -> None:
        log.record(record, [to_json(s) for s in scores])
        bar.update(1)

    folds = leave_one_out(records, A0_GEOMETRY, PRIOR, OTHERS, done=done, on_fold=on_fold)
    bar.close()
    return folds


def by_model(folds: dict[str, list[RecordScore]]) -> dict[str, list[RecordScore]]:
    """Scores regrouped by model."""
    out: dict[str, list[RecordScore]] = {}
    for scores in folds.values():
        for s in scores:
            out.setdefault(s.model, []).append(s)
    return out


def final_fit(kind: str, path: Path, resume: bool) -> dict:
    """The pipeline on all nine sys-id records with one input, journaled (one record, validated) for ``--resume``."""
    need = ("seconds", "chosen", "vector", "structures", "base", "params", "stderr", "offset", "fit_angle_rms", "grid_s")
    log = Journal(path, "identify-a0-final", {"records": list(A0_SYSID), "input": kind}, resume=resume,
                  check=lambda key, doc: [doc[k] for k in need])  # fmt: skip
    if "fit" in log:
        return log.get("fit")
    records = [a0_record(s, INPUTS[kind]) for s in A0_SYSID]
    bar = tqdm(desc=f"fit on all nine, {kind} torque (output-error iterations)", unit="it")
    t0 = time.perf_counter()
    ident = identify(records, A0_GEOMETRY, PRIOR, progress=lambda it, rms: bar.update(1),
                     meta={"robot": "RealAIGym design A.0", "input": f"{kind} torque",
                           "prior": "DFKI A.0 model 1.0 (masses only)"})  # fmt: skip
    seconds = time.perf_counter() - t0
    bar.close()
    save_plant(ident.plant, path.with_name(f"plant_{kind}.json"))
    doc = {
        "seconds": seconds, "chosen": ident.chosen, "vector": ident.vector().tolist(),
        "structures": ident.plant.meta["structures"],
        "base": [[n, float(b), float(s)] for n, b, s in zip(ident.base.names, ident.output_error.beta,
                                                            ident.output_error.stderr(), strict=True)],
        "params": ident.plant.params, "stderr": ident.plant.stderr, "offset": list(ident.plant.torque_offset),
        "fit_angle_rms": ident.output_error.angle_rms.tolist(), "grid_s": ident.prepared[0].dt,
    }  # fmt: skip
    log.record("fit", doc)
    return doc


def a0_figure(
    preps: list[Prepared],
    shown: dict[str, np.ndarray],
    valid: dict[str, list[RecordScore]],
    loo: dict[str, list[RecordScore]],
    kind: str,
    path: Path,
) -> Path:
    """Error against horizon (swing-ups and held-out sys-id records), and each swing-up measured against predicted."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    n = len(preps)
    fig = plt.figure(figsize=(15, 2.3 * n + 4.4))
    grid = fig.add_gridspec(n + 1, 2, height_ratios=[1.6] + [1.0] * n, hspace=0.6, wspace=0.13)
    for j in range(2):
        ax = fig.add_subplot(grid[0, j])
        for name, color in COLORS.items():
            ax.plot(HORIZONS, pooled(valid[name])[1][:, j], "o-", color=color, lw=2.5 if name == "pendulab" else 1.3)
            ax.plot(HORIZONS, pooled(loo[name])[1][:, j], "s--", color=color, lw=1.0, ms=4, alpha=0.8)
        ax.set_xlabel("prediction horizon [s]")
        ax.set_ylabel(f"RMS error of q{j + 1} [rad]")
        ax.set_title(f"open-loop prediction error, joint {j + 1}")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    for i, prep in enumerate(preps):
        for j in range(2):
            ax = fig.add_subplot(grid[i + 1, j])
            measured = prep.q_measured[:, j]
            for name, pi in reversed(shown.items()):  # pendulab drawn last, on top of DFKI's
                for t, q in open_loop_segments(prep, pi, A0_GEOMETRY, every=1.0, length=1.0):
                    ax.plot(t, q[j], color=COLORS[name], lw=1.3 if name == "pendulab" else 1.0, alpha=0.9)
            ax.plot(prep.t, measured, color="k", lw=1.4)
            span = measured.max() - measured.min()
            ax.set_ylim(measured.min() - 0.25 * span, measured.max() + 0.25 * span)  # predictions that leave are cut off
            ax.set_xlim(prep.t[0], prep.t[-1])
            ax.set_ylabel(f"q{j + 1} [rad]")
            ax.set_title(f"swing-up {prep.name}, joint {j + 1}", fontsize=10)
            ax.grid(True, alpha=0.3)
            if i == n - 1:
                ax.set_xlabel("time [s]")
    handles = [Line2D([], [], color=c, lw=2, label=m) for m, c in COLORS.items()]
    handles += [
        Line2D([], [], color="gray", marker="o", lw=1.3, label="error on the three swing-ups (held out)"),
        Line2D([], [], color="gray", marker="s", ls="--", lw=1.0, label="error on the held-out sys-id records (leave one out)"),
        Line2D([], [], color="k", lw=1.4, label="measured angle"),
    ]
    fig.legend(handles=handles, loc="upper center", ncol=4, bbox_to_anchor=(0.5, 0.955), fontsize=9, frameon=False)
    fig.suptitle(
        f"RealAIGym A.0, {kind} torque as the input. Swing-up panels: measured angle and 1 s open-loop predictions from the "
        "measured state every 1 s\n(pendulab, DFKI 1.0, DFKI 2.0; the y-axis is cut at the measured range \u00b125 %, so "
        "diverging predictions leave the panel)",
        fontsize=11,
        y=0.995,
    )
    return save_figure(fig, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", default="pendulab-out/bench_identify_a0", help="journals and the fitted plant")
    ap.add_argument("--resume", action="store_true", help="skip folds (and the final fit) already journaled")
    ap.add_argument("--out", default=str(RESULTS))
    args = ap.parse_args()
    out, work = Path(args.out), Path(args.work)
    work.mkdir(parents=True, exist_ok=True)

    loo = {kind: by_model(run_folds(kind, work / f"folds_{kind}.json", args.resume)) for kind in INPUTS}
    # The input: the one with the lower held-out angle RMS at more (horizon, joint) pairs.
    loo_p = {kind: pooled(v["pendulab"])[1] for kind, v in loo.items()}
    wins = int((loo_p["commanded"] < loo_p["measured"]).sum())
    chosen = "commanded" if wins > loo_p["measured"].size / 2 else "measured"
    other = "measured" if chosen == "commanded" else "commanded"
    finals = {kind: final_fit(kind, work / f"final_{kind}.json", args.resume) for kind in (chosen, other)}
    final = finals[chosen]

    # Validation: the swing-ups, judged once per input.
    valid: dict[str, dict[str, list[RecordScore]]] = {}
    preps: dict[str, list] = {}
    for kind in (chosen, other):
        valid[kind], preps[kind] = {}, []
        for stamp in tqdm(A0_SWINGUP, desc=f"validation on the swing-ups, {kind} torque", unit="record"):
            prep = prepare(a0_record(stamp, INPUTS[kind]))
            preps[kind].append(prep)
            valid[kind].setdefault("pendulab", []).append(
                score_record(prep, "pendulab", np.array(finals[kind]["vector"]), A0_GEOMETRY)
            )
            for name, p in OTHERS.items():
                valid[kind].setdefault(name, []).append(score_record(prep, name, standard_vector(p), A0_GEOMETRY))
    per_record = {stamp: {m: [s for s in v if s.record == stamp] for m, v in valid[chosen].items()} for stamp in A0_SWINGUP}

    vec = np.array(final["vector"])
    shown = {"pendulab": vec, "DFKI 1.0": standard_vector(DFKI_A0["1.0"]), "DFKI 2.0": standard_vector(DFKI_A0["2.0"])}
    fig = a0_figure(preps[chosen], shown, valid[chosen], loo[chosen], chosen, out / "identify_a0.png")

    k025 = HORIZONS.index(0.25)
    loo_ours_t, loo_ours_p = pooled(loo[chosen]["pendulab"])
    loo_others = [pooled(v) for m, v in loo[chosen].items() if m != "pendulab"]
    loo_beats = all((loo_ours_p < p).all() for _, p in loo_others)
    loo_torque = [all(loo_ours_t[j] < t[j] for t, _ in loo_others) for j in range(2)]
    ours_t, ours_p = pooled(valid[chosen]["pendulab"])
    others_valid = {m: pooled(v) for m, v in valid[chosen].items() if m != "pendulab"}
    beats = {m: bool((ours_t < t).all() and (ours_p < p).all()) for m, (t, p) in others_valid.items()}
    lower_angles = {m: bool((ours_p < p).all()) for m, (_, p) in others_valid.items()}
    higher_angles = {m: bool((ours_p > p).all()) for m, (_, p) in others_valid.items()}
    best_name = {j: min(others_valid, key=lambda m, j=j: others_valid[m][1][k025, j]) for j in range(2)}
    gain = {j: 1.0 - ours_p[k025, j] / others_valid[best_name[j]][1][k025, j] for j in range(2)}

    def versus(j: int) -> str:
        word = "below" if gain[j] >= 0 else "above"
        return f"{100 * abs(gain[j]):.0f} % {word} {best_name[j]}'s (q{j + 1})"

    lines = [
        "# Identification of RealAIGym's design A.0 robot (the second robot, real records)",
        "",
        f"Command: `python benchmarks/bench_identify_a0.py`; machine: {platform.processor() or platform.machine()}, "
        f"{time.strftime('%Y-%m-%d')}. Figure: [identify_a0.png](identify_a0.png). Every pipeline setting is the "
        "default chosen on C.1 (8 Hz cutoff, the five structures, the 1 % rule, 1 s output-error windows).",
        "",
        "## Leave-one-record-out on the nine sys-id records, measured torque as the input (pooled over the held-out records)",
        "",
        *table(loo["measured"]),
        "",
        "## The same with the commanded torque as the input",
        "",
        *table(loo["commanded"]),
        "",
        "pendulab's held-out angle RMS, measured / commanded torque as the input: "
        + "; ".join(
            f"{h} s: {a[0]:.4f} / {b[0]:.4f} (q1), {a[1]:.4f} / {b[1]:.4f} (q2) rad"
            for h, a, b in zip(HORIZONS, loo_p["measured"], loo_p["commanded"], strict=True)
        )
        + f". The command is lower at {wins} of {loo_p['measured'].size} (horizon, joint) pairs: **the input is the "
        f"{chosen} torque**. (Torque residuals of the two tables are against different signals and do not compare.) "
        f"With it, pendulab's held-out angle error is lower than every DFKI set's at every horizon and joint: {loo_beats}; "
        "its torque residual is lower than every DFKI set's on joint 1 / joint 2: "
        f"{loo_torque[0]} / {loo_torque[1]}.",
        "",
        f"## Structure chosen (all nine sys-id records, {chosen} torque)",
        "",
        "| structure | base parameters | LOO torque RMS q1 / q2 [N.m] | LOO weighted score | BIC |",
        "|---|---|---|---|---|",
        *[
            f"| {st['name']} | {st['n_base']} | {st['cv_rms'][0]:.4f} / {st['cv_rms'][1]:.4f} | {st['cv_score']:.4f} "
            f"| {st['bic']:.1f} |"
            for st in final["structures"]
        ],
        "",
        f"Chosen: **{final['chosen']}** (smallest structure within 1 % of the best cross-validated score). "
        f"Records on one {1e3 * final['grid_s']:.2f} ms grid (trajectory_11's 1.5 ms resampled). "
        f"Whole identification: {final['seconds']:.1f} s. Output-error angle RMS on the fitted windows: "
        f"{final['fit_angle_rms'][0]:.4f} / {final['fit_angle_rms'][1]:.4f} rad.",
        "",
        "## Parameters (all nine sys-id records; standard errors from the output-error fit)",
        "",
        "| base parameter | value | standard error |",
        "|---|---|---|",
        *[f"| {n} | {b:.6g} | {s:.2g} |" for n, b, s in final["base"]],
        "",
        "Physical realization (masses from the prior, DFKI A.0 1.0; the motion cannot see them): "
        + ", ".join(f"{k} = {v:.5g}" for k, v in final["params"].items())
        + f"; torque offsets {final['offset'][0]:.4g}, {final['offset'][1]:.4g} N.m.",
        "",
        f"## Validation: the three pendubot swing-ups (never fitted, tuned or chosen on), {chosen} torque, pooled",
        "",
        *table(valid[chosen]),
        "",
        f"At 0.25 s pendulab's angle error is {versus(0)} and {versus(1)}, the best DFKI sets there. "
        "pendulab's angle error is lower at every horizon and joint than "
        + (", ".join(m for m, b in lower_angles.items() if b) or "no DFKI set")
        + "; higher at every horizon and joint than "
        + (", ".join(m for m, b in higher_angles.items() if b) or "no DFKI set")
        + ". Lower in torque residual on both joints and in angle error everywhere: "
        + ", ".join(f"{m}: {b}" for m, b in beats.items())
        + ".",
        "",
    ]
    for stamp in A0_SWINGUP:
        lines += [f"### Swing-up {stamp}", "", *table(per_record[stamp]), ""]
    lines += [
        f"## For reference: the {other} torque as the input (not chosen)",
        "",
        f"pendulab refitted on the nine with the {other} torque ({finals[other]['chosen']} chosen), and DFKI's sets, "
        "on the swing-ups with that input:",
        "",
        *table(valid[other]),
        "",
    ]
    out.mkdir(parents=True, exist_ok=True)
    (out / "identify_a0.md").write_text("\n".join(lines))
    doc = {
        "loo": {kind: summary(v) for kind, v in loo.items()},
        "input": chosen, "command_wins": wins,
        "final": final, "final_other_input": finals[other],
        "validation": summary(valid[chosen]),
        "validation_per_record": {stamp: summary(v) for stamp, v in per_record.items()},
        "validation_other_input": summary(valid[other]),
        "gain_at_0.25s": [gain[0], gain[1]], "best_dfki_at_0.25s": [best_name[0], best_name[1]], "beats": beats,
        "lower_angle_error_everywhere": lower_angles, "higher_angle_error_everywhere": higher_angles,
        "horizons": list(HORIZONS), "figure": str(fig.name),
    }  # fmt: skip
    (out / "identify_a0.json").write_text(json.dumps(doc, indent=2) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()

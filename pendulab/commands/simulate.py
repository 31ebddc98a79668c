"""``pendulab simulate``: run one scene or model and write its trajectory, figures and summary."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from typing import Any

import numpy as np

from ._common import (
    VOCABULARY,
    CLIError,
    add_plant_option,
    add_vocabulary_option,
    docs_page,
    format_summary,
    parse_number,
    parse_settings,
    plant_settings,
    summarize,
    trajectory_format,
    write_trajectory,
)

__all__ = ["register", "run"]

_KINDS = ("rigid", "elastic")


def register(subparsers: Any) -> None:
    """Add the ``simulate`` sub-command."""
    p = subparsers.add_parser(
        "simulate",
        help="simulate a scene or a model; write CSV/NPZ, figures, a summary",
        description=(
            f"Simulate a scene (TOML file or shipped name, see {docs_page('scenes')}) or a model with default "
            "parameters. --set overrides parameters and initial-state values by name; the other options "
            "override the scene's simulation settings."
        ),
    )
    src = p.add_argument_group("what to simulate (exactly one)")
    src.add_argument("--scene", metavar="FILE|NAME", help="scene file or shipped scene name (e.g. seed_paper)")
    src.add_argument(
        *VOCABULARY["model kind"],
        dest="model",
        metavar="KIND",
        help="model with default parameters, at rest: rigid | elastic; or 'auto' with --scene: the cheapest model of "
        "the hierarchy (linearized, rigid, rigid+quasi-static, elastic) predicted within the scene's [outputs] "
        "tolerance, decided before running (pendulab scene check; its table and horizon of validity go to stderr)",
    )
    src.add_argument(
        "--verify",
        action="store_true",
        help="with --model auto: also run the reference and report the chosen level's predicted against measured error",
    )
    add_vocabulary_option(
        p, "parameters", "set", "parameter (m1, k1, ...) or initial state (theta1, omega2, r1, ...) in SI units; repeatable"
    )
    add_vocabulary_option(p, "initial state", "set", "initial state entry (theta1, omega2, r1, ...) in SI units; repeatable")
    p.add_argument("--t-final", metavar="S", help="horizon [s]")
    p.add_argument("--dt", metavar="S", help="output step [s]")
    p.add_argument(
        "--method",
        help="integration method: auto (default; from stiffness and tolerance) or one of pendulab.METHODS, e.g. taylor",
    )
    p.add_argument("--rtol", metavar="TOL", help="relative tolerance")
    p.add_argument("--atol", metavar="TOL", help="absolute tolerance")
    add_plant_option(p, "a rigid --model or --scene; --set overrides its values")
    p.add_argument("--out", metavar="FILE", help="write the trajectory: .csv (header t, states, inputs, outputs) or .npz")
    p.add_argument("--plot", metavar="DIR", help="write the figures (PNG) into DIR")
    p.add_argument("--json", action="store_true", help="print the summary as JSON instead of a table")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``pendulab simulate``; return the exit status."""
    from ..scene import default_scene, load_scene

    auto = args.model == "auto"
    if auto and args.scene is None:
        raise CLIError("--model auto needs --scene FILE|NAME (the scene states the outputs and tolerance to meet)")
    if not auto and (args.scene is None) == (args.model is None):
        raise CLIError("give exactly one of --scene FILE|NAME or --model rigid|elastic (or --scene with --model auto)")
    if getattr(args, "verify", False) and not auto:
        raise CLIError("--verify applies to --model auto only (it proves the a priori choice against the reference)")
    if args.model is not None and args.model not in (*_KINDS, "auto"):
        raise CLIError(f"--model {args.model!r}: expected one of {[*_KINDS, 'auto']}")
    settings = parse_settings(args.set)
    overrides = {
        "t_final": parse_number("--t-final", args.t_final, positive=True),
        "dt": parse_number("--dt", args.dt, positive=True),
        "rtol": parse_number("--rtol", args.rtol, positive=True),
        "atol": parse_number("--atol", args.atol, positive=True),
        "method": args.method,
    }
    if args.out is not None:
        trajectory_format(args.out)  # fail before simulating

    scene = load_scene(args.scene) if args.scene is not None else default_scene(args.model)
    settings = {**plant_settings(args, scene.model.kind), **settings}
    if settings:
        scene = scene.with_settings(**settings)
    given = {k: v for k, v in overrides.items() if v is not None}
    print(f"pendulab simulate: {scene.name} ({scene.model.kind}) ...", file=sys.stderr)
    if auto:
        model, traj, extra = _simulate_auto(dataclasses.replace(scene, **given), verify=args.verify)
    else:
        model, traj, extra = scene.model, scene.simulate(**given), {}
    summary = summarize(scene.name, model, traj)
    summary["scene"] = scene.name
    summary["scene_model"] = scene.model.kind
    summary.update(extra)

    if args.out is not None:
        summary["out"] = str(write_trajectory(traj, args.out))
        print(f"pendulab simulate: wrote {summary['out']}", file=sys.stderr)
    if args.plot is not None:
        from ..viz.figures import save_figures

        written = save_figures({scene.name: (model, traj)}, args.plot)
        summary["figures"] = {k: str(v) for k, v in written.items()}
        print(f"pendulab simulate: wrote {len(written)} figures into {args.plot}", file=sys.stderr)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(format_summary([summary]))
    return 0


def _simulate_auto(scene: Any, verify: bool = False) -> tuple[Any, Any, dict[str, Any]]:
    """The cheapest model level predicted within the scene's tolerance: the model run, its own trajectory, summary extras.

    The level is chosen a priori (:func:`pendulab.scene.choice.choose_model`: predicted errors, no reference run).
    A rigid level runs the rigid counterpart itself (its own states, solver and statistics; no spring rows);
    ``rigid+quasi-static`` adds the quasi-static spring stretch, labelled as such; the scene's own model level
    runs the scene; ``linearized`` keeps the scene model's states (the rule's own linear solution, reused).
    ``verify`` also runs the reference and adds predicted against measured error to the summary.
    """
    from ..integrate import simulate
    from ..model.counterpart import rigid_counterpart, rigid_state
    from ..model.quasistatic import quasi_static_lengths
    from ..scene.choice import choose_model

    start = time.perf_counter()
    choice = choose_model(scene, verify=verify)
    print(choice.table(), file=sys.stderr)
    extra: dict[str, Any] = {
        "model_level": choice.chosen,
        "scene_params": {k: float(v) for k, v in scene.model.params.resolved().items()},
        "predicted_error": choice.to_dict()["levels"][[lv.name for lv in choice.levels].index(choice.chosen)]["predicted_error"],
        "valid_until_s": choice.trusted_until,
        "reference_horizon_s": choice.reference_horizon,
        "needed_rtol": choice.needed_rtol,
        "verdict": choice.verdict,
        "rule_time_s": choice.rule_time,
    }
    if choice.verification is not None:
        extra["verification"] = choice.verification.to_dict()
    if choice.chosen in ("rigid", "rigid+quasi-static") and scene.model.kind == "elastic":
        rigid = rigid_counterpart(scene.model)
        traj = simulate(
            rigid,
            rigid_state(scene.model, scene.x0),
            scene.t_final,
            dt=scene.dt,
            method=scene.method,
            rtol=scene.rtol,
            atol=scene.atol,
            u=scene.input_spec(),
        )
        if choice.chosen == "rigid+quasi-static":
            r = quasi_static_lengths(scene.model, traj.x[:, :2], traj.x[:, 2:], scene.u)  # as the hierarchy's level
            stretch = r - [scene.model.params.L1, scene.model.params.L2]
            extra["stretch_source"] = "quasi-static"
            extra["max_stretch_m"] = float(np.max(np.abs(stretch)))
        return rigid, traj, extra
    if choice.chosen != "linearized":  # the scene's own model: its own run, with the solver's statistics and inputs
        return scene.model, scene.simulate(), extra
    extra["method_note"] = "exact modal solution of the linearization at the nearest equilibrium"
    traj = choice.simulate(scene)
    # The summary reports the chosen model's own cost: the rule, whose linear solution is the level's run.
    traj = dataclasses.replace(traj, stats={**traj.stats, "wall_time": time.perf_counter() - start})
    return scene.model, traj, extra

"""Balance upright with LQR
========================

Balance the double pendulum upright with LQR: rigid and elastic, full / pendubot / acrobot.

For each model and actuation: design the LQR gain at up-up on the exact
linearization, simulate the nonlinear model from a perturbed upright state
with a sampled (100 Hz), saturated controller, and estimate the region of
attraction along a few directions by bisection on simulations (rigid model by
default: about 10 s; ``run(roa_kinds=("rigid", "elastic"))`` adds the elastic
one, three times as long). Prints the tables and writes one figure of the
closed-loop responses.

Run: ``python examples/balance_lqr.py [OUT_DIR]`` (default ``balance_figures``;
progress on stderr)
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import pendulab as pl  # noqa: E402
from pendulab.control import format_roa, lqr_balance, region_of_attraction, simulate_balance, wrap_state_error  # noqa: E402
from pendulab.control.balance import DEFAULT_DIRECTIONS  # noqa: E402

#: Torque limit of the demonstration [N.m].
U_MAX = 20.0


def run(
    *,
    kinds: Sequence[str] = ("rigid", "elastic"),
    actuations: Sequence[str] = ("full", "pendubot", "acrobot"),
    perturbation: tuple[float, float] = (0.1, -0.1),
    u_max: float = 20.0,
    t_final: float = 5.0,
    roa: bool = True,
    roa_kinds: Sequence[str] = ("rigid",),
    roa_tol: float = 0.02,
    out_dir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Design, simulate and (optionally) estimate the region of attraction.

    Parameters
    ----------
    kinds : sequence of {"rigid", "elastic"}
    actuations : sequence of {"full", "pendubot", "acrobot"}
    perturbation : (float, float)
        Initial (d theta1, d theta2) from upright [rad].
    u_max : float
        Torque limit [N.m].
    t_final : float
        Horizon [s].
    roa : bool
        Estimate the region of attraction (several simulations per direction).
    roa_kinds : sequence of {"rigid", "elastic"}
        Models whose region of attraction is estimated (about 3 s per actuation
        for the rigid model, 9 s for the elastic one).
    roa_tol : float
        Bisection tolerance [rad].
    out_dir : path, optional
        Where to write ``balance_lqr.png``.
    progress : callable(str), optional
        Called with a one-line status before each region-of-attraction bisection (one per direction).

    Returns
    -------
    dict
        ``designs``, ``trajectories`` and ``roa`` keyed by (kind, actuation);
        ``figure`` (path or None).
    """
    out: dict = {"designs": {}, "trajectories": {}, "roa": {}, "figure": None}
    for kind in kinds:
        model = pl.make_model(kind)
        for act in actuations:
            design = lqr_balance(model, act)
            x0 = design.x_eq.copy()
            x0[:2] += perturbation
            out["designs"][(kind, act)] = design
            out["trajectories"][(kind, act)] = simulate_balance(model, design, x0, t_final, u_max=u_max)
            if roa and kind in roa_kinds:
                rows = []
                for name, direction in DEFAULT_DIRECTIONS.items():  # one direction at a time, for the progress line
                    if progress is not None:
                        progress(f"region of attraction: {kind}, {act}, along {name} (bisection on simulations) ...")
                    rows += region_of_attraction(model, design, {name: direction}, u_max=u_max, t_final=t_final, tol=roa_tol)
                out["roa"][(kind, act)] = rows
    if out_dir is not None:
        out["figure"] = _figure(out, kinds, actuations, u_max, Path(out_dir))
    return out


def _figure(out: dict, kinds: Sequence[str], actuations: Sequence[str], u_max: float, out_dir: Path) -> Path:
    fig, axes = plt.subplots(2, len(actuations), figsize=(4.2 * len(actuations), 6.2), squeeze=False, sharex=True)
    for j, act in enumerate(actuations):
        for kind, ls in zip(kinds, ("-", "--"), strict=False):
            traj = out["trajectories"][(kind, act)]
            design = out["designs"][(kind, act)]
            err = wrap_state_error(traj.x - design.x_eq, traj.state_names)
            for i, name in enumerate(("theta1", "theta2")):
                axes[0][j].plot(traj.t, err[:, i], ls, color=f"C{i}", label=f"{name} - pi ({kind})")
            for i in design.input_indices:
                axes[1][j].plot(traj.t, traj.u[:, i], ls, color=f"C{i + 2}", label=f"tau{i + 1} ({kind})")
        axes[0][j].set_title(f"{act}: LQR at up-up, |tau| <= {u_max:g} N.m", fontsize=10)
        axes[0][j].set_ylabel("angle from upright [rad]")
        axes[1][j].set_ylabel("torque [N.m]")
        axes[1][j].set_xlabel("time [s]")
        for ax in axes[:, j]:
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7)
    fig.suptitle("Balancing the double pendulum (solid: rigid, dashed: elastic k = 500 N/m)", fontsize=11)
    fig.tight_layout()
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "balance_lqr.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("balance_figures")
    result = run(u_max=U_MAX, out_dir=out_dir, progress=lambda s: print(s, file=sys.stderr))
    print(f"{'model':<8} {'actuation':<9} {'max Re(cl) [1/s]':>16} {'final |angle error| [rad]':>26} {'max |tau| [N.m]':>16}")
    for (kind, act), design in result["designs"].items():
        traj = result["trajectories"][(kind, act)]
        err = np.abs(wrap_state_error(traj.x[-1] - design.x_eq, traj.state_names)[:2]).max()
        ctrl = design.closed_loop_eigenvalues
        print(f"{kind:<8} {act:<9} {ctrl.real.max():>16.3g} {err:>26.2e} {np.abs(traj.u).max():>16.3g}")
    for (kind, act), rows in result["roa"].items():
        print()
        print(format_roa(rows, title=f"region of attraction: {kind}, {act} (|tau| <= {U_MAX:g} N.m, from rest)"))
    print(f"\nwrote {result['figure']}")


if __name__ == "__main__":
    main()

"""Co-simulate exported FMUs
=========================

Co-simulate exported pendulab FMUs under sampled controllers.

Exports a rigid and an elastic FMU, then

1. balances the rigid FMU with LQR through the co-simulation master and checks it
   against the native sampled loop (same controller, zero-order hold);
2. steps the rigid and a stiff elastic FMU side by side in one master with the same torques;
3. demonstrates step retry: a master-side bound rejects big steps, the master
   restores the saved FMU state and covers the step in halves.

Run: ``python examples/cosimulate_fmu.py [OUT_DIR]`` (default ``cosim_figures``: the side-by-side figure;
prints a summary; needs a C compiler; about 10 s, progress on stderr).
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

import pendulab as pl
from pendulab.control.feedback import as_feedback, balance_controller, energy_swingup, upright_state
from pendulab.cosim import cosim, cosim_many
from pendulab.cosim.plots import plot_side_by_side
from pendulab.fmu.export import export


def run(
    *,
    t_final: float = 3.0,
    comm_step: float = 0.01,
    fmi_version: int = 2,
    fmus: tuple[Path, Path] | None = None,
    out_dir: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """Run the three demonstrations; return their key numbers.

    Parameters
    ----------
    t_final : float
        Horizon of the balance runs [s].
    comm_step : float
        Communication step = controller sample time [s].
    fmi_version : {2, 3}
    fmus : (Path, Path), optional
        Already exported rigid and elastic FMUs (default parameters); default: export them to a temporary directory.
    out_dir : str or Path, optional
        Where to write ``side_by_side.png`` (rigid vs elastic at k = 5e3 and 5e4 N/m); no figure if None.
    progress : callable(str), optional
        Called with a one-line status before each step (export, then the three demonstrations).

    Returns
    -------
    dict
        ``max_state_diff_native`` (FMU vs native loop), ``rigid_vs_elastic`` (max angle
        difference under the same torques), ``n_rejected`` and ``retry_vs_plain``.
    """
    say = progress or (lambda message: None)
    with tempfile.TemporaryDirectory() as tmp:
        rigid, stiff = pl.rigid(), pl.elastic(k1=5e4, k2=5e4)
        if fmus is None:
            say(f"exporting the rigid model as an FMI {fmi_version}.0 FMU (generated C, compiled) ...")
            fmu_rigid = export(rigid, Path(tmp) / "rigid.fmu", fmi_version)
            say(f"exporting the elastic model as an FMI {fmi_version}.0 FMU ...")
            fmus = (fmu_rigid, export(pl.elastic(), Path(tmp) / "elastic.fmu", fmi_version))
        fmu_r, fmu_e = fmus

        # 1. LQR balance through the FMU vs natively.
        say(f"1. LQR balance of the rigid FMU over {t_final:g} s, and the same loop natively ...")
        ctrl = balance_controller(rigid, comm_step)
        x0 = upright_state(rigid)
        x0[0] += 0.1
        co = cosim(fmu_r, ctrl, comm_step, t_final, x0=x0, tolerance=1e-10)
        nat = pl.simulate(rigid, x0, t_final, dt=comm_step, u=as_feedback(ctrl, rigid), rtol=1e-11, atol=1e-11)

        # 2. Rigid and elastic plants in one master, same torques (controller reads the rigid plant). The
        #    elastic plant runs open loop around an unstable equilibrium, so keep this part to 1 s.
        say("2. rigid and elastic FMUs side by side in one master ...")
        xe = upright_state(stiff)
        xe[0] += 0.1
        stiff_params = [None, {"k1": 5e4, "k2": 5e4}]  # FMU parameters set at instantiation
        both = cosim_many(
            [fmu_r, fmu_e], ctrl, comm_step, min(t_final, 1.0), x0=[x0, xe], params=stiff_params, solver="rodas4", tolerance=1e-9
        )
        if out_dir is not None:
            soft = pl.elastic(k1=5e3, k2=5e3)
            xs = upright_state(soft)
            xs[0] += 0.1
            three = cosim_many(
                [fmu_r, fmu_e, fmu_e],
                ctrl,
                comm_step,
                1.0,
                x0=[x0, xs, xe],
                params=[None, {"k1": 5e3, "k2": 5e3}, {"k1": 5e4, "k2": 5e4}],
                solver="rodas4",
                tolerance=1e-9,
            )
            labels = ["rigid (controller reads it)", "elastic k = 5e3 N/m", "elastic k = 5e4 N/m"]
            plot_side_by_side(three, labels, Path(out_dir) / "side_by_side.png", "three FMUs in one master, same torques")

        # 3. Step retry on a swing-up with a coarse 50 ms step and a 0.25 rad-per-step bound.
        say("3. energy swing-up with 50 ms steps, plain and with step retry ...")
        swing = energy_swingup(rigid, 0.05)
        start = rigid.state(theta1=0.1)
        plain = cosim(fmu_r, swing, 0.05, 4.0, x0=start, tolerance=1e-10)
        retried = cosim(
            fmu_r,
            swing,
            0.05,
            4.0,
            x0=start,
            tolerance=1e-10,
            check=lambda t, xa, xb: bool(np.abs(xb[:2] - xa[:2]).max() < 0.25),
            max_halvings=4,
        )
        return {
            "max_state_diff_native": float(np.abs(co.x - nat.x).max()),
            "rigid_vs_elastic": float(np.abs(both[0].x[:, :2] - both[1].x[:, :2]).max()),
            "n_rejected": int(retried.stats["n_rejected"]),
            "retry_vs_plain": float(np.abs(retried.x - plain.x).max()),
        }


def main() -> None:
    out_dir = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("cosim_figures")
    out = run(out_dir=out_dir, progress=lambda message: print(message, file=sys.stderr))
    print(f"FMU vs native sampled loop: max state difference {out['max_state_diff_native']:.2e}")
    print(
        f"rigid vs elastic (k = 5e4 N/m) under the same torques: max angle difference {out['rigid_vs_elastic']:.2e} rad over 1 s"
    )
    print(f"step retry: {out['n_rejected']} rejected steps, result within {out['retry_vs_plain']:.2e} of the plain run")
    print(f"wrote {out_dir / 'side_by_side.png'}")


if __name__ == "__main__":
    main()

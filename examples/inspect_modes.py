"""Equilibria and modes
====================

Inspect the equilibria and modes of the rigid and elastic double pendulum.

Prints a mode table per equilibrium (natural frequency in rad/s and Hz,
damping ratio, time constant of unstable modes, normalized shape labelled by
what moves), and writes the mode-shape snapshots and the frequency-against-
stiffness chart (elastic pendular modes converge to the rigid ones, spring
modes climb as sqrt(k)).

Run: ``python examples/inspect_modes.py [OUT_DIR]`` (default ``modes_figures``)
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from pathlib import Path

import pendulab as pl
from pendulab.analysis.modes import mode_table
from pendulab.viz.modes import save_mode_figures


def run(
    *,
    k: float = 500.0,
    names: Sequence[str] = ("down-down", "up-up"),
    out_dir: str | Path | None = None,
) -> dict:
    """Modes of both models at the named equilibria; optionally write the figures.

    Parameters
    ----------
    k : float
        Spring stiffness k1 = k2 of the elastic model [N/m].
    names : sequence of str
        Equilibria to analyse.
    out_dir : path, optional
        Where to write PNG figures (none written when ``None``).

    Returns
    -------
    dict
        ``modes[(kind, name)]`` -> tuple of Mode; ``equilibria[(kind, name)]``
        -> Equilibrium; ``figures`` -> list of written paths.
    """
    models = {"rigid": pl.rigid(), "elastic": pl.elastic(k1=k, k2=k)}
    result: dict = {"modes": {}, "equilibria": {}, "figures": []}
    for kind, model in models.items():
        eqs = [pl.equilibrium(model, n) for n in names]
        for eq in eqs:
            result["equilibria"][(kind, eq.name)] = eq
            result["modes"][(kind, eq.name)] = pl.modes(model, eq)
        if out_dir is not None:
            result["figures"] += save_mode_figures(model, out_dir, eqs)
    return result


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("modes_figures")
    result = run(out_dir=out)
    for (kind, name), ms in result["modes"].items():
        print(f"== {kind} {name}: {result['equilibria'][(kind, name)].stability}")
        print(mode_table(ms))
        print()
    for path in result["figures"]:
        print(f"wrote {path}")


if __name__ == "__main__":
    main()

"""Core invariants of the symbolic model that every other module relies on."""

import numpy as np

import pendulab as pl


def test_rigid_energy_conserved_chaotic():
    model = pl.rigid()
    traj = pl.simulate(model, [2.0, 2.0, 0.0, 0.0], 5.0, method="cvodes-adams", rtol=1e-11, atol=1e-11)
    e = traj["energy"]
    # Tight tolerances: CVODES at 1e-11 keeps energy to ~1e-9 relative over 5 s.
    assert np.max(np.abs(e - e[0])) / abs(e[0]) < 1e-8

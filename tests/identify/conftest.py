"""Synthetic robot records: a known model driven by multisine torques, with C.1's quantization and noise."""

from __future__ import annotations

import numpy as np
import pytest

from pendulab.identify.published import C1_GEOMETRY, DFKI_C1
from pendulab.identify.records import Record, make_record
from pendulab.identify.regressor import STANDARD_NAMES, robot_to_standard
from pendulab.identify.simulate import joint_rhs

#: The truth: DFKI's C.1 model 1.0 (with rotor inertia, viscous and Coulomb friction) and small reading offsets.
TRUE_PARAMS = dict(DFKI_C1["1.0"])
TRUE_OFFSET = (0.01, -0.015)

#: C.1's reading steps, measured from the shipped records (pendulab.identify.preprocess.quantum).
ANGLE_STEP = 3.8148e-4
TORQUE_STEP = 5.86081e-3


def true_vector() -> np.ndarray:
    pi = robot_to_standard(TRUE_PARAMS)
    pi["o1"], pi["o2"] = TRUE_OFFSET
    return np.array([pi[n] for n in STANDARD_NAMES])


def synthetic_record(seed: int, duration: float = 6.0, torque_noise: float = 0.01) -> Record:
    """Simulate the truth under a random multisine (0.3-3 Hz, ~0.5 N.m per joint) and read it like C.1.

    Time stamps are C.1's: 2 ms with one in 50 intervals stretched to 3.5 ms. The simulation runs at
    0.25 ms with the torque held per sample; angles are quantized to the encoder step, torques get
    white noise and the reading step, plus the reading offset.
    """
    rng = np.random.default_rng(seed)
    dts = np.where(rng.random(int(duration / 0.002)) < 0.02, 0.0035, 0.002)
    t = np.concatenate([[0.0], np.cumsum(dts)])
    t = t[t <= duration]
    freqs = rng.uniform(0.3, 3.0, size=(2, 4))
    phases = rng.uniform(0, 2 * np.pi, size=(2, 4))
    amp = rng.uniform(0.08, 0.15, size=(2, 4))
    tau = np.stack([(amp[j] * np.sin(2 * np.pi * freqs[j] * t[:, None] + phases[j])).sum(axis=1) for j in range(2)], axis=1)
    f = joint_rhs()
    pi = true_vector()
    fixed = np.array([C1_GEOMETRY[k] for k in ("l1", "l2", "g", "gr")])
    x = np.zeros(4)
    q = np.zeros((t.size, 2))
    for i in range(t.size):
        q[i] = x[:2]
        if i == t.size - 1:
            break
        h_total = t[i + 1] - t[i]
        n_sub = int(round(h_total / 0.00025))
        h = h_total / n_sub
        u = tau[i] + np.array(TRUE_OFFSET)  # the model subtracts the offset from the reading
        for _ in range(n_sub):
            k1 = np.asarray(f(x, u, pi, fixed)).ravel()
            k2 = np.asarray(f(x + h / 2 * k1, u, pi, fixed)).ravel()
            k3 = np.asarray(f(x + h / 2 * k2, u, pi, fixed)).ravel()
            k4 = np.asarray(f(x + h * k3, u, pi, fixed)).ravel()
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    q_read = np.round(q / ANGLE_STEP) * ANGLE_STEP
    tau_read = tau + np.array(TRUE_OFFSET) + rng.normal(0.0, torque_noise, tau.shape)
    tau_read = np.round(tau_read / TORQUE_STEP) * TORQUE_STEP
    return make_record(f"synthetic-{seed}", t, q_read, tau_read)


@pytest.fixture(scope="session")
def synthetic_records() -> list[Record]:
    return [synthetic_record(seed) for seed in range(4)]


@pytest.fixture(scope="session")
def synthetic_truth() -> tuple[dict[str, float], tuple[float, float]]:
    return TRUE_PARAMS, TRUE_OFFSET

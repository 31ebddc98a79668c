"""RealAIGym's robustness-v2 benchmark restated independently, in upstream's conventions, for side-by-side tests.

Written for pendulab from the behaviour of github.com/dfki-ric-underactuated-lab/double_pendulum
at commit 1e8544e67f3da72a51ee52fbbb278e131ce2a43f (BSD-3-Clause; copyright the DFKI
Underactuated Lab): ``model/plant.py`` (``DoublePendulumPlant``, formulas "UnderactuatedLecture"),
``simulation/simulation.py`` (``Simulator.simulate``: measurement, controller, applied torque, RK4
step, process noise), ``simulation/perturbations.py``, ``analysis/benchmark.py`` (the per-category
loops) and ``analysis/benchmark_scores.py``. It is a restatement, not a copy of that code (the
project does not carry upstream's source): it keeps what the numbers depend on, in upstream's
way of computing them, and differs from pendulab's runner where an independent check needs it:

* joint coordinates throughout (``q2`` relative to link 1), not pendulab's absolute angles;
* the equations of motion typed as the lecture formulas (mass, Coriolis, gravity matrices, friction
  vector, ``inv(M)``), not derived by CasADi from a Lagrangian;
* NumPy's *global* generator, called exactly where upstream calls it (``np.random.normal`` for the
  measurement, the torque and the process noise every step; ``rand``, ``shuffle``, ``rand``,
  ``uniform`` for a perturbation), not a pre-drawn block per run.

``real_upstream()`` imports upstream's own package instead when ``PENDULAB_UPSTREAM_DOUBLE_PENDULUM``
names its ``src/python`` directory (a local checkout), so the same test can run the original.
"""

from __future__ import annotations

import os
import sys
import types

import numpy as np

MODEL_1_0 = {
    "m": [0.5234602302310271, 0.6255677234174437],
    "l": [0.2, 0.3],
    "r": [0.2, 0.25569305436052964],
    "I": [0.031887199591513114, 0.05086984812807257],
    "g": 9.81,
    "gr": 6.0,
}


class LecturePlant:
    """The double pendulum in joint coordinates with rotor inertia and joint friction (lecture formulas)."""

    def __init__(self, m, l, r, I, b, cf, Ir, tl, g=9.81, gr=6.0):  # noqa: E741 (upstream's names)
        self.m, self.l, self.r, self.I, self.b, self.cf, self.Ir, self.g, self.gr = m, l, r, I, b, cf, Ir, g, gr
        self.tl = tl
        self.B = np.diag([0.0 if tl[0] == 0 else 1.0, 0.0 if tl[1] == 0 else 1.0])

    def rhs(self, x, tau):
        m, l, r, I, g, Ir, gr = self.m, self.l, self.r, self.I, self.g, self.Ir, self.gr
        c2, s2 = np.cos(x[1]), np.sin(x[1])
        h = m[1] * l[0] * r[1]
        M = np.array(
            [
                [I[0] + I[1] + m[1] * l[0] ** 2 + 2 * h * c2 + gr**2 * Ir + Ir, I[1] + h * c2 - gr * Ir],
                [I[1] + h * c2 - gr * Ir, I[1] + gr**2 * Ir],
            ]
        )
        C = np.array([[-2 * h * s2 * x[3], -h * s2 * x[3]], [h * s2 * x[2], 0.0]])
        G = np.array(
            [
                -m[0] * g * r[0] * np.sin(x[0]) - m[1] * g * (l[0] * np.sin(x[0]) + r[1] * np.sin(x[0] + x[1])),
                -m[1] * g * r[1] * np.sin(x[0] + x[1]),
            ]
        )
        F = np.array([self.b[i] * x[2 + i] + self.cf[i] * np.arctan(100 * x[2 + i]) for i in range(2)])
        acc = np.linalg.inv(M) @ (G + self.B @ np.asarray(tau) - C @ x[2:] - F)
        return np.array([x[2], x[3], acc[0], acc[1]])


def plant_for(task: str, *, Ir=0.0, m1r1=None, I1=None, b1=0.0, cf1=0.0, m2r2=None, m2=None, I2=None, b2=0.0, cf2=0.0):
    """The benchmark's plant of a task with one variation applied (``m1r1``, ``m2r2`` move the centre of mass)."""
    p = MODEL_1_0
    m = [p["m"][0], p["m"][1] if m2 is None else m2]
    r = [p["r"][0] if m1r1 is None else m1r1 / m[0], p["r"][1] if m2r2 is None else m2r2 / m[1]]
    inertia = [p["I"][0] if I1 is None else I1, p["I"][1] if I2 is None else I2]
    tl = [6.0, 0.0] if task == "pendubot" else [0.0, 6.0]
    return LecturePlant(m, p["l"], r, inertia, [b1, b2], [cf1, cf2], Ir, tl, g=p["g"], gr=p["gr"])


def gauss_pulses(tmax, dt, n_per_joint, min_t_dist, sigma_minmax, amp_minmax):
    """Random Gaussian torque pulses drawn from the global generator, in upstream's call order."""
    n = 2 * n_per_joint
    room = (tmax - (n + 1) * min_t_dist) / n
    mu = [min_t_dist + np.random.rand() * room]
    for _ in range(n - 1):
        mu.append(mu[-1] + min_t_dist + np.random.rand() * room)
    np.random.shuffle(mu)
    mu = np.reshape(mu, (2, n_per_joint))
    sigma = sigma_minmax[0] + np.random.rand(2, n_per_joint) * (sigma_minmax[1] - sigma_minmax[0])
    span = amp_minmax[1] - amp_minmax[0]
    amp = np.random.uniform(-span, span, size=(2, n_per_joint))
    amp += amp_minmax[0] * np.sign(amp)
    t = np.arange(0, tmax, dt)
    arr = np.asarray(
        [
            np.sum(
                [amp[j][i] * np.exp(-np.power(t - mu[j][i], 2.0) / (2 * sigma[j][i] ** 2.0)) for i in range(n_per_joint)], axis=0
            )
            for j in range(2)
        ]
    )
    return arr, mu, sigma, amp


def simulate(plant, controller, *, dt=0.002, tf=10.0, meas_sigma=(0.0,) * 4, delay=0.0, u_sigma=(0.0, 0.0), k=1.0, pert=((), ())):
    """One episode: upstream's step order and global-generator draws. Returns the final joint-coordinate state."""
    x = np.zeros(4)
    t = 0.0
    xs, taus = [x.copy()], []
    n_delay = int(delay / dt) + 1
    controller.reset()
    controller.init()
    while t < tf:
        xm = np.copy(xs[max(-n_delay, -len(xs))]) if n_delay > 1 else np.copy(x)
        xm = np.random.normal(xm, list(meas_sigma), np.shape(x))
        u = controller.get_control_output(x=xm, t=t)
        last = np.asarray(taus[-1]) if taus else np.zeros(2)
        nu = last + k * (np.copy(u) - last)
        nu = np.random.normal(nu, list(u_sigma), np.shape(nu))
        nu[0] = np.clip(nu[0], -plant.tl[0], plant.tl[0])
        nu[1] = np.clip(nu[1], -plant.tl[1], plant.tl[1])
        i = int(t / dt)
        for j in range(2):
            if i < len(pert[j]):
                nu[j] += pert[j][i]
        k1 = plant.rhs(x, nu)
        k2 = plant.rhs(x + 0.5 * dt * k1, nu)
        k3 = plant.rhs(x + 0.5 * dt * k2, nu)
        k4 = plant.rhs(x + dt * k3, nu)
        x = x + dt * ((k1 + 2.0 * (k2 + k3) + k4) / 6.0)
        x = np.random.normal(x, [0.0] * 4, np.shape(x))
        t += dt
        xs.append(x.copy())
        taus.append(list(nu))
    return x


def success(x) -> bool:
    """Final state within (0.35, 0.35, 1, 1) of (pi, 0, 0, 0), angles wrapped as ``wrap_angles_top``."""
    y = np.copy(x)
    y[0] = x[0] % (2 * np.pi)
    y[1] = (x[1] + np.pi) % (2 * np.pi) - np.pi
    goal, eps = (np.pi, 0.0, 0.0, 0.0), (0.35, 0.35, 1.0, 1.0)
    return all(abs(y[i] - goal[i]) < eps[i] for i in range(4))


def benchmark(task, controller, *, model_lists, meas_levels, u_levels, resp_levels, delay_levels, reps, u_reps, pert_reps):
    """The six categories in upstream's order; returns (successes per run, final states per run) in run order."""
    succ, finals = [], []

    def run(plant, **kw):
        xf = simulate(plant, controller, **kw)
        finals.append(xf)
        succ.append(success(xf))

    act = 0 if task == "pendubot" else 1
    for name, values in model_lists.items():
        for v in values:
            run(plant_for(task, **{name: v}))
    nominal = plant_for(task)
    for s in meas_levels:
        for _ in range(reps):
            run(nominal, meas_sigma=(0.0, 0.0, s, s))
    for s in u_levels:
        for _ in range(u_reps):
            us = [0.0, 0.0]
            us[act] = s
            run(nominal, u_sigma=us)
    for kk in resp_levels:
        run(nominal, k=kk)
    for d in delay_levels:
        run(nominal, delay=d)
    for _ in range(pert_reps):
        arr, *_ = gauss_pulses(10.0, 0.002, 3, 1.0, [0.05, 0.1], [0.5, 5.0])
        run(nominal, pert=arr)
    return succ, finals


class UpstreamStyle:
    """A pendulab SampledController behind upstream's controller interface (joint coordinates in, both torques out)."""

    def __init__(self, ctrl):
        from pendulab.control.feedback import full_input

        self.ctrl, self.full = ctrl, full_input
        self.ratio = round(ctrl.sample_time / 0.002)
        self.k, self.held = 0, np.zeros(2)

    def reset(self):
        self.ctrl.reset()
        self.k = 0

    def init(self):
        pass

    def get_control_output(self, x, t):
        if self.k % self.ratio == 0:
            self.held = self.full(self.ctrl, self.ctrl(t, np.array([x[0], x[0] + x[1], x[2], x[2] + x[3]])))
        self.k += 1
        return self.held


def real_upstream() -> types.ModuleType | None:
    """Upstream's own ``double_pendulum`` package from ``$PENDULAB_UPSTREAM_DOUBLE_PENDULUM`` (its ``src/python``), or None."""
    path = os.environ.get("PENDULAB_UPSTREAM_DOUBLE_PENDULUM")
    if not path or not os.path.isdir(os.path.join(path, "double_pendulum")):
        return None
    if path not in sys.path:
        sys.path.insert(0, path)
    sys.modules.setdefault("pandas", types.ModuleType("pandas"))  # imported by a CSV helper the benchmark never calls
    import double_pendulum.analysis.benchmark as bench

    return bench

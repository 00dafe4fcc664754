"""Exciting closed-loop trajectories of serial robots, integrated accurately.

Each joint follows a multi-sine reference under PD control with gravity
compensation from the nominal model; the controller acts in continuous time, so
the torques logged at the samples are exactly those the integrator applied."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.integrate import solve_ivp


def multisine(n: int, seed: int, amplitude: float = 0.6, frequencies=(0.15, 0.35, 0.6, 0.95, 1.4)):
    """q_ref(t), q_ref'(t) of n joints: sums of sines with random phases."""
    rng = np.random.default_rng(seed)
    f = np.asarray(frequencies)
    phase = rng.uniform(0, 2 * np.pi, (n, len(f)))
    weight = amplitude / len(f) / np.sqrt(f)[None, :] * rng.uniform(0.6, 1.0, (n, len(f)))
    offset = rng.uniform(-0.5, 0.5, n)

    def reference(t: float) -> tuple[np.ndarray, np.ndarray]:
        angle = 2 * np.pi * f[None, :] * t + phase
        return offset + (weight * np.sin(angle)).sum(1), \
            (weight * 2 * np.pi * f[None, :] * np.cos(angle)).sum(1)
    return reference


def simulate(forward_dynamics: Callable, gravity: Callable, n: int, duration: float, h: float,
             seed: int, kp: float | np.ndarray = 400.0, kd: float | np.ndarray = 40.0,
             rtol: float = 1e-10, reference: Callable | None = None,
             start: tuple | None = None, method: str = "DOP853"):
    """(t, q, qd, qdd, tau) sampled every h of the closed loop; forward_dynamics(q, qd, tau)
    and gravity(q) of the true robot / the nominal model.  reference(t) -> (q_ref, q_ref')
    defaults to multisine(n, seed); start = (t0, q0, qd0) continues a run from its state
    (default: t0 = 0 at rest on the reference); method: solve_ivp's ("Radau" for a robot at
    rest, where the saturated Coulomb friction is stiff)."""
    reference = reference or multisine(n, seed)

    def torque(t: float, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        q_ref, qd_ref = reference(t)
        return kp * (q_ref - q) + kd * (qd_ref - qd) + gravity(q)

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        q, qd = x[:n], x[n:]
        return np.concatenate([qd, forward_dynamics(q, qd, torque(t, q, qd))])

    t0, q0, qd0 = start if start is not None else (0.0, reference(0.0)[0], np.zeros(n))
    t = t0 + np.arange(0.0, duration + h / 2, h)
    solution = solve_ivp(rhs, (t0, t[-1]), np.concatenate([q0, qd0]), method=method,
                         t_eval=t, rtol=rtol, atol=rtol * 1e-2)
    if not solution.success:
        raise RuntimeError(f"integration failed: {solution.message}")
    q, qd = solution.y[:n].T, solution.y[n:].T
    tau = np.array([torque(tk, a, b) for tk, a, b in zip(t, q, qd)])
    qdd = np.array([forward_dynamics(a, b, c) for a, b, c in zip(q, qd, tau)])
    return t, q, qd, qdd, tau


def quantize(q: np.ndarray, bits: int) -> np.ndarray:
    """Encoder readings of `bits` bits per turn."""
    resolution = 2 * np.pi / 2 ** bits
    return np.round(q / resolution) * resolution

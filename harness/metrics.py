"""Scores of a scenario run: how well the observer and identifier did.

Definitions (also in docs/scenarios.md):
- velocity error e2 = omega - x2_hat; ``max_e2`` is max |e2| for t >= 1 s.
- ``convergence_time``: the first time after which |e2| stays below 0.02 rad/s
  (twice the largest steady-state error the paper's scheme shows).
- true perturbation xi = v - d(t) omega - sum_k (c_k - cbar_k) psi_k(theta, omega),
  what the filtered injection z_eq_filtered should equal.
- ``rms_perturbation``: RMS(z_eq_filtered - xi) after the transient (for a square
  wave, away from the jumps); ``delay``: the time shift s minimizing
  RMS(z_eq_filtered(t) - xi(t - s)).
- LSM: relative error of each identified coefficient at 20 s and at the end.
- MFF: RMS of d_hat - d after the transient, and the lag of d_hat behind d.
"""
from __future__ import annotations

import numpy as np

from .master import Records
from .scenarios import Scenario

CONVERGENCE_THRESHOLD = 0.02  # rad/s


def joint_basis(theta: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """psi = [sin x1, x2, sign x2, x1, 1] as rows."""
    return np.vstack([np.sin(theta), omega, np.sign(omega), theta, np.ones_like(theta)])


def true_perturbation(s: Scenario, r: Records) -> np.ndarray:
    theta, omega = r["plant.theta"], r["plant.omega"]
    mismatch = np.array(s.c_true) - np.array(s.c_nominal)
    return r["plant.v"] - r["plant.d"] * omega - mismatch @ joint_basis(theta, omega)


def convergence_time(t: np.ndarray, error: np.ndarray, threshold: float) -> float:
    """First time after which |error| stays below threshold (inf if it never does)."""
    above = np.nonzero(np.abs(error) >= threshold)[0]
    if above.size == 0:
        return float(t[0])
    if above[-1] == len(t) - 1:
        return float("inf")
    return float(t[above[-1] + 1])


def best_shift(t: np.ndarray, estimate: np.ndarray, truth: np.ndarray, mask: np.ndarray,
               max_shift: float) -> tuple[float, float]:
    """(shift, rms): the delay s in [0, max_shift] minimizing RMS(estimate(t) - truth(t - s)).

    Searched on a grid of at most 1000 shifts (the data are decimated to match)."""
    dt = float(np.median(np.diff(t)))
    q = max(1, int(np.ceil(max_shift / dt / 1000)))
    estimate, truth, mask, dt = estimate[::q], truth[::q], mask[::q], dt * q
    best = (0.0, float("inf"))
    for lag in range(0, int(round(max_shift / dt)) + 1):
        e = estimate[lag:] - truth[: len(truth) - lag]
        m = mask[lag:]
        rms = float(np.sqrt(np.mean(e[m] ** 2)))
        if rms < best[1]:
            best = (lag * dt, rms)
    return best


def away_from_jumps(t: np.ndarray, signal: np.ndarray, before: float, after: float) -> np.ndarray:
    """Mask that is False from ``before`` s before to ``after`` s after each jump of signal."""
    jumps = t[1:][np.abs(np.diff(signal)) > 1e-9]
    mask = np.ones_like(t, dtype=bool)
    for tj in jumps:
        mask &= ~((t >= tj - before) & (t <= tj + after))
    return mask


def score(s: Scenario, r: Records) -> dict[str, float]:
    """All metrics of one run, as a flat dict of floats."""
    t = r.time
    e1 = r["plant.theta"] - r["observer.x1_hat[1]"]
    e2 = r["plant.omega"] - r["observer.x2_hat[1]"]
    after1 = t >= 1.0
    out: dict[str, float] = {
        "max_e1_after_1s": float(np.max(np.abs(e1[after1]))),
        "max_e2_after_1s": float(np.max(np.abs(e2[after1]))),
        "mean_e2_after_1s": float(np.mean(e2[after1])),
        "convergence_time": convergence_time(t, e2, CONVERGENCE_THRESHOLD),
    }
    after = t >= s.transient
    if s.kind == "perturbation":
        xi = true_perturbation(s, r)
        z = r["observer.z_eq_filtered[1]"]
        mask = after.copy()
        if s.plant.get("disturbance") == 2:
            mask &= away_from_jumps(t, r["plant.v"], 0.005, 0.05)
        out["rms_perturbation"] = float(np.sqrt(np.mean((z - xi)[mask] ** 2)))
        out["delay"], out["rms_perturbation_shifted"] = best_shift(t, z, xi, mask, 0.1)
    elif s.kind == "lsm":
        for k, name in enumerate(["a1", "a2", "a3"]):
            estimate = r[f"observer.theta_hat[1,{k + 1}]"]
            truth = s.c_true[k]
            out[f"{name}_rel_error_end"] = float(abs(estimate[-1] - truth) / truth)
            at20 = np.searchsorted(t, 20.0)
            if at20 < len(t):
                out[f"{name}_rel_error_20s"] = float(abs(estimate[at20] - truth) / truth)
    elif s.kind == "mff":
        d_hat, d = r["observer.theta_hat[1,2]"], r["plant.d"]
        out["rms_damping"] = float(np.sqrt(np.mean((d_hat - d)[after] ** 2)))
        out["damping_lag"], out["rms_damping_shifted"] = best_shift(t, d_hat, d, after, 2.0)
    return out

"""Metrics of one method on one case (all after the case's transient).

* ``vel_rms``, ``vel_max``: RMS and max |x2 - velocity estimate|.
* LSM cases (A, 6.2): ``err_<p>`` relative error of p in b, c1, c2, c3 at the end;
  ``t1pct_<p>`` the time after which it stays within 1 % (inf: never);
  ``param_worst`` / ``t1pct_worst`` the worst over c1, c2, c3 (b is reported on
  its own since the FMU may hold it at the nominal value).
* 6.1: ``pert_rms`` RMS(zbar - xi) with xi = true acceleration - nominal model at
  the true state; ``pert_delay``, ``pert_rms_shifted`` from harness.metrics.best_shift.
* 6.3: ``d_rms`` RMS(d_hat - d); ``d_lag``, ``d_rms_shifted`` likewise.
* ``tv_zbar``: total variation of the perturbation estimate per second (chattering).
"""
from __future__ import annotations

import math

import numpy as np

from harness.metrics import best_shift

from .methods import Case, Estimate

NAN = float("nan")
WITHIN = 0.01


def time_within(t: np.ndarray, estimate: np.ndarray, truth: float, tol: float = WITHIN) -> float:
    """First time after which |estimate - truth| <= tol |truth| for good (inf if the last
    value is outside, NaN if the trajectory has NaN)."""
    if estimate is None or len(estimate) == 0 or not np.all(np.isfinite(estimate)):
        return NAN
    outside = np.nonzero(np.abs(estimate - truth) > tol * abs(truth))[0]
    if outside.size == 0:
        return float(t[0])
    if outside[-1] == len(t) - 1:
        return math.inf
    return float(t[outside[-1] + 1])


def _rms(e: np.ndarray) -> float:
    return float(np.sqrt(np.mean(e ** 2))) if e.size and np.all(np.isfinite(e)) else NAN


def score(case: Case, est: Estimate) -> dict[str, float]:
    """All metrics of one estimate (NaN where the method failed or does not deliver)."""
    data = case.data
    t = data.t
    after = t >= case.transient
    out: dict[str, float] = {}
    if est.velocity is not None:
        e = (data.x2 - est.velocity)[after]
        out["vel_rms"] = _rms(e)
        out["vel_max"] = float(np.max(np.abs(e))) if np.all(np.isfinite(e)) else NAN
    else:
        out["vel_rms"] = out["vel_max"] = NAN

    kind = case.scenario_kind
    if kind == "lsm":
        truth = {"b": data.b, "c1": data.c[0], "c2": data.c[1], "c3": data.c[2]}
        for p, true in truth.items():
            traj = est.params.get(p)
            if traj is None or est.param_t is None:
                out[f"err_{p}"] = out[f"t1pct_{p}"] = NAN
                continue
            out[f"err_{p}"] = float(abs(traj[-1] - true) / abs(true))
            out[f"t1pct_{p}"] = time_within(est.param_t, traj, true)
        cs = [out[f"err_c{k}"] for k in (1, 2, 3)]
        ts = [out[f"t1pct_c{k}"] for k in (1, 2, 3)]
        out["param_worst"] = max(cs) if all(math.isfinite(c) for c in cs) else NAN
        out["t1pct_worst"] = max(ts) if not any(math.isnan(x) for x in ts) else NAN

    xi = data.acc - (case.b_nominal * data.u - case.c_nominal[0] * np.sin(data.x1)
                     - case.c_nominal[1] * data.x2 - case.c_nominal[2] * np.sign(data.x2))
    if kind == "perturbation":
        if est.zbar is not None and np.all(np.isfinite(est.zbar[after])):
            out["pert_rms"] = _rms((est.zbar - xi)[after])
            out["pert_delay"], out["pert_rms_shifted"] = best_shift(t, est.zbar, xi, after, 0.1)
        else:
            out["pert_rms"] = out["pert_delay"] = out["pert_rms_shifted"] = NAN
    if kind == "mff":
        d_hat = est.params.get("d")
        if d_hat is not None and np.all(np.isfinite(d_hat[after])):
            out["d_rms"] = _rms((d_hat - data.d)[after])
            out["d_lag"], out["d_rms_shifted"] = best_shift(t, d_hat, data.d, after, 2.0)
        else:
            out["d_rms"] = out["d_lag"] = out["d_rms_shifted"] = NAN

    if est.zbar is not None and np.all(np.isfinite(est.zbar[after])):
        z = est.zbar[after]
        out["tv_zbar"] = float(np.sum(np.abs(np.diff(z))) / max(t[after][-1] - t[after][0], 1e-12))
    else:
        out["tv_zbar"] = NAN
    return out

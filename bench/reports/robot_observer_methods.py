"""The model-based observer (fmu/src/core/robot_observer.c) as methods of bench/reports/robots.py,
and the cost of its internal step:

    .venv/bin/python -m bench.reports.robot_observer_methods

- "model obs (URDF)": the observer with the URDF's model (the truth's links differ by
  0.8..1.2, or the payload is missing; the friction is unknown) and the online identifier
  (LSM over the base parameters) fed by it;
- "model obs (ident.)": the observer with the model identified offline from the same log
  by the sg pipeline (a causal observer of a robot whose model was identified once), the
  online identifier on top; "(ident. sign)": the same with the Coulomb shape fixed to
  sign(q'), the one the identification assumes;
- "FMU": the RobotObserver FMU (FMI 2, fmpy) on the log with the identified model and the
  gains of the row above: the same numbers as "model obs (ident.)" but its output after
  doStep(t_k, h) is the prediction for t_k + h, scored against the velocity there.

The gains (one pair for all joints) and the Coulomb shape of the observer's model are
tuned on the truth like the Kalman baseline (an oracle tuning of the velocity RMS, max
over joints): alpha1 = 10^x (x in [-1, 5]), alpha2 = k alpha1^(1/2) with k in {0.3, 1,
3, 10} (Theorem 3.1 with f+ = alpha1/2 and p = 0.5 gives k = 9.9: its bound is for
continuous time, the implicit scheme is stable below it and filters noise better), and
the Coulomb friction's smoothing velocity v_s in {0 (sign), 0.005, 0.02, 0.05} rad/s
(the simulated truth saturates below 0.02 rad/s; the identification assumes sign).
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np

from bench.reports.realdata.baselines import tune_log10
from bench.reports.robot_trajectories import multisine
from harness.robot.base_parameters import base_parameters
from harness.robot.examples import example_urdf
from harness.robot.fmu import fmu_parameters, run_fmu
from harness.robot.layout import ParameterLayout
from harness.robot.pipeline import identify_robot
from harness.robot.urdf import read_urdf

MODEL_METHODS = ("model obs (URDF)", "model obs (ident.)", "model obs (ident. sign)", "FMU")
SHAPES = (0.0, 0.005, 0.02, 0.05)  # [rad/s] Coulomb smoothing velocities tried
START = 0.2  # [s] the identifier starts after the observer's transient


def _rms(velocity: np.ndarray, qd: np.ndarray, skip: int) -> float:
    error = velocity[skip:-skip] - qd[skip:-skip]
    return float(np.sqrt(np.mean(error ** 2, axis=0)).max())


def _standard(base, pi_nominal: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Standard parameters with the base parameters beta (dependent columns 0)."""
    pi = pi_nominal.copy()
    pi[base.dependent] = 0.0
    pi[base.base] = beta
    return pi


def tune(robot, pi: np.ndarray, log, qd: np.ndarray, skip: int, shapes=SHAPES):
    """(the observer's model, (alpha1, alpha2, v_s)) of the least velocity RMS."""
    n, h = robot.n, log.step
    # (velocity RMS, the observer's model, (alpha1, alpha2, v_s)) of the best so far
    best: tuple[float, Any, tuple[float, float, float] | None] = (np.inf, None, None)
    for v_s in shapes:
        link, friction, _ = ParameterLayout(n).split(pi)
        body = robot.rigid_body(link=link, friction=friction, coulomb_velocity=v_s)
        for k in (0.3, 1.0, 3.0, 10.0):
            def cost(alpha1, body=body, k=k):
                return _rms(body.observe(log.q, log.u, h, 0.0, alpha1=alpha1,
                                         alpha2=k * np.sqrt(alpha1))["velocity"], qd, skip)
            x, rms = tune_log10(cost, -1.0, 5.0, coarse=1.0)
            if rms < best[0]:
                best = (rms, body, (10.0 ** x, k * 10.0 ** (x / 2), v_s))
    _, best_body, gains = best
    assert gains is not None, "tune: no gains were scored"
    print(f"  tuned: alpha1 {gains[0]:.3g}, alpha2 {gains[1]:.3g}, v_s {gains[2]:g}",
          flush=True)
    return best_body, gains


def model_observer(method: str, robot, log, qd: np.ndarray, unknown: str, skip: int,
                   shared: dict) -> tuple[np.ndarray, np.ndarray]:
    """(identified standard parameters, velocity at each sample) of one method; `shared`
    carries the identified model and the tuned gains from one method to the next."""
    h = log.step
    base = base_parameters(robot.rigid_body(), robot.arrays()["types"], robot.joint_names,
                           unknown)
    scale = np.sqrt(np.mean(log.u ** 2, axis=0))
    if method == "FMU":
        pi, (alpha1, alpha2, v_s) = shared["identified"], shared["tuned"]
        parameters = fmu_parameters(robot, unknown, h=h, alpha1=alpha1, alpha2=alpha2,
                                    t_id=START, torque_scale=scale, pi=pi, coulomb_velocity=v_s)
        result = run_fmu(shared["fmu"], parameters, log, statistics_interval=1e9)
        # the estimate for t_k + h is compared with the velocity at t_k + h
        velocity = np.vstack([result["velocity"][:1], result["velocity"][:-1]])
        return _standard(base, pi, result["base_estimate"]), velocity
    if method == "model obs (URDF)":
        pi = robot.parameters()
    elif "identified" in shared:
        pi = shared["identified"]
    else:
        pi = shared["identified"] = identify_robot(robot, log, unknown=unknown, method="sg").pi
    sign = method == "model obs (ident. sign)"
    body, tuned = tune(robot, pi, log, qd, skip, (0.0,) if sign else SHAPES)
    alpha1, alpha2, _ = tuned
    if method == "model obs (ident.)":
        shared["tuned"] = tuned  # the FMU's
    result = body.observe(log.q, log.u, h, 0.0, alpha1=alpha1, alpha2=alpha2, identify={
        "columns": base.base, "kind": "lsm", "rho": 1e-6, "torque_scale": scale,
        "start": int(START / h)})
    return _standard(base, pi, base.project(pi) + result["delta"]), result["velocity"]


def step_cost(name: str, steps: int = 20000, runs: int = 5) -> tuple[int, int, float]:
    """(joints, base parameters, median wall time per internal step [us]) of the observer
    with the online identification of every base parameter and the friction (the FMU's
    internal step without the FMI layer), along a smooth trajectory of the URDF's model."""
    urdf, locked = example_urdf(name)
    robot = read_urdf(urdf, locked=locked)
    body = robot.rigid_body()
    base = base_parameters(body, robot.arrays()["types"], robot.joint_names)
    reference, h = multisine(robot.n, 1), 1e-3
    q, qd = map(np.array, zip(*(reference(k * h) for k in range(steps))))
    qdd = np.gradient(qd, h, axis=0)
    u = body.inverse_dynamics(q, qd, qdd)
    times = []
    for _ in range(runs):
        started = time.perf_counter()
        body.observe(q, u, h, 10.0, identify={"columns": base.base, "kind": "lsm"})
        times.append(time.perf_counter() - started)
    return robot.n, base.count, 1e6 * float(np.median(times)) / steps


if __name__ == "__main__":
    # .venv/bin/python -m bench.reports.robot_observer_methods: the cost of one internal step
    for robot_name in ("double_pendulum", "ur5", "panda"):
        n, p, us = step_cost(robot_name)
        print(f"{robot_name}: {n} joints, {p} base parameters: {us:.1f} us per step "
              f"(median of 5 runs of 20000 steps)")

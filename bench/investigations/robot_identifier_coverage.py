"""Do the RobotObserver's standard errors mean what they say?  Its online identifier
(regressor_identifier.c, through the native library's offline path, the FMU's arithmetic)
over noise seeds:

    .venv/bin/python -m bench.investigations.robot_identifier_coverage [--seeds 50]
        [--noise 1e-5,1e-4] [--seconds 20] [--regressions window,observer]

The double pendulum of harness/robot/examples with viscous and Coulomb friction (0.05, 0.2;
0.04, 0.1), moved along an analytic multi-sine (bench/reports/robot_trajectories.multisine,
seed 3) at 1 kHz, torques by inverse dynamics; the positions measured with white noise of
each std (one seed per run). The observer has the URDF's inertials and no friction (f+ =
1000, the identifier LSM over the four friction columns from 0.2 s, rho 1e-6), regressing
through the fixed-lag window (the FMU's default) or on the observer's causal estimates, on
the same logs. Per regression, noise and parameter: the mean error relative to the truth,
the mean error over the spread of the estimates across the seeds (a bias the standard
errors cannot see), the mean reported standard error over that spread (1 when they mean
what they say), and the share of seeds whose truth lies within 2 standard errors. Prints a
Markdown table (not a test).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from bench.reports.robot_trajectories import multisine
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf

FRICTION = np.array([[0.05, 0.2], [0.04, 0.1]])  # per joint: viscous, Coulomb
NAMES = ("joint1 viscous", "joint1 Coulomb", "joint2 viscous", "joint2 Coulomb")
RATE, START, F_PLUS = 1000.0, 200, 1000.0
COLUMNS = np.arange(20, 24)  # the friction's columns of the two-joint regressor


def trajectory(seconds: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, q', q'' of the two joints at RATE; q'' by a central difference of the analytic
    q' over 1e-6 s (error about 1e-12 of it)."""
    reference = multisine(2, seed=3)
    t = np.arange(0.0, seconds, 1.0 / RATE)
    step = 1e-6
    q = np.array([reference(tk)[0] for tk in t])
    qd = np.array([reference(tk)[1] for tk in t])
    qdd = np.array([(reference(tk + step)[1] - reference(tk - step)[1]) / (2 * step)
                    for tk in t])
    return q, qd, qdd


def report(seeds: int, noises: list[float], seconds: float, regressions: list[str]) -> None:
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    truth = robot.rigid_body(friction=FRICTION)
    model = robot.rigid_body(friction=np.zeros_like(FRICTION))
    q, qd, qdd = trajectory(seconds)
    tau = truth.inverse_dynamics(q, qd, qdd)
    exact = FRICTION.ravel()
    print(f"## The robot identifier's standard errors over {seeds} noise seeds ({seconds:g} s "
          f"at {RATE:g} Hz)\n")
    print("| regression | noise [rad] | parameter | mean error | bias / spread | "
          "mean std / spread | within 2 std |")
    print("|---|---|---|---|---|---|---|")
    for regression, noise in ((r, n) for r in regressions for n in noises):
        started = time.perf_counter()
        estimates, errors = [], []
        for seed in range(seeds):
            measured = q + noise * np.random.default_rng(seed).standard_normal(q.shape)
            result = model.observe(measured, tau, 1.0 / RATE, F_PLUS,
                                   identify={"columns": COLUMNS, "kind": "lsm", "rho": 1e-6,
                                             "start": START, "regression": regression})
            estimates.append(result["delta"])
            errors.append(result["std_error"])
        theta, std = np.array(estimates), np.array(errors)
        spread = theta.std(axis=0, ddof=1)
        for k, name in enumerate(NAMES):
            bias = theta[:, k].mean() - exact[k]
            inside = np.mean(np.abs(theta[:, k] - exact[k]) <= 2 * std[:, k])
            print(f"| {regression} | {noise:g} | {name} | {100 * bias / exact[k]:+.2f} % | "
                  f"{bias / spread[k]:+.2f} | {std[:, k].mean() / spread[k]:.2f} | "
                  f"{100 * inside:.0f} % |")
        print(f"<!-- {regression}, noise {noise:g}: {time.perf_counter() - started:.1f} s -->")


def cli() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=50)
    parser.add_argument("--noise", default="1e-5,1e-4", help="comma-separated stds [rad]")
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--regressions", default="window,observer",
                        help="comma-separated: window (the default), observer")
    args = parser.parse_args()
    report(args.seeds, [float(x) for x in args.noise.split(",")], args.seconds,
           args.regressions.split(","))


if __name__ == "__main__":
    cli()

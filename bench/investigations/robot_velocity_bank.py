"""Why the causal `observer` velocities of the robot pipeline miss the oracle Kalman filter
with encoder noise: per joint, the noise-adaptive bank's velocity RMS, the bandwidths it
publishes (share of samples), and the causal Kalman filter's RMS at the bank members'
bandwidths (lambda = (omega h)^6) and at its oracle tuning.

    .venv/bin/python -m bench.investigations.robot_velocity_bank [--robot double_pendulum] [--rate 1000]
                                                  [--seconds 10] [--bits 17]

The log is bench/reports/robots.py's training log (same truth, controller and seed)."""
from __future__ import annotations

import argparse

import numpy as np

from bench.reports.realdata.baselines import kalman, tune_log10
from bench.reports.robot_trajectories import quantize, simulate
from bench.reports.robots import pinocchio_truth, truth_of
from harness.robot.examples import example_urdf
from harness.robot.joint_log import JointLog
from harness.robot.native import observe_adaptive
from harness.robot.smoothing import savitzky_golay
from harness.robot.urdf import read_urdf

GAINS = {"double_pendulum": (50.0, 5.0), "ur5": (400.0, 40.0), "panda": (200.0, 20.0)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--robot", default="double_pendulum")
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--bits", type=int, default=17)
    args = parser.parse_args()
    path, locked = example_urdf(args.robot)
    robot = read_urdf(path, locked=locked)
    link, friction, _ = truth_of(args.robot, robot, np.random.default_rng(1))
    nominal = robot.rigid_body()
    h = 1.0 / args.rate
    kp, kd = GAINS[args.robot]
    t, q, qd, _, tau = simulate(pinocchio_truth(path, locked, link, friction),
                                lambda x: nominal.gravity(x)[0], robot.n, args.seconds, h,
                                seed=1, kp=kp, kd=kd)
    y = quantize(q, args.bits)
    skip = int(0.5 / h)
    scored = slice(skip, -skip)
    bound = 1.5 * np.abs(savitzky_golay(JointLog(t, y, tau), 0.05)[2]).max(axis=0) + 1e-3
    bank = observe_adaptive(y, h, bound)
    members = [2.0 * 1.8 ** k for k in range(40) if 2.0 * 1.8 ** k * h <= 0.5]
    for i in range(robot.n):
        def rms(v):
            return float(np.sqrt(np.mean((v[scored] - qd[scored, i]) ** 2)))  # noqa: B023 (called in this iteration)
        published, counts = np.unique(bank.bandwidth[scored, i], return_counts=True)
        share = ", ".join(f"{w:.0f}: {100 * c / counts.sum():.0f} %"
                          for w, c in zip(published, counts))
        at_members = {w: rms(kalman(y[:, i], h, (w * h) ** 6)[1]) for w in members}
        best = min(at_members, key=at_members.__getitem__)
        log_lam, oracle = tune_log10(lambda lam: rms(kalman(y[:, i], h, lam)[1]), -18, 0,  # noqa: B023 (called in this iteration)
                                     coarse=1.0)
        print(f"joint {i + 1}: bank {rms(bank.velocity[:, i]):.3g} rad/s (published rad/s: "
              f"{share}); Kalman at the members' bandwidths: best {best:.0f} rad/s "
              f"{at_members[best]:.3g}, next faster {at_members.get(best * 1.8, np.nan):.3g}; "
              f"oracle Kalman {oracle:.3g} (omega {10 ** (log_lam / 6) / h:.0f} rad/s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

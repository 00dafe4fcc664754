"""identify --robot's wall time on a 6-joint arm: 3000 and 30,000 samples.

    python -m bench.perf.identify_robot_speed [--samples 3000,30000] [--robot ur5]

Simulates the arm (the robots report's closed loop: bench.reports.robot_trajectories,
its URDF with the truth of bench.reports.robots, 17-bit encoders) for 30 s at the rate
that gives the number of samples, writes the log as CSV, and times the whole command
line (`sto-harness identify LOG --robot URDF`, consistent URDF included) in a child
process, median of --repeats runs; beside it, the time of ordinary least squares on
Savitzky-Golay derivatives of the same log in this process (the baseline's cost).
"""
from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from bench.reports.robot_trajectories import quantize, simulate
from bench.reports.robots import pinocchio_truth, truth_of
from harness.robot.examples import example_urdf
from harness.robot.urdf import read_urdf

SECONDS = 30.0


def write_log(name: str, samples: int, path: Path) -> str:
    urdf, locked = example_urdf(name)
    robot = read_urdf(urdf, locked=locked)
    link, friction, _ = truth_of(name, robot, np.random.default_rng(1))
    forward = pinocchio_truth(urdf, locked, link, friction)
    nominal = robot.rigid_body()
    h = SECONDS / samples
    t, q, _, _, tau = simulate(forward, lambda x: nominal.gravity(x)[0], robot.n, SECONDS - h, h,
                               seed=1, rtol=1e-8)
    columns = {"t": t, **{f"q{i + 1}": quantize(q, 17)[:, i] for i in range(robot.n)},
               **{f"u{i + 1}": tau[:, i] for i in range(robot.n)}}
    pd.DataFrame(columns).to_csv(path, index=False, float_format="%.17g")
    return str(urdf)


def least_squares_seconds(urdf: str, path: Path) -> float:
    from harness.robot.base_parameters import base_parameters
    from harness.robot.joint_log import JointLog
    from harness.robot.smoothing import savitzky_golay

    robot = read_urdf(urdf)
    data = pd.read_csv(path).to_numpy()
    n = robot.n
    log = JointLog(data[:, 0], data[:, 1:1 + n], data[:, 1 + n:1 + 2 * n])
    start = time.perf_counter()
    q, qd, qdd, u = savitzky_golay(log, 0.05)
    body = robot.rigid_body()
    base = base_parameters(body, robot.arrays()["types"], robot.joint_names, "all")
    Yb = base.regressor(body.regressor(q, qd, qdd))
    np.linalg.lstsq(Yb.reshape(-1, base.count), u.ravel(), rcond=None)
    return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", default="3000,30000")
    parser.add_argument("--robot", default="ur5")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print("| samples | identify --robot (median) | least squares alone |\n|---|---|---|")
    for samples in (int(s) for s in args.samples.split(",")):
        with tempfile.TemporaryDirectory() as folder:
            log = Path(folder) / "log.csv"
            urdf = write_log(args.robot, samples, log)
            times = []
            for k in range(args.repeats):
                start = time.perf_counter()
                status = subprocess.run([sys.executable, "-m", "harness", "identify", str(log),
                                         "--robot", urdf, "--out", str(Path(folder) / f"o{k}"),
                                         "--quiet"], capture_output=True, text=True)
                times.append(time.perf_counter() - start)
                if status.returncode not in (0, 1):
                    print(status.stderr, file=sys.stderr)
                    return 1
            print(f"| {samples} | {statistics.median(times):.2f} s | "
                  f"{least_squares_seconds(urdf, log):.2f} s |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

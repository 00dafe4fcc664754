"""The consistent projection's wall time (harness.robot.consistency.consistent_parameters):
the 7-joint Panda and the 6-joint UR5.

    python -m bench.perf.consistent_projection [--robots panda,ur5] [--repeats 7]

Per robot: its base parameters (all unknown, the core's model), a truth as the robots
report's (bench.reports.robots.truth_of: links 0.8..1.2 times the URDF's, friction added),
an estimate of its base parameters with a 1e-3 relative standard error and its noise,
the friction's prior scale the truth's, and the projection at the default
--urdf-tolerance, timed in this process (building the convex program and solving it),
median of --repeats runs after one untimed run (cvxpy's first canonicalization imports
its modules).  The table has the objective's three parts at the optimum (D, B, Q) beside
the times.  Target: 0.5 s for 7 joints.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

from bench.reports.robots import truth_of
from harness.robot.base_parameters import base_parameters
from harness.robot.consistency import DEFAULT_URDF_TOLERANCE, consistent_parameters
from harness.robot.examples import example_urdf
from harness.robot.layout import ParameterLayout
from harness.robot.urdf import read_urdf


def problem(name: str):
    """(robot, base parameters, estimate, covariance, data scale) of the example robot
    `name`."""
    path, locked = example_urdf(name)
    robot = read_urdf(path, locked=locked)
    base = base_parameters(robot.rigid_body(), robot.arrays()["types"], robot.joint_names)
    rng = np.random.default_rng(1)
    link, friction, _ = truth_of(name, robot, rng)
    layout = ParameterLayout(robot.n)
    beta = base.project(layout.join(link, friction))
    sigma = 1e-3 * np.abs(beta) + 1e-6
    # the friction's scale as the pipeline's data would give it (prior_scales): the truth's
    data_scale = np.full(layout.size, np.nan)
    data_scale[layout.friction] = friction.ravel()
    return (robot, base, beta + sigma * rng.normal(size=len(beta)), np.diag(sigma ** 2),
            data_scale)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--robots", default="panda,ur5")
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print(f"python -m bench.perf.consistent_projection --robots {args.robots} "
          f"--repeats {args.repeats}  ({os.cpu_count()} cores, tolerance "
          f"{DEFAULT_URDF_TOLERANCE}, relative standard error 1e-3)")
    print("| robot | joints | base parameters | median | min | max | status | D | B | Q |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name in args.robots.split(","):
        robot, base, beta, covariance, scale = problem(name)
        consistent_parameters(robot, base, beta, covariance, scale)  # untimed: imports
        times = []
        for _ in range(args.repeats):
            start = time.perf_counter()
            p = consistent_parameters(robot, base, beta, covariance, scale)
            times.append(time.perf_counter() - start)
        print(f"| {name} | {robot.n} | {base.count} | {statistics.median(times):.3f} s | "
              f"{min(times):.3f} s | {max(times):.3f} s | {p.status} | {p.distance:.3g} | "
              f"{p.divergence:.3g} | {p.terms_prior:.3g} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Two logs of a three-joint arm for the example (not measured data: a simulation).

    python examples/robot_arm/simulate.py --out DIR

writes DIR/arm.csv (estimation, 30 s) and DIR/arm_validation.csv (another trajectory,
15 s), columns t [ms], q1..q3 [deg], u1..u3 [N.m], at 500 Hz: the arm of arm.urdf with
"real" values away from the URDF's (every link's inertia scaled by LINK_SCALE) and the
drive effects a maker's URDF does not state (TRUTH: viscous friction, a Coulomb level
per direction, a torque offset, the rotor's reflected inertia), moving along sums of
sines, the angles read by 17-bit encoders.  The torques are the inverse dynamics of the
exact trajectory, so the only noise is the encoders'.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from harness.robot.urdf import read_urdf

HERE = Path(__file__).resolve().parent
RATE, BITS = 500.0, 17
LINK_SCALE = (1.1, 0.9, 1.15)  # each link's mass, first moments and inertias
TRUTH = {  # per joint: base_yaw, shoulder, elbow
    "viscous": (0.25, 0.35, 0.12),           # N.m.s/rad
    "coulomb_positive": (0.45, 0.60, 0.30),  # N.m, while q' > 0
    "coulomb_negative": (0.35, 0.40, 0.25),  # N.m, while q' < 0
    "offset": (0.0, 0.8, -0.3),              # N.m
    "armature": (0.05, 0.08, 0.03),          # kg.m^2
}


def trajectory(seconds: float, seed: int) -> tuple[np.ndarray, ...]:
    """t, and q, q', q'' (N, 3) of a sum of four sines per joint."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, 1.0 / RATE)
    f = rng.uniform(0.1, 1.0, (3, 4))
    phase = rng.uniform(0, 2 * np.pi, (3, 4))
    amplitude = np.array([[0.8], [0.5], [0.6]]) / np.sqrt(4 * f)
    w = 2 * np.pi * f
    angle = w[None] * t[:, None, None] + phase[None]
    q = (amplitude * np.sin(angle)).sum(-1)
    qd = (amplitude * w * np.cos(angle)).sum(-1)
    qdd = -(amplitude * w ** 2 * np.sin(angle)).sum(-1)
    return t, q, qd, qdd


def torques(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """The real arm's joint torques."""
    robot = read_urdf(HERE / "arm.urdf")
    link = robot.arrays()["link"] * np.asarray(LINK_SCALE)[:, None]
    plus, minus = np.array(TRUTH["coulomb_positive"]), np.array(TRUTH["coulomb_negative"])
    friction = np.column_stack([TRUTH["viscous"], 0.5 * (plus + minus)])
    tau = robot.rigid_body(link=link, friction=friction).inverse_dynamics(q, qd, qdd)
    # the Coulomb level per direction, the offset and the rotor's inertia
    return (tau + 0.5 * (plus - minus) * (qd != 0) + np.array(TRUTH["offset"]) +
            np.array(TRUTH["armature"]) * qdd)


def log(seconds: float, seed: int) -> np.ndarray:
    t, q, qd, qdd = trajectory(seconds, seed)
    step = 2 * np.pi / 2 ** BITS
    encoder = np.round(q / step) * step
    return np.column_stack([1e3 * t, np.degrees(encoder), torques(q, qd, qdd)])


def write_logs(out: Path) -> None:
    """out/arm.csv and out/arm_validation.csv."""
    out.mkdir(parents=True, exist_ok=True)
    for name, seconds, seed in (("arm.csv", 30.0, 1), ("arm_validation.csv", 15.0, 2)):
        np.savetxt(out / name, log(seconds, seed), delimiter=",",
                   header="t,q1,q2,q3,u1,u2,u3", comments="", fmt="%.12g")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    write_logs(args.out)
    print(f"wrote {args.out / 'arm.csv'} and {args.out / 'arm_validation.csv'}")


if __name__ == "__main__":
    main()

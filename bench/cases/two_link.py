"""The two-link arm at 200 Hz with a passive second joint, and its model file written by hand.

The arm is example-robot-data's double pendulum (two parallel revolute axes along x, the
second joint l = 0.1 m from the first along link 1's z) carrying an unknown 0.3 kg tip
payload, with viscous and Coulomb friction added (bench/reports/robots.py: truth_of).
Its logs are those of case b of bench/reports/robot_real_logs.py, simulated by that
module's functions: Pinocchio under PD control of joint 1 along a multi-sine, joint 2
passive (torque 0, moved by joint 1), a clock jittering +-10 % about 5 ms, encoder steps
of 0.01 rad.

The model file states the same rigid body by its base parameters, the inertial
combinations a practitioner writes for a planar arm with parallel axes (link i's mass m_i,
first moments MY_i, MZ_i and inertia ZZ_i about its joint axis, at its joint):

    ZZ1R = ZZ1 + m2 l^2,  MZ1R = MZ1 + m2 l,  MY1,  ZZ2,  MY2,  MZ2

and each joint's viscous (fv) and Coulomb (fc) friction.  Gravity is -9.81 m/s^2 along z,
so link i's potential energy is g (MY_i sin q + MZ_i cos q) in its absolute angle.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bench.reports.robot_real_logs import CASES, joint_log, write_csv
from bench.reports.robots import pinocchio_truth, truth_of
from harness.robot.examples import example_urdf
from harness.robot.urdf import Robot, read_urdf

CASE = next(c for c in CASES if c.key == "b")  # 200 Hz, jitter, joint 2 passive, 0.01 rad
ROBOT = "double_pendulum"
LENGTH = 0.1        # joint 2's distance from joint 1 along link 1's z [m]
GRAVITY = 9.81      # Pinocchio's, along -z [m/s^2]
NAMES = ("ZZ1R", "MY1", "MZ1R", "ZZ2", "MY2", "MZ2", "fv1", "fc1", "fv2", "fc2")
TRAIN_SEED, VALIDATION_SEED = 1, 101  # robot_real_logs' seeds

MODEL_TOML = """\
# The two-link arm (example-robot-data's double pendulum): two parallel revolute joints,
# the second l = 0.1 m from the first; joint 2 is passive (its torque u2 is 0).
# c2 = cos(q2), s2 = sin(q2), q12 = q1 + q2 (link 2's absolute angle).
[model]
coordinates = ["q1", "q2"]
inputs = ["u1", "u2"]
equations = [
  "ZZ1R*der(q1,2) + ZZ2*(der(q1,2) + der(q2,2)) + l*(MZ2*cos(q2) + MY2*sin(q2))*(2*der(q1,2) + der(q2,2)) + l*(MY2*cos(q2) - MZ2*sin(q2))*der(q2)*(2*der(q1) + der(q2)) + g*(MY1*cos(q1) - MZ1R*sin(q1)) + g*(MY2*cos(q1 + q2) - MZ2*sin(q1 + q2)) + fv1*der(q1) + fc1*sign(der(q1)) = u1",
  "ZZ2*(der(q1,2) + der(q2,2)) + l*(MZ2*cos(q2) + MY2*sin(q2))*der(q1,2) - l*(MY2*cos(q2) - MZ2*sin(q2))*der(q1)^2 + g*(MY2*cos(q1 + q2) - MZ2*sin(q1 + q2)) + fv2*der(q2) + fc2*sign(der(q2)) = u2",
]

[parameters]   # nominal values: the maker's URDF
ZZ1R = {{ nominal = {ZZ1R}, unit = "kg.m^2" }}   # ZZ1 + m2 l^2
MY1  = {{ nominal = {MY1}, unit = "kg.m" }}
MZ1R = {{ nominal = {MZ1R}, unit = "kg.m" }}     # MZ1 + m2 l
ZZ2  = {{ nominal = {ZZ2}, unit = "kg.m^2" }}
MY2  = {{ nominal = {MY2}, unit = "kg.m" }}
MZ2  = {{ nominal = {MZ2}, unit = "kg.m" }}
fv1  = {{ nominal = {fv1}, unit = "N.m.s/rad" }}
fc1  = {{ nominal = {fc1}, unit = "N.m" }}
fv2  = {{ nominal = {fv2}, unit = "N.m.s/rad" }}
fc2  = {{ nominal = {fc2}, unit = "N.m" }}

[constants]
l = {{ value = 0.1, unit = "m" }}
g = {{ value = 9.81, unit = "m/s^2" }}

[units]
q1 = "rad"
q2 = "rad"
u1 = "N.m"
u2 = "N.m"
"""


def robot() -> tuple[Robot, Path]:
    path, locked = example_urdf(ROBOT)
    return read_urdf(path, locked=locked), path


def base_values(link: np.ndarray, friction: np.ndarray) -> np.ndarray:
    """The model file's parameters (NAMES) of link parameters (2, 10: Pinocchio's dynamic
    parameters m, m c, inertia at the link frame's origin) and friction (2, 2: viscous,
    Coulomb)."""
    m2 = link[1, 0]
    return np.array([link[0, 4] + m2 * LENGTH ** 2, link[0, 2], link[0, 3] + m2 * LENGTH,
                     link[1, 4], link[1, 2], link[1, 3], *friction.ravel()])


def truth() -> tuple[np.ndarray, np.ndarray]:
    """(link, friction) of the simulated arm: the URDF's links with the payload, friction."""
    arm, _ = robot()
    link, friction, _ = truth_of(ROBOT, arm, np.random.default_rng(1))
    return link, friction


def model_toml(values: np.ndarray | None = None) -> str:
    """The model file, its nominal values from the maker's URDF (6 digits), or `values`
    (in full)."""
    if values is None:
        arm, _ = robot()
        urdf = base_values(arm.arrays()["link"], arm.arrays()["friction"])
        text = [f"{v:.6g}" for v in urdf]
    else:
        text = [f"{float(v):.17g}" for v in values]
    return MODEL_TOML.format(**dict(zip(NAMES, text)))


def regressor(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """(N, 2, 10): the model file's equations as columns of NAMES, in plain numpy (a check
    of the file and the bench's independent scorer)."""
    c2, s2 = np.cos(q[:, 1]), np.sin(q[:, 1])
    c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
    c12, s12 = np.cos(q[:, 0] + q[:, 1]), np.sin(q[:, 0] + q[:, 1])
    a1, a2 = qdd[:, 0], qdd[:, 1]
    v1, v2 = qd[:, 0], qd[:, 1]
    Y = np.zeros((len(q), 2, len(NAMES)))
    zero = np.zeros(len(q))
    l, g = LENGTH, GRAVITY
    Y[:, 0] = np.column_stack([
        a1, g * c1, -g * s1, a1 + a2,
        l * s2 * (2 * a1 + a2) + l * c2 * v2 * (2 * v1 + v2) + g * c12,
        l * c2 * (2 * a1 + a2) - l * s2 * v2 * (2 * v1 + v2) - g * s12,
        v1, np.sign(v1), zero, zero])
    Y[:, 1] = np.column_stack([
        zero, zero, zero, a1 + a2,
        l * s2 * a1 - l * c2 * v1 ** 2 + g * c12,
        l * c2 * a1 + l * s2 * v1 ** 2 - g * s12,
        zero, zero, v2, np.sign(v2)])
    return Y


@dataclass
class Run:
    """One simulated run: the log as written (jittered stamps, encoder readings, torques)
    and the true states and torques at the same stamps."""
    t: np.ndarray
    q: np.ndarray
    u: np.ndarray
    q_true: np.ndarray
    qd_true: np.ndarray
    qdd_true: np.ndarray
    tau_true: np.ndarray


def simulate(seconds: float, seed: int) -> Run:
    """A run of `seconds` (robot_real_logs.joint_log with case b's properties)."""
    arm, path = robot()
    link, friction = truth()
    forward = pinocchio_truth(path, (), link, friction)
    (t, q, u), (q_true, qd, qdd, tau) = joint_log(CASE, arm, forward, seconds, seed)
    return Run(t, q, u, q_true, qd, qdd, tau)


def write(run: Run, csv_path: Path, model_path: Path | None = None) -> None:
    """The log as CSV (t, q1, q2, u1, u2: the robot path's default columns and the model
    file's names), and the model file when a path is given."""
    write_csv(Path(csv_path), run.t, run.q, run.u)
    if model_path is not None:
        Path(model_path).write_text(model_toml(), encoding="utf-8")

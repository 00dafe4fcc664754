"""Shared helpers of the robot tests: the two-link arm with a tip payload along an analytic
multi-sine, Pinocchio models of the same URDFs, random chains."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

PAYLOAD, TIP = 0.3, np.array([0.0, 0.0, 0.2])
FRICTION = np.array([[0.05, 0.2], [0.04, 0.1]])


def payload_link(link: np.ndarray) -> np.ndarray:
    """Link 2's standard parameters with a point mass PAYLOAD at TIP."""
    out = link.copy()
    skew = np.array([[0, -TIP[2], TIP[1]], [TIP[2], 0, -TIP[0]], [-TIP[1], TIP[0], 0]])
    I = -PAYLOAD * skew @ skew
    out[1] += [PAYLOAD, *(PAYLOAD * TIP), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]]
    return out


def multisine_log(truth, seconds: float, h: float, start: float = 0.0):
    """(t, q, qd, qdd, tau) of a two-joint arm (`truth`, a RigidBody) along an analytic
    multi-sine: exact velocities and accelerations, torques by inverse dynamics; the
    `seconds` from t = `start` (a long log in pieces)."""
    t = start + np.arange(0.0, seconds, h)
    f = np.array([0.2, 0.45, 0.8, 1.3])
    rng = np.random.default_rng(0)
    phase, amplitude = rng.uniform(0, 2 * np.pi, (2, 4)), np.array([[0.5], [0.4]]) / np.sqrt(f)
    angle = 2 * np.pi * f[None, None, :] * t[:, None, None] + phase[None]
    w = 2 * np.pi * f
    q = (amplitude * np.sin(angle)).sum(-1) / 2
    qd = (amplitude * w * np.cos(angle)).sum(-1) / 2
    qdd = -(amplitude * w ** 2 * np.sin(angle)).sum(-1) / 2
    return t, q, qd, qdd, truth.inverse_dynamics(q, qd, qdd)


def pinocchio_model(path: Path, locked=()) -> pin.Model:
    """Pinocchio's model of the URDF with the locked joints fixed at 0."""
    model = pin.buildModelFromUrdf(str(path))
    if locked:
        model = pin.buildReducedModel(model, [model.getJointId(j) for j in locked],
                                      pin.neutral(model))
    return model


def _origin(rng) -> str:
    xyz = " ".join(f"{x:.6f}" for x in rng.uniform(-0.4, 0.4, 3))
    rpy = " ".join(f"{x:.6f}" for x in rng.uniform(-np.pi, np.pi, 3))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _inertial(rng) -> str:
    # principal moments that satisfy the triangle inequality, rotated
    a, b = rng.uniform(0.01, 0.1, 2)
    c = rng.uniform(abs(a - b) + 1e-3, a + b)
    R = pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))
    I = R @ np.diag([a, b, c]) @ R.T
    return (f'<inertial>{_origin(rng)}<mass value="{rng.uniform(0.5, 3):.6f}"/>'
            f'<inertia ixx="{I[0, 0]:.17g}" ixy="{I[0, 1]:.17g}" ixz="{I[0, 2]:.17g}" iyy="{I[1, 1]:.17g}" '
            f'iyz="{I[1, 2]:.17g}" izz="{I[2, 2]:.17g}"/></inertial>')


def random_chain_urdf(rng, kinds: list[str], fixed_between: bool = True) -> str:
    """A serial chain with the given joint kinds, random placements and axes, and a
    fixed link with its own inertial after every moving joint (and a sensor branch)."""
    links = ['<link name="base"/>']
    joints = []
    parent = "base"
    for i, kind in enumerate(kinds):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        links.append(f'<link name="l{i}">{_inertial(rng)}</link>')
        joints.append(f'<joint name="j{i}" type="{kind}"><parent link="{parent}"/>'
                      f'<child link="l{i}"/>{_origin(rng)}'
                      f'<axis xyz="{float(axis[0])!r} {float(axis[1])!r} {float(axis[2])!r}"/>'
                      f'<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
        parent = f"l{i}"
        if fixed_between:
            links.append(f'<link name="f{i}">{_inertial(rng)}</link>')
            joints.append(f'<joint name="fj{i}" type="fixed"><parent link="{parent}"/>'
                          f'<child link="f{i}"/>{_origin(rng)}</joint>')
            links.append(f'<link name="sensor{i}">{_inertial(rng)}</link>')
            joints.append(f'<joint name="sj{i}" type="fixed"><parent link="{parent}"/>'
                          f'<child link="sensor{i}"/>{_origin(rng)}</joint>')
            parent = f"f{i}"
    return '<robot name="chain">' + "".join(links + joints) + "</robot>"


def swing_log(path: Path, t: np.ndarray, extra: dict[str, np.ndarray] | None = None) -> Path:
    """A CSV log (t, q1, q2, u1, u2) of a slow two-joint swing with torques of its size at
    the times t: enough for the readers and for identifying a payload; `extra` columns
    (name -> values at t) follow them."""
    q = np.column_stack([0.8 * np.sin(1.3 * (t - t[0])), 0.6 * np.sin(2.1 * (t - t[0]))])
    u = np.column_stack([5.0 * np.sin(1.3 * (t - t[0])), 2.0 * np.cos(2.1 * (t - t[0]))])
    extra = extra or {}
    columns = [t, q, u, *(np.broadcast_to(values, t.shape) for values in extra.values())]
    np.savetxt(path, np.column_stack(columns), delimiter=",",
               header=",".join(["t", "q1", "q2", "u1", "u2", *extra]), comments="",
               fmt="%.17g")
    return path


def _add_link(root, name: str, parent: str, kind: str, xyz: str) -> None:
    from lxml import etree
    link = etree.SubElement(root, "link", name=name)
    inertial = etree.SubElement(link, "inertial")
    etree.SubElement(inertial, "origin", xyz="0.01 0.02 0.03", rpy="0 0 0")
    etree.SubElement(inertial, "mass", value="1.7")
    etree.SubElement(inertial, "inertia", ixx="0.01", ixy="0", ixz="0", iyy="0.02", iyz="0",
                     izz="0.03")
    joint = etree.SubElement(root, "joint", name=f"{name}_joint", type=kind)
    etree.SubElement(joint, "parent", link=parent)
    etree.SubElement(joint, "child", link=name)
    etree.SubElement(joint, "origin", xyz=xyz, rpy="0 0 0")
    etree.SubElement(joint, "axis", xyz="0 1 0")


def branching_urdf(folder: Path) -> Path:
    """The double pendulum on a base with two wheels (continuous joints wheel_left_joint,
    wheel_right_joint) and with a finger on its last link (a prismatic finger_joint), as
    folder/mobile.urdf."""
    from lxml import etree

    from harness.robot.examples import example_urdf
    arm, _ = example_urdf("double_pendulum")
    tree = etree.parse(str(arm))
    root = tree.getroot()
    _add_link(root, "wheel_left", "base_link", "continuous", "0 0.3 0")
    _add_link(root, "wheel_right", "base_link", "continuous", "0 -0.3 0")
    _add_link(root, "finger", "link2", "prismatic", "0.1 0 0")
    branching = folder / "mobile.urdf"
    tree.write(str(branching))
    return branching

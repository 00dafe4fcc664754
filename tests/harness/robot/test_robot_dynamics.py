"""The C rigid-body dynamics (fmu/src/core/rigid_body.c) against Pinocchio.

M, C q', G, the full inverse dynamics, the regressor and the forward dynamics on
random states, within 1e-10 relative, for the example robots (UR5, the Panda arm
with its fingers locked, the double pendulum) and random chains with prismatic
joints, arbitrary axes and fixed links merged into their bodies, up to the offline
path's 12 joints."""
from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robot_helpers import pinocchio_model, random_chain_urdf

from harness.robot.layout import ParameterLayout
from harness.robot.urdf import read_urdf

TOLERANCE = 1e-10


def relative(ours: np.ndarray, reference: np.ndarray) -> float:
    """Relative error (absolute below a reference norm of 1e-6, e.g. C q' of one joint)."""
    error = float(np.linalg.norm(ours - reference) / max(np.linalg.norm(reference), 1e-6))
    assert np.isfinite(error)
    return error


def compare(robot, model, rng, samples: int = 20) -> dict[str, float]:
    """Largest relative error of each quantity over random states (without the URDF's
    joint friction, which Pinocchio's algorithms leave out)."""
    n = model.nv
    body, data = robot.rigid_body(friction=np.zeros((n, 2))), model.createData()
    worst: dict[str, float] = {}
    for _ in range(samples):
        q = rng.uniform(-np.pi, np.pi, n)
        v, a, tau = rng.normal(0, 2, n), rng.normal(0, 5, n), rng.normal(0, 10, n)
        G = pin.computeGeneralizedGravity(model, data, q)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        errors = {
            "rnea": relative(body.inverse_dynamics(q, v, a, friction=False)[0],
                             pin.rnea(model, data, q, v, a)),
            "M": relative(body.mass_matrix(q)[0], M),
            "G": relative(body.gravity(q)[0], G),
            "Cqd": relative(body.coriolis(q, v)[0], pin.nonLinearEffects(model, data, q, v) - G),
            "Y": relative(body.regressor(q, v, a)[0][:, ParameterLayout(n).links],
                          pin.computeJointTorqueRegressor(model, data, q, v, a)),
            "aba": relative(body.forward_dynamics(q, v, tau)[0],
                            pin.aba(model, data, q, v, tau)),
        }
        for key, value in errors.items():
            worst[key] = max(worst.get(key, 0.0), value)
    return worst


def test_example_robots_match_pinocchio(example):
    name, path, locked = example
    robot, model = read_urdf(path, locked=locked), pinocchio_model(path, locked)
    assert robot.n == model.nv == {"ur5": 6, "panda": 7, "double_pendulum": 2}[name]
    # the URDF reader's standard parameters are Pinocchio's (fixed links merged alike)
    reference = np.concatenate([model.inertias[i].toDynamicParameters()
                                for i in range(1, model.njoints)])
    assert relative(robot.parameters()[ParameterLayout(robot.n).links], reference) < TOLERANCE
    worst = compare(robot, model, np.random.default_rng(1))
    assert max(worst.values()) < TOLERANCE, worst


@pytest.mark.parametrize("kinds", [["prismatic"], ["revolute", "prismatic", "revolute"],
                                   ["prismatic", "revolute", "prismatic", "revolute",
                                    "continuous", "prismatic", "revolute"],
                                   ["revolute", "prismatic", "revolute", "revolute"] * 3])
def test_random_chains_match_pinocchio(tmp_path, kinds):
    rng = np.random.default_rng(len(kinds))
    path = tmp_path / "chain.urdf"
    path.write_text(random_chain_urdf(rng, kinds))
    robot = read_urdf(path)
    model = pin.buildModelFromUrdf(str(path))
    if "continuous" in kinds:  # Pinocchio's continuous joints take (cos, sin): use revolute
        path.write_text(path.read_text().replace('"continuous"', '"revolute"'))
        model = pin.buildModelFromUrdf(str(path))
    assert robot.n == model.nv == len(kinds)
    worst = compare(robot, model, rng)
    assert max(worst.values()) < TOLERANCE, worst


def test_friction_and_its_regressor_columns(example):
    _, path, locked = example
    robot = read_urdf(path, locked=locked)
    rng = np.random.default_rng(2)
    n = robot.n
    friction = rng.uniform(0.1, 2.0, (n, 2))
    body = robot.rigid_body(friction=friction)
    q, v, a = rng.normal(size=(3, 50, n))
    v[0, 0] = 0.0  # sign(0) = 0
    expected = friction[:, 0] * v + friction[:, 1] * np.sign(v)
    tau = body.inverse_dynamics(q, v, a)
    assert np.allclose(tau - body.inverse_dynamics(q, v, a, friction=False), expected,
                       rtol=1e-12, atol=1e-12)
    # tau = Y pi with the friction parameters last, (viscous, Coulomb) per joint
    pi = np.concatenate([robot.arrays()["link"].ravel(), friction.ravel()])
    assert np.allclose(np.einsum("kij,j->ki", body.regressor(q, v, a), pi), tau,
                       rtol=1e-11, atol=1e-11 * np.abs(tau).max())


def test_smooth_coulomb_friction_saturates():
    from harness.robot.examples import example_urdf
    path, _ = example_urdf("double_pendulum")
    body = read_urdf(path).rigid_body(friction=np.array([[0.0, 2.0], [0.0, 3.0]]),
                                      coulomb_velocity=0.1)
    v = np.array([[0.05, -0.5]])
    tau = body.inverse_dynamics(np.zeros((1, 2)), v, np.zeros((1, 2)), gravity=False)
    assert np.allclose(tau, [[2.0 * 0.5, -3.0]], rtol=1e-12)
    Y = body.regressor(np.zeros((1, 2)), v, np.zeros((1, 2)))[0]
    assert np.allclose(Y[:, 20:], [[0.05, 0.5, 0, 0], [0, 0, -0.5, -1.0]])


def test_bad_flat_arrays_are_rejected():
    from harness.robot.native import RigidBody
    good = dict(types=[0], axis=[0, 0, 1], xyz=[0, 0, 0], rpy=[0, 0, 0], link=[1] + [0] * 9,
                friction=[0, 0])
    for change, message in [({"axis": [0, 0, 0]}, "axis is zero"),
                            ({"types": [3]}, "neither revolute"),
                            ({"xyz": [np.nan, 0, 0]}, "not finite")]:
        with pytest.raises(ValueError, match=message):
            RigidBody(**{**good, **change})
    with pytest.raises(ValueError, match="between 1 and 12"):
        RigidBody(types=[0] * 13, axis=[0, 0, 1] * 13, xyz=[0] * 39, rpy=[0] * 39,
                  link=[1] * 130, friction=[0] * 26)

"""The two-link bench case (bench/cases/two_link.py): its hand-written model file states
Pinocchio's inverse dynamics of the same URDF, and its logs are what the paths read."""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from bench.cases import two_link
from harness.model import read_model


def test_model_file_is_pinocchio_inverse_dynamics(tmp_path):
    link, friction = two_link.truth()
    _, path = two_link.robot()
    model = pin.buildModelFromUrdf(str(path))
    for i in range(1, model.njoints):
        model.inertias[i] = pin.Inertia.FromDynamicParameters(link[i - 1])
    data = model.createData()
    rng = np.random.default_rng(3)
    q, qd, qdd = (rng.uniform(-a, a, (200, 2)) for a in (np.pi, 4.0, 20.0))
    tau = np.array([pin.rnea(model, data, *state) for state in zip(q, qd, qdd)])
    tau += friction[:, 0] * qd + friction[:, 1] * np.sign(qd)
    theta = two_link.base_values(link, friction)
    (tmp_path / "arm.toml").write_text(two_link.model_toml())
    arm = read_model(tmp_path / "arm.toml")
    assert arm.parameter_names == two_link.NAMES
    Y, r = arm.regressor(q, qd, qdd, tau)
    assert np.allclose(r, tau, rtol=0, atol=0)
    scale = np.sqrt(np.mean(tau ** 2, axis=0))
    assert np.all(np.abs(Y @ theta - tau).max(axis=0) <= 1e-9 * scale)
    # the bench's own numpy copy (its scorer) is the same regressor
    assert np.allclose(two_link.regressor(q, qd, qdd), Y, rtol=1e-12, atol=1e-12)
    # the nominal values are the maker's URDF's
    urdf = two_link.robot()[0].arrays()
    nominal = two_link.base_values(urdf["link"], urdf["friction"])
    assert np.allclose(arm.nominal, nominal, rtol=1e-5, atol=1e-12)


def test_logs_have_the_case_properties(tmp_path):
    run = two_link.simulate(2.0, seed=1)
    step = np.diff(run.t)
    assert 0.9 / 200 - 1e-12 <= step.min() and step.max() <= 1.1 / 200 + 1e-12
    assert np.all(run.u[:, 1] == 0) and np.any(run.u[:, 0] != 0)   # joint 2 passive
    assert np.allclose(run.q / 0.01, np.round(run.q / 0.01), atol=1e-9)  # encoder steps
    assert np.all(np.abs(run.q - run.q_true) <= 0.005 + 1e-12)
    two_link.write(run, tmp_path / "log.csv", tmp_path / "arm.toml")
    header = (tmp_path / "log.csv").read_text().splitlines()[0]
    assert header == "t,q1,q2,u1,u2"


def test_robot_base_parameters_are_the_model_files():
    from bench.reports.two_link_paths import positive_definite, robot_mapping
    robot, _ = two_link.robot()
    order, names = robot_mapping(robot)  # raises unless the regressors agree
    assert [names[k] for k in order][:3] == ["joint1.Ixx", "joint1.my", "joint1.mz"]
    assert positive_definite(two_link.base_values(*two_link.truth()))

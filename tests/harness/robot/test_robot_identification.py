"""Base parameters and regressor-form identification: offline least squares (Python)
and the online LSM/MFF in information form (fmu/src/core/regressor_identifier.c)."""
from __future__ import annotations

import numpy as np
import pytest

from harness.model.fit import fit as least_squares
from harness.robot.base_parameters import base_parameters, random_states
from harness.robot.examples import example_urdf
from harness.robot.layout import ParameterLayout
from harness.robot.urdf import read_urdf

# known counts: planar 2R (6 inertial), UR5 (36), Panda (43), plus 2 friction per joint
BASE_COUNTS = {"double_pendulum": (10, 8), "ur5": (48, 22), "panda": (57, 24)}


def setup(name: str, unknown: str = "all"):
    path, locked = example_urdf(name)
    robot = read_urdf(path, locked=locked)
    body = robot.rigid_body()
    types = robot.arrays()["types"]
    return robot, body, types, base_parameters(body, types, robot.joint_names, unknown)


@pytest.mark.parametrize("unknown", ["all", "payload"])
def test_base_parameters_reproduce_the_torques(example, unknown):
    name = example[0]
    robot, body, types, base = setup(name, unknown)
    assert base.count == BASE_COUNTS[name][unknown == "payload"]
    rng = np.random.default_rng(4)
    Y = body.regressor(*random_states(types, 100, rng))
    # any change of the unknown parameters moves the torques as its base projection does
    change = np.zeros(ParameterLayout(robot.n).size)
    change[base.base] = rng.normal(size=base.count)
    change[base.dependent] = rng.normal(size=len(base.dependent))
    exact = Y @ change
    assert np.abs(base.regressor(Y) @ base.project(change) - exact).max() < 1e-10 * np.abs(exact).max()
    # and the base regressor has full rank
    assert np.linalg.matrix_rank(base.regressor(Y).reshape(-1, base.count)) == base.count


def test_offline_least_squares_is_exact_without_noise():
    robot, body, types, base = setup("ur5")
    rng = np.random.default_rng(5)
    q, qd, qdd = random_states(types, 400, rng)
    truth = robot.parameters() * rng.uniform(0.7, 1.3, ParameterLayout(robot.n).size)
    tau = body.regressor(q, qd, qdd) @ truth
    fit = least_squares(base.regressor(body.regressor(q, qd, qdd)), tau,
                        base.project(robot.parameters()))
    expected = base.project(truth)
    assert np.abs(fit.theta - expected).max() < 1e-8 * np.abs(expected).max()


def noisy_pendulum(seed: int, samples: int = 4000, noise: float = 0.05):
    robot, body, types, base = setup("double_pendulum")
    rng = np.random.default_rng(seed)
    q, qd, qdd = random_states(types, samples, np.random.default_rng(0))
    truth = robot.parameters()
    tau = body.inverse_dynamics(q, qd, qdd) + rng.normal(0, noise, (samples, 2))
    return robot, body, base, (q, qd, qdd, tau), base.project(truth)


def test_standard_errors_match_the_spread_of_repeated_fits():
    estimates, errors = [], []
    for seed in range(40):
        robot, body, base, (q, qd, qdd, tau), truth = noisy_pendulum(seed)
        fit = least_squares(base.regressor(body.regressor(q, qd, qdd)), tau, truth, batch=20)
        estimates.append(fit.theta - truth)
        errors.append(fit.std_error)
    spread, predicted = np.std(estimates, axis=0), np.mean(errors, axis=0)
    assert np.all(np.abs(np.mean(estimates, axis=0)) < 3 * spread / np.sqrt(40) + 1e-12)
    assert np.all((predicted > 0.7 * spread) & (predicted < 1.4 * spread)), (predicted, spread)


def test_online_lsm_is_the_regularized_least_squares():
    robot, body, base, (q, qd, qdd, tau), truth = noisy_pendulum(1, samples=3000)
    h, rho, scale = 1e-3, 1e-4, np.array([1.0, 0.5])
    online = body.identify_online(base.base, q, qd, qdd, tau, h=h, rho=rho, torque_scale=scale)
    Yb = base.regressor(body.regressor(q, qd, qdd))
    z = tau - body.inverse_dynamics(q, qd, qdd)
    W = 1.0 / scale ** 2
    P = rho * np.eye(base.count) + h * np.einsum("kia,i,kib->ab", Yb, W, Yb)
    b = h * np.einsum("kia,i,ki->a", Yb, W, z)
    expected = np.linalg.solve(P, b)
    assert np.abs(online["delta"] - expected).max() < 1e-9 * np.abs(expected).max()
    assert online["gamma_trace"] == pytest.approx(np.trace(np.linalg.inv(P)), rel=1e-9)
    # the estimate is the truth within a few standard errors, which are of the offline size
    offline = least_squares(Yb, tau, truth, batch=20)
    errors = np.abs(online["delta"] + base.project(robot.parameters()) - truth)
    assert np.all(errors < 4 * online["std_error"])
    assert np.all(online["std_error"] < 3 * offline.std_error)
    assert np.all(online["std_error"] > offline.std_error / 3)
    assert online["excitation"] > 0


@pytest.mark.parametrize("order", ["ascending", "shuffled"])
def test_online_lsm_over_a_7_joint_regressor_reads_only_its_nonzero_blocks(order):
    """The step skips the regressor's structural zeros (joint i's row for the links
    before i, the other joints' friction): the same P and b as the dense formula,
    in any column order; the nominal torques Y pi (rb_regressor_torque) with friction."""
    robot, _, types, base = setup("panda")
    rng = np.random.default_rng(3)
    body = robot.rigid_body(friction=rng.uniform(0.5, 2.0, (robot.n, 2)))
    q, qd, qdd = random_states(types, 300, rng)
    tau = rng.normal(0, 5, q.shape)
    columns = base.base if order == "ascending" else rng.permutation(base.base)
    h, rho, scale = 1e-3, 1e-2, rng.uniform(0.5, 2.0, robot.n)
    online = body.identify_online(columns, q, qd, qdd, tau, h=h, rho=rho, torque_scale=scale)
    Yb = body.regressor(q, qd, qdd)[:, :, columns]
    z = tau - body.inverse_dynamics(q, qd, qdd)
    W = 1.0 / scale ** 2
    P = rho * np.eye(len(columns)) + h * np.einsum("kia,i,kib->ab", Yb, W, Yb)
    b = h * np.einsum("kia,i,ki->a", Yb, W, z)
    expected = np.linalg.solve(P, b)
    assert np.abs(online["delta"] - expected).max() < 1e-8 * np.abs(expected).max()
    assert online["gamma_trace"] == pytest.approx(np.trace(np.linalg.inv(P)), rel=1e-8)


def test_online_reset_forgets_everything_before():
    robot, body, base, (q, qd, qdd, tau), truth = noisy_pendulum(2, samples=2000)
    tau = tau.copy()
    tau[:1000] += 50.0  # garbage before the reset
    whole = body.identify_online(base.base, q, qd, qdd, tau, h=1e-3, reset_at=1000)
    after = body.identify_online(base.base, q[1000:], qd[1000:], qdd[1000:], tau[1000:], h=1e-3)
    assert np.allclose(whole["delta"], after["delta"], rtol=1e-12, atol=1e-12)


def test_online_mff_tracks_a_change_and_keeps_gamma_bounded():
    robot, body, types, base = setup("double_pendulum", "payload")
    rng = np.random.default_rng(6)
    q, qd, qdd = random_states(types, 20000, rng)
    link = robot.arrays()["link"].copy()
    heavier = link.copy()
    heavier[1, 0] += 0.3  # a payload of 0.3 kg at joint 2's origin, picked up half-way
    tau = np.concatenate([robot.rigid_body(link=link).inverse_dynamics(q[:10000], qd[:10000], qdd[:10000]),
                          robot.rigid_body(link=heavier).inverse_dynamics(q[10000:], qd[10000:], qdd[10000:])])
    rho = 1e-3
    mff = body.identify_online(base.base, q, qd, qdd, tau, h=1e-3, kind="mff", R=0.01, rho=rho)
    lsm = body.identify_online(base.base, q, qd, qdd, tau, h=1e-3, kind="lsm", rho=rho)
    mass = base.names.index("joint2.m")
    assert mff["delta"][mass] == pytest.approx(0.3, rel=1e-3)   # forgot the first half
    assert lsm["delta"][mass] == pytest.approx(0.15, rel=2e-2)  # the mean of both halves
    assert mff["gamma_trace"] <= base.count / rho
    # at rest only the gravity direction of the mass is excited: Gamma tends to I / rho
    # in all the others, bounded instead of winding up
    rest = np.zeros((5000, 2))
    still = body.identify_online(base.base, rest, rest, rest, body.inverse_dynamics(rest, rest, rest),
                                 h=1e-3, kind="mff", R=0.01, rho=rho)
    assert still["gamma_trace"] == pytest.approx((base.count - 1) / rho, rel=1e-4)
    assert np.abs(still["delta"]).max() < 1e-9


def test_bad_identifier_settings_are_rejected():
    robot, body, base, (q, qd, qdd, tau), _ = noisy_pendulum(3, samples=10)
    for kwargs in [dict(columns=[0, 0]), dict(columns=[99]), dict(h=0.0), dict(rho=-1.0),
                   dict(kind="mff", R=1.5)]:
        settings = {"columns": base.base, "h": 1e-3, **kwargs}
        with pytest.raises(ValueError, match="online identifier rejected"):
            body.identify_online(settings.pop("columns"), q, qd, qdd, tau, **settings)

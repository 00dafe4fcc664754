"""The model-based velocity observer of fmu/src/core/robot_observer.c (through ctypes) and
the RobotObserver FMU's parameters written from a URDF (harness.robot.fmu)."""
from __future__ import annotations

import numpy as np
import pytest
from robot_helpers import FRICTION, multisine_log, payload_link

from harness.cli import main
from harness.robot.examples import example_urdf
from harness.robot.fmu import fmu_parameters, read_ssv, start_values, write_ssv
from harness.robot.urdf import read_urdf

H = 1e-3


@pytest.fixture(scope="module")
def arm():
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    truth = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=FRICTION)
    return path, robot, truth, multisine_log(truth, 3.0, H)


def _velocity_error(body, log, f_plus):
    t, q, qd, _, tau = log
    velocity = body.observe(q, tau, H, f_plus)["velocity"]
    return np.abs(velocity - qd)[int(0.2 / H):]


def test_the_model_based_observer_is_accurate_with_the_exact_model(arm):
    """Noise-free, 1 kHz, the two-link arm with its payload and friction in the model:
    RMS 1.8e-4 and 2.8e-4 rad/s, largest 0.0042 and 0.0062 rad/s (at the Coulomb
    reversals) for joint velocities up to 3.8 rad/s."""
    _, _, truth, log = arm
    error = _velocity_error(truth, log, 10.0)
    assert np.all(np.sqrt(np.mean(error ** 2, axis=0)) < 5e-4)
    assert np.all(error.max(axis=0) < 0.01)


def test_a_model_without_the_payload_is_caught(arm):
    """The same gains with the URDF's model (no payload, no friction): the bound of the
    test above does not hold, so it measures the model."""
    _, robot, _, log = arm
    error = _velocity_error(robot.rigid_body(), log, 10.0)
    assert not np.all(np.sqrt(np.mean(error ** 2, axis=0)) < 5e-3)


def _identify_friction(model, q, tau, **rule):
    return model.observe(q, tau, H, 1000.0, identify={"columns": np.arange(20, 24),
                                                      "kind": "lsm", "rho": 1e-6, "start": 200,
                                                      **rule})


def test_online_identification_finds_the_friction(arm):
    """The URDF's inertials plus the payload, friction unknown (nominal 0): the identifier,
    regressing through the fixed-lag window (the default), finds the viscous and Coulomb
    coefficients within 1e-4 (measured: -0.0058, 0.0037, -0.0007, 0.0006 %), and its
    standard errors cover what is left (the error 0.26 to 1.06 of them, measured) while
    saying that it is small (2e-5 to 6e-5 of each coefficient)."""
    _, robot, truth, (t, q, _, _, tau) = arm
    model = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=np.zeros((2, 2)))
    result = _identify_friction(model, q, tau)
    assert result["delta"] == pytest.approx(FRICTION.ravel(), rel=1e-4)
    error = np.abs(result["delta"] - FRICTION.ravel())
    assert np.all(error < 3 * result["std_error"])
    assert np.all(result["std_error"] < 2e-4 * FRICTION.ravel())
    assert result["excitation"] > 0


def test_online_identification_from_the_observer_finds_the_friction(arm):
    """The same through the observer's estimates (regression "observer"): within 0.1 %
    (measured: 0.006, 0.002, 0.024, 0.007 %; 5.3, 3.2, 5.6, 3.8 % when the regression
    filtered q, q', q'', u (5 ms) instead of the regressor).  On this light arm (M^-1 up
    to 1400) the missing friction is an acceleration error of up to 600 rad/s^2, hence
    f+ = 1000.

    Noise-free, what is left is the observer's error at the reversals, a bias: the standard
    errors (from the residuals' scores) are of its size, 1.1 to 6.9 times smaller
    (measured), not a bound on it."""
    _, robot, truth, (t, q, _, _, tau) = arm
    model = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=np.zeros((2, 2)))
    result = _identify_friction(model, q, tau, regression="observer")
    assert result["delta"] == pytest.approx(FRICTION.ravel(), rel=1e-3)
    error = np.abs(result["delta"] - FRICTION.ravel())
    assert np.all(result["std_error"] > error / 10) and np.all(result["std_error"] < 3 * error)


def test_the_window_keeps_the_friction_on_noisy_positions(arm):
    """Positions with 1e-4 rad of white noise: through the window the friction comes out
    within 1 % and within 3 of its standard errors (measured, seed 0: 0.52, -0.31, -0.10,
    0.11 %, 0.24 to 1.38 standard errors; seeds 0-5 within 0.6 %), where the observer's
    causal estimates are off by 2 to 59 % (seeds 0-5: up to 391 %)."""
    _, robot, truth, (t, q, _, _, tau) = arm
    model = robot.rigid_body(link=payload_link(robot.arrays()["link"]), friction=np.zeros((2, 2)))
    noisy = q + 1e-4 * np.random.default_rng(0).standard_normal(q.shape)
    window = _identify_friction(model, noisy, tau)
    assert window["delta"] == pytest.approx(FRICTION.ravel(), rel=1e-2)
    assert np.all(np.abs(window["delta"] - FRICTION.ravel()) < 3 * window["std_error"])
    observer = _identify_friction(model, noisy, tau, regression="observer")
    assert np.max(np.abs(observer["delta"] / FRICTION.ravel() - 1)) > 0.2


@pytest.mark.parametrize("regression", ["window", "observer"])
def test_slow_joint_equations_are_left_out_online(arm, regression):
    """The truth's Coulomb friction is f_c sat(q'/0.05), the model's f_c sign(q'): with the
    default rule (min_speed 0.05 rad/s, reversal_margin 0.02 s) the friction comes out
    within 0.1 % (measured, observer: 0.006, 0.002, 0.024, 0.007 %), with every equation
    used 0.2-0.5 % off (regression filter tau 10 ms, the default)."""
    _, robot, _, _ = arm
    link = payload_link(robot.arrays()["link"])
    truth = robot.rigid_body(link=link, friction=FRICTION, coulomb_velocity=0.05)
    _, q, _, _, tau = multisine_log(truth, 3.0, H)
    model = robot.rigid_body(link=link, friction=np.zeros((2, 2)))
    assert _identify_friction(model, q, tau, regression=regression)["delta"] == pytest.approx(
        FRICTION.ravel(), rel=1e-3)
    every = _identify_friction(model, q, tau, min_speed=0.0, reversal_margin=0.0,
                               regression=regression)
    assert np.max(np.abs(every["delta"] / FRICTION.ravel() - 1)) > 3e-3
    taken = every["weight"][~np.isnan(every["weight"])]
    assert taken.size > 0.8 * every["weight"].size and np.all(taken == 1.0)


def _rule(velocity: np.ndarray, h: float, min_speed: float, margin: float) -> np.ndarray:
    """The rule of robot_observer.h on the observer's velocity estimates: joint i's
    equation of sample k weighs 0 if a sample j in k - margin/h .. k was slow (|v| <
    min_speed) or reversed (its sign differs from sample j-1's); the observer starts as
    after such a sample (j = -1)."""
    bad = np.abs(velocity) < min_speed
    bad[1:] |= np.signbit(velocity[1:]) != np.signbit(velocity[:-1])
    last_bad = np.where(bad, np.arange(len(velocity))[:, None], -1)
    last_bad = np.maximum.accumulate(last_bad, axis=0)
    return (np.arange(len(velocity))[:, None] - last_bad > round(margin / h)).astype(float)


@pytest.mark.parametrize("min_speed, margin", [(0.05, 0.02), (0.3, 0.05), (0.0, 0.01)])
def test_the_online_weights_follow_the_rule(arm, min_speed, margin):
    _, _, truth, (t, q, _, _, tau) = arm
    result = _identify_friction(truth, q, tau, min_speed=min_speed, reversal_margin=margin,
                                regression="observer")
    expected = _rule(result["velocity"], H, min_speed, margin)
    taken = ~np.isnan(result["weight"])  # the rows from the identifier's start on
    assert np.array_equal(taken[:-1, 0], np.arange(len(q) - 1) >= 199)
    assert taken[-2].all() and not taken[-1].any()
    assert np.array_equal(result["weight"][taken], expected[taken])
    assert 0.5 < expected.mean() < 1.0  # the rule leaves some equations out, not all


def test_the_window_leaves_out_both_sides_of_a_reversal(arm):
    """Through the window, a joint's equation is left out on both sides of each reversal
    of its velocity (FL_REVERSAL_PERIODS of the cut-off, at least 8 samples here), and
    after it for reversal_margin more; most equations stay."""
    _, _, truth, (t, q, qd, _, tau) = arm
    weight = _identify_friction(truth, q, tau)["weight"]
    for i in range(2):
        flips = np.flatnonzero(np.signbit(qd[1:, i]) != np.signbit(qd[:-1, i])) + 1
        flips = flips[(flips > 300) & (flips < len(q) - 300)]
        assert flips.size > 2
        for k in flips:
            near = weight[k - 8:k + 8 + 20, i]
            assert np.all(near[~np.isnan(near)] == 0.0)
        assert 0.5 < np.nanmean(weight[:, i]) < 1.0


@pytest.mark.parametrize("rule", [{"min_speed": -0.1}, {"reversal_margin": float("nan")}])
def test_a_bad_rule_is_refused(arm, rule):
    _, _, truth, (t, q, _, _, tau) = arm
    with pytest.raises(ValueError, match="min_speed .* and reversal_margin .* must be finite"):
        _identify_friction(truth, q[:100], tau[:100], **rule)


def test_parameters_from_the_urdf(arm):
    path, robot, _, _ = arm
    parameters = fmu_parameters(robot, unknown="payload")
    assert parameters["n"] == 2 and parameters["base_count"] == 8
    assert parameters["link"].shape == (2, 10) and parameters["base_columns"].shape == (8,)
    values = start_values(parameters)
    assert values["link[2,1]"] == pytest.approx(robot.arrays()["link"][1, 0])
    assert values["joint_type[1]"] == 0 and isinstance(values["base_columns[8]"], int)
    assert "q[1]" not in values


def test_the_parameter_set_round_trips(arm, tmp_path):
    _, robot, _, _ = arm
    parameters = fmu_parameters(robot)
    written = write_ssv(parameters, tmp_path / "robot.ssv")
    assert read_ssv(written) == start_values(parameters)


def test_the_command_line_writes_the_parameter_set(arm, tmp_path, capsys):
    path, robot, _, _ = arm
    out = tmp_path / "robot.ssv"
    assert main(["robot-fmu-parameters", str(path), "--out", str(out), "--unknown", "payload",
                 "--f-plus", "20"]) == 0
    values = read_ssv(out)
    assert values["n"] == 2 and values["base_count"] == 8 and values["f_plus[2]"] == 20.0
    assert str(out) in capsys.readouterr().out


def test_the_command_line_writes_the_rule_of_left_out_equations(arm, tmp_path):
    path, _, _, _ = arm
    out = tmp_path / "robot.ssv"
    assert main(["robot-fmu-parameters", str(path), "--out", str(out)]) == 0
    assert read_ssv(out)["min_speed"] == 0.05 and read_ssv(out)["reversal_margin"] == 0.02
    assert main(["robot-fmu-parameters", str(path), "--out", str(out), "--min-speed", "0.1",
                 "--reversal-margin", "0"]) == 0
    values = read_ssv(out)
    assert values["min_speed"] == 0.1 and values["reversal_margin"] == 0.0


def test_joint_terms_beside_the_urdf_are_said_to_be_left_out(arm, tmp_path, capsys):
    """An identify run's joint_terms.csv next to the URDF: the FMU's parameters are the
    URDF's model alone, and the command says so (exit 1: written, with a warning)."""
    import shutil
    path, robot, _, _ = arm
    urdf = tmp_path / "identified.urdf"
    shutil.copy(path, urdf)
    rows = "".join(f"{name},offset,0.5,,N.m\n" for name in robot.joint_names)
    (tmp_path / "joint_terms.csv").write_text("joint,term,value,std_error,unit\n" + rows)
    # written, with a warning: exit 1 (docs/cli.md)
    assert main(["robot-fmu-parameters", str(urdf), "--out", str(tmp_path / "r.ssv")]) == 1
    assert (tmp_path / "r.ssv").is_file()
    assert "holds joint terms (offset) that the RobotObserver FMU does not model" in \
        capsys.readouterr().err
    (tmp_path / "joint_terms.csv").write_text("joint,term,value,std_error,unit\n")
    assert main(["robot-fmu-parameters", str(urdf), "--out", str(tmp_path / "r.ssv")]) == 0
    assert "joint terms" not in capsys.readouterr().err


def test_the_command_line_names_a_bad_urdf(tmp_path, capsys):
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot")
    assert main(["robot-fmu-parameters", str(bad), "--out", str(tmp_path / "x.ssv")]) == 2
    assert "does not parse" in capsys.readouterr().err

"""The RobotObserver FMU (FMI 2 and FMI 3): the same numbers as the offline ctypes path
(harness.robot.native) on the same log, its default experiment, and clear errors for
bad parameters."""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import simulate_fmu

from harness.robot.examples import example_urdf
from harness.robot.fmu import INTEGERS, fmu_parameters, run_fmu, start_values
from harness.robot.joint_log import JointLog
from harness.robot.layout import ParameterLayout
from harness.robot.urdf import read_urdf
from tests.conftest import fmu_path
from tests.harness.robot.robot_helpers import FRICTION, multisine_log, payload_link

from .fmi_helpers import ERROR, OK, RawFMU, RawFMU3, instances

H = 1e-3
F_PLUS = 1000.0  # the URDF's arm without friction: model errors up to 600 rad/s^2


@pytest.fixture(scope="module")
def case():
    """The two-link arm with its payload, friction unknown (nominal 0), a 1 s log."""
    path, _ = example_urdf("double_pendulum")
    robot = read_urdf(path)
    link = payload_link(robot.arrays()["link"])
    truth = robot.rigid_body(link=link, friction=FRICTION)
    t, q, qd, _, tau = multisine_log(truth, 1.0, H)
    layout = ParameterLayout(robot.n)
    pi = layout.join(link, np.zeros(layout.friction_size * robot.n))
    parameters = fmu_parameters(robot, unknown="payload", f_plus=F_PLUS, pi=pi, t_id=0.2,
                                torque_scale=np.sqrt(np.mean(tau ** 2, axis=0)))
    offline = robot.rigid_body(link=link, friction=np.zeros((2, 2))).observe(
        q, tau, H, F_PLUS, identify={"columns": parameters["base_columns"], "kind": "lsm",
                                     "rho": parameters["rho"], "start": 200,
                                     "torque_scale": parameters["torque_scale"],
                                     "statistics_interval": 0.0})  # run_fmu's
    return JointLog(t, q, tau), qd, parameters, offline


def test_the_fmu_runs_the_offline_path_exactly(case):
    log, qd, parameters, offline = case
    result = run_fmu(fmu_path("RobotObserver"), parameters, log)
    # after doStep(t_k, h): the prediction for t_k + h that the offline path records at k
    np.testing.assert_allclose(result["velocity"], offline["prediction"], rtol=0, atol=1e-12)
    np.testing.assert_allclose(result["velocity_sample"], offline["velocity"], rtol=0,
                               atol=1e-12)
    # what it publishes after the last sample: the same schedule of the solves with
    # standard errors (each spread over the samples after its snapshot)
    published = offline["published"]
    np.testing.assert_allclose(result["base_estimate"],
                               parameters["base_nominal"] + published["delta"], atol=1e-12)
    np.testing.assert_allclose(result["base_std"], published["std_error"], rtol=1e-12)
    assert result["gamma_trace"] == pytest.approx(published["gamma_trace"], rel=1e-12)
    assert result["excitation"] == pytest.approx(published["excitation"], rel=1e-12)
    np.testing.assert_allclose(result["base_excitation"], published["column_excitation"],
                               rtol=1e-12)
    assert np.all((published["column_excitation"] > 0) & (published["column_excitation"] <= 1))
    # which is the full solve at a snapshot a few samples before the end (here the
    # statistics change by up to 2.4 % a sample)
    body = read_urdf(example_urdf("double_pendulum")[0]).rigid_body(
        link=parameters["link"], friction=np.zeros((2, 2)))
    identify = {"columns": parameters["base_columns"], "kind": "lsm", "rho": parameters["rho"],
                "start": 200, "torque_scale": parameters["torque_scale"]}
    lags = [lag for lag in range(1, 6)
            if np.allclose(body.observe(log.q[:-lag], log.u[:-lag], H, F_PLUS,
                                        identify=identify)["std_error"],
                           published["std_error"], rtol=1e-12, atol=0)]
    assert len(lags) == 1, lags
    # and it observes: RMS 0.009 and 0.013 rad/s with the friction unknown to the model
    error = result["velocity"][200:-1] - qd[201:]
    assert np.all(np.sqrt(np.mean(error ** 2, axis=0)) < 0.02)


def test_the_estimates_do_not_depend_on_the_communication_step(case):
    """The log's samples held over 10 internal steps, fed at a communication step of h and
    of 10 h: the same velocities at the common points and the same estimates, standard
    errors and statistics at the end (the statistics follow the internal steps)."""
    log, _, parameters, _ = case
    held = (np.arange(len(log.t)) // 10) * 10
    steady = JointLog(log.t, log.q[held], log.u[held])
    fine = run_fmu(fmu_path("RobotObserver"), parameters, steady)
    coarse = run_fmu(fmu_path("RobotObserver"), parameters, steady, samples_per_step=10)
    np.testing.assert_array_equal(fine["velocity"][9::10], coarse["velocity"])
    for name in ("base_estimate", "base_std", "base_excitation", "gamma_trace", "excitation"):
        np.testing.assert_array_equal(fine[name], coarse[name], err_msg=name)


def test_the_rule_of_left_out_equations_reaches_the_fmu(case):
    """min_speed and reversal_margin other than the defaults: still the offline numbers,
    and not the defaults' (the parameters reach the identifier)."""
    log, _, parameters, offline = case
    rule = {"min_speed": 0.3, "reversal_margin": 0.05}
    changed = {**parameters, **rule}
    identify = {"columns": parameters["base_columns"], "kind": "lsm", "rho": parameters["rho"],
                "start": 200, "torque_scale": parameters["torque_scale"],
                "statistics_interval": 0.0, **rule}
    link, n = parameters["link"], parameters["n"]
    path, _ = example_urdf("double_pendulum")
    model = read_urdf(path).rigid_body(link=link, friction=np.zeros((n, 2)))
    expected = model.observe(log.q, log.u, H, F_PLUS, identify=identify)
    result = run_fmu(fmu_path("RobotObserver"), changed, log)
    np.testing.assert_allclose(result["base_estimate"],
                               parameters["base_nominal"] + expected["published"]["delta"],
                               atol=1e-12)
    assert np.max(np.abs(expected["published"]["delta"] - offline["published"]["delta"])) > 1e-6


def _fmi3_run(fmu: RawFMU3, parameters: dict, log: JointLog, steps: int) -> list[float]:
    """Sets the parameters as whole arrays (rows beyond n keep their start values)."""
    assert fmu.call("EnterInitializationMode", False, 0.0, 0.0, False, 0.0) == OK
    for name, value in {**parameters, "statistics_interval": 0.0}.items():
        kind = "Int32" if name in INTEGERS else "Float64"
        flat = list(np.ravel(value))
        current = fmu.get(kind, [name])
        assert fmu.set(kind, {name: flat + current[len(flat):]}) == OK, fmu.messages()
    n = parameters["n"]
    pad = [0.0] * (7 - n)
    inputs = lambda k: {"q": [*log.q[k], *pad], "u": [*log.u[k], *pad]}  # noqa: E731
    assert fmu.set("Float64", inputs(0)) == OK
    assert fmu.call("ExitInitializationMode") == OK, fmu.messages()
    velocity = []
    for k in range(steps):
        assert fmu.set("Float64", inputs(k)) == OK
        assert fmu.do_step(k * H, H)[0] == OK, fmu.messages()
        velocity.append(fmu.get("Float64", ["qd_hat"])[:n])
    return velocity + fmu.get("Float64", ["base_estimate"])[:parameters["base_count"]]


@pytest.fixture
def make3():
    yield from instances(RawFMU3, fmu_path("RobotObserver", 3))


def test_fmi3_gives_the_fmi2_numbers(case, make3):
    log, _, parameters, offline = case
    out = _fmi3_run(make3(), parameters, log, 400)
    np.testing.assert_allclose(np.array(out[:400]), offline["prediction"][:400], atol=1e-12)
    fmi2 = run_fmu(fmu_path("RobotObserver"), parameters,
                   JointLog(log.t[:400], log.q[:400], log.u[:400]))
    np.testing.assert_allclose(out[400:], fmi2["base_estimate"], atol=1e-12)


@pytest.mark.parametrize("version", [2, 3])
def test_the_default_experiment_runs(version):
    result = simulate_fmu(str(fmu_path("RobotObserver", version)), stop_time=1.0,
                          output_interval=0.01)
    names = [n for n in result.dtype.names if n != "time"]
    assert len(result) == 101 and names
    for name in names:
        assert np.all(np.isfinite(np.asarray(result[name], dtype=float))), name


@pytest.fixture
def make():
    yield from instances(RawFMU, fmu_path("RobotObserver"))


def _bad(make, reals=None, integers=None) -> str:
    """Initializes with the changed parameters; expects an error; returns the log."""
    fmu = make()
    assert fmu.initialize(reals=reals, integers=integers) == ERROR
    return fmu.messages()


def test_a_negative_min_speed_is_refused(make):
    fmu = make()
    assert fmu.set_real({"min_speed": -0.1}) == ERROR
    assert "min_speed" in fmu.messages()


def test_more_than_seven_joints_is_refused(make):
    fmu = make()
    assert fmu.set_integer({"n": 8}) == ERROR
    assert "n = 8 is out of range [1, 7]" in fmu.messages()


@pytest.mark.parametrize("reals, integers, message", [
    ({"link[2,5]": -0.01}, None, "link[2]: the inertia about the centre of mass"),
    ({"link[1,1]": -1.0}, None, "link[1]: negative mass -1"),
    ({"axis[2,1]": 0.0}, None, "axis[2] = (0, 0, 0) is zero"),
    ({f"link[{i},{j}]": 0.0 for i in (1, 2) for j in range(1, 11)}, None,
     "M(q) of the robot's parameters is not positive definite"),
    (None, {"base_columns[1]": 30}, "base_columns[1] = 30: a 2-joint regressor has columns "
     "0..23"),
    (None, {"base_columns[2]": 20}, "base_columns[1] and base_columns[2] are both 20"),
    (None, {"base_count": 30}, "base_count = 30 exceeds the 24 columns"),
    ({"reversal_margin": float("inf")}, None, "reversal_margin = inf is not finite"),
    ({"f_plus[1]": 0.0}, None, "joint 1: no gains from f_plus[1] = 0"),
])
def test_bad_parameters_are_clear_errors(make, reals, integers, message):
    assert message in _bad(make, reals, integers)


def test_a_diverging_observer_is_an_error_not_a_crash(make):
    fmu = make()
    assert fmu.initialize() == OK
    assert fmu.set_real({"u[1]": 1e306, "u[2]": -1e306}) == OK
    statuses = [fmu.do_step(k * H, H) for k in range(10)]
    assert ERROR in statuses, "a torque beyond floating point never diverged"
    assert "observer diverged at t = " in fmu.messages()
    assert "raise f_plus[" in fmu.messages()


def test_the_parameter_names_exist_in_both_versions(case):
    _, _, parameters, _ = case
    from fmpy import read_model_description
    for version in (2, 3):
        names = {v.name for v in read_model_description(
            str(fmu_path("RobotObserver", version))).modelVariables}
        wanted = set(start_values(parameters)) if version == 2 else set(parameters)
        assert wanted <= names, wanted - names

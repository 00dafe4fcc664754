"""The bench FMUs: the paper's pendulum and the twisting controller."""
from __future__ import annotations

import math

import numpy as np
import pytest

from .fmi_helpers import OK, RawFMU

J = 1.1 * 0.81


def run_pendulum(fmu_path, reals, integers=None, seconds=1.0, H=1e-3, u=0.0,
                 outputs=("theta", "omega", "acceleration", "v", "d")):
    fmu = RawFMU(fmu_path)
    assert fmu.initialize(reals=reals, integers=integers) == OK, fmu.messages()
    rows = [[0.0] + fmu.get_real(list(outputs))]
    t = 0.0
    for k in range(int(round(seconds / H))):
        assert fmu.set_real({"u": u}) == OK
        assert fmu.do_step(t, H) == OK, fmu.messages()
        t = (k + 1) * H
        rows.append([t] + fmu.get_real(list(outputs)))
    fmu.free()
    return np.array(rows)


def test_true_coefficients(pendulum_fmu):
    fmu = RawFMU(pendulum_fmu)
    assert fmu.initialize() == OK
    a = fmu.get_real(["a_gravity", "a_viscous", "a_coulomb", "b_input"])
    fmu.free()
    assert a == pytest.approx([1.1 * 9.815 * 0.9 / (2 * J), 0.18 / J, 0.45 / J, 1 / J], rel=1e-14)
    assert a[0] == pytest.approx(5.4528, abs=1e-4)  # the paper's a1, a2, a3
    assert a[1] == pytest.approx(0.2020, abs=1e-4) and a[2] == pytest.approx(0.5051, abs=1e-4)


def test_free_oscillation_period_and_energy(pendulum_fmu):
    """Small swing without friction: period 2 pi / sqrt(a_gravity); RK4 conserves energy."""
    r = run_pendulum(pendulum_fmu, {"Vs": 0.0, "Ps": 0.0, "theta_start": 0.01,
                                    "omega_start": 0.0}, seconds=10.0, H=1e-3)
    t, theta, omega = r[:, 0], r[:, 1], r[:, 2]
    a = 1.1 * 9.815 * 0.9 / (2 * J)
    ups = np.nonzero((theta[:-1] < 0) & (theta[1:] >= 0))[0]
    crossings = t[ups] - theta[ups] * (t[ups + 1] - t[ups]) / (theta[ups + 1] - theta[ups])
    period = np.mean(np.diff(crossings))
    # small-angle period, corrected for the 0.01 rad amplitude (1 + theta0^2/16)
    assert period == pytest.approx(2 * math.pi / math.sqrt(a) * (1 + 0.01**2 / 16), rel=1e-5)
    energy = 0.5 * omega**2 + a * (1 - np.cos(theta))
    drift = np.max(np.abs(energy - energy[0])) / energy[0]
    assert drift < 1e-9  # measured 1.4e-12 with RK4 at h = 1e-5 s (explicit Euler would drift)


def test_disturbances_and_time_varying_damping(pendulum_fmu):
    sine = run_pendulum(pendulum_fmu, {}, {"disturbance": 1}, seconds=2.0)
    np.testing.assert_allclose(sine[:, 4], 0.5 * np.sin(2 * sine[:, 0]), atol=1e-14)
    square = run_pendulum(pendulum_fmu, {}, {"disturbance": 2}, seconds=7.0, H=1e-2)
    t = square[:, 0]
    away = np.abs(np.sin(t)) > 1e-9
    np.testing.assert_array_equal(square[away, 4], 0.5 * np.sign(np.sin(t[away])))
    damped = run_pendulum(pendulum_fmu, {"Vs": 0.0}, {"damping": 1}, seconds=2.0)
    np.testing.assert_allclose(damped[:, 5], 0.5 + 0.6 * np.sin(damped[:, 0] / 7), atol=1e-14)


def test_acceleration_output_matches_the_model(pendulum_fmu):
    r = run_pendulum(pendulum_fmu, {}, {"disturbance": 1, "damping": 1}, seconds=1.0, u=2.0)
    t, theta, omega, acc, v, d = r.T
    a1, a2, a3 = 1.1 * 9.815 * 0.9 / (2 * J), 0.18 / J, 0.45 / J
    expected = 2.0 / J - a1 * np.sin(theta) - a2 * omega - a3 * np.sign(omega) - d * omega + v
    np.testing.assert_allclose(acc[1:], expected[1:], rtol=1e-12, atol=1e-12)


def test_plant_step_not_a_multiple_of_h(pendulum_fmu):
    a = run_pendulum(pendulum_fmu, {}, seconds=0.01, H=2.5e-6)  # quarter of h = 1e-5
    b = run_pendulum(pendulum_fmu, {}, seconds=0.01, H=1e-5)
    assert a[-1, 1] == b[-1, 1] and a[-1, 2] == b[-1, 2]


def test_controller_outputs_follow_the_formulas(controller_fmu):
    fmu = RawFMU(controller_fmu)
    assert fmu.setup() == OK and fmu.call("fmi2EnterInitializationMode") == OK
    assert fmu.set_real({"theta": 0.5, "omega": -1.0}) == OK
    assert fmu.call("fmi2ExitInitializationMode") == OK
    for k in range(50):
        t = k * 1e-2
        theta, omega = 0.3 * math.sin(5 * t), -0.2
        assert fmu.set_real({"theta": theta, "omega": omega}) == OK
        assert fmu.do_step(t, 1e-2) == OK
        t1 = t + 1e-2
        theta_d = 0.3 * math.sin(3 * t1 + math.pi / 4) + 0.3 * math.sin(t1 / 2 + math.pi)
        omega_d = 0.9 * math.cos(3 * t1 + math.pi / 4) + 0.15 * math.cos(t1 / 2 + math.pi)
        u = -30 * np.sign(theta - theta_d) - 15 * np.sign(omega - omega_d)
        assert fmu.get_real(["u", "theta_d", "omega_d"]) == pytest.approx([u, theta_d, omega_d],
                                                                          abs=1e-14)
    fmu.free()


def test_closed_loop_tracks_the_reference(pendulum_fmu, controller_fmu):
    from harness.fmus import FMUInstance
    from harness.master import CoSimulation, Link, initialize, run

    fmus = {"plant": FMUInstance(pendulum_fmu, "plant"),
            "controller": FMUInstance(controller_fmu, "controller")}
    sim = CoSimulation(fmus, [Link("controller.u", "plant.u"),
                              Link("plant.theta", "controller.theta"),
                              Link("plant.omega", "controller.omega")])
    try:
        initialize(sim, 0.0, {}, {})
        r = run(sim, 0.0, 5.0, 1e-4, ["plant.theta", "controller.theta_d"], decimation=10)
    finally:
        sim.close()
    late = r.time > 2.0
    error = np.max(np.abs(r["plant.theta"][late] - r["controller.theta_d"][late]))
    assert error < 1e-4  # measured 1.6e-6: the twisting controller holds the reference

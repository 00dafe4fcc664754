"""The bench FMUs through fmpy's FMU2Slave: the paper's pendulum (section 6)
and the twisting controller (44)/(46), alone and in a closed loop."""
from __future__ import annotations

import math
import shutil

import numpy as np
import pytest
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)

J = 1.1 * 0.9**2                    # M L^2 = 0.891 kg.m2
A_GRAVITY = 1.1 * 9.815 * 0.9 / (2 * J)
A_VISCOUS, A_COULOMB = 0.18 / J, 0.45 / J


class Bench:
    """One FMU2Slave instance addressed by variable name; records log messages."""

    def __init__(self, fmu, unzipped, name="instance", reals=None, integers=None,
                 inputs=None, start_time=0.0):
        md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.messages: list[str] = []
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                               modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        self.slave.instantiate(callbacks=self.callbacks, loggingOn=True)
        self.slave.setupExperiment(startTime=start_time)
        self.slave.enterInitializationMode()
        if integers:
            self.slave.setInteger([self.vr[k] for k in integers], list(integers.values()))
        self.set({**(reals or {}), **(inputs or {})})
        self.slave.exitInitializationMode()
        self.t = start_time
        self.failed = False

    def _log(self, env, instance, status, category, message):
        self.messages.append(message.decode() if message else "")

    def set(self, values: dict):
        if values:
            self.slave.setReal([self.vr[k] for k in values], [float(v) for v in values.values()])

    def get(self, *names):
        return self.slave.getReal([self.vr[k] for k in names])

    def step(self, H):
        try:
            self.slave.doStep(self.t, H)
        except FMICallException:
            self.failed = True  # the instance is in the error state: no fmi2Terminate
            raise
        self.t += H

    def close(self):
        if not self.failed:
            self.slave.terminate()
        self.slave.freeInstance()


@pytest.fixture(scope="module")
def unzipped(pendulum_fmu, controller_fmu):
    dirs = {fmu: extract(str(fmu)) for fmu in (pendulum_fmu, controller_fmu)}
    yield dirs
    for d in dirs.values():
        shutil.rmtree(d, ignore_errors=True)


@pytest.fixture
def pendulum(pendulum_fmu, unzipped):
    made = []

    def make(reals=None, integers=None, **kw):
        b = Bench(pendulum_fmu, unzipped[pendulum_fmu], "plant", reals, integers, **kw)
        made.append(b)
        return b
    yield make
    for b in made:
        b.close()


@pytest.fixture
def controller(controller_fmu, unzipped):
    made = []

    def make(reals=None, **kw):
        b = Bench(controller_fmu, unzipped[controller_fmu], "controller", reals, **kw)
        made.append(b)
        return b
    yield make
    for b in made:
        b.close()


OUTPUTS = ("theta", "omega", "acceleration", "v", "d")


def record(plant, seconds, H, u=0.0):
    """Rows [t, theta, omega, acceleration, v, d] from t = 0 to seconds."""
    rows = [[plant.t, *plant.get(*OUTPUTS)]]
    for _ in range(int(round(seconds / H))):
        plant.set({"u": u})
        plant.step(H)
        rows.append([plant.t, *plant.get(*OUTPUTS)])
    return np.array(rows)


# ---- pendulum ---------------------------------------------------------------

def test_calculated_parameters_are_the_true_coefficients(pendulum):
    a = pendulum().get("a_gravity", "a_viscous", "a_coulomb", "b_input")
    assert a == pytest.approx([A_GRAVITY, A_VISCOUS, A_COULOMB, 1 / 0.891], rel=1e-14)
    assert a == pytest.approx([5.452777777, 0.202020202, 0.505050505, 1.122334455], abs=1e-8)


def test_at_rest_it_stays_at_rest(pendulum):
    """theta_start = omega_start = 0, no u, v, d and sign(0) = 0: the pendulum stays down.
    (The start values are 0.1 rad and 0.5 rad/s, so that the default experiment moves.)"""
    r = record(pendulum({"theta_start": 0.0, "omega_start": 0.0}), 0.1, 1e-2)
    assert np.all(r[:, 1:] == 0.0)


def test_free_oscillation_period_and_energy(pendulum):
    """Small swing without friction: period 2 pi / sqrt(a_gravity); RK4 keeps the energy."""
    theta0 = 0.01
    r = record(pendulum({"Vs": 0.0, "Ps": 0.0, "theta_start": theta0, "omega_start": 0.0}),
               10.0, 1e-3)
    t, theta, omega = r[:, 0], r[:, 1], r[:, 2]
    ups = np.nonzero((theta[:-1] < 0) & (theta[1:] >= 0))[0]
    # upward zero crossings by cubic (Hermite) interpolation, with omega as slope
    crossings = []
    for i in ups:
        dt = t[i + 1] - t[i]
        s = np.roots(_hermite(theta[i], theta[i + 1], omega[i] * dt, omega[i + 1] * dt))
        s = s[np.isreal(s)].real
        crossings.append(t[i] + dt * s[(s >= -1e-9) & (s <= 1 + 1e-9)][0])
    assert len(crossings) >= 3  # 10 s is 3.7 periods
    period = np.mean(np.diff(crossings))
    small_angle = 2 * math.pi / math.sqrt(A_GRAVITY)
    assert period == pytest.approx(small_angle, rel=1e-3)
    # with the finite-amplitude correction 1 + theta0^2/16: measured 3.6e-11 (the
    # next term of the series, 11 theta0^4/3072, is 3.6e-11)
    assert period == pytest.approx(small_angle * (1 + theta0**2 / 16), rel=1e-9)
    energy = 0.5 * omega**2 + A_GRAVITY * (1 - np.cos(theta))
    drift = np.max(np.abs(energy - energy[0])) / energy[0]
    # RK4 at h = 1e-5 s: measured 1.4e-12.  Explicit Euler would gain about
    # N h^2 a_gravity = 1e6 * 1e-10 * 5.45 = 5e-4 over the 10 s.
    assert drift < 1e-10


def _hermite(p0, p1, m0, m1):
    """Coefficients (highest first) of the cubic Hermite p(s) on s in [0, 1]."""
    return [2 * p0 - 2 * p1 + m0 + m1, -3 * p0 + 3 * p1 - 2 * m0 - m1, m0, p0]


def test_disturbance_outputs(pendulum):
    sine = record(pendulum(integers={"disturbance": 1}), 2.0, 1e-2)
    t = sine[:, 0]
    np.testing.assert_allclose(sine[:, 4], 0.5 * np.sin(2 * t), rtol=0, atol=1e-14)
    assert np.all(sine[:, 5] == 0.0)  # damping 0: d = 0
    square = record(pendulum(integers={"disturbance": 2}), 7.0, 1e-2)
    t = square[:, 0]
    away = np.abs(np.sin(t)) > 1e-9   # v_period = 2 pi: v = 0.5 sign(sin t)
    assert np.count_nonzero(~away) == 1  # only t = 0, where sign(0) = 0
    assert square[0, 4] == 0.0
    np.testing.assert_array_equal(square[away, 4], 0.5 * np.sign(np.sin(t[away])))
    assert set(square[away, 4]) == {-0.5, 0.5}


def test_time_varying_damping_output(pendulum):
    r = record(pendulum({"Vs": 0.0}, {"damping": 1}), 10.0, 1e-2)
    t = r[:, 0]
    np.testing.assert_allclose(r[:, 5], 0.5 + 0.6 * np.sin(t / 7), rtol=0, atol=1e-14)
    assert np.all(r[:, 4] == 0.0)  # disturbance 0: v = 0


def test_acceleration_output_is_the_model_at_the_output_state(pendulum):
    plant = pendulum({"theta_start": 0.1, "omega_start": 0.5},
                     {"disturbance": 1, "damping": 1})
    rows = [[0.0, *plant.get(*OUTPUTS)]]
    us = [0.0]  # at initialization u is its start value 0
    for k in range(300):  # u changes every step: the output uses the u just applied
        u = 2.0 * math.sin(0.05 * k) - 0.3
        us.append(u)
        plant.set({"u": u})
        plant.step(1e-2)
        rows.append([plant.t, *plant.get(*OUTPUTS)])
    t, theta, omega, acc, v, d = np.array(rows).T
    u = np.array(us)
    expected = (u / J - A_GRAVITY * np.sin(theta) - A_VISCOUS * omega
                - A_COULOMB * np.sign(omega) - d * omega + v)
    np.testing.assert_allclose(acc, expected, rtol=1e-13, atol=1e-13)
    assert np.any(omega > 0) and np.any(omega < 0)  # both Coulomb branches seen


def test_step_not_a_multiple_of_h(pendulum):
    """H = 2.5e-5 with h = 1e-5: the layer runs the grid steps, the outputs are
    the state at the end of the communication step (a final partial RK4 step)."""
    params = ({"theta_start": 0.1, "omega_start": 0.5}, {"disturbance": 1, "damping": 1})
    odd = record(pendulum(*params), 0.01, 2.5e-5, u=2.0)
    on_grid = record(pendulum({**params[0], "h": 2.5e-6}, params[1]), 0.01, 2.5e-5, u=2.0)
    coarse = record(pendulum(*params), 0.01, 1e-5, u=2.0)
    assert odd.shape == (401, 6) and odd[-1, 0] == pytest.approx(0.01, abs=1e-15)
    # every output at every communication point, against a plant whose grid hits it
    np.testing.assert_allclose(odd[:, 1:], on_grid[:, 1:], rtol=0, atol=1e-12)
    # at the common grid points (every 5e-5 s) the state is the same grid state
    np.testing.assert_allclose(odd[::2, 1:3], coarse[::5, 1:3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(odd[:, 4], 0.5 * np.sin(2 * odd[:, 0]), rtol=0, atol=1e-14)


def test_divergence_is_an_error_naming_the_variable(pendulum):
    """RK4 is unstable for h a_viscous > 2.79: a huge Vs at h = 1e-5 overflows."""
    plant = pendulum({"Vs": 1e6, "omega_start": 1.0})
    with pytest.raises(FMICallException):
        for _ in range(100):
            plant.step(1e-3)
    assert any("diverged" in m and "theta is not finite" in m for m in plant.messages), \
        plant.messages


# ---- twisting controller -----------------------------------------------------

def reference(t):
    theta_d = 0.3 * math.sin(3 * t + math.pi / 4) + 0.3 * math.sin(0.5 * t + math.pi)
    omega_d = 0.9 * math.cos(3 * t + math.pi / 4) + 0.15 * math.cos(0.5 * t + math.pi)
    return theta_d, omega_d


def twisting(theta, omega, t):
    theta_d, omega_d = reference(t)
    return -30 * np.sign(theta - theta_d) - 15 * np.sign(omega - omega_d), theta_d, omega_d


def test_controller_outputs_follow_the_formulas(controller):
    t0 = 0.7
    c = controller(inputs={"theta": 0.5, "omega": -1.0}, start_time=t0)
    # initialization: the control for the start time from the initial inputs
    assert c.get("u", "theta_d", "omega_d") == pytest.approx(twisting(0.5, -1.0, t0), abs=1e-15)
    rng = np.random.default_rng(1)
    seen = set()
    for _ in range(200):
        theta, omega = rng.uniform(-0.6, 0.6), rng.uniform(-1.5, 1.5)
        c.set({"theta": theta, "omega": omega})
        c.step(1e-2)  # 100 samples of h = 1e-4, the last one for t + H
        expected = twisting(theta, omega, c.t)
        # the FMU's time is start + k h, the test's is t += H: a few ulp apart
        assert c.get("u", "theta_d", "omega_d") == pytest.approx(expected, abs=1e-12)
        seen.add(expected[0])
    assert seen == {-45.0, -15.0, 15.0, 45.0}  # every sign combination


def test_controller_omega_d_is_the_derivative_of_theta_d(controller):
    c = controller()
    H = 1e-3
    rows = [c.get("theta_d", "omega_d")]
    for _ in range(int(round(15.0 / H))):
        c.step(H)
        rows.append(c.get("theta_d", "omega_d"))
    theta_d, omega_d = np.array(rows).T
    central = (theta_d[2:] - theta_d[:-2]) / (2 * H)
    # truncation H^2/6 max|third derivative| <= 1e-6/6 (0.3 27 + 0.3 0.125) = 1.4e-6
    np.testing.assert_allclose(central, omega_d[1:-1], rtol=0, atol=2e-6)


# ---- closed loop ---------------------------------------------------------------

def test_closed_loop_tracks_the_reference(pendulum, controller):
    """Plain Python master, H = 1e-4: plant step, then the controller samples its state."""
    plant = pendulum({"theta_start": 0.1, "omega_start": 0.5})
    theta, omega = plant.get("theta", "omega")
    ctrl = controller(inputs={"theta": theta, "omega": omega})
    p, c = plant.slave, ctrl.slave
    vr_u_in, vr_state = [plant.vr["u"]], [plant.vr["theta"], plant.vr["omega"]]
    vr_state_in = [ctrl.vr["theta"], ctrl.vr["omega"]]
    vr_out = [ctrl.vr["u"], ctrl.vr["theta_d"]]
    H, n = 1e-4, 50000
    u, theta_d = c.getReal(vr_out)
    errors = np.empty(n)
    for k in range(n):
        t = k * H
        p.setReal(vr_u_in, [u])
        p.doStep(t, H)
        state = p.getReal(vr_state)
        c.setReal(vr_state_in, state)
        c.doStep(t, H)
        u, theta_d = c.getReal(vr_out)
        errors[k] = state[0] - theta_d
    late = np.arange(1, n + 1) * H > 2.0
    worst = np.max(np.abs(errors[late]))
    assert worst < 1e-5  # measured 1.7e-6 (the paper asks < 0.05 rad)
    assert np.max(np.abs(errors[:100])) > 0.05  # it did start away from the reference

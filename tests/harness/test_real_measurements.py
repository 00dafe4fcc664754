"""The defaults on measurements as users have them: noisy, quantized, from a
plant integrated differently from the observer, with a nominal input gain 10 % off.

Small and fast cases; the full grid is bench/reports/real_measurements.py.  The data are a
pendulum (Coulomb friction included) under a multi-sine torque held over each 1 ms
sample (the Pendulum FMU, RK4), fed to the observer through `harness.identify`.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.fmus import FMUInstance
from harness.identify import Recording, identify
from harness.metrics import score
from harness.scenarios import (
    A_COULOMB,
    A_GRAVITY,
    A_VISCOUS,
    PAPER_METHOD,
    SCENARIOS,
    J,
    improved_overrides,
    run_scenario,
)

H = 1e-3
TRUE = {"c_nominal[1]": A_GRAVITY, "c_nominal[2]": A_VISCOUS, "c_nominal[3]": A_COULOMB}
NOMINAL = {"b": 1.1 / J, "c_nominal[1]": 2.0, "c_nominal[2]": 0.1, "c_nominal[3]": 0.1,
           "identifier": 1}


def _torque(t: np.ndarray) -> np.ndarray:
    return J * (2 * np.sin(2 * math.pi * 0.23 * t + 0.3) + 2 * np.sin(2 * math.pi * 0.61 * t + 1.9)
                + 5 * np.sin(2 * math.pi * 1.37 * t + 4.1) + 10 * np.sin(2 * math.pi * 2.71 * t))


def _simulate(pendulum_fmu, t: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """theta, omega of the Pendulum FMU at the times t, u[k] held over [t_k, t_k+1)."""
    plant = FMUInstance(pendulum_fmu, "plant")
    try:
        plant.setup(0.0, {"theta_start": 0.0, "omega_start": 0.0})
        plant.exit_initialization()
        theta, omega = np.empty(t.size), np.empty(t.size)
        for k in range(t.size):
            theta[k], omega[k] = plant.get(["theta", "omega"])
            if k < t.size - 1:
                plant.set({"u": float(u[k])})
                plant.do_step(t[k], t[k + 1] - t[k])
    finally:
        plant.close()
    return theta, omega


@pytest.fixture(scope="module")
def swing(pendulum_fmu):
    """theta, omega of 40 s of the pendulum at 1 kHz (u held over each sample)."""
    t = np.arange(int(round(40.0 / H)) + 1) * H
    u = _torque(t)
    return (t, *_simulate(pendulum_fmu, t, u), u)


def _identify(observer_fmu, t, y, u, **parameters):
    return identify(Recording(t, y, u), observer_fmu, {**NOMINAL, **parameters})


def _quantized(x: np.ndarray, bits: int) -> np.ndarray:
    q = 2 * math.pi / 2**bits
    return q * np.round(x / q)


@pytest.mark.parametrize("std", [1e-5, 1e-4])
def test_the_noise_level_is_estimated(observer_fmu, swing, std):
    t, theta, _, u = swing
    y = theta + np.random.default_rng(1).normal(0.0, std, theta.size)
    out = _identify(observer_fmu, t, y, u)
    assert out["noise_std"][-1] == pytest.approx(std, rel=0.1)


def test_the_quantization_step_is_estimated(observer_fmu, swing):
    t, theta, _, u = swing
    out = _identify(observer_fmu, t, _quantized(theta, 16), u)
    assert out["noise_std"][-1] == pytest.approx(2 * math.pi / 2**16 / math.sqrt(12), rel=0.3)


@pytest.mark.parametrize("bits", [None, 16])
def test_the_input_gain_is_recovered_from_a_nominal_10_percent_off(observer_fmu, swing, bits):
    t, theta, _, u = swing
    y = theta if bits is None else _quantized(theta, bits)
    out = _identify(observer_fmu, t, y, u)
    assert out["b_hat"][-1] == pytest.approx(1 / J, rel=0.005)  # the target
    # measured (both cases): gravity 0.02 %, Coulomb 0.06 %; the viscous term, the
    # smallest, 2.0 % (the 0.1 % noise-free target is not met at 1 kHz)
    assert out["theta_hat[1,1]"][-1] == pytest.approx(TRUE["c_nominal[1]"], rel=0.005)
    assert out["theta_hat[1,3]"][-1] == pytest.approx(TRUE["c_nominal[3]"], rel=0.005)
    assert out["theta_hat[1,2]"][-1] == pytest.approx(TRUE["c_nominal[2]"], rel=0.03)


def test_the_velocity_beats_the_paper_scheme_on_a_12_bit_encoder(observer_fmu, swing):
    t, theta, omega, u = swing
    y = _quantized(theta, 12)
    after = t >= 1.0
    defaults = _identify(observer_fmu, t, y, u, identifier=0)
    paper = _identify(observer_fmu, t, y, u, identifier=0, **PAPER_METHOD,
                      **{"alpha1[1]": 8.0, "alpha2[1]": 24.0})
    rms = {name: float(np.sqrt(np.mean((o["x2_hat"] - omega[: o["t"].size])[after[: o["t"].size]] ** 2)))
           for name, o in (("defaults", defaults), ("paper", paper))}
    assert rms["defaults"] < 0.5 * rms["paper"], rms


def test_standard_errors_match_the_spread_over_noise_seeds(observer_fmu, swing):
    """The reported standard error against the spread of the estimates over 96 noise
    seeds (noise 1e-3 rad, where the noise dominates the error): within the issue's
    factor 1.5 for every parameter (measured: gravity 0.85, viscous 0.92, Coulomb
    0.90, b 0.95; the spread of 96 seeds is itself uncertain by 7 %)."""
    t, theta, _, u = swing
    estimates, reported = [], []
    for seed in range(96):
        y = theta + np.random.default_rng(seed).normal(0.0, 1e-3, theta.size)
        out = _identify(observer_fmu, t, y, u)
        estimates.append([out[f"theta_hat[1,{k}]"][-1] for k in (1, 2, 3)] + [out["b_hat"][-1]])
        reported.append([out[f"theta_std[1,{k}]"][-1] for k in (1, 2, 3)] + [out["b_std"][-1]])
    ratio = np.mean(reported, axis=0) / np.std(estimates, axis=0, ddof=1)
    assert np.all((ratio > 1 / 1.5) & (ratio < 1.5)), ratio


@pytest.mark.parametrize("noise", [1e-5, 1e-4])
def test_defaults_no_worse_than_the_paper_scheme_on_a_short_noisy_run(observer_fmu,
                                                                       controller_fmu, noise):
    s = SCENARIOS["6.1-sine"]
    fmu_dir = observer_fmu.parent
    paper = score(s, run_scenario(s, fmu_dir, noise_std=noise))
    defaults = score(s, run_scenario(s, fmu_dir, noise_std=noise,
                                     observer_overrides=improved_overrides(s)))
    assert defaults["rms_perturbation"] <= paper["rms_perturbation"]
    assert defaults["max_e2_after_1s"] <= paper["max_e2_after_1s"]


def test_defaults_no_worse_than_the_paper_scheme_on_euler_plant_data(observer_fmu):
    """The 6.1 sine perturbation on samples of a plant integrated by explicit Euler at
    the observer's own step h = 1e-4 (the paper's discretization)."""
    h, n = 1e-4, 50000
    t = np.arange(n + 1) * h
    u = 1.5 * np.sin(1.3 * t) + np.sin(3.1 * t + 0.5)
    v = 0.5 * np.sin(2 * t)
    x, w = np.empty(n + 1), np.empty(n + 1)
    x[0], w[0] = 0.1, 0.5
    for k in range(n):
        x[k + 1] = x[k] + h * w[k]
        w[k + 1] = w[k] + h * (u[k] / J - A_GRAVITY * math.sin(x[k]) - A_VISCOUS * w[k] + v[k])
    model = {"b": 1 / J, "c_nominal[1]": A_GRAVITY, "c_nominal[2]": A_VISCOUS,
             "c_nominal[3]": 0.0, "identifier": 0}
    paper = {**model, **PAPER_METHOD, "alpha1[1]": 2.2211, "alpha2[1]": 19.1819, "tau": 0.02}
    rms = {}
    for name, parameters in (("defaults", model), ("paper", paper)):
        out = identify(Recording(t, x, u), observer_fmu, parameters)
        after = out["t"] >= 1.0
        error = out["z_eq_filtered"] - v[: out["t"].size]
        rms[name] = float(np.sqrt(np.mean(error[after] ** 2)))
    assert rms["defaults"] <= rms["paper"], rms


def test_the_identified_model_fed_back_sharpens_the_velocity(observer_fmu, swing):
    """model_feedback (the default): once the LSM has identified the joint, the observer
    predicts with the identified model instead of the nominal one (b 10 % off, gravity
    and friction the paper's guesses), so that its members track only what is left.
    Noise 1e-4 rad: velocity RMS after 5 s 4.4e-4 rad/s against 5.0e-3 without (measured);
    the estimates come from the same regression, shifted back to the nominal model, and
    agree within 0.3 of their standard errors (measured)."""
    t, theta, omega, u = swing
    y = theta + np.random.default_rng(3).normal(0.0, 1e-4, theta.size)
    after = t >= 5.0
    on = _identify(observer_fmu, t, y, u)
    off = _identify(observer_fmu, t, y, u, model_feedback=False)
    rms = {name: float(np.sqrt(np.mean((o["x2_hat"] - omega)[after] ** 2)))
           for name, o in (("on", on), ("off", off))}
    assert rms["on"] < 0.2 * rms["off"], rms
    for key, std in [(f"theta_hat[1,{k}]", f"theta_std[1,{k}]") for k in (1, 2, 3)] + [
            ("b_hat", "b_std")]:
        assert abs(on[key][-1] - off[key][-1]) < on[std][-1], key


def test_a_member_stands_in_while_the_injection_saturates(observer_fmu, pendulum_fmu):
    """Exact samples, a nominal b 10 % off and a 30 ms half-sine torque burst every
    second (peak acceleration 300 rad/s^2): the model error (about 30 rad/s^2) outruns
    the default alpha1 = 2 f_plus = 20 during the bursts, too seldom for the bank to
    leave the super-twisting observer, whose velocity error then grows by the excess
    times h each step.  Meanwhile the velocity of the member of the smallest one-step
    mean square is published.  Measured, velocity RMS and max after 0.5 s: 4.4e-3 and 0.046 rad/s,
    against 1.2e-2 and 0.16 with the super-twisting observer's published throughout."""
    n = int(round(6.0 / H))
    t = np.arange(n + 1) * H
    burst = (t % 1.0) < 0.03
    u = _torque(t) + J * 300.0 * burst * np.sin(math.pi * (t % 1.0) / 0.03)
    theta, omega = _simulate(pendulum_fmu, t, u)
    out = _identify(observer_fmu, t, theta, u, model_feedback=False)
    error = np.abs(out["x2_hat"] - omega)[t >= 0.5]
    assert np.sqrt(np.mean(error**2)) < 6e-3 and error.max() < 0.08, (
        np.sqrt(np.mean(error**2)), error.max())

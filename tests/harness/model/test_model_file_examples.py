"""The example model files read, and their regressors agree with the equations evaluated
directly: Y theta - r equals lhs - rhs at random samples and parameters."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sympy

from harness.model import Model, parse_model, read_model, rms_columns

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
SAMPLES = 257


def _random(shape, seed):
    return np.random.default_rng(seed).normal(size=shape)


def _theta(model: Model, seed: int) -> np.ndarray:
    return model.nominal + _random(len(model.parameters), seed)


def test_emps_example():
    model = read_model(EXAMPLES / "emps" / "emps.toml")
    assert model.coordinates == ("x",) and model.inputs == ("vir",)
    assert model.parameter_names == ("M", "Fv", "Fc", "OF")
    assert model.parameter_units == {"M": "kg", "Fv": "N.s/m", "Fc": "N", "OF": "N"}
    assert model.columns == {"t": "t", "x": "qm", "vir": "vir"}
    q, qd, qdd, vir = (_random(SAMPLES, seed) for seed in range(4))
    M, Fv, Fc, OF = theta = _theta(model, 9)
    Y, r = model.regressor(q, qd, qdd, vir)
    assert Y.shape == (SAMPLES, 1, 4) and r.shape == (SAMPLES, 1)
    direct = M * qdd + Fv * qd + Fc * np.sign(qd) + OF - 35.15065188 * vir
    np.testing.assert_allclose(Y @ theta - r, direct[:, None], rtol=1e-12, atol=1e-9)


def test_pendulum_example():
    model = read_model(EXAMPLES / "pendulum" / "pendulum.toml")
    assert model.parameter_names == ("J", "ML", "Vs", "Ps")
    q, qd, qdd, u = (_random(SAMPLES, seed) for seed in range(4))
    J, ML, Vs, Ps = theta = _theta(model, 8)
    Y, r = model.regressor(q, qd, qdd, u)
    direct = J * qdd + ML * 9.815 / 2 * np.sin(q) + Vs * qd + Ps * np.sign(qd) - u
    np.testing.assert_allclose(Y @ theta - r, direct[:, None], rtol=1e-12, atol=1e-9)


def test_pendulum_of_the_paper_balances_with_its_values():
    """The paper's numbers: J = M L^2 = 0.891, MgL/2J = 5.4528; at rest at angle theta the
    torque M g L / 2 sin(theta) holds the arm."""
    model = read_model(EXAMPLES / "pendulum" / "pendulum.toml")
    theta = np.array([0.891, 1.1 * 0.9, 0.18, 0.45])
    angle = np.linspace(-1, 1, 5)
    torque = 1.1 * 9.815 * 0.9 / 2 * np.sin(angle)
    Y, r = model.regressor(angle, np.zeros(5), np.zeros(5), torque)
    np.testing.assert_allclose(Y @ theta, r, atol=1e-12)
    assert 1.1 * 9.815 * 0.9 / 2 / 0.891 == pytest.approx(5.4528, abs=1e-4)


def test_two_mass_example():
    model = read_model(EXAMPLES / "two_mass" / "two_mass.toml")
    assert model.coordinates == ("x1", "x2") and len(model.equations) == 2
    assert model.columns["t"] == "time"
    q, qd, qdd = (_random((SAMPLES, 2), seed) for seed in range(3))
    F = _random((SAMPLES, 1), 3)
    theta = _theta(model, 7)
    m1, m2, c1, c2, k, d = theta
    Y, r = model.regressor(q, qd, qdd, F)
    assert Y.shape == (SAMPLES, 2, 6) and r.shape == (SAMPLES, 2)
    (x1, x2), (v1, v2), (a1, a2) = q.T, qd.T, qdd.T
    direct = np.stack([m1 * a1 + c1 * v1 + k * (x1 - x2) + d * (v1 - v2) - F[:, 0],
                       m2 * a2 + c2 * v2 + k * (x2 - x1) + d * (v2 - v1)], axis=1)
    np.testing.assert_allclose(Y @ theta - r, direct, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(model.residuals(theta, q, qd, qdd, F), direct, atol=1e-9)
    # m2 and c2 do not enter the first equation, m1 and c1 not the second
    assert not Y[:, 0, [1, 3]].any() and not Y[:, 1, [0, 2]].any()


# The model file as the contract writes it, comments included.
CONTRACT = """
[model]
coordinates = ["x"]                 # generalized coordinates, measured
inputs = ["F"]                      # known inputs (forces / torques)
equations = ["M*der(x,2) + Fv*der(x) + Fc*sign(der(x)) + OF = F"]   # one per coordinate
[parameters]                        # unknown: identified
M  = { nominal = 100, unit = "kg" }
Fv = { nominal = 0, unit = "N.s/m" }
Fc = { nominal = 0, unit = "N" }
OF = { nominal = 0, unit = "N" }
[constants]                         # known values, e.g. g = 9.81
[units]                             # optional: then every term is dimension-checked
x = "m"
F = "N"
[columns]                           # log column of each name (default: the name itself)
t = "t"
x = "qm"
F = "force"
"""


def test_the_contracts_file_splits_into_its_regressor():
    model = parse_model(CONTRACT)
    (equation,) = model.equations
    F = model.symbols.inputs["F"]
    v, a = model.symbols.velocity["x"], model.symbols.acceleration["x"]
    assert equation.terms == (a, v, sympy.sign(v), sympy.Integer(1))
    assert equation.known == F
    assert str(v) == "der(x)" and str(a) == "der(x,2)"
    assert model.columns == {"t": "t", "x": "qm", "F": "force"}
    assert model.source == "<model>"


def test_without_units_or_columns():
    equation = ("a*der(q,2) + b*cos(q)*der(q)^2 + c*tanh(10*der(q))"
                " + e*exp(-abs(q))*sqrt(1 + q^2) = 0")
    model = parse_model(f"""
[model]
coordinates = ["q"]
equations = ["{equation}"]
[parameters]
a = {{ nominal = 1 }}
b = {{ nominal = 0 }}
c = {{ nominal = 0 }}
e = {{ nominal = 0 }}
""")
    assert model.inputs == () and model.units == {} and model.columns == {"t": "t", "q": "q"}
    assert model.parameter_units == {"a": "", "b": "", "c": "", "e": ""}
    q, qd, qdd = (_random(SAMPLES, seed) for seed in range(3))
    Y, r = model.regressor(q, qd, qdd)
    np.testing.assert_allclose(Y[:, 0, :], np.stack(
        [qdd, np.cos(q) * qd ** 2, np.tanh(10 * qd), np.exp(-abs(q)) * np.sqrt(1 + q ** 2)], 1))
    assert not r.any()


def test_a_known_part_on_the_left_and_a_parameter_on_the_right():
    """Everything moves to one side: parameters on the right, known terms on the left."""
    model = parse_model("""
[model]
coordinates = ["x"]
inputs = ["u"]
equations = ["2*der(x,2) + k0*x + g0 = u - c*der(x) + M*(3 - der(x,2))"]
[parameters]
k0 = { nominal = 1 }
c = { nominal = 1 }
M = { nominal = 1 }
[constants]
g0 = 4.5
""")
    q, qd, qdd, u = (_random(SAMPLES, seed) for seed in range(4))
    theta = np.array([1.5, -0.5, 2.0])
    Y, r = model.regressor(q, qd, qdd, u)
    direct = 2 * qdd + theta[0] * q + 4.5 - (u - theta[1] * qd + theta[2] * (3 - qdd))
    np.testing.assert_allclose(Y[:, 0] @ theta - r[:, 0], direct, rtol=1e-12, atol=1e-9)


def test_column_scales_are_the_rms_of_the_columns():
    model = read_model(EXAMPLES / "emps" / "emps.toml")
    t = np.linspace(0, 2, 2001)
    q = 0.1 * np.sin(3 * t)
    qd, qdd = 0.3 * np.cos(3 * t), -0.9 * np.sin(3 * t)
    scales = model.column_scales(q, qd, qdd, np.zeros_like(t))
    rms = lambda a: np.sqrt(np.mean(a ** 2))  # noqa: E731
    np.testing.assert_allclose(scales, [rms(qdd), rms(qd), rms(np.sign(qd)), 1.0])
    two = read_model(EXAMPLES / "two_mass" / "two_mass.toml")
    Y, _ = two.regressor(*(_random((SAMPLES, 2), s) for s in range(3)), _random(SAMPLES, 4))
    np.testing.assert_allclose(rms_columns(Y) ** 2,
                               np.einsum("sik,sik->k", Y, Y) / SAMPLES)


def test_regressor_shapes():
    model = read_model(EXAMPLES / "two_mass" / "two_mass.toml")
    ones = np.ones((3, 2))
    Y, r = model.regressor(ones, ones, ones, np.ones((3, 1)))
    assert Y.shape == (3, 2, 6) and r.shape == (3, 2)
    with pytest.raises(ValueError, match=r"q must have shape \(samples, 2\)"):
        model.regressor(np.ones(3), ones, ones, np.ones((3, 1)))
    with pytest.raises(ValueError, match="same number of samples"):
        model.regressor(ones, np.ones((4, 2)), ones, np.ones((3, 1)))
    with pytest.raises(ValueError, match=r"inputs must have shape \(samples, 1\)"):
        model.regressor(ones, ones, ones, np.ones((3, 2)))


def test_regressor_is_fast_enough_for_long_logs():
    """A million samples of the two-mass model in well under a second's worth of numpy."""
    import time
    model = read_model(EXAMPLES / "two_mass" / "two_mass.toml")
    big = np.ones((1_000_000, 2))
    model.regressor(big[:10], big[:10], big[:10], big[:10, :1])  # compile once
    start = time.perf_counter()
    Y, _ = model.regressor(big, big, big, big[:, :1])
    assert Y.shape == (1_000_000, 2, 6)
    assert time.perf_counter() - start < 5.0  # measured 0.53 s; the machine is shared


def test_a_two_link_arm_with_coupled_inertia():
    """M(q) q'' + C(q, q') q' + G(q) = tau with the arm's base parameters a1..a5: the
    inertia terms are products of parameters and functions of q, still linear in a."""
    model = parse_model("""
[model]
coordinates = ["q1", "q2"]
inputs = ["tau1", "tau2"]
equations = [
  "(a1 + 2*a2*cos(q2))*der(q1,2) + (a3 + a2*cos(q2))*der(q2,2) - a2*sin(q2)*(2*der(q1)*der(q2) + der(q2)^2) + a4*g*cos(q1) + a5*g*cos(q1 + q2) = tau1",
  "(a3 + a2*cos(q2))*der(q1,2) + a3*der(q2,2) + a2*sin(q2)*der(q1)^2 + a5*g*cos(q1 + q2) = tau2",
]
[parameters]
a1 = { nominal = 1.0, unit = "kg.m^2" }
a2 = { nominal = 0.2, unit = "kg.m^2" }
a3 = { nominal = 0.3, unit = "kg.m^2" }
a4 = { nominal = 1.5, unit = "kg.m" }
a5 = { nominal = 0.5, unit = "kg.m" }
[constants]
g = { value = 9.81, unit = "m/s^2" }
[units]
q1 = "rad"
q2 = "rad"
tau1 = "N.m"
tau2 = "N.m"
""")
    q, qd, qdd, tau = (_random((SAMPLES, 2), seed) for seed in range(4))
    a1, a2, a3, a4, a5 = theta = _theta(model, 5)
    (q1, q2), (v1, v2), (w1, w2) = q.T, qd.T, qdd.T
    g = 9.81
    direct = np.stack([
        (a1 + 2 * a2 * np.cos(q2)) * w1 + (a3 + a2 * np.cos(q2)) * w2
        - a2 * np.sin(q2) * (2 * v1 * v2 + v2 ** 2) + a4 * g * np.cos(q1)
        + a5 * g * np.cos(q1 + q2) - tau[:, 0],
        (a3 + a2 * np.cos(q2)) * w1 + a3 * w2 + a2 * np.sin(q2) * v1 ** 2
        + a5 * g * np.cos(q1 + q2) - tau[:, 1]], axis=1)
    Y, r = model.regressor(q, qd, qdd, tau)
    np.testing.assert_allclose(Y @ theta - r, direct, rtol=1e-12, atol=1e-9)

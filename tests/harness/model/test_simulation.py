"""A model file simulated (harness.model.simulation): against closed forms, scipy, and
itself (the core's C through the term program, and the numpy loop that runs a model
beyond the term program's limits)."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate
from model_text import model

from harness.model import parse_model
from harness.model.simulation import (
    Dynamics,
    input_at,
    linearized,
    simulate,
    substeps,
    time_constant,
)

OSCILLATOR = """
[model]
coordinates = ["x"]
inputs = ["u"]
equations = ["m*der(x,2) + d*der(x) + k*x = u"]
[parameters]
m = { nominal = 1 }
d = { nominal = 0 }
k = { nominal = 1 }
"""
TWO_MASSES = """
[model]
coordinates = ["x1", "x2"]
inputs = ["F"]
equations = ["m1*der(x1,2) + k*(x1 - x2) + c*der(x1) = F",
             "m2*der(x2,2) + k*(x2 - x1) + m2*0.5*der(x1,2) = 0"]
[parameters]
m1 = { nominal = 2 }
m2 = { nominal = 1 }
k = { nominal = 50 }
c = { nominal = 0.5 }
"""
STEP = 1e-3


def _run(text: str, theta, q0, qd0, u, parts=4):
    """The runs by the C core and by numpy (the program taken away)."""
    model = parse_model(text)
    fine = input_at(u, STEP, parts)
    span = np.ones(len(q0))
    runs = []
    for native in (True, False):
        dynamics = Dynamics(model)
        if not native:
            dynamics.__dict__["program"] = None
        runs.append(simulate(dynamics, np.asarray(theta, float), np.atleast_2d(q0),
                             np.atleast_2d(qd0), fine[None], STEP, parts, span))
    return runs


def test_an_undamped_oscillator_follows_its_cosine():
    omega = 2 * np.pi * 5.0
    u = np.zeros((2001, 1))
    many, one = _run(OSCILLATOR, [1.0, 0.0, omega ** 2], [1.0], [0.0], u)
    t = np.arange(2001) * STEP
    assert np.max(np.abs(many.q[0, :, 0] - np.cos(omega * t))) < 1e-7
    assert np.max(np.abs(one.q[0] - many.q[0])) < 1e-12  # numpy runs the same scheme
    assert many.diverged[0] == -1 and one.diverged[0] == -1


def test_two_coupled_masses_match_scipy():
    """The mass matrix has an off-diagonal entry (m2/2 in the second equation)."""
    theta = [2.0, 1.0, 50.0, 0.5]
    t = np.arange(3001) * STEP
    F = np.sin(2 * np.pi * 1.3 * t)[:, None]
    many, one = _run(TWO_MASSES, theta, [0.1, -0.05], [0.0, 0.2], F)

    def rhs(time, s):
        x1, x2, v1, v2 = s
        force = np.sin(2 * np.pi * 1.3 * time)
        a1 = (force - 50 * (x1 - x2) - 0.5 * v1) / 2.0
        a2 = -50 * (x2 - x1) - 0.5 * a1
        return [v1, v2, a1, a2]
    reference = scipy.integrate.solve_ivp(rhs, (0, t[-1]), [0.1, -0.05, 0.0, 0.2], t_eval=t,
                                          rtol=1e-11, atol=1e-12).y[:2].T
    assert np.max(np.abs(many.q[0] - reference)) < 1e-6
    assert np.max(np.abs(one.q[0] - many.q[0])) < 1e-11


def test_an_unstable_model_is_marked_where_it_diverges():
    u = np.zeros((5001, 1))
    many, one = _run(OSCILLATOR, [1.0, -20.0, 100.0], [1e-3], [0.0], u)
    assert 0 < many.diverged[0] < 5000 and one.diverged[0] == many.diverged[0]
    assert np.all(np.isfinite(many.q))


def test_input_between_samples_is_band_limited():
    """A sine at a quarter of the sample rate, recovered between its samples."""
    t = np.arange(4001) * STEP
    u = np.sin(2 * np.pi * 250.0 * t + 0.3)[:, None]
    fine = input_at(u, STEP, 2)
    t_fine = np.arange(fine.shape[0]) * STEP / 4
    middle = slice(1000, -1000)  # away from the mirrored ends
    assert np.max(np.abs(fine[middle, 0] - np.sin(2 * np.pi * 250.0 * t_fine[middle] + 0.3))) \
        < 1e-2


def test_substeps_and_time_constant_follow_the_modes():
    model = parse_model(OSCILLATOR)
    dynamics = Dynamics(model)
    omega, zeta = 2 * np.pi * 60.0, 0.05
    theta = np.array([1.0, 2 * zeta * omega, omega ** 2])
    q = np.linspace(-1, 1, 20)[:, None]
    A = linearized(dynamics, theta, q, np.zeros_like(q), np.zeros_like(q))
    assert time_constant(A) == pytest.approx(1 / (zeta * omega), rel=1e-4)
    assert substeps(A, 1.0 / 610.0) == int(np.ceil(omega / 610.0 / 0.3))
    free = linearized(dynamics, np.array([1.0, 0.0, 0.0]), q, np.zeros_like(q),
                      np.zeros_like(q))
    assert time_constant(free) == np.inf  # no mode decays: a free mass


# ---- names the generated code shares with the file ----


@pytest.mark.cli
@pytest.mark.parametrize("name", ["e", "theta_0", "E", "x0"])
def test_the_simulations_generated_code_names_never_collide_with_the_files(tmp_path, name):
    """The simulation's compiled function (scores, cross-validation, output error) means
    the coordinate by the coordinate's name and Euler's number by exp(1)."""
    from harness.model import read_model
    from harness.model.simulation import Dynamics

    eq = "M*der({c},2) + Fv*exp(1)*der({c}) + atan({c}) = F"
    ours = Dynamics(read_model(model(tmp_path / "a.toml", eq.format(c=name), c=name)))
    plain = Dynamics(read_model(model(tmp_path / "b.toml", eq.format(c="y"), c="y")))
    rng = np.random.default_rng(2)
    q, qd, u = (rng.normal(size=(20, 1)) for _ in range(3))
    theta = np.array([2.0, 0.7])
    assert np.array_equal(ours(q, qd, u, theta), plain(q, qd, u, theta))

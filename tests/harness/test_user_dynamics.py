"""User dynamics in the master loop (harness.user_dynamics): the example of
docs/user_dynamics.md identifies a flexible joint, and fails when F and phi are not
applied at the step they belong to."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import harness.user_dynamics
from harness.fmus import FMUInstance
from harness.master import CoSimulation, Link, initialize, run
from harness.user_dynamics import AttachedDynamics

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = re.findall(r"```python\n(.*?)```", (REPO / "docs" / "user_dynamics.md").read_text(),
                     re.S)[0]


def _run_example(monkeypatch, wrap=None) -> dict:
    """The docs' example as written; ``wrap`` replaces the user's function by a faulty one."""
    monkeypatch.chdir(REPO)
    if wrap is not None:
        monkeypatch.setattr(harness.user_dynamics, "AttachedDynamics",
                            lambda function, **kw: AttachedDynamics(wrap(function), **kw))
    namespace: dict = {}
    exec(compile(EXAMPLE, "docs/user_dynamics.md", "exec"), namespace)
    return namespace


K_TOLERANCE, C_TOLERANCE = 2e-3, 6e-4


def test_docs_example_identifies_the_flexible_joint(observer_fmu, monkeypatch, capsys):
    ns = _run_example(monkeypatch)
    # measured: 39.9994 and 39.9995 (true 40), friction 0.29987 (true 0.3)
    assert ns["k_link"] == pytest.approx(40.0, abs=K_TOLERANCE)
    assert ns["k_motor"] == pytest.approx(40.0, abs=K_TOLERANCE)
    assert ns["c_motor"] == pytest.approx(0.3, abs=C_TOLERANCE)
    printed = capsys.readouterr().out
    assert "stiffness 39.999" in printed and "motor friction 0.2998" in printed


def test_the_tolerances_catch_F_and_phi_applied_one_step_late(observer_fmu, monkeypatch):
    def one_step_late(function):
        previous = []

        def late(t, y, x2_hat, u):
            now = function(t, y, x2_hat, u)
            result = previous[0] if previous else now
            previous[:] = [now]
            return result
        return late

    ns = _run_example(monkeypatch, one_step_late)
    # measured: stiffness 39.9978 (link row), friction 0.30137
    assert abs(ns["k_link"] - 40.0) > K_TOLERANCE
    assert abs(ns["c_motor"] - 0.3) > C_TOLERANCE


def test_the_tolerances_catch_F_not_applied(observer_fmu, monkeypatch):
    def without_F(function):
        return lambda t, y, x2_hat, u: ([0.0, 0.0], function(t, y, x2_hat, u)[1])

    ns = _run_example(monkeypatch, without_F)
    # measured: stiffness 3.72 (link row), -0.48 (motor row), friction -0.0104
    assert abs(ns["k_link"] - 40.0) > 30 and abs(ns["c_motor"] - 0.3) > 0.3


def _observer(observer_fmu, **parameters):
    y = np.zeros(50)
    sim = CoSimulation({"observer": FMUInstance(observer_fmu, "observer")},
                       [Link("signal:y", "observer.y[1]")])
    initialize(sim, 0.0, {"observer": {"h": 1e-3, **parameters}}, {"y": y})
    return sim, {"y": y}


def test_the_observer_must_be_in_external_mode_with_the_same_sizes(observer_fmu):
    function = lambda t, y, x2_hat, u: ([0.0], [])  # noqa: E731
    sim, signals = _observer(observer_fmu)
    try:
        with pytest.raises(ValueError, match="nominal_model = 1; F and phi are used only with "
                                             "nominal_model = 2"):
            run(sim, 0.0, 0.01, 1e-3, [], signals=signals,
                dynamics=AttachedDynamics(function, n=1, l=0))
    finally:
        sim.close()
    sim, signals = _observer(observer_fmu, nominal_model=2, l=2)
    try:
        with pytest.raises(ValueError, match="n = 1, l = 3, but observer is set up with "
                                             "n = 1, l = 2"):
            run(sim, 0.0, 0.01, 1e-3, [], signals=signals,
                dynamics=AttachedDynamics(function, n=1, l=3))
        with pytest.raises(ValueError, match="has no input phi\\[9\\]"):
            run(sim, 0.0, 0.01, 1e-3, [], signals=signals,
                dynamics=AttachedDynamics(function, n=1, l=9))
        with pytest.raises(ValueError, match="unknown signal 'u'"):
            run(sim, 0.0, 0.01, 1e-3, [], signals=signals,
                dynamics=AttachedDynamics(function, n=1, l=2, inputs=["signal:u"]))
        with pytest.raises(ValueError, match="Python loop only"):
            run(sim, 0.0, 0.01, 1e-3, [], signals=signals, use_native=True,
                dynamics=AttachedDynamics(function, n=1, l=2))
    finally:
        sim.close()


@pytest.mark.parametrize("returned, message", [
    (([0.0, 1.0], [1.0, 2.0]), "returned 2 values of F and 2 of phi; the observer takes "
                               "n = 1 and l = 2"),
    (([0.0], [1.0, float("nan")]), "returned phi\\[2\\] = nan, not finite"),
])
def test_a_bad_return_value_stops_the_run_with_its_time(observer_fmu, returned, message):
    calls = []

    def function(t, y, x2_hat, u):
        calls.append(t)
        return ([0.0], [0.0, 0.0]) if len(calls) < 4 else returned

    sim, signals = _observer(observer_fmu, nominal_model=2, l=2)
    try:
        with pytest.raises(ValueError, match="at t = 0.003 s " + message):
            run(sim, 0.0, 0.01, 1e-3, [], signals=signals,
                dynamics=AttachedDynamics(function, n=1, l=2))
    finally:
        sim.close()

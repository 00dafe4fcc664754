"""The work of one doStep is bounded by a budget in units of work, not steps.

A step count alone let an expensive configuration run for minutes in one call
(RobotObserver, 7 joints: doStep(0, 1e4) was 10^7 accepted internal steps,
about 188 s).  Every FMU has the parameter max_work (value reference 121,
default 10^9 work units, about a nanosecond of one core each) and the
calculated parameter work_per_step (122, the model's estimate per internal
step from its configuration): a communication step whose internal steps times
work_per_step exceed max_work is refused before any work, naming the budget,
the work asked and the longest step allowed; max_internal_steps still applies.
Any accepted step of the heaviest configurations finishes in about a second
(SLOW allows for a loaded machine).  Each case runs in a forked child with a
timeout: a step that does the work anyway fails by the timeout.
"""
from __future__ import annotations

import math
import os
import time

import pytest

from fmu.fmi_helpers import RawFMU3
from harness.robot.layout import ParameterLayout
from tools.abuse.abuse_fmi import ERROR, MODELS, OK, REPO, Raw, assert_usable_after_reset, isolated

OBS, PEN, CTL, ROBOT, *_ = MODELS
BUDGET_VR, WORK_VR, DEFAULT_BUDGET = 121, 122, 1e9
QUICK = 0.5   # s: a refused step returns at once
SLOW = 4.0    # s: about 1 s unloaded; twice the 2 s target on a machine shared by three
if os.environ.get("STO_EXPECT_SANITIZED") == "1":
    SLOW *= 5.0  # AddressSanitizer's builds (tools/abuse/sanitize.sh) run several times slower
TIMEOUT = 30.0


def robot(n: int, identifier: int, p: int) -> dict:
    """n joints (the default arm's links repeated), p identified base columns."""
    parameters = {"n": n, "identifier": identifier,
                  **{f"f_plus[{i + 1}]": 1000.0 for i in range(n)}}
    if identifier:
        layout = ParameterLayout(n)
        first = 0 if p == layout.standard_size else layout.link_end  # all, or the friction
        parameters["base_count"] = p
        parameters.update({f"base_columns[{k + 1}]": first + k for k in range(p)})
    return parameters


EXTERNAL = {"nominal_model": 2, "n": 4, "l": 8, "mff_drift": False,
            **{f"identify[{k}]": True for k in range(1, 9)}}
# The heaviest configurations of each model (measured, docs/observer.md and docs/robots.md).
HEAVY = [
    (ROBOT, robot(7, 1, 84)), (ROBOT, robot(7, 2, 84)), (ROBOT, robot(7, 1, 14)),
    (ROBOT, robot(7, 0, 0)), (ROBOT, robot(2, 1, 4)),
    (OBS, {}), (OBS, {"identifier": 2, "identifier_start": 0, "h": 1e-3, **EXTERNAL}),
    (OBS, {"identifier": 1, "identifier_start": 0, **EXTERNAL}),
    (PEN, {"damping": 1, "disturbance": 1}), (CTL, {}),
]
HEAVY_IDS = [f"{m}-" + "-".join(f"{k}={v}" for k, v in p.items()
                                if not k.startswith(("f_plus", "base_col", "identify[")))
             for m, p in HEAVY]


def _longest_step_is_fast_and_one_more_is_refused(model: str, parameters: dict):
    f = Raw(model)
    assert f.initialize(parameters) <= 1, f.messages()
    h, work, budget = f.get_real(["h", "work_per_step", "max_work"])[1]
    assert budget == DEFAULT_BUDGET and work >= 0.0
    assert f.do_step(0.0, 100 * h) == OK, f.messages()  # past the start-up
    t = 100 * h
    most = min(math.floor(budget / work) if work > 0 else 10**7, 10**7)
    start = time.perf_counter()
    status = f.do_step(t, most * h)
    took = time.perf_counter() - start
    assert status == OK, f.messages()
    assert took < SLOW, f"{most} internal steps of work {work:g} took {took:.2f} s"
    print(f"{model} {most} steps of work_per_step {work:g}: {took:.2f} s")
    t += most * h
    if work > 0:
        start = time.perf_counter()
        assert f.do_step(t, (most + 1) * h) == ERROR
        assert time.perf_counter() - start < QUICK
        errors = f.errors()
        assert f"needs {most + 1} internal steps" in errors, errors
        assert f"work budget max_work = {budget:.4g}" in errors, errors
        assert f"at most {most} internal steps" in errors, errors
        assert "raise the parameter max_work (value reference 121)" in errors, errors
        f.assert_escaped()
    f.free()


@pytest.mark.parametrize("model, parameters", HEAVY, ids=HEAVY_IDS)
def test_the_longest_accepted_step_is_fast_and_one_step_more_is_refused(model, parameters):
    isolated(_longest_step_is_fast_and_one_more_is_refused, model, parameters, timeout=TIMEOUT)


LONG = [(ROBOT, robot(7, 1, 14), 1e4), (ROBOT, robot(7, 1, 84), 1e4), (ROBOT, {}, 1e4),
        (ROBOT, robot(7, 0, 0), 1e3), (OBS, {"identifier": 2, **EXTERNAL}, 999.0),
        (PEN, {}, 99.0)]


def _long_step_refused(model: str, parameters: dict, H: float):
    f = Raw(model)
    assert f.initialize(parameters) <= 1, f.messages()
    start = time.perf_counter()
    assert f.do_step(0.0, H) == ERROR, "accepted"
    assert time.perf_counter() - start < QUICK
    h, work = f.get_real(["h", "work_per_step"])[1]  # getters stay allowed in the Error state
    steps = round(H / h)
    assert steps <= 10**7  # within max_internal_steps: only the budget refuses it
    errors = f.errors()
    assert f"needs {steps} internal steps of h = {h:g} at work_per_step = {work:g}" in errors
    assert f"{steps * work:.4g} units, more than the work budget max_work = 1e+09" in errors
    f.assert_escaped()
    assert_usable_after_reset(f)
    f.free()


@pytest.mark.parametrize("model, parameters, H", LONG,
                         ids=[f"{m}-{len(p)}-H={H:g}" for m, p, H in LONG])
def test_a_long_step_within_max_internal_steps_is_refused_by_the_budget(model, parameters, H):
    """RobotObserver with 7 joints: doStep(0, 1e4) was accepted and ran ~188 s."""
    isolated(_long_step_refused, model, parameters, H, timeout=TIMEOUT)


def test_fmi3_refuses_the_long_robot_step_by_the_budget():
    def run():
        f = RawFMU3(REPO / "build" / "fmi3" / "RobotObserver.fmu"
                    if not os.environ.get("STO_FMI3_DIR")
                    else os.path.join(os.environ["STO_FMI3_DIR"], "RobotObserver.fmu"))
        assert f.call("EnterInitializationMode", False, 0.0, 0.0, False, 0.0) == OK
        assert f.set("Int32", {"n": [7]}) == OK
        assert f.set("Float64", {"f_plus": [1000.0] * 7}) == OK
        assert f.call("ExitInitializationMode") == OK, f.messages()
        start = time.perf_counter()
        status, _, _, _, last = f.do_step(0.0, 1e4)
        assert status == ERROR and last == 0.0
        assert time.perf_counter() - start < QUICK
        assert "more than the work budget max_work = 1e+09" in f.messages(), f.messages()
        f.free()
    isolated(run, timeout=TIMEOUT)


def _raised_budget(model: str):
    f = Raw(model)
    assert f.initialize({"max_work": 2e6}) == OK, f.messages()
    h, work = f.get_real(["h", "work_per_step"])[1]
    most = math.floor(2e6 / work)
    assert f.do_step(0.0, (most + 1) * h) == ERROR
    f.free()
    f = Raw(model)
    assert f.initialize({"max_work": 4e6}) == OK
    assert f.do_step(0.0, (most + 1) * h) == OK, f.messages()
    f.free()


@pytest.mark.parametrize("model", [OBS, PEN, ROBOT])
def test_raising_the_budget_allows_longer_steps(model):
    isolated(_raised_budget, model, timeout=TIMEOUT)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_the_budget_has_a_range(model, value):
    def run():
        f = Raw(model)
        assert f.set_real({"max_work": value}) == ERROR, f.messages()
        assert "max_work" in f.errors()
        assert_usable_after_reset(f)
    isolated(run)


def test_the_budget_and_the_estimate_are_declared_alike_in_every_fmu():
    for model in MODELS:
        f = Raw(model, instantiate=False)
        budget, work = f.variables["max_work"], f.variables["work_per_step"]
        assert (budget.valueReference, budget.type, budget.causality, budget.variability) == (
            BUDGET_VR, "Real", "parameter", "fixed")
        assert float(budget.start) == DEFAULT_BUDGET and float(budget.min) == 0.0
        assert "refused" in budget.description and "Raise it" in budget.description
        assert (work.valueReference, work.type, work.causality) == (
            WORK_VR, "Real", "calculatedParameter")


def test_the_estimate_follows_the_configuration():
    """The robot's estimate grows with joints and identified parameters (the
    7-joint arm with all 84 columns costs about 5 times the 2-joint default), and with
    the identifier's fixed-lag window (5 FL_MAX_HALF = 1200 units per joint)."""
    def work(model, parameters):
        f = Raw(model)
        assert f.initialize(parameters) <= 1, f.messages()
        value = f.get_real(["work_per_step"])[1][0]
        f.free()
        return value
    def run():
        assert work(ROBOT, {}) == pytest.approx(400 * 2 + 1000 + 2 * 4 * 7 / 6 + 1200 * 2)
        assert work(ROBOT, {"regression": 0}) == pytest.approx(400 * 2 + 1000 + 2 * 4 * 7 / 6)
        assert work(ROBOT, robot(7, 1, 84)) == pytest.approx(400 * 7 + 1000 + 7 * 84 * 87 / 6
                                                             + 1200 * 7)
        assert work(ROBOT, robot(7, 0, 0)) == 2800
        assert work(OBS, {}) == 650 and work(OBS, {"scheme": 1}) == 10
        assert work(OBS, {"identifier": 1}) > work(OBS, {})
        assert work(CTL, {}) == 0.0
    isolated(run)

"""The master loop: both implementations agree bit for bit, and failures are explained."""
from __future__ import annotations

import numpy as np
import pytest

from harness.fmus import FMUError, FMUInstance
from harness.master import CoSimulation, Link, initialize, run
from harness.scenarios import COMMUNICATION_STEP, PROBES, SCENARIOS, build

FMU_DIR = None


def _run_62(fmu_dir, use_native: bool, seconds: float = 0.3, noise_std: float = 1e-4):
    s = SCENARIOS["6.2"]
    n = int(round(seconds / COMMUNICATION_STEP))
    noise = np.random.default_rng(1).normal(0.0, noise_std, n)
    sim = build(s, fmu_dir)
    try:
        initialize(sim, 0.0, {"plant": s.plant, "controller": s.controller,
                              "observer": s.observer}, {"noise": noise})
        return run(sim, 0.0, seconds, COMMUNICATION_STEP, PROBES, decimation=7,
                   signals={"noise": noise}, use_native=use_native)
    finally:
        sim.close()


def test_native_and_python_loops_give_identical_records(observer_fmu, pendulum_fmu,
                                                        controller_fmu):
    fmu_dir = observer_fmu.parent
    native = _run_62(fmu_dir, True)
    python = _run_62(fmu_dir, False)
    assert len(native.time) == len(python.time) == 3000 // 7 + 1
    np.testing.assert_array_equal(native.time, python.time)
    for name in PROBES:
        np.testing.assert_array_equal(native[name], python[name], err_msg=name)
    # and the loop did something: the pendulum moved, the observer followed it
    assert np.ptp(native["plant.theta"]) > 0.05
    assert np.max(np.abs(native["plant.theta"] - native["observer.x1_hat[1]"])[100:]) < 1e-3


def test_signals_drive_an_fmu_alone(observer_fmu):
    t = np.arange(0, 0.5, 1e-3)
    y = 0.3 * np.sin(2 * t)
    observer = FMUInstance(observer_fmu, "observer")
    sim = CoSimulation({"observer": observer}, [Link("signal:y", "observer.y[1]")])
    try:
        params = {"nominal_model": 2, "h": 1e-3, "alpha1[1]": 5.0, "alpha2[1]": 8.0}
        initialize(sim, 0.0, {"observer": params}, {"y": y})
        r = run(sim, 0.0, 0.5, 1e-3, ["observer.x2_hat[1]"], signals={"y": y})
    finally:
        sim.close()
    # F = 0 and phi unused: the observer differentiates y; velocity 0.6 cos 2t
    late = r.time > 0.3
    assert np.max(np.abs(r["observer.x2_hat[1]"][late] - 0.6 * np.cos(2 * r.time[late]))) < 5e-3


def test_an_fmu_failure_names_the_fmu_and_says_why(observer_fmu):
    observer = FMUInstance(observer_fmu, "observer")
    sim = CoSimulation({"observer": observer}, [Link("signal:y", "observer.y[1]")])
    y = np.full(100, np.inf)
    try:
        with pytest.raises(FMUError, match=r"observer: .*y\[1\] = inf is not finite"):
            initialize(sim, 0.0, {}, {"y": y})
    finally:
        sim.close()


def test_bad_wiring_is_rejected_before_running(observer_fmu):
    observer = FMUInstance(observer_fmu, "observer")
    try:
        with pytest.raises(KeyError, match="no variable named 'nonsense'"):
            CoSimulation({"observer": observer}, [Link("signal:y", "observer.nonsense")])
        with pytest.raises(ValueError, match="does not name 'fmu.variable'"):
            CoSimulation({"observer": observer}, [Link("signal:y", "plant.u")])
    finally:
        observer.close()
